"""SIL: plant runner and generated controller as separate processes, against MIL."""

import json
import os
import shutil
import signal
import threading
import time
from pathlib import Path

import numpy as np
import pytest

from mechatron.cli import main
from mechatron.errors import SimulationError
from mechatron.realtime.hil import STALL_S, run_hil

pytestmark = pytest.mark.skipif(shutil.which("cc") is None, reason="no C compiler (cc)")


def _check_timing_reported(res, steps):
    for col in ("exec_s", "wake_late_s", "busy_s"):
        a = res.log[col]
        assert a.size == steps and np.all(np.isfinite(a))
    assert np.all(res.log["exec_s"] > 0)
    s = res.summary()
    assert s["max_step_time_s"] == pytest.approx(res.log["exec_s"].max(), rel=1e-6)
    assert 0 <= s["overruns"] <= steps


@pytest.mark.parametrize("name,var", [("speed", "w"), ("position", "phi")])
def test_sil_2s_at_10khz_agrees_with_mil(name, var, on_schedule):
    res = on_schedule(name, duration=2.0, rate=10_000.0)
    assert res.runner["steps"] == 20_000
    _check_timing_reported(res, 20_000)
    # the percentage is recomputed here from the raw logs, not taken from the code
    d = res.log[var] - res.mil[var]
    ref_size = np.max(np.abs(res.mil["ref"]))
    rms_pct = 100 * np.sqrt(np.mean(d ** 2)) / ref_size
    assert rms_pct < 2.0
    assert res.summary()["rms_diff_percent"] == pytest.approx(rms_pct, rel=1e-9)
    # and the loop did its job: the plant followed the reference
    assert np.mean(res.log[var][-1000:]) == pytest.approx(res.mil["ref"][-1], rel=0.02)


def _pause_the_loop(at, length):
    """Stop the SIL loop (``mt_sil``, a child of this process) ``at`` s after it starts,
    for ``length`` s: the pause a host gives a virtual machine. Returns the thread."""
    def pause():
        me, deadline = str(os.getpid()), time.monotonic() + 120
        while time.monotonic() < deadline:
            for d in Path("/proc").iterdir():
                try:
                    stat = (d / "stat").read_text()
                    args = (d / "cmdline").read_bytes().split(b"\0")
                except (OSError, ValueError):
                    continue
                if stat.split(") ")[-1].split()[1] == me and b"--rate" in args \
                        and args[0].endswith(b"mt_sil"):
                    time.sleep(at)
                    os.kill(int(d.name), signal.SIGSTOP)
                    time.sleep(length)
                    os.kill(int(d.name), signal.SIGCONT)
                    return
            time.sleep(0.002)
    t = threading.Thread(target=pause, daemon=True)
    t.start()
    return t


@pytest.mark.skipif(not Path("/proc/self/stat").exists(), reason="needs /proc")
def test_a_paused_loop_reports_the_stall_and_its_cost(on_schedule):
    # paused for 0.2 s (2000 periods) early in a 2 s run (room for a slow start), the loop
    # catches up by stepping the plant with the duty held: the run names the stall, and
    # the gap in its log spans the pause
    pauser = _pause_the_loop(at=0.3, length=0.2)
    res = run_hil("speed", mode="sil", duration=2.0, rate=10_000.0)
    pauser.join(timeout=5)
    assert not pauser.is_alive()
    gap = res.longest_gap
    assert 1500 <= gap <= res.runner["steps"]
    assert res.summary()["longest_gap_steps"] == gap
    got = res.log["got"]
    assert np.sum(got == 0) == res.runner["missed_steps"] >= gap
    assert any("stalled" in n and f"{gap} consecutive steps" in n for n in res.notes)
    # a kept schedule has no such gap, and says nothing of a stall
    calm = on_schedule("speed", duration=0.3, rate=10_000.0)
    assert calm.longest_gap < STALL_S * 10_000
    assert not any("stalled" in n for n in calm.notes)


@pytest.mark.parametrize("name,var", [("speed", "w"), ("position", "phi")])
def test_sil_in_lockstep_reproduces_mil_to_rounding(name, var):
    """No step missed: the generated controller (mechatron.codegen C of the block model)
    and the generated plant, as two processes, repeat MIL's desktop run of the same
    functions to rounding, step by step, through the reference step at 0.05 s."""
    res = run_hil(name, mode="sil", duration=0.15, rate=10_000.0, lockstep=True)
    assert res.runner["steps"] == 1500 and res.runner["missed_steps"] == 0
    assert np.all(res.log["got"] == 1)
    for col in ("duty", "ref"):
        np.testing.assert_allclose(res.log[col], res.mil[col], rtol=0, atol=1e-12)
    scale = np.max(np.abs(res.mil[var]))
    assert scale > 1.0                       # the loop moved the motor
    np.testing.assert_allclose(res.log[var], res.mil[var], rtol=0, atol=1e-12 * scale)
    assert any("lockstep" in n for n in res.notes)


