"""Which results of an optimization sit on a bound.

A parameter or gain that ends on its bound is not an interior optimum: the bound, not the
data or the requirements, decided its value, and the optimum may lie beyond it. Estimation
and response optimization flag such values in their results and reports.
"""

from __future__ import annotations

import math

import numpy as np

from mechatron.errors import ParameterError

__all__ = ["at_bounds", "describe_at_bounds", "check_bounds"]

#: A value within this fraction of its scale from a bound counts as on it.
RTOL = 1e-6


def at_bounds(names, values, lower, upper, scales=None, rtol: float = RTOL) -> dict:
    """``{name: {"side": "min"|"max", "bound": b}}`` for every value on a finite bound.

    A value counts as on its bound when it is within ``rtol`` times its scale (default:
    the larger of ``|bound|`` and ``|value|``, at least 1e-300) of it.
    """
    out = {}
    scales = [None] * len(names) if scales is None else scales
    for name, x, lo, hi, sc in zip(names, np.asarray(values, float), lower, upper, scales):
        for side, b in (("min", lo), ("max", hi)):
            if b is None or not math.isfinite(b):
                continue
            size = sc if sc else max(abs(b), abs(x), 1e-300)
            if abs(x - b) <= rtol * size:
                out[name] = {"side": side, "bound": float(b)}
                break
    return out


def describe_at_bounds(hits: dict, what: str = "value") -> str:
    """One sentence about the values on their bounds (empty when there are none)."""
    if not hits:
        return ""
    parts = [f"{name} at its {'lower' if h['side'] == 'min' else 'upper'} bound "
             f"{h['bound']:g}" for name, h in hits.items()]
    return (f"{'; '.join(parts)}: the bound decided the {what}, not an interior optimum; "
            "widen the bound if the physics allows it, or fix the parameter at it.")


def check_bounds(var, kind: str) -> None:
    """Check the bounds of a free parameter or design variable (``name``, ``initial``,
    ``min``, ``max``, ``scale``): numbers, ``min < max``, ``initial`` between them,
    ``scale > 0``; every problem in one :class:`ParameterError` that names ``kind``
    (``"free parameter"``, ``"design variable"``) and the name."""
    where = f"{kind} '{var.name}'"
    problems = []
    for key in ("initial", "min", "max", "scale"):
        v = getattr(var, key)
        if v is not None and (isinstance(v, bool) or not isinstance(v, (int, float, np.number))
                              or math.isnan(v)):
            problems.append(f"{where}: {key} must be a number, got {v!r}.")
    if problems:
        raise ParameterError(" ".join(problems), problems=problems, path=var.name)
    if not var.min < var.max:
        problems.append(f"{where}: the lower bound min = {var.min:g} is not below the "
                        f"upper bound max = {var.max:g}.")
    elif var.initial is not None and not var.min <= var.initial <= var.max:
        problems.append(f"{where}: starting value {var.initial:g} is outside "
                        f"[{var.min:g}, {var.max:g}].")
    if var.scale is not None and not var.scale > 0:
        problems.append(f"{where}: scale must be > 0, got {var.scale:g}.")
    if problems:
        raise ParameterError(" ".join(problems), problems=problems, path=var.name)
