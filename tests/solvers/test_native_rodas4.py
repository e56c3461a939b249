"""The compiled Rosenbrock solver ``"rodas4"`` against analytic solutions and CVODES."""

from __future__ import annotations

import re

import numpy as np
import pytest

import mechatron as mt
from mechatron.errors import SimulationError
from mechatron.library import blocks
from mechatron.library.electrical import (Capacitor, ControlledVoltageSource, Diode,
                                          ElectricalReference, Resistor)
from mechatron.solvers.initial import initialize
from mechatron.solvers.native import compiler, integrate_native, native_library

pytestmark = pytest.mark.skipif(compiler() is None, reason="no C compiler on this machine")


def _dc_motor_analytic(P: dict, t: np.ndarray):
    """i(t), w(t) of L di/dt = V - R i - k w, J dw/dt = k i - B w from rest."""
    R, L, k, J, B, V = (P[q] for q in ("R", "L", "k", "J", "B", "V"))
    A = np.array([[-R / L, -k / L], [k / J, -B / J]])
    b = np.array([V / L, 0.0])
    lam, vec = np.linalg.eig(A)
    y_inf = -np.linalg.solve(A, b)
    c = np.linalg.solve(vec, -y_inf)
    y = y_inf[:, None] + (vec * c) @ np.exp(np.outer(lam, t))
    return y[0].real, y[1].real


@pytest.fixture(scope="module")
def motor():
    entry = mt.models.get("dc_motor")
    cm = mt.compile_model(entry.build("acausal"))
    return entry, cm


def test_dc_motor_matches_the_analytic_solution(motor):
    entry, cm = motor
    P = entry.values()
    paths = entry.output_paths("acausal")
    t = np.array([0.0, 1e-4, 1e-3, 1e-2, 0.1, 0.5])
    res = mt.simulate(cm, 0.5, solver="rodas4", rtol=1e-10, atol=1e-12, t_out=t)
    i_ref, w_ref = _dc_motor_analytic(P, t)
    assert res.stats.solver == "rodas4"
    np.testing.assert_allclose(res[paths["w"]][1:], w_ref[1:], rtol=1e-7)
    np.testing.assert_allclose(res[paths["i"]][1:], i_ref[1:], rtol=1e-7)
    w_inf = P["k"] * P["V"] / (P["R"] * P["B"] + P["k"] ** 2)
    assert abs(res[paths["w"]][-1] - w_inf) <= 1e-8 * w_inf


def test_dense_output_between_steps_is_accurate(motor):
    """1001 output points, several per step: the Hermite interpolant between steps keeps
    the error at the level of the tolerance."""
    entry, cm = motor
    paths = entry.output_paths("acausal")
    t = np.linspace(0.0, 0.02, 1001)
    res = mt.simulate(cm, 0.02, solver="rodas4", rtol=1e-8, atol=1e-10, t_out=t)
    assert res.stats.steps < t.size / 2        # most points lie between steps
    i_ref, w_ref = _dc_motor_analytic(entry.values(), t)
    assert np.max(np.abs(res[paths["w"]] - w_ref)) <= 1e-6 * np.max(np.abs(w_ref))
    assert np.max(np.abs(res[paths["i"]] - i_ref)) <= 1e-6 * np.max(np.abs(i_ref))


def test_error_follows_the_tolerance(motor):
    entry, cm = motor
    paths = entry.output_paths("acausal")
    t = np.linspace(0.0, 0.01, 51)
    i_ref, w_ref = _dc_motor_analytic(entry.values(), t)
    errors, steps = [], []
    for rtol in (1e-4, 1e-6, 1e-8):
        res = mt.simulate(cm, 0.01, solver="rodas4", rtol=rtol, atol=rtol * 1e-2, t_out=t)
        errors.append(np.max(np.abs(res[paths["w"]] - w_ref)) / np.max(w_ref))
        steps.append(res.stats.steps)
    assert errors[0] > errors[1] > errors[2]
    assert errors[2] < 1e-7
    assert steps[0] < steps[1] < steps[2]


def test_convergence_order_is_four(motor):
    """Constant steps h, h/2, h/4 on the linear motor: the error falls by 2^4 per halving."""
    entry, cm = motor
    p = cm.p0.copy()
    X0, _, _ = initialize(cm, p, 0.0)
    t = np.array([0.0, 4e-3])
    _, w_ref = _dc_motor_analytic(entry.values(), t)
    iw = cm.names.index(entry.output_paths("acausal")["w"])
    errs = []
    for h in (2e-4, 1e-4, 5e-5):
        Y, _, st = integrate_native(cm, t, X0, p, rtol=1e-6, atol=1e-8, fixed_step=h)
        assert st["n_steps"] == round(4e-3 / h)
        errs.append(abs(Y[iw, -1] - w_ref[-1]))
    orders = np.log2(np.array(errs[:-1]) / np.array(errs[1:]))
    assert np.all(orders > 3.7), orders


