"""Ideal rotational sensors (they neither store nor dissipate energy)."""

from mechatron.core import Output, Variable, der
from mechatron.library.rotational.interfaces import TwoFlange

__all__ = ["TorqueSensor", "AngleSensor", "PowerSensor"]


class TorqueSensor(TwoFlange):
    """Ideal torque sensor in series: a rigid link (``w = 0``, ``A.w = B.w``) with output
    ``T = tau``, the torque passed from A to B."""

    T = Output("N*m", doc="Measured torque from A to B")

    def equations(self):
        return [self.w == 0, self.T == self.tau]


class AngleSensor(TwoFlange):
    """Ideal relative angle sensor: no torque (``tau = 0``); ``dphi/dt = w`` with ``phi``
    its own state (start 0); output ``Phi = phi``."""

    Phi = Output("rad", doc="Measured angle, A relative to B")
    phi = Variable("rad", start=0.0, doc="Relative angle, integral of A.w - B.w")

    def equations(self):
        return [self.tau == 0, der(self.phi) == self.w, self.Phi == self.phi]


class PowerSensor(TwoFlange):
    """Ideal power sensor in series: a rigid link (``w = 0``) with outputs ``P = tau A.w``
    (power passed from A to B) and ``T = tau``."""

    P = Output("W", doc="Mechanical power passed from A to B")
    T = Output("N*m", doc="Torque passed from A to B")

    def equations(self):
        return [self.w == 0, self.P == self.tau * self.A.w, self.T == self.tau]
