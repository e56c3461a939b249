"""Position servo with encoder quantization: the simulated sampled loop matches an exact
discretisation in NumPy tick by tick, it stops within one count of a reference that is a
whole count, and hunts in a limit cycle across the count boundary when the reference
lies between two counts."""

import numpy as np
import pytest

import mechatron as mt
from mechatron.models.servo_encoder import count, sampled_response

ENTRY = mt.models.get("servo_encoder")


def _run(t_stop, **params):
    p = ENTRY.values(**params)
    ticks = np.arange(int(round(t_stop / p["Ts"])) + 1) * p["Ts"]
    # the ticks and the points half-way between them
    t = np.union1d(ticks, ticks[:-1] + p["Ts"] / 2)
    res = mt.simulate(ENTRY.build(**params), t_stop, rtol=1e-10, atol=1e-12, t_out=t)
    ref_t, X, U = sampled_response(**p, t_stop=t_stop)
    on_tick = np.isin(t, ticks)
    return p, res, on_tick, X, U


@pytest.fixture(scope="module")
def default_run():
    return _run(0.1)


def test_sampled_loop_matches_the_exact_discretisation(default_run):
    p, res, on_tick, X, U = default_run
    np.testing.assert_allclose(res["encoder.phi"][on_tick], X[:, 2], rtol=0, atol=1e-9)
    np.testing.assert_allclose(res["rotor.w"][on_tick], X[:, 1], rtol=0, atol=1e-6)
    np.testing.assert_allclose(res["inductor.i"][on_tick], X[:, 0], rtol=0, atol=1e-8)
    # between ticks the controller holds its output (zero-order hold): half a sample
    # after tick k the voltage is u_k
    np.testing.assert_allclose(res["controller.y"][~on_tick], U[:-1], rtol=0, atol=1e-9)
    # the start saturates the power stage
    assert U[0] == pytest.approx(p["V_max"])


def test_servo_stops_within_one_count_of_a_whole_count_reference(default_run):
    p, res, on_tick, X, U = default_run
    q = count(p["lines"])
    n_ref = p["theta_ref"] / q
    assert n_ref == pytest.approx(round(n_ref), abs=1e-9)
    theta = res.final("encoder.phi")
    # every angle of the reference's count reads zero error: 0 <= error < one count
    assert 0.0 <= theta - p["theta_ref"] < q
    assert res.final("encoder.n") == round(n_ref)
    assert abs(res.final("rotor.w")) < 1e-9 and res.final("controller.y") == 0.0
    # a continuous sensor would have brought it to the reference exactly: the residual
    # offset is the quantization's doing
    _, X_ideal, _ = sampled_response(**p, t_stop=0.1, quantize=False)
    assert abs(X_ideal[-1, 2] - p["theta_ref"]) < 1e-3 * q


def test_between_counts_the_servo_hunts_in_a_limit_cycle():
    q = count(ENTRY.values()["lines"])
    params = {"theta_ref": 1000.5 * q}
    p, res, on_tick, X, U = _run(0.15, **params)
    np.testing.assert_allclose(res["encoder.phi"][on_tick], X[:, 2], rtol=0, atol=1e-9)
    t = res.t
    tail = t > 0.1
    n = res["encoder.n"][tail]
    # it never rests: the error reads +-q/2, so the drive pushes it back and forth
    # across the boundary between counts 1000 and 1001
    assert set(np.unique(n)) == {1000.0, 1001.0}
    theta = res["encoder.phi"][tail] / q
    amplitude = np.ptp(theta)
    assert 0.5 < amplitude < 2.0                       # about one count peak to peak
    # the amplitude at the ticks and the cycle's period, from the NumPy loop
    tick_theta = X[:, 2][np.arange(len(X)) * p["Ts"] > 0.1] / q
    assert np.ptp(res["encoder.phi"][on_tick & tail] / q) == pytest.approx(
        np.ptp(tick_theta), rel=1e-6)
    period = next(m for m in range(1, 20)
                  if np.allclose(tick_theta[m:], tick_theta[:-m], atol=1e-6))
    assert period == 4                                  # a 4 ms (4-sample) cycle
