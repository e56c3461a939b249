"""Translational components."""

import casadi as ca

from mechatron.core import Component, Input, Output, Parameter, Variable, der
from mechatron.library._options import OptionDispatch
from mechatron.library.translational.interfaces import Flange, TwoFlange


class Mass(OptionDispatch, Component):
    """Point mass referenced to the (implicit) ground.

    Equations: ``m dv/dt = port.f``, ``v = port.v``. Stores ``m v^2 / 2``.

    The position (MSL's ``Mass.s``) is a state only where it is asked for:
    ``Mass(use_s=True)`` or a start position ``Mass(s=...)`` builds a
    :class:`MassWithPosition`; without, the compiled model has no position state.
    """

    _options = {"use_s": False}

    @classmethod
    def _variant(cls, options, kwargs):
        return MassWithPosition if options["use_s"] or "s" in kwargs else cls

    port = Flange(doc="Flange of the mass")
    m = Parameter("kg", default=1.0, min=0, doc="Mass")
    v = Variable("m/s", doc="Velocity")

    def equations(self):
        return [self.v == self.port.v, self.m * der(self.v) == self.port.f]


class MassWithPosition(Mass):
    """Point mass with its position as a state (``Mass(use_s=True)`` or ``Mass(s=...)``;
    MSL's ``Mass`` with ``s``).

    Equations: as :class:`Mass`, and ``ds/dt == v`` (``s`` starts at 0 unless given).
    """

    _options = {"use_s": True}
    s = Variable("m", start=0.0, doc="Position of the mass")

    def equations(self):
        return [der(self.s) == self.v]


class TranslationalSpring(TwoFlange):
    """Ideal linear spring: ``f = k x``, ``dx/dt = v``; stores ``k x^2 / 2``."""

    k = Parameter("N/m", default=1.0, min=0, doc="Spring rate")
    x = Variable("m", start=0.0, doc="Deformation, A relative to B")

    def equations(self):
        return [der(self.x) == self.v, self.f == self.k * self.x]


class TranslationalDamper(TwoFlange):
    """Ideal viscous damper: ``f = b v``; dissipates ``b v^2``."""

    b = Parameter("N*s/m", default=1.0, min=0, doc="Damping coefficient")

    def equations(self):
        return [self.f == self.b * self.v]


class TranslationalFriction(TwoFlange):
    """Friction with Stribeck, Coulomb and viscous parts (Simscape's formulation).

    ``f = sqrt(2e)(F_brk - F_C) exp(-(v/v_St)^2) v/v_St + F_C tanh(v/v_C) + b v`` with
    ``v_St = v_brk sqrt(2)``, ``v_C = v_brk/10``. Smooth through ``v = 0``.
    """

    F_brk = Parameter("N", default=25.0, min=0, doc="Breakaway friction force")
    v_brk = Parameter("m/s", default=0.1, min=0, doc="Breakaway friction velocity")
    F_C = Parameter("N", default=20.0, min=0, doc="Coulomb friction force")
    b = Parameter("N*s/m", default=100.0, min=0, doc="Viscous friction coefficient")

    def equations(self):
        v_st = self.v_brk * ca.sqrt(2.0)
        x = self.v / v_st
        return [self.f == ca.sqrt(2 * ca.exp(1)) * (self.F_brk - self.F_C) * ca.exp(-x ** 2)
                * x + self.F_C * ca.tanh(self.v / (self.v_brk / 10)) + self.b * self.v]


class TranslationalReference(Component, reference=True):
    """Translational ground: ``port.v = 0``."""

    port = Flange(doc="Grounded flange")

    def equations(self):
        return [self.port.v == 0]


class IdealForceSource(TwoFlange):
    """Force source driven by a signal: applies ``f_in`` to the flange connected at A and
    the reaction at B (``A.f = -f_in``)."""

    f_in = Input("N", doc="Commanded force")

    def equations(self):
        return [self.f == -self.f_in]


class MotionSensor(TwoFlange):
    """Ideal motion sensor: no force; outputs velocity ``V = A.v - B.v`` and position ``X``
    (own state, start 0)."""

    V = Output("m/s", doc="Measured relative velocity")
    X = Output("m", doc="Measured relative position")
    x = Variable("m", start=0.0, doc="Relative position")

    def equations(self):
        return [self.f == 0, self.V == self.v, der(self.x) == self.v, self.X == self.x]