def test_sil_with_one_percent_loss_completes_counts_and_stays_stable(on_schedule):
    # the two-process bridge (its replies can come late, not only be dropped); the
    # one-process loop's accounting is tested in test_sil_loop.py
    res = on_schedule("speed", duration=1.0, rate=10_000.0, loss=0.01, seed=7,
                      transport="udp")
    s = res.summary()
    assert s["steps"] == 10_000
    dropped = s["dropped_on_purpose"]["plant"] + s["dropped_on_purpose"]["controller"]
    assert 100 <= dropped <= 320           # ~1 % of ~2 x 10000 packets
    # each dropped packet costs its step its reply; only drops are lost (late ones came)
    assert s["lost_packets"] == dropped
    assert s["missed_steps"] >= dropped
    assert s["controller_lost_samples"] == s["dropped_on_purpose"]["plant"]
    assert s["rms_diff_percent"] < 2.0
    assert np.all(np.abs(res.log["w"]) < 130)          # bounded: below the no-load speed


def test_sil_over_a_pseudo_terminal():
    # a tty's round trip (~50-500 us under load) does not fit a 100 us period reliably;
    # 2 kHz is the rate a serial line between two processes keeps
    res = run_hil("position", mode="sil", duration=0.5, rate=2_000.0, transport="pty")
    assert res.runner["steps"] == 1000
    assert res.runner["received"] > 0 and res.runner["bad_frames"] == 0
    assert res.summary()["rms_diff_percent"] < 2.0


def test_cli_json_and_report(tmp_path, capsys):
    report = tmp_path / "hil.html"
    code = main(["hil", "speed", "--mode", "sil", "--duration", "0.2", "--rate", "5000",
                 "--loss", "0.01", "--json", "--report", str(report)])
    assert code == 0
    out = json.loads(capsys.readouterr().out)
    for key in ("steps", "overruns", "lost_packets", "rms_diff_percent",
                "max_step_time_s"):
        assert key in out
    assert out["steps"] == 1000
    text = report.read_text()
    assert "data:image/png;base64," in text and "RMS difference" in text


@pytest.mark.parametrize("kwargs,match", [
    ({"mode": "hil"}, "--mode must be"),
    ({"loss": 1.5}, "--loss is a probability"),
    ({"duration": -1.0}, "--duration must be"),
    ({"rate": 0.0}, "--rate must be"),
])
def test_bad_input_is_a_clear_error(kwargs, match):
    with pytest.raises(SimulationError, match=match):
        run_hil("speed", **kwargs)


def test_unknown_experiment_cli(capsys):
    assert main(["hil", "nosuch"]) == 2


def test_lockstep_hil_with_packet_loss_waits_no_2_s_per_lost_packet():
    """Lockstep over UDP with 5 % injected loss: a lost packet used to cost its step the
    whole reply timeout (pil_timeout, 2 s), ~200 losses here, some 400 s. Once replies
    have come, a step waits only a bounded multiple of their round trip; every loss is
    counted and reported."""
    steps, rate, pil_timeout = 2000, 10_000.0, 2.0
    res = run_hil("speed", mode="sil", duration=steps / rate, rate=rate, loss=0.05, seed=3,
                  transport="udp", lockstep=True, pil_timeout=pil_timeout)
    s = res.summary()
    assert s["steps"] == steps
    dropped = s["dropped_on_purpose"]["plant"] + s["dropped_on_purpose"]["controller"]
    assert 100 <= dropped <= 300             # ~5 % of ~2 x 2000 packets
    # every dropped packet cost its step its reply, and is reported as lost
    assert s["lost_packets"] + s["late_packets"] == s["missed_steps"] >= dropped
    assert s["lost_packets"] >= 1
    assert any("lost" in n and "held the previous duty" in n for n in s["notes"])
    # the wait for a lost reply: bounded well under the start-up timeout
    assert 0 < s["reply_timeout_s"] <= 0.25 * pil_timeout
    # no stall: the run's wall time is the steps plus one bounded wait per loss, far
    # below one pil_timeout per lost packet (generous: 4x the bounded waits + 10 s)
    bound = steps / rate + 4 * s["missed_steps"] * s["reply_timeout_s"] + 10.0
    assert res.runner["wall_time_s"] < min(bound, 0.25 * dropped * pil_timeout)
    # the controller filled in the samples it never got, and the loop stayed stable
    assert s["controller_lost_samples"] == s["dropped_on_purpose"]["plant"]
    assert np.all(np.abs(res.log["w"]) < 130)


def test_some_plots_lack_quantity_names_and_units(tmp_path, capsys, saved_figures):
    """The HIL report's traces and timing plots: each axis a quantity with its unit."""
    code = main(["hil", "speed", "--mode", "sil", "--duration", "0.05", "--rate", "5000",
                 "--loss", "0.01", "--json", "--report", str(tmp_path / "hil.html")])
    capsys.readouterr()
    assert code == 0
    assert len(saved_figures) == 2
    assert saved_figures.problems() == []
