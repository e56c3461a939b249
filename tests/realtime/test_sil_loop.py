"""SIL in one real-time C loop (mt_sil): the generated plant and controller against MIL,
the lost-sample and overrun accounting, the overrun budget, refused privileges reported;
`mechatron hil plant` over UDP against the generated controller process."""

import json
import shutil
import socket
import subprocess
import threading
import time
import warnings

import numpy as np
import pytest

from mechatron.cli import main
from mechatron.realtime.cgen import build_host
from mechatron.realtime.hil import OverrunWarning, run_hil
from mechatron.realtime.loop import LOG_COLUMNS, build_loop, run_mil

pytestmark = pytest.mark.skipif(shutil.which("cc") is None, reason="no C compiler (cc)")


def _no_null(obj, path="summary"):
    if isinstance(obj, dict):
        for k, v in obj.items():
            _no_null(v, f"{path}.{k}")
    elif isinstance(obj, list):
        for i, v in enumerate(obj):
            _no_null(v, f"{path}[{i}]")
    else:
        assert obj is not None, path


def _mil_replaying(loop, got: np.ndarray) -> dict[str, np.ndarray]:
    """MIL stepped as the one loop stepped with the samples it lost (``got[k]`` 0: step
    k started a period late and skipped its exchange; sil_loop.c, ctrl_core.c): the
    plant holds the previous duty over that step and the controller does not run; the
    next sample that arrives first runs the controller once for each step lost before
    it, with ``valid = 0`` (it extrapolates the count), then for its own. Every step is
    logged as `run_mil` logs it. With no sample lost it is `run_mil`, step by step."""
    x, xc = loop.x0, loop.xc0
    duty, ref = None, None
    pending = []                        # the steps lost since the last exchange
    rows = []
    for k in range(got.size):
        meas = np.asarray(loop.plant_out(x), dtype=float).ravel()
        if got[k]:
            for j in pending:
                xc, _ = loop.ctrl_step(xc, 0.0, j, 0)
            pending = []
            xc, out = loop.ctrl_step(xc, meas[0], k, 1)
            out = np.asarray(out, dtype=float).ravel()
            duty, ref = out[0], out[1]
        else:
            assert duty is not None, "the first sample was lost: no duty to hold"
            pending.append(k)
        rows.append([k * loop.dt, duty, ref, *meas])
        x = loop.plant_step(x, duty, k)
    return dict(zip(LOG_COLUMNS, np.array(rows).T))


@pytest.mark.parametrize("name,var", [("speed", "w"), ("position", "phi")])
def test_one_loop_equals_mil_with_its_lost_samples_replayed(name, var):
    """A real-time run on a shared machine loses a few samples wherever the host delays
    a step (a step that starts a period late skips its exchange). MIL stepped with the
    same samples lost (`_mil_replaying`) is the same functions on the desktop: the run
    equals it at every step to rounding, the reference step at 0.05 s and the lost
    samples' extrapolation included."""
    loop = build_loop(name, rate=10_000.0)
    # replaying with nothing lost is MIL itself (checked at once, run or no run)
    plain, mil = _mil_replaying(loop, np.ones(3000, dtype=bool)), run_mil(loop, 3000)
    for col in LOG_COLUMNS:
        np.testing.assert_allclose(plain[col], mil[col], rtol=0,
                                   atol=1e-12 * max(1.0, np.max(np.abs(plain[col]))))
    for _attempt in range(3):       # (a pause of 0.1 s or more restarts the controller)
        res = run_hil(name, duration=0.3, rate=10_000.0)
        if res.longest_gap < 1000 and res.log["got"][0] == 1:
            break
    got = res.log["got"] == 1
    s = res.summary()
    assert s["transport"] == "sim" and s["steps"] == 3000
    mil = _mil_replaying(loop, got)
    for col in ("duty", "ref"):        # the same functions in C: equal to rounding
        np.testing.assert_allclose(res.log[col], mil[col], rtol=0, atol=1e-12)
    scale = np.max(np.abs(mil[var]))
    np.testing.assert_allclose(res.log[var], mil[var], atol=1e-12 * scale)
    # with no sample lost, that is the run's own comparison with MIL
    if got.all():
        np.testing.assert_allclose(res.log[var], res.mil[var], atol=1e-12 * scale)
    # every figure of the report is a number (no null), jitter given as percentiles
    _no_null(s)
    tm = s["timing"]
    for p in ("median", "p90", "p99", "p999", "max"):
        assert tm[f"jitter_{p}_s"] >= 0 and tm[f"period_jitter_{p}_s"] >= 0
    assert tm["jitter_median_s"] <= tm["jitter_p99_s"] <= tm["jitter_max_s"]
    assert s["lost_samples"] == s["missed_steps"] == int((~got).sum())
    assert s["overrun_percent"] == pytest.approx(100 * s["overruns"] / 3000)
    if s["cpu"] >= 0:                  # pinned: the idle-priority spinner ran beside it
        assert s["keep_awake"] is True


