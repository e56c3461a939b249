"""The ``mechatron hil`` command (added by :mod:`mechatron.realtime.cli`)."""

from __future__ import annotations

import argparse
import sys
import warnings

from mechatron.realtime.experiments import EXPERIMENTS

__all__ = ["add_hil_command", "cmd_hil", "EXIT_OVER_BUDGET"]

#: Exit code when the overrun budget (``--max-overruns``) is exceeded.
EXIT_OVER_BUDGET = 3


def add_hil_command(sub) -> None:
    """Add ``hil`` to the ``mechatron`` sub-parsers."""
    from mechatron.cli import add_json
    p = sub.add_parser(
        "hil", help="hardware-in-the-loop experiment (SIL or PIL) against MIL",
        description="Run the DC motor (RC-filtered PWM, H-bridge, encoder) and the "
                    "generated controller in one real-time C loop (SIL, --transport sim), "
                    "as two processes over UDP or a pseudo-terminal, or with the "
                    "controller as firmware on an emulated Cortex-M3 in QEMU (PIL); "
                    "compare with model-in-the-loop and report timing (jitter "
                    "percentiles, overruns) and lost samples. 'hil plant' runs only the "
                    "plant, against a controller on real hardware (--tty, --mf624) or "
                    "over UDP. Experiments: "
                    + "; ".join(f"{k}: {e.doc}" for k, e in EXPERIMENTS.items()),
        epilog="Exit code 3: the share of overrun steps exceeded --max-overruns.")
    p.add_argument("name", metavar="NAME", choices=sorted(EXPERIMENTS) + ["plant"],
                   help="experiment: " + ", ".join(EXPERIMENTS) + "; or 'plant' (the "
                        "plant side only, see --tty, --mf624, --udp-port)")
    p.add_argument("--mode", choices=("sil", "pil"), default="sil",
                   help="sil: controller on this machine; pil: firmware in QEMU "
                        "(default: %(default)s)")
    p.add_argument("--duration", type=float, default=2.0, metavar="S",
                   help="simulated time in s (default: %(default)s)")
    p.add_argument("--rate", type=float, default=None, metavar="HZ",
                   help="step rate in Hz (default: 10000; 'hil plant': 200)")
    p.add_argument("--loss", type=float, default=0.0, metavar="P",
                   help="drop each sample and command on purpose with probability P "
                        "(default: 0)")
    p.add_argument("--transport", choices=("sim", "udp", "pty"), default="sim",
                   help="SIL link: sim (plant and controller in one real-time C loop), "
                        "udp (two processes on loopback) or pty (two processes over a "
                        "pseudo-terminal serial line) (default: %(default)s)")
    p.add_argument("--lockstep", action="store_true",
                   help="SIL: wait for every reply instead of keeping real time (no "
                        "missed steps: SIL then reproduces MIL to rounding)")
    p.add_argument("--max-overruns", type=float, metavar="F",
                   help="overrun budget, a fraction of the steps (0.001: 0.1 %%); when "
                        "exceeded a warning is printed and the exit code is 3")
    p.add_argument("--cpu", type=int, metavar="N",
                   help="sim: pin the loop to CPU N (default: the last CPU)")
    p.add_argument("--spin", type=float, metavar="S",
                   help="sim: poll the clock for the last S s before each deadline "
                        "(default: half the period, at most 50 us; 0: sleep only)")
    p.add_argument("--no-keep-awake", action="store_true",
                   help="sim: do not run the idle-priority spinner that keeps the loop's "
                        "CPU from halting between periods")
    p.add_argument("--no-rt", action="store_true",
                   help="do not ask for real-time scheduling (SCHED_FIFO, mlockall, "
                        "CPU pinning)")
    p.add_argument("--seed", type=int, default=1, help="seed of the loss injection")
    p.add_argument("--report", metavar="FILE.html", help="write the HTML report")
    g = p.add_argument_group("hil plant: the link to the controller (one of)")
    g.add_argument("--tty", metavar="DEV",
                   help="serial line to the microcontroller, e.g. /dev/ttyUSB0 (framed "
                        "packets: sequence number, timestamp, payload, CRC-16)")
    g.add_argument("--baud", type=int, default=115200,
                   help="serial line speed (default: %(default)s)")
    g.add_argument("--mf624", metavar="DEV",
                   help="Humusoft MF624 through its UIO device, e.g. /dev/uio0 (AD0 in, "
                        "encoder A/B on DOUT0/1)")
    g.add_argument("--udp-port", type=int, metavar="PORT",
                   help="bind this UDP port and answer the controller's HELLO")
    g.add_argument("--experiment", choices=sorted(EXPERIMENTS), default="speed",
                   help="hil plant: the experiment whose plant runs (default: "
                        "%(default)s)")
    g.add_argument("--out", metavar="FILE.csv", help="hil plant: write the log as CSV")
    add_json(p)
    p.set_defaults(func=cmd_hil)


