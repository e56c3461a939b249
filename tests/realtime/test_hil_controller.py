"""The HIL controller: a diagram of signal blocks, generated as C by mechatron.codegen, and
that C (driven through the controller core of SIL and PIL) against the block model's own
desktop fixed-step run."""

import shutil
import subprocess

import casadi as ca
import numpy as np
import pytest

from mechatron.errors import SimulationError
from mechatron.realtime.cgen import C_DIR, CTRL_DIR, generate_controller
from mechatron.realtime.controller import (CONTROLLER_INPUTS, CONTROLLER_OUTPUTS,
                                           CONTROLLER_SOLVER)
from mechatron.realtime.loop import Experiment, build_loop, run_mil, window_samples
from mechatron.solvers.fixed import make_step
from mechatron.solvers.initial import initialize

# Feeds SAMPLE packets ("seq count" per line; a missing seq is a lost sample) to the
# controller core of mt_controller and the firmware, prints each COMMAND it answers.
DRIVER = r"""
#include <stdio.h>
#include <string.h>
#include "ctrl_core.h"

int main(void)
{
    static mt_ctrl c;
    mt_packet in, out;
    unsigned seq;
    double count;
    mt_ctrl_init(&c);
    memset(&in, 0, sizeof in);
    while (scanf("%u %lf", &seq, &count) == 2) {
        in.type = MT_SAMPLE;
        in.seq = seq;
        in.a = count;
        if (mt_ctrl_handle(&c, &in, &out) == 1) {
            printf("%u %.17g %.17g\n", (unsigned)out.seq, out.a, out.b);
        }
    }
    printf("%u %u %u\n", c.lost_samples, c.steps, c.bad_inputs);
    return 0;
}
"""


def _desktop_run(loop, counts, valid):
    """The compiled block model stepped by its own fixed-step function (make_step, as
    mt.simulate's fixed-step run), parameters numeric per step: the inputs in
    count.value/valid.value, time -dt + k dt. Returns the outputs by name."""
    cm, dt = loop.controller, loop.dt
    n = counts.size
    step = make_step(cm, CONTROLLER_SOLVER, dt)
    p = cm.parameter_vector()
    X0, z0, _ = initialize(cm, p, -dt)
    P = np.repeat(p.reshape(-1, 1), n, axis=1)
    P[cm.param_names.index(CONTROLLER_INPUTS[0])] = counts
    P[cm.param_names.index(CONTROLLER_INPUTS[1])] = valid
    T = (-dt + dt * np.arange(n)).reshape(1, -1)
    x0 = np.concatenate([np.asarray(X0, float), np.asarray(z0, float)])
    _, Y = step.mapaccum("run", n)(x0, ca.DM.zeros(0, n), P, T)
    Y = np.array(Y)
    return {name: Y[cm.names.index(name)] for name in CONTROLLER_OUTPUTS}


@pytest.mark.skipif(shutil.which("cc") is None, reason="no C compiler (cc)")
@pytest.mark.parametrize("name", ["speed", "position"])
def test_generated_controller_c_matches_the_desktop_fixed_step_run(name, tmp_path):
    loop = build_loop(name, rate=10_000.0)
    code = generate_controller(loop, tmp_path / CTRL_DIR)
    assert {f"{code.name}.h", f"{code.name}.c", f"{code.name}_casadi.c"} <= set(code.files)
    for f in ("ctrl_core.c", "ctrl_core.h", "mt_packet.c", "mt_packet.h"):
        shutil.copy(C_DIR / f, tmp_path / f)
    (tmp_path / "driver.c").write_text(DRIVER)
    subprocess.run(["cc", "-std=c99", "-O2", "-Wall", "-Wextra", "-Werror", "-pedantic",
                    "-ffp-contract=off", "-I", CTRL_DIR, "-o", "driver", "driver.c",
                    "ctrl_core.c", "mt_packet.c", f"{CTRL_DIR}/{code.name}.c",
                    f"{CTRL_DIR}/{code.name}_casadi.c", "-lm"], cwd=tmp_path, check=True)

    # a recorded input sequence: the encoder counts of a closed-loop MIL run through the
    # reference step at 0.05 s, with 3 % of the samples and one burst of 6 lost
    n = 1500
    counts = run_mil(loop, n)["count"]
    rng = np.random.default_rng(3)
    valid = rng.uniform(size=n) > 0.03
    valid[700:706] = False
    valid[0] = valid[-1] = True
    feed = "".join(f"{k} {counts[k]:.17g}\n" for k in range(n) if valid[k])
    proc = subprocess.run([str(tmp_path / "driver")], input=feed, capture_output=True,
                          text=True, check=True)
    lines = proc.stdout.split("\n")
    rows = np.array([[float(v) for v in line.split()] for line in lines[:-2]])
    lost, steps, bad = (int(v) for v in lines[-2].split())
    assert (lost, steps, bad) == (int(np.sum(~valid)), n, 0)
    seq = rows[:, 0].astype(int)
    np.testing.assert_array_equal(seq, np.nonzero(valid)[0])

    # the controller's input for a lost sample is its own extrapolation (count unused)
    desk = _desktop_run(loop, np.where(valid, counts, 0.0), valid.astype(float))
    np.testing.assert_allclose(rows[:, 1], desk["duty.y"][seq], rtol=0, atol=1e-12)
    np.testing.assert_allclose(rows[:, 2], desk["ref.y"][seq], rtol=0, atol=1e-12)
    # and MIL's ctrl_step (the same model with the inputs spliced in) is that run too
    xc, duty = loop.xc0, []
    for k in range(n):
        xc, out = loop.ctrl_step(xc, counts[k] if valid[k] else 0.0, k, float(valid[k]))
        duty.append(float(out[0]))
    np.testing.assert_allclose(duty, desk["duty.y"], rtol=0, atol=1e-12)
    # the run did control something: the duty left 1/2 after the reference step
    assert np.ptp(rows[:, 1]) > 0.05


def test_controller_is_a_block_diagram_with_the_speed_window_as_unit_delays():
    loop = build_loop("speed", rate=5_000.0)
    cm = loop.controller
    M = window_samples(loop.experiment, loop.dt)
    assert M == 5
    assert [f"d{j}.x" for j in range(1, M + 1)] == [n for n in cm.state_names
                                                     if n.endswith(".x")]
    assert {"pid.I", "pid.e_prev"} <= set(cm.state_names)
    for name in CONTROLLER_INPUTS:
        assert name in cm.param_names
    assert cm.param_names.count("pid.Ts") == 1
    assert float(cm.parameter_vector()[cm.param_names.index("pid.Ts")]) == loop.dt


@pytest.mark.parametrize("kwargs,match", [
    (dict(reference=()), "the reference has no step"),
    (dict(reference=((0.0, 1.0),), Kp=0.0, Kd=0.1), "needs Kp != 0"),
])
def test_bad_experiment_is_a_clear_error(kwargs, match):
    exp = Experiment(**{**dict(name="x", quantity="speed", reference=((0.0, 1.0),), Kp=1.0,
                               Ki=0.0), **kwargs})
    with pytest.raises(SimulationError, match=match):
        build_loop(exp, rate=1000.0)
