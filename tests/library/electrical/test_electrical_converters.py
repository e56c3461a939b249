"""H-bridge and three-phase bridge against the exact solutions of the circuits they form
(an RL load switched on and then freewheeling through the diodes into the supply; the
six-step staircase of a wye load), and the battery's constant-current discharge against
its equivalent circuit solved by hand."""

import numpy as np
import pytest

import mechatron as mt
from mechatron.library import blocks
from mechatron.library import electrical as el


def test_hbridge_drives_and_freewheels_an_rl_load():
    V, R, L, RON, VF, RD, T1 = 24.0, 2.0, 10e-3, 1e-3, 0.7, 1e-3, 5e-3
    m = mt.System("hb")
    src = m.add("src", el.DCVoltageSource(V=V))
    hb = m.add("hb", el.HBridge(R_on=RON, V_f=VF, R_d=RD))
    r = m.add("r", el.Resistor(R=R))
    ind = m.add("ind", el.Inductor(L=L))
    on = m.add("on", blocks.Step(t_step=T1, initial=1.0, final=0.0))
    off = m.add("off", blocks.Constant(value=0.0))
    g = m.add("g", el.ElectricalReference())
    m.connect(src.p, hb.dc_p)
    m.connect(src.n, hb.dc_n, g.port)
    m.connect(hb.out_a, r.p)
    m.connect(r.n, ind.p)
    m.connect(ind.n, hb.out_b)
    m.connect(on.y, hb.fire_p)
    m.connect(off.y, hb.fire_n)
    t = np.linspace(0, 12e-3, 1201)
    # once the current has died, the inductor sees only the off-conductances: a time
    # constant of L G_off ~ 1e-10 s, a stiff problem (an explicit method crawls)
    res = mt.simulate(m, t[-1], t_out=t, rtol=1e-10, atol=1e-12, solver="rosenbrock")
    i = res["ind.i"]
    # driving: L di/dt = V - (R + 2 R_on) i
    r1 = R + 2 * RON
    i1 = V / r1 * (1 - np.exp(-T1 * r1 / L))
    drive = t <= T1
    np.testing.assert_allclose(i[drive], V / r1 * (1 - np.exp(-t[drive] * r1 / L)),
                               atol=1e-5)
    # freewheeling through the two opposite diodes into the supply:
    # L di/dt = -(V + 2 V_f) - (R + 2 R_d) i until the current dies, then it stays ~0
    r2, e2 = R + 2 * RD, V + 2 * VF
    t_zero = T1 + L / r2 * np.log((i1 + e2 / r2) / (e2 / r2))
    fw = (t > T1) & (t < t_zero)
    np.testing.assert_allclose(i[fw], -e2 / r2 + (i1 + e2 / r2)
                               * np.exp(-(t[fw] - T1) * r2 / L), atol=1e-5)
    assert np.all(np.abs(i[t > t_zero + 1e-4]) < 1e-6)
    # while freewheeling the load sees -(V + 2 V_f) less its own drop, and the current
    # flows back into the supply
    k = np.nonzero(fw)[0][5]
    assert res["hb.out_a.v"][k] - res["hb.out_b.v"][k] == pytest.approx(
        -(e2 + 2 * RD * i[k]), rel=1e-6)
    assert res["src.i"][k] == pytest.approx(i[k], rel=1e-5)   # into src.p: charging it


