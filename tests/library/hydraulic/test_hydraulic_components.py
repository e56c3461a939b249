"""Hydraulic components against fluid-power formulas and energy conservation."""

import numpy as np
import pytest

import mechatron as mt
from mechatron.library import blocks
from mechatron.library import hydraulic as hy
from mechatron.library import rotational as rot
from mechatron.library import translational as tr

TOL = dict(rtol=1e-10, atol=1e-14)
RHO, NU, BETA = 860.0, 32e-6, 1.5e9


def orifice_ref(area, dp, Cd=0.7, rho=RHO, nu=NU, re_cr=12.0):
    """Independent NumPy statement of the smooth orifice law."""
    d_h = np.sqrt(4 * area / np.pi)
    p_cr = rho / 2 * (re_cr * nu / (Cd * d_h)) ** 2
    return Cd * area * np.sqrt(2 / rho) * dp / (dp ** 2 + p_cr ** 2) ** 0.25, p_cr


def across(element, P, *, controlled=False):
    """Reservoir -> pressure source (rise P) -> element.A; element.B -> reservoir."""
    m = mt.System("across")
    tank = m.add("tank", hy.HydraulicReference())
    src = m.add("src", hy.ControlledPressureSource() if controlled
                else hy.PressureSource(P=P))
    e = m.add("e", element)
    m.connect(tank.port, src.A, e.B)
    m.connect(src.B, e.A)
    return m


@pytest.mark.parametrize("dp", [50e5, 2e5, -30e5])
def test_orifice_is_turbulent_well_above_the_transition(dp):
    area = 2e-6
    res = mt.simulate(across(hy.FixedOrifice(area=area), dp), 1e-3, **TOL)
    q_turb = 0.7 * area * np.sqrt(2 * abs(dp) / RHO) * np.sign(dp)
    ref, p_cr = orifice_ref(area, dp)
    assert p_cr < 1e-2 * abs(dp)
    assert res.final("e.q") == pytest.approx(ref, rel=1e-12)
    assert res.final("e.q") == pytest.approx(q_turb, rel=(p_cr / dp) ** 2)


def test_orifice_is_laminar_and_linear_near_zero_pressure_drop():
    area = 2e-6
    _, p_cr = orifice_ref(area, 1.0)
    # the transition pressure is where the turbulent law reaches the critical Reynolds
    d_h = np.sqrt(4 * area / np.pi)
    q_cr = 0.7 * area * np.sqrt(2 * p_cr / RHO)
    assert q_cr * d_h / (area * NU) == pytest.approx(12.0, rel=1e-12)
    dp = 1e-3 * p_cr
    res = mt.simulate(across(hy.FixedOrifice(area=area), dp), 1e-3, **TOL)
    laminar = 2 * 0.7 ** 2 * area * d_h * dp / (RHO * 12.0 * NU)
    assert res.final("e.q") == pytest.approx(laminar, rel=1e-6)


def test_fluid_properties_are_handed_over_by_params_for():
    water = hy.Fluid(rho=998.0, nu=1.0e-6, beta=2.2e9)
    kw = water.params_for(hy.FixedOrifice)
    assert kw == {"rho": 998.0, "nu": 1.0e-6}
    assert hy.ISO_VG32.params_for(hy.ConstantVolumeChamber) == {"beta": 1.5e9}
    res = mt.simulate(across(hy.FixedOrifice(area=1e-6, **kw), 1e5), 1e-3, **TOL)
    ref, _ = orifice_ref(1e-6, 1e5, rho=998.0, nu=1e-6)
    assert res.final("e.q") == pytest.approx(ref, rel=1e-12)


def test_variable_orifice_follows_its_area_signal():
    m = across(hy.VariableOrifice(), 10e5)
    ramp = m.add("ramp", blocks.Ramp(slope=1e-6, initial=1e-7))
    m.connect(ramp.y, m.e.area_in)
    t = np.linspace(0, 2, 5)
    res = mt.simulate(m, 2.0, t_out=t, **TOL)
    ref, _ = orifice_ref(1e-7 + 1e-6 * t, 10e5)
    np.testing.assert_allclose(res["e.q"], ref, rtol=1e-10)


