"""Generated C99: strict compilation, agreement with the desktop fixed-step run, tunable
parameters, signal-block controllers, events, and the Cortex-M4 cross-build."""

import re
import subprocess

import numpy as np
import pytest
import scipy.linalg

import mechatron as mt
from mechatron.codegen import (CodegenError, build, cross_compile, generate_c,
                               run_harness)
from mechatron.codegen.c.build import have_cross_compiler
from mechatron.codegen.compare import max_relative_difference
from mechatron.library import blocks

DT = 1e-4        # 10 kHz


@pytest.fixture(scope="module")
def motor():
    return mt.compile_model(mt.models.get("dc_motor").build())


@pytest.mark.parametrize("solver, iterations", [("rk4", 3), ("backward_euler", 2)])
def test_dc_motor_c_matches_desktop_fixed_step_at_10_khz(motor, tmp_path, solver,
                                                         iterations):
    code = generate_c(motor, tmp_path, solver=solver, dt=DT, iterations=iterations,
                      t_stop=0.2)
    build(code)
    c_res = run_harness(code)
    desk = mt.simulate(motor, 0.2, solver=solver, dt=DT, iterations=iterations)
    assert c_res.names == desk.names
    np.testing.assert_array_equal(c_res.t, desk.t)
    assert max_relative_difference(c_res, desk) <= 1e-12
    # and the physics: the final speed approaches k V / (R B + k^2)
    V, R, k, B = 19.2, 7.1, 0.151, 1.236e-4
    assert c_res.final("inertia.w") == pytest.approx(k * V / (R * B + k * k), rel=1e-3)


def test_generated_sources_have_no_dynamic_memory_and_no_mutable_globals(motor, tmp_path):
    code = generate_c(motor, tmp_path, solver="rk4", dt=DT)
    for fname in (f"{code.name}.c", f"{code.name}_casadi.c", f"{code.name}.h"):
        text = (tmp_path / fname).read_text()
        assert not re.search(r"\b(malloc|calloc|realloc|free)\s*\(", text), fname
        for line in text.splitlines():
            m = re.match(r"\s*static\s+(?!const\b)(?!int\b\s*\w+\()(?!void\b)(\w+)", line)
            assert m is None or "(" in line, f"{fname}: mutable static: {line}"
    header = (tmp_path / f"{code.name}.h").read_text()
    for api in ("_init(", "_step(", "_set_parameter(", "_get_output(",
                "_set_resistor_R(", "_get_inertia_w("):
        assert api in header


def test_harness_csv_has_the_columns_of_mechatron_simulate(motor, tmp_path, capsys):
    from mechatron.cli import main
    out = tmp_path / "desktop.csv"
    code = main(["simulate", "dc_motor", "--solver", "rk4", "--dt", "1e-4", "--t-stop",
                 "0.05", "--out", str(out)])
    assert code == 0, capsys.readouterr().err
    code = generate_c(motor, tmp_path / "c", solver="rk4", dt=DT, t_stop=0.05)
    build(code)
    c_res = run_harness(code, out=tmp_path / "c.csv")
    head_c = (tmp_path / "c.csv").read_text().splitlines()[0]
    head_d = out.read_text().splitlines()[0]
    assert head_c == head_d
    desk = mt.results.SimResult.load(out)
    assert max_relative_difference(c_res, desk) <= 1e-12


def test_parameters_are_tunable_in_the_generated_code(motor, tmp_path):
    code = generate_c(motor, tmp_path, solver="rk4", dt=DT, t_stop=0.1)
    build(code)
    params = {"source.V": 12.0, "resistor.R": 5.0}
    c_res = run_harness(code, params=params)
    desk = mt.simulate(motor, 0.1, solver="rk4", dt=DT, params=params)
    assert max_relative_difference(c_res, desk) <= 1e-12
    V, R, k, B = 12.0, 5.0, 0.151, 1.236e-4
    assert c_res.final("inertia.w") == pytest.approx(k * V / (R * B + k * k), rel=1e-2)
    # out-of-range values are refused by the C setter (bounds of the declarations)
    proc = subprocess.run([str(code.harness), "--set", "resistor.R=-1"],
                          capture_output=True, text=True)
    assert proc.returncode == 2 and "bounds" in proc.stderr


class PI(mt.Component):
    """PI controller: ``y = kp e + ki xi``, ``der(xi) = e`` with ``e = r - m``."""

    r = mt.Input("1", doc="Reference")
    m = mt.Input("1", doc="Measurement")
    y = mt.Output("1", doc="Command")
    xi = mt.Variable("1*s", start=0.0, doc="Integral of the error")
    kp = mt.Parameter("1", default=2.0, doc="Proportional gain")
    ki = mt.Parameter("1/s", default=5.0, doc="Integral gain")

    def equations(self):
        return [mt.der(self.xi) == self.r - self.m,
                self.y == self.kp * (self.r - self.m) + self.ki * self.xi]


