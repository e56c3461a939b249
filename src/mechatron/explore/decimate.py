"""Reduce a signal to what a plot of a given pixel width can show.

A line plot ``width`` pixels wide draws, in each pixel column, a vertical stroke from the
smallest to the largest value of the samples that fall in that column. Keeping, per
column, the sample holding the minimum and the one holding the maximum (in time order)
draws the same picture from at most ``2 * width`` points, whatever the length of the log:
peaks, spikes and the envelope of fast oscillations survive, unlike with every-n-th-sample
thinning. Inside a zoomed window the columns are narrower, so the full resolution comes
back as the window shrinks.
"""

from __future__ import annotations

import numpy as np

__all__ = ["decimate", "window"]


def window(t: np.ndarray, t0: float | None, t1: float | None) -> slice:
    """The samples of the non-decreasing time axis ``t`` inside ``[t0, t1]``, plus one on
    each side (so that a line leaves the plot at its edges rather than stopping short)."""
    lo = 0 if t0 is None else max(int(np.searchsorted(t, t0, side="left")) - 1, 0)
    hi = t.size if t1 is None else min(int(np.searchsorted(t, t1, side="right")) + 1, t.size)
    return slice(lo, max(hi, lo))


def decimate(t, y, width: int, t0: float | None = None,
             t1: float | None = None) -> tuple[np.ndarray, np.ndarray, bool]:
    """The points of ``(t, y)`` in ``[t0, t1]`` that a plot ``width`` pixels wide needs.

    Parameters
    ----------
    t : array_like, shape (n,)
        Non-decreasing times (a repeated time marks an event).
    y : array_like, shape (n,)
        Values; NaN samples are ignored by the reduction (a column of NaN only is a gap).
    width : int
        Number of pixel columns, >= 1.
    t0, t1 : float, optional
        The time window (default: the whole log).

    Returns
    -------
    t, y : numpy.ndarray
        The kept samples, in time order: all of them when the window holds at most
        ``2 * width`` samples, else the minimum and the maximum of each pixel column.
    decimated : bool
        Whether samples were dropped.
    """
    t = np.asarray(t, dtype=float)
    y = np.asarray(y, dtype=float)
    width = int(width)
    if width < 1:
        raise ValueError(f"decimate: width must be >= 1 pixel, got {width}.")
    part = window(t, t0, t1)
    tw, yw = t[part], y[part]
    if tw.size <= 2 * width:
        return tw, yw, False
    a = tw[0] if t0 is None else float(t0)
    b = tw[-1] if t1 is None else float(t1)
    span = b - a if b > a else 1.0
    # column of each sample; the two samples outside the window get columns -1 and width
    col = np.clip(np.floor((tw - a) / span * width), -1, width).astype(np.int64)
    starts = np.flatnonzero(np.r_[True, col[1:] != col[:-1]])
    lengths = np.diff(np.r_[starts, tw.size])
    segment = np.repeat(np.arange(starts.size), lengths)
    with np.errstate(invalid="ignore"):
        lows = np.fmin.reduceat(yw, starts)
        highs = np.fmax.reduceat(yw, starts)
    keep = []
    for extreme in (lows, highs):
        hit = np.flatnonzero(yw == np.repeat(extreme, lengths))
        _, first = np.unique(segment[hit], return_index=True)   # first sample per column
        keep.append(hit[first])
    idx = np.unique(np.concatenate(keep))                       # sorted: time order
    return tw[idx], yw[idx], True