def flow_into(element, Q, port="port", controlled=False):
    """Reservoir -> flow source Q -> element.<port>."""
    m = mt.System("flow_into")
    tank = m.add("tank", hy.HydraulicReference())
    src = m.add("src", hy.ControlledFlowSource() if controlled else hy.FlowSource(Q=Q))
    e = m.add("e", element)
    m.connect(tank.port, src.A)
    m.connect(src.B, getattr(e, port))
    if port == "A":
        m.connect(e.B, tank.port)
    return m


def test_resistive_pipe_obeys_hagen_poiseuille():
    L, D, Q = 3.0, 8e-3, 2e-5
    res = mt.simulate(flow_into(hy.ResistivePipe(length=L, D=D), Q, port="A"), 1e-3, **TOL)
    mu = RHO * NU
    assert res.final("e.dp") == pytest.approx(128 * mu * L * Q / (np.pi * D ** 4),
                                              rel=1e-12)
    assert 4 * Q / (np.pi * D * NU) < 2300  # laminar, as the law assumes


def test_compressible_pipe_fills_its_volume_with_the_RC_time_constant():
    """Step of P at A, B open to tank: V/beta p' = (P - 2p)/(R/2) so p -> P/2 with
    tau = V R / (4 beta)."""
    L, D, P = 10.0, 6e-3, 50e5
    R = 128 * RHO * NU * L / (np.pi * D ** 4)
    V = np.pi * D ** 2 / 4 * L
    tau = V * R / (4 * BETA)
    m = across(hy.CompressiblePipe(length=L, D=D, p=0.0), P)
    t = np.linspace(0, 5 * tau, 11)
    res = mt.simulate(m, t[-1], t_out=t, **TOL)
    np.testing.assert_allclose(res["e.p"], P / 2 * (1 - np.exp(-t / tau)), rtol=1e-7,
                               atol=1e-3)
    # in steady state the pipe passes P / R
    res = mt.simulate(m, 40 * tau, **TOL)
    assert res.final("e.A.q") == pytest.approx(P / R, rel=1e-8)
    assert res.final("e.B.q") == pytest.approx(-P / R, rel=1e-8)


def test_chamber_pressure_rises_at_beta_q_over_V():
    V, Q = 2e-4, 1e-5
    t = np.linspace(0, 0.01, 6)
    res = mt.simulate(flow_into(hy.ConstantVolumeChamber(V=V), Q), 0.01, t_out=t, **TOL)
    np.testing.assert_allclose(res["e.p"], BETA * Q * t / V, rtol=1e-9, atol=1e-6)


def test_controlled_flow_source_and_sensors():
    """A sine flow into a chamber: p = beta/V * integral of q; sensors agree."""
    V = 1e-4
    # reservoir -> controlled flow source -> flow meter -> chamber; the pressure sensor
    # reads the chamber against the tank
    m = mt.System("sensed")
    tank = m.add("tank", hy.HydraulicReference())
    src = m.add("src", hy.ControlledFlowSource())
    s2 = m.add("sine", blocks.Sine(amplitude=1e-5, f=5.0))
    fs = m.add("fs", hy.FlowSensor())
    ch = m.add("ch", hy.ConstantVolumeChamber(V=V))
    ps = m.add("ps", hy.PressureSensor())
    m.connect(s2.y, src.Q_in)
    m.connect(tank.port, src.A, ps.B)
    m.connect(src.B, fs.A)
    m.connect(fs.B, ch.port, ps.A)
    t = np.linspace(0, 0.4, 9)
    res = mt.simulate(m, 0.4, t_out=t, **TOL)
    w = 2 * np.pi * 5.0
    p = BETA / V * 1e-5 * (1 - np.cos(w * t)) / w
    np.testing.assert_allclose(res["ps.p_rel"], p, rtol=1e-8, atol=1e-7 * p.max())
    np.testing.assert_allclose(res["fs.Q"], 1e-5 * np.sin(w * t), rtol=1e-9, atol=1e-16)


