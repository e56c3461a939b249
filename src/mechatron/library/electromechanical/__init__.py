"""Converters between the electrical and mechanical domains."""

from mechatron.core import Parameter
from mechatron.library.electrical.interfaces import OnePort
from mechatron.library.rotational.interfaces import TwoFlange

__all__ = ["RotationalEMF"]


class RotationalEMF(OnePort, TwoFlange):
    """Ideal rotational electromechanical converter (the DC motor's air gap).

    Equations: ``v = k w`` (back EMF) and ``tau = -k i``: the converter absorbs electrical
    power ``v i`` and delivers the same ``k i w`` at flange A (``tau w + v i = 0``), so a
    positive current drives the flange connected at A forward.
    """

    k = Parameter("V*s/rad", default=0.1, min=0, doc="Torque and back-EMF constant")

    def equations(self):
        return [self.v == self.k * self.w, self.tau == -self.k * self.i]
