"""Translational friction elements with a true stuck mode (Modelica's
``PartialFriction``): support friction, brake, and a mass with end stops and friction.

While stuck the relative velocity is held exactly (the relative acceleration is zero) and
the friction force is the unknown that keeps it so; the element breaks away when that
force exceeds the static limit and sticks again when the relative velocity crosses zero.
See :mod:`mechatron.library.rotational.stickslip` for the mode logic. The smooth
:class:`~mechatron.library.translational.TranslationalFriction` stays available.
"""

import casadi as ca

from mechatron.core import (Component, Discrete, Input, Parameter, Variable, der, if_else,
                            logic_and, pre, reinit, when)
from mechatron.library.rotational.friction import SpeedTableOption, stribeck, table_value
from mechatron.library.rotational.stickslip import initial_mode, stick_slip
from mechatron.library.translational.interfaces import Flange, TwoFlange

__all__ = ["PartialFriction", "SupportFriction", "Brake", "MassWithStopAndFriction"]


class PartialFriction(TwoFlange, partial=True):
    """Stuck/sliding friction between flanges A and B (Modelica's ``PartialFriction``).

    Modes (``mode``): 1 sliding forward (``v > 0``), 0 stuck (``a = 0``, the force is
    the unknown), -1 sliding backward; the start mode follows the start velocity. Both
    sides need mass (or a prescribed motion): while stuck they move as one body.
    """

    m_s = Parameter("kg", default=1.0, min=0,
                    doc="Scale of the stuck equation m_s a = 0 (any positive value)")
    a = Variable("m/s^2", doc="Relative acceleration, der(v)")
    mode = Discrete("1", start=0, kind="integer",
                    doc="1 sliding forward, 0 stuck, -1 sliding backward")
    v_lock = Discrete("m/s", start=0.0,
                      doc="Relative velocity at the last lock (0 up to the event location)")

    def equations(self):
        return [self.a == der(self.v)]

    def initial_equations(self):
        return [initial_mode(self.mode, self.v)]


class SupportFriction(SpeedTableOption, PartialFriction):
    """Friction with a true stuck mode between a body (A) and its support (B).

    Kinetic force (Stribeck, Coulomb and viscous parts) for ``v = A.v - B.v``::

        f = (F_C + (F_brk - F_C) g(|v| / v_S) + b |v|) sign(v),   g(x) = exp(-x^2)
        stuck: der(v) = 0 while |f| <= F_brk g(0) + F_C (1 - g(0))

    so the break-away force is ``F_brk`` (with the default ``g``); Coulomb friction alone
    is ``F_brk = F_C``. ``stribeck_table``: rows ``(x, g)`` from ``x = 0`` replacing
    ``exp(-x^2)``. Reference: Modelica.Mechanics.Translational.Components.SupportFriction.
    """

    F_brk = Parameter("N", default=25.0, min=0, doc="Break-away (static) force")
    F_C = Parameter("N", default=20.0, min=0, doc="Coulomb friction force")
    v_S = Parameter("m/s", default=0.1, min=0, doc="Stribeck velocity")
    b = Parameter("N*s/m", default=0.0, min=0, doc="Viscous friction coefficient")

    def equations(self):
        kinetic = stribeck(ca.fabs(self.v), self._table, self.F_C, self.F_brk, self.v_S,
                           self.b)
        static = stribeck(0 * self.v, self._table, self.F_C, self.F_brk, self.v_S, self.b)
        return stick_slip(self.mode, self.v, self.v_lock, self.a, self.f, self.m_s,
                          kinetic, -kinetic, static, static)


class Brake(SpeedTableOption, PartialFriction):
    """Translational brake with a true stuck mode, pressed by the normal force ``f_n``:
    the moving part at A, the housing at B.

    With ``fn = max(f_n, 0)`` and ``v = A.v - B.v``::

        sliding:  f = fn mu(|v|) sign(v)        (mu constant, or mu_table)
        stuck:    der(v) = 0 while |f| <= peak fn mu(0)

    ``mu_table``: rows ``(|v| / v_ref, mu)`` from speed 0, linear between them, the last
    value held. Reference: Modelica.Mechanics.Translational.Components.Brake.
    """

    f_n = Input("N", doc="Normal force pressing the brake pads")
    mu = Parameter("1", default=0.3, min=0,
                   doc="Kinetic friction coefficient (when no mu_table is given)")
    peak = Parameter("1", default=1.0, min=1,
                     doc="Static friction coefficient / kinetic one at zero speed")
    v_ref = Parameter("m/s", default=1.0, min=0, doc="Unit of the speed column of mu_table")

    table_keyword = "mu_table"

    def _mu(self, speed):
        if self._table is None:
            return self.mu
        return table_value(speed / self.v_ref, self._table)

    def equations(self):
        fn = ca.fmax(self.f_n, 0 * self.f_n)
        kinetic = fn * self._mu(ca.fabs(self.v))
        static = self.peak * fn * self._mu(0 * self.v)
        return stick_slip(self.mode, self.v, self.v_lock, self.a, self.f, self.m_s,
                          kinetic, -kinetic, static, static)


