"""The BLDC drive of the database (``bldc_motor``): Hall sectors, six-step currents, torque
constant, speed regulation, energy balance, and switched against averaged PWM.

Every check compares with an analytic fact of the drive (the sector as a function of the
rotor angle, ``T = k_e (i_high - i_low)`` on the back-EMF flat tops, the leakage bound of
an open inverter leg, Newton's law averaged over whole turns, conservation of energy), not
with numbers taken from a previous run.
"""

import math

import casadi as ca
import numpy as np
import pytest

import mechatron as mt
from mechatron.errors import ModelError
from mechatron.library.electrical import interfaces as el_if
from mechatron.library.rotational import interfaces as rot_if
from mechatron.models.compare import compare_variants
from mechatron.models.bldc import COMMUTATION, ENTRY, trapezoid

P = ENTRY.values()                     # SI defaults
T_SETTLE = 0.06                        # s: the speed loop has settled (design: ~40 ms)
T_STOP = 0.2
PHASES = "abc"
FETS = [f"leg_{k}.{side}" for k in PHASES for side in ("high", "low")]  # InverterLeg parts


def expected_sector(theta_e):
    """Sector s covers electrical angles [30 + 60 (s - 1), 90 + 60 (s - 1)) degrees."""
    x = np.mod(np.asarray(theta_e) - math.pi / 6, 2 * math.pi)
    return 1 + np.floor(x / (math.pi / 3))


@pytest.fixture(scope="module")
def run():
    """The acausal drive with averaged PWM, 0.2 s on a fine grid."""
    t = np.linspace(0.0, T_STOP, 20001)
    return mt.simulate(ENTRY.build("acausal"), T_STOP, rtol=1e-8, atol=1e-10, t_out=t)


def steady(res):
    return res.t >= T_SETTLE


def away_from_commutation(res, margin=1.5e-3):
    """Samples after settling, not within ``margin`` s after a sector change, and with no
    body diode conducting."""
    t, s = res.t, res["hall.sector"]
    changes = t[1:][np.diff(s) != 0]
    since = np.full(t.shape, np.inf)
    for tc in changes:
        after = t >= tc
        since[after] = np.minimum(since[after], t[after] - tc)
    return steady(res) & (since > margin) & ~diode_conducts(res)


def diode_conducts(res):
    """A body diode carries current (the logged diode currents of blocked diodes are
    rounding noise below 1e-12 A)."""
    return sum(np.abs(res[f"{q}.i_d"]) for q in FETS) > 1e-9


def test_trapezoid_is_the_clipped_triangle_wave():
    x = np.linspace(-4 * math.pi, 4 * math.pi, 4001)
    ref = np.clip(np.arcsin(np.sin(x)) / (math.pi / 6), -1, 1)
    X = ca.SX.sym("x")
    f = ca.Function("f", [X], [trapezoid(X)])
    np.testing.assert_allclose(np.array(f(x)).ravel(), ref, atol=1e-12)
    np.testing.assert_allclose([trapezoid(float(v)) for v in x], ref, atol=1e-12)
    # finite slope everywhere (the asin form has an infinite one at the peaks)
    df = ca.Function("df", [X], [ca.jacobian(trapezoid(X), X)])
    slopes = np.array(df(np.array([-math.pi / 2, math.pi / 2, 3 * math.pi / 2]))).ravel()
    assert np.all(np.isfinite(slopes))


