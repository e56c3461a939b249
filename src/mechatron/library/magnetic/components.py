"""Magnetic components: reluctances, eddy-current loss, sources, reference, sensors."""

import math

from mechatron.core import Component, Input, Output, Parameter, der
from mechatron.library.magnetic.interfaces import MagneticPort, TwoPort

__all__ = ["MU0", "Reluctance", "AirGapReluctance", "VariableAirGapReluctance",
           "EddyCurrent", "MmfSource", "ControlledMmfSource", "FluxSource",
           "ControlledFluxSource", "MagneticReference", "FluxSensor", "MmfSensor"]

#: Vacuum permeability, H/m (the SI value 4 pi 1e-7, within 1e-9 of CODATA 2018).
MU0 = 4e-7 * math.pi


class Reluctance(TwoPort):
    """Linear reluctance (Simscape: Reluctance).

    Equations: ``mmf = R phi`` (magnetic Ohm's law, Hopkinson's law). Stores the magnetic
    energy ``R phi^2 / 2`` (its power is ``mmf dphi/dt``). Limitations: linear, no
    saturation or hysteresis.
    """

    R = Parameter("A/Wb", default=1e6, min=0, doc="Reluctance")

    def equations(self):
        return [self.mmf == self.R * self.phi]


class AirGapReluctance(TwoPort):
    """Reluctance of a flux tube of uniform section (Simscape: Fundamental Reluctance).

    Equations: ``mmf = R phi`` with ``R = g / (mu0 mu_r area)``. Limitations: no fringing
    (``area`` should be the effective area), linear material.
    """

    g = Parameter("m", default=1e-3, min=0, doc="Length of the flux path (gap length)")
    area = Parameter("m^2", default=1e-4, min=0, doc="Cross-section area")
    mu_r = Parameter("1", default=1.0, min=0, doc="Relative permeability")
    mu0 = Parameter("H/m", default=MU0, min=0, doc="Vacuum permeability")

    def equations(self):
        return [self.mmf == self.g / (self.mu0 * self.mu_r * self.area) * self.phi]


class VariableAirGapReluctance(TwoPort):
    """Air gap whose length is a signal (Simscape: Variable Reluctance).

    Equations: ``mmf = R(g) phi``, ``R(g) = g / (mu0 area)``. No force is computed: use
    :class:`~mechatron.library.magnetic.ReluctanceForceActuator` when the gap is a
    mechanical degree of freedom. Limitations: ``g`` must stay > 0.
    """

    g = Input("m", doc="Gap length")
    area = Parameter("m^2", default=1e-4, min=0, doc="Pole face area")
    mu0 = Parameter("H/m", default=MU0, min=0, doc="Vacuum permeability")

    def equations(self):
        return [self.mmf == self.g / (self.mu0 * self.area) * self.phi]


class EddyCurrent(TwoPort):
    """Eddy-current loss of a conducting core section (Modelica: EddyCurrent).

    Equations: ``mmf = G dphi/dt`` with ``G`` the equivalent conductance of the eddy-current
    path (for a solid tube ``G = sigma_el * area / length``). Dissipates
    ``G (dphi/dt)^2 >= 0``. Limitations: lumped, no skin effect.
    """

    G = Parameter("S", default=1.0, min=0, doc="Equivalent eddy-current conductance")

    def equations(self):
        return [self.mmf == self.G * der(self.phi)]


class MmfSource(TwoPort):
    """Ideal constant mmf source: ``B.mmf - A.mmf = F`` (it drives flux out of ``B``
    through the external circuit into ``A``)."""

    F = Parameter("A", default=1.0, doc="Magnetomotive force, B.mmf - A.mmf")

    def equations(self):
        return [self.mmf == -self.F]


class ControlledMmfSource(TwoPort):
    """Ideal mmf source driven by a signal: ``B.mmf - A.mmf = F_in``."""

    F_in = Input("A", doc="Commanded magnetomotive force, B.mmf - A.mmf")

    def equations(self):
        return [self.mmf == -self.F_in]


class FluxSource(TwoPort):
    """Ideal constant flux source: ``phi = Phi`` from A to B through the source (it
    pushes flux out of ``B`` into the external circuit)."""

    Phi = Parameter("Wb", default=1e-4, doc="Flux from A to B through the source")

    def equations(self):
        return [self.phi == self.Phi]


class ControlledFluxSource(TwoPort):
    """Ideal flux source driven by a signal: ``phi = Phi_in``."""

    Phi_in = Input("Wb", doc="Commanded flux from A to B through the source")

    def equations(self):
        return [self.phi == self.Phi_in]


class MagneticReference(Component, reference=True):
    """Magnetic reference: ``port.mmf = 0``. Every magnetic network needs one."""

    port = MagneticPort(doc="Port at zero magnetic potential")

    def equations(self):
        return [self.port.mmf == 0]


class FluxSensor(TwoPort):
    """Ideal flux sensor in series: ``mmf = 0``, output ``Phi = phi`` (from A to B)."""

    Phi = Output("Wb", doc="Measured flux from A to B")

    def equations(self):
        return [self.mmf == 0, self.Phi == self.phi]


class MmfSensor(TwoPort):
    """Ideal mmf sensor across two ports: ``phi = 0``, output ``F = A.mmf - B.mmf``."""

    F = Output("A", doc="Measured mmf A.mmf - B.mmf")

    def equations(self):
        return [self.phi == 0, self.F == self.mmf]