def test_cylinder_force_is_pA_AA_minus_pB_AB_and_accelerates_a_mass():
    AA, AB, pA, pB, mass_kg = 2e-3, 1.2e-3, 40e5, 10e5, 50.0
    m = mt.System("cyl")
    tank = m.add("tank", hy.HydraulicReference())
    sa = m.add("sa", hy.PressureSource(P=pA))
    sb = m.add("sb", hy.PressureSource(P=pB))
    cyl = m.add("cyl", hy.DoubleActingCylinder(area_A=AA, area_B=AB, x=0.01))
    load = m.add("load", tr.Mass(m=mass_kg, v=0.0))
    ground = m.add("ground", tr.TranslationalReference())
    m.connect(tank.port, sa.A, sb.A)
    m.connect(sa.B, cyl.A)
    m.connect(sb.B, cyl.B)
    m.connect(cyl.rod, load.port)
    m.connect(cyl.case, ground.port)
    t = np.linspace(0, 0.05, 6)
    res = mt.simulate(m, 0.05, t_out=t, **TOL)
    F = pA * AA - pB * AB
    np.testing.assert_allclose(res["cyl.F"], F, rtol=1e-12)
    np.testing.assert_allclose(res["cyl.x"], 0.01 + F * t ** 2 / (2 * mass_kg), rtol=1e-9)
    # the chambers take area * velocity (pressures are held, so no compression)
    v = F * t / mass_kg
    np.testing.assert_allclose(res["cyl.A.q"], AA * v, rtol=1e-8, atol=1e-14)
    np.testing.assert_allclose(res["cyl.B.q"], -AB * v, rtol=1e-8, atol=1e-14)


def test_cylinder_fed_by_a_flow_moves_at_q_over_area():
    AA, AB, Q, b = 2e-3, 1.2e-3, 1e-4, 2e4
    m = mt.System("cyl_flow")
    tank = m.add("tank", hy.HydraulicReference())
    src = m.add("src", hy.FlowSource(Q=Q))
    cyl = m.add("cyl", hy.DoubleActingCylinder(area_A=AA, area_B=AB, x=0.05))
    damper = m.add("d", tr.TranslationalDamper(b=b))
    ground = m.add("ground", tr.TranslationalReference())
    m.connect(tank.port, src.A, cyl.B)
    m.connect(src.B, cyl.A)
    m.connect(cyl.rod, damper.A)
    m.connect(cyl.case, damper.B, ground.port)
    t = np.concatenate([[0.0, 1e-9], np.linspace(0.01, 0.2, 20)])
    res = mt.simulate(m, 0.2, t_out=t, **TOL)
    v = Q / AA
    assert res.final("d.v") == pytest.approx(v, rel=1e-8)
    assert res.final("cyl.A.p") == pytest.approx(b * v / AA, rel=1e-8)
    # compressibility: the pressure builds at the chamber's rate beta Q / V_A first
    V_A = 1e-5 + AA * 0.05
    rate = (res["cyl.A.p"][1] - res["cyl.A.p"][0]) / (res.t[1] - res.t[0])
    assert rate == pytest.approx(BETA * Q / V_A, rel=1e-4)


def pump_rig(D, k_leak, T, J, R, w0):
    m = mt.System("pump")
    tank = m.add("tank", hy.HydraulicReference())
    pump = m.add("pump", hy.FixedDisplacementPump(D=D, k_leak=k_leak))
    pipe = m.add("pipe", hy.ResistivePipe(length=1.0, D=4e-3))
    torque = m.add("tq", blocks.Constant(value=T))
    src = m.add("src", rot.IdealTorqueSource())
    inertia = m.add("J", rot.Inertia(J=J, w=w0))
    ground = m.add("ground", rot.RotationalReference())
    m.connect(tank.port, pump.A, pipe.B)
    m.connect(pump.B, pipe.A)
    m.connect(torque.y, src.tau_in)
    m.connect(src.A, inertia.port, pump.shaft)
    m.connect(src.B, pump.case, ground.port)
    return m


def test_pump_delivers_D_w_and_needs_D_dp():
    D, T, J, w0 = 2e-6, 5.0, 0.01, 100.0
    R = 128 * RHO * NU * 1.0 / (np.pi * (4e-3) ** 4)
    m = pump_rig(D, 0.0, T, J, R, w0)
    t = np.linspace(0, 0.5, 11)
    res = mt.simulate(m, 0.5, t_out=t, **TOL)
    # J w' = T - D dp, dp = R D w: first order towards T / (R D^2)
    w_inf, tau = T / (R * D ** 2), J / (R * D ** 2)
    w = w_inf + (w0 - w_inf) * np.exp(-t / tau)
    np.testing.assert_allclose(res["pump.w"], w, rtol=1e-8)
    np.testing.assert_allclose(res["pump.q"], D * res["pump.w"], rtol=1e-12)
    np.testing.assert_allclose(res["pump.shaft.tau"], D * res["pump.dp"], rtol=1e-12)
    np.testing.assert_allclose(res["pump.dp"], R * D * w, rtol=1e-8)


