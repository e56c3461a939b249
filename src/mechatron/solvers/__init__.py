"""Simulation: ``simulate`` dispatches to variable-step SUNDIALS or a fixed-step method."""

from mechatron.solvers.fixed import METHODS, make_step
from mechatron.solvers.simulate import SOLVERS, simulate

__all__ = ["simulate", "make_step", "METHODS", "SOLVERS"]
