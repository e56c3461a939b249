"""SIL and PIL runs of the HIL experiments, and their comparison with MIL.

:func:`run_hil` builds the plant and controller C (:mod:`mechatron.realtime.cgen`) and
runs them:

- SIL over ``transport="sim"`` (the default): plant and controller in one real-time C
  loop, ``mt_sil`` (no link at all, so nothing but the schedule limits the rate);
- SIL over ``"udp"`` or ``"pty"``: the plant runner ``mt_plant`` and the controller
  ``mt_controller`` as two processes connected by the bridge;
- PIL: ``mt_plant`` and the controller firmware in QEMU, over its emulated UART.

It reads the per-step log and statistics, runs the same loop as MIL
(:func:`mechatron.realtime.loop.run_mil`) and compares the two.
"""

from __future__ import annotations

import json
import math
import os
import secrets
import select
import shutil
import signal
import subprocess
import tempfile
import warnings
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from mechatron.errors import SimulationError
from mechatron.realtime.cgen import build_firmware, build_host, find_tool
from mechatron.realtime.loop import EXPERIMENTS, LoopFunctions, build_loop, run_mil

__all__ = ["HILResult", "run_hil", "compare", "timing_stats", "QEMU_MACHINE",
           "qemu_available", "TRANSPORTS", "OverrunWarning", "default_cpu", "default_spin"]

RUNNER_COLUMNS = ("t", "duty", "ref", "count", "w", "phi", "v_c", "i", "got",
                  "wake_late_s", "exec_s", "busy_s", "rtt_s")
QEMU_MACHINE = "lm3s6965evb"
MAX_STEPS = 20_000_000
#: SIL links: ``sim`` (plant and controller in one C loop), ``udp``, ``pty``.
TRANSPORTS = ("sim", "udp", "pty")
#: Exit code of ``mt_sil`` (and of ``mechatron hil``) when the overrun budget is exceeded.
EXIT_OVER_BUDGET = 3
#: A run of consecutive steps without an exchange this long (s) is reported as a stall.
STALL_S = 0.01


class OverrunWarning(RuntimeWarning):
    """A real-time run overran its period more often than its budget allows."""


def default_cpu() -> int | None:
    """The CPU the real-time loop is pinned to: the last one this process may use (the
    first CPU takes most device interrupts), or None on a single CPU."""
    try:
        cpus = sorted(os.sched_getaffinity(0))
    except (AttributeError, OSError):
        return None
    return cpus[-1] if len(cpus) > 1 else None


