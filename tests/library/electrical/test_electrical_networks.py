"""Passive and ideal electrical parts against analytic answers: variable resistor,
potentiometer, heating resistor, mutual inductor, ideal transformer with power sensors,
op-amp amplifiers, and the energy balance of a driven RLC network."""

import numpy as np
import pytest
from scipy.linalg import expm

import mechatron as mt
from mechatron.core import Input, Variable, der
from mechatron.library import blocks
from mechatron.library import electrical as el
from mechatron.library import thermal as th


class Integrator(mt.Component):
    """Test-only: ``der(y) == u`` from y(0) = 0 (an energy meter when u is a power)."""

    u = Input("1", doc="Integrand")
    y = Variable("1", start=0.0, doc="Integral of u")

    def equations(self):
        return [der(self.y) == self.u]


def test_variable_resistor_follows_its_signal():
    V = 6.0
    m = mt.System("vr")
    ramp = m.add("ramp", blocks.Ramp(initial=2.0, slope=10.0))
    src = m.add("src", el.DCVoltageSource(V=V))
    r = m.add("r", el.VariableResistor())
    g = m.add("g", el.ElectricalReference())
    m.connect(ramp.y, r.R)
    m.connect(src.p, r.p)
    m.connect(r.n, src.n, g.port)
    res = mt.simulate(m, 1.0, t_out=np.linspace(0, 1, 51))
    np.testing.assert_allclose(res["r.i"], V / (2.0 + 10.0 * res.t), rtol=1e-13)


@pytest.mark.parametrize("x", [0.0, 0.25, 0.8, 1.0, 1.7])
def test_potentiometer_divides_with_a_loaded_wiper(x):
    V, R, RMIN, RL = 10.0, 1e3, 0.5, 2.2e3
    m = mt.System("pot")
    pos = m.add("pos", blocks.Constant(value=x))
    src = m.add("src", el.DCVoltageSource(V=V))
    pot = m.add("pot", el.Potentiometer(R=R, R_min=RMIN))
    load = m.add("load", el.Resistor(R=RL))
    g = m.add("g", el.ElectricalReference())
    m.connect(pos.y, pot.x)
    m.connect(src.p, pot.p)
    m.connect(pot.wiper, load.p)
    m.connect(pot.n, load.n, src.n, g.port)
    res = mt.simulate(m, 1e-3, t_out=np.array([0.0, 1e-3]))
    xc = min(max(x, 0.0), 1.0)
    r_top, r_bot = R * xc + RMIN, R * (1 - xc) + RMIN
    r_par = r_bot * RL / (r_bot + RL)
    v_w = V * r_par / (r_top + r_par)
    assert res.final("load.v") == pytest.approx(v_w, rel=1e-13)
    # the load draws its current out of the wiper (pin currents are positive inwards)
    assert res.final("pot.wiper.i") == pytest.approx(-v_w / RL, rel=1e-12)
    assert res.final("pot.p.i") + res.final("pot.n.i") + res.final("pot.wiper.i") == \
        pytest.approx(0.0, abs=1e-15)


@pytest.mark.parametrize("temp", [300.15, 350.0, 420.0])
def test_heating_resistor_resistance_and_heat_at_a_fixed_temperature(temp):
    V, R_REF, ALPHA, T_REF = 12.0, 4.0, 3.9e-3, 300.15
    m = mt.System("hr")
    src = m.add("src", el.DCVoltageSource(V=V))
    r = m.add("r", el.HeatingResistor(R_ref=R_REF, alpha=ALPHA, T_ref=T_REF))
    amb = m.add("amb", th.FixedTemperature(T=temp))
    g = m.add("g", el.ElectricalReference())
    m.connect(src.p, r.p)
    m.connect(r.n, src.n, g.port)
    m.connect(r.heat_port, amb.port)
    res = mt.simulate(m, 1e-3, t_out=np.array([0.0, 1e-3]))
    R = R_REF * (1 + ALPHA * (temp - T_REF))
    assert res.final("r.R") == pytest.approx(R, rel=1e-14)
    assert res.final("r.i") == pytest.approx(V / R, rel=1e-13)
    # the loss leaves through the heat port into the fixed temperature
    assert res.final("r.heat_port.Q") == pytest.approx(-V ** 2 / R, rel=1e-13)
    assert res.final("amb.port.Q") == pytest.approx(V ** 2 / R, rel=1e-13)