class Lag(mt.Component):
    """First-order lag ``tau dy/dt = K u - y``."""

    u = mt.Input("1", doc="Input")
    y = mt.Output("1", start=0.0, doc="Output")
    K = mt.Parameter("1", default=1.5, doc="Gain")
    tau = mt.Parameter("s", default=0.05, doc="Time constant")

    def equations(self):
        return [self.tau * mt.der(self.y) == self.K * self.u - self.y]


def test_signal_block_controller_generates_c_the_same_way(tmp_path):
    m = mt.System("loop")
    ref = m.add("ref", blocks.Constant(value=1.0))
    pi = m.add("pi", PI())
    lag = m.add("lag", Lag())
    m.connect(ref.y, pi.r)
    m.connect(pi.y, lag.u)
    m.connect(lag.y, pi.m)
    cm = mt.compile_model(m)
    code = generate_c(cm, tmp_path, solver="rk4", dt=1e-3, t_stop=1.0)
    build(code)
    c_res = run_harness(code)
    desk = mt.simulate(cm, 1.0, solver="rk4", dt=1e-3)
    assert max_relative_difference(c_res, desk) <= 1e-12
    # independent solution of the linear loop: d/dt [y, xi] = A [y, xi] + b r
    kp, ki, K, tau = 2.0, 5.0, 1.5, 0.05
    A = np.array([[-(1 + K * kp) / tau, K * ki / tau], [-1.0, 0.0]])
    b = np.array([K * kp / tau, 1.0])
    x_exact = np.linalg.solve(A, (scipy.linalg.expm(A * 1.0) - np.eye(2)) @ b)
    assert c_res.final("lag.y") == pytest.approx(x_exact[0], abs=1e-9)
    assert c_res.final("pi.xi") == pytest.approx(x_exact[1], abs=1e-9)


def test_models_with_events_keep_their_modes_in_the_c_state(tmp_path):
    m = mt.System("rc_step")
    step = m.add("step", blocks.Step(t_step=0.01, initial=0.0, final=2.0))
    lag = m.add("lag", Lag(K=1.0, tau=0.02))
    m.connect(step.y, lag.u)
    cm = mt.compile_model(m)
    assert cm.nr >= 1        # the step's relation is part of the state
    code = generate_c(cm, tmp_path, solver="trapezoidal", dt=1e-3, iterations=2,
                      t_stop=0.1)
    build(code)
    c_res = run_harness(code)
    desk = mt.simulate(cm, 0.1, solver="trapezoidal", dt=1e-3, iterations=2)
    assert max_relative_difference(c_res, desk) <= 1e-12
    t = 0.1 - 0.01
    assert c_res.final("lag.y") == pytest.approx(2.0 * (1 - np.exp(-t / 0.02)), rel=2e-2)


def test_bad_requests_are_clear_errors(motor, tmp_path):
    with pytest.raises(CodegenError, match="unknown fixed-step solver 'rk5'"):
        generate_c(motor, tmp_path, solver="rk5", dt=DT)
    with pytest.raises(CodegenError, match="step size must be a number > 0"):
        generate_c(motor, tmp_path, solver="rk4", dt=0.0)
    (tmp_path / "file").write_text("x")
    with pytest.raises(CodegenError, match="not a directory"):
        generate_c(motor, tmp_path / "file", solver="rk4", dt=DT)


@pytest.mark.skipif(not have_cross_compiler(),
                    reason="arm-none-eabi-gcc not installed (apt-get install "
                           "gcc-arm-none-eabi libnewlib-arm-none-eabi)")
def test_cross_compiles_for_cortex_m4_and_reports_sizes(motor, tmp_path):
    code = generate_c(motor, tmp_path, solver="rk4", dt=DT)
    sizes = cross_compile(code)
    assert sizes["flash_bytes"] == sizes["text_bytes"] + sizes["data_bytes"]
    # the model instance (5 arrays of doubles and pointers) lives in RAM
    assert sizes["ram_bytes"] >= 8 * (2 + 2 + 6 + 43)
    assert 1000 < sizes["flash_bytes"] < 200_000


def test_state_updated_in_place_only_when_the_step_reads_it_whole_first():
    import casadi as ca

    from mechatron.codegen.c.generator import reads_state_before_writing
    x, u, p, t = ca.SX.sym("x", 2), ca.SX.sym("u", 0), ca.SX.sym("p"), ca.SX.sym("t")
    # x_next[0] = x[0]*p is written before x[1] is read: in place would be wrong
    late = ca.Function("late", [x, u, p, t], [x * p, x[0] + 1])
    # x_next[0] = x[0]*x[1]*p needs the whole state before the first write
    early = ca.Function("early", [x, u, p, t], [ca.vertcat(x[0] * x[1] * p, x[1] - x[0]),
                                                  x[0] + 1])
    assert not reads_state_before_writing(late)
    assert reads_state_before_writing(early)


