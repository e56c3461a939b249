"""MSL-named rotational parts: SpringDamper against the damped oscillator's exact solution
and its energy balance; ElastoBacklash against a hand-written SciPy model of the same
limited contact law (and, undamped, against the free flight plus half a spring period);
IdealPlanetary against Willis' relation and conservation of power."""

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import mechatron as mt
from mechatron.library import rotational as rot


def inertia_on(part, J, w0=0.0):
    """``part`` between the ground (A) and an inertia (B)."""
    m = mt.System("one")
    m.add("x", part)
    inertia = m.add("j", rot.Inertia(J=J, w=w0))
    g = m.add("g", rot.RotationalReference())
    m.connect(part.A, g.port)
    m.connect(part.B, inertia.port)
    return m


def test_spring_damper_is_the_damped_oscillator_and_conserves_energy():
    J, c, d, phi0 = 0.02, 50.0, 0.1, 0.3
    m = inertia_on(rot.SpringDamper(c=c, d=d, phi_rel0=phi0), J)
    t = np.linspace(0, 2.0, 4001)
    res = mt.simulate(m, 2.0, t_out=t, rtol=1e-11, atol=1e-13)
    # J x'' + d x' + c x = 0 with x = phi_rel - phi_rel0, x(0) = -phi0, x'(0) = 0
    zeta_w, wd = d / (2 * J), np.sqrt(c / J - (d / (2 * J)) ** 2)
    x = -phi0 * np.exp(-zeta_w * t) * (np.cos(wd * t) + zeta_w / wd * np.sin(wd * t))
    np.testing.assert_allclose(res["x.phi_rel"], phi0 + x, atol=1e-8)
    # phi_rel is B relative to A: the inertia's speed
    xd = phi0 * (zeta_w ** 2 + wd ** 2) / wd * np.exp(-zeta_w * t) * np.sin(wd * t)
    np.testing.assert_allclose(res["j.w"], xd, atol=1e-7)
    stored = 0.5 * J * res["j.w"] ** 2 + 0.5 * c * (res["x.phi_rel"] - phi0) ** 2
    lost = np.concatenate([[0.0], np.cumsum(np.diff(t) * 0.5 * (res["x.P_loss"][1:]
                                                                   + res["x.P_loss"][:-1]))])
    np.testing.assert_allclose(stored + lost, 0.5 * c * phi0 ** 2, rtol=1e-5)


def backlash_reference(J, c, d, b, phi_rel0, w0, t_eval):
    """Hand-written model: J phi'' = -tau_msl(phi, phi') for the inertia at B (A fixed),
    tau_msl the limited contact law."""
    def tau_msl(phi, w):
        x = phi - phi_rel0
        if x > b / 2:
            el = c * (x - b / 2)
            return el + min(max(d * w, -el), el)
        if x < -b / 2:
            el = c * (-b / 2 - x)
            return -(el + min(max(-d * w, -el), el))
        return 0.0

    def rhs(t, y):
        return [y[1], -tau_msl(y[0], y[1]) / J]

    # the law is continuous (zero at first contact), so DOP853's error control steps
    # through its kinks without events
    sol = solve_ivp(rhs, (0.0, t_eval[-1]), [0.0, w0], t_eval=t_eval, rtol=1e-12,
                    atol=1e-14, method="DOP853", max_step=1e-4)
    return sol.y


@pytest.mark.parametrize("d", [0.0, 5.0, 200.0])
def test_elasto_backlash_matches_the_scipy_model(d):
    J, c, b, phi0, w0 = 1e-3, 1e3, 0.02, 0.005, 2.0
    part = rot.ElastoBacklash(b=b, c=c, d=d, phi_rel0=phi0)
    t_stop = 0.08
    t = np.linspace(0, t_stop, 801)
    res = mt.simulate(inertia_on(part, J, w0), t_stop, t_out=t, rtol=1e-11, atol=1e-13)
    yr = backlash_reference(J, c, d, b, phi0, w0, t)
    np.testing.assert_allclose(res["x.phi_rel"], yr[0], atol=1e-8)
    np.testing.assert_allclose(res["j.w"], yr[1], atol=1e-6)
    # the contact torque never pulls: on the upper side tau_msl >= 0, on the lower <= 0
    x = res["x.phi_rel"] - phi0
    tau_msl = -res["x.tau"]
    assert np.all(tau_msl[x > b / 2] >= -1e-9) and np.all(tau_msl[x < -b / 2] <= 1e-9)
    assert np.all(tau_msl[np.abs(x) < b / 2 - 1e-9] == 0.0)


