"""Comparing two simulation logs column by column."""

from __future__ import annotations

import numpy as np

from mechatron.codegen._common import CodegenError
from mechatron.results import SimResult

__all__ = ["max_relative_difference"]


def max_relative_difference(a: SimResult, b: SimResult, names=None) -> float:
    """Largest ``|a - b|`` over time and variables, each variable scaled by the largest
    ``|b|`` among the variables of its unit (absolute where all of them are identically
    zero); the time axes must be equal.

    By unit, not by variable: a variable that is zero in the physics comes out of the
    arithmetic as rounding, ``1e-15`` of the quantities it is computed from (the current
    into a reference, the sum of a node's currents), and two correct runs differ in that
    rounding by as much as the variable itself; its scale is that of its kind."""
    if len(a.t) != len(b.t) or np.max(np.abs(a.t - b.t), initial=0.0) > 1e-12 * max(
            1.0, float(np.max(np.abs(b.t)))):
        raise CodegenError(f"cannot compare logs on different time axes ({len(a.t)} and "
                           f"{len(b.t)} points).")
    names = list(names or b.names)
    units = b.units
    largest = [float(np.max(np.abs(b[name]), initial=0.0)) for name in names]
    by_unit: dict[str, float] = {}
    for name, big in zip(names, largest):
        unit = units.get(name, "")
        by_unit[unit] = max(by_unit.get(unit, 0.0), big)
    worst = 0.0
    for name in names:
        scale = by_unit[units.get(name, "")] or 1.0
        worst = max(worst, float(np.max(np.abs(a[name] - b[name]), initial=0.0)) / scale)
    return worst