def test_stiff_linear_system_takes_few_steps():
    """x1' = -x1 + x2 ... with eigenvalues -1 and -1e6: an explicit method needs a million
    steps over 5 s; the L-stable Rosenbrock method follows the slow mode."""

    class Stiff(mt.Component):
        a = mt.Variable("1", start=1.0)
        b = mt.Variable("1", start=2.0)

        def equations(self):
            return [mt.der(self.a) == -self.a,
                    mt.der(self.b) == -1e6 * (self.b - self.a) - self.a]

    cm = mt.compile_model(Stiff())
    t = np.linspace(0.0, 5.0, 11)
    res = mt.simulate(cm, 5.0, solver="rodas4", rtol=1e-8, atol=1e-12, t_out=t)
    a = np.exp(-t)
    # b = a + (b0 - a0) e^{-1e6 t} exactly (b - a obeys (b - a)' = -1e6 (b - a))
    np.testing.assert_allclose(res["a"], a, rtol=1e-7)
    np.testing.assert_allclose(res["b"][1:], a[1:], rtol=1e-7)
    assert res.stats.steps < 400


def _rc_sine(R=1e3, C=1e-6, V=2.0, f=200.0):
    m = mt.System("rc_sine")
    src = m.add("src", ControlledVoltageSource())
    sine = m.add("sine", blocks.Sine(amplitude=V, f=f))
    r = m.add("r", Resistor(R=R))
    c = m.add("c", Capacitor(C=C))
    gnd = m.add("gnd", ElectricalReference())
    m.connect(sine.y, src.u)
    m.connect(src.p, r.p)
    m.connect(r.n, c.p)
    m.connect(c.n, src.n, gnd.port)
    return m


def test_time_dependent_source_uses_the_time_derivative():
    """RC driven by V sin(wt) from rest: the exact solution, which a Rosenbrock method only
    reaches at its order when the df/dt term of every stage is right."""
    R, C, V, f = 1e3, 1e-6, 2.0, 200.0
    cm = mt.compile_model(_rc_sine(R, C, V, f))
    t = np.linspace(0.0, 0.02, 401)
    res = mt.simulate(cm, 0.02, solver="rodas4", rtol=1e-9, atol=1e-12, t_out=t)
    w, tau = 2 * np.pi * f, R * C
    k = V / (1 + (w * tau) ** 2)
    exact = k * (np.sin(w * t) - w * tau * np.cos(w * t) + w * tau * np.exp(-t / tau))
    assert np.max(np.abs(res["c.v"] - exact)) <= 1e-7 * V


def test_parameters_change_without_recompiling(motor):
    entry, cm = motor
    paths = entry.output_paths("acausal")
    lib = native_library(cm)
    R_path = next(n for n in cm.param_names if n.endswith(".R"))
    P = dict(entry.values(), R=9.0)
    res = mt.simulate(cm, 0.5, solver="rodas4", params={R_path: 9.0}, rtol=1e-9,
                      atol=1e-12, t_out=[0.0, 0.5])
    assert native_library(cm) is lib
    w_inf = P["k"] * P["V"] / (P["R"] * P["B"] + P["k"] ** 2)
    assert abs(res[paths["w"]][-1] - w_inf) <= 1e-7 * w_inf


@pytest.mark.parametrize("name, variant", [("msd_vertical", "acausal"),
                                           ("cart_pendulum", "equation"),
                                           ("motor_heating", "acausal"),
                                           ("dc_motor_speed_pi", "cascade"),
                                           ("double_pendulum", "multibody")])
def test_database_models_agree_with_cvodes(name, variant):
    entry = mt.models.get(name)
    cm = mt.compile_model(entry.build(variant))
    t_stop = entry.experiment.t_stop
    a = mt.simulate(cm, t_stop, solver="rodas4", rtol=1e-9, atol=1e-11)
    b = mt.simulate(cm, t_stop, solver="cvodes", rtol=1e-10, atol=1e-12)
    for path in entry.output_paths(variant).values():
        scale = np.max(np.abs(b[path])) + 1e-9
        assert np.max(np.abs(a[path] - b[path])) <= 1e-5 * scale, path