def test_pump_leakage_reduces_delivery_by_k_leak_dp():
    D, k = 2e-6, 1e-12
    R = 128 * RHO * NU * 1.0 / (np.pi * (4e-3) ** 4)
    res = mt.simulate(pump_rig(D, k, 5.0, 0.01, R, 100.0), 15.0, **TOL)  # 25 tau
    q, dp, w = res["pump.q"], res["pump.dp"], res["pump.w"]
    np.testing.assert_allclose(q, D * w - k * dp, rtol=1e-12)
    # steady state: dp = R q, J w' = 0 = T - D dp
    assert res.final("pump.dp") == pytest.approx(5.0 / D, rel=1e-6)
    assert res.final("pump.w") == pytest.approx((5.0 / D / R + k * 5.0 / D) / D, rel=1e-6)


def test_motor_turns_a_pressure_into_torque_D_dp():
    D, P, J, b, k = 3e-6, 80e5, 0.02, 0.01, 2e-13
    m = mt.System("motor")
    tank = m.add("tank", hy.HydraulicReference())
    src = m.add("src", hy.PressureSource(P=P))
    mot = m.add("mot", hy.FixedDisplacementMotor(D=D, k_leak=k))
    inertia = m.add("J", rot.Inertia(J=J, w=0.0))
    damper = m.add("b", rot.RotationalDamper(D=b))
    ground = m.add("ground", rot.RotationalReference())
    m.connect(tank.port, src.A, mot.B)
    m.connect(src.B, mot.A)
    m.connect(mot.shaft, inertia.port, damper.A)
    m.connect(mot.case, damper.B, ground.port)
    t = np.linspace(0, 10, 11)
    res = mt.simulate(m, 10.0, t_out=t, **TOL)
    w = D * P / b * (1 - np.exp(-b * t / J))
    np.testing.assert_allclose(res["J.w"], w, rtol=1e-8, atol=1e-9)
    np.testing.assert_allclose(res["mot.q"], D * w + k * P, rtol=1e-8)


def test_check_valve_opens_from_the_cracking_pressure():
    A_max, A_leak, pc, po = 1e-5, 1e-12, 1e5, 3e5
    m = across(hy.CheckValve(A_max=A_max, A_leak=A_leak, p_crack=pc, p_open=po), 0.0,
               controlled=True)
    ramp = m.add("ramp", blocks.Ramp(slope=1e5, initial=-2e5))
    m.connect(ramp.y, m.src.P_in)
    t = np.linspace(0, 6, 61)
    res = mt.simulate(m, 6.0, t_out=t, **TOL)
    dp = -2e5 + 1e5 * t
    frac = np.clip((dp - pc) / (po - pc), 0, 1)
    q, _ = orifice_ref(A_leak + (A_max - A_leak) * frac, dp)
    np.testing.assert_allclose(res["e.q"], q, rtol=1e-9, atol=1e-15)
    assert np.all(np.abs(res["e.q"][dp <= pc]) < 1e-8)        # closed: leakage only
    assert res.final("e.q") == pytest.approx(orifice_ref(A_max, 4e5)[0], rel=1e-9)


def test_four_way_valve_routes_P_to_A_and_B_to_T_for_a_positive_spool():
    x_max, A_max, A_leak = 1e-3, 1e-5, 1e-12
    pressures = {"P": 100e5, "A": 30e5, "B": 20e5, "T": 0.0}
    m = mt.System("valve")
    tank = m.add("tank", hy.HydraulicReference())
    v = m.add("v", hy.FourWayDirectionalValve(x_max=x_max, A_max=A_max, A_leak=A_leak))
    spool = m.add("spool", blocks.Ramp(slope=1e-3, initial=-1.5e-3))
    m.connect(spool.y, v.x)
    m.connect(v.T, tank.port)
    for name in ("P", "A", "B"):
        src = m.add(f"s{name}", hy.PressureSource(P=pressures[name]))
        m.connect(src.A, tank.port)
        m.connect(src.B, getattr(v, name))
    t = np.linspace(0, 3, 61)
    res = mt.simulate(m, 3.0, t_out=t, **TOL)
    x = -1.5e-3 + 1e-3 * t
    a_pos = A_leak + (A_max - A_leak) * np.clip(x / x_max, 0, 1)
    a_neg = A_leak + (A_max - A_leak) * np.clip(-x / x_max, 0, 1)
    p = pressures
    np.testing.assert_allclose(res["v.q_PA"], orifice_ref(a_pos, p["P"] - p["A"])[0],
                               rtol=1e-9, atol=1e-15)
    np.testing.assert_allclose(res["v.q_BT"], orifice_ref(a_pos, p["B"] - p["T"])[0],
                               rtol=1e-9, atol=1e-15)
    np.testing.assert_allclose(res["v.q_PB"], orifice_ref(a_neg, p["P"] - p["B"])[0],
                               rtol=1e-9, atol=1e-15)
    np.testing.assert_allclose(res["v.q_AT"], orifice_ref(a_neg, p["A"] - p["T"])[0],
                               rtol=1e-9, atol=1e-15)
    total = res["v.P.q"] + res["v.A.q"] + res["v.B.q"] + res["v.T.q"]
    np.testing.assert_allclose(total, 0.0, atol=1e-18)  # the valve stores no fluid


