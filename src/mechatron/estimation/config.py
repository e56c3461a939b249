"""TOML problem files for ``mechatron estimate``, ``sensitivity`` and ``optimize``.

The format is documented in ``docs/estimation.md``. Paths in a file are relative to the
file's folder. Values may carry units (``"340 uH"``); they are converted to the unit of
the model parameter they set. Unknown keys are errors (a typo must not be ignored).
"""

from __future__ import annotations

import logging
import math
import tomllib
from pathlib import Path


import mechatron as mt
from mechatron.errors import DataError, ModelError, ParameterError, UnitError
from mechatron.estimation.data import Experiment, load_experiment
from mechatron.units import to_base, to_si

__all__ = ["load_config", "build_model", "build_estimation", "build_sensitivity",
           "build_response", "generate_bench_data", "validation_experiments",
           "per_experiment"]

log = logging.getLogger(__name__)

_TOP = {"model", "experiments", "parameters", "fixed", "offsets", "free_x0",
        "virtual_bench", "options", "sensitivity", "requirements", "design", "simulation",
        "inputs", "outputs", "title", "validation", "estimation"}
#: Keys of ``[estimation]``: multi-start estimation (see :mod:`.multistart`).
ESTIMATION_KEYS = ("starts", "seed", "sampling", "workers", "address")
#: Keys of an ``[[experiments]]`` (and ``[[validation]]``) table.
_EXPERIMENT_KEYS = ("name", "file", "time", "inputs", "outputs", "units", "params", "x0",
                    "hold", "sigma", "rows", "t_range", "params_free", "fit")

#: Keys of each ``[[requirements]]`` type, with the check of each value.
_REQUIREMENT_KEYS = {
    "step": {"signal", "final", "initial", "t_step", "rise_time", "rise", "overshoot",
             "settling_time", "settling"},
    "bound": {"signal", "lower", "upper", "t_start", "t_end"},
    "tracking": {"signal", "reference", "weight"},
}
_BENCH_RUNS = ("locked_rotor", "voltage_step", "multi_step")


def load_config(path) -> dict:
    """Read and check a problem file; ``cfg["_dir"]`` is its folder and ``cfg["_path"]``
    its path.

    Every problem of the file is collected (unknown keys, wrong types, impossible values
    such as a noise level <= 0, zero samples or substeps, a lower bound above the upper
    one), each named by file, table and key, and raised as one :class:`DataError`.
    Checks that need the model (parameter names, units) follow when it is built.
    """
    path = Path(path)
    if not path.exists():
        raise DataError(f"{path}: no such file.", path=str(path))
    try:
        cfg = tomllib.loads(path.read_text())
    except tomllib.TOMLDecodeError as exc:
        raise DataError(f"{path}: not valid TOML ({exc}).", path=str(path)) from None
    except UnicodeDecodeError as exc:
        raise DataError(f"{path}: not a text file ({exc}).", path=str(path)) from None
    problems = check_config(cfg, str(path))
    if problems:
        short = [p.removeprefix(f"{path}: ") for p in problems]
        raise DataError(f"{path}: {len(problems)} problem(s): " + "; ".join(short),
                        problems=problems, path=str(path))
    cfg["_dir"] = path.parent
    cfg["_path"] = str(path)
    return cfg


def _unknown(names, allowed) -> str:
    """Unknown names, each with the nearest valid one: ``mni (did you mean min?)``."""
    import difflib
    out = []
    for name in names:
        close = difflib.get_close_matches(str(name), sorted(map(str, allowed)), 1, 0.6)
        out.append(f"{name} (did you mean {close[0]}?)" if close else str(name))
    return ", ".join(out)


