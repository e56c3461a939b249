"""The plant side of a HIL run over any I/O backend (:mod:`mechatron.realtime.io`).

:func:`run_plant` steps the experiment's plant (:func:`mechatron.realtime.loop.
build_loop`: ``plant_out``, ``plant_step``) against a controller on the other end of a
:class:`~mechatron.realtime.io.PlantIO`: a microcontroller on a serial line, a card, a
process over UDP. Python runs once per step here (about 20-40 us a step), so this loop
serves links slower than that (a 115200 baud serial line carries ~300 steps/s); the
10 kHz SIL loop is C (:func:`mechatron.realtime.hil.run_hil`, ``transport="sim"``).
"""

from __future__ import annotations

import math
import time

import numpy as np

from mechatron.errors import SimulationError
from mechatron.realtime.io.base import PlantIO
from mechatron.realtime.loop import LOG_COLUMNS, LoopFunctions, build_loop

__all__ = ["run_plant"]


def run_plant(io: PlantIO, name: str | LoopFunctions = "speed", *, rate: float = 200.0,
              duration: float = 1.0, wait: float = 0.8, lockstep: float | None = None,
              hello_timeout: float = 10.0) -> dict:
    """Run the plant of experiment ``name`` at ``rate`` Hz for ``duration`` s over ``io``.

    Each step ``k`` at ``t_k = k / rate`` (absolute schedule): measure, ``io.write``,
    ``io.read`` until ``t_k + wait / rate`` (with ``lockstep`` set: until that many
    seconds after the write, and the schedule restarts after each step), advance the
    plant with the command's duty, or the previous one when none came (a lost sample).

    Returns ``{"log": {column: array}, "stats": {...}}``: the log's columns are
    :data:`~mechatron.realtime.loop.LOG_COLUMNS` plus ``got`` and ``wake_late_s``; the
    statistics the link's counters, ``steps``, ``overruns`` and ``wall_time_s``.
    """
    if not (math.isfinite(rate) and rate > 0):
        raise SimulationError(f"hil plant: --rate must be a number of Hz > 0, got {rate!r}.")
    if not (math.isfinite(duration) and duration > 0):
        raise SimulationError(f"hil plant: --duration must be > 0 s, got {duration!r}.")
    loop = name if isinstance(name, LoopFunctions) else build_loop(name, rate=rate)
    steps = int(round(duration * rate))
    period = 1.0 / rate
    out_f, step_f = loop.plant_out, loop.plant_step
    x = np.array(loop.x0, dtype=float)
    duty = 0.5
    ref = 0.0
    rows = np.zeros((steps, len(LOG_COLUMNS) + 2))
    overruns = 0
    io.start(hello_timeout)
    start = time.monotonic() + 1e-3
    t0_wall = start
    try:
        for k in range(steps):
            t_k = start + k * period
            now = time.monotonic()
            if now < t_k:
                time.sleep(t_k - now)
            late = time.monotonic() - t_k
            meas = np.array(out_f(x), dtype=float).ravel()
            io.write(k, k * period, meas)
            deadline = (time.monotonic() + lockstep) if lockstep else t_k + wait * period
            cmd = io.read(k, deadline)
            if cmd is not None:
                duty = cmd.values[0]
                if len(cmd.values) > 1:
                    ref = cmd.values[1]
            rows[k, :len(LOG_COLUMNS)] = (k * period, duty, ref, *meas)
            rows[k, -2:] = (cmd is not None, late)
            x = np.array(step_f(x, duty, k), dtype=float).ravel()
            if time.monotonic() > t_k + period:
                if lockstep:
                    start = time.monotonic() - (k + 1) * period   # restart the schedule
                else:
                    overruns += 1
    finally:
        io.stop()
    wall = time.monotonic() - t0_wall
    cols = (*LOG_COLUMNS, "got", "wake_late_s")
    return {"log": {c: rows[:, i].copy() for i, c in enumerate(cols)},
            "stats": {"kind": io.kind, "steps": steps, "rate_hz": rate,
                      "overruns": overruns, "wall_time_s": wall,
                      "lockstep": bool(lockstep), **io.stats.as_dict()}}
