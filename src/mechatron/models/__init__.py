"""The database of mechatronic models.

``list()`` gives every entry; ``get(name)`` one :class:`ModelEntry` with ``build``,
``experiment``, ``parameters`` (units, defaults, provenance), ``outputs``, ``variants`` and
``expected`` values.
"""

from mechatron.models.entry import Experiment, ModelEntry, ParameterInfo
from mechatron.models.registry import get, list, register  # noqa: A004
from mechatron.models import dc_motor_control  # noqa: E402,F401  (registers its entries)

__all__ = ["ModelEntry", "Experiment", "ParameterInfo", "get", "list", "register"]