class _Checks:
    """Collects problems of a problem file as ``[table] key: what is wrong``."""

    def __init__(self):
        self.problems: list[str] = []

    def add(self, where: str, text: str) -> None:
        self.problems.append(f"{where}: {text}")

    def keys(self, where: str, table, allowed, required=()) -> bool:
        """``table`` is a table with only ``allowed`` keys and every ``required`` one."""
        if not isinstance(table, dict):
            self.add(where, f"expected a table, got {_show(table)}")
            return False
        unknown = sorted(set(table) - set(allowed))
        if unknown:
            self.add(where, f"unknown key(s) {_unknown(unknown, allowed)}; known: "
                            f"{', '.join(sorted(allowed))}")
        for key in required:
            if key not in table:
                self.add(where, f"missing '{key}'")
        return True

    def number(self, where: str, value, *, positive=False, nonnegative=False,
               integer=False, minimum=None, maximum=None, units=False):
        """A finite number (or with ``units`` a quantity string); returns it in SI base
        units, or None when it is not one (a problem is recorded)."""
        if isinstance(value, bool) or not isinstance(value, (int, float, str)):
            self.add(where, f"expected a {'whole ' if integer else ''}number, got "
                            f"{_show(value)}")
            return None
        if isinstance(value, str):
            if not units:
                self.add(where, f"expected a number, got the text {value!r}")
                return None
            try:
                x = to_base(value, where)
            except UnitError as exc:
                self.add(where, str(exc).split(": ", 1)[-1].rstrip("."))
                return None
        else:
            x = float(value)
        if integer and (isinstance(value, float) and not x.is_integer()):
            self.add(where, f"expected a whole number, got {value!r}")
            return None
        if not math.isfinite(x):
            self.add(where, f"expected a finite number, got {value!r}")
            return None
        if positive and not x > 0:
            self.add(where, f"must be > 0, got {value!r}")
            return None
        if nonnegative and x < 0:
            self.add(where, f"must be >= 0, got {value!r}")
            return None
        if minimum is not None and x < minimum:
            self.add(where, f"must be at least {minimum}, got {value!r}")
            return None
        if maximum is not None and x > maximum:
            self.add(where, f"must be at most {maximum}, got {value!r}")
            return None
        return x

    def text(self, where: str, value, choices=None) -> None:
        if not isinstance(value, str):
            self.add(where, f"expected a text, got {_show(value)}")
        elif choices is not None and value not in choices:
            self.add(where, f"must be one of {', '.join(choices)}, got {value!r}")

    def names(self, where: str, value, *, mapping_ok=False) -> None:
        ok = isinstance(value, list) and all(isinstance(v, str) for v in value)
        if mapping_ok and isinstance(value, dict):
            ok = all(isinstance(v, str) for v in value.values())
        if not ok:
            self.add(where, "expected a list of names" + (" or a table of names"
                                                          if mapping_ok else "")
                     + f", got {_show(value)}")

    def values(self, where: str, table, *, positive=False) -> None:
        """A table whose values are numbers or quantities (e.g. ``[fixed]``)."""
        if self.keys(where, table, table if isinstance(table, dict) else ()):
            for key, value in table.items():
                self.number(f"{where} {key}", value, units=True, positive=positive)

    def bounds(self, where: str, spec) -> None:
        """A free parameter or design variable: a value, or ``{initial, min, max,
        scale}`` with min < max and the initial value between them."""
        if not isinstance(spec, dict):
            self.number(where, spec, units=True)
            return
        self.keys(where, spec, ("initial", "min", "max", "scale"))
        v = {k: self.number(f"{where}.{k}", spec[k], units=True, positive=k == "scale")
             for k in ("initial", "min", "max", "scale") if k in spec}
        lo, hi, x0 = v.get("min"), v.get("max"), v.get("initial")
        if lo is not None and hi is not None and not lo < hi:
            self.add(where, f"the lower bound min = {spec['min']!r} is not below the upper "
                            f"bound max = {spec['max']!r}")
        elif x0 is not None and ((lo is not None and x0 < lo) or (hi is not None and x0 > hi)):
            self.add(where, f"initial = {spec['initial']!r} is outside "
                            f"[{spec.get('min', '-inf')!r}, {spec.get('max', 'inf')!r}]")


def _show(value) -> str:
    kind = {dict: "a table", list: "a list", str: "a text", bool: "a boolean"}.get(
        type(value), type(value).__name__)
    return f"{kind} {value!r}" if not isinstance(value, dict) else kind


