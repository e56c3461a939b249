"""MSL-named translational parts: SpringDamper with a natural length against the damped
oscillator's exact solution; ElastoGap (contact only while compressed, a force that never
pulls) against the undamped impact's exact answer and a hand-written SciPy model of the
limited contact law, with the energy balance."""

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import mechatron as mt
from mechatron.library import translational as tr


def test_spring_damper_with_a_natural_length():
    m_, c, d, s0, L = 2.0, 800.0, 4.0, 0.1, 0.13
    m = mt.System("sd")
    sd = m.add("sd", tr.SpringDamper(c=c, d=d, s_rel0=s0, s_rel=L))
    mass = m.add("mass", tr.Mass(m=m_))
    g = m.add("g", tr.TranslationalReference())
    m.connect(sd.A, g.port)
    m.connect(sd.B, mass.port)
    t = np.linspace(0, 1.0, 2001)
    res = mt.simulate(m, 1.0, t_out=t, rtol=1e-11, atol=1e-13)
    # m x'' + d x' + c x = 0, x = s_rel - s_rel0 (the mass is at B), x(0) = L - s0
    a, wd = d / (2 * m_), np.sqrt(c / m_ - (d / (2 * m_)) ** 2)
    x0 = L - s0
    x = x0 * np.exp(-a * t) * (np.cos(wd * t) + a / wd * np.sin(wd * t))
    np.testing.assert_allclose(res["sd.s_rel"], s0 + x, atol=1e-9)
    np.testing.assert_allclose(res["mass.v"], -x0 * (a ** 2 + wd ** 2) / wd
                               * np.exp(-a * t) * np.sin(wd * t), atol=1e-8)
    # stretched at t = 0: the mass at B is pulled back towards A
    assert res["sd.f"][0] == pytest.approx(-c * x0, rel=1e-12)


def gap_model(c, d, s0, L, m_, v0):
    """A mass at A moving at v0 towards the ground at B, a distance L away; contact at
    s_rel0."""
    m = mt.System("gap")
    gap = m.add("gap", tr.ElastoGap(c=c, d=d, s_rel0=s0, s_rel=L))
    mass = m.add("mass", tr.Mass(m=m_, v=v0))
    g = m.add("g", tr.TranslationalReference())
    m.connect(gap.A, mass.port)
    m.connect(gap.B, g.port)
    return m


def test_elasto_gap_undamped_impact():
    m_, c, s0, L, v0 = 0.5, 2e4, 0.01, 0.03, 1.5
    t_hit = (L - s0) / v0
    half = np.pi * np.sqrt(m_ / c)
    t = np.array([0.0, 0.5 * t_hit, t_hit + 0.5 * half, t_hit + half + 0.01])
    res = mt.simulate(gap_model(c, 0.0, s0, L, m_, v0), t[-1], t_out=t, rtol=1e-11,
                      atol=1e-13)
    assert res["gap.contact"][1] == 0.0 and res["gap.f"][1] == 0.0
    assert res["gap.s_rel"][2] == pytest.approx(s0 - v0 * np.sqrt(m_ / c), rel=1e-7)
    assert res["gap.contact"][2] == 1.0
    assert res["mass.v"][3] == pytest.approx(-v0, rel=1e-7)
    assert res["gap.s_rel"][3] == pytest.approx(s0 + 0.01 * v0, rel=1e-6)
    assert res.stats.events["gap"] == 2


@pytest.mark.parametrize("d", [20.0, 300.0, 5e3])
def test_elasto_gap_matches_the_scipy_model_and_never_pulls(d):
    m_, c, s0, L, v0 = 0.5, 2e4, 0.01, 0.03, 1.5

    def force(s, v):                                  # f on the component at A
        delta = s0 - s
        if delta <= 0:
            return 0.0
        el = c * delta
        return el + min(max(d * v, -el), el)

    def rhs(t, y):                                    # y = (s_rel, v_mass)
        return [-y[1], -force(y[0], y[1]) / m_]

    t = np.linspace(0, 0.05, 501)
    ref = solve_ivp(rhs, (0, t[-1]), [L, v0], t_eval=t, rtol=1e-12, atol=1e-14,
                    method="DOP853", max_step=1e-4)
    res = mt.simulate(gap_model(c, d, s0, L, m_, v0), t[-1], t_out=t, rtol=1e-11,
                      atol=1e-13)
    np.testing.assert_allclose(res["gap.s_rel"], ref.y[0], atol=1e-9)
    np.testing.assert_allclose(res["mass.v"], ref.y[1], atol=1e-6)
    assert np.all(res["gap.f"] >= -1e-12)                        # never pulls
    assert np.all(res["gap.f"][res["gap.s_rel"] > s0] == 0.0)     # only in contact
    # energy: what the mass lost is what the contact dissipated plus what it stores
    te = np.linspace(0, t[-1], 50001)
    fine = mt.simulate(gap_model(c, d, s0, L, m_, v0), t[-1], t_out=te, rtol=1e-11,
                       atol=1e-13)
    p_abs = fine["gap.f"] * fine["gap.v"]
    absorbed = np.trapezoid(p_abs, te)
    stored = 0.5 * c * max(s0 - fine["gap.s_rel"][-1], 0.0) ** 2
    ke = 0.5 * m_ * fine["mass.v"] ** 2
    assert ke[0] - ke[-1] == pytest.approx(absorbed, rel=1e-5)
    assert absorbed >= stored - 1e-12
