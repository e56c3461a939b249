"""Substeps chosen from an error estimate (``substeps=None``): step doubling, ``m``
against ``2m`` Radau substeps per sample, in standard errors of the fit.

The data are made by ``mt.simulate`` with CVODES at tight tolerances (variable step, an
implementation independent of the Radau transcription under test), with Gaussian noise of
a known level. The truth must lie in the stated 95% intervals with the chosen substeps;
where the time constants' rule or a fixed small count is used instead, the estimates are
biased far outside them (the resonance), or the result names the discretization error
(the kink)."""

import logging

import casadi as ca
import numpy as np
import pytest

import mechatron as mt
from mechatron.errors import DataError, ParameterError
from mechatron.estimation import EstimationProblem, Experiment, FreeParameter, estimate
from mechatron.estimation.discretize import choose_substeps, noise_level


@pytest.fixture(autouse=True)
def _quiet():
    logger = logging.getLogger("mechatron")
    level = logger.level
    logger.setLevel(logging.ERROR)
    yield
    logger.setLevel(level)


class Resonator(mt.Component):
    """``x'' + 2 zeta w x' + w^2 x = w^2 r``: a lightly damped mode."""

    w = mt.Parameter("1/s", default=60.0)
    zeta = mt.Parameter("1", default=0.02)
    r = mt.Input("1", start=0.0)
    x = mt.Variable("1", start=0.0)
    v = mt.Variable("1/s", start=0.0)

    def equations(self):
        return [mt.der(self.x) == self.v,
                mt.der(self.v) == self.w ** 2 * (self.r - self.x)
                - 2 * self.zeta * self.w * self.v]


class SaturatedSpeedLoop(mt.Component):
    """``J w' = sat(Kp (r - w)) - B w`` with the saturation written with ``fmin``/``fmax``:
    a kink in the dynamics and no event."""

    J = mt.Parameter("1", default=0.01)
    B = mt.Parameter("1", default=0.05)
    Kp = mt.Parameter("1", default=1.0)
    r = mt.Input("1", start=0.0)
    w = mt.Variable("1", start=0.0)

    def equations(self):
        u = ca.fmin(ca.fmax(self.Kp * (self.r - self.w), -1.0), 1.0)
        return [self.J * mt.der(self.w) == u - self.B * self.w]


def _reference(t, amp):
    return amp * (np.sin(2 * np.pi * 0.5 * t)
                  + 0.5 * np.sign(np.sin(2 * np.pi * 0.2 * t + 0.3)))


def _experiment(model, t, out, sigma, amp=1.0, seed=0):
    cm = mt.compile_model(model)
    r = _reference(t, amp)
    res = mt.simulate(cm, float(t[-1]), t_out=t, inputs={"r": (t, r)}, solver="cvodes",
                      rtol=1e-10, atol=1e-12)
    y = res[out] + sigma * np.random.default_rng(seed).standard_normal(t.size)
    # the reference is interpolated linearly by the simulation: the same hold here
    return cm, Experiment(t=t, inputs={"r": r}, outputs={"y": y}, sigma={"y": sigma},
                          name="synthetic", hold="linear")


def _inside(fit, name, truth):
    lo, hi = fit.ci95[name]
    return lo <= truth <= hi


def test_the_error_estimate_resolves_a_resonance_the_time_constant_rule_steps_over():
    """A 60 rad/s mode sampled at 20 Hz (w h = 3): the time constants' rule (a step of up
    to 4 / |lambda|) gives 1 substep, with which L-stable Radau damps the mode away and the
    damping ratio comes out 40 times too small; the error estimate asks for more."""
    t = np.round(np.arange(0, 4 + 1e-9, 0.05), 12)
    cm, exp = _experiment(Resonator(), t, "x", 0.01)
    free = [FreeParameter("w", 50.0, 0), FreeParameter("zeta", 0.02, 0)]
    # the time constants' rule at the start (|lambda| = w = 50 for a light damping)
    m_rule = choose_substeps(0.05, 1 / 50.0, ratio=4.0)
    assert m_rule == 1
    fixed = estimate(EstimationProblem(cm, [exp], free, inputs={"r": "r"},
                                       outputs={"y": "x"}, substeps=m_rule, jit=False),
                     refine=False)
    assert not _inside(fixed, "zeta", 0.02)
    assert fixed.parameters["zeta"] < 0.01
    assert any("discretization error" in w for w in fixed.warnings)
    assert fixed.discretization["synthetic"]["error_std"] > 1.0

    prob = EstimationProblem(cm, [exp], free, inputs={"r": "r"}, outputs={"y": "x"},
                             jit=False)
    m = prob.bound[0]["substeps"]
    assert m > m_rule
    fit = estimate(prob)
    assert _inside(fit, "w", 60.0) and _inside(fit, "zeta", 0.02)
    d = fit.to_dict()["discretization"]["synthetic"]
    assert d["chosen"] == "error" and d["substeps"] >= m
    assert d["error_initial"] <= 0.1 and d["error"] <= 0.1 and d["tolerance"] == 0.1
    assert not any("discretization error" in w for w in fit.warnings)


