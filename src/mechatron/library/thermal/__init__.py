"""Thermal domain: across = temperature T (K), through = heat flow Q (W).

Sign rules: a through variable is positive when heat flows **into** the component at the
port. Two-port components have ports ``A`` and ``B``: ``dT = A.T - B.T`` and ``Q`` is the
heat flow into the component at ``A`` (and out at ``B``), so ``Q > 0`` when heat passes
from A to B. One-port components (heat capacitor, sources, sensors, reference) have a
single port ``port``. Sources are written from the network's side: ``HeatFlowSource``'s
``Q_flow > 0`` heats what is connected. Temperatures are absolute (K): radiation needs it.

Thermal networks need no explicit reference component: a ``FixedTemperature`` or a
``HeatCapacitor`` fixes the temperature level.
"""

from mechatron.library.thermal.components import (BodyRadiation,
                                                  ControlledConvectiveHeatTransfer,
                                                  ConvectiveHeatTransfer, HeatCapacitor,
                                                  ThermalConductor, ThermalResistor)
from mechatron.library.thermal.interfaces import HeatPort, TwoPort
from mechatron.library.thermal.sources import (FixedTemperature, HeatFlowSensor,
                                               HeatFlowSource, PrescribedHeatFlow,
                                               PrescribedTemperature,
                                               RelativeTemperatureSensor,
                                               TemperatureSensor, ThermalReference)

__all__ = ["HeatPort", "TwoPort", "HeatCapacitor", "ThermalConductor", "ThermalResistor",
           "ConvectiveHeatTransfer", "ControlledConvectiveHeatTransfer", "BodyRadiation",
           "FixedTemperature", "PrescribedTemperature", "ThermalReference",
           "HeatFlowSource", "PrescribedHeatFlow", "TemperatureSensor",
           "RelativeTemperatureSensor", "HeatFlowSensor"]
