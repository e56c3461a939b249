"""The explorer's JSON API, with the server on an ephemeral port in a thread: every
endpoint, bad input answered with a clear JSON error while the server keeps serving, and
the physics of what it simulates checked against the DC motor's analytic solution."""

from __future__ import annotations

import csv
import io
import json
import shutil
import urllib.error
import urllib.request

import numpy as np
import pytest

import mechatron as mt
from mechatron.explore import ExploreServer, Workspace
from mechatron.results import SimResult

# the seed's DC motor (dc_motor's defaults): final speed k V / (R B + k^2)
V, R, K, B = 19.2, 7.1, 0.151, 1.236e-4


def w_final(v=V, r=R):
    return K * v / (r * B + K * K)


@pytest.fixture(scope="module")
def server():
    srv = ExploreServer(Workspace(), port=0)
    srv.start()
    yield srv
    srv.shutdown()
    srv.server_close()


def call(server, path, body=None, method=None, raw=None, headers=None):
    """``(status, answer)``: JSON decoded when the answer is JSON, else bytes."""
    data = raw if raw is not None else (None if body is None else json.dumps(body).encode())
    req = urllib.request.Request(server.url + path.lstrip("/"), data=data, method=method,
                                 headers={"Content-Type": "application/json", **(headers or {})})
    try:
        with urllib.request.urlopen(req, timeout=120) as r:
            status, ctype, payload = r.status, r.headers["Content-Type"], r.read()
    except urllib.error.HTTPError as e:
        status, ctype, payload = e.code, e.headers["Content-Type"], e.read()
    if ctype.startswith("application/json"):
        return status, json.loads(payload)
    return status, payload


def error(server, path, status=400, **kw):
    got, answer = call(server, path, **kw)
    assert got == status, answer
    assert set(answer) == {"error"}
    # the server keeps serving
    assert call(server, "/api/models")[0] == 200
    return answer["error"]


# ------------------------------------------------------------------ page and database
def test_page_and_its_scripts_are_served(server):
    status, page = call(server, "/")
    assert status == 200 and b"<title>Mechatron explorer</title>" in page
    for name in ("app.js", "plot.js", "app.css"):
        status, body = call(server, f"/static/{name}")
        assert status == 200 and len(body) > 1000
    # nothing is fetched from elsewhere
    assert b"http" not in page.replace(b"http-equiv", b"")
    assert b"https://" not in call(server, "/static/app.js")[1]


def test_models_and_one_entry(server):
    status, models = call(server, "/api/models")
    assert status == 200
    names = {m["name"]: m for m in models}
    assert len(names) == len(mt.models.list())
    assert "acausal" in names["dc_motor"]["variants"]
    status, entry = call(server, "/api/models/dc_motor")
    params = {p["name"]: p for p in entry["parameters"]}
    assert params["L"]["unit"] == "H" and params["L"]["default"] == pytest.approx(3.408e-4)
    assert "6-1" in params["L"]["source"]                     # provenance: the seed's table
    assert entry["default_variant"] in entry["variants"]
    status, parts = call(server, "/api/models/dc_motor/parts")
    kinds = {p["path"]: p["class"] for p in parts}
    assert kinds["inductor"] == "Inductor" and "L di/dt" in \
        next(p["doc"] for p in parts if p["path"] == "inductor").replace("``", "").replace("*", "")


def test_unknown_model_is_a_clear_error(server):
    message = error(server, "/api/models/dc_motr")
    assert "no model 'dc_motr'" in message and "dc_motor" in message
    message = error(server, "/api/simulate", body={"model": "dc_motr"})
    assert "dc_motor" in message
    message = error(server, "/api/simulate", body={"model": "dc_motor", "variant": "nope"})
    assert "no variant 'nope'" in message and "acausal" in message


@pytest.mark.skipif(shutil.which("dot") is None, reason="Graphviz's dot is not installed")
def test_diagram_is_svg_with_the_parts(server):
    status, svg = call(server, "/api/models/dc_motor/diagram?variant=acausal")
    assert status == 200 and svg.startswith(b"<svg")
    for part in (b"inductor", b"emf", b"inertia"):
        assert part in svg


def test_library_sections(server):
    status, sections = call(server, "/api/library")
    assert status == 200
    by_name = {s["name"]: s for s in sections}
    comps = {c["name"]: c for c in by_name["electrical"]["components"]}
    inductor = comps["Inductor"]
    assert {p["name"]: p["unit"] for p in inductor["parameters"]}["L"] == "H"
    assert {"p", "n"} <= {p["name"] for p in inductor["ports"]}
    assert inductor["doc"]


