"""FMU import: an FMU made by any FMI 2.0 or 3.0 tool as a sampled block of a model.

- :class:`FMUComponent` (``mt.FMUComponent``): the block, with the FMU's inputs, outputs
  and parameters as its ports and parameters (:mod:`mechatron.fmi.component`).
- :func:`cosimulate`: what ``mt.simulate`` runs for a model holding such blocks (the host
  integrated between communication points, the FMUs stepped at them through FMPy;
  :mod:`mechatron.fmi.cosim`).

See docs/fmu_import.md.
"""

from mechatron.fmi.component import FMUComponent, describe_fmu, port_name
from mechatron.fmi.cosim import cosimulate

__all__ = ["FMUComponent", "cosimulate", "describe_fmu", "port_name"]
