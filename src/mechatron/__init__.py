"""Mechatron: acausal modeling, simulation, identification and real-time code for
mechatronic systems.

>>> import mechatron as mt
>>> res = mt.simulate(mt.models.get("dc_motor").build(), 0.5)
"""

import logging as _logging

# The library logs to the "mechatron" logger and never prints; an application chooses
# what to show (the command line shows warnings, and more with -v).
_logging.getLogger("mechatron").addHandler(_logging.NullHandler())

from mechatron.compiler import CompiledModel, compile_model  # noqa: E402
from mechatron.core import (Across, Component, Connector, Discrete, Domain, Input, Output,
                            Parameter, Start, System, Through, Variable, connect, der,
                            if_else, logic_and, logic_not, logic_or)
from mechatron.core.events import (Clock, initial, pre, reinit, sample, steady_state,
                                   terminal, when)
from mechatron.results import SimResult, SolverStats
from mechatron.solvers import simulate
from mechatron.analysis import OperatingPoint, linearize, trim
from mechatron import errors, library, models  # noqa: E402  (public subpackages)

__version__ = "0.1.0"

__all__ = ["Component", "Connector", "Domain", "System", "Parameter", "Variable", "Start",
           "Across", "Through", "Input", "Output", "connect", "der", "if_else",
           "Clock", "sample", "when", "Discrete", "pre", "initial", "terminal", "reinit",
           "steady_state", "logic_and", "logic_or", "logic_not",
           "compile_model", "CompiledModel", "simulate", "SimResult", "SolverStats",
           "linearize", "trim", "OperatingPoint",
           "library", "models"]
