"""Fuzz tests of the ``mechatron`` command (issue 20): random arguments to every fast
command and random mutations of every problem-file schema (estimate, sensitivity,
optimize). Every run must end in a result (exit 0; 1 for ``optimize`` with a requirement
not met) or in one line ``error: ...`` with exit 2, never a traceback or an "unexpected"
error, within 30 s of CPU time, and never leave a partial or temporary file:
after a failed run every file that was there is unchanged.

The command runs in-process (:func:`mechatron.cli.main`), which is what
``python -m mechatron`` calls.
"""

from __future__ import annotations

import copy
import hashlib
import json
import math
import os
import resource
import shutil
import tomllib
from pathlib import Path

import pytest
from hypothesis import HealthCheck, event, given, settings
from hypothesis import strategies as st

from mechatron._io import TEMP_PREFIX
from mechatron.cli import main

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = ROOT / "examples"

#: The most CPU time (this process and its children, s) one run may take. CPU time, not
#: wall time: the machine may be shared, and a run waiting for a core is not stalled.
RUN_LIMIT = 30.0

FUZZ = settings(max_examples=int(os.environ.get("MECHATRON_FUZZ_EXAMPLES", 40)),
                deadline=None, database=None,
                derandomize=not os.environ.get("MECHATRON_FUZZ_EXAMPLES"),
                suppress_health_check=list(HealthCheck))


# -------------------------------------------------------------------------- the contract
def _files(folder: Path) -> dict[str, str]:
    return {str(p.relative_to(folder)): hashlib.sha1(p.read_bytes()).hexdigest()
            for p in sorted(folder.rglob("*")) if p.is_file()}


def _cpu() -> float:
    own = resource.getrusage(resource.RUSAGE_SELF)
    children = resource.getrusage(resource.RUSAGE_CHILDREN)
    return own.ru_utime + own.ru_stime + children.ru_utime + children.ru_stime


def check_run(capsys, folder: Path, argv: list[str], *, may_fail_requirements=False):
    """Run ``argv`` in-process and check the contract of the module docstring."""
    before = _files(folder)
    start = _cpu()
    code = main(argv)
    used = _cpu() - start
    out, err = capsys.readouterr()
    assert used < RUN_LIMIT, (argv, used)
    event(f"{argv[0]}: exit {code}")
    text = out + err
    assert "Traceback" not in text, (argv, text)
    assert "unexpected" not in err, (argv, err)
    leftovers = [p for p in folder.rglob(TEMP_PREFIX + "*")]
    assert not leftovers, (argv, leftovers)
    if code == 0 or (code == 1 and may_fail_requirements and "error:" not in err):
        return code, out, err
    assert code == 2, (argv, code, err)
    lines = err.splitlines()
    errors = [line for line in lines if line.startswith("error: ")]
    assert len(errors) == 1 and lines[-1] == errors[0], (argv, err)
    after = _files(folder)
    changed = [k for k, h in before.items() if after.get(k) != h]
    assert not changed, (argv, changed)            # a failed run changed no file
    return code, out, err


# ------------------------------------------------------------------ command-line arguments
NUMBERS = ["0", "-1", "1", "2", "0.5", "1e-12", "1e-9", "1e-4", "1e-3", "0.01", "5e-3",
           "1e5", "1e308", "inf", "-inf", "nan", "7,1", "1_000", "", " ", "x", "3 mH",
           "3 kg", "0x10", "1/2", "١", "1e-320"]
MODELS = ["dc_motor", "dc_moter", "rc_circuit", "os:abort", "os.path:join", "no_such.py",
          "examples/user_component.py", "examples/user_component.py:Motor",
          "examples/user_component.py:Nope", "mechatron.models.dc_motor_control:"
          "DCMotorSpeedPIVoltage", "", "-", "../../../etc/passwd"]
SETS = ["R=7.5", "R=7,1 ohm", "R=-5", "R=0", "L=340 uH", "L=3 kg", "V=nan", "V=inf", "Q=1",
        "R", "=1", "R==1", "J=1e308", "k=1e-320", "B=0", "V=12 V"]
OUTS = ["log.csv", "log.parquet", "log.txt", "plot.png", "plot.svg", "no/dir/x.csv", "",
        "out", "x.fmu"]
SOLVERS = ["rk4", "euler", "heun", "implicit_euler", "trapezoidal", "cvodes", "idas", "auto",
           "rk45", "rodas4", "magic", ""]

