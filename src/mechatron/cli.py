"""The ``mechatron`` command (also ``python -m mechatron``).

Subcommands
-----------
``models``
    List the model database.
``show NAME``
    Description, parameters with units and provenance, variants, outputs, experiment and
    expected values of one entry.
``simulate NAME``
    Build, compile and simulate one variant; print the final value of every output and the
    solver profile; optionally save the log (CSV/Parquet) and a plot.
``compare NAME``
    Simulate every variant on the same output grid and print their largest deviations.
``demo``
    The showcase: :data:`DEMO_STEPS`, run in order.

Every subcommand takes ``--help``; ``--json`` prints one JSON object on stdout instead of
the human summary. A model (``NAME``) is a database name, a user's file
``path/to/model.py[:ClassName]`` or ``package.module:ClassName`` (see
:mod:`mechatron.models.user`). The library's log (the ``mechatron`` logger) goes to
stderr: warnings always, what is done with ``-v``, details with ``-vv``. Runs over
:data:`PROGRESS_DELAY` s show a progress bar (tqdm) on stderr when it is a terminal;
``-q`` hides it.

Exit codes and errors
---------------------
0 on success; 2 for a usage error (argparse's, also one line) or a problem with the
user's input (any :class:`~mechatron.errors.MechatronError`, :class:`ValueError`,
:class:`TypeError`, an :class:`OSError` such as a missing file or folder or a full disk),
reported as one line ``error: <message>`` on stderr; 1 for an unexpected error (a bug),
also one line, or for a demo whose checks failed. ``tests/test_cli_fuzz.py`` holds the
commands to this on random arguments and problem files. Set
``MECHATRON_DEBUG=1`` to get the traceback as well.

Later subcommands (``library``, ``codegen``, ``estimate``...) live beside the code they
drive, in a module named in :data:`EXTENSIONS` that defines ``add_commands(sub)``; it
adds its parsers to ``sub`` and uses the helpers of this module (:func:`emit`,
:func:`emit_json`, :func:`table`, :func:`add_json`). The command-line modules are the
only ones of Mechatron that print.
"""

from __future__ import annotations

import argparse
import difflib
import json
import logging
import math
import os
import signal
import sys
import threading
import time
import traceback
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

import mechatron as mt
from mechatron._io import save_figure
from mechatron.errors import MechatronError
from mechatron.models.compare import COMPARE_POINTS, compare_variants
from mechatron.models.user import entry_for
from mechatron.models.compare import relative as _relative
from mechatron.models.compare import max_deviation as _max_deviation
from mechatron.results import SUFFIXES as LOG_SUFFIXES
from mechatron.results import SimResult
from mechatron.solvers import METHODS as FIXED_STEP_METHODS
from mechatron.solvers import SOLVERS
from mechatron.solvers.simulate import MAX_MEMORY
from mechatron.units import check_number_text

__all__ = ["main", "build_parser", "EXTENSIONS", "DEMO_STEPS", "DemoStep", "DemoRun", "CommandError",
           "EXIT_OK", "EXIT_FAILURE", "EXIT_USAGE"]

EXIT_OK = 0
EXIT_FAILURE = 1     # an unexpected error, or a demo check that failed
EXIT_USAGE = 2       # bad arguments or bad input (argparse's own code for usage errors)


#: Exceptions that mean "the input is wrong", not "Mechatron is wrong".
#: ``OSError`` covers the environment as well: a full disk, a folder that cannot be written.
USER_ERRORS = (MechatronError, ValueError, TypeError, OSError)


class CommandError(MechatronError, ValueError):
    """A command-line argument that cannot be used as given."""


#: Help of a NAME argument: what the commands accept as a model.
MODEL_HELP = ("model: a database name (see `mechatron models`), a Python file "
              "path/to/model.py[:ClassName] or package.module:ClassName")


# ---------------------------------------------------------------------------- formatting
# The public names (emit, emit_json, table, add_json, ...) are defined after the parser
# helpers below; extension modules import them from here.
def _emit(text: str = "") -> None:
    print(text)


def _emit_json(obj: Any) -> None:
    print(json.dumps(_jsonable(obj), indent=2, allow_nan=False))


