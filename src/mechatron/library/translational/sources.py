"""Translational motion and force sources."""

from mechatron.core import Input, Parameter, Variable, der
from mechatron.library.translational.interfaces import TwoFlange

__all__ = ["IdealVelocitySource", "IdealPositionSource", "ConstantForce"]


class IdealVelocitySource(TwoFlange):
    """Imposes the relative velocity ``v = A.v - B.v = v_ref`` whatever the force.

    Equations: ``v = v_ref``, ``dx/dt = v`` (``x``, the distance travelled, is its own
    state, start 0).
    """

    v_ref = Input("m/s", doc="Commanded velocity A.v - B.v")
    x = Variable("m", start=0.0, doc="Distance travelled, A relative to B")

    def equations(self):
        return [self.v == self.v_ref, der(self.x) == self.v]


class IdealPositionSource(TwoFlange):
    """Imposes the relative position ``x = x_ref`` (A relative to B).

    Equations: ``x = x_ref``, ``dx/dt = v``. The velocity is the time derivative of the
    command, so the command must be differentiable; the compiler differentiates it (index
    reduction).
    """

    x_ref = Input("m", doc="Commanded position, A relative to B")
    x = Variable("m", doc="Position, A relative to B")

    def equations(self):
        return [self.x == self.x_ref, der(self.x) == self.v]


class ConstantForce(TwoFlange):
    """Constant force source: applies ``F`` to the flange connected at A and ``-F`` at B
    (``f = -F``)."""

    F = Parameter("N", default=1.0, doc="Force applied at A")

    def equations(self):
        return [self.f == -self.F]
