"""Thermal components: mass, conduction, convection, radiation."""

from mechatron.core import Component, Input, Parameter, Variable, der
from mechatron.library.thermal.interfaces import HeatPort, TwoPort

__all__ = ["HeatCapacitor", "ThermalConductor", "ThermalResistor", "ConvectiveHeatTransfer",
           "ControlledConvectiveHeatTransfer", "BodyRadiation"]

#: Stefan-Boltzmann constant, W/(m^2 K^4) (CODATA 2018, exact).
SIGMA = 5.670374419e-8


class HeatCapacitor(Component):
    """Lumped thermal mass (Simscape: Thermal Mass).

    Equations::

        T = port.T
        C dT/dt = port.Q

    ``port.Q`` is the heat flow into the mass; it stores ``C (T - T_ref)`` of internal
    energy. Limitations: uniform temperature (Biot number << 1), constant heat capacity.
    """

    port = HeatPort(doc="Port of the mass")
    C = Parameter("J/K", default=1.0, min=0, doc="Heat capacity (mass times specific heat)")
    T = Variable("K", start=293.15, doc="Temperature of the mass")

    def equations(self):
        return [self.T == self.port.T, self.C * der(self.T) == self.port.Q]


class ThermalConductor(TwoPort):
    """Linear heat conduction (Simscape: Conductive Heat Transfer with ``G = k A / D``).

    Equations: ``Q = G dT`` with ``dT = A.T - B.T``; heat flows from the hotter port. The
    element stores no energy: ``A.Q + B.Q = 0``; it transfers ``Q`` from A to B.
    Limitations: constant conductance, no thermal mass (add a HeatCapacitor for it).
    """

    G = Parameter("W/K", default=1.0, min=0, doc="Thermal conductance")

    def equations(self):
        return [self.Q == self.G * self.dT]


class ThermalResistor(TwoPort):
    """Linear thermal resistance: ``dT = R Q``, the inverse of :class:`ThermalConductor`.

    Sign convention as :class:`TwoPort`: ``Q`` flows from A to B when ``A.T > B.T``.
    Limitations: ``R`` must be positive (a zero resistance is an ideal connection).
    """

    R = Parameter("K/W", default=1.0, min=0, doc="Thermal resistance")

    def equations(self):
        return [self.dT == self.R * self.Q]


class ConvectiveHeatTransfer(TwoPort):
    """Convection between a solid surface (A) and a fluid (B) (Simscape: Convective Heat
    Transfer).

    Equations: ``Q = h Area dT`` with ``dT = A.T - B.T``. Limitations: constant film
    coefficient ``h``; use :class:`ControlledConvectiveHeatTransfer` for a varying one.
    """

    h = Parameter("W/(m^2*K)", default=10.0, min=0, doc="Heat transfer coefficient")
    area = Parameter("m^2", default=1e-2, min=0, doc="Surface area")

    def equations(self):
        return [self.Q == self.h * self.area * self.dT]


class ControlledConvectiveHeatTransfer(TwoPort):
    """Convection with a thermal conductance given by a signal (Modelica: Convection).

    Equations: ``Q = Gc dT``, ``Gc = h A`` supplied by the input. Limitations: ``Gc``
    should stay >= 0 (not checked at run time).
    """

    Gc = Input("W/K", doc="Convective thermal conductance h*A")

    def equations(self):
        return [self.Q == self.Gc * self.dT]


class BodyRadiation(TwoPort):
    """Radiative exchange between two bodies (Simscape: Radiative Heat Transfer).

    Equations: ``Q = sigma Gr (A.T^4 - B.T^4)`` with ``Gr = epsilon * area`` the radiation
    factor (for two grey bodies: ``area / (1/eps_A + 1/eps_B - 1)`` for parallel plates)
    and ``sigma`` the Stefan-Boltzmann constant. Temperatures are absolute (K).
    Limitations: grey, diffuse surfaces; view factors are folded into ``Gr``.
    """

    Gr = Parameter("m^2", default=1e-2, min=0, doc="Net radiation factor emissivity*area")
    sigma = Parameter("W/(m^2*K^4)", default=SIGMA, min=0,
                      doc="Stefan-Boltzmann constant")

    def equations(self):
        return [self.Q == self.sigma * self.Gr * (self.A.T ** 4 - self.B.T ** 4)]
