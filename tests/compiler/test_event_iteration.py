"""Event iteration: relations that reach their surfaces at the same instant settle on one
consistent set of modes, checked against the exact solution of the circuit."""

import numpy as np
import pytest

import mechatron as mt
from mechatron.library import electrical as el

E, R, L, I0 = 10.0, 1.0, 1e-2, 1.0
V1, V2, RD, GD = 0.7, 0.6, 1e-3, 1e-8


def two_diodes():
    """An inductor's current driven down through two series diodes against a source.

    Both diodes conduct ``i = (v - V_f)/R_d + G_d V_f``; the current falls until the
    first reaches ``i = G_d V1`` and blocks, the second (``i = G_d V2``) 1e-12 s later, a
    gap below the event iteration's resolution, so both turn off in one event. There
    the second one's residual distance in its on state (1e-12 V) reads 0.1 V in its off
    state (times 1/(R_d G_d)), crossed back in the same 1e-12 s: a rule bounding the
    distance instead of the time to cross toggled it until the iteration gave up."""
    m = mt.System("two_diodes")
    src = m.add("src", el.DCVoltageSource(V=E))
    r = m.add("r", el.Resistor(R=R))
    ind = m.add("l", el.Inductor(L=L, i=I0))
    d1 = m.add("d1", el.Diode(Vf=V1, Ron=RD, Goff=GD))
    d2 = m.add("d2", el.Diode(Vf=V2, Ron=RD, Goff=GD))
    g = m.add("g", el.ElectricalReference())
    m.connect(src.n, r.p, g.port)
    m.connect(r.n, ind.p)
    m.connect(ind.n, d1.p)
    m.connect(d1.n, d2.p)
    m.connect(d2.n, src.p)
    return m


@pytest.mark.parametrize("solver", ["rosenbrock", "rodas4"])
def test_series_diodes_blocking_at_one_instant_settle_off(solver):
    # both conducting: L di/dt = -E - R i - v1 - v2, v_k = V_k + R_d (i - G_d V_k)
    a, b = E + (V1 + V2) * (1 - RD * GD), R + 2 * RD
    t_off = L / b * np.log((I0 + a / b) / (GD * V1 + a / b))     # i = G_d V1
    t = np.linspace(0, 2 * t_off, 401)
    res = mt.simulate(two_diodes(), t[-1], t_out=t, rtol=1e-10, atol=1e-12, solver=solver)
    i = res["l.i"]
    on = t < t_off
    np.testing.assert_allclose(i[on], -a / b + (I0 + a / b) * np.exp(-b * t[on] / L),
                               rtol=1e-8, atol=1e-10)
    # one event each, at the instant the first diode blocks
    assert res.stats.events == {"d1": 1, "d2": 1}
    assert res.event_times["d1"] == pytest.approx(t_off, abs=1e-9)
    assert res.event_times["d2"] == pytest.approx(t_off, abs=1e-9)
    # both blocking: i = G_d v_k, the current settles (L G_d / 2 = 5e-11 s) at the
    # leakage -E / (R + 2 / G_d). The check starts 0.2 ms later: an output in the step
    # across that transient is interpolated from the step's ends (rodas4's Hermite
    # interpolant), not a solution value
    late = t > t_off + 2e-4
    np.testing.assert_allclose(i[late], -E / (R + 2 / GD), rtol=1e-4)
    assert np.all(res["d1.on"][late] == 0) and np.all(res["d2.on"][late] == 0)
    np.testing.assert_allclose(res["d2.v"][late], -E / 2 * (1 / GD) / (R / 2 + 1 / GD),
                               rtol=1e-4)
