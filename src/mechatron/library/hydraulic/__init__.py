"""Isothermal-liquid hydraulic domain: across = pressure p (Pa), through = volumetric flow
rate q (m^3/s).

Sign rules: flow is positive when it enters the component at the port. Two-port
components have ports ``A`` and ``B``: ``dp = A.p - B.p`` and ``q`` flows from A to B
through the component. Pressures are gauge (relative to the atmosphere); components that
need absolute pressure (gas accumulator) add their ``p_atm``. Sources are oriented like a
pump, from A (inlet) to B (outlet): ``FlowSource`` delivers ``Q`` at B,
``PressureSource`` keeps ``B.p - A.p = P``. One-port components (chamber, accumulators,
reservoir) have a single port ``port``; multi-port ones use their Simscape names (valve
``P``, ``T``, ``A``, ``B``; cylinder ``A``, ``B`` and translational ``rod``, ``case``;
pump and motor ``A``, ``B`` and rotational ``shaft``, ``case``). Every hydraulic network
needs a ``HydraulicReference`` or a ``Reservoir``.

The fluid's density ``rho``, kinematic viscosity ``nu`` and bulk modulus ``beta`` are
parameters of each component that needs them, defaulting to ``ISO_VG32``; a
:class:`Fluid` hands them over with ``**fluid.params_for(Component)``.
"""

from mechatron.library.hydraulic.components import (CheckValve, CompressiblePipe,
                                                    ConstantVolumeChamber,
                                                    DoubleActingCylinder,
                                                    FixedDisplacementMotor,
                                                    FixedDisplacementPump, FixedOrifice,
                                                    FourWayDirectionalValve,
                                                    GasChargedAccumulator, ResistivePipe,
                                                    SpringLoadedAccumulator,
                                                    VariableOrifice, orifice_flow)
from mechatron.library.hydraulic.interfaces import ISO_VG32, Fluid, HydraulicPort, TwoPort
from mechatron.library.hydraulic.sources import (ControlledFlowSource,
                                                 ControlledPressureSource, FlowSensor,
                                                 FlowSource, HydraulicReference,
                                                 PressureSensor, PressureSource, Reservoir)

__all__ = ["HydraulicPort", "TwoPort", "Fluid", "ISO_VG32", "orifice_flow",
           "FixedOrifice", "VariableOrifice", "ResistivePipe", "CompressiblePipe",
           "ConstantVolumeChamber", "DoubleActingCylinder", "FixedDisplacementPump",
           "FixedDisplacementMotor", "CheckValve", "FourWayDirectionalValve",
           "GasChargedAccumulator", "SpringLoadedAccumulator", "HydraulicReference",
           "Reservoir", "FlowSource", "ControlledFlowSource", "PressureSource",
           "ControlledPressureSource", "PressureSensor", "FlowSensor"]
