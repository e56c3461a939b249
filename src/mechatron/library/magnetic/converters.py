"""Converters between the magnetic domain and the electrical and translational ones."""

from mechatron.core import Parameter, Variable, der
from mechatron.library.electrical.interfaces import OnePort
from mechatron.library.magnetic.components import MU0
from mechatron.library.magnetic.interfaces import TwoPort
from mechatron.library.translational.interfaces import Flange

__all__ = ["ElectromagneticConverter", "ReluctanceForceActuator"]


class ElectromagneticConverter(OnePort, TwoPort):
    """Coil of ``N`` turns linking a magnetic path (Simscape: Electromagnetic Converter).

    Electrical pins ``p``/``n`` (``v = p.v - n.v``, current ``i`` from p to n), magnetic
    ports ``A``/``B`` (``mmf = A.mmf - B.mmf``, flux ``phi`` from A to B through the coil).

    Equations::

        B.mmf - A.mmf = N i        (the coil is an mmf source for the magnetic circuit)
        v = N dphi/dt              (Faraday's law)

    so a positive current drives a positive flux ``phi`` (A to B inside the coil) and
    ``v i + mmf dphi/dt = 0``: lossless, no stored energy. A coil on a magnetic path of
    reluctance ``R`` has the inductance ``L = N^2 / R``. Limitations: no winding
    resistance (add a Resistor), no leakage flux.
    """

    N = Parameter("1", default=100.0, min=0, doc="Number of turns")

    def equations(self):
        return [self.mmf == -self.N * self.i, self.v == self.N * der(self.phi)]


class ReluctanceForceActuator(TwoPort):
    """Variable air gap with its magnetic force (Simscape: Reluctance Force Actuator).

    Magnetic ports ``A``/``B``; translational flanges ``rod`` and ``case``. The gap length
    ``x`` grows as the rod moves away from the case: ``dx/dt = rod.v - case.v``.

    Equations::

        R(x) = x / (mu0 area)
        mmf = R(x) phi
        F = -phi^2 / (2 mu0 area)  = -(phi^2/2) dR/dx   (force on the rod along +x)
        rod.f = -F,  case.f = F

    ``F`` is the derivative of the co-energy ``W'(i, x) = (N i)^2 / (2 R(x))`` at constant
    current, equivalently ``-dW/dx`` of the stored energy ``W = R phi^2 / 2`` at constant
    flux: the force always closes the gap. Power balance:
    ``mmf dphi/dt + rod.f (rod.v - case.v) = d/dt (R phi^2 / 2)``.
    Limitations: no fringing or leakage, no iron saturation, no end stop: ``x`` must stay
    > 0 (add a hard stop or a spring in the mechanical circuit).
    """

    rod = Flange(doc="Moving flange (armature)")
    case = Flange(doc="Fixed flange (yoke)")
    area = Parameter("m^2", default=1e-4, min=0, doc="Pole face area")
    mu0 = Parameter("H/m", default=MU0, min=0, doc="Vacuum permeability")
    x = Variable("m", start=1e-3, doc="Gap length")
    F = Variable("N", doc="Magnetic force on the rod, positive when it opens the gap")

    def equations(self):
        return [der(self.x) == self.rod.v - self.case.v,
                self.mmf == self.x / (self.mu0 * self.area) * self.phi,
                self.F == -self.phi ** 2 / (2 * self.mu0 * self.area),
                self.rod.f == -self.F,
                self.rod.f + self.case.f == 0]
