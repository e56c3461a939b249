"""Estimation of models with events: sampled controllers with saturation (time events,
exact), state events through the smooth approximation, and the checks that refuse what
would be wrong (a clock between substeps, state events without the approximation).

The data are made by ``mt.simulate`` (variable step, events located by the integrator):
an implementation independent of the sampled Radau transcription under test."""

import casadi as ca
import numpy as np
import pytest

import mechatron as mt
from mechatron.errors import DataError, ModelError
from mechatron.estimation import EstimationProblem, Experiment, estimate
from mechatron.estimation.discretize import Trajectory, state_event_relations
from mechatron.estimation.native import compiler


class SampledPIServo(mt.Component):
    """A first-order speed plant ``tau w' = -w + K u`` under a PI controller sampled every
    ``Ts`` with an output limit and clamping anti-windup; the set point ``r`` is an
    external input."""

    K = mt.Parameter("1", default=2.0, doc="Plant gain")
    tau = mt.Parameter("s", default=0.3, doc="Plant time constant")
    Kp = mt.Parameter("1", default=3.0)
    Ki = mt.Parameter("1/s", default=6.0)
    Ts = mt.Parameter("s", default=0.01)
    u_max = mt.Parameter("1", default=1.0)
    r = mt.Input("1", start=0.0, doc="Set point")
    w = mt.Variable("1", start=0.0, doc="Plant output")
    u = mt.Variable("1", start=0.0, doc="Controller output, held")
    integral = mt.Variable("1", start=0.0, doc="Integral state")

    def equations(self):
        e = self.r - self.w
        v = self.Kp * e + self.integral
        windup = mt.logic_or(mt.logic_and(v > self.u_max, e > 0),
                             mt.logic_and(v < -self.u_max, e < 0))
        return [self.tau * mt.der(self.w) == -self.w + self.K * self.u,
                mt.sample(mt.Clock(self.Ts, 0.0),
                          output={self.u: ca.fmin(ca.fmax(v, -self.u_max), self.u_max)},
                          update={self.integral: mt.if_else(
                              windup, self.integral, self.integral + self.Ki * self.Ts * e)})]


class SaturatedLoop(mt.Component):
    """A continuous P loop whose actuator saturates: ``tau x' = -x + K sat(Kp (r - x))``;
    the saturation's relations switch with the state (state events)."""

    K = mt.Parameter("1", default=1.5)
    tau = mt.Parameter("s", default=0.2)
    Kp = mt.Parameter("1", default=4.0)
    r = mt.Input("1", start=0.0)
    x = mt.Variable("1", start=0.0)
    a = mt.Variable("1", doc="Actuator output")

    def equations(self):
        c = self.Kp * (self.r - self.x)
        return [self.a == mt.if_else(c > 1.0, 1.0, mt.if_else(c < -1.0, -1.0, c)),
                self.tau * mt.der(self.x) == -self.x + self.K * self.a]


def _reference(t):
    """Steps large enough to saturate the controller, and a slow sine."""
    r = np.where(t < 0.5, 0.0, 1.5) - np.where(t >= 1.5, 2.5, 0.0)
    return r + 0.3 * np.sin(2 * np.pi * 0.7 * t) * (t >= 2.5)


def _measure(model, t, output, sigma, seed, hold="zoh", **params):
    """Noisy samples of ``output`` from a variable-step simulation (the reference is
    interpolated linearly there: ``hold="linear"`` when the model reads it between
    samples)."""
    cm = mt.compile_model(model)
    res = mt.simulate(cm, float(t[-1]), t_out=t, inputs={"r": (t, _reference(t))},
                      params=params or None, rtol=1e-10, atol=1e-12)
    y = res[output] + sigma * np.random.default_rng(seed).standard_normal(t.size)
    return cm, Experiment(t=t, inputs={"r": _reference(t)}, outputs={"y": y},
                          sigma={"y": sigma or 1.0}, name="synthetic", hold=hold), res


def test_sampled_trajectory_matches_the_event_simulation():
    """The Radau transcription with the event iteration at the substep ends reproduces
    the variable-step simulation (ticks located by the integrator) at the samples: the
    controller's saturation and anti-windup act at the same ticks."""
    t = np.round(np.arange(0, 3.0 + 1e-9, 0.01), 12)
    # the simulation is read at the samples (w is continuous there) and half a sample
    # later (u is held: the value the tick set, which a sample of the trajectory shows)
    tm = np.round(t[:-1] + 0.005, 12)
    cm, exp, res = _measure(SampledPIServo(), np.union1d(t, tm), "w", 0.0, 0)
    on = np.isin(res.t, t)
    traj = Trajectory(cm, t, [cm.param_names.index("r")],
                      [cm.names.index("w"), cm.names.index("u")], substeps=4)
    Y, _ = traj(cm.p0, np.array(cm.x_start[:cm.nx]), _reference(t)[None, :])
    assert np.max(np.abs(res["u"])) == pytest.approx(1.0)      # the limit is reached
    np.testing.assert_allclose(Y[1][:-1], res["u"][~on], atol=1e-9)
    np.testing.assert_allclose(Y[0], res["w"][on], atol=2e-8)


