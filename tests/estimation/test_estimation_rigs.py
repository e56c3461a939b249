"""What real rigs need in a problem file: a model file of one's own, a row range per
experiment (fit on the first rows, validate on the rest), parameters per experiment next
to shared ones, and outputs that are expressions of model variables; each estimated on
synthetic data with a known truth."""

from __future__ import annotations

import json
import textwrap

import numpy as np
import pytest

import mechatron as mt
from mechatron.cli import main
from mechatron.errors import DataError, ModelError
from mechatron.estimation import EstimationProblem, Experiment, estimate
from mechatron.estimation.config import build_estimation, build_model, load_config
from mechatron.estimation.expressions import parse_output

RIG = textwrap.dedent('''
    import mechatron as mt


    class Rig(mt.Component):
        """First-order lag and a sensor with an offset: tau y' = K u - y, s = y + off."""

        K = mt.Parameter("1", default=1.0, doc="Gain")
        tau = mt.Parameter("s", default=1.0, min=0, doc="Time constant")
        u = mt.Parameter("1", default=0.0, doc="Input, driven by the data")
        off = mt.Parameter("1", default=0.0, doc="Sensor offset")
        y = mt.Variable("1", start=0.0, doc="Output")
        s = mt.Variable("1", doc="Sensor reading")

        def equations(self):
            return [self.tau * mt.der(self.y) == self.K * self.u - self.y,
                    self.s == self.y + self.off]


    class Other(Rig):
        """A second class, so that the file needs 'class'."""
''')

TRUTH = {"K": 2.5, "tau": 0.3}


def _lag(u, h, K, tau, y0=0.0):
    """The lag driven by a held input, exactly on the sample grid (analytic)."""
    a = np.exp(-h / tau)
    y = np.empty(u.size)
    y[0] = y0
    for k in range(u.size - 1):
        y[k + 1] = a * y[k] + (1 - a) * K * u[k]
    return y