def _jsonable(obj: Any) -> Any:
    """``obj`` with NumPy scalars made plain and non-finite floats made ``null``."""
    if isinstance(obj, dict):
        return {str(k): _jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_jsonable(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return _jsonable(obj.tolist())
    if isinstance(obj, (bool, np.bool_)):
        return bool(obj)
    if isinstance(obj, (int, np.integer)):
        return int(obj)
    if isinstance(obj, (float, np.floating)):
        return float(obj) if math.isfinite(obj) else None
    if isinstance(obj, Path):
        return str(obj)
    return obj


def _one_line(text: str) -> str:
    """Collapse a (possibly multi-line) message into one line."""
    parts = [line.strip() for line in str(text).splitlines() if line.strip()]
    return "; ".join(parts) if parts else "(no message)"


def _num(x: float | None, digits: int = 10) -> str:
    return "-" if x is None else f"{x:.{digits}g}"


def _duration(seconds: float | None) -> str:
    if seconds is None:
        return "-"
    if seconds < 1e-3:
        return f"{seconds * 1e6:.0f} us"
    if seconds < 1.0:
        return f"{seconds * 1e3:.1f} ms"
    return f"{seconds:.2f} s"


def _table(headers: Sequence[str], rows: Iterable[Sequence[Any]], *, right: str = "",
           indent: str = "  ") -> str:
    """A plain text table; columns whose index is in ``right`` (e.g. ``"12"``) are
    right-aligned."""
    cells = [[str(c) for c in headers]] + [[str(c) for c in r] for r in rows]
    widths = [max(len(r[i]) for r in cells) for i in range(len(headers))]
    lines = []
    for row in cells:
        parts = [c.rjust(w) if str(i) in right else c.ljust(w)
                 for i, (c, w) in enumerate(zip(row, widths))]
        lines.append(indent + "  ".join(parts).rstrip())
    return "\n".join(lines)


def _first_sentence(text: str, width: int = 78) -> str:
    text = " ".join(text.split())
    head = text.split(". ")[0].rstrip(".")
    return head if len(head) <= width else head[: width - 3].rstrip() + "..."


# ------------------------------------------------------------------------ shared helpers
def _parse_sets(items: Sequence[str] | None, entry) -> dict[str, float | str]:
    """``--set NAME=VALUE`` items as keyword arguments of ``entry.build``.

    Plain numbers become floats (SI); anything else is passed on as a quantity string for
    pint (``"340 uH"``), which ``entry.build`` converts or rejects with the parameter's name.
    """
    params: dict[str, float | str] = {}
    for item in items or ():
        key, sep, value = item.partition("=")
        key, value = key.strip(), value.strip()
        if not sep or not key or not value:
            raise CommandError(f"--set {item!r}: expected NAME=VALUE, e.g. --set R=7.5 or "
                               f"--set \"L=340 uH\".")
        if key not in entry.parameters:
            close = [k for k in entry.parameters if k.lower() == key.lower()]
            close += [k for k in difflib.get_close_matches(key, list(entry.parameters), 3)
                      if k not in close]
            hint = f" Did you mean {', '.join(close)}?" if close else ""
            raise CommandError(f"--set {key}: model '{entry.name}' has no parameter "
                               f"'{key}'.{hint} Parameters: {', '.join(entry.parameters)} "
                               f"(`mechatron show {entry.name}` describes them).")
        if key in params:
            raise CommandError(f"--set {key}: given twice ({params[key]!r} and {value!r}); "
                               f"give each parameter once.")
        params[key] = _number_or_quantity(key, value)
    return params


def _parse_inputs(items: Sequence[str] | None) -> dict[str, object]:
    """``--input U=VALUE`` (a number in SI or a quantity, constant) or ``--input
    U=FILE.csv`` (a table: a header row with a column ``t`` in s and one value column, or
    a column named ``U`` among several): the ``inputs`` of :func:`mechatron.simulate`."""
    inputs: dict[str, object] = {}
    for item in items or ():
        key, sep, value = item.partition("=")
        key, value = key.strip(), value.strip()
        if not sep or not key or not value:
            raise CommandError(f"--input {item!r}: expected NAME=VALUE or NAME=FILE.csv, "
                               "e.g. --input u=3.5 or --input u=drive.csv.")
        if key in inputs:
            raise CommandError(f"--input {key}: given twice; give each input once.")
        if value.lower().endswith(".csv"):
            inputs[key] = _input_table(key, Path(value))
        else:
            check_number_text(value, f"--input {key}")
            try:
                inputs[key] = float(value)
            except ValueError:
                inputs[key] = value          # a quantity string, checked by simulate
            else:
                if not math.isfinite(inputs[key]):
                    raise CommandError(f"--input {key}: expected a finite value, got "
                                       f"{value!r}.")
    return inputs


def _input_table(key: str, path: Path) -> tuple[np.ndarray, np.ndarray]:
    if not path.is_file():
        raise CommandError(f"--input {key}={path}: no such file. Give a CSV file with a "
                           f"header row 't,{key}'.")
    lines = [line for line in path.read_text(errors="replace").splitlines() if line.strip()]
    if len(lines) < 2:
        got = "an empty file" if not lines else "a header and no rows"
        raise CommandError(f"--input {key}={path}: {got}; expected a header row 't,{key}' "
                           "and at least one row of numbers.")
    try:
        data = np.genfromtxt(path, delimiter=",", names=True, dtype=float, ndmin=1)
    except ValueError as exc:
        raise CommandError(f"--input {key}={path}: cannot read it as CSV of numbers "
                           f"({exc}). Expected a header row 't,{key}' and rows of "
                           "numbers.") from None
    names = list(data.dtype.names or ())
    values = [n for n in names if n != "t"]
    column = key if key in values else (values[0] if len(values) == 1 else None)
    if "t" not in names or column is None:
        raise CommandError(f"--input {key}={path}: expected a column 't' (s) and one value "
                           f"column (or one named '{key}'), got columns "
                           f"{', '.join(names) or '(none)'}.")
    return np.atleast_1d(data["t"]), np.atleast_1d(data[column])


def _number_or_quantity(key: str, value: str) -> float | str:
    check_number_text(value, f"--set {key}")
    try:
        number = float(value)
    except ValueError:
        return value
    if not math.isfinite(number):
        raise CommandError(f"--set {key}: expected a finite value, got {value!r}.")
    return number


#: The most steps a fixed-step run of the command line may take: every step is kept in
#: memory (states, and the logged variables computed from them).
MAX_FIXED_STEPS = 10_000_000


def check_step_count(dt: float, t_stop: float, limit: int = MAX_FIXED_STEPS, *,
                     force: bool = False) -> int:
    """The number of fixed steps of ``t_stop / dt``; a :class:`CommandError` naming both
    when it is above ``limit`` (the run would exhaust the memory, not finish), unless
    ``force`` (the command's ``--force``)."""
    if not (isinstance(t_stop, (int, float)) and math.isfinite(t_stop) and t_stop > 0):
        return 0                       # simulate reports a bad t_stop itself
    steps = t_stop / dt
    if steps > limit and not force:
        raise CommandError(f"--dt {dt:g} s with t_stop {t_stop:g} s: {steps:.3g} fixed "
                           f"steps, more than the {limit:,} a run may take (each step is "
                           f"kept in memory). Give a larger --dt (at least "
                           f"{t_stop / limit:.3g} s) or a shorter --t-stop; --force "
                           f"goes on anyway.")
    return int(math.ceil(steps))


def _output_path(path: str | None, option: str, suffixes: Sequence[str]) -> Path | None:
    """Check an output file before any work is done: suffix and existing directory."""
    if path is None:
        return None
    p = Path(path)
    if p.suffix.lower() not in suffixes:
        got = repr(p.suffix) if p.suffix else "no suffix"
        raise CommandError(f"{option} {path}: cannot write {got}; use one of "
                           f"{', '.join(suffixes)}.")
    parent = p.parent if str(p.parent) else Path(".")
    if not parent.is_dir():
        raise FileNotFoundError(f"{option} {path}: directory '{parent}' does not exist; "
                                f"create it first.")
    return p


def _figure_suffixes() -> tuple[str, ...]:
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    return tuple(f".{s}" for s in FigureCanvasAgg.get_supported_filetypes())


def _new_figure(rows: int, *, width: float = 8.0, height: float = 2.4, sharex: bool = True):
    from matplotlib.figure import Figure  # no pyplot: no global state, no window

    fig = Figure(figsize=(width, 1.0 + height * rows), layout="constrained")
    axes = list(fig.subplots(rows, 1, sharex=sharex, squeeze=False)[:, 0])
    return fig, axes


def _unit_label(unit: str) -> str:
    return f"[{unit}]" if unit else "[1]"


@dataclass(frozen=True)
class _Settings:
    """What a ``simulate``/``compare`` run uses: the experiment with the options applied."""

    t_stop: float
    solver: str
    dt: float | None
    rtol: float
    atol: float

    @classmethod
    def resolve(cls, args: argparse.Namespace, entry) -> _Settings:
        exp = entry.experiment
        solver = getattr(args, "solver", None) or exp.solver
        user_dt = getattr(args, "dt", None)
        dt = user_dt if user_dt is not None else exp.dt
        fixed = solver in FIXED_STEP_METHODS
        if user_dt is not None and not fixed:
            raise CommandError(f"--dt {user_dt:g}: solver '{solver}' chooses its own steps; "
                               f"--dt needs a fixed-step --solver "
                               f"({', '.join(FIXED_STEP_METHODS)}).")
        if fixed and dt is None:
            raise CommandError(f"--solver {solver}: a fixed-step method needs a step size; "
                               f"give one with --dt, e.g. --dt 1e-5.")
        if dt is not None and not (math.isfinite(dt) and dt > 0):
            raise CommandError(f"--dt: the step size must be a number > 0, got {dt!r}.")
        t_stop = getattr(args, "t_stop", None)
        t_stop = exp.t_stop if t_stop is None else t_stop
        if fixed:
            check_step_count(dt, t_stop, force=getattr(args, "force", False))
        rtol = getattr(args, "rtol", None)
        atol = getattr(args, "atol", None)
        for option, value in (("--rtol", rtol), ("--atol", atol)):
            if value is not None and not (math.isfinite(value) and value > 0):
                raise CommandError(f"{option}: a tolerance must be a number > 0, "
                                   f"got {value!r}.")
        return cls(t_stop=t_stop, solver=solver, dt=dt if fixed else None,
                   rtol=exp.rtol if rtol is None else rtol,
                   atol=exp.atol if atol is None else atol)

    def describe(self) -> str:
        if self.dt is not None:
            return f"{self.solver}, dt {self.dt:g} s"
        return f"{self.solver}, rtol {self.rtol:g}, atol {self.atol:g}"

    def as_dict(self) -> dict[str, Any]:
        return {"t_stop": self.t_stop, "solver": self.solver, "dt": self.dt,
                "rtol": self.rtol, "atol": self.atol}


def _profile_rows(runs: dict[str, Any]) -> list[list[str]]:
    """Rows of the solver profile table, one per run (name -> SolverStats)."""
    rows = []
    for name, st in runs.items():
        events = sum(st.events.values()) if st.events else 0
        rows.append([name, st.solver, f"{st.steps:,}", f"{st.rejected_steps:,}",
                     f"{st.rhs_evals:,}", f"{st.jac_evals:,}", f"{events:,}",
                     _duration(st.wall_time), _duration(st.compile_time)])
    return rows


_PROFILE_HEADERS = ["run", "solver", "steps", "rejected", "rhs evals", "jac evals", "events",
                    "wall time", "compile time"]


# ------------------------------------------------------------------------------ models
def cmd_models(args: argparse.Namespace) -> int:
    entries = mt.models.list()
    if args.tag:
        tag = args.tag.lower()
        entries = [e for e in entries if tag in (t.lower() for t in e.tags)]
        if not entries:
            tags = sorted({t for e in mt.models.list() for t in e.tags})
            raise CommandError(f"--tag {args.tag}: no model has this tag. Tags in the "
                               f"database: {', '.join(tags) or '(none)'}.")
    if args.json:
        _emit_json({"models": [{"name": e.name, "variants": list(e.variants),
                                "default_variant": e.default_variant,
                                "description": e.description, "tags": list(e.tags)}
                               for e in entries]})
        return EXIT_OK
    _emit(_table(["name", "variants", "description"],
                 [[e.name, ", ".join(e.variants), _first_sentence(e.description, 64)]
                  for e in entries], indent=""))
    _emit(f"\n{len(entries)} model(s). `mechatron show NAME` describes one.")
    return EXIT_OK


# -------------------------------------------------------------------------------- show
def _entry_dict(entry) -> dict[str, Any]:
    exp = entry.experiment
    return {
        "name": entry.name,
        "description": entry.description,
        "tags": list(entry.tags),
        "parameters": {k: {"default": p.default, "unit": p.unit, "description": p.doc,
                           "source": p.source} for k, p in entry.parameters.items()},
        "variants": list(entry.variants),
        "default_variant": entry.default_variant,
        "outputs": {label: {"unit": entry.output_units.get(label, ""),
                            "paths": {v: paths.get(label) for v, paths in
                                      entry.outputs.items()}}
                    for label in _labels(entry)},
        "experiment": {"t_stop": exp.t_stop, "solver": exp.solver, "rtol": exp.rtol,
                       "atol": exp.atol, "dt": exp.dt},
        "expected": dict(entry.expected),
        "expected_tolerance": entry.expected_tolerance,
    }


def _labels(entry) -> list[str]:
    """Output labels of every variant, in order of first appearance."""
    labels: dict[str, None] = {}
    for paths in entry.outputs.values():
        labels.update(dict.fromkeys(paths))
    return list(labels)


def cmd_show(args: argparse.Namespace) -> int:
    entry = entry_for(args.name)
    if args.json:
        _emit_json(_entry_dict(entry))
        return EXIT_OK
    exp = entry.experiment
    _emit(f"{entry.name}: {' '.join(entry.description.split())}")
    if entry.tags:
        _emit(f"tags: {', '.join(entry.tags)}")
    _emit("\nparameters (give them with `mechatron simulate "
          f"{entry.name} --set NAME=VALUE`, units optional):")
    _emit(_table(["name", "default", "unit", "description", "source"],
                 [[k, _num(p.default, 6), p.unit, p.doc, p.source]
                  for k, p in entry.parameters.items()], right="1"))
    _emit("\nvariants: " + ", ".join(v + (" (default)" if v == entry.default_variant else "")
                                     for v in entry.variants))
    _emit("\noutputs (instance path in each variant):")
    variants = list(entry.variants)
    _emit(_table(["label", "unit", *variants],
                 [[label, entry.output_units.get(label, ""),
                   *[entry.outputs.get(v, {}).get(label, "-") for v in variants]]
                  for label in _labels(entry)]))
    fixed = f", dt {exp.dt:g} s" if exp.dt is not None else ""
    _emit(f"\nexperiment: t_stop {exp.t_stop:g} s, solver {exp.solver}, rtol {exp.rtol:g}, "
          f"atol {exp.atol:g}{fixed}")
    if entry.expected:
        _emit(f"\nexpected values at t_stop (tolerance {entry.expected_tolerance:g}):")
        _emit(_table(["label", "value", "unit"],
                     [[label, _num(value), entry.output_units.get(label, "")]
                      for label, value in entry.expected.items()], right="1"))
    return EXIT_OK


# ---------------------------------------------------------------------------- simulate
def cmd_simulate(args: argparse.Namespace) -> int:
    entry = entry_for(args.name)
    params = _parse_sets(args.set, entry)
    variant = args.variant or entry.default_variant
    settings = _Settings.resolve(args, entry)
    out = _output_path(args.out, "--out", LOG_SUFFIXES)
    plot = _output_path(args.plot, "--plot", _figure_suffixes()) if args.plot else None

    inputs = _parse_inputs(args.input)
    model = entry.build(variant, **params)
    outputs = dict(entry.output_paths(variant))
    if not outputs:                 # a user's model that declares no variables: its states
        model = mt.compile_model(model)
        outputs = {name: name for name in model.state_names}
    res = mt.simulate(model, settings.t_stop, solver=settings.solver, dt=settings.dt,
                      rtol=settings.rtol, atol=settings.atol, inputs=inputs or None,
                      max_memory=None if args.force else MAX_MEMORY)
    final = {label: res.final(path) for label, path in outputs.items()}
    units = {label: entry.output_units.get(label, res.units.get(path, ""))
             for label, path in outputs.items()}
    # Reference values hold for the default experiment only.
    default_run = not params and not inputs and settings.t_stop == entry.experiment.t_stop
    expected = {k: v for k, v in entry.expected.items() if k in final} if default_run else {}

    files: dict[str, str] = {}
    if out is not None:
        files["out"] = str(res.save(out))
    if plot is not None:
        res.plot(*outputs.values(), path=plot)
        files["plot"] = str(plot)

    if args.json:
        _emit_json({"model": entry.name, "variant": variant, **settings.as_dict(),
                    "parameters": entry.values(**params), "set": params,
                    "inputs": list(args.input),
                    "outputs": outputs, "units": units, "final": final,
                    "expected": expected, "stats": res.stats.as_dict(), "files": files})
        return EXIT_OK

    changed = "".join(f", {k} = {v}" for k, v in params.items())
    changed += "".join(f", input {item}" for item in args.input)
    _emit(f"{entry.name} ({variant}{changed}): {settings.t_stop:g} s, "
          f"{settings.describe()}")
    _emit(f"\nfinal values at t = {res.t[-1]:g} s:")
    headers = ["label", "value", "unit", "path"]
    rows = [[label, _num(final[label]), units[label], path]
            for label, path in outputs.items()]
    if expected:
        headers += ["expected", "rel. error"]
        for row, label in zip(rows, outputs):
            ref = expected.get(label)
            row += ([_num(ref), f"{_relative(abs(final[label] - ref), abs(ref)):.1e}"]
                    if ref is not None else ["-", "-"])
    _emit(_table(headers, rows, right="145"))
    _emit("\nsolver profile:")
    _emit(_table(_PROFILE_HEADERS, _profile_rows({variant: res.stats}), right="2345678"))
    if files:
        _emit("")
    for kind, path in files.items():
        _emit(f"wrote {path} ({'simulation log' if kind == 'out' else 'plot'})")
    return EXIT_OK


# ----------------------------------------------------------------------------- compare
def cmd_compare(args: argparse.Namespace) -> int:
    entry = entry_for(args.name)
    params = _parse_sets(args.set, entry)
    settings = _Settings.resolve(args, entry)
    out = _output_path(args.out, "--out", _figure_suffixes()) if args.out else None
    with progress(args, total=len(entry.variants), desc="compare", unit="variant") as bar:
        cmp = compare_variants(entry, params=params, t_stop=settings.t_stop,
                               solver=settings.solver, dt=settings.dt, rtol=settings.rtol,
                               atol=settings.atol, points=COMPARE_POINTS,
                               progress=lambda done, total: bar.update(done - bar.n))
    variants, ref, labels = list(cmp.results), cmp.reference, cmp.labels

    files: dict[str, str] = {}
    if out is not None:
        save_figure(cmp.figure(), out, dpi=100)
        files["out"] = str(out)

    if args.json:
        _emit_json({"model": entry.name, "reference": ref, "variants": variants,
                    **settings.as_dict(), "points": COMPARE_POINTS, "set": params,
                    "deviations": cmp.deviations,
                    "missing": {k: v for k, v in cmp.missing.items() if v},
                    "final": cmp.final(),
                    "stats": {v: r.stats.as_dict() for v, r in cmp.results.items()},
                    "files": files})
        return EXIT_OK

    _emit(f"{entry.name}: {len(variants)} variant(s) over {settings.t_stop:g} s on "
          f"{COMPARE_POINTS} common output points ({settings.describe()})")
    if len(variants) < 2:
        _emit("only one variant: nothing to compare.")
    else:
        _emit(f"\nlargest deviation from the reference variant '{ref}' "
              f"(relative to the largest |value| of the reference):")
        rows = []
        for v in variants[1:]:
            for label in labels:
                d = cmp.deviations[v].get(label)
                unit = entry.output_units.get(label, "")
                rows.append([v, label, unit] + (["-", "-"] if d is None else
                            [f"{d['max_abs']:.3e}", f"{d['max_rel']:.3e}"]))
        _emit(_table(["variant", "label", "unit", "max abs dev", "max rel dev"], rows,
                     right="34"))
        for v, labels_missing in cmp.missing.items():
            if labels_missing:
                _emit(f"note: variant '{v}' has no output {', '.join(labels_missing)}.")
    _emit("\nsolver profile:")
    _emit(_table(_PROFILE_HEADERS,
                 _profile_rows({v: r.stats for v, r in cmp.results.items()}),
                 right="2345678"))
    for path in files.values():
        _emit(f"\nwrote {path} (overlay plot)")
    return EXIT_OK


# -------------------------------------------------------------------------- regression
def cmd_regression(args: argparse.Namespace) -> int:
    from mechatron.estimation.cli import _need_dask, _reach_scheduler
    from mechatron.models.regression import POINTS, run_regression
    if args.workers is not None and args.workers < 1:
        raise CommandError(f"--workers: at least 1, got {args.workers}.")
    names = [mt.models.get(n).name for n in args.names] if args.names else \
        [e.name for e in mt.models.list()]
    if args.dask:
        _need_dask("--dask")
        _reach_scheduler("--dask", args.dask)
    start = time.perf_counter()
    with progress(args, total=len(names), desc="regression", unit="model") as bar:
        rows = run_regression(names, workers=args.workers, address=args.dask,
                              progress=lambda done, total: bar.update(done - bar.n))
    wall = time.perf_counter() - start
    failed = [r["model"] for r in rows if not r["passed"]]
    where = f"the Dask cluster at {args.dask}" if args.dask else \
        ("this process" if args.workers == 1 else
         f"{args.workers or os.cpu_count() or 1} local process(es)")
    if args.json:
        _emit_json({"models": rows, "points": POINTS, "where": where, "wall_time_s": wall,
                    "passed": not failed, "failed": failed})
        return EXIT_FAILURE if failed else EXIT_OK
    _emit(f"{len(rows)} model(s) on {where}, {POINTS} output points each, in "
          f"{_duration(wall)}:")
    _emit(_table(["model", "variants", "expected: worst rel. err (limit)",
                  "variants: worst dev (limit)", "result"],
                 [[r["model"], ", ".join(r["variants"]) or "-",
                   "-" if r["error"] else
                   f"{r['expected_worst']:.1e} ({r['expected_tolerance']:g})",
                   "-" if r["error"] or len(r["variants"]) < 2 else
                   f"{r['variants_worst']:.1e} ({r['variant_tolerance']:g})",
                   "ok" if r["passed"] else
                   (f"ERROR {r['error']}" if r["error"] else "FAILED")]
                  for r in rows], right="23"))
    _emit(f"\n{len(rows) - len(failed)} of {len(rows)} passed"
          + (f"; failed: {', '.join(failed)}" if failed else "") + ".")
    return EXIT_FAILURE if failed else EXIT_OK


# -------------------------------------------------------------------------------- demo
@dataclass(frozen=True)
class DemoCheck:
    """A number the demo promises, with its limit."""

    what: str
    value: float
    limit: float

    @property
    def ok(self) -> bool:
        return bool(self.value <= self.limit)


@dataclass
class DemoRun:
    """What the demo steps share: settings, and what earlier steps produced."""

    out: Path
    say: Callable[[str], None] = _emit
    name: str = "dc_motor"
    variants: tuple[str, ...] = ("acausal", "ode")
    t_stop: float = 0.5
    rtol: float = 1e-10
    atol: float = 1e-12
    rk4_dt: float = 1e-5
    agreement_limit: float = 1e-8    # variants vs each other, relative to the peak
    analytic_limit: float = 1e-8     # final values vs the analytic steady state
    rk4_limit: float = 1e-4          # fixed-step vs variable-step, relative to the peak
    entry: Any = None
    models: dict[str, Any] = field(default_factory=dict)
    compiled: dict[str, Any] = field(default_factory=dict)
    compile_times: dict[str, float] = field(default_factory=dict)
    results: dict[str, SimResult] = field(default_factory=dict)
    fixed: SimResult | None = None
    checks: list[DemoCheck] = field(default_factory=list)
    files: list[Path] = field(default_factory=list)

    def check(self, what: str, value: float, limit: float) -> DemoCheck:
        c = DemoCheck(what, value, limit)
        self.checks.append(c)
        return c

    def grid(self) -> np.ndarray:
        """Output times: every RK4 step over the first 500 steps (the electrical transient
        lasts some 50 us), then 990 more points; all on RK4 steps."""
        fine = np.arange(500) * self.rk4_dt
        return np.concatenate([fine, np.linspace(500 * self.rk4_dt, self.t_stop, 991)])

    def path(self, variant: str, label: str) -> str:
        return self.entry.output_paths(variant)[label]


@dataclass(frozen=True)
class DemoStep:
    """One step of the demo: a title and a function of the shared :class:`DemoRun`."""

    title: str
    run: Callable[[DemoRun], None]


def _demo_build(d: DemoRun) -> None:
    d.entry = mt.models.get(d.name)
    values = d.entry.values()
    d.say("  parameters: " + ", ".join(f"{k} = {v:g} {d.entry.parameters[k].unit}"
                                        for k, v in values.items()))
    for v in d.variants:
        m = d.models[v] = d.entry.build(v)
        doc = (type(m).__doc__ or "").strip().splitlines()
        summary = doc[0].rstrip(".") if doc else type(m).__name__
        parts = m.components
        what = (f"{len(parts)} components ({', '.join(parts)})" if parts else
                "no components, equations only")
        d.say(f"  {v}: {summary}; {what}")


def _demo_compile(d: DemoRun) -> None:
    for v in d.variants:
        t0 = time.perf_counter()
        d.compiled[v] = cm = mt.compile_model(d.models[v])
        d.compile_times[v] = time.perf_counter() - t0
        d.say(f"  {v}: compiled in {_duration(d.compile_times[v])}")
        for line in _report_lines(cm.report):
            d.say(f"    {line}")


def _report_lines(report: dict) -> list[str]:
    """The compile report as text; tolerant of keys that a compiler version lacks."""
    var, eq = report.get("variables", {}), report.get("equations", {})
    lines = [f"equations/variables: {eq.get('flat', '?')}/{var.get('flat', '?')} flattened, "
             f"{eq.get('after_alias', '?')}/{var.get('after_alias', '?')} after alias "
             f"elimination ({report.get('aliases_eliminated', '?')} aliases), "
             f"{eq.get('after_index_reduction', '?')} after index reduction"]
    states = report.get("states", [])
    diff = report.get("differentiated_equations", [])
    lines.append(f"states ({len(states)}): {', '.join(states) or '-'}; "
                 f"{var.get('algebraic', 0)} algebraic; "
                 f"{len(diff)} equation(s) differentiated")
    lines.append(f"BLT: {report.get('blocks', '?')} blocks, largest "
                 f"{report.get('largest_block', '?')}, "
                 f"{report.get('tearing_variables', 0)} tearing variable(s), "
                 f"{report.get('relations', 0)} event relation(s)")
    timings = dict(report.get("timings", {}))
    total = timings.pop("total", None)
    if timings:
        lines.append("passes: " + ", ".join(f"{k} {_duration(s)}" for k, s in timings.items())
                     + (f"; total {_duration(total)}" if total is not None else ""))
    return lines


def _demo_simulate(d: DemoRun) -> None:
    grid = d.grid()
    for v in d.variants:
        res = d.results[v] = mt.simulate(d.compiled[v], d.t_stop, rtol=d.rtol, atol=d.atol,
                                         t_out=grid)
        res.stats.compile_time = d.compile_times[v]
        finals = ", ".join(f"{label} = {res.final(p):.12g} {d.entry.output_units[label]}"
                           for label, p in d.entry.output_paths(v).items())
        d.say(f"  {v}: {d.t_stop:g} s, rtol {d.rtol:g}, atol {d.atol:g} -> {finals}")


def _demo_agreement(d: DemoRun) -> None:
    ref, others = d.variants[0], d.variants[1:]
    for v in others:
        for label in ("w", "i"):
            dev, rel = _max_deviation(d.results[v][d.path(v, label)],
                                      d.results[ref][d.path(ref, label)])
            c = d.check(f"{v} vs {ref}: {label}", rel, d.agreement_limit)
            d.say(f"  {label}: max |{v} - {ref}| = {dev:.3e} {d.entry.output_units[label]}"
                  f", {rel:.3e} of the peak  [{'ok' if c.ok else 'FAILED'}, limit "
                  f"{c.limit:g}]")


def _demo_analytic(d: DemoRun) -> None:
    p = d.entry.values()
    den = p["R"] * p["B"] + p["k"] ** 2
    exact = {"w": p["k"] * p["V"] / den, "i": p["B"] * p["V"] / den}
    d.say(f"  steady state: w = k V / (R B + k^2) = {exact['w']:.12g} rad/s, "
          f"i = B V / (R B + k^2) = {exact['i']:.12g} A")
    for v in d.variants:
        for label in ("w", "i"):
            sim = d.results[v].final(d.path(v, label))
            rel = _relative(abs(sim - exact[label]), abs(exact[label]))
            c = d.check(f"{v}: final {label} vs analytic", rel, d.analytic_limit)
            d.say(f"  {v:8s} {label}({d.t_stop:g} s) = {sim:.12g}, relative error "
                  f"{rel:.1e}  [{'ok' if c.ok else 'FAILED'}]")


def _demo_profile(d: DemoRun) -> None:
    d.say(_table(_PROFILE_HEADERS, _profile_rows({v: d.results[v].stats
                                                  for v in d.variants}),
                 right="2345678"))


def _demo_speed(d: DemoRun) -> None:
    """The compiled Rosenbrock solver on the acausal motor (default tolerances, the demo's
    output grid): agreement with the tight CVODES run (checked) and its time beside CVODES
    and SciPy's LSODA on the hand-written ODE with the same tolerances and grid (printed,
    not checked: timings are not assertions)."""
    from scipy.integrate import solve_ivp

    from mechatron.solvers.native import compiler
    v = d.variants[0]
    cm = d.compiled[v]
    if compiler() is None:
        d.say("  skipped: no C compiler (cc, gcc or $CC) for solver='rodas4'")
        return
    ref = d.results[v]
    grid = ref.t

    def median_time(fn, n=21):
        times = []
        for _ in range(n):
            t0 = time.perf_counter()
            out = fn()
            times.append(time.perf_counter() - t0)
        return out, float(np.median(times))

    first = mt.simulate(cm, d.t_stop, solver="rodas4", t_out=grid)
    fast, t_rodas = median_time(lambda: mt.simulate(cm, d.t_stop, solver="rodas4",
                                                    t_out=grid))
    _, t_cvodes = median_time(lambda: mt.simulate(cm, d.t_stop, solver="cvodes",
                                                  t_out=grid))
    P = d.entry.values()
    A = np.array([[-P["R"] / P["L"], -P["k"] / P["L"]], [P["k"] / P["J"], -P["B"] / P["J"]]])
    b = np.array([P["V"] / P["L"], 0.0])
    _, t_lsoda = median_time(lambda: solve_ivp(lambda t, y: A @ y + b, (0.0, d.t_stop),
                                               np.zeros(2), method="LSODA", t_eval=grid,
                                               rtol=1e-6, atol=1e-8))
    d.say(f"  C library ready in {_duration(first.stats.compile_time or 0.0)} (built once, "
          "then loaded from the cache)")
    d.say(f"  one run: rodas4 {t_rodas * 1e3:.3f} ms, CVODES {t_cvodes * 1e3:.3f} ms, "
          f"SciPy LSODA {t_lsoda * 1e3:.3f} ms  (LSODA / rodas4 = "
          f"{t_lsoda / t_rodas:.0f}x; timings vary with the machine)")
    for label in ("w", "i"):
        path = d.path(v, label)
        dev, rel = _max_deviation(fast[path], ref[path])
        c = d.check(f"rodas4 vs CVODES: {label}", rel, 1e-5)
        d.say(f"  {label}: max |rodas4 (rtol 1e-6) - tight CVODES| = {dev:.3e} "
              f"{d.entry.output_units[label]}, {rel:.3e} of the peak  "
              f"[{'ok' if c.ok else 'FAILED'}, limit {c.limit:g}]")


def _demo_fixed_step(d: DemoRun) -> None:
    v = d.variants[0]
    d.fixed = fixed = mt.simulate(d.compiled[v], d.t_stop, solver="rk4", dt=d.rk4_dt)
    st = fixed.stats
    d.say(f"  {v}: RK4, dt {d.rk4_dt:g} s: {st.steps:,} steps, {st.rhs_evals:,} rhs evals "
          f"in {_duration(st.wall_time)} ({st.wall_time / max(st.steps, 1) * 1e6:.2f} us "
          f"per step, including setup)")
    ref = d.results[v]
    for label in ("w", "i"):
        path = d.path(v, label)
        dev, rel = _max_deviation(fixed.at(ref.t, path), ref[path])
        c = d.check(f"RK4 vs variable-step: {label}", rel, d.rk4_limit)
        d.say(f"  {label}: max |RK4 - variable-step| = {dev:.3e} "
              f"{d.entry.output_units[label]}, {rel:.3e} of the peak  "
              f"[{'ok' if c.ok else 'FAILED'}, limit {c.limit:g}]")


def _demo_files(d: DemoRun) -> None:
    d.out.mkdir(parents=True, exist_ok=True)
    for v in d.variants:
        d.files.append(d.results[v].save(d.out / f"{d.name}_{v}.csv"))
    v = d.variants[0]
    ref = d.results[v]
    response = d.out / f"{d.name}_response.png"
    ref.plot(*d.entry.output_paths(v).values(), path=response)
    d.files.append(response)
    d.files.append(_demo_startup_plot(d))
    for f in d.files:
        d.say(f"  wrote {f}")


def _demo_startup_plot(d: DemoRun) -> Path:
    """First 5 ms of both variants and RK4, and the RK4 deviation over the whole run."""
    fig, axes = _new_figure(3, sharex=False)
    window = 5e-3
    for axis, label in zip(axes, ("w", "i")):
        for k, v in enumerate(d.variants):
            res = d.results[v]
            keep = res.t <= window
            axis.plot(res.t[keep] * 1e3, res[d.path(v, label)][keep], ["-", "--"][k % 2],
                      label=f"{v}, variable-step")
        if d.fixed is not None:
            v = d.variants[0]
            keep = d.fixed.t <= window
            axis.plot(d.fixed.t[keep][::20] * 1e3, d.fixed[d.path(v, label)][keep][::20],
                      ".", markersize=3, label=f"{v}, RK4 dt {d.rk4_dt:g} s")
        axis.set_ylabel(f"{label} {_unit_label(d.entry.output_units[label])}")
        axis.set_xlabel("t [ms]")
        axis.grid(True, alpha=0.3)
        axis.legend(loc="best", fontsize="small")
    axis = axes[2]
    if d.fixed is not None:
        v = d.variants[0]
        ref = d.results[v]
        for label in ("w", "i"):
            path = d.path(v, label)
            err = np.abs(d.fixed.at(ref.t, path) - ref[path]) / np.max(np.abs(ref[path]))
            axis.semilogy(ref.t, np.maximum(err, 1e-17), label=label)
        axis.legend(loc="best", fontsize="small")
    axis.set_ylabel("|RK4 - variable-step| / peak [1]")
    axis.set_xlabel("t [s]")
    axis.grid(True, alpha=0.3)
    fig.suptitle(f"{d.name}: start-up, acausal vs ODE vs fixed-step RK4")
    path = d.out / f"{d.name}_startup.png"
    save_figure(fig, path, dpi=100)
    return path


def _demo_database(d: DemoRun) -> None:
    """Every database model: its default experiment against its expected values, and its
    variants against each other (the rows of ``mechatron regression``, run here)."""
    from mechatron.models.regression import run_regression
    rows = []
    for r in run_regression(workers=1):
        if r["error"]:
            d.check(f"{r['model']}: runs", math.inf, 0.0)
            rows.append([r["model"], "-", "-", "-", r["error"]])
            continue
        d.check(f"{r['model']}: expected values", r["expected_worst"],
                r["expected_tolerance"])
        several = len(r["variants"]) > 1
        if several:
            d.check(f"{r['model']}: variants agree", r["variants_worst"],
                    r["variant_tolerance"])
        rows.append([r["model"], ", ".join(r["variants"]), f"{r['expected_worst']:.1e}",
                     f"{r['variants_worst']:.1e}" if several else "-",
                     _duration(r["wall_time_s"])])
    d.say(_table(["model", "variants", "expected: worst rel. err", "variants: worst dev",
                  "simulated in"], rows, right="234"))


def _demo_report(d: DemoRun) -> None:
    from mechatron.report.diagram import write_diagram
    from mechatron.report.html import write_report
    import shutil
    d.out.mkdir(parents=True, exist_ok=True)
    if shutil.which("dot") is None:
        d.say("  Graphviz is not installed: skipping the diagram (run `make demo` as root "
              "to install it)")
    else:
        d.files.append(write_diagram(d.entry.build("acausal"), d.out / f"{d.name}.svg",
                                     d.name))
        d.say(f"  wrote {d.files[-1]} (the network, domain-coloured)")
    d.files.append(write_report(d.entry, d.out / f"{d.name}_report.html"))
    d.say(f"  wrote {d.files[-1]} (description, diagram, parameters, plots, variants, "
          "solver profile)")


def _demo_codegen(d: DemoRun) -> None:
    """The DC motor's RK4 step as standalone C and as an FMI 2.0 co-simulation FMU."""
    from mechatron.codegen import demo_run
    r = demo_run(d.out / "codegen")
    c = d.check("generated C vs desktop RK4 (every variable)", r["max_rel_difference"],
                1e-12)
    d.say(f"  C99 in {r['c_dir']}: {r['steps']:,} RK4 steps at 10 kHz, max relative "
          f"difference to the desktop run {r['max_rel_difference']:.1e} "
          f"[{'ok' if c.ok else 'FAILED'}, limit 1e-12]")
    d.say(f"  {r['ns_per_step']:.0f} ns per step ({r['operations']} operations); final "
          f"speed {r['final_w']:.6f} rad/s, analytic {r['analytic_w']:.6f}")
    fmu = r.get("fmu_check") or {}
    if r.get("fmu") and fmu.get("fmpy"):
        d.check("FMU: FMPy validation problems", float(len(fmu["validation_problems"])), 0)
        c = d.check("FMU in FMPy vs desktop", fmu["max_rel_difference_to_desktop"], 1e-6)
        d.say(f"  FMU {r['fmu']}: FMPy validation {len(fmu['validation_problems'])} "
              f"problem(s); FMPy run vs desktop {fmu['max_rel_difference_to_desktop']:.1e} "
              f"[{'ok' if c.ok else 'FAILED'}, limit 1e-6]")
    elif r.get("fmu"):
        d.say(f"  FMU {r['fmu']} (FMPy not installed: not checked)")
    else:
        d.say(f"  no FMU: {fmu.get('error', 'not built')}")
    d.files += [Path(p) for p in (r["csv"], r.get("fmu")) if p]


def _demo_estimation(d: DemoRun) -> None:
    """The seed's chapter 6 on a virtual test bench whose hidden truth is table 6-1."""
    from mechatron.estimation import demo_run
    r = demo_run(d.out / "estimation")
    cls = r["classic"]["errors_pct"]
    d.say("  classic tests (locked rotor, steps, free run): "
          + ", ".join(f"{n} {cls[n]:+.2f}%" for n in ("R", "L", "k", "J", "B")))
    sens = r["sensitivity"]
    d.say(f"  sensitivity: {sens['simulations']} simulations "
          f"({sens['simulations_per_s']:.0f}/s), ranking {', '.join(sens['ranking'])}")
    est = r["estimation"]
    d.say(f"  estimation from the best sample, two experiments ({est['wall_s']:.2f} s, "
          f"{est['iterations']} iterations):")
    d.say(_table(["parameter", "truth", "estimate", "error", "95% interval"],
                 [[n, _num(r["truth"][n], 5), _num(v, 6), f"{est['errors_pct'][n]:+.3f}%",
                   f"[{_num(est['ci95'][n][0], 5)}, {_num(est['ci95'][n][1], 5)}]"]
                  for n, v in est["values"].items()], right="123"))
    opt = r["optimization"]
    d.say(f"  speed PI optimized in {opt['iterations']} iterations: "
          + ", ".join(f"{k} {v:.4g}" for k, v in opt["optimized"].items()))
    for row in opt["requirements"]:
        d.say(f"    {row['requirement']}: {row['start']:.4g} -> {row['optimized']:.4g} "
              f"(limit {row['limit']}) {'met' if row['met'] else 'NOT met'}")
    for what, ok in r["checks"].items():
        d.check(f"chapter 6: {what}", 0.0 if ok else 1.0, 0.0)
        d.say(f"  [{'ok' if ok else 'FAILED'}] {what}")
    d.files += [Path(f) for f in r["files"]]


#: The showcase, in order. Later features append or insert their own steps.
DEMO_STEPS: list[DemoStep] = [
    DemoStep("Build the DC motor both ways: acausal network and hand-written ODEs",
             _demo_build),
    DemoStep("Compile: flatten, alias elimination, index reduction, BLT, lowering",
             _demo_compile),
    DemoStep("Simulate with CVODES at tight tolerance", _demo_simulate),
    DemoStep("Agreement of the two variants", _demo_agreement),
    DemoStep("Analytic steady state versus simulation", _demo_analytic),
    DemoStep("Solver profile", _demo_profile),
    DemoStep("Speed: the model and a Rosenbrock solver compiled to C (solver='rodas4')",
             _demo_speed),
    DemoStep("Fixed-step RK4 (the step function of code generation and HIL)",
             _demo_fixed_step),
    DemoStep("Plots and simulation logs", _demo_files),
    DemoStep("The model database: expected values and variants compared", _demo_database),
    DemoStep("Diagram and HTML report of the DC motor", _demo_report),
    DemoStep("Chapter 6 on a virtual bench: classic tests, sensitivity, estimation, "
             "PI optimization", _demo_estimation),
    DemoStep("C code and FMU of the DC motor (fixed-step RK4 at 10 kHz)", _demo_codegen),
]


def cmd_demo(args: argparse.Namespace) -> int:
    out = Path(args.out)
    if out.exists() and not out.is_dir():
        raise CommandError(f"--out {out}: exists and is not a directory; give a directory "
                           f"for the demo's plots and logs.")
    out.mkdir(parents=True, exist_ok=True)  # fail now, not after the simulations
    d = DemoRun(out=out)
    start = time.perf_counter()
    _emit(f"Mechatron {mt.__version__} demo")
    for k, step in enumerate(DEMO_STEPS, 1):
        _emit(f"\n[{k}/{len(DEMO_STEPS)}] {step.title}")
        t0 = time.perf_counter()
        step.run(d)
        _emit(f"  ({_duration(time.perf_counter() - t0)})")
    failed = [c for c in d.checks if not c.ok]
    _emit(f"\ndemo finished in {_duration(time.perf_counter() - start)}: "
          f"{len(d.checks) - len(failed)} of {len(d.checks)} checks passed; "
          f"{len(d.files)} files in {d.out}")
    for c in failed:
        _emit(f"FAILED: {c.what}: {c.value:.3e} > {c.limit:g}")
    return EXIT_FAILURE if failed else EXIT_OK


# ------------------------------------------------------------------------------ parser
#: Modules that add subcommands: each defines ``add_commands(sub)`` (``sub`` is the
#: ``argparse`` sub-parsers object); a module that does not exist yet is skipped.
EXTENSIONS = (
    "mechatron.library.cli",
    "mechatron.report.cli",
    "mechatron.estimation.cli",
    "mechatron.codegen.cli",
    "mechatron.realtime.cli",
    "mechatron.analysis.cli",
    "mechatron.explore.cli",
)


def _add_extensions(sub) -> None:
    import importlib
    for name in EXTENSIONS:
        try:
            module = importlib.import_module(name)
        except ModuleNotFoundError as exc:
            if exc.name is not None and name.startswith(exc.name):
                continue          # that extension is not part of this installation
            raise
        module.add_commands(sub)


def _add_json(p: argparse.ArgumentParser) -> None:
    p.add_argument("--json", action="store_true",
                   help="print one JSON object on stdout instead of the summary")


def _add_set(p: argparse.ArgumentParser) -> None:
    p.add_argument("--set", action="append", default=[], metavar="P=VALUE",
                   help="set model parameter P (by its name in `mechatron show`); a plain "
                        "number is SI, or give a unit: --set \"L=340 uH\". Repeatable.")


def _add_verbose(p: argparse.ArgumentParser, dest: str) -> None:
    p.add_argument("-v", "--verbose", action="count", default=0, dest=dest,
                   help="show what Mechatron does on stderr (-v: progress and files, "
                        "-vv: details); warnings are always shown")


class _Parser(argparse.ArgumentParser):
    """argparse with a usage error reported as one line, like every other error."""

    def error(self, message: str):
        self.exit(EXIT_USAGE, f"error: {self.prog}: {_one_line(message)}; see "
                              f"`{self.prog} --help`.\n")


def _add_quiet(p: argparse.ArgumentParser) -> None:
    names = [n for n in ("-q", "--quiet") if n not in p._option_string_actions]
    if names:
        p.add_argument(*names, action="store_true", dest="quiet",
                       help="no progress bars on stderr (they show only on a terminal, "
                            "for runs over 2 s)")


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of the ``mechatron`` command."""
    parser = _Parser(
        prog="mechatron",
        description="Acausal modeling and simulation of mechatronic systems.",
        epilog="Errors are reported as one line on stderr (exit code 2 for bad input); "
               "set MECHATRON_DEBUG=1 for tracebacks.")
    parser.add_argument("--version", action="version", version=f"%(prog)s {mt.__version__}")
    _add_verbose(parser, "verbose")
    parser.add_argument("-q", "--quiet", action="store_true", dest="quiet_global",
                        help="no progress bars on stderr")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)

    p = sub.add_parser("models", help="list the model database",
                       description="List the models of the database: name, variants and a "
                                   "one-line description.")
    p.add_argument("--tag", metavar="T", help="only models with tag T (e.g. motor)")
    _add_json(p)
    p.set_defaults(func=cmd_models)

    p = sub.add_parser("show", help="describe one model",
                       description="Describe one model: parameters with units, defaults "
                                   "and sources; variants; outputs; experiment; expected "
                                   "values.")
    p.add_argument("name", metavar="NAME", help=MODEL_HELP)
    _add_json(p)
    p.set_defaults(func=cmd_show)

    p = sub.add_parser("simulate", help="simulate one model",
                       description="Build, compile and simulate one variant of a model; "
                                   "print the final value of each output and the solver "
                                   "profile. Defaults come from the model's experiment.")
    p.add_argument("name", metavar="NAME", help=MODEL_HELP)
    p.add_argument("--variant", metavar="V", help="variant to build (default: the first)")
    p.add_argument("--t-stop", type=float, metavar="T", help="end time in s")
    _add_set(p)
    p.add_argument("--solver", metavar="S",
                   help="one of " + ", ".join(SOLVERS) + "; the fixed-step ones ("
                        + ", ".join(FIXED_STEP_METHODS) + ") need --dt "
                        "(default: the model's experiment)")
    p.add_argument("--dt", type=float, metavar="H", help="step of a fixed-step solver, in s")
    p.add_argument("--force", action="store_true",
                   help="run a fixed-step simulation even when its step count or memory "
                        "estimate is above the limit")
    p.add_argument("--rtol", type=float, metavar="R", help="relative tolerance")
    p.add_argument("--atol", type=float, metavar="A", help="absolute tolerance")
    p.add_argument("--input", action="append", default=[], metavar="U=VALUE|FILE.csv",
                   help="drive external input U of the model: a constant (--input u=3.5, "
                        "--input \"u=3.5 V\") or a CSV table with columns t and a value "
                        "(piecewise linear, held outside its range). Repeatable.")
    p.add_argument("--out", metavar="FILE",
                   help="write the whole simulation log (.csv: columns t, then instance "
                        "paths; or .parquet)")
    p.add_argument("--plot", metavar="FILE.png", help="write a plot of the outputs")
    _add_json(p)
    p.set_defaults(func=cmd_simulate)

    p = sub.add_parser("compare", help="compare all variants of a model",
                       description="Simulate every variant of a model on the same "
                                   f"{COMPARE_POINTS}-point output grid with the "
                                   "experiment's solver and tolerances, and print the "
                                   "largest deviation of each output from the first "
                                   "variant.")
    p.add_argument("name", metavar="NAME", help=MODEL_HELP)
    p.add_argument("--t-stop", type=float, metavar="T", help="end time in s")
    _add_set(p)
    p.add_argument("--out", metavar="FILE.png", help="write an overlay plot")
    _add_json(p)
    p.set_defaults(func=cmd_compare)

    p = sub.add_parser("regression", help="check every database model against its "
                                          "expected values",
                       description="Regression run of the model database: each model's "
                                   "default experiment against its expected values and "
                                   "its variants against each other, one task per model "
                                   "on local processes or a Dask cluster. Exit code 1 if "
                                   "a model fails.")
    p.add_argument("names", nargs="*", metavar="NAME",
                   help="models to check (default: the whole database)")
    p.add_argument("--workers", type=int, metavar="N",
                   help="local worker processes (default: one per CPU; 1: in this process)")
    p.add_argument("--dask", metavar="ADDRESS",
                   help="run the models on the Dask cluster at ADDRESS (needs "
                        "dask.distributed)")
    _add_json(p)
    p.set_defaults(func=cmd_regression)

    p = sub.add_parser("demo", help="the showcase, end to end",
                       description="Build the DC motor as an acausal network and as ODEs, "
                                   "compile, simulate, check against the analytic steady "
                                   "state and a fixed-step RK4 run, and write plots and "
                                   "logs.")
    p.add_argument("--out", metavar="DIR", default="demo_output",
                   help="directory for plots and logs (default: %(default)s)")
    p.set_defaults(func=cmd_demo)
    _add_extensions(sub)
    for command in sub.choices.values():       # `mechatron simulate ... -v` works too
        _add_verbose(command, "verbose_command")
        _add_quiet(command)
    return parser


#: Seconds a run must last before its progress bar appears.
PROGRESS_DELAY = 2.0


def progress(args: argparse.Namespace | None = None, *, total: int | None = None,
             desc: str = "", unit: str = "it"):
    """A progress bar (tqdm) on stderr for a run of ``total`` items: it appears only when
    the run lasts over :data:`PROGRESS_DELAY` s, stderr is a terminal and ``-q`` was not
    given; otherwise its methods do nothing. Use it as a context manager."""
    from tqdm import tqdm
    quiet = args is not None and (getattr(args, "quiet", False)
                                  or getattr(args, "quiet_global", False))
    try:
        tty = sys.stderr.isatty()
    except (AttributeError, ValueError):
        tty = False
    return tqdm(total=total, desc=desc, unit=unit, file=sys.stderr, delay=PROGRESS_DELAY,
                disable=quiet or not tty, leave=False, dynamic_ncols=True,
                mininterval=0.2)


#: Helpers for the extension modules of :data:`EXTENSIONS`.
emit = _emit
emit_json = _emit_json
jsonable = _jsonable
table = _table
add_json = _add_json
add_set = _add_set
duration = _duration
num = _num
output_path = _output_path
new_figure = _new_figure
parse_sets = _parse_sets


# -------------------------------------------------------------------------------- main
def _debug() -> bool:
    return os.environ.get("MECHATRON_DEBUG", "").strip() not in ("", "0")


class _StderrHandler(logging.Handler):
    """Records of the ``mechatron`` logger as lines on the current ``sys.stderr`` (looked
    up at each record, so that redirections apply): ``warning: ...``, ``debug: ...``;
    info records as they are."""

    def emit(self, record: logging.LogRecord) -> None:
        try:
            text = record.getMessage()
            if record.levelno != logging.INFO:
                text = f"{record.levelname.lower()}: {text}"
            print(text, file=sys.stderr, flush=True)
        except Exception:  # logging must never break the command
            self.handleError(record)


def _logging(verbosity: int) -> Callable[[], None]:
    """Show the ``mechatron`` logger's records on stderr: warnings always, info with
    ``-v``, debug with ``-vv``. Returns the function that undoes it."""
    logger = logging.getLogger("mechatron")
    level = (logging.WARNING, logging.INFO)[verbosity] if verbosity < 2 else logging.DEBUG
    handler = _StderrHandler(level)
    before = logger.level
    logger.setLevel(level)
    logger.addHandler(handler)

    def undo() -> None:
        logger.removeHandler(handler)
        logger.setLevel(before)
    return undo


def _fail(message: str, code: int) -> int:
    if _debug():
        traceback.print_exc()
    print(f"error: {_one_line(message)}", file=sys.stderr)
    return code


class Terminated(KeyboardInterrupt):
    """SIGTERM (``kill``, ``timeout``) during a command: unwound like Ctrl-C, so that
    every ``finally`` runs (temporary build folders removed, child processes stopped,
    no partial file), and the command exits with 143."""


def _on_sigterm(signum, frame) -> None:
    if getattr(_on_sigterm, "fired", False):
        return                       # a second SIGTERM (timeout also signals the group)
    _on_sigterm.fired = True         # must not cut the cleanup short
    raise Terminated()


def _catch_sigterm() -> Callable[[], None]:
    """Install :func:`_on_sigterm` for the command's run (main thread only); returns the
    function that puts the previous handler back."""
    if threading.current_thread() is not threading.main_thread():
        return lambda: None
    before = signal.getsignal(signal.SIGTERM)
    _on_sigterm.fired = False
    signal.signal(signal.SIGTERM, _on_sigterm)

    def undo() -> None:
        signal.signal(signal.SIGTERM, before if before is not None else signal.SIG_DFL)
    return undo


def _interrupt_within(exc: BaseException) -> KeyboardInterrupt | None:
    """The Ctrl-C or SIGTERM behind ``exc``, if any: a signal that arrives while a C
    extension runs (CasADi converting a matrix) surfaces as a ``SystemError`` whose
    context is the interrupt, after the same clean-up."""
    seen = set()
    while exc is not None and id(exc) not in seen:
        if isinstance(exc, KeyboardInterrupt):
            return exc
        seen.add(id(exc))
        exc = exc.__cause__ or exc.__context__
    return None


def _stopped(stop: KeyboardInterrupt) -> int:
    """The message and exit code of an interrupted command: 143 for SIGTERM, 130 for
    Ctrl-C (the clean-up has run)."""
    if isinstance(stop, Terminated):
        print("error: terminated (SIGTERM); temporary files removed.", file=sys.stderr)
        return 143
    print("error: interrupted.", file=sys.stderr)
    return 130


def main(argv: Sequence[str] | None = None) -> int:
    """Run the ``mechatron`` command with ``argv`` (default: ``sys.argv[1:]``).

    Returns the exit code: 0 on success, 2 for bad arguments or input, 1 otherwise;
    130 after Ctrl-C and 143 after SIGTERM, both after the same clean-up.
    """
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
    except SystemExit as exc:  # --help, --version, or a usage error (already printed)
        return exc.code if isinstance(exc.code, int) else EXIT_USAGE
    undo_logging = _logging(getattr(args, "verbose", 0)
                            + getattr(args, "verbose_command", 0))
    undo_sigterm = _catch_sigterm()
    try:
        return int(args.func(args) or EXIT_OK)
    except KeyboardInterrupt as exc:        # Ctrl-C, or SIGTERM (`Terminated`)
        return _stopped(exc)
    except BrokenPipeError:  # e.g. `mechatron models | head -1`
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        return EXIT_OK
    except USER_ERRORS as exc:
        return _fail(str(exc), EXIT_USAGE)
    except Exception as exc:  # a bug: still one line, the traceback on request
        stop = _interrupt_within(exc)
        if stop is not None:
            return _stopped(stop)
        return _fail(f"unexpected {type(exc).__name__}: {exc} (a bug in Mechatron; "
                     f"run with MECHATRON_DEBUG=1 for the traceback and report it)",
                     EXIT_FAILURE)
    finally:
        undo_sigterm()
        undo_logging()


if __name__ == "__main__":
    sys.exit(main())
