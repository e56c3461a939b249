"""Rotational components."""

import casadi as ca

from mechatron.core import Component, Input, Output, Parameter, Variable, der
from mechatron.library._options import OptionDispatch
from mechatron.library.rotational.interfaces import Flange, TwoFlange


class Inertia(OptionDispatch, Component):
    """Rotating inertia referenced to the (implicit) ground.

    Equations: ``J dw/dt = port.tau``, ``w = port.w``. Stores ``J w^2 / 2``.

    The angle (MSL's ``Inertia.phi``) is a state only where it is asked for:
    ``Inertia(use_phi=True)`` or a start angle ``Inertia(phi=...)`` builds an
    :class:`InertiaWithAngle`; without, the compiled model has no angle state.
    """

    _options = {"use_phi": False}

    @classmethod
    def _variant(cls, options, kwargs):
        return InertiaWithAngle if options["use_phi"] or "phi" in kwargs else cls

    port = Flange(doc="Flange of the inertia")
    J = Parameter("kg*m^2", default=1e-3, min=0, doc="Moment of inertia")
    w = Variable("rad/s", doc="Angular velocity")

    def equations(self):
        return [self.w == self.port.w,
                self.J * der(self.w) == self.port.tau]


class InertiaWithAngle(Inertia):
    """Rotating inertia with its angle as a state (``Inertia(use_phi=True)`` or
    ``Inertia(phi=...)``; MSL's ``Inertia`` with ``phi``).

    Equations: as :class:`Inertia`, and ``dphi/dt == w`` (``phi`` starts at 0 unless
    given).
    """

    _options = {"use_phi": True}
    phi = Variable("rad", start=0.0, doc="Angle of the inertia")

    def equations(self):
        return [der(self.phi) == self.w]


class RotationalSpring(TwoFlange):
    """Ideal torsional spring.

    Equations: ``tau = k phi``, ``dphi/dt = w`` with the deflection ``phi`` its own state.
    Stores ``k phi^2 / 2``.
    """

    k = Parameter("N*m/rad", default=1.0, min=0, doc="Spring rate")
    phi = Variable("rad", start=0.0, doc="Deflection, angle of A relative to B")

    def equations(self):
        return [der(self.phi) == self.w, self.tau == self.k * self.phi]


class RotationalDamper(TwoFlange):
    """Ideal viscous damper: ``tau = D w``. Dissipates ``D w^2``."""

    D = Parameter("N*m*s/rad", default=1e-3, min=0, doc="Damping coefficient")

    def equations(self):
        return [self.tau == self.D * self.w]


class RotationalFriction(TwoFlange):
    """Friction with Stribeck, Coulomb and viscous parts (Simscape's formulation).

    Equations, with ``w_St = w_brk*sqrt(2)`` and ``w_C = w_brk/10``::

        tau = sqrt(2e) (T_brk - T_C) exp(-(w/w_St)^2) w/w_St + T_C tanh(w/w_C) + f w

    Smooth through ``w = 0`` (no events); the peak ``T_brk`` is reached near ``w_brk``.
    """

    T_brk = Parameter("N*m", default=0.0118, min=0, doc="Breakaway friction torque")
    w_brk = Parameter("rad/s", default=0.1, min=0, doc="Breakaway friction velocity")
    T_C = Parameter("N*m", default=0.00854, min=0, doc="Coulomb friction torque")
    f = Parameter("N*m*s/rad", default=1.236e-4, min=0, doc="Viscous friction coefficient")

    def equations(self):
        w_st = self.w_brk * ca.sqrt(2.0)
        w_c = self.w_brk / 10
        x = self.w / w_st
        return [self.tau == ca.sqrt(2 * ca.exp(1)) * (self.T_brk - self.T_C)
                * ca.exp(-x ** 2) * x + self.T_C * ca.tanh(self.w / w_c) + self.f * self.w]


class IdealGear(Component):
    """Ideal gear without losses, its support grounded.

    Equations: ``A.w = ratio * B.w``, ``B.tau = -ratio * A.tau`` (power in = power out).
    """

    A = Flange(doc="Input flange")
    B = Flange(doc="Output flange")
    ratio = Parameter("1", default=1.0, doc="Speed ratio A.w / B.w")

    def equations(self):
        return [self.A.w == self.ratio * self.B.w,
                self.B.tau == -self.ratio * self.A.tau]


class RotationalReference(Component, reference=True):
    """Rotational ground: ``port.w = 0``."""

    port = Flange(doc="Grounded flange")

    def equations(self):
        return [self.port.w == 0]


class IdealTorqueSource(TwoFlange):
    """Torque source driven by a signal: applies ``tau_in`` to the flange connected at A
    and the reaction ``-tau_in`` at B (``A.tau = -tau_in``)."""

    tau_in = Input("N*m", doc="Commanded torque")

    def equations(self):
        return [self.tau == -self.tau_in]


class AngularVelocitySensor(TwoFlange):
    """Ideal angular velocity sensor: no torque, output ``W = A.w - B.w``; also the angle
    ``phi`` (own state, start 0)."""

    W = Output("rad/s", doc="Measured relative angular velocity")
    phi = Variable("rad", start=0.0, doc="Relative angle, integral of W")

    def equations(self):
        return [self.tau == 0, self.W == self.w, der(self.phi) == self.w]