def check_config(cfg: dict, path: str = "config") -> list[str]:
    """Every problem of a problem file (as read by :mod:`tomllib`), each as
    ``<path>: [table] key: what is wrong``; empty when the file is sound."""
    c = _Checks()
    unknown = sorted(k for k in set(cfg) - _TOP if not k.startswith("_"))   # _dir, _path
    if unknown:
        c.add("top level", f"unknown section(s) {_unknown(unknown, _TOP)}; known: "
                           f"{', '.join(sorted(_TOP))}")
    if "title" in cfg:
        c.text("title", cfg["title"])
    for key in ("offsets", "free_x0"):
        if key in cfg:
            c.names(key, cfg[key])

    model = cfg.get("model", {})
    if c.keys("[model]", model, ("name", "file", "class", "variant", "set")):
        if ("name" in model) == ("file" in model):
            c.add("[model]", "give either 'name' (a database model, see `mechatron "
                             "models`) or 'file' (a Python file, with 'class' when it "
                             "defines several)" + (", not both" if "name" in model else ""))
        for key in ("name", "file", "class"):
            if key in model:
                c.text(f"[model] {key}", model[key])
        if "class" in model and "file" not in model:
            c.add("[model] class", "needs 'file', the Python file that defines it")
        if "variant" in model:
            c.text("[model] variant", model["variant"])
        if "set" in model:
            c.values("[model] set", model["set"])

    vb = cfg.get("virtual_bench")
    if vb is not None and c.keys("[virtual_bench]", vb, ("seed", "stribeck", "runs")):
        if "seed" in vb:
            c.number("[virtual_bench] seed", vb["seed"], integer=True, nonnegative=True)
        if "stribeck" in vb and not isinstance(vb["stribeck"], bool):
            c.add("[virtual_bench] stribeck", f"expected true or false, got "
                                              f"{_show(vb['stribeck'])}")
        runs = vb.get("runs", {})
        if c.keys("[virtual_bench] runs", runs, _BENCH_RUNS):
            for run, file in runs.items():
                c.text(f"[virtual_bench] runs.{run}", file)

    for table in ("experiments", "validation"):
        _check_experiments(c, table, cfg.get(table, []))

    for table in ("inputs", "outputs"):
        if table in cfg and c.keys(f"[{table}]", cfg[table], cfg[table]
                                   if isinstance(cfg[table], dict) else ()):
            for label, target in cfg[table].items():
                c.text(f"[{table}] {label}", target)

    for table in ("parameters", "design"):
        spec = cfg.get(table, {})
        if c.keys(f"[{table}]", spec, spec if isinstance(spec, dict) else ()):
            for name, entry in spec.items():
                c.bounds(f"[{table}] {name}", entry)
    if "fixed" in cfg:
        c.values("[fixed]", cfg["fixed"])

    opts = cfg.get("options", {})
    if c.keys("[options]", opts, ("substeps", "jit", "smooth", "substep_tol",
                                  "max_substeps")):
        if "substeps" in opts:
            from mechatron.estimation.problem import MAX_SUBSTEPS
            c.number("[options] substeps", opts["substeps"], integer=True, minimum=1,
                     maximum=MAX_SUBSTEPS)
        if "smooth" in opts:
            c.number("[options] smooth", opts["smooth"], positive=True)
        if "substep_tol" in opts:
            c.number("[options] substep_tol", opts["substep_tol"], positive=True)
        if "max_substeps" in opts:
            from mechatron.estimation.problem import MAX_SUBSTEPS
            c.number("[options] max_substeps", opts["max_substeps"], integer=True,
                     minimum=1, maximum=MAX_SUBSTEPS)
        if "jit" in opts and opts["jit"] not in (True, False, "auto"):
            c.add("[options] jit", f"must be true, false or \"auto\", got {opts['jit']!r}")

    est = cfg.get("estimation")
    if est is not None and c.keys("[estimation]", est, ESTIMATION_KEYS):
        if "starts" in est:
            c.number("[estimation] starts", est["starts"], integer=True, minimum=1)
        if "seed" in est:
            c.number("[estimation] seed", est["seed"], integer=True, nonnegative=True)
        if "sampling" in est:
            c.text("[estimation] sampling", est["sampling"], ("lhs", "sobol"))
        if "workers" in est:
            c.number("[estimation] workers", est["workers"], integer=True, minimum=1)
        if "address" in est:
            c.text("[estimation] address", est["address"])

    sens = cfg.get("sensitivity")
    if sens is not None and c.keys("[sensitivity]", sens, ("samples", "method", "seed",
                                                           "workers", "best", "address",
                                                           "distributions")):
        if "samples" in sens:
            c.number("[sensitivity] samples", sens["samples"], integer=True, minimum=2)
        if "method" in sens:
            c.text("[sensitivity] method", sens["method"], ("random", "lhs", "sobol"))
        if "seed" in sens:
            c.number("[sensitivity] seed", sens["seed"], integer=True, nonnegative=True)
        for key in ("workers", "best"):
            if key in sens:
                c.number(f"[sensitivity] {key}", sens[key], integer=True, minimum=1)
        if "address" in sens:
            c.text("[sensitivity] address", sens["address"])
        dists = sens.get("distributions", {})
        if c.keys("[sensitivity.distributions]", dists,
                  dists if isinstance(dists, dict) else ()):
            for name, d in dists.items():
                _check_distribution(c, f"[sensitivity.distributions] {name}", d)

    sim = cfg.get("simulation")
    if sim is not None and c.keys("[simulation]", sim, ("t_stop", "points", "signals")):
        if "t_stop" in sim:
            c.number("[simulation] t_stop", sim["t_stop"], positive=True)
        if "points" in sim:
            c.number("[simulation] points", sim["points"], integer=True, minimum=2)
        if "signals" in sim:
            c.names("[simulation] signals", sim["signals"], mapping_ok=True)

    reqs = cfg.get("requirements", [])
    if not isinstance(reqs, list):
        c.add("[[requirements]]", f"expected an array of tables, got {_show(reqs)}")
        reqs = []
    for k, req in enumerate(reqs, 1):
        _check_requirement(c, f"[[requirements]] {k}", req)
    return [f"{path}: {p}" for p in c.problems]


