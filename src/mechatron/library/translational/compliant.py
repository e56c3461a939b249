"""Compliant couplings with MSL's names and parameters (``Mechanics.Translational.
Components``): spring-damper with a natural length, and the elastic gap that only pushes.

Unlike the older parts of this package (whose relative position is A relative to B),
these use MSL's relative distance ``s_rel = s_B - s_A`` (the length from A to B), so an
MSL model's ``s_rel0`` and start values carry over unchanged; ``v_rel = B.v - A.v = -v``.
"""

from mechatron.core import Parameter, Variable, der, if_else
from mechatron.library.rotational.compliant import limited_contact
from mechatron.library.translational.interfaces import TwoFlange

__all__ = ["SpringDamper", "ElastoGap"]


class SpringDamper(TwoFlange):
    """Linear spring with a natural length and a damper in parallel (MSL's
    ``SpringDamper``).

    Equations, with ``s_rel`` (the length from A to B, its own state)::

        der(s_rel) == v_rel,              v_rel = B.v - A.v = -v
        f_msl = c (s_rel - s_rel0) + d v_rel
        f == -f_msl                       (f enters at A; MSL's flange_b.f = f_msl)
        P_loss == d v_rel^2

    Stretched beyond ``s_rel0`` it pulls A and B together. Stores
    ``c (s_rel - s_rel0)^2 / 2``.
    """

    c = Parameter("N/m", default=1.0, min=0, doc="Spring constant")
    d = Parameter("N*s/m", default=0.0, min=0, doc="Damping constant")
    s_rel0 = Parameter("m", default=0.0, doc="Unstretched spring length")
    s_rel = Variable("m", start=0.0, doc="Length from A to B, s_B - s_A (MSL's s_rel)")
    P_loss = Variable("W", doc="Power dissipated by the damper")

    def equations(self):
        v_rel = -self.v
        return [der(self.s_rel) == v_rel,
                self.f == -(self.c * (self.s_rel - self.s_rel0) + self.d * v_rel),
                self.P_loss == self.d * v_rel ** 2]


class ElastoGap(TwoFlange):
    """One-sided elastic contact: a spring-damper that acts only while compressed and
    never pulls (MSL's ``ElastoGap``).

    With ``s_rel`` the length from A to B (own state, ``der(s_rel) == v_rel = -v``), the
    penetration ``delta = s_rel0 - s_rel`` and its rate ``der(delta) = v``::

        f == c delta + clamp(d v, -c delta, c delta)     delta > 0 (contact)
        f == 0                                           otherwise

    ``f`` enters at A: A is pushed away from B by ``f >= 0``, never pulled. The damping
    force is limited as MSL's (``0 <= f <= 2 c delta``), so the force is continuous at
    first contact and at release. Contact and release are events. Limitation: a linear
    spring (MSL's exponent ``n`` is fixed at its default 1).
    """

    c = Parameter("N/m", default=1e6, min=0, doc="Spring constant of the contact")
    d = Parameter("N*s/m", default=0.0, min=0, doc="Damping constant of the contact")
    s_rel0 = Parameter("m", default=0.0, doc="Length from A to B at which contact begins")
    s_rel = Variable("m", start=0.0, doc="Length from A to B, s_B - s_A (MSL's s_rel)")
    contact = Variable("1", doc="1 while in contact (compressed), else 0")

    def equations(self):
        delta = self.s_rel0 - self.s_rel
        return [der(self.s_rel) == -self.v,
                self.contact == if_else(delta > 0, 1, 0),
                self.f == limited_contact(delta, self.v, self.c, self.d)]