# ------------------------------------------------------------------ simulation and signals
def test_simulate_then_change_parameters_without_recompiling(server, monkeypatch):
    status, run = call(server, "/api/simulate", body={"model": "dc_motor"})
    assert status == 200 and run["kind"] == "simulation" and run["n_vars"] > 20
    status, sig = call(server, f"/api/runs/{run['id']}/signal?name=inertia.w&width=2000")
    assert sig["unit"] == "rad/s" and not sig["decimated"]
    assert sig["y"][-1] == pytest.approx(w_final(), rel=1e-5)
    status, params = call(server, "/api/models/dc_motor/parameters")
    units = {p["path"]: p["unit"] for p in params}
    assert units["inductor.L"] == "H" and units["source.V"] == "V"

    def no_compile(*args, **kwargs):
        raise AssertionError("the model was compiled again")

    monkeypatch.setattr(mt, "compile_model", no_compile)
    status, half = call(server, "/api/simulate",
                        body={"model": "dc_motor", "params": {"source.V": "9.6 V"},
                              "replace": run["id"]})
    assert status == 200 and half["id"] == run["id"] and half["params"] == {"source.V": 9.6}
    status, sig2 = call(server, f"/api/runs/{run['id']}/signal?name=inertia.w&width=2000")
    # linear model from rest: the whole response scales with the voltage
    assert np.allclose(sig2["y"], np.asarray(sig["y"]) / 2, rtol=1e-4, atol=1e-6 * w_final())
    status, other = call(server, "/api/simulate",
                         body={"model": "dc_motor", "params": {"resistor.R": 14.2,
                                                               "inductor.L": "340 uH"}})
    assert other["id"] != run["id"]
    status, sig3 = call(server, f"/api/runs/{other['id']}/signal?name=inertia.w&width=2000")
    assert sig3["y"][-1] == pytest.approx(w_final(r=14.2), rel=1e-5)


def test_concurrent_changes_each_get_their_own_answer(server):
    from concurrent.futures import ThreadPoolExecutor

    def one(v):
        status, run = call(server, "/api/simulate",
                           body={"model": "dc_motor", "params": {"source.V": v}})
        status, sig = call(server, f"/api/runs/{run['id']}/signal?name=inertia.w&width=50")
        return sig["y"][-1]

    volts = [6.0, 12.0, 18.0, 24.0]
    with ThreadPoolExecutor(4) as pool:
        finals = list(pool.map(one, volts))
    assert finals == pytest.approx([w_final(v) for v in volts], rel=1e-5)


def test_wrong_unit_and_unknown_parameter(server):
    message = error(server, "/api/simulate",
                    body={"model": "dc_motor", "params": {"inductor.L": "3 V"}})
    assert "inductor.L" in message and "H" in message and "3 V" in message
    message = error(server, "/api/simulate",
                    body={"model": "dc_motor", "params": {"inductor.LL": 1e-3}})
    assert "inductor.LL" in message and "inductor.L" in message
    message = error(server, "/api/simulate",
                    body={"model": "dc_motor", "params": {"resistor.R": -1}})
    assert "resistor.R must be >= 0" in message
    message = error(server, "/api/simulate", body={"model": "dc_motor", "t_stop": -1})
    assert "stop time" in message
    assert "not JSON" in error(server, "/api/simulate", raw=b"{nope", method="POST")


def test_signal_is_decimated_to_the_width_and_exact_in_a_window(server, tmp_path):
    ws = server.workspace
    t = np.linspace(0.0, 1.0, 200_001)
    y = np.sin(2 * np.pi * 50 * t) * t
    y[77_777] = 5.0                                          # a spike
    run = _add(ws, SimResult(t, [y], ["x.y"], ["m"]), "big", tmp_path)
    status, sig = call(server, f"/api/runs/{run.id}/signal?name=x.y&width=400")
    assert sig["decimated"] and len(sig["t"]) <= 2 * 402
    assert max(sig["y"]) == 5.0 and min(sig["y"]) == y.min()
    status, sig = call(server, f"/api/runs/{run.id}/signal?name=x.y&width=400"
                               "&t0=0.25&t1=0.2505")
    inside = np.flatnonzero((t >= 0.25) & (t <= 0.2505))
    assert not sig["decimated"] and sig["n_window"] == inside.size + 2
    assert np.array_equal(sig["t"], t[inside[0] - 1:inside[-1] + 2])
    assert "no such variable" in error(server, f"/api/runs/{run.id}/signal?name=x.z&width=9")
    assert "width must be" in error(server, f"/api/runs/{run.id}/signal?name=x.y&width=0")
    assert "width must be" in error(server, f"/api/runs/{run.id}/signal?name=x.y&width=abc")
    assert "t0" in error(server, f"/api/runs/{run.id}/signal?name=x.y&width=9&t0=nan")
    assert "no run 'r999'" in error(server, "/api/runs/r999/signal?name=x.y&width=9")


