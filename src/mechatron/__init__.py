"""Mechatron: acausal modeling, simulation, identification and real-time code for
mechatronic systems.

>>> import mechatron as mt
>>> res = mt.simulate(mt.models.get("dc_motor").build(), 0.5)

``import mechatron`` loads the modeling language only; the compiler, the solvers, the
component library, the model database and the applications (codegen, estimation, realtime,
report, viz) are imported on first use of their name (``mt.simulate``,
``mt.library.electrical``, ``mt.models.get``, ...), and pint, SciPy, pandas and matplotlib
when a function needs them.
"""

from __future__ import annotations

import importlib
import logging as _logging

from mechatron import errors
from mechatron.core import (Across, Component, Connector, Discrete, Domain, Input, Output,
                            Parameter, Start, System, Through, Variable, connect, der,
                            if_else, logic_and, logic_not, logic_or)
from mechatron.core.events import (Clock, initial, pre, reinit, sample, steady_state,
                                   terminal, when)

# The library logs to the "mechatron" logger and never prints; an application chooses
# what to show (the command line shows warnings, and more with -v).
_logging.getLogger("mechatron").addHandler(_logging.NullHandler())

TYPE_CHECKING = False       # typing.TYPE_CHECKING without importing typing
if TYPE_CHECKING:
    from mechatron import (analysis, cli, codegen, compiler, core, estimation, library,
                           models, realtime, report, results, solvers, units, viz)
    from mechatron.analysis import OperatingPoint, linearize, trim
    from mechatron.compiler import CompiledModel, compile_model
    from mechatron.fmi import FMUComponent
    from mechatron.results import SimResult, SolverStats
    from mechatron.solvers import simulate

__version__ = "0.1.0"

__all__ = ["Component", "Connector", "Domain", "System", "Parameter", "Variable", "Start",
           "Across", "Through", "Input", "Output", "connect", "der", "if_else",
           "Clock", "sample", "when", "Discrete", "pre", "initial", "terminal", "reinit",
           "steady_state", "logic_and", "logic_or", "logic_not",
           "compile_model", "CompiledModel", "simulate", "SimResult", "SolverStats",
           "linearize", "trim", "OperatingPoint", "FMUComponent",
           "library", "models"]

#: Public names imported on first access: name -> module that defines it.
_LAZY_NAMES = {"compile_model": "mechatron.compiler",
               "linearize": "mechatron.analysis",
               "trim": "mechatron.analysis",
               "OperatingPoint": "mechatron.analysis",
               "FMUComponent": "mechatron.fmi",
               "CompiledModel": "mechatron.compiler.compiled",
               "simulate": "mechatron.solvers",
               "SimResult": "mechatron.results",
               "SolverStats": "mechatron.results"}

#: Subpackages reachable as attributes (``mt.library``, ``mt.codegen``) before an import.
_SUBMODULES = frozenset({"analysis", "cli", "codegen", "compiler", "core", "estimation", "fmi",
                         "library",
                         "models", "realtime", "report", "results", "solvers", "units",
                         "viz"})


def __getattr__(name: str):
    if name in _LAZY_NAMES:
        value = getattr(importlib.import_module(_LAZY_NAMES[name]), name)
    elif name in _SUBMODULES:
        value = importlib.import_module(f"{__name__}.{name}")
    else:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    globals()[name] = value     # later accesses are plain attribute lookups
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_LAZY_NAMES) | _SUBMODULES)