def test_sensitivities_through_time_events_match_finite_differences():
    t = np.round(np.arange(0, 3.0 + 1e-9, 0.01), 12)
    cm = mt.compile_model(SampledPIServo())
    names = ["K", "tau", "Kp", "Ki", "u_max"]
    D = np.zeros((cm.p0.size, len(names)))
    for j, n in enumerate(names):
        D[cm.param_names.index(n), j] = 1.0
    traj = Trajectory(cm, t, [cm.param_names.index("r")], [cm.names.index("w")],
                      substeps=3)
    U = _reference(t)[None, :]
    x0 = np.array(cm.x_start[:cm.nx])
    _, dY = traj.sensitivity_function(D)(cm.p0, x0, U, np.zeros((cm.nx, len(names))))
    dY = np.array(dY)
    for j, n in enumerate(names):
        h = 1e-6 * abs(cm.p0[cm.param_names.index(n)])
        p1, p2 = cm.p0.copy(), cm.p0.copy()
        p1[cm.param_names.index(n)] += h
        p2[cm.param_names.index(n)] -= h
        fd = (traj(p1, x0, U)[0][0] - traj(p2, x0, U)[0][0]) / (2 * h)
        np.testing.assert_allclose(dY[j], fd, atol=1e-6 * np.abs(fd).max() + 1e-9,
                                   err_msg=n)


def test_event_sensitivity_along_directions_equals_the_jacobian_product():
    """The sensitivity step carries ``S`` through the events at a substep end along its
    directions (one forward sweep per direction): the same as the Jacobians of the new
    state times ``[S; D]``; where no event is due, state and ``S`` pass unchanged."""
    cm = mt.compile_model(SampledPIServo())
    t = np.round(np.arange(0, 0.2 + 1e-9, 0.01), 12)
    traj = Trajectory(cm, t, [cm.param_names.index("r")], [cm.names.index("w")])
    rng = np.random.default_rng(3)
    D = rng.standard_normal((cm.p0.size, 3))
    S = rng.standard_normal((cm.nx, 3))
    x = np.array([0.4, -0.2, 0.9])[:cm.nx]
    r = traj._rest0()
    u, tick = np.array([1.2]), 0.05
    switch = traj._event_switch_sens(ca.DM(D))
    xn, rn, Sn = (np.array(v) for v in switch(1, x, r, cm.p0, u, tick, S))
    xr, rr, jx, jp = (np.array(v) for v in traj._event_fn(x, r, cm.p0, u, tick))
    np.testing.assert_array_equal(xn.ravel(), xr.ravel())
    np.testing.assert_array_equal(rn.ravel(), rr.ravel())
    np.testing.assert_allclose(Sn, jx @ S + jp @ D, rtol=1e-12, atol=1e-12)
    assert not np.allclose(Sn, S)                   # the tick moved the controller
    xs, rs, Ss = (np.array(v) for v in switch(0, x, r, cm.p0, u, tick, S))
    np.testing.assert_array_equal(xs.ravel(), x)
    np.testing.assert_array_equal(Ss, S)


@pytest.mark.skipif(compiler() is None, reason="no C compiler on the PATH")
def test_native_time_loop_steps_through_the_events_like_the_casadi_loop():
    """The C loop over the samples gives the bits of CasADi's ``mapaccum`` of the same
    compiled step on a model with clock ticks, a saturation and a held input: outputs,
    states and sensitivities."""
    t = np.round(np.arange(0, 2.0 + 1e-9, 0.01), 12)
    cm = mt.compile_model(SampledPIServo())
    traj = Trajectory(cm, t, [cm.param_names.index("r")],
                      [cm.names.index("w"), cm.names.index("u")], substeps=2, jit=True)
    assert traj._loop is not None
    U = _reference(t)[None, :]
    x0 = np.array(cm.x_start[:cm.nx])
    Y, X = traj(cm.p0, x0, U)
    Yc, Xc, _ = traj._mx_functions()[1](cm.p0, x0, U)
    np.testing.assert_array_equal(Y, Yc.full())
    np.testing.assert_array_equal(X, Xc.full())
    assert np.max(np.abs(Y[1])) == pytest.approx(1.0)      # the limit is reached
    D = np.eye(cm.p0.size)[:, [cm.param_names.index(n) for n in ("K", "Kp", "Ki")]]
    S0 = np.zeros((cm.nx, 3))
    Y1, dY = traj.sensitivity_function(D)(cm.p0, x0, U, S0)
    traj._loop = None                           # the same trajectory's CasADi loop
    traj._sens.clear()
    traj.jit = False
    Y2, dY2 = traj.sensitivity_function(D)(cm.p0, x0, U, S0)
    np.testing.assert_allclose(dY, dY2, rtol=1e-12, atol=1e-12 * np.abs(dY2).max())
    np.testing.assert_allclose(Y1, Y2, rtol=1e-12, atol=1e-14)


