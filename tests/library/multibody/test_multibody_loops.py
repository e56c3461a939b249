"""Closed kinematic loops: a torque-driven four-bar against its reduced one-degree-of-
freedom ODE (SciPy), loop closure, an energy balance; a slider-crank against its
closed-form kinematics; a singular start reported at compile time."""

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import mechatron as mt
from mechatron.errors import ModelError, StructuralError
from mechatron.library.multibody import mechanisms as mech
from mechatron.library.multibody.reference import FourBarGeometry, four_bar_rhs

A, B, C, D = 0.2, 0.6, 0.5, 0.6
THETA0 = math.pi / 3


def closure(res, a=A, b=B, c=C, d=D):
    """Distance between the end of the chain (forward kinematics from the joint angles)
    and the ground pivot D."""
    q1, q2, q3 = res["j1.q"], res["j2.q"], res["j3.q"]
    x = a * np.cos(q1) + b * np.cos(q1 + q2) + c * np.cos(q1 + q2 + q3) - d
    y = a * np.sin(q1) + b * np.sin(q1 + q2) + c * np.sin(q1 + q2 + q3)
    return np.hypot(x, y)


@pytest.fixture(scope="module")
def four_bar_run():
    cm = mt.compile_model(mech.four_bar(a=A, b=B, c=C, d=D, theta0=THETA0))
    return cm, mt.simulate(cm, 10.0, rtol=1e-10, atol=1e-12)


def test_four_bar_keeps_the_crank_as_its_state(four_bar_run):
    cm, _ = four_bar_run
    assert sorted(cm.state_names) == ["j1.q", "j1.w"]


def test_four_bar_loop_closure_stays_below_1e_9_m(four_bar_run):
    _, res = four_bar_run
    assert np.max(closure(res)) < 1e-9
    # the crank turns several times: the selection stays valid over full revolutions
    assert res["j1.q"][-1] - THETA0 > 4 * math.pi


def test_four_bar_matches_the_reduced_lagrange_ode(four_bar_run):
    _, res = four_bar_run
    rhs = four_bar_rhs(FourBarGeometry(A, B, C, D), density=1.0, torque=1.0, damping=0.1)
    sol = solve_ivp(rhs, (0.0, 10.0), [THETA0, 0.0], t_eval=res.t, method="DOP853",
                    rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(res["j1.q"], sol.y[0], atol=1e-6)
    np.testing.assert_allclose(res["j1.w"], sol.y[1], atol=1e-6)


def test_four_bar_energy_balance(four_bar_run):
    """E(t) - E(0) = work of the motor - heat of the bearing damper (Simpson's rule on a
    fine output grid)."""
    cm, _ = four_bar_run
    res = mt.simulate(cm, 10.0, rtol=1e-10, atol=1e-12, t_out=np.linspace(0, 10, 10001))
    bodies = ("crank_body", "coupler_body", "rocker_body")
    e = sum(res[f"{b}.E_kin"] + res[f"{b}.E_pot"] for b in bodies)
    w = res["j1.w"]
    power = 1.0 * w - 0.1 * w ** 2
    from scipy.integrate import cumulative_simpson
    work = cumulative_simpson(power, x=res.t, initial=0.0)
    assert np.max(np.abs(e - e[0] - work)) < 1e-6 * np.max(np.abs(work))


def test_slider_crank_slider_follows_the_closed_form():
    r, l, omega, th0 = 0.1, 0.3, 2 * math.pi, 0.3
    res = mt.simulate(mech.slider_crank(r=r, l=l, omega=omega, theta0=th0), 2.0,
                      rtol=1e-10, atol=1e-12)
    theta = th0 + omega * res.t
    np.testing.assert_allclose(res["j1.q"], theta, atol=1e-9)
    x = mech.slider_crank_position(theta, r, l)
    assert np.max(np.abs(res["slider.s"] - x)) < 1e-8
    # slider velocity: dx/dt by the chain rule
    s = r * np.sin(theta)
    v = -r * omega * np.sin(theta) \
        - s * r * omega * np.cos(theta) / np.sqrt(l ** 2 - s ** 2)
    np.testing.assert_allclose(res["slider.v"], v, atol=1e-7)


def test_singular_start_is_reported_at_compile_time():
    # b - c = |BD| at theta = 0: every link on the x-axis, the loop cannot be solved for
    # any choice of dependent coordinates
    with pytest.raises(StructuralError, match="state selection is singular"):
        mt.compile_model(mech.four_bar(a=0.2, b=0.6, c=0.5, d=0.3, theta0=0.0))


def test_a_loop_that_cannot_close_is_a_model_error():
    with pytest.raises(ModelError, match="cannot close"):
        mech.four_bar(a=0.5, b=0.1, c=0.1, d=2.0)
    with pytest.raises(ModelError, match="longer than the crank"):
        mech.slider_crank(r=0.3, l=0.2)
