"""Min/max decimation: what a plot of a given pixel width shows is kept."""

from __future__ import annotations

import numpy as np
import pytest

from mechatron.explore.decimate import decimate


def _columns(t, y, width, t0, t1):
    """Reference, written independently: the samples holding the min and the max of each
    pixel column (samples in [t0, t1] only), by a loop over the columns."""
    out = []
    edges = np.linspace(t0, t1, width + 1)
    for k in range(width):
        last = k == width - 1
        inside = np.flatnonzero((t >= edges[k]) & ((t <= edges[k + 1]) if last
                                                   else (t < edges[k + 1])))
        if inside.size:
            out.append((inside[np.argmin(y[inside])], inside[np.argmax(y[inside])]))
    return out


@pytest.mark.parametrize("window", [(None, None), (0.2, 0.7), (0.5001, 0.5003)])
def test_each_pixel_column_keeps_its_min_and_max(window):
    rng = np.random.default_rng(7)
    n, width = 200_000, 300
    t = np.sort(rng.uniform(0.0, 1.0, n))
    y = np.cumsum(rng.normal(size=n)) + 50 * np.sin(2 * np.pi * 400 * t)
    t0, t1 = window
    td, yd, dropped = decimate(t, y, width, t0, t1)
    a, b = (t[0], t[-1]) if t0 is None else (t0, t1)
    inside = (t >= a) & (t <= b)
    if inside.sum() <= 2 * width:
        assert not dropped
        return
    assert dropped
    assert td.size <= 2 * (width + 2)
    assert np.all(np.diff(td) >= 0)                       # time order
    # every kept point is a sample of the log
    pos = np.searchsorted(t, td)
    assert np.array_equal(t[pos], td) and np.array_equal(y[pos], yd)
    kept = set(pos.tolist())
    columns = _columns(t, y, width, a, b)
    assert len(columns) >= width - 1
    for i_min, i_max in columns:        # random times: no sample sits on a column edge
        assert i_min in kept and i_max in kept
    # the global extremes of the window survive
    assert yd[(td >= a) & (td <= b)].max() == y[inside].max()
    assert yd[(td >= a) & (td <= b)].min() == y[inside].min()


def test_a_one_sample_spike_survives():
    t = np.linspace(0.0, 10.0, 1_000_001)
    y = np.sin(t)
    y[123_457] = 1e3
    td, yd, dropped = decimate(t, y, 200)
    assert dropped and yd.max() == 1e3 and td[np.argmax(yd)] == t[123_457]


def test_small_windows_come_back_at_full_resolution():
    t = np.linspace(0.0, 1.0, 100_001)
    y = t ** 2
    td, yd, dropped = decimate(t, y, 500, 0.25, 0.2501)
    inside = np.flatnonzero((t >= 0.25) & (t <= 0.2501))
    assert not dropped
    # all samples of the window, and one on each side so the line reaches the edges
    assert np.array_equal(td, t[inside[0] - 1:inside[-1] + 2])
    assert np.array_equal(yd, y[inside[0] - 1:inside[-1] + 2])


def test_nan_columns_are_gaps_and_events_keep_both_values():
    t = np.linspace(0.0, 1.0, 10_001)
    t = np.insert(t, 5001, t[5000])                    # an event at t = 0.5: time repeats
    y = np.where(t < 0.5, 0.0, 1.0)
    y[5000], y[5001] = 0.0, 1.0                        # values before and after the event
    y[2000:3000] = np.nan
    td, yd, dropped = decimate(t, y, 100)
    assert dropped
    assert not np.any(np.isnan(yd))
    assert not np.any((td > 0.2001) & (td < 0.2999))   # the NaN stretch is a gap
    near = np.abs(td - 0.5) <= 0.01                    # the column of the event
    assert np.any(yd[near & (td <= 0.5)] == 0.0) and np.any(yd[near & (td >= 0.5)] == 1.0)


def test_width_must_be_positive():
    with pytest.raises(ValueError, match="width must be >= 1"):
        decimate([0.0, 1.0], [0.0, 1.0], 0)