def test_injected_loss_is_counted_once_and_filled_in_by_the_controller(on_schedule):
    res = on_schedule("speed", duration=0.5, rate=10_000.0, loss=0.02, seed=3)
    s, r = res.summary(), res.runner
    dropped = s["dropped_on_purpose"]["plant"] + s["dropped_on_purpose"]["controller"]
    assert 100 <= dropped <= 300                          # ~2 % of 2 x 5000
    assert s["lost_samples"] == dropped + r["skipped_samples"] == s["missed_steps"]
    # the controller saw the gaps in the sequence (all but trailing ones) and filled them
    unseen = s["dropped_on_purpose"]["plant"] + r["skipped_samples"]
    assert unseen - 3 <= s["controller_lost_samples"] <= unseen
    assert s["rms_diff_percent"] < 2.0
    assert np.all(res.log["duty"][res.log["got"] == 0][1:] >= 0)


def test_overrun_budget_warns_and_exits_3(tmp_path):
    """Scheduled at 1 MHz no step (a few us) fits its 1 us period: the budget is exceeded
    for sure (the model is built for 10 kHz; only the schedule matters here)."""
    exes = build_host(build_loop("speed", rate=10_000.0), tmp_path)
    p = subprocess.run([str(exes["sil"]), "--rate", "1000000", "--steps", "2000",
                        "--max-overruns", "0.001", "--stats", str(tmp_path / "s.json")],
                       capture_output=True, text=True)
    assert p.returncode == 3
    assert "exceed the budget of 0.1 %" in p.stderr
    stats = json.loads((tmp_path / "s.json").read_text())
    assert stats["over_budget"] is True and stats["overruns"] > 2
    assert stats["steps"] == 2000                 # the run still went to its end


def test_budget_in_the_api_and_refused_pinning_is_a_note():
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        res = run_hil("speed", duration=0.1, rate=10_000.0, max_overruns=0.0, cpu=4095)
    over = res.runner["overruns"] > 0
    assert res.over_budget is over and res.summary()["over_budget"] is over
    budget = [w for w in caught if issubclass(w.category, OverrunWarning)]
    assert len(budget) == int(over)
    if over:
        assert "exceed the budget of 0 %" in str(budget[0].message)
    assert res.summary()["overrun_budget_percent"] == 0.0
    assert any(n.startswith("CPU pinning refused") and "ran without it" in n
               for n in res.notes)
    assert res.summary()["cpu"] == -1


def test_cli_hil_plant_over_udp_against_the_controller_process(tmp_path, capsys):
    exes = build_host(build_loop("speed", rate=500.0), tmp_path)
    s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    s.bind(("127.0.0.1", 0))
    port = s.getsockname()[1]
    s.close()
    codes = []
    t = threading.Thread(target=lambda: codes.append(main(
        ["hil", "plant", "--udp-port", str(port), "--experiment", "speed", "--rate", "500",
         "--duration", "0.2", "--json", "--out", str(tmp_path / "plant.csv")])))
    t.start()
    ctrl = None
    try:
        time.sleep(1.0)                   # the plant binds its port first
        ctrl = subprocess.Popen([str(exes["controller"]), "--udp", str(port),
                                 "--stats", str(tmp_path / "c.json")])
        t.join(timeout=60)
        assert ctrl.wait(timeout=10) == 0
    finally:
        if ctrl is not None and ctrl.poll() is None:
            ctrl.kill()
    assert codes == [0]
    out = json.loads(capsys.readouterr().out)
    assert out["kind"] == "udp" and out["steps"] == 100
    assert out["received"] + out["lost"] == 100 and out["bad_frames"] == 0
    data = np.genfromtxt(tmp_path / "plant.csv", delimiter=",", names=True)
    # a Python loop on a loaded machine misses some 1.6 ms reply windows: whatever
    # came in time is counted received, the rest lost, and the log says which
    assert data.size == 100 and data["got"].sum() == out["received"] > 0
    assert data["w"][-1] > 1.0            # the controller's commands drove the motor
    cstats = json.loads((tmp_path / "c.json").read_text())
    assert cstats["samples"] == 100 and cstats["stopped"] is True
