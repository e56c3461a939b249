"""The plant side of a HIL run over any I/O backend (:mod:`mechatron.realtime.io`).

:func:`run_plant` steps the experiment's plant (:func:`mechatron.realtime.loop.
build_loop`: ``plant_out``, ``plant_step``) against a controller on the other end of a
:class:`~mechatron.realtime.io.PlantIO`: a microcontroller on a serial line, a card, a
process over UDP. Python runs once per step here (about 20-40 us a step), so this loop
serves links slower than that (a 115200 baud serial line carries ~300 steps/s); the
10 kHz SIL loop is C (:func:`mechatron.realtime.hil.run_hil`, ``transport="sim"``).
The plant's step functions are the generated C of the SIL loop, compiled into a shared
library and called through :mod:`ctypes` (a few us a call; CasADi's own call, used when
no C compiler is found, takes 50-100 us).
"""

from __future__ import annotations

import ctypes
import math
import os
import subprocess
import tempfile
import time
from pathlib import Path

import numpy as np

from mechatron.errors import SimulationError
from mechatron.realtime.io.base import PlantIO
from mechatron.realtime.loop import LOG_COLUMNS, LoopFunctions, build_loop

__all__ = ["run_plant", "CompiledPlant"]


class CompiledPlant:
    """``plant_out(x)`` and ``plant_step(x, duty, k)`` of a :class:`LoopFunctions` as
    generated C (``casadi.CodeGenerator``, as for ``mt_sil``) in a shared library."""

    def __init__(self, loop: LoopFunctions, cc: str) -> None:
        from mechatron.realtime.cgen import _gen
        self._tmp = tempfile.TemporaryDirectory(prefix="mechatron-plant-")
        d = Path(self._tmp.name)
        _gen("plant_model", [loop.plant_out, loop.plant_step], d)
        so = d / "libplant.so"
        proc = subprocess.run([cc, "-std=c99", "-O2", "-shared", "-fPIC", "-o", str(so),
                               str(d / "plant_model.c"), "-lm"], capture_output=True,
                              text=True)
        if proc.returncode != 0:
            raise SimulationError(f"hil plant: compiling the plant failed: "
                                  f"{proc.stderr.strip()[:1000]}")
        self.lib = ctypes.CDLL(str(so))
        self.nx = loop.x0.size
        self.x = (ctypes.c_double * self.nx)(*loop.x0)
        self.xn = (ctypes.c_double * self.nx)()
        self.meas = (ctypes.c_double * loop.plant_out.size1_out(0))()
        self.duty, self.k = ctypes.c_double(), ctypes.c_double()
        self.calls = {}
        dp = ctypes.POINTER(ctypes.c_double)
        for name, args, res in (("plant_out", [self.x], [self.meas]),
                                ("plant_step", [self.x, self.duty, self.k], [self.xn])):
            sz = [ctypes.c_int() for _ in range(4)]
            getattr(self.lib, f"{name}_work")(*[ctypes.byref(v) for v in sz])
            arg = (dp * max(sz[0].value, 1))(*[ctypes.cast(ctypes.byref(a), dp)
                                               for a in args])
            out = (dp * max(sz[1].value, 1))(*[ctypes.cast(ctypes.byref(r), dp)
                                               for r in res])
            iw = (ctypes.c_int * max(sz[2].value, 1))()
            w = (ctypes.c_double * max(sz[3].value, 1))()
            self.calls[name] = (getattr(self.lib, name), arg, out, iw, w)

    def _call(self, name: str) -> None:
        f, arg, out, iw, w = self.calls[name]
        if f(arg, out, iw, w, 0) != 0:
            raise SimulationError(f"hil plant: {name} failed.")

    def out(self) -> np.ndarray:
        self._call("plant_out")
        return np.frombuffer(self.meas, dtype=float).copy()

    def step(self, duty: float, k: int) -> None:
        self.duty.value, self.k.value = duty, float(k)
        self._call("plant_step")
        ctypes.memmove(self.x, self.xn, ctypes.sizeof(self.x))

    def close(self) -> None:
        self._tmp.cleanup()


