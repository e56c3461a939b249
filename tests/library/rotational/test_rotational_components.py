"""Rotational components against analytic answers: hard stop, backlash, clutch, gears
with efficiency, fan load, sources and sensors."""

import numpy as np
import pytest

import mechatron as mt
from mechatron.library import blocks
from mechatron.library import rotational as rot

TOL = dict(rtol=1e-10, atol=1e-12)


def grounded(name):
    m = mt.System(name)
    g = m.add("g", rot.RotationalReference())
    return m, g


# ----------------------------------------------------------------------------- hard stop
@pytest.mark.parametrize("T", [5.0, -3.0])
def test_hard_stop_penetration_at_rest_is_T_over_k(T):
    k, upper, lower = 1e4, 0.1, -0.2
    m, g = grounded("stop")
    j = m.add("j", rot.Inertia(J=0.01))
    src = m.add("src", rot.ConstantTorque(T=T))
    hs = m.add("hs", rot.RotationalHardStop(upper=upper, lower=lower, k=k, d=5.0))
    m.connect(src.A, j.port, hs.A)
    m.connect(src.B, hs.B, g.port)
    res = mt.simulate(m, 3.0, **TOL)
    bound = upper if T > 0 else lower
    assert res.final("hs.phi") == pytest.approx(bound + T / k, abs=1e-9)
    assert res.final("j.w") == pytest.approx(0.0, abs=1e-8)
    assert res.stats.events["hs"] >= 2          # contact is located as events
    # one-sided: the upper stop only pushes (tau >= 0), the lower one only pulls back
    assert (np.sign(T) * res["hs.tau"] >= -1e-9).all()


def test_hard_stop_never_pulls_on_a_bounce():
    """A fast impact with little damping rebounds between the stops: the contact torque
    only pushes back into the band (>= 0 at the upper stop, <= 0 at the lower) and is zero
    whenever phi is inside the band."""
    m, g = grounded("bounce")
    j = m.add("j", rot.Inertia(J=0.01, w=10.0))
    hs = m.add("hs", rot.RotationalHardStop(upper=0.1, lower=-0.1, k=1e4, d=2.0))
    m.connect(j.port, hs.A)
    m.connect(hs.B, g.port)
    res = mt.simulate(m, 0.05, t_out=np.linspace(0, 0.05, 5001), **TOL)
    inside = (res["hs.phi"] < 0.1 - 1e-9) & (res["hs.phi"] > -0.1 + 1e-9)
    assert np.abs(res["hs.tau"][inside]).max() < 1e-9
    upper = res["hs.phi"] > 0
    assert (res["hs.tau"][upper] >= -1e-9).all() and (res["hs.tau"][~upper] <= 1e-9).all()
    assert res["hs.tau"].max() > 10 and res["hs.tau"].min() < -10   # both stops hit
    # each rebound loses energy to the damper, never gains
    assert 0 < abs(res.final("j.w")) < 10.0


# ------------------------------------------------------------------------------ backlash
def test_backlash_dead_band_then_drive_with_penetration_D_w0_over_k():
    """A velocity source turns A at w0 from the centre of a band b: B (an inertia with a
    damper) stays still until t = b/(2 w0), then follows at w0 with the damper torque
    D w0 carried by a tooth penetration D w0 / k."""
    b, w0, k, D = 0.02, 2.0, 1e5, 0.5
    m, g = grounded("backlash")
    c = m.add("c", blocks.Constant(value=w0))
    vs = m.add("vs", rot.IdealAngularVelocitySource())
    bl = m.add("bl", rot.RotationalBacklash(b=b, k=k, d=20.0))
    j = m.add("j", rot.Inertia(J=1e-3))
    dmp = m.add("dmp", rot.RotationalDamper(D=D))
    m.connect(c.y, vs.w_ref)
    m.connect(vs.A, bl.A)
    m.connect(bl.B, j.port, dmp.A)
    m.connect(vs.B, dmp.B, g.port)
    t_contact = b / (2 * w0)
    t = np.union1d(np.linspace(0, 1.0, 2001), [t_contact - 1e-6, t_contact + 1e-4])
    res = mt.simulate(m, 1.0, t_out=t, **TOL)
    before = t <= t_contact - 1e-6
    assert np.abs(res["j.w"][before]).max() < 1e-12
    assert np.abs(res["bl.tau"][before]).max() < 1e-12
    assert res["bl.tau"][np.searchsorted(t, t_contact + 1e-4)] > 0   # engaged right after
    assert res.final("j.w") == pytest.approx(w0, rel=1e-8)
    assert res.final("bl.phi") == pytest.approx(b / 2 + D * w0 / k, rel=1e-7)


