"""FMUs of dc_motor: FMI 2.0 CS and ME, FMI 3.0 CS, checked with FMPy (an independent
importer): validation, and simulation against Mechatron."""

import subprocess
import zipfile
from pathlib import Path

import numpy as np
import pytest

import mechatron as mt
from mechatron.codegen import CodegenError, export_fmu

fmpy = pytest.importorskip("fmpy", reason="FMPy is needed to check FMUs (pip install fmpy)")
from fmpy import read_model_description, simulate_fmu  # noqa: E402
from fmpy.validation import validate_fmu  # noqa: E402

T_STOP, DT = 0.05, 1e-4
OUTPUTS = ["inertia.w", "inductor.i"]


@pytest.fixture(scope="module")
def motor():
    return mt.compile_model(mt.models.get("dc_motor").build())


@pytest.fixture(scope="module")
def reference(motor):
    """Variable-step reference on the communication grid."""
    grid = np.linspace(0, T_STOP, int(round(T_STOP / DT)) + 1)
    return mt.simulate(motor, T_STOP, rtol=1e-11, atol=1e-13, t_out=grid)


def _relative(a, b):
    return np.max(np.abs(a - b)) / np.max(np.abs(b))


@pytest.mark.parametrize("fmi", [2, 3])
def test_cosimulation_fmu_validates_and_matches_mechatron(motor, tmp_path, fmi):
    path = tmp_path / f"dc_motor_{fmi}.fmu"
    info = export_fmu(motor, path, fmi=fmi, kind="cs", solver="rk4", dt=DT, t_stop=T_STOP)
    assert validate_fmu(str(path)) == []
    desk = mt.simulate(motor, T_STOP, solver="rk4", dt=DT)
    res = simulate_fmu(str(path), stop_time=T_STOP, output_interval=DT, output=OUTPUTS)
    np.testing.assert_allclose(res["time"], desk.t, rtol=0, atol=1e-12)
    for name in OUTPUTS:
        assert _relative(res[name], desk[name]) <= 1e-6
    assert info["platform"] in ("linux64", "x86_64-linux", "darwin64", "aarch64-linux",
                                "x86_64-darwin", "aarch64-darwin")
    names = zipfile.ZipFile(path).namelist()
    assert "sources/dc_motor_casadi.c" in names
    assert any(n.startswith("binaries/") for n in names)
    if fmi == 3:
        assert "sources/buildDescription.xml" in names


def test_cosimulation_with_tuned_parameter_and_coarser_communication(motor, tmp_path):
    path = tmp_path / "dc_motor.fmu"
    export_fmu(motor, path, fmi=2, kind="cs", solver="backward_euler", iterations=2, dt=DT,
               t_stop=T_STOP)
    res = simulate_fmu(str(path), stop_time=T_STOP, output_interval=10 * DT,
                       start_values={"source.V": 12.0}, output=OUTPUTS)
    desk = mt.simulate(motor, T_STOP, solver="backward_euler", iterations=2, dt=DT,
                       params={"source.V": 12.0})
    for name in OUTPUTS:
        assert _relative(res[name], desk[name][::10]) <= 1e-6


def test_model_exchange_fmu_validates_and_matches_the_variable_step_reference(
        motor, tmp_path, reference):
    path = tmp_path / "dc_motor_me.fmu"
    export_fmu(motor, path, fmi=2, kind="me", dt=DT, t_stop=T_STOP)
    assert validate_fmu(str(path)) == []
    md = read_model_description(str(path))
    assert md.modelExchange is not None and len(md.derivatives) == motor.nx
    res = simulate_fmu(str(path), stop_time=T_STOP, output_interval=DT, output=OUTPUTS,
                       relative_tolerance=1e-10)
    for name in OUTPUTS:
        got = np.interp(reference.t, res["time"], res[name])
        assert _relative(got, reference[name]) <= 1e-6


