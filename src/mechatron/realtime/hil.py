"""SIL and PIL runs of the HIL experiments, and their comparison with MIL.

:func:`run_hil` builds the plant and controller C (:mod:`mechatron.realtime.cgen`), starts
the plant runner (``mt_plant``) and the controller (a host process ``mt_controller`` for
SIL, the firmware in QEMU for PIL) as separate processes connected by the bridge, waits
for them, reads the runner's per-step log and statistics, runs the same loop as MIL
(:func:`mechatron.realtime.loop.run_mil`) and compares the two.
"""

from __future__ import annotations

import json
import math
import os
import select
import signal
import subprocess
import tempfile
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from mechatron.errors import SimulationError
from mechatron.realtime.cgen import build_firmware, build_host, find_tool
from mechatron.realtime.loop import EXPERIMENTS, LoopFunctions, build_loop, run_mil

__all__ = ["HILResult", "run_hil", "compare", "timing_stats", "QEMU_MACHINE",
           "qemu_available"]

RUNNER_COLUMNS = ("t", "duty", "ref", "count", "w", "phi", "v_c", "i", "got",
                  "wake_late_s", "exec_s", "busy_s", "rtt_s")
QEMU_MACHINE = "lm3s6965evb"
MAX_STEPS = 20_000_000


@dataclass
class HILResult:
    """Outcome of one HIL run: logs, statistics, and the comparison with MIL."""

    name: str
    mode: str
    rate: float
    duration: float
    loss: float
    log: dict[str, np.ndarray]
    mil: dict[str, np.ndarray]
    runner: dict
    controller: dict
    comparison: dict
    timing: dict
    notes: list[str] = field(default_factory=list)

    def summary(self) -> dict:
        """The JSON summary of ``mechatron hil --json``."""
        r = self.runner
        return {
            "name": self.name, "mode": self.mode, "rate_hz": self.rate,
            "duration_s": self.duration, "loss": self.loss,
            "steps": r["steps"], "requested_steps": r["requested_steps"],
            "overruns": r["overruns"], "missed_steps": r["missed_steps"],
            "lost_packets": r["lost_packets"], "late_packets": r["late_packets"],
            "dropped_on_purpose": {"plant": r["dropped_on_purpose"],
                                   "controller": self.controller.get("dropped_on_purpose")},
            "controller_lost_samples": self.controller.get("lost_samples"),
            "rms_diff_percent": self.comparison["rms_diff_percent"],
            "peak_diff_percent": self.comparison["peak_diff_percent"],
            "compared": self.comparison["variable"],
            "max_step_time_s": r["max_step_time_s"],
            "median_step_time_s": r["median_step_time_s"],
            "timing": self.timing, "realtime_scheduling": r["realtime"],
            "realtime_factor": self.timing["realtime_factor"],
            "notes": list(self.notes),
        }


def timing_stats(log: dict[str, np.ndarray], rate: float, wall_time: float) -> dict:
    """Median, 99th percentile and worst step time, wake-up jitter and round trip."""
    def q(a, p):
        a = a[np.isfinite(a)]
        return float(np.percentile(a, p)) if a.size else None

    rtt = log["rtt_s"][log["rtt_s"] >= 0]
    n = log["t"].size
    return {
        "step_time_median_s": q(log["exec_s"], 50),
        "step_time_p99_s": q(log["exec_s"], 99),
        "step_time_max_s": q(log["exec_s"], 100),
        "jitter_median_s": q(log["wake_late_s"], 50),
        "jitter_p99_s": q(log["wake_late_s"], 99),
        "jitter_max_s": q(log["wake_late_s"], 100),
        "busy_max_s": q(log["busy_s"], 100),
        "round_trip_median_s": q(rtt, 50) if rtt.size else None,
        "round_trip_max_s": q(rtt, 100) if rtt.size else None,
        "realtime_factor": (n / rate) / wall_time if wall_time > 0 else None,
    }


def compare(log: dict[str, np.ndarray], mil: dict[str, np.ndarray], loop: LoopFunctions
            ) -> dict:
    """RMS and peak difference of the controlled variable, HIL against MIL, in % of the
    reference's size (:attr:`Experiment.ref_scale`), over the common steps."""
    exp = loop.experiment
    var = "w" if exp.quantity == "speed" else "phi"
    n = min(log[var].size, mil[var].size)
    if n == 0:
        raise SimulationError(f"hil '{exp.name}': the run logged no step; nothing to "
                              "compare.")
    d = log[var][:n] - mil[var][:n]
    scale = exp.ref_scale
    return {"variable": var, "unit": exp.unit, "steps": n, "ref_scale": scale,
            "rms_diff": float(np.sqrt(np.mean(d ** 2))),
            "peak_diff": float(np.max(np.abs(d))),
            "rms_diff_percent": 100.0 * float(np.sqrt(np.mean(d ** 2))) / scale,
            "peak_diff_percent": 100.0 * float(np.max(np.abs(d))) / scale}