# ---------------------------------------------------------------------------------- clutch
def clutch_model(fn, drive):
    m, g = grounded("clutch")
    f = m.add("fn", blocks.Constant(value=fn))
    cl = m.add("cl", rot.FrictionClutch(mu_k=0.3, mu_s=0.4, R=0.1, n=2, w_tol=1e-3))
    m.connect(f.y, cl.f_n)
    m.connect(cl.B, g.port)
    return m, g, cl, drive(m, g, cl)


def test_clutch_slip_torque_is_n_R_mu_k_fn():
    fn, w_slip = 200.0, 5.0

    def drive(m, g, cl):
        c = m.add("c", blocks.Constant(value=w_slip))
        vs = m.add("vs", rot.IdealAngularVelocitySource())
        m.connect(c.y, vs.w_ref)
        m.connect(vs.A, cl.A)
        m.connect(vs.B, g.port)

    m, *_ = clutch_model(fn, drive)
    res = mt.simulate(m, 0.1, **TOL)
    assert res.final("cl.tau") == pytest.approx(2 * 0.1 * 0.3 * fn, rel=1e-12)
    # the source delivers exactly the dissipated power
    assert res.final("cl.tau") * res.final("cl.w") > 0


@pytest.mark.parametrize("T", [10.0, 20.0])
def test_clutch_sticks_below_static_capacity_and_slips_above(T):
    """Capacity n R mu_s fn = 16 N*m: 10 N*m is carried with a slip below a few w_tol
    (sticking); 20 N*m accelerates the inertia at (T - n R mu_k fn)/J."""
    fn, J = 200.0, 0.05

    def drive(m, g, cl):
        c = m.add("c", blocks.Constant(value=T))
        src = m.add("src", rot.IdealTorqueSource())
        j = m.add("j", rot.Inertia(J=J))
        m.connect(c.y, src.tau_in)
        m.connect(src.A, j.port, cl.A)
        m.connect(src.B, g.port)

    m, *_ = clutch_model(fn, drive)
    res = mt.simulate(m, 1.0, t_out=np.linspace(0, 1.0, 101), **TOL)
    if T < 2 * 0.1 * 0.4 * fn:
        assert abs(res.final("j.w")) < 1e-3                     # w_tol atanh(10/16) ~ 0.7e-3
        assert res.final("cl.tau") == pytest.approx(T, rel=1e-8)
    else:
        accel = (T - 2 * 0.1 * 0.3 * fn) / J
        slope = (res["j.w"][-1] - res["j.w"][50]) / 0.5
        assert slope == pytest.approx(accel, rel=1e-9)


# ----------------------------------------------------------------------------------- gears
def gear_drive(forward, ratio=3.0, eta=0.8, T=2.0, D=0.1):
    """Torque T drives one side of a LossyGear (support grounded), a damper D loads the
    other; inertias on both sides."""
    m, g = grounded("gear")
    c = m.add("c", blocks.Constant(value=T))
    src = m.add("src", rot.IdealTorqueSource())
    gear = m.add("gear", rot.LossyGear(ratio=ratio, eta=eta))
    ja = m.add("ja", rot.Inertia(J=1e-3))
    jb = m.add("jb", rot.Inertia(J=1e-2))
    dmp = m.add("dmp", rot.RotationalDamper(D=D))
    m.connect(c.y, src.tau_in)
    drive, load = (ja, jb) if forward else (jb, ja)
    m.connect(src.A, drive.port, gear.A if forward else gear.B)
    m.connect(dmp.A, load.port, gear.B if forward else gear.A)
    m.connect(src.B, dmp.B, gear.S, g.port)
    return m


def test_lossy_gear_forward_power_flow_loses_1_minus_eta():
    ratio, eta, T, D = 3.0, 0.8, 2.0, 0.1
    res = mt.simulate(gear_drive(True, ratio, eta, T, D), 20.0, **TOL)
    w_b = eta * ratio * T / D
    assert res.final("jb.w") == pytest.approx(w_b, rel=1e-8)
    assert res.final("ja.w") == pytest.approx(ratio * w_b, rel=1e-8)
    p_in = T * res.final("ja.w")
    assert res.final("gear.P_loss") == pytest.approx((1 - eta) * p_in, rel=1e-8)
    assert res.final("gear.S.tau") == pytest.approx(-(T - eta * ratio * T), rel=1e-8)


def test_lossy_gear_backward_power_flow_divides_by_eta():
    """Driving B: the torque reaching A is eta T / ratio (not T / (eta ratio))."""
    ratio, eta, T, D = 3.0, 0.8, 2.0, 0.1
    res = mt.simulate(gear_drive(False, ratio, eta, T, D), 5.0, **TOL)
    w_a = eta * T / (ratio * D)
    assert res.final("ja.w") == pytest.approx(w_a, rel=1e-8)
    assert res.final("jb.w") == pytest.approx(w_a / ratio, rel=1e-8)
    p_in = T * res.final("jb.w")
    assert res.final("gear.P_loss") == pytest.approx((1 - eta) * p_in, rel=1e-8)