@pytest.mark.parametrize("name", ["dc_motor", "dc_motor_speed_pi"])
def test_c_step_equals_desktop_bit_for_bit_in_place_or_through_scratch(name, tmp_path):
    """dc_motor's RK4 step updates the state in place, dc_motor_speed_pi's goes through
    the scratch copy; both give the desktop run's numbers exactly."""
    from mechatron.codegen.c.generator import prepare, reads_state_before_writing
    cm = mt.compile_model(mt.models.get(name).build())
    in_place = reads_state_before_writing(prepare(cm, solver="rk4", dt=DT).step)
    assert in_place == (name == "dc_motor")
    code = generate_c(cm, tmp_path, solver="rk4", dt=DT, t_stop=0.05)
    source = (tmp_path / f"{code.name}_casadi.c").read_text()
    assert "!=0)" not in source and "]? arg[" not in source     # no per-scalar tests
    build(code)
    c_res = run_harness(code)
    desk = mt.simulate(cm, 0.05, solver="rk4", dt=DT)
    assert c_res.names == desk.names
    for n in desk.names:
        np.testing.assert_array_equal(c_res[n], desk[n], err_msg=n)


def test_random_networks_generate_c_that_builds_and_matches_desktop(tmp_path, monkeypatch):
    """Networks of random subsystems (tests.compiler.test_random_networks): one with
    subsystems folded, whose CSV header (368 variables) is longer than a C99 compiler
    must take as one string literal, stepped in C exactly as on the desktop; one written
    out, with an algebraic loop of 13 unknowns solved by Newton iterations in each stage,
    to rounding (the loop's linear solves are not the desktop's operations in order)."""
    from tests.compiler.test_folding import unfolded
    from tests.compiler.test_random_networks import random_network
    folded = mt.compile_model(random_network(0)())
    looped = unfolded(monkeypatch, random_network(32))
    assert len(",".join(["t", *folded.names])) > 4095 and looped.nz == 13
    for cm, where in ((folded, "a"), (looped, "b")):
        code = generate_c(cm, tmp_path / where, solver="rk4", dt=1e-5, t_stop=0.002)
        build(code)
        c_res = run_harness(code)
        desk = mt.simulate(cm, 0.002, solver="rk4", dt=1e-5)
        assert c_res.names == desk.names
        if cm is folded:
            for n in desk.names:
                np.testing.assert_array_equal(c_res[n], desk[n], err_msg=n)
        else:
            assert max_relative_difference(c_res, desk) <= 1e-12


def test_relative_difference_scales_each_variable_by_its_kind():
    """A current that is zero in the physics (into a reference) comes out as rounding; it
    is compared on the scale of the model's currents, not on its own."""
    t = np.linspace(0.0, 1.0, 3)
    names, units = ["r.i", "gnd.i", "r.v"], ["A", "A", "V"]
    b = mt.SimResult(t, np.array([[2.0, 3.0, 4.0], [1e-15, -2e-15, 0.0], [1.0, 1.0, 1.0]]),
                     names, units)
    a = mt.SimResult(t, np.array([[2.0, 3.0, 4.0], [3e-15, 0.0, 1e-15], [1.0, 1.0, 1.0]]),
                     names, units)
    assert max_relative_difference(a, b) == pytest.approx(2e-15 / 4.0)
    # a voltage off by 1e-3 of the largest voltage is 1e-3 off, whatever the currents
    c = mt.SimResult(t, np.array([[2.0, 3.0, 4.0], [1e-15, -2e-15, 0.0],
                                  [1.0, 1.001, 1.0]]), names, units)
    assert max_relative_difference(c, b) == pytest.approx(1e-3)


def test_c_flushes_subnormals_as_the_desktop_does_and_matches_it_bit_for_bit(tmp_path):
    """An RC ladder of 120 sections stepped by RK4 at dt = RC / 1000: each stage carries
    the step at the source one section further, a thousand times smaller, so the far
    capacitors pass through subnormal values (below 1e-308; about 300 of them when
    unflushed), which the desktop's solvers flush to zero
    (mechatron.solvers.fpenv); the harness sets the same mode (mt_fpmode.h), so both give
    the same numbers and neither holds a subnormal."""
    from mechatron.solvers.fpenv import flushing_available
    from tests.solvers.test_logging import ladder
    if not flushing_available():
        pytest.skip("no known floating-point environment layout: the desktop runs unflushed")
    cm = mt.compile_model(ladder(120))
    code = generate_c(cm, tmp_path, solver="rk4", dt=1e-6, t_stop=3e-5)
    build(code)
    c_res = run_harness(code)
    desk = mt.simulate(cm, 3e-5, solver="rk4", dt=1e-6)
    tiny = np.finfo(float).tiny
    values = np.array([desk[n] for n in desk.names])
    assert np.sum((values != 0) & (np.abs(values) < 1e-290)) > 100   # flushed neighbours
    for n in desk.names:
        np.testing.assert_array_equal(c_res[n], desk[n], err_msg=n)
        assert not np.any((c_res[n] != 0) & (np.abs(c_res[n]) < tiny)), n