def test_hall_sectors_follow_the_rotor_angle_in_order(run):
    theta = run["motor.airgap.phi"]            # one pole pair: electrical = mechanical
    sector = run["hall.sector"]
    # away from the edges (grid resolution) the sector is the analytic one
    edge = np.abs(np.mod(theta - math.pi / 6 + 1e-9, math.pi / 3))
    clear = (edge > 1e-3) & (edge < math.pi / 3 - 1e-3)
    np.testing.assert_array_equal(sector[clear], expected_sector(theta[clear]))
    # at constant speed the sequence runs 1, 2, ..., 6, 1, ... through every sector
    m = steady(run)
    s = sector[m]
    changes = np.nonzero(np.diff(s))[0]
    seq = s[np.concatenate([[0], changes + 1])]
    assert len(seq) >= 12 and set(seq) == {1, 2, 3, 4, 5, 6}
    np.testing.assert_array_equal(np.mod(np.diff(seq), 6), 1)
    # each complete visit spans 60 electrical degrees (to the grid's angle resolution)
    th = theta[m]
    starts = th[changes + 1]
    resolution = run["motor.inertia.w"].max() * (run.t[1] - run.t[0])
    np.testing.assert_allclose(np.diff(starts), math.pi / 3, atol=1.01 * resolution)


def test_speed_settles_within_two_percent_of_the_reference(run):
    w, w_ref = run["motor.inertia.w"], P["w_ref"]
    m = steady(run)
    assert np.max(np.abs(w[m] - w_ref)) <= 0.02 * w_ref
    # integral action: the mean over the last whole electrical turns is the reference
    theta = run["motor.airgap.phi"]
    turns = np.floor(theta / (2 * math.pi))
    last = (turns >= turns[-1] - 2) & (turns < turns[-1])
    assert np.mean(w[last]) == pytest.approx(w_ref, rel=1e-3)


def test_phase_currents_show_six_step_commutation(run):
    """Per sector exactly two phases conduct, equal and opposite; the third carries only
    the leakage of its open leg, |G_off (V_p - 2 u)| <= G_off V_p, between commutations;
    body diodes conduct only right after a commutation (the outgoing phase's current)."""
    m = away_from_commutation(run)
    assert m.sum() > 5000
    sector = run["hall.sector"][m]
    V_p = run["supply.v"][m]
    leak = P["G_off"] * V_p * (1 + 1e-6)
    currents = {k: run[f"motor.airgap.i_{k}"][m] for k in PHASES}
    for s, (hi, lo) in COMMUTATION.items():
        sel = sector == s
        assert sel.sum() > 200, s
        floating = ({"a", "b", "c"} - {hi, lo}).pop()
        i_hi, i_lo, i_fl = currents[hi][sel], currents[lo][sel], currents[floating][sel]
        assert np.all(np.abs(i_fl) <= leak[sel])
        assert np.all(np.abs(i_hi + i_lo) <= leak[sel])
        assert np.all(i_hi > 20 * leak[sel])        # motoring: into the high phase
    # no switch ever sees more than the link voltage plus a diode drop: the outgoing
    # phase's current is taken over by a diode at once, not forced through G_off
    for q in FETS:
        v = run[f"{q}.v"]
        assert v.max() < P["V_dc"] + 1.0 and v.min() > -2.0, q
    # the diodes carry current only within 1 ms after a sector change (outgoing phase)
    t, s = run.t, run["hall.sector"]
    changes = t[1:][np.diff(s) != 0]
    conducting = t[diode_conducts(run) & steady(run)]
    assert conducting.size > 0
    lag = np.array([tc - changes[changes <= tc].max() for tc in conducting])
    assert lag.max() < 1e-3


def test_torque_is_two_ke_times_the_phase_current(run):
    """On the flat tops, T = k_e (i_high - i_low) = 2 k_e I (plus k_e f i of the floating
    phase's leakage); and over whole turns in steady state the mean electromagnetic torque
    balances load and friction (J dw/dt averages to the change of speed)."""
    m = away_from_commutation(run)
    sector = run["hall.sector"][m]
    T = run["motor.airgap.T"][m]
    bound = P["k_e"] * P["G_off"] * run["supply.v"][m] * (1 + 1e-6)
    checked = 0
    for s, (hi, lo) in COMMUTATION.items():
        sel = sector == s
        I = (run[f"motor.airgap.i_{hi}"][m][sel] - run[f"motor.airgap.i_{lo}"][m][sel]) / 2
        assert np.all(np.abs(T[sel] - 2 * P["k_e"] * I) <= bound[sel])
        checked += sel.sum()
    assert checked == m.sum()
    # Newton, averaged over the last two whole turns
    theta, t, w = run["motor.airgap.phi"], run.t, run["motor.inertia.w"]
    turns = np.floor(theta / (2 * math.pi))
    last = (turns >= turns[-1] - 2) & (turns < turns[-1])
    i0, i1 = np.nonzero(last)[0][[0, -1]]
    span = t[i1] - t[i0]
    mean_T = np.trapezoid(run["motor.airgap.T"][i0:i1 + 1], t[i0:i1 + 1]) / span
    mean_load = P["T_load"] + P["B"] * np.trapezoid(w[i0:i1 + 1], t[i0:i1 + 1]) / span
    inertial = P["J"] * (w[i1] - w[i0]) / span
    assert mean_T == pytest.approx(mean_load + inertial, rel=1e-4)


