"""Electrical machines (Modelica's ``Electrical.Machines``): each one part with electrical
pins, a shaft ``flange`` and a housing ``support``, built as a subsystem of library
components. ``use_heat_port=True`` builds a machine with a ``heat_port`` that takes its
losses (MSL's ``useThermalPort``)."""

from mechatron.library.machines.dc import (AirGapDC, DCElectricalExcited,
                                           DCElectricalExcitedWithHeatPort, DCPermanentMagnet,
                                           DCPermanentMagnetWithHeatPort, DCSeries,
                                           DCSeriesWithHeatPort, DCShunt, DCShuntWithHeatPort)
from mechatron.library.machines.induction import (AirGapInduction, InductionMachine,
                                                  InductionMachineWithHeatPort)
from mechatron.library.machines.synchronous import (PMSM, AirGapPMSM, AirGapTrapezoidal,
                                                    PMSMWithHeatPort, TrapezoidalPMSM,
                                                    TrapezoidalPMSMWithHeatPort, trapezoid)

__all__ = ["DCPermanentMagnet", "DCElectricalExcited", "DCSeries", "DCShunt", "AirGapDC",
           "DCPermanentMagnetWithHeatPort", "DCElectricalExcitedWithHeatPort",
           "DCSeriesWithHeatPort", "DCShuntWithHeatPort",
           "PMSM", "TrapezoidalPMSM", "AirGapPMSM", "AirGapTrapezoidal", "PMSMWithHeatPort",
           "TrapezoidalPMSMWithHeatPort", "trapezoid", "InductionMachine", "AirGapInduction",
           "InductionMachineWithHeatPort"]