def _check_experiments(c: _Checks, table: str, experiments) -> None:
    """``[[experiments]]`` or ``[[validation]]``: data files and how they bind."""
    if not isinstance(experiments, list):
        c.add(f"[[{table}]]", f"expected an array of tables ([[{table}]]), got "
                              f"{_show(experiments)}")
        return
    for k, exp in enumerate(experiments, 1):
        where = f"[[{table}]] {k}" + (f" ({exp['name']})" if isinstance(exp, dict)
                                      and isinstance(exp.get("name"), str) else "")
        if not c.keys(where, exp, _EXPERIMENT_KEYS, required=("file",)):
            continue
        if "fit" in exp and (table != "experiments" or not isinstance(exp["fit"], bool)):
            c.add(f"{where} fit", f"expected true or false in [[experiments]], got "
                                  f"{_show(exp['fit'])}")
        for key in ("name", "file", "time"):
            if key in exp:
                c.text(f"{where} {key}", exp[key])
        for key in ("inputs", "outputs"):
            if key in exp:
                c.names(f"{where} {key}", exp[key], mapping_ok=True)
        if "hold" in exp:
            c.text(f"{where} hold", exp["hold"], ("zoh", "linear"))
        if "units" in exp and c.keys(f"{where} units", exp["units"],
                                     exp["units"] if isinstance(exp["units"], dict) else ()):
            for label, unit in exp["units"].items():
                c.text(f"{where} units.{label}", unit)
        for key in ("params", "x0"):
            if key in exp:
                c.values(f"{where} {key}", exp[key])
        if "sigma" in exp and isinstance(exp["sigma"], dict):
            outputs = exp.get("outputs", [])
            for label, value in exp["sigma"].items():
                c.number(f"{where} sigma.{label}", value, positive=True)
                if isinstance(outputs, (list, dict)) and outputs and label not in outputs:
                    c.add(f"{where} sigma.{label}", f"'{label}' is not an output of this "
                          f"experiment ({', '.join(outputs)})")
        elif "sigma" in exp:
            c.add(f"{where} sigma", f"expected a table, got {_show(exp['sigma'])}")

        for key, whole in (("rows", True), ("t_range", False)):
            if key not in exp:
                continue
            v = exp[key]
            if not (isinstance(v, list) and 1 <= len(v) <= 2):
                c.add(f"{where} {key}", f"expected [start, stop] or [start], got {_show(v)}")
                continue
            vals = [c.number(f"{where} {key}", x, integer=whole) for x in v]
            same_sign = not whole or (vals[0] >= 0) == (vals[1] >= 0) \
                if len(vals) == 2 and None not in vals else False
            if same_sign and not vals[0] < vals[1]:
                c.add(f"{where} {key}", f"start {v[0]!r} is not below stop {v[1]!r}")
        if "params_free" in exp:
            c.names(f"{where} params_free", exp["params_free"])


