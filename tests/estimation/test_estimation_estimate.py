"""Parameter estimation: exact recovery from noise-free data, confidence intervals against
linear regression, and the acceptance case on the virtual bench."""

import numpy as np
import pytest
import scipy.stats

import mechatron as mt
from mechatron.errors import ParameterError
from mechatron.estimation import EstimationProblem, Experiment, FreeParameter, estimate
from mechatron.estimation import classic
from mechatron.estimation.bench import TABLE_6_1, VirtualBench


def test_noise_free_data_from_cvodes_are_fitted_exactly():
    """Data: the database's acausal DC motor simulated by CVODES at tight tolerance
    (another integrator); start values off by a factor of 2."""
    entry = mt.models.get("dc_motor")
    t = np.linspace(0, 0.01, 401)
    res = mt.simulate(entry.build("acausal"), 0.01, rtol=1e-12, atol=1e-14, t_out=t)
    e = Experiment("step", t=t, outputs={"i": res["inductor.i"], "w": res["inertia.w"]},
                   units={"i": "A", "w": "rad/s"})
    free = [FreeParameter("resistor.R", 2 * 7.1, 0.1, 100),
            FreeParameter("emf.k", 0.151 / 2, 1e-3, 10),
            FreeParameter("inertia.J", 2 * 4.8e-6, 1e-8, 1e-3)]
    prob = EstimationProblem(entry.build("acausal"), [e], free,
                             outputs={"i": "inductor.i", "w": "inertia.w"}, jit=False)
    out = estimate(prob)
    assert out.success
    for name, truth in [("resistor.R", 7.1), ("emf.k", 0.151), ("inertia.J", 4.8e-6)]:
        assert out.parameters[name] == pytest.approx(truth, rel=2e-6)
    assert out.cost < 1e-8 * out.cost_initial
    assert out.history[0]["theta"][0] == pytest.approx(14.2)
    assert out.history[-1]["cost"] == pytest.approx(out.cost)


class Line(mt.Component):
    """x' = c: with x(0) free, the output is the straight line x0 + c t."""

    c = mt.Parameter("1/s", default=1.0)
    x = mt.Variable("1", start=0.0)

    def equations(self):
        return [mt.der(self.x) == self.c]


def test_intervals_and_correlation_equal_those_of_linear_regression():
    """covariance="white" is the textbook covariance of ordinary least squares; the
    default (HAC) one is reported beside it as ``ci95_white``."""
    rng = np.random.default_rng(3)
    t = np.linspace(0, 2, 60)
    y = 0.7 + 1.9 * t + 0.05 * rng.standard_normal(t.size)
    e = Experiment("line", t=t, outputs={"y": y})
    prob = EstimationProblem(Line(), [e], [FreeParameter("c", 1.0)], outputs={"y": "x"},
                             free_x0=["x"], jit=False)
    out = estimate(prob, covariance="white")
    hac = estimate(prob)
    assert hac.ci95_white["c"] == pytest.approx(out.ci95["c"])
    # ordinary least squares by hand
    A = np.column_stack([t, np.ones_like(t)])
    coef, ssr, *_ = np.linalg.lstsq(A, y, rcond=None)
    dof = t.size - 2
    cov = ssr[0] / dof * np.linalg.inv(A.T @ A)
    half = scipy.stats.t.ppf(0.975, dof) * np.sqrt(np.diag(cov))
    assert out.parameters["c"] == pytest.approx(coef[0], rel=1e-9)
    assert out.parameters["line:x"] == pytest.approx(coef[1], rel=1e-9)
    assert out.ci95["c"] == pytest.approx((coef[0] - half[0], coef[0] + half[0]), rel=1e-7)
    corr = cov[0, 1] / np.sqrt(cov[0, 0] * cov[1, 1])
    assert out.correlation[0, 1] == pytest.approx(corr, rel=1e-7)


def test_bad_problem_definitions_are_named():
    e = Experiment("line", t=[0, 1, 2], outputs={"y": [0, 1, 2]})
    with pytest.raises(ParameterError, match="free parameter 'd' is not a parameter"):
        EstimationProblem(Line(), [e], ["d"], outputs={"y": "x"})
    with pytest.raises(ParameterError, match="starting value 5 is outside"):
        EstimationProblem(Line(), [e], [FreeParameter("c", 5, 0, 1)], outputs={"y": "x"})
    with pytest.raises(ParameterError, match="output 'y' is compared with 'q'"):
        EstimationProblem(Line(), [e], ["c"], outputs={"y": "q"})