def test_sampled_controller_with_saturation_is_estimated_with_known_truth():
    t = np.round(np.arange(0, 4.0 + 1e-9, 0.01), 12)
    truth = {"K": 2.0, "tau": 0.3}
    sigma = 0.005
    cm, exp, _ = _measure(SampledPIServo(), t, "w", sigma, 1)
    prob = EstimationProblem(cm, [exp], [dict(name="K", initial=1.0, min=0.1),
                                         dict(name="tau", initial=0.6, min=0.01)],
                             inputs={"r": "r"}, outputs={"y": "w"})
    res = estimate(prob)
    assert res.success
    for j, name in enumerate(res.names):
        lo, hi = res.ci95[name]
        # the truth inside the 95% interval widened to 4 standard deviations, and the
        # interval itself tight (white noise, a well-excited loop)
        assert abs(res.values[j] - truth[name]) < 4 * res.std[j], name
        assert res.std[j] < 0.01 * truth[name], name
    # the residuals are the noise: cost / n close to 1
    assert res.cost / prob.n_residuals == pytest.approx(1.0, abs=0.2)


def test_state_events_need_the_smooth_approximation_and_then_estimate():
    t = np.round(np.arange(0, 4.0 + 1e-9, 0.01), 12)
    sigma = 0.002
    cm, exp, res = _measure(SaturatedLoop(), t, "x", sigma, 2, hold="linear")
    assert np.max(np.abs(res["a"])) == pytest.approx(1.0)       # the actuator saturates
    assert state_event_relations(cm) != []
    free = [dict(name="K", initial=1.0, min=0.1), dict(name="tau", initial=0.4, min=0.01)]
    with pytest.raises(ModelError, match="state events.*smooth"):
        EstimationProblem(cm, [exp], free, inputs={"r": "r"}, outputs={"y": "x"})
    prob = EstimationProblem(cm, [exp], free, inputs={"r": "r"}, outputs={"y": "x"},
                             smooth=1e-3)
    fit = estimate(prob)
    assert fit.parameters["K"] == pytest.approx(1.5, rel=5e-3)
    assert fit.parameters["tau"] == pytest.approx(0.2, rel=5e-3)


def test_a_clock_between_the_substeps_is_refused():
    """Data sampled at 15 ms against a 10 ms controller: ticks fall inside intervals."""
    t = np.round(np.arange(0, 0.3 + 1e-9, 0.015), 12)
    cm = mt.compile_model(SampledPIServo())
    exp = Experiment(t=t, inputs={"r": np.ones(t.size)}, outputs={"y": 1 - np.exp(-t / 0.05)},
                     sigma={"y": 0.01}, name="coarse")     # (all-zero data are refused first)
    with pytest.raises(DataError, match=r"ticks at t = 0\.01 s, between the substeps"):
        EstimationProblem(cm, [exp], ["K"], inputs={"r": "r"}, outputs={"y": "w"},
                          substeps=1)
    # three substeps put every 10 ms tick on a 5 ms substep end
    EstimationProblem(cm, [exp], ["K"], inputs={"r": "r"}, outputs={"y": "w"},
                      substeps=3)


class StepDrivenLag(mt.Component):
    """``tau x' = -x + u`` with a step of ``u`` at ``t_step`` (a switching time known in
    advance, a time event)."""

    tau = mt.Parameter("s", default=0.1)
    t_step = mt.Parameter("s", default=0.2)
    x = mt.Variable("1", start=0.0)

    def equations(self):
        return [self.tau * mt.der(self.x) == -self.x + mt.if_else(self.time < self.t_step,
                                                                 0.0, 1.0)]


def test_a_known_switching_time_on_the_grid_is_exact_and_off_it_refused():
    t = np.round(np.arange(0, 1.0 + 1e-9, 0.01), 12)
    cm = mt.compile_model(StepDrivenLag())
    traj = Trajectory(cm, t, [], [cm.names.index("x")], substeps=4)
    traj.check_ticks(cm.p0)
    y = traj(cm.p0, np.zeros(1), np.zeros((0, t.size)))[0][0]
    exact = np.where(t < 0.2, 0.0, 1 - np.exp(-(t - 0.2) / 0.1))
    np.testing.assert_allclose(y, exact, atol=1e-8)
    # d x(t)/d tau, analytic, through the exact switching instant
    D = np.zeros((cm.p0.size, 1))
    D[cm.param_names.index("tau"), 0] = 1.0
    dy = np.array(traj.sensitivity_function(D)(cm.p0, np.zeros(1), np.zeros((0, t.size)),
                                               np.zeros((1, 1)))[0 + 1]).ravel()
    s = np.clip(t - 0.2, 0, None)
    np.testing.assert_allclose(dy, -s / 0.1 ** 2 * np.exp(-s / 0.1), atol=1e-7)
    traj.check_ticks(cm.parameter_vector({"t_step": 0.205}))     # a substep end
    p = cm.parameter_vector({"t_step": 0.2063})
    with pytest.raises(DataError, match=r"relation of time switches between t = 0\.205 s"):
        traj.check_ticks(p)