class _CasadiPlant:
    def __init__(self, loop: LoopFunctions) -> None:
        self.loop, self.x = loop, np.array(loop.x0, dtype=float)

    def out(self) -> np.ndarray:
        return np.array(self.loop.plant_out(self.x), dtype=float).ravel()

    def step(self, duty: float, k: int) -> None:
        self.x = np.array(self.loop.plant_step(self.x, duty, k), dtype=float).ravel()

    def close(self) -> None:
        pass


def _plant(loop: LoopFunctions):
    from mechatron.realtime.cgen import find_tool
    cc = os.environ.get("CC") or find_tool("cc") or find_tool("gcc")
    return CompiledPlant(loop, cc) if cc else _CasadiPlant(loop)


#: Lockstep: once replies have come, one not in after this many mean round trips...
LOSS_RTT_FACTOR = 20.0
#: ...and at least this many seconds is lost (as the C runner ``mt_plant`` does).
LOSS_FLOOR_S = 0.05


def run_plant(io: PlantIO, name: str | LoopFunctions = "speed", *, rate: float = 200.0,
              duration: float = 1.0, wait: float = 0.8, lockstep: float | None = None,
              hello_timeout: float = 10.0) -> dict:
    """Run the plant of experiment ``name`` at ``rate`` Hz for ``duration`` s over ``io``.

    Each step ``k`` at ``t_k = k / rate`` (absolute schedule): measure, ``io.write``,
    ``io.read`` until ``t_k + wait / rate`` (with ``lockstep`` set: until that many
    seconds after the write, and the schedule restarts after each step; once replies
    have come, only :data:`LOSS_RTT_FACTOR` times their mean round trip, at least
    :data:`LOSS_FLOOR_S`, so that a lost packet costs a bounded wait), advance the
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
    plant = _plant(loop)
    duty = 0.5
    ref = 0.0
    rows = np.zeros((steps, len(LOG_COLUMNS) + 2))
    overruns = 0
    sum_rtt, n_rtt, max_tmo = 0.0, 0, 0.0
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
            meas = plant.out()
            t_send = time.monotonic()
            io.write(k, k * period, meas)
            if lockstep:
                tmo = lockstep
                if n_rtt:
                    tmo = min(lockstep, max(LOSS_FLOOR_S, LOSS_RTT_FACTOR * sum_rtt / n_rtt))
                    max_tmo = max(max_tmo, tmo)
                deadline = t_send + tmo
            else:
                deadline = t_k + wait * period
            cmd = io.read(k, deadline)
            if cmd is not None and lockstep:
                sum_rtt += time.monotonic() - t_send
                n_rtt += 1
            if cmd is not None:
                duty = cmd.values[0]
                if len(cmd.values) > 1:
                    ref = cmd.values[1]
            rows[k, :len(LOG_COLUMNS)] = (k * period, duty, ref, *meas)
            rows[k, -2:] = (cmd is not None, late)
            plant.step(duty, k)
            if time.monotonic() > t_k + period:
                if lockstep:
                    start = time.monotonic() - (k + 1) * period   # restart the schedule
                else:
                    overruns += 1
    finally:
        io.stop()
        plant.close()
    wall = time.monotonic() - t0_wall
    cols = (*LOG_COLUMNS, "got", "wake_late_s")
    return {"log": {c: rows[:, i].copy() for i, c in enumerate(cols)},
            "stats": {"kind": io.kind, "steps": steps, "rate_hz": rate,
                      "overruns": overruns, "wall_time_s": wall,
                      "lockstep": bool(lockstep),
                      "reply_timeout_s": max_tmo if lockstep else wait * period,
                      **io.stats.as_dict()}}