def test_heating_resistor_self_heating_settles_where_loss_equals_conduction():
    """R(T) = R_ref (1 + alpha (T - T_ref)) heats a capacitance C through G to ambient:
    the steady state solves G (T - Ta) = V^2 / R(T), a quadratic in T."""
    V, R_REF, ALPHA, T_REF, C, G, TA = 10.0, 5.0, 4e-3, 293.15, 2.0, 0.5, 293.15
    m = mt.System("self_heating")
    src = m.add("src", el.DCVoltageSource(V=V))
    r = m.add("r", el.HeatingResistor(R_ref=R_REF, alpha=ALPHA, T_ref=T_REF))
    cap = m.add("cap", th.HeatCapacitor(C=C, T=TA))
    cond = m.add("cond", th.ThermalConductor(G=G))
    amb = m.add("amb", th.FixedTemperature(T=TA))
    g = m.add("g", el.ElectricalReference())
    m.connect(src.p, r.p)
    m.connect(r.n, src.n, g.port)
    m.connect(r.heat_port, cap.port, cond.A)
    m.connect(cond.B, amb.port)
    res = mt.simulate(m, 200.0, rtol=1e-10, atol=1e-12)
    # G (T - Ta) R_ref (1 + alpha (T - T_ref)) = V^2, with u = T - Ta and Ta = T_ref
    a, b, c = G * R_REF * ALPHA, G * R_REF, -V ** 2
    u = (-b + np.sqrt(b * b - 4 * a * c)) / (2 * a)
    assert res.final("cap.T") == pytest.approx(TA + u, rel=1e-8)


def test_mutual_inductor_coupled_currents_match_the_matrix_exponential():
    V, R1, R2, L1, L2, M = 5.0, 2.0, 3.0, 10e-3, 20e-3, 12e-3
    m = mt.System("mi")
    src = m.add("src", el.DCVoltageSource(V=V))
    r1 = m.add("r1", el.Resistor(R=R1))
    mi = m.add("mi", el.MutualInductor(L1=L1, L2=L2, M=M))
    r2 = m.add("r2", el.Resistor(R=R2))
    g = m.add("g", el.ElectricalReference())
    m.connect(src.p, r1.p)
    m.connect(r1.n, mi.p1)
    m.connect(mi.p2, r2.p)
    m.connect(mi.n1, mi.n2, r2.n, src.n, g.port)
    times = np.array([0.0, 1e-3, 3e-3, 1e-2, 3e-2])
    res = mt.simulate(m, times[-1], rtol=1e-11, atol=1e-13, t_out=times)
    # [L1 M; M L2] d/dt [i1; i2] = [V - R1 i1; -R2 i2]   (i2 into p2 = -load current)
    Lm = np.array([[L1, M], [M, L2]])
    A = np.linalg.solve(Lm, np.diag([-R1, -R2]))
    b = np.linalg.solve(Lm, [V, 0.0])
    x_inf = -np.linalg.solve(A, b)
    ref = np.array([x_inf - expm(A * t) @ x_inf for t in times])
    np.testing.assert_allclose(res["mi.i1"], ref[:, 0], rtol=1e-8, atol=1e-12)
    np.testing.assert_allclose(res["mi.i2"], ref[:, 1], rtol=1e-8, atol=1e-12)
    # the secondary current is induced (opposes the primary's rise), then decays
    assert res["mi.i2"][1] < 0 and abs(res["mi.i2"][-1]) < abs(res["mi.i2"][1])