def qemu_available() -> str | None:
    """Why PIL cannot run here (a missing tool), or None if it can."""
    missing = [t for t in ("qemu-system-arm", "arm-none-eabi-gcc") if not find_tool(t)]
    if missing:
        return (f"{', '.join(missing)} not found; install qemu-system-arm, "
                "gcc-arm-none-eabi and libnewlib-arm-none-eabi (apt-get)")
    return None


def _read_ready(proc: subprocess.Popen, timeout: float) -> list[str]:
    ready, _, _ = select.select([proc.stdout], [], [], timeout)
    if not ready:
        raise SimulationError(f"hil: the plant runner did not start within {timeout:g} s.")
    line = proc.stdout.readline().strip()
    if not line.startswith("READY"):
        err = proc.stderr.read() if proc.poll() is not None else ""
        raise SimulationError(f"hil: the plant runner failed to start: {line or err}")
    return line.split()


def _stop(proc: subprocess.Popen | None) -> None:
    if proc is not None and proc.poll() is None:
        proc.send_signal(signal.SIGTERM)
        try:
            proc.wait(timeout=5)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()


def _read_log(path: Path) -> dict[str, np.ndarray]:
    data = np.fromfile(path, dtype="<f8")
    data = data.reshape(-1, len(RUNNER_COLUMNS))
    return {name: data[:, i].copy() for i, name in enumerate(RUNNER_COLUMNS)}


def run_hil(name: str = "speed", *, mode: str = "sil", duration: float = 2.0,
            rate: float = 10_000.0, loss: float = 0.0, transport: str = "udp",
            realtime: bool = True, wait: float = 0.8, seed: int = 1,
            build_dir: str | os.PathLike | None = None, pil_timeout: float = 2.0,
            lockstep: bool = False) -> HILResult:
    """Run one HIL experiment and compare it with MIL.

    Parameters
    ----------
    name : str
        An experiment of :data:`mechatron.realtime.loop.EXPERIMENTS` (``speed``,
        ``position``).
    mode : str
        ``"sil"`` (controller as a host process) or ``"pil"`` (controller firmware on
        QEMU's emulated LM3S6965, over its UART0).
    duration, rate : float
        Simulated time in s, and the plant's step rate in Hz.
    loss : float
        Probability, in [0, 1), that each sample and each command is dropped on purpose.
    transport : str
        SIL bridge: ``"udp"`` (loopback) or ``"pty"`` (pseudo-terminal serial line). PIL
        always uses the emulated UART (a pseudo-terminal on the host side).
    realtime : bool
        Ask for SCHED_FIFO (granted only with the privilege; reported either way).
    wait : float
        Fraction of the period the plant waits for a reply before holding the previous
        duty (SIL). PIL waits up to ``pil_timeout`` s per step instead (lockstep: QEMU
        cannot keep 10 kHz, so the run is slower than real time and says so).
    lockstep : bool
        SIL only: wait for every reply (up to ``pil_timeout`` s) instead of keeping real
        time, as PIL always does. No step is then missed, so SIL must reproduce MIL to
        rounding; timing figures are not those of a real-time run.
    """
    if mode not in ("sil", "pil"):
        raise SimulationError(f"hil: --mode must be 'sil' or 'pil', got {mode!r}.")
    if name not in EXPERIMENTS:
        raise SimulationError(f"hil: unknown experiment '{name}'. Choose one of "
                              f"{', '.join(EXPERIMENTS)}.")
    if not (math.isfinite(duration) and duration > 0):
        raise SimulationError(f"hil: --duration must be a number of s > 0, got {duration!r}.")
    if not (math.isfinite(rate) and 0 < rate <= 100_000):
        raise SimulationError(f"hil: --rate must be in (0, 100000] Hz, got {rate!r}.")
    if not (0.0 <= loss < 1.0):
        raise SimulationError(f"hil: --loss is a probability in [0, 1), got {loss!r}.")
    if transport not in ("udp", "pty"):
        raise SimulationError(f"hil: transport must be 'udp' or 'pty', got {transport!r}.")
    steps = int(round(duration * rate))
    if steps < 1 or steps > MAX_STEPS:
        raise SimulationError(f"hil: duration x rate = {steps} steps; give between 1 and "
                              f"{MAX_STEPS:,} (the runner keeps its log in memory).")
    if mode == "pil":
        why = qemu_available()
        if why:
            raise SimulationError(f"hil --mode pil: {why}.")
    loop = build_loop(name, rate=rate)
    tmp = None
    if build_dir is None:
        tmp = tempfile.TemporaryDirectory(prefix="mechatron-hil-")
        build_dir = tmp.name
    out = Path(build_dir)
    try:
        return _run(loop, name, mode, duration, rate, loss, transport, realtime, wait,
                    seed, out, steps, pil_timeout, lockstep or mode == "pil")
    finally:
        if tmp is not None:
            tmp.cleanup()