@pytest.fixture(scope="module")
def bench_runs():
    bench = VirtualBench(seed=11)
    return bench, bench.locked_rotor(), bench.multi_step(), bench.voltage_step(t_stop=0.04)


def test_classic_tests_recover_R_and_k_within_3_percent(bench_runs):
    bench, locked, multi, step = bench_runs
    R = classic.locked_rotor_resistance(locked)
    L = classic.electrical_time_constant(locked, R.value)
    k, B, T_C = classic.free_running_constants(multi, R.value)
    J = classic.mechanical_time_constant(step, R.value, k.value, B.value, L.value)
    truth = bench.truth
    assert R.value == pytest.approx(truth["R"], rel=0.03)
    assert k.value == pytest.approx(truth["k"], rel=0.03)
    assert L.value == pytest.approx(truth["L"], rel=0.05)
    assert J.value == pytest.approx(truth["J"], rel=0.05)
    assert B.value == pytest.approx(truth["B"], rel=0.1)
    assert R.details["offset_A"] == pytest.approx(bench.current_offset, abs=0.01)


def test_stribeck_fit_of_the_torque_speed_curve(bench_runs):
    bench = bench_runs[0]
    w = np.concatenate([np.linspace(0.01, 1, 25), np.linspace(1.5, 150, 20)])
    curve = bench.friction_curve(w)
    fit = classic.fit_stribeck(curve.w, bench.truth["k"] * curve.i)
    for name in ("T_brk", "w_brk", "T_C", "B"):
        assert fit[name].value == pytest.approx(bench.truth[name], rel=0.05)
        assert abs(fit[name].value - bench.truth[name]) < 4 * fit[name].std


def test_acceptance_estimation_from_two_experiments(bench_runs):
    """R, L, k, J, B within 2% from guesses off by a factor of 3; the 95% intervals hold
    the truth. Breakaway friction fixed at the classic Stribeck fit."""
    bench, locked, multi, _ = bench_runs
    curve = bench.friction_curve(np.concatenate([np.linspace(0.01, 1, 25),
                                                 np.linspace(1.5, 150, 20)]))
    fit = classic.fit_stribeck(curve.w, 0.15 * curve.i)
    factors = {"R": 3, "L": 1 / 3, "k": 3, "J": 1 / 3, "B": 3, "T_C": 1 / 3}
    free = [FreeParameter(n, TABLE_6_1[n] * f, 0.0) for n, f in factors.items()]
    prob = EstimationProblem(bench.model(), [multi, locked], free, inputs={"V": "V"},
                             outputs={"i": "i", "w": "rate(phi)"}, offsets=["i"],
                             fixed={"T_brk": fit["T_brk"].value,
                                    "w_brk": fit["w_brk"].value})
    out = estimate(prob)
    assert out.success
    for name in ("R", "L", "k", "J", "B"):
        truth = bench.truth[name]
        assert out.parameters[name] == pytest.approx(truth, rel=0.02), name
        lo, hi = out.ci95[name]
        assert lo <= truth <= hi, (name, lo, truth, hi)
    assert out.nrmse["locked_rotor"]["i"] < out.nrmse_initial["locked_rotor"]["i"]
    assert len(out.history) >= 3


def test_noise_free_data_of_a_stiff_network_ask_no_finer_substeps_than_they_can_show():
    """A random network of 19 states (tests.compiler.test_random_networks, seed 2),
    fitted to its own noise-free simulation: the residuals at the solution are the
    discretization error itself, so the fit's standard errors over the noise level
    (std_scale) shrink with every refinement and asked for ever finer substeps, up to
    the limit (minutes at 400). No data show an error below noise_level's floor, 1e-4 of
    their range: std_scale stays at least that floor over the noise level."""
    from tests.compiler.test_random_networks import T_END, random_network
    cm = mt.compile_model(random_network(2)())
    true = float(cm.p0[cm.param_names.index("u0.Rb")])
    t = np.linspace(0.0, T_END, 41)
    res = mt.simulate(cm, T_END, rtol=1e-10, atol=1e-12, t_out=t)
    outs = {"a": "u0.p0.i", "b": "u0.p1.i"}
    run = Experiment("run", t=t, outputs={k: res[v] for k, v in outs.items()})
    prob = EstimationProblem(cm, [run], [FreeParameter("u0.Rb", 1.6 * true, 0.01, 100.0)],
                             outputs=outs, max_substeps=64)
    out = estimate(prob)
    assert out.parameters["u0.Rb"] == pytest.approx(true, rel=1e-6)
    assert prob.bound[0]["substeps"] <= 4