def _check_distribution(c: _Checks, where: str, d) -> None:
    if not isinstance(d, dict):
        c.add(where, f"expected a table such as {{ kind = \"uniform\", low = 5, high = 10 }}"
                     f", got {_show(d)}")
        return
    kind = d.get("kind", "uniform")
    if kind not in ("uniform", "normal", "loguniform"):
        c.add(f"{where} kind", f"must be uniform, normal or loguniform, got {kind!r}")
        return
    keys = ("mean", "std") if kind == "normal" else ("low", "high")
    c.keys(where, d, ("kind", *keys), required=keys)
    v = {k: c.number(f"{where}.{k}", d[k], units=True) for k in keys if k in d}
    if kind == "normal":
        if v.get("std") is not None and not v["std"] > 0:
            c.add(f"{where}.std", f"must be > 0, got {d['std']!r}")
        return
    lo, hi = v.get("low"), v.get("high")
    if lo is not None and hi is not None and not lo < hi:
        c.add(where, f"low = {d['low']!r} is not below high = {d['high']!r}")
    if kind == "loguniform" and lo is not None and not lo > 0:
        c.add(f"{where}.low", f"a loguniform distribution needs low > 0, got {d['low']!r}")


def _check_requirement(c: _Checks, where: str, req) -> None:
    if not isinstance(req, dict):
        c.add(where, f"expected a table, got {_show(req)}")
        return
    kind = req.get("type")
    if kind not in _REQUIREMENT_KEYS:
        c.add(f"{where} type", f"must be step, bound or tracking, got {kind!r}")
        return
    where = f"{where} ({kind})"
    c.keys(where, req, {"type", *_REQUIREMENT_KEYS[kind]},
           required=("signal", "final") if kind == "step" else ("signal",))
    if "signal" in req:
        c.text(f"{where} signal", req["signal"])
    num = {}
    for key in _REQUIREMENT_KEYS[kind] - {"signal", "reference"}:
        if key in req:
            positive = key in ("rise_time", "settling_time", "settling", "weight")
            num[key] = c.number(f"{where} {key}", req[key], positive=positive,
                                nonnegative=key in ("overshoot", "t_step", "t_start"))
    if "reference" in req:
        c.number(f"{where} reference", req["reference"])
    if num.get("rise") is not None and not 0 < num["rise"] <= 100:
        c.add(f"{where} rise", f"a percentage of the step in (0, 100], got {req['rise']!r}")
    for lo, hi in (("lower", "upper"), ("t_start", "t_end")):
        if num.get(lo) is not None and num.get(hi) is not None and not num[lo] < num[hi]:
            c.add(where, f"{lo} = {req[lo]!r} is not below {hi} = {req[hi]!r}")


