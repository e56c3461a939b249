"""The explorer in headless Chromium: a scripted user session (scenario_basic.js, run by
the page itself from its address) opens the DC motor, plots two signals by clicking the
variable tree, changes a parameter and sees the plot change, overlays a second run and a
CSV measurement, zooms, enters a parameter of the wrong unit, and exports a PNG.

The page posts what it saw to the server; the test reads that report and keeps the
exported PNG and a screenshot of the final page as artifacts (in ``tmp_path``, or in the
folder named by ``MECHATRON_TEST_ARTIFACTS``). Skipped when Chromium is not installed
(``make`` installs it as root, see tools/sysdeps.sh).
"""

from __future__ import annotations

import base64
import json
import os
import shutil
import subprocess
import time
from pathlib import Path
from urllib.parse import parse_qsl, urlencode

import numpy as np
import pytest

from mechatron.explore import ExploreServer, Workspace
from mechatron.results import SimResult

CHROMIUM = next((p for p in ("/usr/bin/chromium", shutil.which("chromium") or "",
                             shutil.which("chromium-browser") or "") if p and Path(p).exists()),
                None)
pytestmark = pytest.mark.skipif(CHROMIUM is None, reason="Chromium is not installed "
                                "(/usr/bin/chromium); `make test` as root installs it")
PNG = b"\x89PNG\r\n\x1a\n"


def chromium(profile: Path, url: str, *args: str) -> subprocess.CompletedProcess:
    return subprocess.run(
        [CHROMIUM, "--headless", "--no-sandbox", "--disable-gpu", "--no-first-run",
         "--disable-background-networking", "--disable-component-update", "--disable-sync",
         f"--user-data-dir={profile}", "--window-size=1400,860",
         "--enable-logging=stderr", "--v=0",        # the page's console, for failures
         # virtual time stands still while requests are pending, so the budget is spent
         # only on the page's own waits
         "--virtual-time-budget=120000", *args, url],
        capture_output=True, text=True, timeout=300)


def _console(run: subprocess.CompletedProcess) -> str:
    lines = [line for line in run.stderr.splitlines() if "CONSOLE" in line]
    return "\n".join(lines[-20:]) or run.stderr[-3000:]


@pytest.fixture
def artifacts(tmp_path):
    folder = os.environ.get("MECHATRON_TEST_ARTIFACTS")
    path = Path(folder) / "explore" if folder else tmp_path / "artifacts"
    path.mkdir(parents=True, exist_ok=True)
    return path


def test_a_user_session_in_headless_chromium(tmp_path, artifacts):
    # a "measurement": the first-order approximation of the motor's speed, with noise
    t = np.linspace(0.0, 0.5, 501)
    w = 122.44 * (1.0 - np.exp(-t / 3e-3)) + np.random.default_rng(3).normal(0, 1, t.size)
    SimResult(t, [w], ["inertia.w"], ["rad/s"]).save(tmp_path / "measured.csv")

    server = ExploreServer(Workspace(), port=0)
    server.start()
    try:
        query = urlencode({"scenario": "basic", "csv": str(tmp_path / "measured.csv")})
        run = chromium(tmp_path / "profile", f"{server.url}?{query}", "--dump-dom")
        for _ in range(100):                     # the report is posted just before exit
            if server.scenario_report:
                break
            time.sleep(0.1)
        report = server.scenario_report
        assert report, "the scenario posted no report; the page's console:\n" + _console(run)
        failed = [c for c in report["checks"] if not c["ok"]]
        assert not failed, failed
        names = {c["what"] for c in report["checks"]}
        for step in ("two signals plotted", "half the voltage gives half the speed",
                     "both runs drawn", "difference to the first run at t_stop",
                     "measurement overlaid", "dragging zooms to the dragged span", "wrong unit reported in the page",
                     "server still serves", "PNG export", "CSV export of a selection"):
            assert step in names
        (artifacts / "explore_report.json").write_text(
            json.dumps({k: v for k, v in report.items() if k != "png"}, indent=1))
        png = base64.b64decode(report["png"].split(",", 1)[1])
        assert png.startswith(PNG)
        (artifacts / "explore_export.png").write_bytes(png)

        # the final state of the session, from its address, as a screenshot
        address = [kv for kv in parse_qsl(report["address"].lstrip("?")) if kv[0] != "scenario"]
        shot = artifacts / "explore_session.png"
        chromium(tmp_path / "profile2", f"{server.url}?{urlencode(address)}",
                 f"--screenshot={shot}")
        assert shot.read_bytes().startswith(PNG) and shot.stat().st_size > 20_000
    finally:
        server.shutdown()
        server.server_close()


def test_a_log_of_10000_variables_stays_responsive(tmp_path, artifacts):
    # 10,000 variables x 20,001 points, without the memory: every row is one array
    t = np.linspace(0.0, 1.0, 20_001)
    row = np.sin(2 * np.pi * 40 * t)
    names = [f"part{k // 10}.sub{k % 10}.x" for k in range(10_000)]
    res = SimResult(t, np.broadcast_to(row, (len(names), t.size)), names, ["m"] * len(names))
    workspace = Workspace()
    run = workspace.add_result(res, "large")
    server = ExploreServer(workspace, port=0, startup={"view": "results", "run": run.id})
    server.start()
    try:
        out = chromium(tmp_path / "profile", f"{server.url}?scenario=large", "--dump-dom")
        for _ in range(100):
            if server.scenario_report:
                break
            time.sleep(0.1)
        report = server.scenario_report
        assert report, "the scenario posted no report; the page's console:\n" + _console(out)
        (artifacts / "explore_large_report.json").write_text(json.dumps(report, indent=1))
        failed = [c for c in report["checks"] if not c["ok"]]
        assert not failed, failed
        assert len(report["checks"]) == 6
    finally:
        server.shutdown()
        server.server_close()

