"""Electrical domain: across = voltage v (V), through = current i (A).

Pins are ``p`` and ``n``; a two-pin component's ``v = p.v - n.v`` and ``i`` flows from
``p`` through the component to ``n`` (positive into ``p``). ``v * i > 0`` is power absorbed.
"""

from mechatron.library.electrical.interfaces import OnePort, Pin
from mechatron.library.electrical.passive import Capacitor, Diode, Inductor, Resistor
from mechatron.library.electrical.sensors import CurrentSensor, VoltageSensor
from mechatron.library.electrical.sources import (ControlledVoltageSource, DCCurrentSource,
                                                  DCVoltageSource, ElectricalReference)

__all__ = ["Pin", "OnePort", "Resistor", "Inductor", "Capacitor", "Diode",
           "DCVoltageSource", "ControlledVoltageSource", "DCCurrentSource",
           "ElectricalReference", "CurrentSensor", "VoltageSensor"]
