"""EMPS database model: the sampled closed loop matches a tick-by-tick NumPy
implementation of the authors' controller and plant, and it comes to rest where the
position loop balances the offset force."""

import math

import numpy as np
import pytest

import mechatron as mt
from mechatron.models.emps import CONSTANTS, REFERENCE, final_position

ENTRY = mt.models.get("emps")


def numpy_loop(qg, t_stop, substeps=50, M=REFERENCE["M"], Fv=REFERENCE["Fv"],
               Fc=REFERENCE["Fc"], offset=REFERENCE["offset"], v_c=1e-4):
    """The closed loop written out: at each tick ``k Ts`` the controller reads ``q`` and
    the reference, the output is held over the sample, the plant is integrated by RK4
    with ``substeps`` steps per sample. Returns q, v and vir at the ticks (vir the value
    set at the tick)."""
    gtau, kp, kv, Ts, vmax = (CONSTANTS[k] for k in ("gtau", "kp", "kv", "Ts", "vir_max"))
    n = int(round(t_stop / Ts))
    q = v = q_prev = qf_prev = 0.0
    out = np.zeros((n + 1, 3))
    h = Ts / substeps

    def acc(vv, vir):
        return (gtau * vir - Fv * vv - Fc * math.tanh(vv / v_c) - offset) / M

    for k in range(n + 1):
        qf = 0.5 * (q + q_prev)
        dq = (qf - qf_prev) / Ts
        vir = min(max(kv * (kp * (qg - q) - dq), -vmax), vmax)
        q_prev, qf_prev = q, qf
        out[k] = q, v, vir
        for _ in range(substeps):
            k1q, k1v = v, acc(v, vir)
            k2q, k2v = v + h / 2 * k1v, acc(v + h / 2 * k1v, vir)
            k3q, k3v = v + h / 2 * k2v, acc(v + h / 2 * k2v, vir)
            k4q, k4v = v + h * k3v, acc(v + h * k3v, vir)
            q += h / 6 * (k1q + 2 * k2q + 2 * k3q + k4q)
            v += h / 6 * (k1v + 2 * k2v + 2 * k3v + k4v)
    return out


def test_sampled_loop_matches_the_numpy_loop_tick_by_tick():
    """A 10 mm step saturates the drive, then the loop settles; the positions at the
    ticks and the held controller output (read half a sample after each tick) agree."""
    t_stop, Ts = 0.4, CONSTANTS["Ts"]
    ticks = np.arange(int(round(t_stop / Ts)) + 1) * Ts
    mid = ticks[:-1] + Ts / 2
    res = mt.simulate(ENTRY.build(qg=0.01), t_stop, rtol=1e-10, atol=1e-13,
                      t_out=np.union1d(ticks, mid))
    ref = numpy_loop(0.01, t_stop)
    on = np.isin(res.t, ticks)
    assert np.sum(np.abs(ref[:, 2]) == 10.0) > 20            # saturated for a while
    np.testing.assert_allclose(res["q"][on], ref[:, 0], rtol=0, atol=1e-9)
    np.testing.assert_allclose(res["v"][on], ref[:, 1], rtol=0, atol=1e-7)
    np.testing.assert_allclose(res["vir"][~on], ref[:-1, 2], rtol=0, atol=1e-5)


def test_rest_position_balances_the_offset_force():
    """At rest the Coulomb law gives no force and the P position loop holds the offset:
    ``gtau kv kp (qg - q) = offset``."""
    res = mt.simulate(ENTRY.build(qg=0.02, offset=-6.0), 4.0, rtol=1e-9, atol=1e-12)
    q = res.final("q")
    assert q == pytest.approx(final_position(0.02, offset=-6.0), abs=1e-10)
    assert q - 0.02 == pytest.approx(6.0 / (CONSTANTS["gtau"] * CONSTANTS["kv"]
                                            * CONSTANTS["kp"]), rel=1e-4)
    assert res.final("vir") == pytest.approx(-6.0 / CONSTANTS["gtau"], rel=1e-5)
