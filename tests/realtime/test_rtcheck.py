"""rtcheck: stability functions, Jacobian eigenvalues, the sweep's errors against the exact
solution of the linear DC motor, recommendations (non-stiff and stiff), zero crossings."""

import json
import math

import numpy as np
import pytest
import scipy.linalg

import mechatron as mt
from mechatron.library import blocks
from mechatron.realtime.rtcheck import (EXPLICIT, IMPLICIT, jacobian_eigenvalues, rtcheck,
                                        stability_function, stable_step)
from mechatron.solvers import METHODS

V, R, L, k, J, B = 19.2, 7.1, 3.408e-4, 0.151, 4.8e-6, 1.236e-4
RATE = 10_000.0


def motor_matrix(L=L):
    return np.array([[-R / L, -k / L], [k / J, -B / J]])


def exact_motor(t, L=L):
    """[i, w](t) from rest under the voltage step, for every t."""
    A = motor_matrix(L)
    b = np.array([V / L, 0.0])
    return np.array([np.linalg.solve(A, (scipy.linalg.expm(A * tk) - np.eye(2)) @ b)
                     for tk in np.atleast_1d(t)]).T


@pytest.fixture(scope="module")
def motor():
    return mt.compile_model(mt.models.get("dc_motor").build())


def test_stability_functions_match_their_closed_forms():
    z = np.array([-0.5, -2.0 + 1j, 0.3j, -3.0])
    np.testing.assert_allclose(stability_function("euler", z), 1 + z)
    np.testing.assert_allclose(stability_function("heun", z), 1 + z + z**2 / 2)
    np.testing.assert_allclose(stability_function("rk4", z),
                               1 + z + z**2 / 2 + z**3 / 6 + z**4 / 24)
    np.testing.assert_allclose(stability_function("backward_euler", z), 1 / (1 - z))
    np.testing.assert_allclose(stability_function("trapezoidal", z), (1 + z / 2) / (1 - z / 2))
    # ode14x: order 3 (R - e^z = O(z^4)) and stiff decay (R -> 0 as z -> -inf)
    small = np.array([1e-2, 5e-3])
    err = np.abs(stability_function("ode14x", -small) - np.exp(-small))
    assert np.log2(err[0] / err[1]) == pytest.approx(4, abs=0.1)
    assert abs(stability_function("ode14x", -1e6)) < 1e-5


def test_stable_step_is_the_classical_stability_interval():
    assert stable_step("euler", [-1.0], h_max=10) == pytest.approx(2.0, rel=1e-5)
    assert stable_step("rk4", [-1.0], h_max=10) == pytest.approx(2.785293563, rel=1e-5)
    assert stable_step("backward_euler", [-1e9], h_max=1.0) == 1.0


def test_jacobian_eigenvalues_are_those_of_the_motor_matrix(motor):
    from mechatron.solvers.initial import initialize
    X0, z0, _ = initialize(motor, motor.p0, 0.0)
    eigs = jacobian_eigenvalues(motor, motor.p0, [(0.0, X0, z0)])
    np.testing.assert_allclose(np.sort_complex(eigs),
                               np.sort_complex(np.linalg.eigvals(motor_matrix())), rtol=1e-10)


@pytest.fixture(scope="module")
def check(motor):
    return rtcheck(motor, rate=RATE, t_stop=0.05, outputs=["inductor.i", "inertia.w"],
                   solvers=["rk4", "backward_euler"], substeps=(1, 2, 4), iterations=(2,),
                   timing_steps=20_000)


def test_reported_errors_at_10_khz_are_the_errors_against_the_exact_solution(motor, check):
    t = np.arange(0, 501) / RATE
    exact = exact_motor(t)
    peaks = np.max(np.abs(exact), axis=1)
    for solver, its in (("rk4", 3), ("backward_euler", 2)):
        run = mt.simulate(motor, 0.05, solver=solver, dt=1 / RATE, iterations=its)
        got = np.vstack([run["inductor.i"], run["inertia.w"]])
        true_err = np.max(np.max(np.abs(got - exact), axis=1) / peaks)
        row = next(c for c in check.candidates if c.solver == solver and c.steps_per_period == 1)
        # the reference is CVODES at rtol 1e-10: the reported error is the true one
        assert row.max_error == pytest.approx(true_err, rel=1e-4)
        assert true_err <= row.max_error * (1 + 1e-4)


def test_recommends_a_working_configuration_for_the_dc_motor(motor, check):
    best = check.recommended
    assert best is not None and best.ok
    assert best.solver == "rk4"                 # not stiff at 10 kHz: explicit preferred
    assert "not stiff" in " ".join(check.reasons)
    run = mt.simulate(motor, 0.05, solver=best.solver, dt=best.dt,
                      iterations=best.iterations or 1)
    idx = np.arange(0, len(run.t), best.steps_per_period)
    exact = exact_motor(run.t[idx])
    got = np.vstack([run["inductor.i"][idx], run["inertia.w"][idx]])
    err = np.max(np.max(np.abs(got - exact), axis=1) / np.max(np.abs(exact), axis=1))
    assert err <= check.tolerance
    assert best.ns_per_step > 0 and best.margin >= check.min_margin
    assert best.margin == pytest.approx(
        1 - best.steps_per_period * best.ns_per_step * 1e-9 * RATE)
    assert check.zero_crossings == {}


