"""TOML problem files for ``mechatron estimate``, ``sensitivity`` and ``optimize``.

The format is documented in ``docs/estimation.md``. Paths in a file are relative to the
file's folder. Values may carry units (``"340 uH"``); they are converted to the unit of
the model parameter they set. Unknown keys are errors (a typo must not be ignored).
"""

from __future__ import annotations

import importlib
import tomllib
from pathlib import Path


import mechatron as mt
from mechatron.errors import DataError, ParameterError
from mechatron.estimation.data import Experiment, load_experiment
from mechatron.units import to_si

__all__ = ["load_config", "build_model", "build_estimation", "build_sensitivity",
           "build_response", "generate_bench_data"]

_TOP = {"model", "experiments", "parameters", "fixed", "offsets", "free_x0",
        "virtual_bench", "options", "sensitivity", "requirements", "design", "simulation",
        "inputs", "outputs", "title"}


def load_config(path) -> dict:
    """Read a problem file; ``cfg["_dir"]`` is its folder and ``cfg["_path"]`` its path."""
    path = Path(path)
    if not path.exists():
        raise DataError(f"{path}: no such file.", path=str(path))
    try:
        cfg = tomllib.loads(path.read_text())
    except tomllib.TOMLDecodeError as exc:
        raise DataError(f"{path}: not valid TOML ({exc}).", path=str(path)) from None
    unknown = sorted(set(cfg) - _TOP)
    if unknown:
        raise DataError(f"{path}: unknown section(s) {', '.join(unknown)}; known: "
                        f"{', '.join(sorted(_TOP))}.", path=str(path))
    cfg["_dir"] = path.parent
    cfg["_path"] = str(path)
    return cfg


def build_model(cfg: dict):
    """The model named by ``[model] name``: a database entry (``"dc_motor"``, with
    optional ``variant`` and ``set``) or ``"package.module:Callable"`` returning a model."""
    spec = cfg.get("model", {})
    name = spec.get("name")
    if not name:
        raise DataError(f"{cfg.get('_path', 'config')}: [model] needs a 'name': a database "
                        "entry (see `mechatron models`) or 'module:Class'.")
    if ":" in name:
        module, _, attr = name.partition(":")
        try:
            obj = getattr(importlib.import_module(module), attr)
        except (ImportError, AttributeError) as exc:
            raise DataError(f"{cfg.get('_path')}: [model] name '{name}': cannot import "
                            f"({exc}).") from None
        return obj()
    entry = mt.models.get(name)
    return entry.build(spec.get("variant"), **spec.get("set", {}))


def _value(raw, unit: str, where: str) -> float:
    return float(to_si(raw, unit, where))


def _experiments(cfg: dict) -> list[Experiment]:
    base = Path(cfg["_dir"])
    out = []
    for k, spec in enumerate(cfg.get("experiments", [])):
        if "file" not in spec:
            raise DataError(f"{cfg['_path']}: [[experiments]] number {k + 1} has no 'file'.")
        path = base / spec["file"]
        exp = load_experiment(path, time=spec.get("time", "t"),
                              inputs=spec.get("inputs", []), outputs=spec.get("outputs", []),
                              units=spec.get("units"), name=spec.get("name"),
                              params=dict(spec.get("params", {})),
                              x0=dict(spec.get("x0", {})), hold=spec.get("hold", "zoh"),
                              sigma=dict(spec.get("sigma", {})))
        out.append(exp)
    if not out:
        raise DataError(f"{cfg['_path']}: no [[experiments]]; give at least one data file.")
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
                                 f"of the model (parameters: {', '.join(cm.param_names)}).",
                                 path=name)
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
    return EstimationProblem(cm, _experiments(cfg), free,
                             inputs=cfg.get("inputs", {}), outputs=cfg.get("outputs", {}),
                             fixed=fixed, offsets=cfg.get("offsets", []),
                             free_x0=cfg.get("free_x0", []),
                             substeps=opts.get("substeps"),
                             jit=opts.get("jit", "auto"))


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
