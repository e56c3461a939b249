"""Rotational motion and torque sources."""

from mechatron.core import Input, Parameter, Variable, der
from mechatron.library.rotational.interfaces import TwoFlange

__all__ = ["IdealAngularVelocitySource", "IdealAngleSource", "ConstantTorque"]


class IdealAngularVelocitySource(TwoFlange):
    """Imposes the relative angular velocity ``w = A.w - B.w = w_ref`` whatever the torque.

    Equations: ``w = w_ref``, ``dphi/dt = w`` (``phi``, the angle turned, is its own state,
    start 0). The torque ``tau`` it needs is whatever the network demands.
    """

    w_ref = Input("rad/s", doc="Commanded angular velocity A.w - B.w")
    phi = Variable("rad", start=0.0, doc="Angle turned, A relative to B")

    def equations(self):
        return [self.w == self.w_ref, der(self.phi) == self.w]


class IdealAngleSource(TwoFlange):
    """Imposes the relative angle ``phi = phi_ref`` (A relative to B).

    Equations: ``phi = phi_ref``, ``dphi/dt = w``. The velocity is the time derivative of
    the command, so the command must be differentiable (a sine, a smooth profile); the
    compiler differentiates it (index reduction).
    """

    phi_ref = Input("rad", doc="Commanded angle, A relative to B")
    phi = Variable("rad", doc="Angle, A relative to B")

    def equations(self):
        return [self.phi == self.phi_ref, der(self.phi) == self.w]


class ConstantTorque(TwoFlange):
    """Constant torque source: applies ``T`` to the flange connected at A and ``-T`` at B
    (``tau = -T``, ``A.tau = -T``)."""

    T = Parameter("N*m", default=1.0, doc="Torque applied at A")

    def equations(self):
        return [self.tau == -self.T]
