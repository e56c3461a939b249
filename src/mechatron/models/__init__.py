"""The database of mechatronic models.

``list()`` gives every entry; ``get(name)`` one :class:`ModelEntry` with ``build``,
``experiment``, ``parameters`` (units, defaults, provenance), ``outputs``, ``variants`` and
``expected`` values. The modules defining the entries are imported by the first ``list()``
or ``get()`` (or on access to one of them, ``mechatron.models.dc_motor``).
"""

import importlib

from mechatron.models.entry import Experiment, ModelEntry, ParameterInfo
from mechatron.models.registry import BUILTIN_MODULES, get, list, register  # noqa: A004

__all__ = ["ModelEntry", "Experiment", "ParameterInfo", "get", "list", "register"]


def __getattr__(name: str):
    if name in BUILTIN_MODULES or name == "compare":
        return importlib.import_module(f"{__name__}.{name}")
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
