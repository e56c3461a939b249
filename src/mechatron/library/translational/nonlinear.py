"""Translational hard stop and preloaded spring."""

from mechatron.core import Parameter, Variable, der
from mechatron.library.rotational.contact import penalty_force
from mechatron.library.translational.interfaces import TwoFlange

__all__ = ["TranslationalHardStop", "PreloadedSpring"]


class TranslationalHardStop(TwoFlange):
    """Double-sided translational hard stop with penalty contact.

    The relative position ``x`` (A relative to B, its own state, ``dx/dt = v``) may move
    freely between ``lower`` and ``upper``. Beyond a bound the stop is a spring-damper that
    only pushes::

        f = max(k (x - upper) + d v, 0)    for x > upper
        f = min(k (x - lower) + d v, 0)    for x < lower
        f = 0                              otherwise

    Sign: ``f`` enters at A, so the flange at A feels ``-f``. At rest against a stop under
    a steady force ``F`` the penetration is ``F / k``. Contact, release and the instant the
    damper would pull are events. Limitation: a penalty method (stiff for large ``k``).
    """

    upper = Parameter("m", default=0.01, doc="Upper bound of x")
    lower = Parameter("m", default=-0.01, doc="Lower bound of x")
    k = Parameter("N/m", default=1e6, min=0, doc="Contact stiffness")
    d = Parameter("N*s/m", default=100.0, min=0, doc="Contact damping")
    x = Variable("m", start=0.0, doc="Relative position, A relative to B")

    def equations(self):
        upper = penalty_force(self.x - self.upper, self.v, self.k, self.d)
        lower = penalty_force(self.lower - self.x, -self.v, self.k, self.d)
        return [der(self.x) == self.v, self.f == upper - lower]


class PreloadedSpring(TwoFlange):
    """Linear spring mounted with a preload.

    Equations: ``f = F_pre + k x``, ``dx/dt = v``, where ``x`` (A relative to B, its own
    state) is the deformation from the installed length. A positive ``F_pre`` is tension
    (the flanges are pulled together); the free (unloaded) length is the installed length
    minus ``F_pre / k``. Stores ``(F_pre + k x)^2 / (2 k)``.
    """

    k = Parameter("N/m", default=1000.0, min=0, doc="Spring rate")
    F_pre = Parameter("N", default=10.0,
                      doc="Preload force at the installed length (tension > 0)")
    x = Variable("m", start=0.0, doc="Deformation from the installed length, A relative to B")

    def equations(self):
        return [der(self.x) == self.v, self.f == self.F_pre + self.k * self.x]