class MassWithStopAndFriction(SpeedTableOption, Component):
    """Sliding mass with Stribeck friction against the ground and end stops
    (Modelica's ``MassWithStopAndFriction``), with a true stuck mode.

    Position ``s`` (own state) between ``s_min`` and ``s_max``, velocity ``v = port.v``,
    external force ``port.f`` (entering at the port), friction force ``f``::

        m der(v) = port.f - f,   der(s) = v
        sliding: f = (F_C + (F_brk - F_C) exp(-(v / v_S)^2) + b |v|) sign(v)
        stuck:   der(v) = 0 while |f| <= F_brk

    At a stop the impact re-initializes ``v := -e pre(v)`` and ``s`` onto the stop; an
    impact whose rebound ``e |pre(v)|`` is slower than ``v_rest`` (every impact with the
    inelastic default ``e = 0``) puts the mass to rest against the stop, where it holds
    any force pressing it into the stop and leaves when pulled away with more than the
    break-away force. ``stribeck_table``: rows ``(|v| / v_S, g)`` replacing
    ``exp(-(v / v_S)^2)``.
    """

    port = Flange(doc="Flange of the mass")
    m = Parameter("kg", default=1.0, min=0, doc="Mass")
    s_min = Parameter("m", default=-1.0, doc="Lower stop (smallest position)")
    s_max = Parameter("m", default=1.0, doc="Upper stop (largest position)")
    e = Parameter("1", default=0.0, min=0, max=1,
                  doc="Coefficient of restitution of the stops (0 inelastic)")
    v_rest = Parameter("m/s", default=1e-3, min=0,
                       doc="A rebound slower than this ends in rest at the stop")
    F_brk = Parameter("N", default=25.0, min=0, doc="Break-away (static) friction force")
    F_C = Parameter("N", default=20.0, min=0, doc="Coulomb friction force")
    v_S = Parameter("m/s", default=0.1, min=0, doc="Stribeck velocity")
    b = Parameter("N*s/m", default=0.0, min=0, doc="Viscous friction coefficient")
    s = Variable("m", start=0.0, doc="Position")
    v = Variable("m/s", doc="Velocity")
    a = Variable("m/s^2", doc="Acceleration, der(v)")
    f = Variable("N", doc="Friction and stop force against the motion")
    mode = Discrete("1", start=0, kind="integer",
                    doc="1 sliding forward, 0 stuck, -1 sliding backward")
    v_lock = Discrete("m/s", start=0.0, doc="Velocity at the last lock or break-away")
    stop = Discrete("1", start=0, kind="integer",
                    doc="1 resting at the upper stop, -1 at the lower one, 0 neither")
    impacts = Discrete("1", start=0, kind="integer", doc="Number of impacts on the stops")

    def equations(self):
        kinetic = stribeck(ca.fabs(self.v), self._table, self.F_C, self.F_brk, self.v_S,
                           self.b)
        static = stribeck(0 * self.v, self._table, self.F_C, self.F_brk, self.v_S, self.b)
        # the stop ahead, only while moving towards it (no events while leaving it)
        to_upper = if_else(self.mode == 1, self.s - self.s_max, self.s_min - self.s_max)
        to_lower = if_else(self.mode == -1, self.s_min - self.s, self.s_min - self.s_max)
        rebound = -self.e * pre(self.v)
        rests_up = self.e * pre(self.v) < self.v_rest
        rests_down = -self.e * pre(self.v) < self.v_rest
        return [self.v == self.port.v,
                der(self.s) == self.v,
                self.a == der(self.v),
                self.m * self.a == self.port.f - self.f,
                *stick_slip(self.mode, self.v, self.v_lock, self.a, self.f, self.m,
                            kinetic, -kinetic, static, static,
                            blocked_fwd=self.stop == 1, blocked_bwd=self.stop == -1),
                when(to_upper >= 0, update=[
                    reinit(self.s, self.s_max),
                    reinit(self.v, if_else(rests_up, 0 * self.v, rebound)),
                    (self.mode, if_else(rests_up, 0, -1)),
                    (self.stop, if_else(rests_up, 1, 0)),
                    (self.v_lock, 0 * self.v),
                    (self.impacts, self.impacts + 1)]),
                when(to_lower >= 0, update=[
                    reinit(self.s, self.s_min),
                    reinit(self.v, if_else(rests_down, 0 * self.v, rebound)),
                    (self.mode, if_else(rests_down, 0, 1)),
                    (self.stop, if_else(rests_down, -1, 0)),
                    (self.v_lock, 0 * self.v),
                    (self.impacts, self.impacts + 1)]),
                when(logic_and(self.stop != 0, self.mode != 0), update={self.stop: 0})]

    def initial_equations(self):
        return [initial_mode(self.mode, self.v)]
