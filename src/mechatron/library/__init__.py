"""The component library, one subpackage per domain."""

from mechatron.library import (blocks, electrical, electromechanical, hydraulic, machines,
                               magnetic, mechanisms, multibody, physical_signals, rotational,
                               thermal, translational)

__all__ = ["electrical", "rotational", "translational", "mechanisms", "electromechanical",
           "machines",
           "thermal", "magnetic", "hydraulic", "physical_signals", "blocks", "multibody"]
