"""Mechatron: acausal modeling, simulation, identification and real-time code for
mechatronic systems.

>>> import mechatron as mt
>>> res = mt.simulate(mt.models.get("dc_motor").build(), 0.5)
"""

from mechatron.compiler import CompiledModel, compile_model
from mechatron.core import (Across, Component, Connector, Domain, Input, Output, Parameter,
                            Start, System, Through, Variable, connect, der, if_else)
from mechatron.core.events import Clock, sample, when
from mechatron.results import SimResult, SolverStats
from mechatron.solvers import simulate
from mechatron import errors, library, models  # noqa: E402  (public subpackages)

__version__ = "0.1.0"

__all__ = ["Component", "Connector", "Domain", "System", "Parameter", "Variable", "Start",
           "Across", "Through", "Input", "Output", "connect", "der", "if_else",
           "Clock", "sample", "when",
           "compile_model", "CompiledModel", "simulate", "SimResult", "SolverStats",
           "library", "models"]