def test_ideal_transformer_ratios_and_power_conservation():
    VA, F, RS, RL, N = 10.0, 50.0, 1.0, 8.0, 4.0
    m = mt.System("xfmr")
    src = m.add("src", el.ACVoltageSource(V_amp=VA, f=F))
    rs = m.add("rs", el.Resistor(R=RS))
    p_in = m.add("p_in", el.PowerSensor())
    x = m.add("x", el.IdealTransformer(N=N))
    p_out = m.add("p_out", el.PowerSensor())
    rl = m.add("rl", el.Resistor(R=RL))
    g = m.add("g", el.ElectricalReference())
    m.connect(src.p, rs.p)
    m.connect(rs.n, p_in.pc, p_in.pv)
    m.connect(p_in.nc, x.p1)
    m.connect(x.p2, p_out.pc, p_out.pv)
    m.connect(p_out.nc, rl.p)
    m.connect(src.n, x.n1, x.n2, rl.n, p_in.nv, p_out.nv, g.port)
    res = mt.simulate(m, 0.04, t_out=np.linspace(0, 0.04, 401))
    vs = VA * np.sin(2 * np.pi * F * res.t)
    i1 = vs / (RS + N ** 2 * RL)          # the load seen from the primary is N^2 RL
    np.testing.assert_allclose(res["x.i1"], i1, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(res["x.v1"], N * res["x.v2"], rtol=1e-13, atol=1e-14)
    np.testing.assert_allclose(res["x.i2"], -N * res["x.i1"], rtol=1e-13, atol=1e-15)
    np.testing.assert_allclose(res["rl.i"], N * i1, rtol=1e-12, atol=1e-15)
    # power sensors read v*i, and the transformer passes all of it on
    np.testing.assert_allclose(res["p_in.P"], res["x.v1"] * res["x.i1"], rtol=1e-13,
                               atol=1e-15)
    np.testing.assert_allclose(res["p_out.P"], res["rl.v"] * res["rl.i"], rtol=1e-13,
                               atol=1e-15)
    np.testing.assert_allclose(res["p_out.P"], res["p_in.P"], rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(res["p_in.P"], N ** 2 * RL * i1 ** 2, rtol=1e-12,
                               atol=1e-14)
    # the sensors are transparent: no voltage drop in the current path, no current in
    # the voltage path
    assert np.all(res["p_in.pv.i"] == 0) and np.all(res["p_out.nv.i"] == 0)
    np.testing.assert_allclose(res["p_in.pc.v"], res["p_in.nc.v"], atol=0)


# -- op-amps --------------------------------------------------------------------------------

def inverting_amplifier(opamp, vs_amp=1.0, r1=1e3, r2=4.7e3, f=100.0):
    m = mt.System("inv")
    src = m.add("src", el.ACVoltageSource(V_amp=vs_amp, f=f))
    ra = m.add("r1", el.Resistor(R=r1))
    rb = m.add("r2", el.Resistor(R=r2))
    m.add("op", opamp)
    g = m.add("g", el.ElectricalReference())
    m.connect(src.p, ra.p)
    m.connect(ra.n, rb.p, opamp.in_n)
    m.connect(rb.n, opamp.out)
    m.connect(opamp.in_p, src.n, g.port)
    return m


def nodal_inverting(vs, a, r_in, r_out, r1, r2):
    """Independent nodal analysis of the finite-gain inverting amplifier: unknowns the
    inverting-input and output potentials, with in_p grounded."""
    # node n: (vs - vn)/r1 + (vo - vn)/r2 + (0 - vn)/r_in = 0
    # node o: (vn - vo)/r2 + (a (0 - vn) - vo)/r_out = 0
    A = np.array([[-1 / r1 - 1 / r2 - 1 / r_in, 1 / r2],
                  [1 / r2 - a / r_out, -1 / r2 - 1 / r_out]])
    b = np.array([-vs / r1, 0.0])
    return np.linalg.solve(A, b)


def test_ideal_opamp_inverting_gain_is_minus_r2_over_r1():
    res = mt.simulate(inverting_amplifier(el.IdealOpAmp()), 0.02,
                      t_out=np.linspace(0, 0.02, 201))
    np.testing.assert_allclose(res["op.out.v"], -4.7 * res["src.v"], rtol=1e-12,
                               atol=1e-14)
    np.testing.assert_allclose(res["op.in_n.v"], 0.0, atol=1e-15)
    assert np.all(res["op.in_n.i"] == 0)


@pytest.mark.parametrize("a,r_in,r_out", [(1e5, 1e6, 10.0), (50.0, 2e3, 100.0)])
def test_finite_gain_opamp_inverting_amplifier(a, r_in, r_out):
    r1, r2 = 1e3, 4.7e3
    res = mt.simulate(inverting_amplifier(el.FiniteGainOpAmp(A=a, R_in=r_in, R_out=r_out)),
                      0.01, t_out=np.linspace(0, 0.01, 11))
    gain = nodal_inverting(1.0, a, r_in, r_out, r1, r2)[1]
    np.testing.assert_allclose(res["op.out.v"], gain * res["src.v"], rtol=1e-10,
                               atol=1e-13)
    # with R_in -> inf and R_out -> 0 the nodal answer is the textbook formula
    ideal_in = nodal_inverting(1.0, a, 1e15, 1e-12, r1, r2)[1]
    assert ideal_in == pytest.approx(-a * r2 / (r1 + r2 + a * r1), rel=1e-9)


def test_saturating_opamp_clips_at_its_limits():
    A, VMAX, VMIN = 1e4, 12.0, -10.0
    op = el.SaturatingOpAmp(A=A, R_in=1e12, R_out=0.0, V_max=VMAX, V_min=VMIN)
    res = mt.simulate(inverting_amplifier(op, vs_amp=5.0, r2=4.7e3), 0.02,
                      rtol=1e-10, atol=1e-12, t_out=np.linspace(0, 0.02, 801))
    r1, r2 = 1e3, 4.7e3
    g_cl = -A * r2 / (r1 + r2 + A * r1)        # linear closed-loop gain (R_in, R_out ideal)
    expected = np.clip(g_cl * res["src.v"], VMIN, VMAX)
    np.testing.assert_allclose(res["op.out.v"], expected, rtol=1e-8, atol=1e-9)
    assert res["op.out.v"].max() == pytest.approx(VMAX, rel=1e-12)
    assert res["op.out.v"].min() == pytest.approx(VMIN, rel=1e-12)
    # two sine periods: enters and leaves each limit twice
    assert res.stats.events["op"] == 8


# -- energy balance -------------------------------------------------------------------------

def test_rlc_network_energy_balance():
    """An AC source drives R1 in series with L, into C parallel R2: the input energy
    equals the resistive losses plus the magnetic and electric energy stored, to 1e-6."""
    VA, F, R1, L, C, R2 = 5.0, 120.0, 3.0, 20e-3, 100e-6, 40.0
    m = mt.System("rlc")
    src = m.add("src", el.ACVoltageSource(V_amp=VA, f=F, V_offset=1.0))
    ps = m.add("ps", el.PowerSensor())
    r1 = m.add("r1", el.Resistor(R=R1))
    ind = m.add("l", el.Inductor(L=L))
    cap = m.add("c", el.Capacitor(C=C))
    r2 = m.add("r2", el.Resistor(R=R2))
    p1 = m.add("p1", el.PowerSensor())
    p2 = m.add("p2", el.PowerSensor())
    e_in = m.add("e_in", Integrator())
    e_r1 = m.add("e_r1", Integrator())
    e_r2 = m.add("e_r2", Integrator())
    g = m.add("g", el.ElectricalReference())
    m.connect(src.p, ps.pc, ps.pv)
    m.connect(ps.nc, p1.pc, p1.pv)
    m.connect(p1.nc, r1.p)
    m.connect(r1.n, p1.nv, ind.p)
    m.connect(ind.n, cap.p, p2.pc, p2.pv)
    m.connect(p2.nc, r2.p)
    m.connect(src.n, ps.nv, cap.n, r2.n, p2.nv, g.port)
    m.connect(ps.P, e_in.u)
    m.connect(p1.P, e_r1.u)
    m.connect(p2.P, e_r2.u)
    t_stop = 0.1
    res = mt.simulate(m, t_stop, rtol=1e-10, atol=1e-12)
    stored = 0.5 * L * res.final("l.i") ** 2 + 0.5 * C * res.final("c.v") ** 2
    lost = res.final("e_r1.y") + res.final("e_r2.y")
    assert res.final("e_in.y") > 0.1
    assert lost + stored == pytest.approx(res.final("e_in.y"), rel=1e-6)
    # and the power sensor on R1 reads R1 i^2 all along
    np.testing.assert_allclose(res["p1.P"], R1 * res["r1.i"] ** 2, rtol=1e-12, atol=1e-15)