def build_model(cfg: dict):
    """The model of ``[model]``: ``name``, a database entry (``"dc_motor"``, with
    optional ``variant``), or ``file``, a Python file of the user's relative to the
    problem file, with ``class`` naming the :class:`~mechatron.Component` subclass when
    the file defines several (see :mod:`mechatron.models.user`); ``set`` gives parameter
    values. ``name`` accepts database names only: nothing is imported from the import
    path, so a problem file cannot run ``os:abort``."""
    from mechatron.models.user import load_model_file
    where = cfg.get("_path", "config")
    spec = cfg.get("model", {})
    name, file = spec.get("name"), spec.get("file")
    if file:
        if "variant" in spec:
            raise DataError(f"{where}: [model] variant: a model file has no variants; "
                            "remove the key.", path=where)
        target = f"{file}:{spec['class']}" if spec.get("class") else file
        try:
            cls = load_model_file(target, base=cfg.get("_dir"))
        except ModelError as exc:
            raise ModelError(f"{where}: [model] file: {exc}", path=where) from None
        return cls(**spec.get("set", {}))
    if not name:
        raise DataError(f"{where}: [model] needs 'name' (a database entry, see "
                        "`mechatron models`) or 'file' (a Python file, with 'class').",
                        path=where)
    known = [e.name for e in mt.models.list()]
    if name not in known:
        hint = ("Give a file as file = \"model.py\" (and class = \"Name\")"
                if name.endswith(".py") or ".py:" in name or ":" in name else
                f"Known: {', '.join(sorted(known))}")
        raise ModelError(f"{where}: [model] name: '{name}' is not a database model; name "
                         f"accepts database names only. {hint}.", path=where)
    entry = mt.models.get(name)
    return entry.build(spec.get("variant"), **spec.get("set", {}))


def _value(raw, unit: str, where: str) -> float:
    return float(to_si(raw, unit, where))


def _experiments(cfg: dict, table: str = "experiments") -> list[Experiment]:
    """The experiments of ``[[experiments]]`` to fit, each cut to its ``rows`` or
    ``t_range``; with ``table="validation"``, those of ``[[validation]]`` and the
    ``[[experiments]]`` marked ``fit = false`` (simulated with the estimates, not fitted)."""
    base = Path(cfg["_dir"])
    out = []
    for k, spec in enumerate(cfg.get(table, [])):
        if "file" not in spec:
            raise DataError(f"{cfg['_path']}: [[{table}]] number {k + 1} has no 'file'.")
        if table == "experiments" and spec.get("fit", True) is False:
            continue
        out.append(_load(base / spec["file"], spec))
    if table == "validation":
        out += [_load(base / spec["file"], spec) for spec in cfg.get("experiments", [])
                if spec.get("fit", True) is False]
    if not out and table == "experiments":
        raise DataError(f"{cfg['_path']}: no [[experiments]] to fit; give at least one data file (without fit = false).")
    return out


def _load(path, spec: dict) -> Experiment:
    exp = load_experiment(path, time=spec.get("time", "t"),
                          inputs=spec.get("inputs", []), outputs=spec.get("outputs", []),
                          units=spec.get("units"), name=spec.get("name"),
                          params=dict(spec.get("params", {})),
                          x0=dict(spec.get("x0", {})), hold=spec.get("hold", "zoh"),
                          sigma=dict(spec.get("sigma", {})))
    if "rows" in spec or "t_range" in spec:
        pad = [None, None]
        exp = exp.select(rows=(list(spec["rows"]) + pad)[:2] if "rows" in spec else None,
                         t_range=(list(spec["t_range"]) + pad)[:2]
                         if "t_range" in spec else None)
    return exp


def validation_experiments(cfg: dict, data=()) -> list[Experiment]:
    """The validation data: the files ``data`` read with the column mapping of the first
    ``[[experiments]]`` entry (its ``rows``/``t_range`` dropped), or else
    ``[[validation]]``."""
    if data:
        spec = {k: v for k, v in cfg["experiments"][0].items()
                if k not in ("rows", "t_range", "name", "file")}
        return [_load(Path(f), dict(spec, name=Path(f).stem)) for f in data]
    return _experiments(cfg, "validation")