def test_a_kink_written_with_fmin_fmax_does_not_bias_the_estimates():
    """The saturated speed loop switches between its saturated and linear regions dozens
    of times; the Radau steps across a kink lose their order (error ~ h^2), which the
    step-doubling estimate sees: the chosen substeps recover J and B within their
    intervals, and too few substeps are named in the warnings, not silent."""
    t = np.round(np.arange(0, 6 + 1e-9, 0.01), 12)
    cm, exp = _experiment(SaturatedSpeedLoop(), t, "w", 0.01, amp=10.0)
    prob = EstimationProblem(cm, [exp], [FreeParameter("J", 0.02, 0),
                                         FreeParameter("B", 0.1, 0)],
                             inputs={"r": "r"}, outputs={"y": "w"}, jit=False)
    fit = estimate(prob)
    assert _inside(fit, "J", 0.01) and _inside(fit, "B", 0.05)
    assert fit.parameters["J"] == pytest.approx(0.01, rel=5e-3)
    d = fit.discretization["synthetic"]
    assert d["error"] <= 0.1 and d["substeps"] <= 64
    # one substep per sample: the estimate exceeds the tolerance and says so
    coarse = estimate(EstimationProblem(cm, [exp], [FreeParameter("J", 0.02, 0),
                                                    FreeParameter("B", 0.1, 0)],
                                        inputs={"r": "r"}, outputs={"y": "w"},
                                        substeps=1, jit=False), refine=False)
    assert coarse.discretization["synthetic"]["error_std"] > 1.0
    assert any("discretization error" in w and "1 substeps" in w for w in coarse.warnings)


def test_a_tolerance_out_of_reach_is_refused_with_the_limit():
    t = np.round(np.arange(0, 2 + 1e-9, 0.05), 12)
    cm, exp = _experiment(Resonator(), t, "x", 0.01)
    with pytest.raises(DataError, match=r"experiment 'synthetic': with 2 Radau substeps "
                                        r"per sample the discretization error estimate "
                                        r"\(against 4\) is .* above the tolerance "
                                        r"substep_tol = 1e-06; 4 would exceed "
                                        r"max_substeps = 2"):
        EstimationProblem(cm, [exp], ["w"], inputs={"r": "r"}, outputs={"y": "x"},
                          jit=False, max_substeps=2, substep_tol=1e-6)
    with pytest.raises(ParameterError, match="max_substeps must be a whole number from 1 "
                                             "to 1000"):
        EstimationProblem(cm, [exp], ["w"], inputs={"r": "r"}, outputs={"y": "x"},
                          max_substeps=5000)
    with pytest.raises(ParameterError, match="substep_tol must be a number > 0"):
        EstimationProblem(cm, [exp], ["w"], inputs={"r": "r"}, outputs={"y": "x"},
                          substep_tol=0)


def test_the_noise_level_of_a_smooth_signal_is_its_noise():
    """Without a given sigma, the tolerance is relative to the noise read from the data:
    the robust spread of second differences of white noise on a slow signal."""
    t = np.linspace(0, 10, 5000)
    clean = 3 * np.sin(t) + t
    noisy = clean + 0.02 * np.random.default_rng(3).standard_normal(t.size)
    assert noise_level(noisy) == pytest.approx(0.02, rel=0.1)
    # noise-free data fall back on 1e-4 of the range (not 0, which no m could meet)
    assert noise_level(clean) == pytest.approx(1e-4 * np.ptp(clean), rel=1e-6)
