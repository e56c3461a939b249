"""Hydraulic sources, references and sensors."""

from mechatron.core import Component, Input, Output, Parameter
from mechatron.library.hydraulic.interfaces import HydraulicPort, TwoPort

__all__ = ["HydraulicReference", "Reservoir", "FlowSource", "ControlledFlowSource",
           "PressureSource", "ControlledPressureSource", "PressureSensor", "FlowSensor"]


class HydraulicReference(Component, reference=True):
    """Hydraulic reference: atmospheric pressure, ``port.p = 0`` (gauge)."""

    port = HydraulicPort(doc="Port at zero gauge pressure")

    def equations(self):
        return [self.port.p == 0]


class Reservoir(Component, reference=True):
    """Tank at a constant pressure (Simscape: Reservoir): ``port.p = p``. It takes or
    gives any flow and references the network."""

    port = HydraulicPort(doc="Tank port")
    p = Parameter("Pa", default=0.0, doc="Tank pressure (gauge)")

    def equations(self):
        return [self.port.p == self.p]


class FlowSource(TwoPort):
    """Ideal constant flow source: ``q = Q`` from A to B through the source, so the
    source draws ``Q`` from the circuit at ``A`` and delivers it at ``B``."""

    Q = Parameter("m^3/s", default=1e-4, doc="Flow rate from A to B through the source")

    def equations(self):
        return [self.q == self.Q]


class ControlledFlowSource(TwoPort):
    """Ideal flow source driven by a signal: ``q = Q_in`` from A to B."""

    Q_in = Input("m^3/s", doc="Commanded flow rate from A to B through the source")

    def equations(self):
        return [self.q == self.Q_in]


class PressureSource(TwoPort):
    """Ideal constant pressure source: ``B.p - A.p = P`` (it raises the pressure from A,
    the inlet, to B, the outlet)."""

    P = Parameter("Pa", default=1e6, doc="Pressure rise B.p - A.p")

    def equations(self):
        return [self.dp == -self.P]


class ControlledPressureSource(TwoPort):
    """Ideal pressure source driven by a signal: ``B.p - A.p = P_in``."""

    P_in = Input("Pa", doc="Commanded pressure rise B.p - A.p")

    def equations(self):
        return [self.dp == -self.P_in]


class PressureSensor(TwoPort):
    """Ideal pressure sensor across two ports: ``q = 0``, output ``p_rel = A.p - B.p``."""

    p_rel = Output("Pa", doc="Measured pressure difference A.p - B.p")

    def equations(self):
        return [self.q == 0, self.p_rel == self.dp]


class FlowSensor(TwoPort):
    """Ideal flow meter in series: ``dp = 0``, output ``Q = q`` (from A to B)."""

    Q = Output("m^3/s", doc="Measured flow rate from A to B")

    def equations(self):
        return [self.dp == 0, self.Q == self.q]
