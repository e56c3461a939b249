"""Waveforms of time with a start time, as CasADi expressions: the shared core of the
electrical step, ramp, pulse, trapezoid, exponentially damped sine and table sources (and
of the signal ``Ramp``).

Every discontinuity and every kink of a waveform is the switch of a relation of time, so
the compiler turns it into an event that the variable-step solvers locate (the output is
exact on both sides; nothing is smoothed). Periodic waveforms test "inside the interval
``[a, a + w)`` of every period ``T``" with the continuous distance
``cos(2 pi (t - a)/T - pi w/T) - cos(pi w/T)``, as ``blocks.Pulse`` does. These are
helpers for component equations, not components.
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from mechatron.errors import DataError

__all__ = ["step", "ramp", "ramp_slope", "pulse", "trapezoid", "exp_sine", "table", "check_table",
           "in_interval", "wrap"]


def in_interval(t, a, w, period):
    """True while ``t`` lies in ``[a + k period, a + k period + w)`` for some integer k
    (a relation: its two edges per period are events)."""
    theta = 2 * ca.pi * (t - a) / period
    return ca.cos(ca.pi * w / period) < ca.cos(theta - ca.pi * w / period)


def wrap(u, period):
    """``u`` reduced to ``[-period/2, period/2)`` (continuous away from the half periods)."""
    return u - period * ca.floor(u / period + 0.5)


def step(t, height, start_time):
    """``height`` from ``start_time`` on, 0 before (one event)."""
    return ca.if_else(start_time <= t, height, 0)


def ramp(t, height, duration, start_time):
    """0 before ``start_time``, rising linearly to ``height`` over ``duration``, then held
    (two events, at the start and the end of the rise); ``duration > 0``."""
    rise = height * (t - start_time) / duration
    return ca.if_else(start_time <= t, ca.if_else(t < start_time + duration, rise, height), 0)


def ramp_slope(t, slope, duration, start_time):
    """0 before ``start_time``, ``slope (t - start_time)`` for ``duration``, then held at
    ``slope duration`` (``duration = inf``: never held)."""
    # the end-of-rise distance stays finite for duration = inf (an infinite event
    # indicator stops the integrator)
    end = start_time + ca.fmin(duration, 1e300)
    return ca.if_else(start_time <= t,
                      slope * ca.if_else(t < end, t - start_time, duration), 0)


def pulse(t, amplitude, width, period, start_time):
    """``amplitude`` during the first fraction ``width`` of each ``period`` from
    ``start_time`` on, else 0. Enabled half-way through the gap before the first pulse, so
    that the enable never coincides with an edge (two simultaneous events)."""
    enable = start_time - 0.5 * (1 - width) * period <= t
    on = ca.logic_and(in_interval(t, start_time, width * period, period), enable)
    return ca.if_else(on, amplitude, 0)


def trapezoid(t, amplitude, rising, width, falling, period, start_time):
    """Periodic trapezoid from ``start_time`` on: within each period, rise from 0 to
    ``amplitude`` over ``rising``, hold it for ``width``, fall to 0 over ``falling``, stay
    at 0 for the rest of the period. The four corners are events (rise and fall intervals
    are relations); each branch is exact and all branches agree at the corners, so an event
    located within its tolerance leaves no glitch."""
    u = t - start_time
    gap = period - rising - width - falling
    # phase in the period: wraps at the start of the rise (where the waveform is 0)
    s = u - period * ca.floor(u / period)
    plateau = ca.fmax(ca.fmin(ca.fmin(s / rising, 1), (rising + width + falling - s)
                              / falling), 0)
    # phases measured from the rise and the fall, wrapping far from their interval
    s_r = wrap(u - 0.5 * rising, period) + 0.5 * rising
    s_f = wrap(u - rising - width - 0.5 * falling, period) + 0.5 * falling
    shape = ca.if_else(in_interval(t, start_time, rising, period), s_r / rising,
                       ca.if_else(in_interval(t, start_time + rising + width, falling, period),
                                  1 - s_f / falling, plateau))
    enable = start_time - 0.5 * gap <= t
    return ca.if_else(enable, amplitude * shape, 0)


def exp_sine(t, amplitude, f, phase, damping, start_time):
    """``amplitude exp(-damping (t - start_time)) sin(2 pi f (t - start_time) + phase)``
    from ``start_time`` on, 0 before (one event)."""
    u = t - start_time
    return ca.if_else(start_time <= t,
                      amplitude * ca.exp(-damping * u) * ca.sin(2 * ca.pi * f * u + phase), 0)


def check_table(table, where: str) -> tuple[np.ndarray, np.ndarray]:
    """The columns ``(times, values)`` of a table of rows ``(time, value)``: at least two
    rows, finite, times non-decreasing, a time repeated at most twice (a jump)."""
    try:
        arr = np.asarray(table, dtype=float)
    except (TypeError, ValueError):
        raise DataError(f"{where}: table must be rows (time, value) of numbers, got "
                        f"{table!r}.") from None
    if arr.ndim != 2 or arr.shape[1] != 2 or arr.shape[0] < 2:
        raise DataError(f"{where}: table must have at least two rows (time, value), got "
                        f"shape {arr.shape}. Write table=[(0, 0), (1, 2), ...].")
    if not np.all(np.isfinite(arr)):
        bad = int(np.nonzero(~np.all(np.isfinite(arr), axis=1))[0][0])
        raise DataError(f"{where}: row {bad} of the table is not finite, got "
                        f"{tuple(arr[bad])}. Remove or fill missing samples.")
    t, v = arr[:, 0], arr[:, 1]
    dt = np.diff(t)
    if np.any(dt < 0):
        bad = int(np.nonzero(dt < 0)[0][0]) + 1
        raise DataError(f"{where}: table times must not decrease; row {bad} (t = "
                        f"{t[bad]:g}) follows t = {t[bad - 1]:g}. Sort the table.")
    if np.any((dt[1:] == 0) & (dt[:-1] == 0)):
        bad = int(np.nonzero((dt[1:] == 0) & (dt[:-1] == 0))[0][0]) + 2
        raise DataError(f"{where}: table time {t[bad]:g} appears more than twice. A "
                        "jump is two rows with the same time.")
    return t, v


def table(t, times: np.ndarray, values: np.ndarray):
    """Linear interpolation in the table ``(times, values)`` at ``t``, the first value
    held before the first time and the last after the last one. Two rows with the same
    time are a jump. Every breakpoint is an event (one relation ``times[k] <= t`` each,
    crossed once), the kinks and jumps included."""
    out = float(values[0])
    slope_before = 0.0
    k = 0
    n = times.size
    while k < n:
        tk = float(times[k])
        jump = 0.0
        if k + 1 < n and times[k + 1] == tk:
            jump = float(values[k + 1] - values[k])
            k += 1
        slope_after = float((values[k + 1] - values[k]) / (times[k + 1] - times[k])) \
            if k + 1 < n else 0.0
        ds = slope_after - slope_before
        if ds or jump:
            out = out + ca.if_else(tk <= t, jump + ds * (t - tk), 0)
        slope_before = slope_after
        k += 1
    return out