def _run(loop, name, mode, duration, rate, loss, transport, realtime, wait, seed, out,
         steps, pil_timeout, lockstep) -> HILResult:
    exes = build_host(loop, out)
    firmware = build_firmware(loop, out) if mode == "pil" else None
    log_path, stats_path, cstats_path = out / "log.bin", out / "stats.json", out / "ctrl.json"
    plant_cmd = [str(exes["plant"]), "--rate", repr(float(rate)), "--steps", str(steps),
                 "--transport", "udp" if mode == "sil" and transport == "udp" else "pty",
                 "--loss", repr(float(loss)), "--seed", str(seed), "--wait", repr(wait),
                 "--log", str(log_path), "--stats", str(stats_path)]
    if realtime:
        plant_cmd.append("--rt")
    if lockstep:
        plant_cmd += ["--lockstep", repr(float(pil_timeout))]
    if mode == "pil":
        plant_cmd += ["--hello-timeout", "20"]
    notes = []
    plant = ctrl = None
    qemu_log = out / "qemu.log"
    try:
        plant = subprocess.Popen(plant_cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                 text=True)
        _, kind, where = _read_ready(plant, 10.0)
        if mode == "sil":
            ccmd = [str(exes["controller"]),
                    "--udp" if kind == "udp" else "--tty", where,
                    "--loss", repr(float(loss)), "--seed", str(seed + 1),
                    "--stats", str(cstats_path)]
            if realtime:
                ccmd.append("--rt")
            ctrl = subprocess.Popen(ccmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                                    text=True)
        else:
            ccmd = [find_tool("qemu-system-arm"), "-M", QEMU_MACHINE, "-nographic",
                    "-monitor", "none", "-serial", "chardev:uart0",
                    "-chardev", f"serial,id=uart0,path={where}",
                    "-semihosting-config", "enable=on,target=native",
                    "-kernel", str(firmware)]
            ctrl = subprocess.Popen(ccmd, stdin=subprocess.DEVNULL,
                                    stdout=open(qemu_log, "w"), stderr=subprocess.STDOUT)
        budget = 60.0 + duration * (2000.0 * pil_timeout if lockstep else 1.5)
        try:
            plant.wait(timeout=budget)
        except subprocess.TimeoutExpired:
            raise SimulationError(f"hil: the plant runner did not finish within {budget:g} "
                                  "s; stopped it.") from None
        if plant.returncode != 0:
            raise SimulationError(f"hil: the plant runner failed (exit {plant.returncode}): "
                                  f"{plant.stderr.read().strip()[:1000]}")
        try:
            ctrl.wait(timeout=10)
        except subprocess.TimeoutExpired:
            notes.append("the controller did not stop on STOP within 10 s; terminated")
    finally:
        _stop(plant)
        _stop(ctrl)
    runner = json.loads(stats_path.read_text())
    controller = json.loads(cstats_path.read_text()) if cstats_path.exists() else {}
    if mode == "pil":
        controller = _firmware_stats(qemu_log)
    log = _read_log(log_path)
    mil = run_mil(loop, steps)
    timing = timing_stats(log, rate, runner["wall_time_s"])
    if lockstep:      # no schedule to keep: a wake-up lateness has no meaning
        timing.update(jitter_median_s=None, jitter_p99_s=None, jitter_max_s=None)
    if runner["steps"] < steps:
        notes.append(f"stopped after {runner['steps']} of {steps} steps")
    if lockstep or (timing["realtime_factor"] or 0) < 0.98:
        notes.append(f"ran at {timing['realtime_factor']:.3g}x real time "
                     f"({runner['wall_time_s']:.3g} s wall for {steps / rate:g} s)"
                     + (": QEMU cannot keep the rate; the plant waited for each reply "
                        "(lockstep)" if mode == "pil" else
                        ": lockstep, the plant waited for each reply" if lockstep else ""))
    if not runner["realtime"] and realtime:
        notes.append("real-time scheduling (SCHED_FIFO) not permitted; ran in the default "
                     "class")
    return HILResult(name=name, mode=mode, rate=rate, duration=steps / rate, loss=loss,
                     log=log, mil=mil, runner=runner, controller=controller,
                     comparison=compare(log, mil, loop), timing=timing, notes=notes)


def _firmware_stats(path: Path) -> dict:
    """The firmware prints one JSON line of statistics on semihosting before it exits."""
    try:
        text = path.read_text(errors="replace")
    except OSError:
        return {}
    for line in reversed(text.splitlines()):
        line = line.strip()
        if line.startswith("{") and line.endswith("}"):
            try:
                return json.loads(line)
            except json.JSONDecodeError:
                continue
    return {"console": text[-500:]}
