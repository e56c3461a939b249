"""Comparing two simulation logs column by column."""

from __future__ import annotations

import numpy as np

from mechatron.codegen._common import CodegenError
from mechatron.results import SimResult

__all__ = ["max_relative_difference"]


def max_relative_difference(a: SimResult, b: SimResult, names=None) -> float:
    """Largest ``|a - b|`` over time and variables, each variable scaled by its largest
    ``|b|`` (absolute where ``b`` is identically zero); the time axes must be equal."""
    if len(a.t) != len(b.t) or np.max(np.abs(a.t - b.t), initial=0.0) > 1e-12 * max(
            1.0, float(np.max(np.abs(b.t)))):
        raise CodegenError(f"cannot compare logs on different time axes ({len(a.t)} and "
                           f"{len(b.t)} points).")
    worst = 0.0
    for name in names or b.names:
        ref = b[name]
        scale = float(np.max(np.abs(ref), initial=0.0)) or 1.0
        worst = max(worst, float(np.max(np.abs(a[name] - ref), initial=0.0)) / scale)
    return worst