def test_difference_of_two_runs(server, tmp_path):
    ws = server.workspace
    ta = np.linspace(0.0, 1.0, 101)
    tb = np.linspace(0.0, 2.0, 301)                          # another grid, longer
    a = _add(ws, SimResult(ta, [3.0 * ta], ["m.x"], ["m"]), "a", tmp_path)
    b = _add(ws, SimResult(tb, [tb ** 2], ["m.x"], ["m"]), "b", tmp_path)
    status, sig = call(server, f"/api/runs/{b.id}/signal?name=m.x&width=1000&minus={a.id}")
    t, y = np.asarray(sig["t"]), np.array(sig["y"], dtype=float)
    inside = t <= 1.0
    # a is linear, so interpolating it onto b's times is exact
    assert np.allclose(y[inside], t[inside] ** 2 - 3.0 * t[inside], atol=1e-12)
    assert np.all(np.isnan(y[~inside]))                      # outside a's time span: gaps
    assert sig["minus"] == a.id and sig["unit"] == "m"
    c = _add(ws, SimResult(ta, [ta], ["m.x"], ["s"]), "c", tmp_path)
    assert "unit s" in error(server, f"/api/runs/{c.id}/signal?name=m.x&width=9&minus={a.id}")
    d = _add(ws, SimResult(ta, [ta], ["m.y"], ["m"]), "d", tmp_path)
    assert "not logged in run" in error(server,
                                        f"/api/runs/{a.id}/signal?name=m.x&width=9&minus={d.id}")


def test_events_are_found_in_the_log(server, tmp_path):
    t = np.array([0.0, 0.1, 0.2, 0.2, 0.3])                 # an event at t = 0.2
    y = np.array([0.0, 0.0, 0.0, 1.0, 1.0])
    run = _add(server.workspace, SimResult(t, [y], ["s.y"], [""]), "events", tmp_path)
    status, runs = call(server, "/api/runs")
    assert next(r for r in runs if r["id"] == run.id)["events"] == [0.2]


def test_export_a_selection(server, tmp_path):
    ws = server.workspace
    t = np.linspace(0.0, 2.0, 2001)
    res = SimResult(t, [np.sin(t), np.cos(t), t], ["a.x", "a.v", "b.s"], ["m", "m/s", "s"])
    run = _add(ws, res, "export", tmp_path)
    status, body = call(server, f"/api/runs/{run.id}/export?name=a.x&name=b.s&t0=0.5&t1=1.5")
    rows = list(csv.reader(io.StringIO(body.decode())))
    assert rows[0] == ["t", "a.x", "b.s"]
    table = np.array(rows[1:], dtype=float)
    keep = (t >= 0.5) & (t <= 1.5)
    assert np.array_equal(table[:, 0], t[keep]) and np.array_equal(table[:, 1], np.sin(t[keep]))
    status, body = call(server, f"/api/runs/{run.id}/export?name=a&format=parquet")
    assert status == 200 and body[:4] == b"PAR1"
    (tmp_path / "exported.parquet").write_bytes(body)
    loaded = SimResult.load(tmp_path / "exported.parquet")
    assert loaded.names == ["a.x", "a.v"] and loaded.units["a.v"] == "m/s"
    assert "format must be" in error(server, f"/api/runs/{run.id}/export?name=a.x&format=xls")
    assert "no variable chosen" in error(server, f"/api/runs/{run.id}/export")


# ------------------------------------------------------------------ files
def test_open_and_upload_simlogs(server, tmp_path):
    t = np.linspace(0.0, 1.0, 11)
    SimResult(t, [t ** 2], ["m.w"], ["rad/s"]).save(tmp_path / "run.parquet")
    status, run = call(server, "/api/open", body={"path": str(tmp_path / "run.parquet")})
    assert status == 200 and run["kind"] == "file" and run["n_t"] == 11
    status, variables = call(server, f"/api/runs/{run['id']}/variables")
    assert variables["names"] == ["m.w"] and variables["units"] == ["rad/s"]
    text = b"t,m.w\n0,1\n0.5,2\n1,3\n"
    status, up = call(server, "/api/upload?filename=measured.csv", raw=text, method="POST",
                      headers={"Content-Type": "text/csv"})
    assert status == 200 and up["label"] == "measured.csv" and up["n_t"] == 3
    status, sig = call(server, f"/api/runs/{up['id']}/signal?name=m.w&width=10")
    assert sig["y"] == [1.0, 2.0, 3.0]
    assert call(server, f"/api/runs/{up['id']}", method="DELETE")[0] == 200
    assert "no run" in error(server, f"/api/runs/{up['id']}/variables")