def default_spin(rate: float) -> float:
    """Seconds before each deadline the loop polls the clock instead of sleeping: half
    the period, at most 50 us (a sleep's wake-up latency in a virtual machine is
    10-30 us; polling hides it at the price of that share of one CPU)."""
    return min(0.5 / rate, 50e-6)


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
    transport: str = "udp"
    max_overruns: float | None = None

    @property
    def over_budget(self) -> bool:
        """True when the share of overrun steps exceeds :attr:`max_overruns`."""
        if self.max_overruns is None:
            return False
        return self.runner["overruns"] > self.max_overruns * max(self.runner["steps"], 1)

    @property
    def longest_gap(self) -> int:
        """The longest run of consecutive steps in which the plant got no duty from the
        controller (``got`` = 0 in the log). The ordinary overruns of a kept schedule are
        single steps here and there; a long run is a stall (the host paused the loop,
        or the controller stopped answering), through which the plant ran on with the
        duty held: the comparison with MIL then measures the stall as well."""
        got = self.log.get("got")
        if got is None or got.size == 0:
            return 0
        lost = np.concatenate(([0], (got == 0).astype(np.int8), [0]))
        edges = np.flatnonzero(np.diff(lost))       # starts and ends of the runs, in turn
        return int((edges[1::2] - edges[::2]).max()) if edges.size else 0

    def summary(self) -> dict:
        """The JSON summary of ``mechatron hil --json`` (every figure a number, a bool or
        a string: a figure that was not measured is left out, never null)."""
        r = self.runner
        steps = max(r["steps"], 1)
        out = {
            "name": self.name, "mode": self.mode, "transport": self.transport,
            "rate_hz": self.rate, "duration_s": self.duration, "loss": self.loss,
            "steps": r["steps"], "requested_steps": r["requested_steps"],
            "overruns": r["overruns"], "overrun_percent": 100.0 * r["overruns"] / steps,
            "missed_steps": r["missed_steps"],
            "lost_samples": r["lost_packets"], "lost_packets": r["lost_packets"],
            "late_packets": r["late_packets"],
            "dropped_on_purpose": {"plant": r.get("dropped_on_purpose", 0),
                                   "controller": self.controller.get("dropped_on_purpose",
                                                                     0)},
            "controller_lost_samples": self.controller.get("lost_samples", 0),
            "longest_gap_steps": self.longest_gap,
            **({"reply_timeout_s": r["reply_timeout_s"]} if "reply_timeout_s" in r else {}),
            "rms_diff_percent": self.comparison["rms_diff_percent"],
            "peak_diff_percent": self.comparison["peak_diff_percent"],
            "compared": self.comparison["variable"],
            "max_step_time_s": self.timing["step_time_max_s"],
            "median_step_time_s": self.timing["step_time_median_s"],
            "timing": {k: v for k, v in self.timing.items() if v is not None},
            "realtime_scheduling": bool(r.get("realtime", False)),
            "mlockall": bool(r.get("mlockall", r.get("realtime", False))),
            "cpu": r.get("cpu", -1), "keep_awake": bool(r.get("keep_awake", False)),
            "realtime_factor": self.timing["realtime_factor"],
            "over_budget": self.over_budget,
            "notes": list(self.notes),
        }
        if self.max_overruns is not None:
            out["overrun_budget_percent"] = 100.0 * self.max_overruns
        return out