def test_elasto_backlash_undamped_rebound():
    """Undamped: free flight over the gap, half a period sqrt(J/c) pi in contact, back at
    -w0 (an elastic impact)."""
    J, c, b, w0 = 1e-3, 1e3, 0.02, 2.0
    t_hit = (b / 2) / w0
    t_back = t_hit + np.pi * np.sqrt(J / c)
    t = np.array([0.0, 0.5 * t_hit, t_hit + 0.5 * np.pi * np.sqrt(J / c), t_back + 1e-3])
    res = mt.simulate(inertia_on(rot.ElastoBacklash(b=b, c=c), J, w0), t[-1], t_out=t,
                      rtol=1e-11, atol=1e-13)
    assert res["x.phi_rel"][1] == pytest.approx(0.5 * t_hit * w0, rel=1e-9)
    # deepest penetration w0 sqrt(J/c), at rest
    assert res["x.phi_rel"][2] == pytest.approx(b / 2 + w0 * np.sqrt(J / c), rel=1e-7)
    assert res["j.w"][2] == pytest.approx(0.0, abs=1e-6)
    assert res["j.w"][3] == pytest.approx(-w0, rel=1e-7)
    assert res["x.phi_rel"][3] == pytest.approx(b / 2 - 1e-3 * w0, rel=1e-6)


def test_elasto_backlash_vs_the_unlimited_penalty_law():
    """With heavy damping the old ``max(c delta + d rate, 0)`` law (RotationalBacklash)
    already pushes at first contact (d w0 at zero penetration); the limited law starts
    from zero, so the peak contact torques differ."""
    J, c, d, b, w0 = 1e-3, 1e3, 5.0, 0.02, 2.0
    t_hit = (b / 2) / w0
    t = np.array([0.0, t_hit + 1e-7])
    new = mt.simulate(inertia_on(rot.ElastoBacklash(b=b, c=c, d=d), J, w0), t[-1],
                      t_out=t, rtol=1e-11, atol=1e-13)
    # just after contact: elastic c delta ~ c w0 1e-7, the damping limited to the same
    assert abs(new["x.tau"][-1]) <= 2 * c * w0 * 1e-7 * 1.01


def test_ideal_planetary_ring_held():
    """Ring grounded, torque T on the sun (inertia Js), carrier inertia Jc: w_s = (1 + r)
    w_c and by power, w_c(t) = (1 + r) T t / (Js (1 + r)^2 + Jc)."""
    r, T, Js, Jc = 2.5, 0.4, 1e-3, 2e-2
    m = mt.System("pg")
    pg = m.add("pg", rot.IdealPlanetary(ratio=r))
    sun = m.add("sun", rot.Inertia(J=Js))
    car = m.add("car", rot.Inertia(J=Jc))
    drive = m.add("drive", rot.ConstantTorque(T=T))
    g = m.add("g", rot.RotationalReference())
    m.connect(pg.sun, sun.port, drive.A)
    m.connect(pg.carrier, car.port)
    m.connect(pg.ring, g.port, drive.B)
    t = np.linspace(0, 1, 11)
    res = mt.simulate(m, 1.0, t_out=t, rtol=1e-10, atol=1e-12)
    wc = (1 + r) * T * t / (Js * (1 + r) ** 2 + Jc)
    np.testing.assert_allclose(res["car.w"], wc, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(res["sun.w"], (1 + r) * wc, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(res["pg.ring.tau"], r * res["pg.sun.tau"], rtol=1e-12)


def test_ideal_planetary_all_free_conserves_energy():
    r, T = 3.0, 0.2
    m = mt.System("pg3")
    pg = m.add("pg", rot.IdealPlanetary(ratio=r))
    sun = m.add("sun", rot.Inertia(J=1e-3))
    car = m.add("car", rot.Inertia(J=5e-3))
    ring = m.add("ring", rot.Inertia(J=2e-2, w=-1.0))
    drive = m.add("drive", rot.ConstantTorque(T=T))
    g = m.add("g", rot.RotationalReference())
    m.connect(pg.sun, sun.port, drive.A)
    m.connect(pg.carrier, car.port)
    m.connect(pg.ring, ring.port)
    m.connect(drive.B, g.port)
    t = np.linspace(0, 0.5, 5001)
    res = mt.simulate(m, 0.5, t_out=t, rtol=1e-11, atol=1e-13)
    np.testing.assert_allclose((1 + r) * res["car.w"], res["sun.w"] + r * res["ring.w"],
                               atol=1e-10)
    ke = 0.5 * (1e-3 * res["sun.w"] ** 2 + 5e-3 * res["car.w"] ** 2
                + 2e-2 * res["ring.w"] ** 2)
    work = np.concatenate([[0.0], np.cumsum(np.diff(t) * 0.5 * T * (res["sun.w"][1:]
                                                                     + res["sun.w"][:-1]))])
    np.testing.assert_allclose(ke - ke[0], work, atol=1e-7)