# per command: option -> list of values (None: a flag)
OPTIONS: dict[str, dict[str, list[str] | None]] = {
    "models": {"--tag": ["motor", "nope", ""], "--json": None},
    "show": {"--json": None},
    "simulate": {"--variant": ["acausal", "ode", "blocks", "inputs", "nope"],
                 "--t-stop": NUMBERS, "--set": SETS, "--solver": SOLVERS, "--dt": NUMBERS,
                 "--rtol": NUMBERS, "--atol": NUMBERS, "--out": OUTS, "--plot": OUTS,
                 "--input": ["u=1", "u=3,5", "V=12", "tau=0.1", "u=missing.csv",
                             "u=empty.csv", "u=bad.csv", "u=good.csv", "u"],
                 "--json": None, "-v": None, "--force": None},
    "compare": {"--t-stop": NUMBERS, "--set": SETS, "--out": OUTS, "--json": None},
    "codegen": {"--variant": ["acausal", "ode", "nope"], "--set": SETS,
                "--solver": SOLVERS, "--dt": NUMBERS, "--iterations": ["0", "1", "3", "-2",
                                                                       "1e9", "x"],
                "--t-stop": NUMBERS, "--out": ["c_out", "log.csv", "", "no/dir/c"],
                "--json": None},
    "linearize": {"--variant": ["acausal", "ode", "nope"], "--set": SETS,
                  "--input": ["V", "nope", ""], "--output": ["w", "inertia.w", "nope"],
                  "--at": NUMBERS, "--bode": OUTS, "--json": None},
    "diagram": {"--out": ["d.svg", "d.dot", "d.txt", "no/dir/d.svg", ""]},
    "library": {"--json": None},
    # (no --dask: an address that does not answer is waited for, not fuzzed)
    "regression": {"--workers": ["1", "0", "-1", "x", "1e3", ""], "--json": None,
                   "-v": None, "-q": None},
}
#: Model names ``regression`` is given (always at least one: without a name it checks
#: the whole database, minutes of work).
REGRESSION_NAMES = ["dc_motor", "dc_moter", "", "msd", "os:abort", "../../../etc/passwd"]
#: Models fuzzed per command (the others take no model).
TAKES_MODEL = {"show", "simulate", "compare", "codegen", "linearize", "diagram"}


#: Values that make sense, drawn half of the time so that runs get past the checks.
GOOD = {"--t-stop": ["0.01", "0.05", "1e-3"], "--dt": ["1e-4", "1e-5"],
        "--rtol": ["1e-6"], "--atol": ["1e-8"], "--set": ["R=7.5", "L=340 uH", "V=12 V"],
        "--solver": ["rk4", "euler", "auto", "cvodes", "backward_euler"],
        "--variant": ["acausal", "ode"], "--out": ["log.csv", "log.parquet", "c_out",
                                                  "d.svg", "plot.png"],
        "--plot": ["plot.png"], "--bode": ["bode.png"], "--input": ["V"],
        "--at": ["0", "0.01"], "--iterations": ["1", "3"], "--workers": ["1"]}


@st.composite
def command_lines(draw):
    command = draw(st.sampled_from(sorted(OPTIONS)))
    argv = [command]
    if command in TAKES_MODEL and draw(st.integers(0, 9)) > 0:
        argv.append("dc_motor" if draw(st.booleans()) else draw(st.sampled_from(MODELS)))
    if command == "regression":
        argv.append("dc_motor" if draw(st.booleans()) else
                    draw(st.sampled_from(REGRESSION_NAMES)))
    options = OPTIONS[command]
    for option in draw(st.lists(st.sampled_from(sorted(options)), max_size=5)):
        values = options[option]
        argv.append(option)
        if values is not None and draw(st.integers(0, 19)) > 0:
            good = [v for v in GOOD.get(option, ()) if v in values or option == "--input"]
            pool = good if good and draw(st.booleans()) else values
            argv.append(draw(st.sampled_from(pool)))
    if draw(st.integers(0, 9)) == 0:
        argv.insert(draw(st.integers(0, len(argv))),
                    draw(st.sampled_from(["--nope", "-q", "-vv", "--", "x", "--json"])))
    return argv


@pytest.fixture(scope="module")
def workdir(tmp_path_factory):
    folder = tmp_path_factory.mktemp("fuzz")
    shutil.copytree(EXAMPLES, folder / "examples")
    (folder / "empty.csv").write_text("")
    (folder / "bad.csv").write_text("t,u\n0,1\n1,x,3\n")
    (folder / "good.csv").write_text("t,u\n0,0\n0.01,12\n")
    return folder


@FUZZ
@given(argv=command_lines())
def test_fuzz_command_line(argv, workdir, capsys, monkeypatch):
    monkeypatch.chdir(workdir)
    check_run(capsys, workdir, argv)


# ----------------------------------------------------------------------- problem files
def toml_value(value) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        if math.isnan(value):
            return "nan"
        if math.isinf(value):
            return "inf" if value > 0 else "-inf"
        return repr(value)
    if isinstance(value, str):
        return json.dumps(value, ensure_ascii=True)
    if isinstance(value, list):
        return "[" + ", ".join(toml_value(v) for v in value) + "]"
    if isinstance(value, dict):
        return "{" + ", ".join(f"{json.dumps(k)} = {toml_value(v)}"
                               for k, v in value.items()) + "}"
    raise TypeError(value)


