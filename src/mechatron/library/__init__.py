"""The component library, one subpackage per domain.

Each subpackage is imported on first access (``mechatron.library.electrical``), so a model
that uses two domains does not load the other ten.
"""

import importlib

__all__ = ["electrical", "rotational", "translational", "mechanisms", "electromechanical",
           "machines",
           "thermal", "magnetic", "hydraulic", "physical_signals", "blocks", "multibody"]


def __getattr__(name: str):
    if name in __all__:
        module = importlib.import_module(f"{__name__}.{name}")
        globals()[name] = module
        return module
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))