def test_stiff_motor_gets_an_implicit_solver_and_the_reason(motor):
    r = rtcheck(motor, rate=RATE, t_stop=0.02, params={"inductor.L": 1e-8},
                substeps=(1, 2), iterations=(1, 2), measure=False)
    assert r.recommended.solver in IMPLICIT
    assert r.recommended.solver != "trapezoidal"       # not L-stable: rings
    assert all(not math.isfinite(c.max_error) and not c.stable
               for c in r.candidates if c.solver in EXPLICIT)
    text = " ".join(r.reasons)
    assert "stiff at this rate" in text and "implicit" in text
    # the fastest eigenvalue is -R/L (the armature), as the physics says
    assert r.stiffness["fastest"][0] == pytest.approx(-R / 1e-8, rel=1e-3)
    assert r.stiffness["stable_step"]["rk4"] == pytest.approx(2.7853 * 1e-8 / R, rel=1e-3)


class Lag(mt.Component):
    """First-order lag ``tau dy/dt = u - y``."""

    u = mt.Input("1", doc="Input")
    y = mt.Output("1", start=0.0, doc="Output")
    tau = mt.Parameter("s", default=0.01, doc="Time constant")

    def equations(self):
        return [self.tau * mt.der(self.y) == self.u - self.y]


def test_zero_crossings_are_reported_by_component():
    m = mt.System("stepped")
    step = m.add("step", blocks.Step(t_step=0.0123, final=1.0))
    lag = m.add("lag", Lag())
    m.connect(step.y, lag.u)
    r = rtcheck(mt.compile_model(m), rate=1000.0, t_stop=0.05, solvers=["rk4"],
                substeps=(1,), measure=False)
    assert set(r.zero_crossings) == {"step"} and r.zero_crossings["step"] == 1
    assert r.event_times["step"] == pytest.approx(0.0123, abs=1e-6)


def test_bad_input_is_a_clear_error(motor):
    with pytest.raises(mt.errors.SimulationError, match="rate must be"):
        rtcheck(motor, rate=0.0)
    with pytest.raises(mt.errors.SimulationError, match="unknown fixed-step solver"):
        rtcheck(motor, rate=RATE, solvers=["rk5"])


def test_rtcheck_command_json(capsys):
    from mechatron.cli import main
    code = main(["rtcheck", "dc_motor", "--rate", "10000", "--t-stop", "0.01", "--set",
                 "L=1e-8", "--solvers", "rk4,backward_euler", "--no-timing", "--json"])
    out = capsys.readouterr()
    assert code == 0, out.err
    doc = json.loads(out.out)
    assert doc["recommended"]["solver"] == "backward_euler"
    assert set(METHODS) >= {c["solver"] for c in doc["candidates"]}
    code = main(["rtcheck", "dc_motor", "--rate", "-5"])
    assert code == 2 and "--rate" in capsys.readouterr().err


def test_rtcheck_command_table(capsys):
    from mechatron.cli import main
    code = main(["rtcheck", "dc_motor", "--rate", "10000", "--t-stop", "0.01",
                 "--solvers", "rk4", "--no-timing"])
    out = capsys.readouterr().out
    assert code == 0
    assert "zero crossings: none" in out and "recommended: rk4" in out


def test_rtcheck_progress_line(capsys, monkeypatch):
    """rtcheck ran 41 s without a word. It reports every stage: the reference, each run
    of the sweep; the command shows them as a bar on a terminal (after the delay, here
    0 s), none with -q."""
    import io
    import sys
    from mechatron import cli
    seen = []
    rtcheck(mt.models.get("dc_motor").build("acausal"), rate=RATE, t_stop=0.01,
            solvers=["rk4", "backward_euler"], iterations=(1, 2), substeps=(1, 2),
            measure=False, progress=lambda done, total, what: seen.append((done, total)))
    # the reference, rk4 at 2 substeps, backward Euler at 2 iteration counts x 2
    assert seen == [(k, 7) for k in range(1, 8)]

    class Terminal(io.StringIO):
        def isatty(self):
            return True
    monkeypatch.setattr(cli, "PROGRESS_DELAY", 0.0)
    for quiet, shown in (([], True), (["-q"], False)):
        term = Terminal()
        monkeypatch.setattr(sys, "stderr", term)
        code = cli.main(["rtcheck", "dc_motor", "--rate", "10000", "--t-stop", "0.01",
                         "--solvers", "rk4", "--no-timing", *quiet])
        assert code == 0
        assert ("rtcheck" in term.getvalue()) is shown, term.getvalue()
        if shown:
            assert "/4 " in term.getvalue()       # the reference and three substeps


def test_a_sweep_too_large_for_memory_is_refused_not_called_diverged():
    """1000 s at 10 kHz is 1e7 fixed steps per run: the runs are refused by simulate's
    memory estimate, and rtcheck says so instead of listing every method as diverged."""
    from mechatron.errors import RunTooLargeError
    with pytest.raises(RunTooLargeError, match="1e\\+07 fixed steps"):
        rtcheck(mt.models.get("dc_motor").build("acausal"), rate=1e4, t_stop=1000.0,
                solvers=["rk4"], substeps=(1,), measure=False)
