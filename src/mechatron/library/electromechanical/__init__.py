"""Converters between the electrical and mechanical domains."""

from mechatron.core import Parameter, Variable
from mechatron.library.electrical.interfaces import OnePort
from mechatron.library.rotational.interfaces import TwoFlange
from mechatron.library.translational.interfaces import Flange as TranslationalFlange

__all__ = ["RotationalEMF", "TranslationalEMF"]


class RotationalEMF(OnePort, TwoFlange):
    """Ideal rotational electromechanical converter (the DC motor's air gap).

    Equations: ``v = k w`` (back EMF) and ``tau = -k i``: the converter absorbs electrical
    power ``v i`` and delivers the same ``k i w`` at flange A (``tau w + v i = 0``), so a
    positive current drives the flange connected at A forward.
    """

    k = Parameter("V*s/rad", default=0.1, min=0, doc="Torque and back-EMF constant")

    def equations(self):
        return [self.v == self.k * self.w, self.tau == -self.k * self.i]


class TranslationalEMF(OnePort):
    """Ideal translational electromechanical converter: a voice coil or linear motor
    (Modelica's ``TranslationalEMF``).

    Equations::

        v_rel == A.v - B.v,  A.f + B.f == 0,  f == A.f
        v == k v_rel        (back EMF)
        f == -k i           (force on the flange connected at A is k i)

    The converter absorbs electrical power ``v i`` and delivers ``k i v_rel`` at flange A
    (``v i + f v_rel == 0``): a positive current pushes the flange connected at A in the
    positive direction. ``B`` is the support (connect it to a reference when fixed).

    Limitations: constant force constant (no position dependence, no saturation);
    the coil's resistance and inductance are separate components.
    """

    A = TranslationalFlange(doc="Moving flange (the coil's or magnet's moving part)")
    B = TranslationalFlange(doc="Support flange")
    k = Parameter("N/A", default=1.0, min=0, doc="Force and back-EMF constant (N/A = V*s/m)")
    v_rel = Variable("m/s", doc="Velocity of A relative to B")
    f = Variable("N", doc="Force through the converter from A to B")

    def equations(self):
        return [self.v_rel == self.A.v - self.B.v,
                self.A.f + self.B.f == 0,
                self.f == self.A.f,
                self.v == self.k * self.v_rel,
                self.f == -self.k * self.i]