def test_energy_balance(run):
    """Energy from the DC link = stored magnetic and kinetic energy + losses in the
    windings, switches and diodes, friction + work on the load."""
    t = run.t
    integral = lambda y: np.trapezoid(y, t)                              # noqa: E731
    supplied = integral(-run["supply.v"] * run["supply.i"])
    i2 = sum(run[f"motor.airgap.i_{k}"] ** 2 for k in PHASES)
    w = run["motor.inertia.w"]
    stored = 0.5 * P["L"] * (i2[-1] - i2[0]) + 0.5 * P["J"] * (w[-1] ** 2 - w[0] ** 2)
    losses = integral(P["R"] * i2 + sum(run[f"{q}.v"] * run[f"{q}.i"] for q in FETS)
                      + P["B"] * w ** 2 + P["T_load"] * w)
    assert supplied > 0
    # trapezoidal quadrature across the commutation jumps of a 10 us grid: ~1e-4
    assert stored + losses == pytest.approx(supplied, rel=3e-4)


def test_switched_pwm_agrees_with_the_averaged_model_on_average(run):
    """Switched PWM (5 kHz, synchronous rectification) once: the same mean speed and
    duty as the averaged model; the phase-current ripple of the PWM leg is the analytic
    d (1 - d) V_dc / (2 L f) of a 2L inductance chopped at f."""
    f = 5e3
    t_stop = 0.1
    t = np.linspace(0.0, t_stop, 10001)
    res = mt.simulate(ENTRY.build("acausal", f_pwm=f), t_stop, rtol=1e-8, atol=1e-10,
                      t_out=t)
    # one event per PWM edge, two per period
    assert res.stats.events["modulator"] == pytest.approx(2 * f * t_stop, abs=2)
    window = (res.t >= T_SETTLE)
    ref = (run.t >= T_SETTLE) & (run.t <= t_stop)
    w_sw, w_av = np.mean(res["motor.inertia.w"][window]), np.mean(run["motor.inertia.w"][ref])
    assert w_sw == pytest.approx(w_av, rel=1e-2)
    assert w_sw == pytest.approx(P["w_ref"], rel=1e-2)
    d_sw, d_av = np.mean(res["controller.d"][window]), np.mean(run["controller.d"][ref])
    assert d_sw == pytest.approx(d_av, rel=1e-2)
    # ripple: in the middle of a long sector, peak-to-peak over whole PWM periods
    s = res["hall.sector"]
    hi_phase = {sec: COMMUTATION[sec][0] for sec in COMMUTATION}
    t_c = res.t[1:][np.diff(s) != 0]
    t_c = t_c[t_c > T_SETTLE]
    mid = 0.5 * (t_c[0] + t_c[1])
    k = (res.t >= mid) & (res.t < mid + 4 / f)
    i_hi = res[f"motor.airgap.i_{hi_phase[int(s[np.searchsorted(res.t, mid)])]}"][k]
    d = np.mean(res["controller.d"][k])
    ripple = d * (1 - d) * P["V_dc"] / (2 * P["L"] * f)
    assert np.ptp(i_hi) == pytest.approx(ripple, rel=0.1)