def test_gas_accumulator_follows_the_polytropic_law():
    VT, ppr, n, Q, patm = 1e-3, 20e5, 1.4, 1e-5, 101325.0
    m = flow_into(hy.GasChargedAccumulator(V_total=VT, p_pr=ppr, n=n), Q)
    t = np.linspace(0, 50, 11)
    res = mt.simulate(m, 50.0, t_out=t, **TOL)
    V = Q * t
    np.testing.assert_allclose(res["e.V"], V, rtol=1e-10, atol=1e-16)
    np.testing.assert_allclose(res["e.port.p"],
                               (ppr + patm) * (VT / (VT - V)) ** n - patm, rtol=1e-9)


def test_spring_accumulator_pressure_is_linear_in_volume():
    k, area, ppr, Q = 2e5, 1e-3, 1e5, 1e-5
    m = flow_into(hy.SpringLoadedAccumulator(k=k, area=area, p_pr=ppr), Q)
    t = np.linspace(0, 10, 6)
    res = mt.simulate(m, 10.0, t_out=t, **TOL)
    np.testing.assert_allclose(res["e.port.p"], ppr + k * Q * t / area ** 2, rtol=1e-9)


def test_reservoir_sets_the_pressure_level():
    m = mt.System("res")
    tank = m.add("tank", hy.Reservoir(p=3e5))
    src = m.add("src", hy.FlowSource(Q=1e-5))
    orif = m.add("o", hy.FixedOrifice(area=1e-6))
    m.connect(tank.port, src.A, orif.B)
    m.connect(src.B, orif.A)
    res = mt.simulate(m, 1e-3, **TOL)
    q, _ = orifice_ref(1e-6, res.final("o.dp"))
    assert q == pytest.approx(1e-5, rel=1e-10)
    assert res.final("o.A.p") == pytest.approx(3e5 + res.final("o.dp"), rel=1e-12)


class EnergyPressureSource(hy.ControlledPressureSource):
    """Test only: integrates the hydraulic energy it delivers, ``-dp q``."""

    E = mt.Variable("J", start=0.0, doc="Delivered energy")

    def equations(self):
        return [mt.der(self.E) == -self.dp * self.q]


class EnergyOrifice(hy.FixedOrifice):
    """Test only: integrates its loss ``dp q``."""

    E = mt.Variable("J", start=0.0, doc="Dissipated energy")

    def equations(self):
        return [mt.der(self.E) == self.dp * self.q]


class EnergyPipe(hy.ResistivePipe):
    """Test only: integrates its loss ``dp q``."""

    E = mt.Variable("J", start=0.0, doc="Dissipated energy")

    def equations(self):
        return [mt.der(self.E) == self.dp * self.q]


