"""Rotational contact, friction and load components: hard stop, backlash, friction clutch,
quadratic (fan) load."""

import casadi as ca

from mechatron.core import Input, Parameter, Variable, der
from mechatron.library.rotational.contact import penalty_force
from mechatron.library.rotational.interfaces import TwoFlange

__all__ = ["RotationalHardStop", "RotationalBacklash", "FrictionClutch", "FanLoad"]


class RotationalHardStop(TwoFlange):
    """Double-sided rotational hard stop with penalty contact.

    The relative angle ``phi`` (A relative to B, its own state, ``dphi/dt = w``) may move
    freely between ``lower`` and ``upper``. Beyond a bound the stop acts as a spring-damper
    that only pushes back::

        tau = max(k (phi - upper) + d w, 0)    for phi > upper
        tau = min(k (phi - lower) + d w, 0)    for phi < lower
        tau = 0                                otherwise

    Sign: ``tau`` enters at A, so the flange connected at A feels ``-tau`` (pushed back
    into the free band). Contact, release and the instant the damper would pull are events.
    At rest against the upper stop under a steady torque ``T`` the penetration is
    ``T / k``. Limitation: a penalty method; a stiff ``k`` makes the model stiff.
    """

    upper = Parameter("rad", default=0.1, doc="Upper bound of phi")
    lower = Parameter("rad", default=-0.1, doc="Lower bound of phi")
    k = Parameter("N*m/rad", default=1e4, min=0, doc="Contact stiffness")
    d = Parameter("N*m*s/rad", default=10.0, min=0, doc="Contact damping")
    phi = Variable("rad", start=0.0, doc="Relative angle, A relative to B")

    def equations(self):
        upper = penalty_force(self.phi - self.upper, self.w, self.k, self.d)
        lower = penalty_force(self.lower - self.phi, -self.w, self.k, self.d)
        return [der(self.phi) == self.w, self.tau == upper - lower]


class RotationalBacklash(TwoFlange):
    """Backlash: a dead band of total width ``b`` centred on ``phi = 0``.

    No torque is transmitted while ``|phi| < b/2``; beyond, the teeth are in penalty
    contact (see :class:`RotationalHardStop`)::

        tau = max(k (phi - b/2) + d w, 0)    for phi > b/2
        tau = min(k (phi + b/2) + d w, 0)    for phi < -b/2
        tau = 0                              otherwise,   dphi/dt = w

    ``phi`` (A relative to B) is the component's own state, start 0 (centred).
    """

    b = Parameter("rad", default=0.02, min=0, doc="Total backlash (dead band width)")
    k = Parameter("N*m/rad", default=1e5, min=0, doc="Contact stiffness of the teeth")
    d = Parameter("N*m*s/rad", default=10.0, min=0, doc="Contact damping of the teeth")
    phi = Variable("rad", start=0.0, doc="Relative angle, A relative to B")

    def equations(self):
        upper = penalty_force(self.phi - self.b / 2, self.w, self.k, self.d)
        lower = penalty_force(-self.b / 2 - self.phi, -self.w, self.k, self.d)
        return [der(self.phi) == self.w, self.tau == upper - lower]


class FrictionClutch(TwoFlange):
    """Disc friction clutch driven by a normal-force signal, smooth stick/slip.

    With ``fn = max(f_n, 0)`` (the clutch never pulls the plates apart) and the slip speed
    ``w = A.w - B.w``::

        T_s = n R mu_s fn           static capacity,   T_k = n R mu_k fn   kinetic
        tau = fn n R (mu_k + (mu_s - mu_k) exp(-(w / (10 w_tol))^2)) tanh(w / w_tol)

    Sticking is approximated by the steep ``tanh`` around zero slip: a transmitted torque
    ``T < T_s`` is carried at a slip speed of about ``w_tol atanh(T / T_s)``; beyond ``T_s``
    the clutch slips and transmits ``T_k`` once ``|w| >> 10 w_tol``. No events.
    Limitation: a true stuck mode (zero slip) is not modelled; lower ``w_tol`` to approach
    it, at the price of stiffness.
    """

    f_n = Input("N", doc="Normal force pressing the plates together")
    mu_k = Parameter("1", default=0.3, min=0, doc="Kinetic friction coefficient")
    mu_s = Parameter("1", default=0.35, min=0, doc="Static friction coefficient")
    R = Parameter("m", default=0.1, min=0, doc="Effective friction radius")
    n = Parameter("1", default=2, min=1, doc="Number of friction surfaces")
    w_tol = Parameter("rad/s", default=1e-3, min=0, doc="Slip speed of the smooth stick law")

    def equations(self):
        fn = ca.fmax(self.f_n, 0)
        mu = self.mu_k + (self.mu_s - self.mu_k) * ca.exp(-(self.w / (10 * self.w_tol)) ** 2)
        return [self.tau == fn * self.n * self.R * mu * ca.tanh(self.w / self.w_tol)]


class FanLoad(TwoFlange):
    """Quadratic torque-speed load of a fan, pump or propeller.

    ``tau = T_nom (w / w_nom) |w / w_nom|``: the load absorbs ``T_nom`` at ``w_nom`` and
    always dissipates (``tau w >= 0``). A spinning inertia ``J`` coasts down as
    ``w(t) = w0 / (1 + c w0 t / J)`` with ``c = T_nom / w_nom^2``.
    """

    T_nom = Parameter("N*m", default=1.0, min=0, doc="Load torque at the nominal speed")
    w_nom = Parameter("rad/s", default=100.0, min=0, doc="Nominal speed")

    def equations(self):
        x = self.w / self.w_nom
        return [self.tau == self.T_nom * x * ca.fabs(x)]
