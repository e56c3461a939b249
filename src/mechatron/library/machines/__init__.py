"""Electrical machines (Modelica's ``Electrical.Machines``): each one part with electrical
pins, a shaft ``flange`` and a housing ``support``, built as a subsystem of library
components."""

from mechatron.library.machines.dc import (AirGapDC, DCElectricalExcited, DCPermanentMagnet,
                                           DCSeries, DCShunt)

__all__ = ["DCPermanentMagnet", "DCElectricalExcited", "DCSeries", "DCShunt", "AirGapDC"]