def test_hydraulic_energy_balance_source_equals_losses_plus_storage():
    """Pulsating pressure source -> orifice -> chamber -> pipe -> spring accumulator:
    delivered energy = orifice and pipe losses + compression + accumulator energy."""
    V, k, area, ppr = 5e-5, 5e5, 1e-3, 2e5
    m = mt.System("hyd_energy")
    tank = m.add("tank", hy.HydraulicReference())
    sine = m.add("sine", blocks.Sine(amplitude=30e5, offset=50e5, f=3.0))
    src = m.add("src", EnergyPressureSource())
    orif = m.add("orif", EnergyOrifice(area=2e-7))
    ch = m.add("ch", hy.ConstantVolumeChamber(V=V, p=ppr))
    pipe = m.add("pipe", EnergyPipe(length=2.0, D=2e-3))
    acc = m.add("acc", hy.SpringLoadedAccumulator(k=k, area=area, p_pr=ppr, V=0.0))
    m.connect(sine.y, src.P_in)
    m.connect(tank.port, src.A)
    m.connect(src.B, orif.A)
    m.connect(orif.B, ch.port, pipe.A)
    m.connect(pipe.B, acc.port)
    res = mt.simulate(m, 1.0, **TOL)

    def stored(i):
        p, Va = res["ch.p"][i], res["acc.V"][i]
        return V * p ** 2 / (2 * BETA) + ppr * Va + k * Va ** 2 / (2 * area ** 2)

    delivered = res.final("src.E")
    losses = res.final("orif.E") + res.final("pipe.E")
    assert res.final("acc.V") > 1e-6 and losses > 0
    assert losses + stored(-1) - stored(0) == pytest.approx(delivered, rel=1e-6)


class EnergyTorqueSource(rot.IdealTorqueSource):
    """Test only: integrates the mechanical energy it delivers, ``tau_in w``."""

    E = mt.Variable("J", start=0.0, doc="Delivered energy")

    def equations(self):
        return [mt.der(self.E) == self.tau_in * self.w]


class EnergyDamper(rot.RotationalDamper):
    """Test only: integrates its loss ``tau w``."""

    E = mt.Variable("J", start=0.0, doc="Dissipated energy")

    def equations(self):
        return [mt.der(self.E) == self.tau * self.w]


class EnergyPump(hy.FixedDisplacementPump):
    """Test only: integrates the leakage loss ``k_leak dp^2``."""

    E = mt.Variable("J", start=0.0, doc="Leakage loss")

    def equations(self):
        return [mt.der(self.E) == self.k_leak * self.dp ** 2]


class EnergyMotor(hy.FixedDisplacementMotor):
    """Test only: integrates the leakage loss ``k_leak dp^2``."""

    E = mt.Variable("J", start=0.0, doc="Leakage loss")

    def equations(self):
        return [mt.der(self.E) == self.k_leak * self.dp ** 2]


def test_hydrostatic_transmission_energy_balance():
    """Torque -> inertia + pump -> line volume (chamber) with a bleed orifice -> motor ->
    inertia + damper: the delivered shaft energy equals pump and motor leakage, orifice
    and damper losses plus the kinetic and compression energy at the end. The pump and
    motor carry their converted power across domains without loss."""
    J1, J2, V, D = 0.01, 0.05, 1e-4, 3e-6
    m = mt.System("transmission")
    tank = m.add("tank", hy.HydraulicReference())
    ground = m.add("ground", rot.RotationalReference())
    torque = m.add("torque", blocks.Sine(amplitude=4.0, offset=6.0, f=2.0))
    src = m.add("src", EnergyTorqueSource())
    j1 = m.add("j1", rot.Inertia(J=J1, w=0.0))
    pump = m.add("pump", EnergyPump(D=D, k_leak=5e-13))
    line = m.add("line", hy.ConstantVolumeChamber(V=V, p=0.0))
    bleed = m.add("bleed", EnergyOrifice(area=1e-7))
    motor = m.add("motor", EnergyMotor(D=D, k_leak=8e-13))
    j2 = m.add("j2", rot.Inertia(J=J2, w=0.0))
    damper = m.add("damper", EnergyDamper(D=0.02))
    m.connect(torque.y, src.tau_in)
    m.connect(src.A, j1.port, pump.shaft)
    m.connect(src.B, pump.case, motor.case, damper.B, ground.port)
    m.connect(tank.port, pump.A, bleed.B, motor.B)
    m.connect(pump.B, line.port, bleed.A, motor.A)
    m.connect(motor.shaft, j2.port, damper.A)
    res = mt.simulate(m, 2.0, **TOL)
    losses = sum(res.final(f"{k}.E") for k in ("pump", "motor", "bleed", "damper"))
    stored = (0.5 * J1 * res.final("j1.w") ** 2 + 0.5 * J2 * res.final("j2.w") ** 2
              + V * res.final("line.p") ** 2 / (2 * BETA))
    assert res.final("j2.w") > 1.0 and res.final("line.p") > 1e5
    assert losses + stored == pytest.approx(res.final("src.E"), rel=1e-6)
