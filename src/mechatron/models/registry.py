"""The registry of database entries; third-party packages add entries through the
``mechatron.models`` entry point group (each entry point loads a ModelEntry or a callable
returning one or a list of them)."""

from __future__ import annotations

import builtins
import difflib

from mechatron.errors import ModelError
from mechatron.models.entry import ModelEntry

__all__ = ["register", "get", "list"]

#: Modules of the package that register entries when imported.
BUILTIN_MODULES = ("dc_motor", "msd", "double_pendulum", "pmsm", "cart_pendulum",
                   "motor_heating", "quarter_car", "ball_screw", "kinetic_mechanism", "dc_motor_pwm",
                   "solenoid", "hydraulic_cylinder",
                   "buck_converter", "hbridge_filter", "stepper",
                   "bldc", "servo_encoder", "geared_drive", "two_axis", "dc_motor_control", "emps",
                   "planetary_hoist", "saturating_solenoid",
                   "two_clutch_gearbox", "battery_bldc",
                   "induction_dol")

_REGISTRY: dict[str, ModelEntry] = {}
_loaded = False


def register(entry: ModelEntry) -> ModelEntry:
    """Add an entry to the database (its name must be new)."""
    if entry.name in _REGISTRY and _REGISTRY[entry.name] is not entry:
        raise ModelError(f"model '{entry.name}' is registered already.")
    _REGISTRY[entry.name] = entry
    return entry


def _load() -> None:
    global _loaded
    if _loaded:
        return
    _loaded = True
    from importlib import import_module
    from importlib.metadata import entry_points
    for module in BUILTIN_MODULES:
        import_module(f"mechatron.models.{module}")      # each registers its entries
    for ep in entry_points(group="mechatron.models"):
        obj = ep.load()
        obj = obj() if callable(obj) and not isinstance(obj, ModelEntry) else obj
        for entry in (obj if isinstance(obj, (builtins.list, tuple)) else [obj]):
            register(entry)


def list() -> builtins.list[ModelEntry]:  # noqa: A001  (public name, documented in the README)
    """Every entry of the database, sorted by name."""
    _load()
    return [_REGISTRY[k] for k in sorted(_REGISTRY)]


def get(name: str) -> ModelEntry:
    """The entry called ``name``."""
    _load()
    if name not in _REGISTRY:
        close = difflib.get_close_matches(name, _REGISTRY, 3)
        raise ModelError(f"no model '{name}' in the database"
                         + (f"; did you mean {', '.join(close)}?" if close else ".")
                         + " List them with `mechatron models`.", path=name)
    return _REGISTRY[name]