def per_experiment(cfg: dict, table: str = "experiments", data=()) -> dict:
    """``{experiment name: [parameter, ...]}`` from ``params_free`` of each entry; for
    the files ``data`` (see :func:`validation_experiments`), those of the first
    ``[[experiments]]`` entry."""
    if data:
        free = list(cfg["experiments"][0].get("params_free", []))
        return {Path(f).stem: free for f in data} if free else {}
    out = {}
    for k, spec in enumerate(cfg.get(table, [])):
        if spec.get("params_free"):
            name = spec.get("name") or Path(spec["file"]).stem
            out[name] = list(spec["params_free"])
    return out


def generate_bench_data(cfg: dict, *, force: bool = False) -> list[Path]:
    """Write the virtual-bench data files named in ``[virtual_bench]`` that are missing.

    ``[virtual_bench] seed = 0``, and ``runs = {name = "file.csv"}`` with ``name`` one of
    ``locked_rotor``, ``voltage_step``, ``multi_step``."""
    vb = cfg.get("virtual_bench")
    if not vb:
        return []
    from mechatron.estimation.bench import VirtualBench
    base = Path(cfg["_dir"])
    bench = None
    written = []
    for run, file in vb.get("runs", {}).items():
        path = base / file
        if path.exists() and not force:
            continue
        if bench is None:
            bench = VirtualBench(seed=int(vb.get("seed", 0)),
                                 stribeck=bool(vb.get("stribeck", True)))
        if run not in ("locked_rotor", "voltage_step", "multi_step"):
            raise DataError(f"{cfg['_path']}: [virtual_bench] runs: unknown run '{run}'; "
                            "use locked_rotor, voltage_step or multi_step.")
        log.info("virtual bench: generating %s (%s run, seed %s)", path, run,
                 vb.get("seed", 0))
        exp = getattr(bench, run)()
        written.append(exp.save(path))
    return written


def build_estimation(cfg: dict, *, model=None):
    """An :class:`~mechatron.estimation.EstimationProblem` from a problem file."""
    from mechatron.estimation.problem import EstimationProblem, FreeParameter
    generate_bench_data(cfg)
    model = model if model is not None else build_model(cfg)
    cm = mt.compile_model(model) if not isinstance(model, mt.CompiledModel) else model
    units = dict(zip(cm.param_names, cm.param_units))
    free = []
    for name, spec in cfg.get("parameters", {}).items():
        if name not in units:
            raise ParameterError(f"{cfg['_path']}: [parameters] '{name}' is not a parameter "
                                 f"of the model: {cm.not_a_parameter(name)}", path=name)
        spec = spec if isinstance(spec, dict) else {"initial": spec}
        bad = sorted(set(spec) - {"initial", "min", "max", "scale"})
        if bad:
            raise ParameterError(f"{cfg['_path']}: [parameters] {name}: unknown key(s) "
                                 f"{', '.join(bad)}; use initial, min, max, scale.",
                                 path=name)
        kw = {key: _value(spec[key], units[name], f"{name}.{key}")
              for key in ("initial", "min", "max", "scale") if key in spec}
        free.append(FreeParameter(name, **kw))
    fixed = {name: _value(v, units.get(name, ""), name)
             for name, v in cfg.get("fixed", {}).items()}
    opts = cfg.get("options", {})
    # a model with sampled parts goes as it is: its input delays are applied to the data
    # (see mechatron.estimation.delays)
    target = model if cm.nr and not isinstance(model, mt.CompiledModel) else cm
    return EstimationProblem(target, _experiments(cfg), free,
                             inputs=cfg.get("inputs", {}), outputs=cfg.get("outputs", {}),
                             fixed=fixed, offsets=cfg.get("offsets", []),
                             free_x0=cfg.get("free_x0", []),
                             per_experiment=per_experiment(cfg),
                             substeps=opts.get("substeps"),
                             substep_tol=opts.get("substep_tol", 0.1),
                             max_substeps=opts.get("max_substeps", 400),
                             jit=opts.get("jit", "auto"), smooth=opts.get("smooth"),
                             validation=_experiments(cfg, "validation"))


