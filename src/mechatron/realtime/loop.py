"""The closed loop of the HIL experiments: plant and controller step functions, and MIL.

Three CasADi functions describe everything that runs per step; the same functions are
simulated together on the desktop (model-in-the-loop, :func:`run_mil`) and generated as C
for the separate plant and controller processes (SIL) or the firmware (PIL):

``plant_out(x) -> meas``
    Measurements at the current point: ``[count, w, phi, v_c, i]`` (encoder count,
    speed in rad/s, angle in rad, RC filter voltage, armature current).
``plant_step(x, duty, k) -> x_next``
    One fixed-step solver step (``mechatron.solvers.fixed.make_step`` of the compiled
    :class:`~mechatron.realtime.plant.HILPlant`; trapezoidal by default, A-stable for the
    48 us armature time constant at any rate, where RK4 diverges below ~7 kHz) over
    ``[k dt, (k+1) dt]`` with the pin
    voltage set to the PWM average over that step (:func:`~mechatron.realtime.plant.pwm_average`).
``ctrl_step(xc, count, k, valid) -> (xc_next, out)``
    The discrete controller, ``out = [duty, ref, y_meas, u]``: a diagram of signal
    blocks (:func:`mechatron.realtime.controller.build_controller`: unit delays for the
    speed window, Step blocks for the reference, ``DiscretePID`` with saturation and
    clamping anti-windup), compiled, and stepped by the fixed-step function that
    ``mechatron.codegen.generate_c`` emits as C for SIL and PIL (``count`` and ``valid``
    are parameters of the model set before each call; the call ``k`` ends at the tick
    ``k dt``).

Timing of one step ``k`` (identical in MIL, SIL and PIL): the plant samples the encoder
at ``t_k``, the controller turns that count into a duty ``d_k``, and the plant applies
``d_k`` over ``[t_k, t_k+1]``. In SIL/PIL a duty that has not arrived by the plant's
reply deadline is replaced by the previous one (a *missed* step).

The controller computes (see :mod:`mechatron.realtime.controller`)::

    y_meas = w_meas   (speed)  or  phi_meas = 2 pi count / (4 lines)   (position)
    w_meas = 2 pi (count_k - count_{k-M}) / (4 lines M dt)
             (M = max(2, round(window_s / dt)) samples: 10 at 10 kHz)
    e = ref(t_k) - y_meas
    u = Kp e + I - Kd w_meas,   u_sat = min(max(u, -V_s), V_s)
    I_{k+1} = I + Ki dt e   unless u is saturated and e pushes further (clamping)
    duty = 1/2 + u_sat / (2 V_s)      (locked anti-phase H-bridge: 1/2 is 0 V)

``valid = 0`` marks a sample lost on the way: the controller then extrapolates the count
from its window, ``count_k = count_{k-1} + (count_{k-1} - count_{k-M}) / (M - 1)``, and
runs as usual, so its integrator and window stay on the plant's time base.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import casadi as ca
import numpy as np

import mechatron as mt
from mechatron.codegen.c.generator import prepare
from mechatron.compiler.compiled import CompiledModel
from mechatron.errors import SimulationError
from mechatron.realtime.controller import (CONTROLLER_INPUTS, CONTROLLER_OUTPUTS,
                                           CONTROLLER_SOLVER, CONTROLLER_T0,
                                           build_controller)
from mechatron.realtime.experiments import EXPERIMENTS, Experiment
from mechatron.realtime.plant import PLANT_DEFAULTS, build_plant, pwm_average
from mechatron.solvers.fixed import make_step
from mechatron.solvers.initial import initialize

__all__ = ["Experiment", "EXPERIMENTS", "LoopFunctions", "build_loop", "run_mil",
           "MEAS_NAMES", "CTRL_OUT_NAMES", "window_samples"]

MEAS_NAMES = ("count", "w", "phi", "v_c", "i")
#: C prefix of the generated controller (``hilctrl.h``: ``hilctrl_step``, ...).
CONTROLLER_NAME = "hilctrl"
CTRL_OUT_NAMES = ("duty", "ref", "y_meas", "u")


@dataclass
class LoopFunctions:
    """The three step functions of one experiment, with their start values."""

    experiment: Experiment
    dt: float
    f_pwm: float
    method: str
    plant_out: ca.Function
    plant_step: ca.Function
    ctrl_step: ca.Function
    plant_x0: ca.Function          # () -> x0, for the generated code
    ctrl_x0: ca.Function
    x0: np.ndarray
    xc0: np.ndarray
    state_names: list[str] = field(default_factory=list)
    lines: int = PLANT_DEFAULTS["lines"]
    controller: CompiledModel | None = None   # the compiled block diagram
    ctrl_t0: float = 0.0                      # its start time, -dt


def window_samples(exp: Experiment, dt: float) -> int:
    """Samples ``M`` of the speed window at step ``dt`` (at least 2)."""
    return max(2, int(round(exp.window_s / dt)))


def build_loop(experiment: str | Experiment = "speed", *, rate: float = 10_000.0,
               f_pwm: float = PLANT_DEFAULTS["f_pwm"], method: str = "trapezoidal",
               lines: int = PLANT_DEFAULTS["lines"], **plant_params) -> LoopFunctions:
    """Build the plant and controller step functions of an experiment at ``rate`` Hz."""
    exp = EXPERIMENTS.get(experiment) if isinstance(experiment, str) else experiment
    if exp is None:
        raise SimulationError(f"hil: unknown experiment '{experiment}'. Choose one of "
                              f"{', '.join(EXPERIMENTS)}.")
    if not (math.isfinite(rate) and rate > 0):
        raise SimulationError(f"hil: the rate must be a number of Hz > 0, got {rate!r}.")
    if not (math.isfinite(f_pwm) and f_pwm > 0):
        raise SimulationError(f"hil: the PWM frequency must be > 0 Hz, got {f_pwm!r}.")
    dt = 1.0 / rate
    if not (exp.window_s > 0):
        raise SimulationError(f"hil experiment '{exp.name}': the speed window must be "
                              f"> 0 s, got {exp.window_s!r}.")
    if not exp.reference:
        raise SimulationError(f"hil experiment '{exp.name}': the reference has no step; "
                              "give at least one (t_start, value).")
    if exp.Kd and not exp.Kp:
        raise SimulationError(f"hil experiment '{exp.name}': Kd = {exp.Kd!r} needs "
                              "Kp != 0 (the rate feedback enters as e - (Kd/Kp) w_meas).")
    cm = mt.compile_model(build_plant(**plant_params))
    step = make_step(cm, method, dt)
    p0 = cm.parameter_vector()
    X0, z0, _ = initialize(cm, p0)
    ipwm = cm.param_names.index("pwm.V")
    V_io = float(p0[cm.param_names.index("bridge.V_io")])
    V_s = float(p0[cm.param_names.index("bridge.V_s")])
    idx = {n: cm.state_names.index(n) for n in
           ("c_f.v", "inductor.i", "inertia.w", "encoder.phi")}
    cpr = 4 * int(lines)                     # counts per revolution

    x = ca.SX.sym("x", cm.nX + cm.nz)
    duty = ca.SX.sym("duty")
    k = ca.SX.sym("k")
    count = ca.floor(x[idx["encoder.phi"]] * cpr / (2 * math.pi))
    meas = ca.vertcat(count, x[idx["inertia.w"]], x[idx["encoder.phi"]], x[idx["c_f.v"]],
                      x[idx["inductor.i"]])
    plant_out = ca.Function("plant_out", [x], [meas], ["x"], ["meas"])
    p = ca.SX(ca.DM(p0))
    p[ipwm] = pwm_average(duty, k, dt, f_pwm, V_io)
    x_next, _ = step(x, ca.SX(0, 1), p, k * dt)
    plant_step = ca.Function("plant_step", [x, duty, k], [x_next],
                             ["x", "duty", "k"], ["x_next"])

    ctrl_cm = mt.compile_model(build_controller(exp, dt, lines=lines, V_s=V_s))
    prep = prepare(ctrl_cm, solver=CONTROLLER_SOLVER, dt=dt, t0=CONTROLLER_T0 * dt,
                   name=CONTROLLER_NAME)
    ctrl_step = _controller_step(prep)
    x0 = np.concatenate([np.asarray(X0, float), np.asarray(z0, float)])
    xc0 = np.asarray(prep.x_start, dtype=float)
    return LoopFunctions(
        experiment=exp, dt=dt, f_pwm=f_pwm, method=method, plant_out=plant_out,
        plant_step=plant_step, ctrl_step=ctrl_step,
        plant_x0=ca.Function("plant_x0", [], [ca.DM(x0)], [], ["x0"]),
        ctrl_x0=ca.Function("ctrl_x0", [], [ca.DM(xc0)], [], ["xc0"]),
        x0=x0, xc0=xc0, state_names=list(cm.state_names), lines=int(lines),
        controller=ctrl_cm, ctrl_t0=prep.t0)


def _controller_step(prep) -> ca.Function:
    """``ctrl_step(xc, count, k, valid) -> (xc_next, [duty, ref, y_meas, u])``: call ``k``
    of the controller model's fixed-step function (the function the C generator emits),
    from ``t0 + k dt`` to ``t0 + (k+1) dt`` with ``t0 = -dt``, its inputs set to
    ``count`` and ``valid`` and the other parameters at their values."""
    cm = prep.cm
    xc = ca.SX.sym("xc", prep.x_start.size)
    count, k, valid = ca.SX.sym("count"), ca.SX.sym("k"), ca.SX.sym("valid")
    p = ca.SX(ca.DM(prep.p))
    for name, value in zip(CONTROLLER_INPUTS, (count, valid)):
        p[cm.param_names.index(name)] = value
    t = prep.t0 + prep.dt * k              # as the generated C: t0 + DT * k
    xc_next, y = prep.step(xc, ca.SX(prep.step.size1_in(1), 1), p, t)
    out = ca.vertcat(*[y[cm.names.index(n)] for n in CONTROLLER_OUTPUTS])
    return ca.Function("ctrl_step", [xc, count, k, valid], [xc_next, out],
                       ["xc", "count", "k", "valid"], ["xc_next", "out"])


#: Columns of a MIL/SIL log, in order (the C runner writes the same).
LOG_COLUMNS = ("t", "duty", "ref", "count", "w", "phi", "v_c", "i")


def run_mil(loop: LoopFunctions, steps: int) -> dict[str, np.ndarray]:
    """Model-in-the-loop: plant and controller in one native loop (``mapaccum``).

    Returns the log by column (:data:`LOG_COLUMNS`), one row per step ``k``: the plant's
    measurements at ``t_k`` and the duty applied over ``[t_k, t_k+1]``.
    """
    if steps < 1:
        raise SimulationError(f"hil MIL: need at least one step, got {steps}.")
    nx = loop.x0.size
    nxc = loop.xc0.size
    X = ca.SX.sym("X", nx + nxc + 1)          # [x; xc; k]
    x, xc, k = X[:nx], X[nx:nx + nxc], X[nx + nxc]
    meas = loop.plant_out(x)
    xc_next, out = loop.ctrl_step(xc, meas[0], k, 1)
    x_next = loop.plant_step(x, out[0], k)
    row = ca.vertcat(k * loop.dt, out[0], out[1], meas)
    f = ca.Function("mil_step", [X], [ca.vertcat(x_next, xc_next, k + 1), row])
    chunk = 2000
    runs: dict[int, ca.Function] = {}
    state = np.concatenate([loop.x0, loop.xc0, [0.0]])
    rows = []
    done = 0
    while done < steps:     # Python runs once per chunk of native steps, not per step
        m = min(chunk, steps - done)
        if m not in runs:
            runs[m] = f.mapaccum(f"mil_run_{m}", m)
        xs, ys = runs[m](state)
        xs = np.array(xs, dtype=float).reshape(-1, m)
        rows.append(np.array(ys, dtype=float).reshape(-1, m))
        state = xs[:, -1]
        done += m
    Y = np.hstack(rows)
    return {name: Y[i] for i, name in enumerate(LOG_COLUMNS)}
