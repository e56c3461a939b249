"""The registry of database entries; third-party packages add entries through the
``mechatron.models`` entry point group (each entry point loads a ModelEntry or a callable
returning one or a list of them)."""

from __future__ import annotations

import builtins
import difflib

from mechatron.errors import ModelError
from mechatron.models.entry import ModelEntry

__all__ = ["register", "get", "list"]

#: The module that registers each built-in entry (in loading order), so that `get`
#: imports that module alone (importing every model imports the whole library and
#: SciPy's optimizers: about a second); a name not here loads them all.
#: ``tests/models/test_registry.py`` checks it against the registrations.
_MODULE_OF = {"dc_motor": "dc_motor", "msd_horizontal": "msd", "msd_incline": "msd",
              "msd_vertical": "msd", "double_pendulum": "double_pendulum",
              "pmsm_foc": "pmsm", "cart_pendulum": "cart_pendulum",
              "motor_heating": "motor_heating", "quarter_car": "quarter_car",
              "ball_screw_axis": "ball_screw", "kinetic_mechanism": "kinetic_mechanism",
              "dc_motor_pwm": "dc_motor_pwm", "solenoid": "solenoid",
              "hydraulic_cylinder": "hydraulic_cylinder",
              "buck_converter": "buck_converter", "hbridge_rc_filter": "hbridge_filter",
              "stepper_motor": "stepper", "bldc_motor": "bldc",
              "servo_encoder": "servo_encoder", "geared_drive": "geared_drive",
              "two_axis": "two_axis", "dc_motor_position_pi": "dc_motor_control",
              "dc_motor_speed_pi": "dc_motor_control", "emps": "emps",
              "planetary_hoist": "planetary_hoist",
              "saturating_solenoid": "saturating_solenoid",
              "two_clutch_gearbox": "two_clutch_gearbox", "battery_bldc": "battery_bldc",
              "induction_dol": "induction_dol"}

#: Modules of the package that register entries when imported, in the order they load.
BUILTIN_MODULES = tuple(dict.fromkeys(_MODULE_OF.values()))

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
    if name not in _REGISTRY and name in _MODULE_OF and not _loaded:
        from importlib import import_module
        import_module(f"mechatron.models.{_MODULE_OF[name]}")
    if name not in _REGISTRY:
        _load()
    if name not in _REGISTRY:
        close = difflib.get_close_matches(name, _REGISTRY, 3)
        raise ModelError(f"no model '{name}' in the database"
                         + (f"; did you mean {', '.join(close)}?" if close else ".")
                         + " List them with `mechatron models`.", path=name)
    return _REGISTRY[name]
