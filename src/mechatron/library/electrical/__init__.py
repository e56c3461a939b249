"""Electrical domain: across = voltage v (V), through = current i (A).

Pins are ``p`` and ``n``; a two-pin component's ``v = p.v - n.v`` and ``i`` flows from
``p`` through the component to ``n`` (positive into ``p``). ``v * i > 0`` is power absorbed.
Four-pin parts (controlled sources, transformers) have ports ``p1``/``n1`` and
``p2``/``n2``; op-amps ``in_p``, ``in_n``, ``out``; MOSFETs ``p`` (drain), ``n`` (source)
and ``gate``. Current sources push their current ``i`` from ``p`` through the source to
``n``.
"""

from mechatron.library.electrical.ideal import (FiniteGainOpAmp, IdealOpAmp, IdealSwitch,
                                                IdealTransformer, SaturatingOpAmp)
from mechatron.library.electrical.interfaces import OnePort, Pin, TwoPort
from mechatron.library.electrical.passive import (Capacitor, Diode, HeatingResistor, Inductor,
                                                  MutualInductor, Potentiometer, Resistor,
                                                  VariableResistor)
from mechatron.library.electrical.battery import Battery
from mechatron.library.electrical.converters import HalfBridge, HBridge, ThreePhaseBridge
from mechatron.library.electrical.semiconductors import (NMOSFET, NPN, PMOSFET, PNP,
                                                         ExponentialDiode, Thyristor,
                                                         ZenerDiode)
from mechatron.library.electrical.sensors import CurrentSensor, PowerSensor, VoltageSensor
from mechatron.library.electrical.sources import (ACCurrentSource, ACVoltageSource,
                                                  ControlledCurrentSource,
                                                  ControlledPWMVoltageSource,
                                                  ControlledVoltageSource,
                                                  CurrentControlledCurrentSource,
                                                  CurrentControlledVoltageSource,
                                                  DCCurrentSource, DCVoltageSource,
                                                  ElectricalReference, ExpSineCurrent,
                                                  ExpSineVoltage, PulseCurrent, PulseVoltage,
                                                  PWMVoltageSource, RampCurrent, RampVoltage,
                                                  StepCurrent, StepVoltage, TableCurrent,
                                                  TableVoltage, TrapezoidCurrent,
                                                  TrapezoidVoltage,
                                                  VoltageControlledCurrentSource,
                                                  VoltageControlledVoltageSource)
from mechatron.library.rotational.encoders import HallSensor, IncrementalEncoder

__all__ = ["Pin", "OnePort", "TwoPort", "Resistor", "Inductor", "Capacitor", "Diode",
           "DCVoltageSource", "ControlledVoltageSource", "DCCurrentSource",
           "ElectricalReference", "CurrentSensor", "VoltageSensor",
           # issue 3
           "VariableResistor", "HeatingResistor", "Potentiometer", "MutualInductor",
           "IdealTransformer", "IdealOpAmp", "FiniteGainOpAmp", "SaturatingOpAmp",
           "IdealSwitch", "ExponentialDiode", "NMOSFET", "PMOSFET", "PowerSensor",
           "ACVoltageSource", "ACCurrentSource", "ControlledCurrentSource",
           "PWMVoltageSource", "ControlledPWMVoltageSource",
           "VoltageControlledVoltageSource", "VoltageControlledCurrentSource",
           "CurrentControlledVoltageSource", "CurrentControlledCurrentSource",
           # issue 18
           "StepVoltage", "RampVoltage", "PulseVoltage", "TrapezoidVoltage", "ExpSineVoltage",
           "TableVoltage", "StepCurrent", "RampCurrent", "PulseCurrent", "TrapezoidCurrent",
           "ExpSineCurrent", "TableCurrent", "ZenerDiode", "Thyristor", "NPN", "PNP",
           "HalfBridge", "HBridge", "ThreePhaseBridge", "Battery",
           # drive sensors (defined in mechatron.library.rotational.encoders)
           "IncrementalEncoder", "HallSensor"]
