"""Thermal sources, the reference and sensors."""

from mechatron.core import Component, Input, Output, Parameter
from mechatron.library.thermal.interfaces import HeatPort, TwoPort

__all__ = ["FixedTemperature", "PrescribedTemperature", "HeatFlowSource",
           "PrescribedHeatFlow", "ThermalReference", "TemperatureSensor",
           "RelativeTemperatureSensor", "HeatFlowSensor"]


class FixedTemperature(Component):
    """Ideal constant temperature source (Modelica: FixedTemperature; Simscape: Ideal
    Temperature Source with a constant input).

    Equations: ``port.T = T``. Supplies or absorbs whatever heat flow the network needs;
    ``port.Q > 0`` is heat flowing into the source (out of the network).
    """

    port = HeatPort(doc="Port held at T")
    T = Parameter("K", default=293.15, min=0, doc="Fixed absolute temperature")

    def equations(self):
        return [self.port.T == self.T]


class PrescribedTemperature(Component):
    """Ideal temperature source driven by a signal: ``port.T = T_in``."""

    port = HeatPort(doc="Port held at T_in")
    T_in = Input("K", doc="Commanded absolute temperature")

    def equations(self):
        return [self.port.T == self.T_in]


class ThermalReference(Component, reference=True):
    """Thermal reference (Simscape: Thermal Reference): absolute zero, ``port.T = 0 K``.

    Use it as the far end of heat-flow sources and sensors that need one; most networks
    are referenced by a FixedTemperature or by heat capacitors instead.
    """

    port = HeatPort(doc="Port at 0 K")

    def equations(self):
        return [self.port.T == 0]


class HeatFlowSource(Component):
    """Ideal constant heat flow source injecting ``Q_flow`` into the network at ``port``.

    Equations: ``port.Q = -Q_flow`` (the through variable is positive into the component,
    so a positive ``Q_flow`` leaves the source and heats what is connected).
    """

    port = HeatPort(doc="Port the heat is injected at")
    Q_flow = Parameter("W", default=1.0, doc="Heat flow into the network")

    def equations(self):
        return [self.port.Q == -self.Q_flow]


class PrescribedHeatFlow(Component):
    """Heat flow source driven by a signal: ``port.Q = -Q_in`` (``Q_in`` into the
    network)."""

    port = HeatPort(doc="Port the heat is injected at")
    Q_in = Input("W", doc="Commanded heat flow into the network")

    def equations(self):
        return [self.port.Q == -self.Q_in]


class TemperatureSensor(Component):
    """Ideal absolute thermometer: ``port.Q = 0``, output ``T = port.T``."""

    port = HeatPort(doc="Measured port")
    T = Output("K", doc="Measured absolute temperature")

    def equations(self):
        return [self.port.Q == 0, self.T == self.port.T]


class RelativeTemperatureSensor(TwoPort):
    """Ideal differential thermometer: ``Q = 0``, output ``T_rel = A.T - B.T``."""

    T_rel = Output("K", doc="Measured temperature difference A.T - B.T")

    def equations(self):
        return [self.Q == 0, self.T_rel == self.dT]


class HeatFlowSensor(TwoPort):
    """Ideal heat flow meter in series: ``dT = 0``, output ``Q_flow = Q`` (from A to B)."""

    Q_flow = Output("W", doc="Measured heat flow from A to B")

    def equations(self):
        return [self.dT == 0, self.Q_flow == self.Q]
