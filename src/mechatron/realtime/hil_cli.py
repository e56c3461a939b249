"""The ``mechatron hil`` command (added by :mod:`mechatron.realtime.cli`)."""

from __future__ import annotations

import argparse

from mechatron.realtime.loop import EXPERIMENTS

__all__ = ["add_hil_command", "cmd_hil"]


def add_hil_command(sub) -> None:
    """Add ``hil`` to the ``mechatron`` sub-parsers."""
    from mechatron.cli import add_json
    p = sub.add_parser(
        "hil", help="hardware-in-the-loop experiment (SIL or PIL) against MIL",
        description="Run the DC motor (RC-filtered PWM, H-bridge, encoder) as a real-time "
                    "plant process and the generated controller as a separate process "
                    "(SIL) or as firmware on an emulated Cortex-M3 in QEMU (PIL), "
                    "compare with model-in-the-loop, and report timing and packet "
                    "statistics. Experiments: "
                    + "; ".join(f"{k}: {e.doc}" for k, e in EXPERIMENTS.items()))
    p.add_argument("name", metavar="NAME", choices=sorted(EXPERIMENTS),
                   help="experiment: " + ", ".join(EXPERIMENTS))
    p.add_argument("--mode", choices=("sil", "pil"), default="sil",
                   help="sil: controller as a host process; pil: firmware in QEMU "
                        "(default: %(default)s)")
    p.add_argument("--duration", type=float, default=2.0, metavar="S",
                   help="simulated time in s (default: %(default)s)")
    p.add_argument("--rate", type=float, default=10_000.0, metavar="HZ",
                   help="plant step rate in Hz (default: %(default)s)")
    p.add_argument("--loss", type=float, default=0.0, metavar="P",
                   help="drop each packet on purpose with probability P (default: 0)")
    p.add_argument("--transport", choices=("udp", "pty"), default="udp",
                   help="SIL bridge: UDP on loopback or a pseudo-terminal serial line "
                        "(default: %(default)s)")
    p.add_argument("--lockstep", action="store_true",
                   help="SIL: wait for every reply instead of keeping real time (no "
                        "missed steps: SIL then reproduces MIL to rounding)")
    p.add_argument("--no-rt", action="store_true",
                   help="do not ask for real-time scheduling (SCHED_FIFO)")
    p.add_argument("--seed", type=int, default=1, help="seed of the loss injection")
    p.add_argument("--report", metavar="FILE.html", help="write the HTML report")
    add_json(p)
    p.set_defaults(func=cmd_hil)


def cmd_hil(args: argparse.Namespace) -> int:
    from mechatron.cli import emit, emit_json, output_path, table
    from mechatron.realtime.hil import run_hil
    report = output_path(args.report, "--report", (".html", ".htm"))
    res = run_hil(args.name, mode=args.mode, duration=args.duration, rate=args.rate,
                  loss=args.loss, transport=args.transport, realtime=not args.no_rt,
                  seed=args.seed, lockstep=args.lockstep)
    s = res.summary()
    if report is not None:
        from mechatron.realtime.report import write_report
        write_report(res, report)
        s["report"] = str(report)
    if args.json:
        emit_json(s)
        return 0
    tm = res.timing
    c = res.comparison

    def us(x):
        return "-" if x is None else f"{x * 1e6:.2f} us"

    emit(f"hil {res.name} ({res.mode.upper()}): {s['steps']} of {s['requested_steps']} "
         f"steps at {res.rate:g} Hz, loss {res.loss:g}")
    emit(table(["figure", "value"], [
        [f"RMS difference of {c['variable']} vs MIL", f"{c['rms_diff']:.4g} {c['unit']} "
         f"({c['rms_diff_percent']:.4g} % of {c['ref_scale']:g})"],
        [f"peak difference of {c['variable']} vs MIL",
         f"{c['peak_diff']:.4g} {c['unit']} ({c['peak_diff_percent']:.4g} %)"],
        ["step time median / p99 / max", f"{us(tm['step_time_median_s'])} / "
         f"{us(tm['step_time_p99_s'])} / {us(tm['step_time_max_s'])}"],
        ["wake-up jitter median / max", f"{us(tm['jitter_median_s'])} / "
         f"{us(tm['jitter_max_s'])}"],
        ["round trip median / max", f"{us(tm['round_trip_median_s'])} / "
         f"{us(tm['round_trip_max_s'])}"],
        ["overruns", s["overruns"]],
        ["missed steps / late / lost packets",
         f"{s['missed_steps']} / {s['late_packets']} / {s['lost_packets']}"],
        ["dropped on purpose (plant, controller)",
         f"{s['dropped_on_purpose']['plant']}, {s['dropped_on_purpose']['controller']}"],
        ["SCHED_FIFO", s["realtime_scheduling"]],
        ["real-time factor", f"{tm['realtime_factor']:.3g}"],
    ], indent="  "))
    for note in res.notes:
        emit(f"note: {note}")
    if report is not None:
        emit(f"report: {report}")
    return 0
