"""KinematicPTP against the bang-coast-bang profile worked out here: total time, peak
speed, and the position as the double integral of the acceleration (integrated by the
trapezoidal rule on a grid holding the phase changes)."""

import numpy as np
import pytest

import mechatron as mt
from mechatron.library import blocks


def run(**kw):
    m = mt.System("ptp")
    m.add("p", blocks.KinematicPTP(**kw))
    t = np.linspace(0.0, 4.0, 40001)
    return mt.simulate(m, 4.0, t_out=t)


@pytest.mark.parametrize("q0,q1,vmax,amax,t0", [
    (0.5, 2.5, 1.0, 2.0, 0.3),      # trapezoid: D = 2 > vmax^2/amax = 0.5
    (1.0, 0.7, 1.0, 2.0, 0.1),      # triangle downwards: D = 0.3 < 0.5
])
def test_ptp_profile(q0, q1, vmax, amax, t0):
    res = run(q_begin=q0, q_end=q1, qd_max=vmax, qdd_max=amax, start_time=t0)
    D = abs(q1 - q0)
    v = min(vmax, np.sqrt(D * amax))
    ta = v / amax
    tv = D / v - ta
    T = 2 * ta + tv
    t = res.t
    s = np.sign(q1 - q0)
    acc = np.where((t >= t0) & (t < t0 + ta), s * amax, 0.0) \
        - np.where((t >= t0 + ta + tv) & (t < t0 + T), s * amax, 0.0)
    # sample away from the phase changes
    edges = t0 + np.array([0.0, ta, ta + tv, T])
    ok = np.min(np.abs(t[:, None] - edges[None, :]), axis=1) > 1e-6
    np.testing.assert_array_equal(res["p.qdd"][ok], acc[ok])
    # speed and position from the acceleration: exact integrals of the piecewise
    # constant acceleration
    def integral(f, x):
        return np.concatenate([[0.0], np.cumsum(np.diff(x) * 0.5 * (f[1:] + f[:-1]))])
    qd = integral(res["p.qdd"], t)
    q = q0 + integral(res["p.qd"], t)
    np.testing.assert_allclose(res["p.qd"], qd, atol=2e-3 * amax * 1e-1)
    np.testing.assert_allclose(res["p.q"], q, atol=1e-6)
    # the peak speed v is reached (within a grid step of it) and never exceeded
    peak = np.max(np.abs(res["p.qd"]))
    assert v - amax * 1e-4 <= peak <= v * (1 + 1e-12)
    assert res["p.q"][-1] == q1
    assert res["p.moving"][ok].tolist() == ((t >= t0) & (t < t0 + T))[ok].tolist()
    i_end = np.searchsorted(t, t0 + T)
    assert res["p.q"][i_end + 1] == q1 and res["p.qd"][i_end + 1] == 0.0


def test_ptp_without_a_distance_stays_put():
    res = run(q_begin=1.5, q_end=1.5, start_time=0.5)
    assert np.all(res["p.q"] == 1.5)
    assert np.all(res["p.qd"] == 0.0) and np.all(res["p.qdd"] == 0.0)
