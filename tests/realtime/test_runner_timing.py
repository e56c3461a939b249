"""The real-time runner alone (open loop): generated C against the desktop step function,
per-step timing columns, clean stop on a signal."""

import json
import shutil
import signal
import subprocess
import time

import numpy as np
import pytest

from mechatron.realtime.cgen import build_host
from mechatron.realtime.hil import _read_log
from mechatron.realtime.loop import build_loop

pytestmark = pytest.mark.skipif(shutil.which("cc") is None, reason="no C compiler (cc)")


@pytest.fixture(scope="module")
def built(tmp_path_factory):
    d = tmp_path_factory.mktemp("runner")
    loop = build_loop("speed", rate=10_000.0)
    return loop, build_host(loop, d), d


def test_open_loop_run_matches_desktop_step_function(built):
    loop, exes, d = built
    steps, duty = 2000, 0.75
    subprocess.run([str(exes["plant"]), "--rate", "10000", "--steps", str(steps),
                    "--transport", "none", "--duty", str(duty), "--log", str(d / "ol.bin"),
                    "--stats", str(d / "ol.json")], check=True, capture_output=True)
    log = _read_log(d / "ol.bin")
    stats = json.loads((d / "ol.json").read_text())
    x = loop.x0.copy()
    ref = []
    for k in range(steps):                      # the desktop (CasADi VM) evaluation
        ref.append(np.array(loop.plant_out(x)).ravel())
        x = np.array(loop.plant_step(x, duty, k)).ravel()
    ref = np.array(ref)
    np.testing.assert_allclose(log["w"], ref[:, 1], rtol=1e-12, atol=1e-9)
    np.testing.assert_allclose(log["phi"], ref[:, 2], rtol=1e-12, atol=1e-12)
    assert stats["steps"] == steps and stats["overruns"] <= steps
    np.testing.assert_allclose(log["t"], np.arange(steps) / 1e4)
    assert np.all(log["wake_late_s"] > -1e-6)     # never woken before its deadline
    assert stats["max_step_time_s"] == pytest.approx(log["exec_s"].max(), rel=1e-6)
    assert stats["median_step_time_s"] <= stats["max_step_time_s"]
    # the schedule is absolute: the run takes steps / rate, not more (slack for load)
    assert stats["wall_time_s"] == pytest.approx(steps / 1e4, abs=0.05)


def test_runner_stops_cleanly_on_sigint(built):
    _, exes, d = built
    p = subprocess.Popen([str(exes["plant"]), "--rate", "10000", "--steps", "1000000",
                          "--transport", "none", "--log", str(d / "int.bin"),
                          "--stats", str(d / "int.json")], stdout=subprocess.PIPE)
    try:
        assert p.stdout.readline().startswith(b"READY")
        time.sleep(0.3)
        p.send_signal(signal.SIGINT)
        assert p.wait(timeout=10) == 0
    finally:
        if p.poll() is None:
            p.kill()
    stats = json.loads((d / "int.json").read_text())
    assert stats["interrupted"] is True
    assert 0 < stats["steps"] < 1_000_000
    assert _read_log(d / "int.bin")["t"].size == stats["steps"]
