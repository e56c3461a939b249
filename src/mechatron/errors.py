"""The one exception hierarchy of Mechatron.

Every error subclasses a builtin so that ``except ValueError`` keeps working, and carries
structured fields beside its message: ``path`` (the instance path it concerns, if one),
``problems`` (every problem found, when a validator collected several), ``variables`` and
``equations`` (the suspects of a structural error). Messages follow one form:
``<instance path>: <what is wrong>[, got <value>]. <likely cause / what to try>.``
Exceptions never print.
"""

from __future__ import annotations

__all__ = [
    "MechatronError",
    "ModelError",
    "ConnectError",
    "ParameterError",
    "UnitError",
    "StructuralError",
    "InitializationError",
    "SimulationError",
    "RunTooLargeError",
    "DataError",
    "UnknownVariableError",
]


class MechatronError(Exception):
    """Base of every Mechatron error."""

    def __init__(self, message: str, *, path: str | None = None,
                 problems: list[str] | None = None,
                 variables: list[str] | None = None,
                 equations: list[str] | None = None):
        super().__init__(message)
        self.path = path
        self.problems = list(problems) if problems else [message]
        self.variables = list(variables or [])
        self.equations = list(equations or [])


class ModelError(MechatronError, ValueError):
    """A model is wrong: a missing reference, an unconnected port, a bad declaration."""


class ConnectError(ModelError):
    """Ports that cannot be connected (different domains, a signal output to an output)."""


class ParameterError(MechatronError, ValueError):
    """A parameter value is invalid (out of range, not a number)."""


class UnitError(ParameterError):
    """A value has the wrong physical dimension or an unknown unit."""


class StructuralError(ModelError):
    """The equations cannot be matched to the unknowns (over- or under-determined)."""


class InitializationError(MechatronError, ValueError):
    """No consistent initial state satisfies the targets."""


class SimulationError(MechatronError, RuntimeError):
    """The solver failed (step size too small, Newton failure, chattering)."""


class RunTooLargeError(SimulationError):
    """A run refused before it starts: its estimated memory is above the limit."""


class DataError(MechatronError, ValueError):
    """Measured or user-supplied data are malformed (NaN, missing column, bad time axis)."""


class UnknownVariableError(MechatronError, KeyError):
    """A variable name that a simulation log (or model) does not hold.

    Subclasses :class:`KeyError`, so ``except KeyError`` keeps working. ``path`` is the
    name asked for; ``variables`` lists the closest known names (the suggestions).
    """

    def __str__(self) -> str:
        # KeyError would show the repr of the message, quotes and escaped newlines included.
        return str(self.args[0]) if self.args else ""