def toml_text(doc: dict) -> str:
    """A TOML document of ``doc``: scalars first, then tables, then arrays of tables."""
    lines = [f"{json.dumps(k)} = {toml_value(v)}" for k, v in doc.items()
             if not isinstance(v, dict)
             and not (isinstance(v, list) and v and all(isinstance(x, dict) for x in v))]
    for k, v in doc.items():
        if isinstance(v, dict):
            lines.append(f"[{json.dumps(k)}]")
            lines += [f"{json.dumps(kk)} = {toml_value(vv)}" for kk, vv in v.items()]
    for k, v in doc.items():
        if isinstance(v, list) and v and all(isinstance(x, dict) for x in v):
            for item in v:
                lines.append(f"[[{json.dumps(k)}]]")
                lines += [f"{json.dumps(kk)} = {toml_value(vv)}" for kk, vv in item.items()]
    return "\n".join(lines) + "\n"


def _paths(node, prefix=()):
    """Every (path, value) in a parsed TOML document."""
    if isinstance(node, dict):
        for k, v in node.items():
            yield prefix + (k,), v
            yield from _paths(v, prefix + (k,))
    elif isinstance(node, list):
        for i, v in enumerate(node):
            yield prefix + (i,), v
            yield from _paths(v, prefix + (i,))


VALUES = st.one_of(
    st.sampled_from([0, -1, 1, 2, 10**6, 0.0, -0.5, 1e-12, 1e5, 1e300, math.inf, -math.inf,
                     math.nan, True, "", "x", "7,1 ohm", "1 mH", "3 kg", "-1 V", "nan",
                     "dc_motor", "os:abort", "i", "w", "V", "R", "sobol", "zoh", "step",
                     [], ["i"], ["nope"], {}, {"kind": "uniform"}, {"i": 0}]),
    st.floats(allow_nan=True, allow_infinity=True),
    st.integers(-10, 10**6),
    st.text(alphabet="abcRLkJBiwV_:.,/ 0123456789", max_size=12),
)
KEYS = st.sampled_from(["colour", "mni", "sigmas", "min", "max", "initial", "samples",
                        "substeps", "method", "name", "file", "class", "t_stop", "points",
                        "kind", "low", "high", "std", "mean", "address", "workers"])


@st.composite
def mutations(draw, doc):
    doc = copy.deepcopy(doc)
    for _ in range(draw(st.integers(1, 3))):
        paths = [p for p, _ in _paths(doc)]
        path = draw(st.sampled_from(paths))
        parent = doc
        for key in path[:-1]:
            parent = parent[key]
        action = draw(st.sampled_from(["replace", "replace", "replace", "delete", "add"]))
        if action == "delete":
            del parent[path[-1]]
        elif action == "replace":
            parent[path[-1]] = draw(VALUES)
        else:
            target = parent[path[-1]]
            if isinstance(target, dict):
                target[draw(KEYS)] = draw(VALUES)
            else:
                parent[path[-1]] = draw(VALUES)
    return doc


PROBLEMS = {
    "estimate": ("dc_motor_estimate.toml", ["--max-iterations", "2", "--quiet"]),
    "sensitivity": ("dc_motor_sensitivity.toml", ["--samples", "5", "--workers", "1",
                                                  "--quiet"]),
    "optimize": ("dc_motor_speed_pi_optimize.toml", ["--max-iterations", "2", "--quiet"]),
}


@pytest.fixture(scope="module")
def problem_dir(tmp_path_factory):
    """The example problems with their virtual-bench data generated once."""
    folder = tmp_path_factory.mktemp("problems")
    for name, _ in PROBLEMS.values():
        shutil.copy(EXAMPLES / name, folder / name)
    shutil.copy(EXAMPLES / "rigs.py", folder / "rigs.py")      # the problems' own models
    for command, (name, options) in PROBLEMS.items():
        if command != "optimize":
            assert main([command, str(folder / name), "--samples" if command ==
                         "sensitivity" else "--max-iterations", "5", "--quiet",
                         *(["--workers", "1"] if command == "sensitivity" else [])]) == 0
    return folder


@pytest.mark.parametrize("command", sorted(PROBLEMS))
def test_fuzz_problem_files(command, problem_dir, capsys):
    name, options = PROBLEMS[command]
    original = tomllib.loads((EXAMPLES / name).read_text())
    counter = iter(range(10**6))

    @settings(FUZZ, max_examples=int(os.environ.get("MECHATRON_FUZZ_EXAMPLES", 12)))
    @given(doc=mutations(original))
    def run(doc):
        path = problem_dir / f"fuzz_{command}_{next(counter)}.toml"
        path.write_text(toml_text(doc))
        try:
            check_run(capsys, problem_dir,
                      [command, str(path), *options, "--out", str(problem_dir / "out")],
                      may_fail_requirements=command == "optimize")
        finally:
            path.unlink()

    run()