def build_sensitivity(cfg: dict):
    """``(problem, distributions, options)`` for ``mechatron sensitivity``: the estimation
    problem of the file (model, experiments, parameters) and ``[sensitivity]``:
    ``samples``, ``method``, ``seed``, ``workers``, ``best`` and ``distributions`` (per
    parameter ``{kind = "uniform", low, high}``, ``{kind = "normal", mean, std}`` or
    ``{kind = "loguniform", low, high}``)."""
    from mechatron.estimation.sensitivity import Distribution
    sec = dict(cfg.get("sensitivity", {}))
    dspec = sec.pop("distributions", {})
    if not dspec:
        raise DataError(f"{cfg['_path']}: [sensitivity.distributions] is empty; give a "
                        "distribution per parameter, e.g. R = { kind = \"uniform\", "
                        "low = 5, high = 10 }.")
    bad = sorted(set(sec) - {"samples", "method", "seed", "workers", "best", "address"})
    if bad:
        raise DataError(f"{cfg['_path']}: [sensitivity] unknown key(s) {', '.join(bad)}.")
    params = dict(cfg.get("parameters", {}))
    for name in dspec:
        params.setdefault(name, {})
    cfg = dict(cfg, parameters=params)
    prob = build_estimation(cfg)
    units = dict(zip(prob.cm.param_names, prob.cm.param_units))
    dists = {}
    for name, spec in dspec.items():
        kind = spec.get("kind", "uniform")
        u = units.get(name, "")
        if kind == "normal":
            dists[name] = Distribution(kind, _value(spec["mean"], u, name),
                                       _value(spec["std"], u, name))
        else:
            dists[name] = Distribution(kind, _value(spec["low"], u, name),
                                       _value(spec["high"], u, name))
    return prob, dists, sec


def build_response(cfg: dict, *, model=None):
    """A :class:`~mechatron.estimation.optimize.ResponseProblem` from ``[design]``,
    ``[[requirements]]`` (``type`` = "step", "bound" or "tracking") and ``[simulation]``
    (``t_stop``, ``points``)."""
    from mechatron.estimation.optimize import (DesignVariable, ResponseProblem,
                                               SignalBound, StepResponse, Tracking)
    model = model if model is not None else build_model(cfg)
    cm = mt.compile_model(model) if not isinstance(model, mt.CompiledModel) else model
    units = dict(zip(cm.param_names, cm.param_units))
    design = []
    for name, spec in cfg.get("design", {}).items():
        spec = spec if isinstance(spec, dict) else {"initial": spec}
        u = units.get(name, "")
        design.append(DesignVariable(name, **{k: _value(v, u, f"{name}.{k}")
                                              for k, v in spec.items()}))
    if not design:
        raise DataError(f"{cfg['_path']}: [design] is empty; name the parameters to tune.")
    reqs = []
    for k, spec in enumerate(cfg.get("requirements", [])):
        spec = dict(spec)
        kind = spec.pop("type", None)
        try:
            if kind == "step":
                spec["overshoot_pct"] = spec.pop("overshoot", 5.0)
                spec["settling_pct"] = spec.pop("settling", 2.0)
                spec["rise_pct"] = spec.pop("rise", 80.0)
                reqs.append(StepResponse(**spec))
            elif kind == "bound":
                reqs.append(SignalBound(**spec))
            elif kind == "tracking":
                reqs.append(Tracking(**spec))
            else:
                raise DataError(f"{cfg['_path']}: [[requirements]] {k + 1}: type must be "
                                f"step, bound or tracking, got {kind!r}.")
        except TypeError as exc:
            raise DataError(f"{cfg['_path']}: [[requirements]] {k + 1} ({kind}): "
                            f"{exc}.") from None
    sim = cfg.get("simulation", {})
    if "t_stop" not in sim:
        raise DataError(f"{cfg['_path']}: [simulation] needs t_stop (s).")
    fixed = {name: _value(v, units.get(name, ""), name)
             for name, v in cfg.get("fixed", {}).items()}
    return ResponseProblem(cm, design, reqs, t_stop=float(sim["t_stop"]),
                           n_points=int(sim.get("points", 1001)), fixed=fixed,
                           signals=sim.get("signals"))