def test_rectifier_events_at_their_analytic_times():
    """Half-wave rectifier: 5 V, 50 Hz through a piecewise-linear diode into 100 Ohm. The
    diode switches where the source reaches Vf (1 + R Goff), rising and falling: six
    events in 0.05 s, the last at 0.05 s - t1, t1 = asin(Vf (1 + R Goff) / 5) / (2 pi 50).
    """
    m = mt.System("rectifier")
    src = m.add("src", ControlledVoltageSource())
    sine = m.add("sine", blocks.Sine(amplitude=5.0, f=50.0))
    d = m.add("d", Diode())
    r = m.add("r", Resistor(R=100.0))
    gnd = m.add("gnd", ElectricalReference())
    m.connect(sine.y, src.u)
    m.connect(src.p, d.p)
    m.connect(d.n, r.p)
    m.connect(r.n, src.n, gnd.port)
    cm = mt.compile_model(m)
    P = {n.split(".")[-1]: v for n, v in zip(cm.param_names, cm.p0) if n.startswith("d.")}
    res = mt.simulate(cm, 0.05, solver="rodas4", rtol=1e-10, atol=1e-12)
    t1 = np.arcsin(P["Vf"] * (1 + 100.0 * P["Goff"]) / 5.0) / (2 * np.pi * 50.0)
    assert res.stats.events == {"d": 6}
    assert abs(res.event_times["d"] - (0.05 - t1)) < 1e-9
    # the current between events against the network's two linear states
    v = 5.0 * np.sin(2 * np.pi * 50.0 * res.t)
    on = v > P["Vf"] * (1 + 100.0 * P["Goff"])
    i_on = (v - P["Vf"] + P["Ron"] * P["Goff"] * P["Vf"]) / (100.0 + P["Ron"])
    i_off = P["Goff"] * v / (1 + 100.0 * P["Goff"])
    np.testing.assert_allclose(res["r.i"], np.where(on, i_on, i_off), atol=1e-9)


@pytest.mark.parametrize("name, variant", [("buck_converter", "switched"),
                                           ("servo_encoder", "acausal"),
                                           ("geared_drive", "acausal"),
                                           ("stepper_motor", "acausal")])
def test_hybrid_database_models_agree_with_auto(name, variant):
    """Switching converters, sampled controllers, backlash and steps: the same events as
    the CasADi integrators (counted per component) and the same waveforms."""
    entry = mt.models.get(name)
    cm = mt.compile_model(entry.build(variant))
    t_stop = entry.experiment.t_stop
    a = mt.simulate(cm, t_stop, solver="rodas4", rtol=1e-9, atol=1e-11)
    b = mt.simulate(cm, t_stop, solver="auto", rtol=1e-9, atol=1e-11)
    assert a.stats.events == b.stats.events and sum(a.stats.events.values()) > 0
    for path in entry.output_paths(variant).values():
        scale = np.max(np.abs(b[path])) + 1e-9
        assert np.max(np.abs(a[path] - b[path])) <= 1e-6 * scale, path


def test_chattering_is_detected_as_with_auto():
    """x' = -sign(x) from x = 1: a sliding mode from t = 1 s, reported with its component."""
    m = mt.System("chatter")
    sw = m.add("ideal_relay", blocks.Sign())
    g = m.add("g", blocks.Gain(k=-1.0))
    i = m.add("integ", blocks.Integrator(y=1.0))
    m.connect(i.y, sw.u)
    m.connect(sw.y, g.u)
    m.connect(g.y, i.u)
    with pytest.raises(SimulationError, match=r"rodas4: chattering at t = 1 s: events at "
                                              r"'ideal_relay'"):
        mt.simulate(m, 2.0, solver="rodas4")


def test_blow_up_is_reported_with_its_time():
    """x' = x^2, x(0) = 1 has x = 1 / (1 - t): it leaves every bound at t = 1."""

    class BlowUp(mt.Component):
        x = mt.Variable("1", start=1.0)

        def equations(self):
            return [mt.der(self.x) == self.x ** 2]

    with pytest.raises(SimulationError, match=r"rodas4' stopped at t = ") as info:
        mt.simulate(BlowUp(), 2.0, solver="rodas4")
    t_stop = float(re.search(r"stopped at t = (\S+) s", str(info.value)).group(1))
    assert abs(t_stop - 1.0) < 1e-3


def test_missing_compiler_is_a_clear_error(motor, monkeypatch):
    _, cm = motor
    fresh = mt.compile_model(mt.models.get("dc_motor").build("ode"))
    monkeypatch.setattr("mechatron.solvers.native.compiler", lambda: None)
    with pytest.raises(SimulationError, match=r"no C compiler.*solver='auto'"):
        mt.simulate(fresh, 0.1, solver="rodas4")


def test_bad_output_grid_is_refused(motor):
    _, cm = motor
    with pytest.raises(SimulationError, match="strictly increasing"):
        mt.simulate(cm, 0.5, solver="rodas4", t_out=[0.0, 0.2, 0.1])


def test_library_is_cached_on_disk(tmp_path, monkeypatch):
    """A second compiled model of the same source loads the library built by the first."""
    monkeypatch.setenv("MECHATRON_CACHE", str(tmp_path))
    first = mt.compile_model(mt.models.get("dc_motor").build("ode"))
    a = native_library(first)
    second = mt.compile_model(mt.models.get("dc_motor").build("ode"))
    b = native_library(second)
    assert a.path == b.path and a.path.parent.parent == tmp_path
    assert len(list((tmp_path / "rodas4").glob("*.so"))) == 1
