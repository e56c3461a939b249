"""The component library, one subpackage per domain (DESIGN.md §3)."""

from mechatron.library import (blocks, electrical, electromechanical, rotational,
                               translational)

__all__ = ["electrical", "rotational", "translational", "electromechanical", "blocks"]
