"""Mechatron: acausal modeling, simulation, identification and real-time code for
mechatronic systems.

>>> import mechatron as mt
>>> res = mt.simulate(mt.models.get("dc_motor").build(), 0.5)
"""

from mechatron.compiler import CompiledModel, compile_model
from mechatron.core import (Across, Component, Connector, Discrete, Domain, Input, Output,
                            Parameter, Start, System, Through, Variable, connect, der,
                            if_else, logic_and, logic_not, logic_or)
from mechatron.core.events import (Clock, initial, pre, reinit, sample, steady_state,
                                   terminal, when)
from mechatron.results import SimResult, SolverStats
from mechatron.solvers import simulate
from mechatron import errors, library, models  # noqa: E402  (public subpackages)

__version__ = "0.1.0"

__all__ = ["Component", "Connector", "Domain", "System", "Parameter", "Variable", "Start",
           "Across", "Through", "Input", "Output", "connect", "der", "if_else",
           "Clock", "sample", "when", "Discrete", "pre", "initial", "terminal", "reinit",
           "steady_state", "logic_and", "logic_or", "logic_not",
           "compile_model", "CompiledModel", "simulate", "SimResult", "SolverStats",
           "library", "models"]
