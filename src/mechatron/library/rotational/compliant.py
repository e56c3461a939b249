"""Compliant couplings with MSL's names and parameters (``Mechanics.Rotational.Components``):
spring-damper with a free angle, and the elastic backlash whose contact torque never
pulls.

Unlike the older parts of this package (whose relative angle is A relative to B), these
use MSL's relative angle ``phi_rel = phi_B - phi_A`` (B relative to A), so an MSL model's
``phi_rel0`` and start values carry over unchanged; ``w_rel = B.w - A.w = -w``.
"""

import casadi as ca

from mechatron.core import Parameter, Variable, der, if_else
from mechatron.library.rotational.interfaces import TwoFlange

__all__ = ["SpringDamper", "ElastoBacklash", "limited_contact"]


def limited_contact(delta, rate, c, d):
    """Contact force of a spring-damper that only pushes, MSL's way.

    ``F = c delta + clamp(d rate, -c delta, c delta)`` while ``delta > 0`` (in
    contact), else 0. The damping part is limited so that ``0 <= F <= 2 c delta``: the
    force starts from 0 at first contact (no jump by ``d rate``) and never pulls. Contact
    and release are events; the two limits of the damping are kinks (MSL's
    ``noEvent``)."""
    elastic = c * ca.fmax(delta, 0)
    damping = ca.fmin(ca.fmax(d * rate, -elastic), elastic)
    return if_else(delta > 0, elastic + damping, 0)


class SpringDamper(TwoFlange):
    """Linear torsional spring and damper in parallel (MSL's ``SpringDamper``).

    Equations, with MSL's relative angle ``phi_rel`` (B relative to A, its own state)::

        der(phi_rel) == w_rel,            w_rel = B.w - A.w = -w
        tau_msl = c (phi_rel - phi_rel0) + d w_rel
        tau == -tau_msl                   (tau enters at A; MSL's flange_b.tau = tau_msl)
        P_loss == d w_rel^2

    Stores ``c (phi_rel - phi_rel0)^2 / 2``; dissipates ``P_loss``.
    """

    c = Parameter("N*m/rad", default=1e5, min=0, doc="Spring constant")
    d = Parameter("N*m*s/rad", default=0.0, min=0, doc="Damping constant")
    phi_rel0 = Parameter("rad", default=0.0, doc="Unstretched spring angle")
    phi_rel = Variable("rad", start=0.0, doc="Relative angle, B relative to A (MSL's phi_rel)")
    P_loss = Variable("W", doc="Power dissipated by the damper")

    def equations(self):
        w_rel = -self.w
        return [der(self.phi_rel) == w_rel,
                self.tau == -(self.c * (self.phi_rel - self.phi_rel0) + self.d * w_rel),
                self.P_loss == self.d * w_rel ** 2]


class ElastoBacklash(TwoFlange):
    """Backlash with an elastic, damped contact whose torque never pulls (MSL's
    ``ElastoBacklash``).

    With ``phi_diff = phi_rel - phi_rel0`` (``phi_rel`` B relative to A, its own state,
    ``der(phi_rel) == w_rel``, ``w_rel = -w``) and the limited contact law
    ``F(delta, rate) = c delta + clamp(d rate, -c delta, c delta)`` (see
    :func:`limited_contact`)::

        tau_msl = F(phi_diff - b/2, w_rel)         phi_diff >  b/2
        tau_msl = -F(-b/2 - phi_diff, -w_rel)      phi_diff < -b/2
        tau_msl = 0                                otherwise (free in the gap)
        tau == -tau_msl

    so ``|tau|`` stays within ``[0, 2 c |penetration|]`` and is continuous at first
    contact: the damping cannot make the teeth stick (the factor MSL's Backlash examples
    show against ``max(c delta + d rate, 0)``). Contact and release are events.
    """

    b = Parameter("rad", default=0.0, min=0, doc="Total backlash")
    c = Parameter("N*m/rad", default=1e5, min=0, doc="Spring constant of the contact")
    d = Parameter("N*m*s/rad", default=0.0, min=0, doc="Damping constant of the contact")
    phi_rel0 = Parameter("rad", default=0.0, doc="Unstretched angle (centre of the gap)")
    phi_rel = Variable("rad", start=0.0, doc="Relative angle, B relative to A (MSL's phi_rel)")

    def equations(self):
        w_rel = -self.w
        phi_diff = self.phi_rel - self.phi_rel0
        upper = limited_contact(phi_diff - self.b / 2, w_rel, self.c, self.d)
        lower = limited_contact(-self.b / 2 - phi_diff, -w_rel, self.c, self.d)
        return [der(self.phi_rel) == w_rel, self.tau == -(upper - lower)]
