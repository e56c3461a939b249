"""The HTML report of a HIL run: HIL and MIL traces overlaid, their difference, the
runner's timing (step time, wake-up jitter, round trip) and the bridge counters.

The page is self-contained (plots embedded as PNG); its layout is the template file
``templates/hil_report.html``.
"""

from __future__ import annotations

import base64
import html
import io
from importlib import resources
from pathlib import Path
from string import Template

import numpy as np

from mechatron._io import write_text
import mechatron as mt
from mechatron.realtime.hil import HILResult

__all__ = ["write_report"]


def _png(fig) -> str:
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=90)
    return base64.b64encode(buf.getvalue()).decode("ascii")


def _figure(rows: int):
    from matplotlib.figure import Figure   # no pyplot: no global state
    fig = Figure(figsize=(9, 2.3 * rows + 0.6), layout="constrained")
    return fig, fig.subplots(rows, 1, sharex=True, squeeze=False)[:, 0]


def _rows(items) -> str:
    out = []
    for k, v in items:
        if isinstance(v, float):
            v = f"{v:.4g}"
        out.append(f"<tr><td>{html.escape(str(k))}</td><td class=\"num\">"
                   f"{html.escape(str(v))}</td></tr>")
    return "\n".join(out)


def write_report(res: HILResult, path) -> Path:
    """Write the HTML report of ``res`` to ``path``; returns the path."""
    path = Path(path)
    c = res.comparison
    var, unit = c["variable"], c["unit"]
    label = {"w": "speed", "phi": "angle"}[var]
    n = c["steps"]
    t = res.log["t"][:n]
    fig, ax = _figure(3)
    ax[0].plot(t, res.mil["ref"][:n], "k:", lw=1, label="reference")
    ax[0].plot(t, res.mil[var][:n], lw=2, label="MIL")
    ax[0].plot(t, res.log[var][:n], "--", lw=1.2, label=res.mode.upper())
    ax[0].set_ylabel(f"{label} [{unit}]")
    ax[0].legend(loc="best")
    ax[1].plot(t, res.log[var][:n] - res.mil[var][:n], lw=1)
    ax[1].set_ylabel(f"{res.mode.upper()} - MIL [{unit}]")
    ax[2].plot(t, res.mil["duty"][:n], lw=1.5, label="MIL")
    ax[2].plot(t, res.log["duty"][:n], "--", lw=1, label=res.mode.upper())
    miss = res.log["got"][:n] < 0.5
    if miss.any():
        ax[2].plot(t[miss], res.log["duty"][:n][miss], "rx", ms=4, label="missed step")
    ax[2].set_ylabel("PWM duty [1]")
    ax[2].set_xlabel("t [s]")
    ax[2].legend(loc="best")
    traces = _png(fig)
    fig, ax = _figure(2)
    ax[0].semilogy(t, np.maximum(res.log["exec_s"][:n], 1e-9) * 1e6, ".", ms=1)
    ax[0].set_ylabel("step time [us]")
    ax[1].semilogy(t, np.maximum(res.log["wake_late_s"][:n], 1e-9) * 1e6, ".", ms=1,
                   label="wake-up lateness")
    rtt = res.log["rtt_s"][:n]
    ok = rtt >= 0
    ax[1].semilogy(t[ok], np.maximum(rtt[ok], 1e-9) * 1e6, ".", ms=1, label="round trip")
    ax[1].axhline(1e6 / res.rate, color="r", lw=1, label="period")
    ax[1].set_ylabel("time [us]")
    ax[1].set_xlabel("t [s]")
    ax[1].legend(loc="best")
    timing = _png(fig)
    s = res.summary()
    tm = res.timing
    notes = "".join(f'<p class="note">{html.escape(x)}</p>' for x in res.notes)
    page = Template(resources.files("mechatron.realtime").joinpath(
        "templates/hil_report.html").read_text()).substitute(
        title=html.escape(f"{res.name} control, {res.mode.upper()} at {res.rate:g} Hz"),
        description=html.escape(
            "Plant (RC filter, H-bridge, DC motor, encoder) and controller "
            + ("in one real-time C loop" if res.transport == "sim" else
               f"as separate processes over {res.transport}")
            + f" ({res.mode.upper()}), {res.duration:g} s at {res.rate:g} Hz, "
            f"packet loss injected: {res.loss:g}. MIL runs the same step functions in "
            "one process."),
        notes=notes,
        comparison_rows=_rows([
            ("compared variable", f"{label} ({var}) [{unit}]"),
            ("reference size", c["ref_scale"]),
            ("RMS difference", c["rms_diff"]), ("RMS difference [% of reference]",
                                                 c["rms_diff_percent"]),
            ("peak difference", c["peak_diff"]), ("peak difference [% of reference]",
                                                   c["peak_diff_percent"])]),
        timing_rows=_rows([(k, v) for k, v in [
            ("steps (requested)", f"{s['steps']} ({s['requested_steps']})"),
            ("overruns", f"{s['overruns']} ({s['overrun_percent']:.3g} %)"),
            ("median step time [s]", tm["step_time_median_s"]),
            ("99th percentile step time [s]", tm["step_time_p99_s"]),
            ("worst step time [s]", tm["step_time_max_s"]),
            ("median wake-up jitter [s]", tm.get("jitter_median_s")),
            ("99th percentile wake-up jitter [s]", tm.get("jitter_p99_s")),
            ("worst wake-up jitter [s]", tm.get("jitter_max_s")),
            ("99th percentile period jitter [s]", tm.get("period_jitter_p99_s")),
            ("median round trip [s]", tm.get("round_trip_median_s")),
            ("worst round trip [s]", tm.get("round_trip_max_s")),
            ("real-time factor", tm["realtime_factor"]),
            ("SCHED_FIFO", s["realtime_scheduling"])] if v is not None]),
        bridge_rows=_rows([
            ("missed steps (no reply in time)", s["missed_steps"]),
            ("late packets", s["late_packets"]), ("lost packets", s["lost_packets"]),
            ("dropped on purpose by the plant", s["dropped_on_purpose"]["plant"]),
            ("dropped on purpose by the controller",
             s["dropped_on_purpose"]["controller"]),
            ("samples the controller filled in", s["controller_lost_samples"])]),
        traces_png=traces, timing_png=timing, version=html.escape(mt.__version__))
    return write_text(path, page)
