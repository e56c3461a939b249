"""The examples of docs/modeling.md ("Events and discrete variables", "Initial equations")
run, and their results agree with analytic answers computed here."""

import re
from pathlib import Path

import numpy as np
import pytest

DOC = Path(__file__).parents[1] / "docs" / "modeling.md"


@pytest.fixture(scope="module")
def doc():
    text = DOC.read_text()
    start = text.index("## Events and discrete variables")
    end = text.index("## Friction with a stuck mode")      # the next sections' own code
    blocks = re.findall(r"```python\n(.*?)```", text[start:end], re.S)
    assert len(blocks) == 5
    ns: dict = {}
    for block in blocks:
        exec(compile(block, str(DOC), "exec"), ns)
    return ns


def test_counter_counts_ticks(doc):
    res = doc["res_counter"]
    inside = np.abs(res.t / 0.1 - np.round(res.t / 0.1)) > 1e-6     # not on a tick
    np.testing.assert_array_equal(res["n"][inside], np.floor(res.t[inside] / 0.1) + 1)


def test_latch_is_on_between_set_and_reset(doc):
    res = doc["res_latch"]
    phase = np.mod(res.t, 1.0)
    on = (phase > 1 / 12 + 1e-6) & (phase < 7 / 12 - 1e-6)
    off = (phase < 1 / 12 - 1e-6) | (phase > 7 / 12 + 1e-6)
    assert np.all(res["q"][on] == 1) and np.all(res["q"][off] == 0)


def test_ball_rests_after_the_analytic_impacts(doc):
    res = doc["res_ball"]
    g, e, h0, v_rest = 9.81, 0.5, 1.0, 0.5
    v, t_k = np.sqrt(2 * g * h0), np.sqrt(2 * h0 / g)
    while v >= v_rest:                  # impacts t_k; the last one is slower than v_rest
        v *= e
        t_k += 2 * v / g
    assert res.event_times[""] == pytest.approx(t_k, abs=1e-9)
    after = res.t > t_k
    assert np.all(res["h"][after] == 0.0) and np.all(res["v"][after] == 0.0)
    assert np.all(res["resting"][after] == 1)


def test_sampled_pi_matches_the_exact_discretization(doc):
    res = doc["res_pi"]
    Kp, Ki, Ts, u_max, tau = 2.0, 8.0, 0.05, 1.5, 0.2
    a, y, integral, u_hand = np.exp(-Ts / tau), 0.0, 0.0, []
    for _ in range(40):
        e = 1.0 - y
        v = Kp * e + integral
        if v <= u_max:
            integral += Ki * Ts * e
        u_hand.append(min(v, u_max))
        y = a * y + (1 - a) * u_hand[-1]
    k = np.floor(res.t / Ts + 1e-9).astype(int)         # the tick each point follows
    on_tick = np.abs(res.t / Ts - np.round(res.t / Ts)) < 1e-6
    inside = (k < 40) & ~on_tick
    np.testing.assert_allclose(res["u"][inside], np.array(u_hand)[k[inside]], atol=1e-7)


def test_lag_starts_in_steady_state(doc):
    np.testing.assert_allclose(doc["res_lag"]["x"], 1.7, rtol=1e-9)