def timing_stats(log: dict[str, np.ndarray], rate: float, wall_time: float, *,
                 scheduled: bool = True) -> dict:
    """Step time, wake-up jitter, period jitter and round trip, as percentiles.

    ``jitter_*`` is the wake-up lateness against the absolute deadline ``t_k``;
    ``period_jitter_*`` the deviation of the time between two wake-ups from the period,
    ``|(t_wake,k+1 - t_wake,k) - T|``. Without a schedule (``scheduled=False``: lockstep)
    neither has a meaning and both are left out, as is the round trip when no reply was
    timed.
    """
    def q(a, p):
        a = a[np.isfinite(a)]
        return float(np.percentile(a, p)) if a.size else 0.0

    rtt = log["rtt_s"][log["rtt_s"] >= 0]
    n = log["t"].size
    out = {
        "step_time_median_s": q(log["exec_s"], 50),
        "step_time_p99_s": q(log["exec_s"], 99),
        "step_time_max_s": q(log["exec_s"], 100),
        "busy_max_s": q(log["busy_s"], 100),
        "realtime_factor": (n / rate) / wall_time if wall_time > 0 else 0.0,
    }
    if scheduled:
        late = log["wake_late_s"]
        period = np.abs(np.diff(late))      # t_wake,k+1 - t_wake,k - T, as |.|
        for name, p in (("median", 50), ("p90", 90), ("p99", 99), ("p999", 99.9),
                        ("max", 100)):
            out[f"jitter_{name}_s"] = q(late, p)
            out[f"period_jitter_{name}_s"] = q(period, p)
    if rtt.size:
        out.update(round_trip_median_s=q(rtt, 50), round_trip_p99_s=q(rtt, 99),
                   round_trip_max_s=q(rtt, 100))
    return out


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
            rate: float = 10_000.0, loss: float = 0.0, transport: str = "sim",
            realtime: bool = True, wait: float = 0.8, seed: int = 1,
            build_dir: str | os.PathLike | None = None, pil_timeout: float = 2.0,
            lockstep: bool = False, cpu: int | None | str = "auto",
            spin: float | str = "auto", max_overruns: float | None = None,
            keep_awake: bool = True) -> HILResult:
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
        SIL link: ``"sim"`` (plant and controller in one real-time C loop, ``mt_sil``),
        ``"udp"`` (two processes over loopback) or ``"pty"`` (two processes over a
        pseudo-terminal serial line). PIL always uses the emulated UART (a
        pseudo-terminal on the host side).
    realtime : bool
        Ask for SCHED_FIFO and mlockall (granted only with the privilege; a note says
        when refused).
    cpu : int, None or "auto"
        ``sim`` only: the CPU the loop is pinned to (``"auto"``: :func:`default_cpu`;
        None: not pinned).
    spin : float or "auto"
        ``sim`` only: seconds before each deadline spent polling the clock instead of
        sleeping (``"auto"``: :func:`default_spin`; 0: sleep to the deadline).
    keep_awake : bool
        ``sim`` with a pinned CPU: run a ``SCHED_IDLE`` process spinning on the loop's
        CPU, so that a virtual CPU does not halt between periods (waking a halted one
        costs the host's scheduling delay); it takes only time no other task wants.
    max_overruns : float, optional
        Overrun budget, a fraction of the steps (``1e-3``: 0.1 %). When exceeded an
        :class:`OverrunWarning` is issued, a note added and ``over_budget`` set (the
        command line then exits with 3).
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
    if transport not in TRANSPORTS:
        raise SimulationError(f"hil: transport must be one of {', '.join(TRANSPORTS)}, got "
                              f"{transport!r}.")
    if transport == "sim" and (mode == "pil" or lockstep):
        transport = "udp" if mode == "sil" else "pty"   # one loop has nothing to wait for
    if max_overruns is not None and not (0 <= max_overruns <= 1):
        raise SimulationError(f"hil: --max-overruns is a fraction of the steps in [0, 1], "
                              f"got {max_overruns!r}.")
    cpu = default_cpu() if cpu == "auto" else cpu
    spin = default_spin(rate) if spin == "auto" else float(spin)
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
    try:
        if build_dir is None:
            # named before it exists, so that an interrupt (Ctrl-C, SIGTERM) arriving
            # right after the folder is made still finds it in the finally below
            while tmp is None:
                tmp = _new_temporary_name("mechatron-hil-")
                try:
                    os.mkdir(tmp, 0o700)
                except FileExistsError:     # made by another process meanwhile: not ours
                    tmp = None
            build_dir = tmp
        out = Path(build_dir)
        if transport == "sim":
            res = _run_sim(loop, name, rate, loss, realtime, seed, out, steps, cpu, spin,
                           max_overruns, keep_awake)
        else:
            res = _run(loop, name, mode, duration, rate, loss, transport, realtime, wait,
                       seed, out, steps, pil_timeout, lockstep or mode == "pil")
    finally:
        if tmp is not None:
            shutil.rmtree(tmp, ignore_errors=True)
    res.max_overruns = max_overruns
    gap = res.longest_gap
    if not lockstep and mode == "sil" and gap > 1 and gap >= STALL_S * rate:
        res.notes.append(f"the plant went {gap} consecutive steps ({1e3 * gap / rate:.3g} "
                         "ms) without a duty from the controller: the loop stalled (the "
                         "host paused it, or the controller stopped answering) and the "
                         "plant ran on with the duty held, so the comparison with MIL "
                         "measures that stall as well")
    if res.over_budget:
        msg = (f"hil {name}: {res.runner['overruns']} overruns in {res.runner['steps']} "
               f"steps ({100 * res.runner['overruns'] / res.runner['steps']:.3g} %) exceed "
               f"the budget of {100 * max_overruns:.3g} %")
        res.notes.append(msg)
        warnings.warn(msg + ".", OverrunWarning, stacklevel=2)
    return res


def _new_temporary_name(prefix: str) -> str:
    """A path in the temporary directory: ``prefix`` and 16 random hexadecimal digits.
    The caller creates it with ``os.mkdir``, which refuses a path that exists."""
    return os.path.join(tempfile.gettempdir(), prefix + secrets.token_hex(8))


def _run_sim(loop, name, rate, loss, realtime, seed, out, steps, cpu, spin,
             max_overruns, keep_awake) -> HILResult:
    """SIL in one process: ``mt_sil`` runs the generated plant and controller."""
    exes = build_host(loop, out)
    log_path, stats_path = out / "log.bin", out / "stats.json"
    cmd = [str(exes["sil"]), "--rate", repr(float(rate)), "--steps", str(steps),
           "--loss", repr(float(loss)), "--seed", str(seed), "--spin", repr(float(spin)),
           "--log", str(log_path), "--stats", str(stats_path)]
    if realtime:
        cmd.append("--rt")
    if cpu is not None:
        cmd += ["--cpu", str(int(cpu))] + (["--keep-awake"] if keep_awake else [])
    if max_overruns is not None:
        cmd += ["--max-overruns", repr(float(max_overruns))]
    budget = 60.0 + 2.0 * steps / rate
    try:
        proc = subprocess.run(cmd, capture_output=True, text=True, timeout=budget)
    except subprocess.TimeoutExpired:
        raise SimulationError(f"hil: the SIL loop did not finish within {budget:g} s; "
                              "stopped it.") from None
    if proc.returncode not in (0, EXIT_OVER_BUDGET):
        raise SimulationError(f"hil: the SIL loop failed (exit {proc.returncode}): "
                              f"{proc.stderr.strip()[:1000]}")
    runner = json.loads(stats_path.read_text())
    controller = runner.pop("controller")
    log = _read_log(log_path)
    mil = run_mil(loop, steps)
    timing = timing_stats(log, rate, runner["wall_time_s"])
    notes = [f"{n}; ran without it" for n in runner.get("notes", [])]
    if realtime and not runner["realtime"] and not notes:
        notes.append("SCHED_FIFO not granted; ran in the default class")
    if runner["steps"] < steps:
        notes.append(f"stopped after {runner['steps']} of {steps} steps")
    if runner.get("skipped_samples"):
        notes.append(f"{runner['skipped_samples']} step(s) started a period late: their "
                     "samples were not exchanged (lost) and the plant only stepped, to "
                     "regain the schedule")
    return HILResult(name=name, mode="sil", rate=rate, duration=steps / rate, loss=loss,
                     log=log, mil=mil, runner=runner, controller=controller,
                     comparison=compare(log, mil, loop), timing=timing, notes=notes,
                     transport="sim")


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
    # without a schedule to keep (lockstep) a wake-up lateness has no meaning
    timing = timing_stats(log, rate, runner["wall_time_s"], scheduled=not lockstep)
    if runner["steps"] < steps:
        notes.append(f"stopped after {runner['steps']} of {steps} steps")
    if lockstep or (timing["realtime_factor"] or 0) < 0.98:
        notes.append(f"ran at {timing['realtime_factor']:.3g}x real time "
                     f"({runner['wall_time_s']:.3g} s wall for {steps / rate:g} s)"
                     + (": QEMU cannot keep the rate; the plant waited for each reply "
                        "(lockstep)" if mode == "pil" else
                        ": lockstep, the plant waited for each reply" if lockstep else ""))
    if lockstep and runner["missed_steps"]:
        notes.append(f"{runner['missed_steps']} step(s) got no reply within "
                     f"{runner.get('reply_timeout_s', pil_timeout):.3g} s (the reply timeout "
                     "once the link was up: 20 mean round trips, at least 50 ms): "
                     f"{runner['lost_packets']} lost, {runner['late_packets']} late; the "
                     "plant held the previous duty")
    if not runner["realtime"] and realtime:
        notes.append("real-time scheduling (SCHED_FIFO) not permitted; ran in the default "
                     "class")
    return HILResult(name=name, mode=mode, rate=rate, duration=steps / rate, loss=loss,
                     log=log, mil=mil, runner=runner, controller=controller,
                     comparison=compare(log, mil, loop), timing=timing, notes=notes,
                     transport=transport if mode == "sil" else "uart")


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
