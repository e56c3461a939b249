"""Models from outside the database, `mechatron.models.user`: a user's file or an
importable class, checked to be a Component subclass before anything is called."""

from __future__ import annotations

import json
import math
import textwrap

import pytest

from mechatron.cli import main
from mechatron.errors import ModelError
from mechatron.models.user import entry_for, import_component, load_model_file

RC = textwrap.dedent('''
    import mechatron as mt


    class RC(mt.Component):
        """RC low-pass charged from a constant source at t = 0."""
        experiment = {"t_stop": 5e-3}
        V = mt.Parameter("V", default=2.0, doc="Source voltage")
        R = mt.Parameter("Ohm", default="1 kohm", doc="Resistance")
        C = mt.Parameter("F", default="1 uF", doc="Capacitance")
        v = mt.Variable("V", start=0.0, doc="Capacitor voltage")

        def equations(self):
            return [self.C * mt.der(self.v) == (self.V - self.v) / self.R]
''')


def run(capsys, *argv):
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


@pytest.fixture
def rc_file(tmp_path):
    path = tmp_path / "rc_model.py"
    path.write_text(RC)
    return path


def test_a_file_with_one_component_class_is_taken(rc_file):
    cls = load_model_file(str(rc_file))
    assert cls.__name__ == "RC" and cls.__module__.startswith("mechatron_user_rc_model")
    assert load_model_file(f"{rc_file}:RC").__name__ == "RC"


def test_simulate_a_user_file_matches_the_analytic_charge(capsys, rc_file, tmp_path,
                                                          monkeypatch):
    monkeypatch.chdir(tmp_path)
    for spec in ("rc_model.py", "rc_model.py:RC", str(rc_file)):
        code, out, err = run(capsys, "simulate", spec, "--set", "R=2 kohm", "--json")
        assert code == 0, err
        doc = json.loads(out)
        tau = 2e3 * 1e-6
        exact = 2.0 * (1 - math.exp(-5e-3 / tau))          # v(t) = V (1 - e^(-t/RC))
        assert doc["t_stop"] == 5e-3 and doc["outputs"] == {"v": "v"}
        assert doc["final"]["v"] == pytest.approx(exact, rel=1e-5)
    code, out, err = run(capsys, "show", "rc_model.py")
    assert code == 0 and "Source voltage" in out and "kohm" not in out
    assert "1000" in out                                      # R's default in SI


def test_several_classes_need_a_name_and_errors_name_the_file(tmp_path, capsys):
    two = tmp_path / "two.py"
    two.write_text(RC + "\n\nclass RC2(RC):\n    pass\n")
    with pytest.raises(ModelError, match=r"defines 2 component classes \(RC, RC2\); "
                                         r"choose one with .*two.py:ClassName"):
        load_model_file(str(two))
    assert load_model_file(f"{two}:RC2").__name__ == "RC2"
    with pytest.raises(ModelError, match="'mt' is a module, not a concrete"):
        load_model_file(f"{two}:mt")
    (tmp_path / "none.py").write_text("x = 1\n")
    with pytest.raises(ModelError, match="defines no mechatron Component subclass"):
        load_model_file(str(tmp_path / "none.py"))
    (tmp_path / "broken.py").write_text("import mechatron as mt\nclass A(mt.Component:\n")
    with pytest.raises(ModelError, match=r"running the file failed \(line 2\): SyntaxError"):
        load_model_file(str(tmp_path / "broken.py"))
    code, out, err = run(capsys, "simulate", str(tmp_path / "missing.py"))
    assert code == 2 and out == "" and "missing.py: no such file" in err


def test_module_class_must_be_a_component_before_anything_is_called(tmp_path,
                                                                     monkeypatch):
    flag = tmp_path / "called"
    (tmp_path / "payload.py").write_text(textwrap.dedent(f'''
        import mechatron as mt

        def make_model():
            open({str(flag)!r}, "w").write("called")

        class NotAModel:
            def __init__(self):
                open({str(flag)!r}, "w").write("called")

        class Base(mt.Component, partial=True):
            pass
    '''))
    monkeypatch.syspath_prepend(str(tmp_path))
    for spec, what in (("payload:make_model", "a function"), ("payload:NotAModel", "a class"),
                       ("payload:Base", "a partial"), ("os:abort", "a function"),
                       ("shutil:rmtree", "a function"), ("payload:nothing", "not found")):
        with pytest.raises(ModelError, match=f"'{spec.split(':')[1]}' is {what}"):
            import_component(spec)
    assert not flag.exists()
    with pytest.raises(ModelError, match="cannot import module 'no_such_module_xyz'"):
        import_component("no_such_module_xyz:Model")
    entry = entry_for("mechatron.models.dc_motor_control:DCMotorSpeedPIVoltage")
    assert entry.variants and entry.name.endswith("DCMotorSpeedPIVoltage")


def test_problem_file_refuses_os_abort_and_accepts_a_user_file(tmp_path, capsys, rc_file):
    from mechatron.estimation.config import build_model, load_config
    cfg_path = tmp_path / "p.toml"
    cfg_path.write_text('[model]\nname = "os:abort"\n')
    code, out, err = run(capsys, "estimate", str(cfg_path))
    assert code == 2 and out == "" and err.count("\n") == 1
    # [model] name takes database names only (issue 19): nothing is imported
    assert f"{cfg_path}: [model] name: 'os:abort' is not a database model" in err
    # a file relative to the problem file's folder ([model] file and class), with
    # parameters set
    (tmp_path / "sub").mkdir()
    cfg_path = tmp_path / "sub" / "p.toml"
    cfg_path.write_text('[model]\nfile = "../rc_model.py"\nclass = "RC"\n'
                        'set = { R = "2 kohm" }\n')
    model = build_model(load_config(cfg_path))
    assert type(model).__name__ == "RC"
    import mechatron as mt
    res = mt.simulate(model, 5e-3)
    assert res.final("v") == pytest.approx(2.0 * (1 - math.exp(-2.5)), rel=1e-5)


NETWORK = textwrap.dedent('''
    import mechatron as mt
    from mechatron.library import electrical as el


    class Charge(mt.Component):
        """A network of library parts with no variables of its own."""
        experiment = {"t_stop": 5e-3}
        src = el.DCVoltageSource(V=2.0)
        r1 = el.Resistor(R="1 kohm")
        c1 = el.Capacitor(C="1 uF")
        g = el.ElectricalReference()

        def equations(self):
            return [mt.connect(self.src.p, self.r1.p), mt.connect(self.r1.n, self.c1.p),
                    mt.connect(self.src.n, self.c1.n, self.g.port)]
''')


def test_a_network_file_is_described_by_its_states(tmp_path, capsys):
    path = tmp_path / "charge.py"
    path.write_text(NETWORK)
    entry = entry_for(str(path))
    assert entry.outputs == {"model": {"c1.v": "c1.v"}} and entry.output_units == {"c1.v": "V"}
    code, out, err = run(capsys, "simulate", str(path), "--json")
    assert code == 0, err
    assert json.loads(out)["final"]["c1.v"] == pytest.approx(2 * (1 - math.exp(-5)),
                                                             rel=1e-5)
    code, out, err = run(capsys, "report", str(path), "--out", str(tmp_path / "r.html"))
    assert code == 0, err
    assert f"<title>{path}" in (tmp_path / "r.html").read_text()
