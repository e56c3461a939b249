"""HIL plant and controller step functions against independent NumPy implementations."""

import math

import casadi as ca
import numpy as np
import pytest

import mechatron as mt
from mechatron.realtime.loop import EXPERIMENTS, build_loop, run_mil
from mechatron.realtime.plant import PLANT_DEFAULTS, pwm_average


def _pwm_bruteforce(duty, k, dt, f_pwm, v_high, n=200_000):
    """Mean of the square wave over [k dt, (k+1) dt] by dense sampling."""
    t = k * dt + (np.arange(n) + 0.5) * dt / n
    phase = np.mod(t * f_pwm, 1.0)
    return v_high * np.mean(phase < duty)


@pytest.mark.parametrize("dt,f_pwm", [(1e-4, 5000.0), (1e-4, 3000.0), (2.5e-4, 5000.0),
                                      (3e-5, 5000.0)])
def test_pwm_average_matches_dense_sampling(dt, f_pwm):
    d, k = ca.SX.sym("d"), ca.SX.sym("k")
    f = ca.Function("f", [d, k], [pwm_average(d, k, dt, f_pwm, 3.3)])
    rng = np.random.default_rng(0)
    for duty, kk in zip(rng.uniform(-0.2, 1.2, 12), rng.integers(0, 30000, 12)):
        got = float(f(duty, kk))
        want = _pwm_bruteforce(min(max(duty, 0), 1), kk, dt, f_pwm, 3.3)
        assert got == pytest.approx(want, abs=3.3 * 2e-5)


def _open_loop(loop, duty, steps):
    x = ca.SX.sym("x", loop.x0.size)
    k = ca.SX.sym("k")
    X = ca.vertcat(x, k)
    f = ca.Function("ol", [X], [ca.vertcat(loop.plant_step(x, duty, k), k + 1),
                                loop.plant_out(x)])
    xs, ys = f.mapaccum("ol_run", steps)(np.concatenate([loop.x0, [0.0]]))
    return np.array(ys)


@pytest.mark.parametrize("duty", [0.8, 0.3])
def test_open_loop_plant_reaches_analytic_speed(duty):
    """RC mean d V_io -> H-bridge V_s (2 d - 1) -> motor final speed k V / (R B + k^2)."""
    loop = build_loop("speed", rate=10_000.0)
    y = _open_loop(loop, duty, 1500)              # 0.15 s, ~100 mechanical time constants
    p = {k: v.default for k, v in mt.models.get("dc_motor").parameters.items()}
    V_a = PLANT_DEFAULTS["V_s"] * (2 * duty - 1)
    w_final = p["k"] * V_a / (p["R"] * p["B"] + p["k"] ** 2)
    w_mean = y[1, -200:].mean()                    # average over 10 PWM periods (ripple)
    assert w_mean == pytest.approx(w_final, rel=2e-3)
    v_c_mean = y[3, -200:].mean()
    assert v_c_mean == pytest.approx(duty * PLANT_DEFAULTS["V_io"], rel=2e-2)
    cpr = 4 * PLANT_DEFAULTS["lines"]
    np.testing.assert_array_equal(y[0], np.floor(y[2] * cpr / (2 * math.pi)))


def _controller_numpy(exp, counts, valid, dt, cpr, V_s):
    """The documented difference equation, written again in plain Python."""
    M = max(2, round(exp.window_s / dt))
    hist = [0.0] * M
    integ = 0.0
    duties = []
    for k, (c, ok) in enumerate(zip(counts, valid)):
        if not ok:
            c = hist[0] + (hist[0] - hist[M - 1]) / (M - 1)
        w = 2 * math.pi * (c - hist[M - 1]) / (cpr * M * dt)
        y = w if exp.quantity == "speed" else 2 * math.pi * c / cpr
        t = k * dt
        ref = 0.0
        for t0, v in exp.reference:
            if t >= t0 - 1e-12:
                ref = v
        e = ref - y
        u = exp.Kp * e + integ - exp.Kd * w
        us = min(max(u, -V_s), V_s)
        if not ((u > V_s and e > 0) or (u < -V_s and e < 0)):
            integ += exp.Ki * dt * e
        duties.append(0.5 + us / (2 * V_s))
        hist = [c] + hist[:-1]
    return np.array(duties)


@pytest.mark.parametrize("name,rate", [(n, r) for n in EXPERIMENTS for r in (1e4, 2e3)])
def test_controller_matches_hand_written_difference_equation(name, rate):
    loop = build_loop(name, rate=rate)
    rng = np.random.default_rng(1)
    n = 3000
    counts = np.cumsum(rng.integers(0, 9, n)).astype(float)
    valid = rng.uniform(size=n) > 0.05
    xc = loop.xc0.copy()
    got = []
    for k in range(n):
        xc, out = loop.ctrl_step(xc, counts[k], k, float(valid[k]))
        got.append(float(out[0]))
    want = _controller_numpy(loop.experiment, counts, valid, loop.dt,
                             4 * PLANT_DEFAULTS["lines"], PLANT_DEFAULTS["V_s"])
    np.testing.assert_allclose(got, want, rtol=0, atol=1e-12)
    assert min(got) >= 0.0 and max(got) <= 1.0


@pytest.mark.parametrize("rate", [10_000.0, 2_000.0])
def test_mil_tracks_the_references(rate):
    for name, var in (("speed", "w"), ("position", "phi")):
        loop = build_loop(name, rate=rate)
        r = run_mil(loop, int(2.0 * rate))
        exp = loop.experiment
        for (t0, v), t1 in zip(exp.reference, [t for t, _ in exp.reference[1:]] + [2.0]):
            held = (r["t"] > t1 - 0.1) & (r["t"] < t1)   # the last 0.1 s of each hold
            assert np.mean(r[var][held]) == pytest.approx(v, rel=0.02), (name, t0)


@pytest.mark.parametrize("dt,f_pwm", [(1.0, 5000.0), (0.01, 5000.0), (3.3e-3, 7000.0)])
def test_hil_rate_1_hz_pwm_average_is_closed_form_and_small(dt, f_pwm, monkeypatch):
    """`hil --rate 1` unrolled one term per PWM period in a plant step (5,000 at 1 Hz): a
    megabyte of C and minutes of compiling. Beyond MAX_UNROLLED_PERIODS the high time is
    the closed form H(t1) - H(t0); it equals the per-period sum (forced here by raising
    the limit) to 1e-9 of full scale (both floor k dt / T with a 1e-9 guard), with an
    expression a hundredth of the size or less."""
    from mechatron.realtime import plant
    d, k = ca.SX.sym("d"), ca.SX.sym("k")
    closed = ca.Function("c", [d, k], [pwm_average(d, k, dt, f_pwm, 3.3)])
    monkeypatch.setattr(plant, "MAX_UNROLLED_PERIODS", 10 ** 9)
    summed = ca.Function("s", [d, k], [pwm_average(d, k, dt, f_pwm, 3.3)])
    assert closed.n_instructions() < 100 < summed.n_instructions()
    rng = np.random.default_rng(1)
    for duty, kk in zip(rng.uniform(-0.2, 1.2, 12), rng.integers(0, 3000, 12)):
        assert float(closed(duty, kk)) == pytest.approx(float(summed(duty, kk)),
                                                        abs=3.3e-9)
