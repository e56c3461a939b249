"""Interfaces of the signal blocks: signal ports and the helpers that build blocks with a
size chosen at construction (a transfer function's order, a switch's number of inputs).

Signals are dimensionless numbers in SI (a block does not know what its signal means);
Boolean signals are 0.0/1.0 and integer signals whole numbers, both carried as floats.
"""

from __future__ import annotations

import numpy as np

from mechatron.core import Component, Input, Output, Parameter, Variable
from mechatron.errors import ModelError

__all__ = ["SISO", "MISO2", "Sampled", "sized", "piecewise_linear", "hat"]


class SISO(Component, partial=True):
    """One input ``u``, one output ``y``."""

    u = Input("1", doc="Input signal")
    y = Output("1", doc="Output signal")


class MISO2(Component, partial=True):
    """Two inputs ``u1``, ``u2``, one output ``y``."""

    u1 = Input("1", doc="First input")
    u2 = Input("1", doc="Second input")
    y = Output("1", doc="Output signal")


class Sampled(Component, partial=True):
    """A block sampled at ``t_k = offset + k * Ts`` (Simulink's sample time
    ``[Ts, offset]``); its output is held between samples."""

    Ts = Parameter("s", default=1e-3, min=0, doc="Sample time")
    offset = Parameter("s", default=0.0, min=0, doc="Sample time offset (first sample)")


_SIZED: dict = {}


def sized(base: type, n: int, extra: dict) -> type:
    """A concrete subclass of ``base`` with the declarations ``extra`` (cached by size).

    Used for blocks whose number of states or inputs is given at construction; the class
    keeps the base's name, so messages read ``TransferFunction 'plant'``.
    """
    key = (base, n)
    cls = _SIZED.get(key)
    if cls is None:
        cls = type(base.__name__, (base,), dict(extra, __module__=base.__module__,
                                                __doc__=base.__doc__, __qualname__=
                                                f"{base.__qualname__}[{n}]"))
        _SIZED[key] = cls
    return cls


def states(n: int, unit: str = "1", what: str = "State") -> dict:
    """``n`` state declarations ``x1 .. xn`` (start 0)."""
    return {f"x{i + 1}": Variable(unit, start=0.0, doc=f"{what} {i + 1}") for i in range(n)}


def coefficients(values, name: str, owner: str) -> np.ndarray:
    """A 1-D array of finite floats, or a clear error naming the block."""
    try:
        arr = np.atleast_1d(np.asarray(values, dtype=float))
    except (TypeError, ValueError):
        raise ModelError(f"{owner}: {name} must be a sequence of numbers, got "
                         f"{values!r}.") from None
    if arr.ndim != 1 or arr.size == 0 or not np.all(np.isfinite(arr)):
        raise ModelError(f"{owner}: {name} must be a non-empty 1-D sequence of finite "
                         f"numbers, got {values!r}.")
    return arr


def piecewise_linear(u, x: np.ndarray, y: np.ndarray):
    """Linear interpolation of the table ``(x, y)`` at ``u`` (clamped to ``[x0, xn]``) as
    one CasADi expression: ``y0 + s0 (u - x0) + sum_k (s_k - s_k-1) max(u - x_k, 0)``
    with the slopes ``s_k`` of the segments. Exact at the breakpoints, kinks there (no
    events), and plain SX (no function-call node), so it compiles and generates C like
    any other equation."""
    import casadi as ca
    uc = ca.fmin(ca.fmax(u, float(x[0])), float(x[-1]))
    slopes = np.diff(y) / np.diff(x)
    out = float(y[0]) + float(slopes[0]) * (uc - float(x[0]))
    for k in range(1, slopes.size):
        ds = float(slopes[k] - slopes[k - 1])
        if ds:
            out = out + ds * ca.fmax(uc - float(x[k]), 0.0)
    return out


def hat(u, x: np.ndarray, i: int):
    """The i-th linear interpolation basis function ("hat") of the breakpoints ``x`` at
    ``u``: 1 at ``x[i]``, 0 at the other breakpoints."""
    e = np.zeros(x.size)
    e[i] = 1.0
    return piecewise_linear(u, x, e)