def test_simple_gear_reverses_direction_with_teeth_ratio_and_efficiency():
    n_a, n_b, eta, T, D = 20, 50, 0.9, 1.0, 0.2
    m, g = grounded("simple")
    c = m.add("c", blocks.Constant(value=T))
    src = m.add("src", rot.IdealTorqueSource())
    gear = m.add("gear", rot.SimpleGear(N_A=n_a, N_B=n_b, eta=eta))
    ja = m.add("ja", rot.Inertia(J=1e-3))
    jb = m.add("jb", rot.Inertia(J=1e-2))
    dmp = m.add("dmp", rot.RotationalDamper(D=D))
    m.connect(c.y, src.tau_in)
    m.connect(src.A, ja.port, gear.A)
    m.connect(gear.B, jb.port, dmp.A)
    m.connect(src.B, dmp.B, g.port)
    res = mt.simulate(m, 10.0, **TOL)
    # output torque eta (N_B/N_A) T, opposite direction
    w_b = -eta * (n_b / n_a) * T / D
    assert res.final("jb.w") == pytest.approx(w_b, rel=1e-8)
    assert res.final("ja.w") == pytest.approx(-n_b / n_a * w_b, rel=1e-8)
    assert res.final("gear.P_loss") == pytest.approx((1 - eta) * T * res.final("ja.w"),
                                                     rel=1e-8)


# -------------------------------------------------------------------------------- fan load
def test_fan_load_coast_down_follows_w0_over_1_plus_c_w0_t_over_J():
    J, w0, T_nom, w_nom = 0.02, 150.0, 0.5, 100.0
    m, g = grounded("fan")
    j = m.add("j", rot.Inertia(J=J, w=w0))
    fan = m.add("fan", rot.FanLoad(T_nom=T_nom, w_nom=w_nom))
    m.connect(j.port, fan.A)
    m.connect(fan.B, g.port)
    t = np.linspace(0, 2.0, 41)
    res = mt.simulate(m, 2.0, t_out=t, **TOL)
    c = T_nom / w_nom ** 2
    np.testing.assert_allclose(res["j.w"], w0 / (1 + c * w0 * t / J), rtol=1e-8)


# ----------------------------------------------------------------------- sources, sensors
def test_velocity_source_imposes_w_and_torque_is_J_dw_dt():
    J, amp, f = 0.3, 2.0, 1.5
    m, g = grounded("vsrc")
    s = m.add("s", blocks.Sine(amplitude=amp, f=f))
    vs = m.add("vs", rot.IdealAngularVelocitySource())
    ts = m.add("ts", rot.TorqueSensor())
    j = m.add("j", rot.Inertia(J=J))
    m.connect(s.y, vs.w_ref)
    m.connect(vs.A, ts.A)
    m.connect(ts.B, j.port)
    m.connect(vs.B, g.port)
    t = np.linspace(0, 1.0, 51)
    res = mt.simulate(m, 1.0, t_out=t, **TOL)
    om = 2 * np.pi * f
    np.testing.assert_allclose(res["j.w"], amp * np.sin(om * t), atol=1e-10)
    # the sensor passes the torque that accelerates the inertia
    np.testing.assert_allclose(res["ts.T"], J * amp * om * np.cos(om * t), atol=1e-8)
    np.testing.assert_allclose(res["vs.phi"], amp / om * (1 - np.cos(om * t)), atol=1e-8)


def test_angle_source_imposes_phi_and_sensors_read_it():
    J, amp, f = 0.1, 0.5, 2.0
    m, g = grounded("asrc")
    s = m.add("s", blocks.Sine(amplitude=amp, f=f))
    src = m.add("src", rot.IdealAngleSource())
    ps = m.add("ps", rot.PowerSensor())
    j = m.add("j", rot.Inertia(J=J))
    ang = m.add("ang", rot.AngleSensor())
    m.connect(s.y, src.phi_ref)
    m.connect(src.A, ps.A)
    m.connect(ps.B, j.port, ang.A)
    m.connect(src.B, ang.B, g.port)
    t = np.linspace(0, 1.0, 51)
    res = mt.simulate(m, 1.0, t_out=t, **TOL)
    om = 2 * np.pi * f
    np.testing.assert_allclose(res["ang.Phi"], amp * np.sin(om * t), atol=1e-8)
    w = amp * om * np.cos(om * t)
    np.testing.assert_allclose(res["j.w"], w, atol=1e-8)
    tau = -J * amp * om ** 2 * np.sin(om * t)
    np.testing.assert_allclose(res["ps.T"], tau, atol=1e-7)
    np.testing.assert_allclose(res["ps.P"], tau * w, atol=1e-7)   # d/dt (J w^2 / 2)
