"""The HIL controller as a diagram of signal blocks (:mod:`mechatron.library.blocks`).

One discrete controller, sampled at the plant's step ``dt``, for both experiments of
:mod:`mechatron.realtime.loop`::

    count ──┬──────────────────────────────► c ──► d1 ─► d2 ─► ... ─► dM     (UnitDelay)
    valid ──┘  c = valid count + (1 - valid) c_ext,  c_ext = d1 + (d1 - dM) / (M - 1)
    w_meas = 2 pi (c - dM) / (4 lines M dt)                 speed over the last M samples
    y_meas = w_meas (speed)  or  2 pi c / (4 lines) (position)
    ref    = r1 + r2 + ...                                   Step blocks, one per change
    e      = ref - y_meas,   v = e - (Kd / Kp) w_meas         (v = e when Kd = 0)
    u      = DiscretePID(Kp, Ki; limits -V_s .. V_s, clamping anti-windup) of v
    duty   = u / (2 V_s) + 1/2                              (locked anti-phase: 1/2 is 0 V)

- ``count`` and ``valid`` are the controller's **inputs**: :class:`~mechatron.library.
  blocks.Constant` blocks whose parameter ``value`` the caller sets before every step
  (``count.value``: the encoder count at ``t_k``; ``valid.value``: 1, or 0 for a sample
  lost on the way, which the controller then extrapolates from its window so that its
  integrator and window stay on the plant's time base). Mechatron models have no external
  inputs yet (the step function's ``u`` has size 0), so a tunable parameter is the input:
  in the generated C it is set with ``hilctrl_set_count_value``.
- ``duty.y`` is the **output**, with ``ref.y``, ``y_meas`` and ``pid.y`` (the voltage
  command ``u``) for the log.
- For position control ``Kd`` acts on the measured speed (rate feedback), not on the
  error: ``u = Kp e - Kd w_meas``, without the derivative kick of a reference step. With
  ``Ki != 0`` and ``Kd != 0`` the integrator integrates ``v``, not ``e``.
- The reference changes at the first sample instant ``>= t0 - dt/2`` of each change at
  ``t0`` (the half step makes the switch immune to the rounding of ``k dt``).

**Timing.** The model's sample clocks tick at ``k dt``. Its fixed-step function is run
with the start time ``-dt``: the ``k``-th call (``k = 0, 1, ...``) steps from
``(k-1) dt`` to ``k dt``, and the tick at its end reads the inputs set before the call.
So the duty computed from the count of ``t_k`` is the output of call ``k``, with no
extra delay; desktop MIL and the generated C (``mechatron.codegen.generate_c(...,
t0=-dt)``) make the same calls.

Limitations: the speed window ``M = max(2, round(window_s / dt))`` is a chain of ``M``
unit delays (10 at 10 kHz); the extrapolation assumes the speed is constant over the
window.
"""

from __future__ import annotations

import math

import mechatron as mt
from mechatron.library import blocks as bl

__all__ = ["build_controller", "CONTROLLER_INPUTS", "CONTROLLER_OUTPUTS", "CONTROLLER_T0",
           "CONTROLLER_SOLVER"]

#: Parameters that carry the controller's inputs (set before every step).
CONTROLLER_INPUTS = ("count.value", "valid.value")
#: Logged variables that make up the controller's output ``[duty, ref, y_meas, u]``.
CONTROLLER_OUTPUTS = ("duty.y", "ref.y", "y_meas.y", "pid.y")
#: The fixed-step method of the controller model (its states only jump at ticks, so the
#: cheapest explicit method is exact) and its start time in units of ``dt``.
CONTROLLER_SOLVER = "euler"
CONTROLLER_T0 = -1.0