def test_three_phase_bridge_six_step_staircase():
    V, R, RON, F = 300.0, 10.0, 1e-3, 50.0
    m = mt.System("inv")
    src = m.add("src", el.DCVoltageSource(V=V))
    br = m.add("br", el.ThreePhaseBridge(R_on=RON))
    loads = {x: m.add(f"r_{x}", el.Resistor(R=R)) for x in "abc"}
    g = m.add("g", el.ElectricalReference())
    m.connect(src.p, br.dc_p)
    m.connect(src.n, br.dc_n, g.port)
    for k, x in enumerate("abc"):
        m.connect(getattr(br, x), loads[x].p)
        hi = m.add(f"hi_{x}", blocks.Pulse(period=1 / F, width=0.5,
                                           delay=k / (3 * F)))
        lo = m.add(f"lo_{x}", blocks.Pulse(period=1 / F, width=0.5,
                                           delay=k / (3 * F) + 0.5 / F))
        m.connect(hi.y, getattr(br, f"fire_{x}_p"))
        m.connect(lo.y, getattr(br, f"fire_{x}_n"))
    m.connect(loads["a"].n, loads["b"].n, loads["c"].n)     # floating star point
    # sample the middle of each of the six states of the second period
    t = (1 + (np.arange(6) + 0.5) / 6) / F
    res = mt.simulate(m, 2 / F, t_out=t, rtol=1e-10, atol=1e-12)
    # the states: which legs are high in each sixth of the period
    high = np.array([[1, 0, 1], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 1, 1], [0, 0, 1]])
    for k in range(6):
        n_hi = high[k].sum()
        # each high leg in parallel, in series with the low legs in parallel
        i_total = V / ((R + RON) / n_hi + (R + RON) / (3 - n_hi))
        for j, x in enumerate("abc"):
            i_x = i_total / n_hi if high[k, j] else -i_total / (3 - n_hi)
            assert res[f"r_{x}.i"][k] == pytest.approx(i_x, rel=1e-6)
    # line-to-neutral staircase: +-V/3, +-2V/3 (up to the switches' drop)
    v_an = res["r_a.v"]
    np.testing.assert_allclose(v_an, V * R / (R + RON) * np.array([1, 2, 1, -1, -2, -1]) / 3,
                               rtol=1e-6)


def test_battery_constant_current_discharge():
    I, Q, R0, R1, C1, NS = 5.0, 2.5, 0.02, 0.015, 2000.0, 3
    ocv = [(0.0, 3.0), (0.5, 3.6), (1.0, 4.2)]
    m = mt.System("bat")
    bat = m.add("bat", el.Battery(ocv=ocv, Q=Q, R0=R0, R1=R1, C1=C1, n_s=NS, SOC=0.9))
    load = m.add("load", el.DCCurrentSource(I=I))
    g = m.add("g", el.ElectricalReference())
    m.connect(bat.p, load.p)           # the load draws I out of the battery's p
    m.connect(bat.n, load.n, g.port)
    t = np.linspace(0, 900.0, 91)
    res = mt.simulate(m, 900.0, t_out=t, rtol=1e-10, atol=1e-12)
    soc = 0.9 - I * t / (3600 * Q)
    v1 = -I * R1 * (1 - np.exp(-t / (R1 * C1)))
    np.testing.assert_allclose(res["bat.SOC"], soc, atol=1e-10)
    np.testing.assert_allclose(res["bat.v1"], v1, atol=1e-9)
    np.testing.assert_allclose(res["bat.v"], NS * np.interp(soc, [0, 0.5, 1], [3.0, 3.6, 4.2])
                               - I * R0 + v1, atol=1e-8)
    # energy: delivered + dissipated = chemical energy released (n_s 3600 Q int v_oc dSOC)
    te = np.linspace(0, 900.0, 90001)
    fine = mt.simulate(m, 900.0, t_out=te, rtol=1e-10, atol=1e-12)
    delivered = np.trapezoid(-fine["bat.v"] * fine["bat.i"], te)
    lost = np.trapezoid(R0 * fine["bat.i"] ** 2 + fine["bat.v1"] ** 2 / R1, te)
    stored_c = 0.5 * C1 * fine["bat.v1"][-1] ** 2
    s = np.linspace(fine["bat.SOC"][-1], 0.9, 10001)
    chemical = NS * 3600 * Q * np.trapezoid(np.interp(s, [0, 0.5, 1], [3.0, 3.6, 4.2]), s)
    assert delivered + lost + stored_c == pytest.approx(chemical, rel=1e-6)


def test_battery_table_is_checked():
    from mechatron.errors import DataError
    with pytest.raises(DataError, match="strictly increasing"):
        el.Battery(ocv=[(0.0, 3.0), (0.0, 3.5)])