def test_files_that_are_not_simlogs(server, tmp_path):
    (tmp_path / "notes.csv").write_text("time,speed\n0,1\n")
    assert "first column must be 't'" in error(server, "/api/open",
                                               body={"path": str(tmp_path / "notes.csv")})
    (tmp_path / "words.csv").write_text("t,x\n0,one\n")
    assert "not a table of numbers" in error(server, "/api/open",
                                             body={"path": str(tmp_path / "words.csv")})
    (tmp_path / "junk.parquet").write_bytes(b"this is not parquet")
    assert "not a simlog" in error(server, "/api/open",
                                   body={"path": str(tmp_path / "junk.parquet")})
    (tmp_path / "readme.txt").write_text("hello")
    assert ".csv, .parquet" in error(server, "/api/open",
                                     body={"path": str(tmp_path / "readme.txt")})
    assert "folder" in error(server, "/api/open", body={"path": str(tmp_path)})
    assert "missing.csv: no such file" in error(server, "/api/open",
                                                body={"path": str(tmp_path / "missing.csv")})
    assert ".csv or .parquet" in error(server, "/api/upload?filename=x.txt", raw=b"t\n0\n",
                                       method="POST")


# ------------------------------------------------------------------ robustness
def test_unknown_addresses_and_foreign_hosts(server, monkeypatch):
    error(server, "/api/nothing", status=404)
    error(server, "/static/..%2Fserver.py", status=404)
    error(server, "/static/../server.py", status=404)
    error(server, "/etc/passwd", status=404)
    assert "refused" in error(server, "/api/models", status=403,
                              headers={"Host": "evil.example:80"})
    assert "refused" in error(server, "/api/simulate", status=403, body={"model": "dc_motor"},
                              headers={"Origin": "http://evil.example"})
    port = server.server_address[1]
    assert "refused" in error(server, "/api/models", status=403,
                              headers={"Origin": f"http://127.0.0.1:{port + 1}"})
    assert call(server, "/api/models", headers={"Origin": f"http://127.0.0.1:{port}"})[0] == 200

    def broken():
        raise RuntimeError("boom")

    monkeypatch.setattr(server.workspace, "models", broken)
    got, answer = call(server, "/api/models")
    assert got == 500 and "internal error" in answer["error"] and "boom" in answer["error"]
    monkeypatch.undo()
    assert call(server, "/api/models")[0] == 200


def test_scenario_reports_are_kept(server):
    assert call(server, "/api/scenario", body={"checks": [1]})[0] == 200
    assert call(server, "/api/scenario")[1] == {"checks": [1]}


# ------------------------------------------------------------------ helpers
def _add(ws, res, label, folder):
    """Put a log into the workspace as the page's "open" does."""
    path = folder / f"{label}.parquet"
    res.save(path)
    return ws.load(path, label=label)


RC_FILE = '''
import mechatron as mt

class RC(mt.Component):
    """RC low-pass as its equation."""
    experiment = {"t_stop": 5e-3}
    V = mt.Parameter("V", default=2.0, doc="Source voltage")
    R = mt.Parameter("Ohm", default="1 kohm", doc="Resistance")
    C = mt.Parameter("F", default="1 uF", doc="Capacitance")
    v = mt.Variable("V", start=0.0, doc="Capacitor voltage")

    def equations(self):
        return [self.C * mt.der(self.v) == (self.V - self.v) / self.R]
'''


def test_a_users_model_file(tmp_path):
    (tmp_path / "rc_model.py").write_text(RC_FILE)
    spec = str(tmp_path / "rc_model.py")
    srv = ExploreServer(Workspace(), port=0)
    srv.start()
    try:
        status, run = call(srv, "/api/simulate", body={"model": spec, "params": {"R": "2 kohm"}})
        assert status == 200, run
        status, sig = call(srv, f"/api/runs/{run['id']}/signal?name=v&width=2000")
        t, v = np.asarray(sig["t"]), np.asarray(sig["y"])
        # v = V (1 - exp(-t / RC)), RC = 2 ms
        assert np.allclose(v, 2.0 * (1.0 - np.exp(-t / 2e-3)), atol=1e-5)
        status, models = call(srv, "/api/models")
        assert models[0]["name"] == spec
    finally:
        srv.shutdown()
        srv.server_close()