def build_controller(experiment, dt: float, *, lines: int, V_s: float) -> mt.System:
    """The controller of ``experiment`` (an
    :class:`~mechatron.realtime.experiments.Experiment`) sampled every ``dt`` s, for an
    encoder of ``lines`` lines (x4 quadrature) and an H-bridge supply ``V_s``; see the
    module docstring for the diagram."""
    exp = experiment
    M = max(2, int(round(exp.window_s / dt)))
    cpr = 4 * int(lines)
    m = mt.System(f"hil_controller_{exp.name}",
                  doc=f"HIL {exp.quantity} controller, sampled every {dt:g} s")
    count = m.add("count", bl.Constant(value=0.0, doc="Input: encoder count at t_k"))
    valid = m.add("valid", bl.Constant(
        value=1.0, doc="Input: 1 for a received sample, 0 for a lost one"))
    one = m.add("one", bl.Constant(value=1.0))

    # the count used: the input, or the window's extrapolation when the sample was lost
    delays = [m.add(f"d{j + 1}", bl.UnitDelay(Ts=dt)) for j in range(M)]
    first, last = delays[0], delays[-1]
    slope = m.add("slope", bl.Add(k1=1.0 / (M - 1), k2=-1.0 / (M - 1)))
    m.connect(first.y, slope.u1)
    m.connect(last.y, slope.u2)
    c_ext = m.add("c_ext", bl.Add())
    m.connect(first.y, c_ext.u1)
    m.connect(slope.y, c_ext.u2)
    invalid = m.add("invalid", bl.Add(k1=-1.0))          # 1 - valid
    m.connect(valid.y, invalid.u1)
    m.connect(one.y, invalid.u2)
    take = m.add("take", bl.Product())
    m.connect(valid.y, take.u1)
    m.connect(count.y, take.u2)
    fill = m.add("fill", bl.Product())
    m.connect(invalid.y, fill.u1)
    m.connect(c_ext.y, fill.u2)
    c = m.add("c", bl.Add())                 # exactly the input when valid = 1
    m.connect(take.y, c.u1)
    m.connect(fill.y, c.u2)
    m.connect(c.y, first.u)
    for a, b in zip(delays, delays[1:]):
        m.connect(a.y, b.u)

    # measurement: speed over the window, or the angle
    g = 2 * math.pi / (cpr * M * dt)
    w_meas = m.add("w_meas", bl.Add(k1=g, k2=-g))
    m.connect(c.y, w_meas.u1)
    m.connect(last.y, w_meas.u2)
    if exp.quantity == "speed":
        y_meas = m.add("y_meas", bl.Gain(k=1.0))
        m.connect(w_meas.y, y_meas.u)
    else:
        y_meas = m.add("y_meas", bl.Gain(k=2 * math.pi / cpr))
        m.connect(c.y, y_meas.u)

    # reference: one Step block per change, summed
    level = 0.0
    steps = []
    for i, (t0, value) in enumerate(exp.reference):
        steps.append(m.add(f"r{i + 1}", bl.Step(t_step=t0 - dt / 2, initial=0.0,
                                               final=value - level)))
        level = value
    ref = steps[0]
    for i, s in enumerate(steps[1:]):
        add = m.add("ref" if i == len(steps) - 2 else f"ref_{i + 2}", bl.Add())
        m.connect(ref.y, add.u1)
        m.connect(s.y, add.u2)
        ref = add
    if len(steps) == 1:
        ref = m.add("ref", bl.Gain(k=1.0))
        m.connect(steps[0].y, ref.u)

    # error, rate feedback, PID with saturation and anti-windup, duty
    e = m.add("e", bl.Subtract())
    m.connect(ref.y, e.u1)
    m.connect(y_meas.y, e.u2)
    pid = m.add("pid", bl.DiscretePID(Kp=exp.Kp, Ki=exp.Ki, y_min=-V_s, y_max=V_s, Ts=dt))
    if exp.Kd:
        v = m.add("v", bl.Add(k1=1.0, k2=-exp.Kd / exp.Kp))
        m.connect(e.y, v.u1)
        m.connect(w_meas.y, v.u2)
        m.connect(v.y, pid.u)
    else:
        m.connect(e.y, pid.u)
    duty = m.add("duty", bl.Add(k1=1.0 / (2 * V_s), k2=0.5))
    m.connect(pid.y, duty.u1)
    m.connect(one.y, duty.u2)
    return m
