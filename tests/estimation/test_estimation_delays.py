"""A transport delay (`blocks.Delay`) on a measured input in estimation: applied to the
data exactly, estimated with known truth; delays the data cannot carry are refused."""

from __future__ import annotations

import logging

import numpy as np
import pytest

import mechatron as mt
from mechatron.errors import DataError, ModelError
from mechatron.estimation import EstimationProblem, Experiment, FreeParameter, estimate
from mechatron.library import blocks as bl

from tests.estimation.test_estimation_rigs import _lag

H = 0.02


def _rig(T=0.06, Ts=0.02, loop=False, bypass=False):
    m = mt.System("rig")
    cmd = m.add("cmd", bl.Constant(value=0.0))
    dly = m.add("dly", bl.Delay(T=T, Ts=Ts))
    lag = m.add("lag", bl.FirstOrder(k=1.0, T=0.5))
    if loop:                         # the delay in a feedback path: u - y is delayed
        s = m.add("s", bl.Subtract())
        m.connect(cmd.y, s.u1)
        m.connect(lag.y, s.u2)
        m.connect(s.y, dly.u)
        m.connect(dly.y, lag.u)
    elif bypass:                     # the input also reaches the plant undelayed
        a = m.add("a", bl.Add())
        m.connect(cmd.y, dly.u, a.u1)
        m.connect(dly.y, a.u2)
        m.connect(a.y, lag.u)
    else:
        m.connect(cmd.y, dly.u)
        m.connect(dly.y, lag.u)
    return m


def _data(n=400, shift=3, seed=0, noise=0.0):
    rng = np.random.default_rng(seed)
    u = np.repeat(rng.choice([-1.0, 1.0], n // 20 + 1), 20)[:n]
    ud = np.r_[np.zeros(shift), u[:n - shift]]
    y = _lag(ud, H, 2.5, 0.3) + noise * rng.standard_normal(n)
    return Experiment("run", t=np.arange(n) * H, inputs={"u": u}, outputs={"y": y})


FREE = [FreeParameter("lag.k", 1.0, 0.1, 10), FreeParameter("lag.T", 0.5, 0.01, 5)]


def test_gain_and_time_constant_behind_a_delay_are_recovered(caplog):
    """Data: the analytic lag (k = 2.5, T = 0.3 s) of the input delayed by 3 samples; the
    model's Delay(60 ms) is applied to the data and the fit is exact. Without the delay
    the same fit is visibly wrong."""
    caplog.set_level(logging.ERROR)
    e = _data()
    prob = EstimationProblem(_rig(), [e], FREE, inputs={"u": "cmd.value"},
                             outputs={"y": "lag.y"}, jit=False)
    assert prob.input_delays == {"u": pytest.approx(0.06)}
    assert prob.cm.nr == 0
    res = estimate(prob)
    assert res.parameters["lag.k"] == pytest.approx(2.5, rel=1e-6)
    assert res.parameters["lag.T"] == pytest.approx(0.3, rel=1e-6)
    naive = estimate(EstimationProblem(_rig(T=0.0), [e], FREE, inputs={"u": "cmd.value"},
                                       outputs={"y": "lag.y"}, jit=False))
    assert naive.cost > 1e6 * max(res.cost, 1e-30)


def test_a_delay_the_data_cannot_carry_is_refused():
    e = _data()
    with pytest.raises(ModelError, match="Delay 'dly': in estimation a delay must act on "
                                         "a measured input"):
        EstimationProblem(_rig(loop=True), [e], FREE, inputs={"u": "cmd.value"},
                          outputs={"y": "lag.y"}, jit=False)
    with pytest.raises(ModelError, match="also acts on the model without passing the "
                                         "delay"):
        EstimationProblem(_rig(bypass=True), [e], FREE, inputs={"u": "cmd.value"},
                          outputs={"y": "lag.y"}, jit=False)
    with pytest.raises(DataError, match="a delay of 0.05 s is not a whole number of "
                                        "sample periods"):
        EstimationProblem(_rig(T=0.05, Ts=0.01), [e], FREE, inputs={"u": "cmd.value"},
                          outputs={"y": "lag.y"}, jit=False)


def test_a_delay_in_a_model_file_of_a_problem_file(tmp_path, caplog):
    """The same rig from TOML: [model] file with a Delay, the fit exact."""
    caplog.set_level(logging.ERROR)
    from mechatron.estimation.config import build_estimation, load_config
    (tmp_path / "rig.py").write_text(
        "import mechatron as mt\n"
        "from mechatron.library import blocks as bl\n\n\n"
        "class Rig(mt.Component):\n"
        "    cmd = bl.Constant(value=0.0)\n"
        "    dly = bl.Delay(T=\"60 ms\", Ts=\"20 ms\")\n"
        "    lag = bl.FirstOrder(k=1.0, T=0.5)\n\n"
        "    def equations(self):\n"
        "        return [mt.connect(self.cmd.y, self.dly.u),\n"
        "                mt.connect(self.dly.y, self.lag.u)]\n")
    e = _data(seed=4)
    e.save(tmp_path / "run.csv")
    (tmp_path / "p.toml").write_text(
        '[model]\nfile = "rig.py"\n\n[[experiments]]\nfile = "run.csv"\ninputs = ["u"]\n'
        'outputs = ["y"]\n\n[inputs]\nu = "cmd.value"\n[outputs]\ny = "lag.y"\n\n'
        '[parameters]\n"lag.k" = { initial = 1.0, min = 0.1 }\n'
        '"lag.T" = { initial = 0.5, min = 0.01 }\n')
    prob = build_estimation(load_config(tmp_path / "p.toml"))
    res = estimate(prob)
    assert res.parameters["lag.k"] == pytest.approx(2.5, rel=1e-6)
    assert res.parameters["lag.T"] == pytest.approx(0.3, rel=1e-6)