def _write_run(path, n, off, seed, noise=0.005, h=0.02):
    rng = np.random.default_rng(seed)
    u = np.repeat(rng.choice([-1.0, 1.0], n // 25 + 1), 25)[:n]
    y = _lag(u, h, **TRUTH)
    m = 2.0 * (y + off) + noise * rng.standard_normal(n)
    path.write_text("t,u,m\n" + "\n".join(f"{k * h:.6f},{a:.1f},{b:.12g}"
                                          for k, (a, b) in enumerate(zip(u, m))) + "\n")
    return y


PROBLEM = '''
free_x0 = ["y"]

[model]
file = "models/rig.py"
class = "Rig"

[[experiments]]
name = "a"
file = "a.csv"
inputs = ["u"]
outputs = ["m"]
rows = [0, 400]
params_free = ["off"]

[[experiments]]
name = "b"
file = "b.csv"
inputs = ["u"]
outputs = ["m"]
params_free = ["off"]

[[validation]]
name = "a_rest"
file = "a.csv"
inputs = ["u"]
outputs = ["m"]
rows = [400]
params_free = ["off"]

[inputs]
u = "u"

[outputs]
m = "2 * s"

[parameters]
K = { initial = 1.0, min = 0.1, max = 10 }
tau = { initial = 0.2, min = 0.01, max = 5 }
'''


@pytest.fixture
def rig_problem(tmp_path):
    (tmp_path / "models").mkdir()
    (tmp_path / "models" / "rig.py").write_text(RIG)
    _write_run(tmp_path / "a.csv", 600, 0.3, 1)
    _write_run(tmp_path / "b.csv", 300, -0.2, 2)
    cfg = tmp_path / "p.toml"
    cfg.write_text(PROBLEM)
    return cfg


def test_shared_and_per_experiment_parameters_from_a_row_range(rig_problem):
    """K and tau shared, the sensor offset per run (0.3 and -0.2), the output a gain of a
    variable (2 s); experiment a fitted on its first 400 rows only."""
    prob = build_estimation(load_config(rig_problem))
    assert [e.n for e in prob.experiments] == [400, 300]
    assert prob.names == ["K", "tau", "a:y", "b:y", "a:off", "b:off"]
    res = estimate(prob)
    p = res.parameters
    assert p["K"] == pytest.approx(TRUTH["K"], rel=1e-3)
    assert p["tau"] == pytest.approx(TRUTH["tau"], rel=1e-3)
    assert p["a:off"] == pytest.approx(0.3, abs=2e-3)
    assert p["b:off"] == pytest.approx(-0.2, abs=2e-3)
    for name, truth in (("K", 2.5), ("tau", 0.3), ("a:off", 0.3), ("b:off", -0.2)):
        assert abs(p[name] - truth) < 4 * res.std[res.names.index(name)], name
    # the per-experiment offset moves only its own experiment's residuals
    r, J = prob.jacobian(res.values)
    na = prob.bound[0]["exp"].n
    assert np.all(J[na:, prob.names.index("a:off")] == 0)
    assert J[:na, prob.names.index("a:off")] == pytest.approx(2.0 / prob.bound[0]["sigma"][0])


def test_estimate_out_validates_on_the_remaining_rows(rig_problem, capsys):
    """The rows after 400 of the same file: fit above 99% (noise 0.005 on a range of
    about 10), their initial state and offset fitted again, an HTML page with both data
    sets."""
    out = rig_problem.parent / "out"
    assert main(["estimate", str(rig_problem), "--out", str(out), "--json", "--quiet"]) == 0
    doc = json.loads(capsys.readouterr().out)
    val = doc["validation"]["validation"]
    assert val["refitted"] == ["a_rest:y", "a_rest:off"]
    (row,) = val["rows"]
    assert row["experiment"] == "a_rest" and row["n"] == 200
    assert row["fit_percent"] > 99.0
    assert val["parameters"]["a_rest:off"] == pytest.approx(0.3, abs=5e-3)
    page = (out / "estimate_report.html").read_text()
    assert "Estimation data" in page and "Validation data" in page and "a_rest" in page
    assert (out / "validation_residuals.png").stat().st_size > 10000
    assert not list(out.glob("*.tmp*")) and not list(out.glob(".*"))


def test_model_file_and_class_are_relative_to_the_problem_file(rig_problem, tmp_path):
    model = build_model(load_config(rig_problem))
    assert type(model).__name__ == "Rig"
    cfg = tmp_path / "q.toml"
    cfg.write_text('[model]\nfile = "models/rig.py"\n')
    with pytest.raises(ModelError, match="defines 2 component classes"):
        build_model(load_config(cfg))


@pytest.mark.parametrize("name, hint", [("os:abort", "file = "),
                                        ("models/rig.py:Rig", "file = "),
                                        ("dc_motr", "Known: ")])
def test_model_name_takes_database_names_only(tmp_path, name, hint):
    cfg = tmp_path / "p.toml"
    cfg.write_text(f'[model]\nname = "{name}"\n')
    with pytest.raises(ModelError, match=f"'{name}' is not a database model.*{hint}"):
        build_model(load_config(cfg))


def test_model_table_problems_are_collected(tmp_path):
    cfg = tmp_path / "p.toml"
    cfg.write_text('[model]\nname = "dc_motor"\nfile = "x.py"\n'
                   '[[experiments]]\nfile = "a.csv"\nrows = [5, 2]\nparams_free = "off"\n')
    with pytest.raises(DataError) as err:
        load_config(cfg)
    text = str(err.value)
    assert "give either 'name'" in text and "not both" in text
    assert "rows: start 5 is not below stop 2" in text
    assert "params_free: expected a list of names" in text


def test_output_expressions_with_their_derivatives_and_units():
    """abs, a sum and a gain of variables: the values and the exact Jacobian of the
    weighted residuals agree with central differences of the residuals."""
    cm = mt.compile_model(mt.models.get("dc_motor").build("acausal"))
    spec = parse_output("0.5 * abs(inertia.w) + 2 * inductor.i", cm.names)
    assert spec.paths == ["inertia.w", "inductor.i"]
    assert not spec.plain and spec.kind == "value"
    with pytest.raises(DataError, match="the units do not combine"):
        spec.unit(dict(zip(cm.names, cm.units)))
    assert parse_output("3 * abs(inertia.w)", cm.names).unit(
        dict(zip(cm.names, cm.units))) == "rad/s"
    t = np.linspace(0, 0.01, 101)
    sim = mt.simulate(mt.models.get("dc_motor").build("acausal"), 0.01, t_out=t,
                      rtol=1e-10, atol=1e-12)
    i = sim["inductor.i"]
    e = Experiment("run", t=t, outputs={"m": 2 * np.abs(i - 0.2) + i})
    prob = EstimationProblem(cm, [e], ["resistor.R", "emf.k"],
                             outputs={"m": "abs(inductor.i - 0.2) * 2 + resistor.i"},
                             jit=False, substeps=8)
    assert prob._output_unit("m") == "A"
    theta = np.array([7.5, 0.14])
    r, J = prob.jacobian(theta)
    for j in range(2):
        d = np.zeros(2)
        d[j] = 1e-6 * theta[j]
        fd = (prob.residuals(theta + d) - prob.residuals(theta - d)) / (2 * d[j])
        assert J[:, j] == pytest.approx(fd, rel=1e-4, abs=1e-6 * np.abs(fd).max())


@pytest.mark.parametrize("text, what", [
    ("__import__('os').system('true')", "not allowed"),
    ("inertia.w.__class__", "not allowed"),
    ("open('x')", "not allowed"),
    ("inertia.w if 1 else 0", "not allowed"),
    ("[inertia.w]", "not allowed"),
    ("inertia.ww * 2", "does not log"),
    ("inertia.w +", "neither a variable"),
])
def test_output_expressions_refuse_anything_but_arithmetic(text, what):
    cm = mt.compile_model(mt.models.get("dc_motor").build("acausal"))
    with pytest.raises(DataError, match=what):
        parse_output(text, cm.names, "output 'm'")


def test_profile_and_covariance_options_of_the_command(rig_problem, capsys):
    assert main(["estimate", str(rig_problem), "--json", "--quiet", "--profile", "K,tau",
                 "--covariance", "white"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["covariance"] == "white" and doc["ci95"] == doc["ci95_white"]
    assert set(doc["profile_ci95"]) == {"K", "tau"}
    for name in ("K", "tau"):
        lo, hi = doc["profile_ci95"][name]
        assert lo < doc["parameters"][name] < hi
        # the cost is nearly quadratic here: profile and linearized intervals agree
        assert lo == pytest.approx(doc["ci95"][name][0], rel=1e-3)
        assert hi == pytest.approx(doc["ci95"][name][1], rel=1e-3)


def test_experiment_select_by_rows_and_time():
    e = Experiment("e", t=np.arange(10) * 0.5, outputs={"y": np.arange(10.0)},
                   source="e.csv")
    a = e.select(rows=(2, 5))
    assert a.t.tolist() == [1.0, 1.5, 2.0] and a.rows.tolist() == [4, 5, 6]
    b = e.select(t_range=(3.0, None))
    assert b.outputs["y"].tolist() == [6.0, 7.0, 8.0, 9.0]
    assert e.select(rows=(-3, None)).n == 3
    with pytest.raises(DataError, match=r"rows 8:9 keep 1 of 10 samples"):
        e.select(rows=(8, 9))