def cmd_hil(args: argparse.Namespace) -> int:
    from mechatron.cli import emit, emit_json, output_path, table
    from mechatron.realtime.hil import OverrunWarning, run_hil
    if args.name == "plant":
        return cmd_hil_plant(args)
    report = output_path(args.report, "--report", (".html", ".htm"))
    kw = {}
    if args.no_rt:
        kw["cpu"] = None
    elif args.cpu is not None:
        kw["cpu"] = args.cpu
    if args.spin is not None:
        kw["spin"] = args.spin
    kw["keep_awake"] = not args.no_keep_awake
    with warnings.catch_warnings():          # said once below, as a warning line
        warnings.simplefilter("ignore", OverrunWarning)
        res = run_hil(args.name, mode=args.mode, duration=args.duration,
                      rate=10_000.0 if args.rate is None else args.rate, loss=args.loss,
                      transport=args.transport, realtime=not args.no_rt, seed=args.seed,
                      lockstep=args.lockstep, max_overruns=args.max_overruns, **kw)
    if res.over_budget:
        print(f"warning: {res.notes[-1]}.", file=sys.stderr)
    s = res.summary()
    if report is not None:
        from mechatron.realtime.report import write_report
        write_report(res, report)
        s["report"] = str(report)
    if args.json:
        emit_json(s)
        return EXIT_OVER_BUDGET if res.over_budget else 0
    tm = res.timing
    c = res.comparison

    def us(key):
        x = tm.get(key)
        return "-" if x is None else f"{x * 1e6:.2f}"

    emit(f"hil {res.name} ({res.mode.upper()} over {res.transport}): {s['steps']} of "
         f"{s['requested_steps']} steps at {res.rate:g} Hz, loss {res.loss:g}")
    rows = [
        [f"RMS difference of {c['variable']} vs MIL", f"{c['rms_diff']:.4g} {c['unit']} "
         f"({c['rms_diff_percent']:.4g} % of {c['ref_scale']:g})"],
        [f"peak difference of {c['variable']} vs MIL",
         f"{c['peak_diff']:.4g} {c['unit']} ({c['peak_diff_percent']:.4g} %)"],
        ["step time median / p99 / max [us]", f"{us('step_time_median_s')} / "
         f"{us('step_time_p99_s')} / {us('step_time_max_s')}"]]
    if "jitter_median_s" in tm:
        rows += [["wake-up jitter p50 / p99 / p99.9 / max [us]",
                  f"{us('jitter_median_s')} / {us('jitter_p99_s')} / "
                  f"{us('jitter_p999_s')} / {us('jitter_max_s')}"],
                 ["period jitter p50 / p99 / p99.9 / max [us]",
                  f"{us('period_jitter_median_s')} / {us('period_jitter_p99_s')} / "
                  f"{us('period_jitter_p999_s')} / {us('period_jitter_max_s')}"]]
    if "round_trip_median_s" in tm:
        rows.append(["round trip median / max [us]",
                     f"{us('round_trip_median_s')} / {us('round_trip_max_s')}"])
    budget = (f" (budget {s['overrun_budget_percent']:.3g} %)"
              if "overrun_budget_percent" in s else "")
    rows += [
        ["overruns", f"{s['overruns']} ({s['overrun_percent']:.3g} %){budget}"],
        ["lost samples / missed steps / late packets",
         f"{s['lost_samples']} / {s['missed_steps']} / {s['late_packets']}"],
        ["dropped on purpose (plant, controller)",
         f"{s['dropped_on_purpose']['plant']}, {s['dropped_on_purpose']['controller']}"],
        ["SCHED_FIFO / mlockall / CPU", f"{'yes' if s['realtime_scheduling'] else 'no'} / "
         f"{'yes' if s['mlockall'] else 'no'} / "
         f"{s['cpu'] if s['cpu'] >= 0 else 'not pinned'}"],
        ["real-time factor", f"{tm['realtime_factor']:.3g}"]]
    emit(table(["figure", "value"], rows, indent="  "))
    for note in res.notes:
        emit(f"note: {note}")
    if report is not None:
        emit(f"report: {report}")
    return EXIT_OVER_BUDGET if res.over_budget else 0


def cmd_hil_plant(args: argparse.Namespace) -> int:
    """``mechatron hil plant --tty DEV | --mf624 DEV | --udp-port N``."""
    from mechatron.cli import CommandError, emit, emit_json, output_path
    from mechatron.realtime.io import open_io
    from mechatron.realtime.plant_loop import run_plant
    links = [(k, v) for k, v in (("serial", args.tty), ("mf624", args.mf624),
                                 ("udp", args.udp_port)) if v is not None]
    if len(links) != 1:
        raise CommandError("hil plant: give one link to the controller: --tty DEV, "
                           "--mf624 DEV or --udp-port PORT.")
    kind, where = links[0]
    out = output_path(args.out, "--out", (".csv",))
    options = {"serial": {"tty_path": where, "baud": args.baud},
               "mf624": {"device": where}, "udp": {"port": where}}[kind]
    rate = 200.0 if args.rate is None else args.rate
    with open_io(kind, **options) as io:
        if kind == "udp" and not args.json:
            emit(f"hil plant: listening on UDP port {io.port}")
        res = run_plant(io, args.experiment, rate=rate, duration=args.duration,
                        hello_timeout=0.0 if kind == "mf624" else 30.0)
    s = res["stats"]
    if out is not None:
        import numpy as np
        cols = list(res["log"])
        np.savetxt(out, np.column_stack([res["log"][c] for c in cols]), delimiter=",",
                   header=",".join(cols), comments="", fmt="%.17g")
        s["out"] = str(out)
    if args.json:
        emit_json(s)
    else:
        emit(f"hil plant ({kind} {where}): {s['steps']} steps at {rate:g} Hz, "
             f"{s['received']} commands received, {s['lost']} lost, {s['late']} late, "
             f"{s['bad_frames']} bad frames, {s['overruns']} overruns")
    budget = args.max_overruns
    return EXIT_OVER_BUDGET if budget is not None and s["overruns"] > budget * s["steps"] \
        else 0
