"""Ideal translational sensors (they neither store nor dissipate energy)."""

from mechatron.core import Output, Variable, der
from mechatron.library.translational.interfaces import TwoFlange

__all__ = ["PositionSensor", "VelocitySensor", "AccelerationSensor", "ForceSensor",
           "TranslationalPowerSensor"]


class PositionSensor(TwoFlange):
    """Ideal relative position sensor: ``f = 0``; ``dx/dt = v`` with ``x`` its own state
    (start 0, or the initial offset given as ``x=``); output ``X = x``."""

    X = Output("m", doc="Measured position, A relative to B")
    x = Variable("m", start=0.0, doc="Relative position, integral of A.v - B.v")

    def equations(self):
        return [self.f == 0, der(self.x) == self.v, self.X == self.x]


class VelocitySensor(TwoFlange):
    """Ideal relative velocity sensor: ``f = 0``, output ``V = v = A.v - B.v``."""

    V = Output("m/s", doc="Measured velocity A.v - B.v")

    def equations(self):
        return [self.f == 0, self.V == self.v]


class AccelerationSensor(TwoFlange):
    """Ideal relative acceleration sensor: ``f = 0``, output ``a = dv/dt`` with
    ``v = A.v - B.v``."""

    a = Output("m/s^2", doc="Measured acceleration d(A.v - B.v)/dt")

    def equations(self):
        return [self.f == 0, self.a == der(self.v)]


class ForceSensor(TwoFlange):
    """Ideal force sensor in series: a rigid link (``v = 0``) with output ``F = f``, the
    force passed from A to B."""

    F = Output("N", doc="Measured force from A to B")

    def equations(self):
        return [self.v == 0, self.F == self.f]


class TranslationalPowerSensor(TwoFlange):
    """Ideal power sensor in series: a rigid link (``v = 0``) with output ``P = f A.v``,
    the power passed from A to B."""

    P = Output("W", doc="Mechanical power passed from A to B")

    def equations(self):
        return [self.v == 0, self.P == self.f * self.A.v]