def test_switched_pwm_variants_agree():
    """The switched network (library MOSFETs, comparator, gate drivers) and the switched
    equations (switching function in closed-form leg solutions) through the start-up:
    every PWM edge, commutation and diode event at the same instants, so the trajectories
    agree to the integration tolerance."""
    cmp = compare_variants(ENTRY, params={"f_pwm": 5e3}, t_stop=0.02, points=2001)
    assert cmp.results["acausal"].stats.events["modulator"] == 200
    for label, dev in cmp.deviations["equation"].items():
        assert dev["max_rel"] <= 1e-5, (label, dev)


def test_negative_pwm_frequency_is_rejected():
    with pytest.raises(ModelError, match="f_pwm must be >= 0"):
        ENTRY.build("acausal", f_pwm=-1.0)


def test_an_inverter_leg_subsystem_equals_its_parts_wired_flat():
    """The InverterLeg subsystem (MOSFET parameters passed on) against the same two
    MOSFETs and gate drivers wired by hand, driving an RL load from a 24 V rail with the
    high side switched on at 1 ms: the same trajectories to 1e-9."""
    from mechatron.library import blocks
    from mechatron.library import electrical as el
    from mechatron.models.bldc import GateDriver, InverterLeg

    fet = dict(R_on=0.02, G_off=1e-4, V_f=0.7, R_d=0.02)

    def rig(flat):
        m = mt.System("leg_rig")
        rail = m.add("rail", el.DCVoltageSource(V=24.0))
        gnd = m.add("gnd", el.ElectricalReference())
        load_r = m.add("load_r", el.Resistor(R=2.0))
        load_l = m.add("load_l", el.Inductor(L=1e-3, i=0.0))
        on = m.add("on", blocks.Step(t_step=1e-3, initial=0.0, final=1.0))
        off = m.add("off", blocks.Constant(value=0.0))
        m.connect(rail.n, gnd.port, load_l.n)
        if flat:
            high = m.add("high", el.NMOSFET(**fet))
            low = m.add("low", el.NMOSFET(**fet))
            dh = m.add("dh", GateDriver(V_g=10.0))
            dl = m.add("dl", GateDriver(V_g=10.0))
            m.connect(rail.p, high.p)
            m.connect(high.n, low.p, dh.n, load_r.p)
            m.connect(low.n, rail.n, dl.n)
            m.connect(dh.p, high.gate)
            m.connect(dl.p, low.gate)
            m.connect(on.y, dh.cmd)
            m.connect(off.y, dl.cmd)
        else:
            leg = m.add("leg", InverterLeg(V_g=10.0, **fet))
            m.connect(rail.p, leg.dc_p)
            m.connect(leg.dc_n, rail.n)
            m.connect(leg.out, load_r.p)
            m.connect(on.y, leg.cmd_h)
            m.connect(off.y, leg.cmd_l)
        m.connect(load_r.n, load_l.p)
        return m

    t = np.linspace(0, 4e-3, 81)
    sub = mt.simulate(rig(False), 4e-3, t_out=t, rtol=1e-10, atol=1e-12)
    flat = mt.simulate(rig(True), 4e-3, t_out=t, rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(sub["load_l.i"], flat["load_l.i"], atol=1e-9)
    np.testing.assert_allclose(sub["leg.high.i"], flat["high.i"], atol=1e-9)
    # after the switch-on the load current approaches (24 - drop) / (2 + R_on)
    assert sub["load_l.i"][-1] == pytest.approx(24.0 / 2.02 * (1 - np.exp(-3e-3 * 2.02 / 1e-3)),
                                                rel=1e-3)


class SeedWinding(mt.Component):
    """The drive's winding as the seed wrote it before the library had a PMSM (test-local,
    written from the seed's equations): star winding with trapezoidal back EMF, one pole
    pair, the rotor angle its own state; rotor at A, stator at B."""

    A = rot_if.Flange(doc="Rotor")
    B = rot_if.Flange(doc="Stator")
    a = el_if.Pin(doc="Phase a")
    b = el_if.Pin(doc="Phase b")
    c = el_if.Pin(doc="Phase c")
    R = mt.Parameter("Ohm", default=0.5, doc="Phase resistance")
    L = mt.Parameter("H", default=1e-3, doc="Phase inductance")
    k_e = mt.Parameter("V*s/rad", default=0.05, doc="Back-EMF constant per phase")
    i_a = mt.Variable("A", start=0.0, doc="Phase a current")
    i_b = mt.Variable("A", start=0.0, doc="Phase b current")
    theta = mt.Variable("rad", start=0.0, doc="Rotor angle")
    T = mt.Variable("N*m", doc="Torque on the rotor")

    def equations(self):
        w = self.A.w - self.B.w
        th = [self.theta, self.theta - 2 * math.pi / 3, self.theta + 2 * math.pi / 3]
        i = [self.i_a, self.i_b, -(self.i_a + self.i_b)]
        v = [self.a.v, self.b.v, self.c.v]
        e = [self.k_e * w * trapezoid(x) for x in th]
        v_n = (sum(v) - sum(e)) / 3
        return [mt.der(self.theta) == w,
                self.a.i == i[0], self.b.i == i[1], self.c.i == i[2],
                self.L * mt.der(self.i_a) == v[0] - v_n - self.R * i[0] - e[0],
                self.L * mt.der(self.i_b) == v[1] - v_n - self.R * i[1] - e[1],
                self.T == self.k_e * sum(f * j for f, j in zip(map(trapezoid, th), i)),
                self.A.tau == -self.T, self.B.tau == self.T]


def todays_drive():
    """The acausal drive as it was built before it used the library's PMSM: the seed
    winding, a rotor inertia and a friction damper wired at the top."""
    from mechatron.library import blocks
    from mechatron.library import electrical as el
    from mechatron.library import rotational as rot
    from mechatron.models.bldc import (DutyScaledSource, HallSensors, InverterLeg,
                                       SixStepCommutation, SpeedPI)
    m = mt.System("bldc_motor")
    ground = m.add("ground", el.ElectricalReference())
    supply = m.add("supply", DutyScaledSource(V_dc=P["V_dc"]))
    full_on = m.add("pwm_on", blocks.Constant(value=1.0))
    commutation = m.add("commutation", SixStepCommutation())
    controller = m.add("controller", SpeedPI(w_ref=P["w_ref"], K_p=P["K_p"], K_i=P["K_i"],
                                             K_aw=P["K_aw"], d_max=P["d_max"]))
    winding = m.add("winding", SeedWinding(R=P["R"], L=P["L"], k_e=P["k_e"]))
    hall = m.add("hall", HallSensors())
    rotor = m.add("rotor", rot.Inertia(J=P["J"], w=mt.Start(0.0, "low")))
    friction = m.add("friction", rot.RotationalDamper(D=P["B"]))
    load = m.add("load", rot.ConstantTorque(T=-P["T_load"]))
    tacho = m.add("tacho", rot.AngularVelocitySensor())
    housing = m.add("housing", rot.RotationalReference())
    m.connect(supply.n, ground.port)
    for k in PHASES:
        leg = m.add(f"leg_{k}", InverterLeg(R_on=P["R_on"], G_off=P["G_off"],
                                            V_f=P["V_f"], R_d=P["R_d"]))
        m.connect(supply.p, leg.dc_p)
        m.connect(leg.dc_n, supply.n)
        m.connect(leg.out, getattr(winding, k))
        m.connect(getattr(commutation, f"g_{k}h"), leg.cmd_h)
        m.connect(getattr(commutation, f"g_{k}l"), leg.cmd_l)
    m.connect(winding.A, rotor.port, friction.A, load.A, hall.A, tacho.A)
    m.connect(winding.B, friction.B, load.B, hall.B, tacho.B, housing.port)
    m.connect(hall.sector, commutation.sector)
    m.connect(tacho.W, controller.w)
    m.connect(controller.d, supply.d)
    m.connect(full_on.y, commutation.pwm)
    return m


def test_the_drive_on_the_library_pmsm_equals_todays_drive(run):
    """Rebuilt on ``PMSM(emf="trapezoidal")`` the drive has the same equations as the
    seed's wiring; the two runs differ only by the integrator's path (state order, step
    sequence through the ~100 commutation events), so they agree to the integration
    error: 1e-6 of each signal's range at rtol = 1e-8 (two orders for the error that
    accumulates over 0.2 s and the event times located to the tolerance)."""
    ref = mt.simulate(todays_drive(), T_STOP, rtol=1e-8, atol=1e-10, t_out=run.t)
    pairs = {"motor.inertia.w": "rotor.w", "motor.airgap.phi": "winding.theta",
             "motor.airgap.i_a": "winding.i_a", "motor.airgap.i_b": "winding.i_b",
             "motor.airgap.T": "winding.T", "controller.d": "controller.d"}
    for new, old in pairs.items():
        scale = np.ptp(ref[old])
        np.testing.assert_allclose(run[new], ref[old], rtol=0, atol=1e-6 * scale,
                                   err_msg=new)
    # the sector signal is piecewise constant: equal except within the event-time error
    # of an edge (one output sample at most per edge)
    differ = run["hall.sector"] != ref["hall.sector"]
    assert differ.sum() <= 2


def test_the_inputs_variant_closed_by_the_speed_controller_is_the_drive():
    """The ``inputs`` variant (no controller; duty cycle and load torque in) used as a
    part, its duty driven by the module's SpeedPI reading its tachometer and its load by
    the constant torque: the closed-loop ``acausal`` drive to 1e-9 (rtol 1e-12)."""
    from mechatron.library import blocks
    from mechatron.models.bldc import SpeedPI
    cm = mt.compile_model(ENTRY.build("inputs"))
    assert cm.input_names == ["d", "T_load"]
    m = mt.System("closed_loop")
    plant = m.add("plant", ENTRY.build("inputs"))
    pi = m.add("controller", SpeedPI(w_ref=P["w_ref"], K_p=P["K_p"], K_i=P["K_i"],
                                     K_aw=P["K_aw"], d_max=P["d_max"]))
    load = m.add("torque", blocks.Constant(value=P["T_load"]))
    m.connect(plant.tacho.W, pi.w)
    m.connect(pi.d, plant.d)
    m.connect(load.y, plant.T_load)
    t = np.linspace(0.0, 0.05, 101)
    kw = dict(t_out=t, rtol=1e-12, atol=1e-13)
    ref = mt.simulate(ENTRY.build("acausal"), 0.05, **kw)
    res = mt.simulate(m, 0.05, **kw)
    for label, path in ENTRY.output_paths("acausal").items():
        got = res["controller.d" if label == "d" else f"plant.{path}"]
        np.testing.assert_allclose(got, ref[path], rtol=0,
                                   atol=1e-9 * max(1.0, np.abs(ref[path]).max()))


def test_the_inputs_variant_open_loop_reaches_the_dc_motor_speed():
    """Open loop with a constant duty d and load T: with 120-degree conduction the drive
    is a DC motor of constant 2 k_e and resistance 2 R (plus two switch resistances) fed
    with d V_dc, so w = (2 k_e d V_dc - 2 R_t T) / (2 R_t B + (2 k_e)^2), R_t = R + R_on,
    up to the commutation ripple (the back EMF leaves its flat top around commutations)."""
    d, T = 0.5, 0.02
    res = mt.simulate(ENTRY.build("inputs"), 0.3, rtol=1e-8, atol=1e-10,
                      inputs={"d": d, "T_load": T}, t_out=np.linspace(0.2, 0.3, 2001))
    k_t, R_t = 2 * P["k_e"], 2 * (P["R"] + P["R_on"])
    w_dc = (k_t * d * P["V_dc"] - R_t * T) / (R_t * P["B"] + k_t ** 2)
    assert np.mean(res["motor.inertia.w"]) == pytest.approx(w_dc, rel=5e-3)
