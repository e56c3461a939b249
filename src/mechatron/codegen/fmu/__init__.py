"""FMU export: FMI 2.0 co-simulation and model exchange, FMI 3.0 co-simulation."""

from mechatron.codegen.fmu.export import export_fmu, fmi_platform

__all__ = ["export_fmu", "fmi_platform"]