def test_fmu_binary_has_no_hidden_runtime_dependencies(motor, tmp_path):
    path = tmp_path / "dc_motor.fmu"
    export_fmu(motor, path, fmi=2, kind="cs", dt=DT)
    with zipfile.ZipFile(path) as zf:
        lib = [n for n in zf.namelist() if n.startswith("binaries/")][0]
        zf.extract(lib, tmp_path)
    readelf = subprocess.run(["readelf", "-d", str(tmp_path / lib)], capture_output=True,
                             text=True)
    if readelf.returncode != 0:
        pytest.skip("readelf not available")
    needed = {line.split("[")[1].split("]")[0] for line in readelf.stdout.splitlines()
              if "(NEEDED)" in line}
    assert needed <= {"libc.so.6", "libm.so.6"}, needed


def test_communication_step_must_be_a_multiple_of_the_solver_step(motor, tmp_path):
    path = tmp_path / "dc_motor.fmu"
    export_fmu(motor, path, fmi=2, kind="cs", dt=DT)
    with pytest.raises(Exception, match="(?i)dostep|failed|error"):
        simulate_fmu(str(path), stop_time=T_STOP, output_interval=1.5 * DT)


def test_fmu_errors_name_the_problem(motor, tmp_path):
    with pytest.raises(CodegenError, match="FMI 3.0 model exchange is not provided"):
        export_fmu(motor, tmp_path / "x.fmu", fmi=3, kind="me", dt=DT)
    with pytest.raises(CodegenError, match="FMI version must be 2 or 3"):
        export_fmu(motor, tmp_path / "x.fmu", fmi=1, dt=DT)


def test_fmu_command_line(tmp_path, capsys):
    from mechatron.cli import main
    out = tmp_path / "m.fmu"
    code = main(["fmu", "dc_motor", "--fmi", "3", "--kind", "cs", "--dt", "1e-4",
                 "--out", str(out)])
    assert code == 0, capsys.readouterr().err
    assert "FMI 3.0 co-simulation" in capsys.readouterr().out and out.exists()
    assert validate_fmu(str(out)) == []
    code = main(["fmu", "dc_motor", "--dt", "1e-4", "--out", str(tmp_path / "m.zip")])
    assert code == 2 and "must end in .fmu" in capsys.readouterr().err


def test_fmi3_build_description_follows_the_schema(motor, tmp_path):
    lxml_etree = pytest.importorskip("lxml.etree")
    path = tmp_path / "dc_motor3.fmu"
    export_fmu(motor, path, fmi=3, kind="cs", dt=DT)
    schema_file = Path(fmpy.__file__).parent / "schema" / "fmi3" / "fmi3BuildDescription.xsd"
    schema = lxml_etree.XMLSchema(lxml_etree.parse(str(schema_file)))
    with zipfile.ZipFile(path) as zf:
        doc = lxml_etree.fromstring(zf.read("sources/buildDescription.xml"))
        listed = {e.get("name") for e in doc.iter("SourceFile")}
        assert {f"sources/{n}" for n in listed} <= set(zf.namelist())
    assert schema.validate(doc), schema.error_log


@pytest.mark.parametrize("fmi", [2, 3])
def test_cosimulation_fmu_flushes_subnormals_for_its_step_as_the_desktop(tmp_path, fmi):
    """A ladder of 120 sections stepped by RK4 at dt = RC / 1000 passes through subnormal
    values, which the desktop flushes to zero (mechatron.solvers.fpenv). The FMU flushes
    for its step too (and gives its host's mode back after it), so its run is the
    desktop's bit for bit; unflushed, 11 of the capacitors differed."""
    from mechatron.solvers.fpenv import flushing_available
    from tests.solvers.test_logging import ladder
    if not flushing_available():
        pytest.skip("no known floating-point environment layout: the desktop runs unflushed")
    cm = mt.compile_model(ladder(120))
    path = tmp_path / f"ladder_{fmi}.fmu"
    export_fmu(cm, path, fmi=fmi, kind="cs", solver="rk4", dt=1e-6, t_stop=3e-5)
    outputs = [f"c{k}.v" for k in range(120)]
    res = simulate_fmu(str(path), stop_time=3e-5, output_interval=1e-6, output=outputs)
    desk = mt.simulate(cm, 3e-5, solver="rk4", dt=1e-6)
    for name in outputs:
        np.testing.assert_array_equal(res[name], desk[name], err_msg=name)
    assert (np.array([1e-310]) * 1.0)[0] != 0.0     # the host's mode is its own again
