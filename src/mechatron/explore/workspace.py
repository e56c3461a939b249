"""What the explorer holds between requests: the runs (simulation logs and loaded files),
the compiled models (kept, so that a parameter change re-simulates without recompiling),
and the answers of the database and library browsers. No HTTP here: the server
(:mod:`mechatron.explore.server`) turns requests into calls of :class:`Workspace` and its
answers (plain dicts, lists, bytes) into JSON or files.
"""

from __future__ import annotations

import inspect
import itertools
import shutil
import subprocess
import tempfile
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

import mechatron as mt
from mechatron.errors import DataError, ModelError, ParameterError
from mechatron.explore.decimate import decimate, window
from mechatron.results import SimResult

__all__ = ["Workspace", "Run", "event_times", "MAX_WIDTH"]

#: Widest plot the signal endpoint serves, in pixels (a 4K screen).
MAX_WIDTH = 4096
#: Most runs kept, and most bytes of logged values; beyond either the oldest run goes.
MAX_RUNS = 50
MAX_BYTES = 2 * 1024 ** 3


@dataclass
class Run:
    """One log in the explorer: a simulation made here, or a file loaded."""

    id: str
    label: str
    result: SimResult
    kind: str                                   # "simulation" or "file"
    model: str = ""
    variant: str = ""
    params: dict[str, float] = field(default_factory=dict)   # changed ones, SI, by path
    events: list[float] = field(default_factory=list)
    seconds: float | None = None                # wall time of the simulation

    def summary(self) -> dict:
        res = self.result
        return {"id": self.id, "label": self.label, "kind": self.kind, "model": self.model,
                "variant": self.variant, "params": self.params, "events": self.events,
                "n_vars": len(res.names), "n_t": int(res.t.size),
                "t0": float(res.t[0]), "t1": float(res.t[-1]), "seconds": self.seconds}


def event_times(res: SimResult) -> list[float]:
    """Times of the events of a log: a repeated output time (the values before and after
    the event), and each component's last event as the solver reported it."""
    t = res.t
    repeated = t[1:][t[1:] == t[:-1]]
    times = set(np.unique(repeated).tolist()) | set(res.event_times.values())
    return sorted(float(x) for x in times)


class Workspace:
    """The explorer's state; every public method is safe to call from several threads."""

    def __init__(self) -> None:
        self._lock = threading.RLock()
        self._runs: dict[str, Run] = {}
        self._ids = itertools.count(1)
        # (model, variant) -> (entry, compiled model); each compiled once
        self._compiled: dict[tuple[str, str], tuple[object, object]] = {}
        self._compile_locks: dict[tuple[str, str], threading.Lock] = {}
        self._library: list[dict] | None = None
        self._entries: dict[str, object] = {}    # added entries and users' model files
        self._studies: dict[str, object] = {}    # estimation, sensitivity, optimization

    def add_entry(self, entry) -> None:
        """Offer a :class:`~mechatron.models.entry.ModelEntry` that is not in the database
        (a script's own model) under its name."""
        with self._lock:
            self._entries[entry.name] = entry

    def _entry(self, name: str):
        """The entry ``name``: one added here, a database name, or a user's model file
        ``path/to/model.py[:Class]`` (a :class:`ModelError` naming close names if none)."""
        with self._lock:
            if name in self._entries:
                return self._entries[name]
        from mechatron.models.user import component_class, entry_from_class
        cls = component_class(name)
        if cls is None:
            return mt.models.get(name)
        entry = entry_from_class(cls, name=name, source=name)
        with self._lock:
            return self._entries.setdefault(name, entry)   # a file is read once

    # ------------------------------------------------------------------ database
    def models(self) -> list[dict]:
        """The database: name, description, variants, tags of each model."""
        with self._lock:
            extra = list(self._entries.values())
        known = {e.name for e in extra}
        return [{"name": e.name, "description": " ".join(e.description.split()),
                 "variants": list(e.variants), "tags": list(e.tags)}
                for e in extra + [e for e in mt.models.list() if e.name not in known]]

    def model(self, name: str) -> dict:
        """One entry: description, parameters with units and provenance, variants,
        outputs, experiment, expected values, and the parts of its default variant with
        their classes' documentation."""
        entry = self._entry(name)
        exp = entry.experiment
        labels = list(dict.fromkeys(k for paths in entry.outputs.values() for k in paths))
        return {
            "name": entry.name,
            "description": " ".join(entry.description.split()),
            "tags": list(entry.tags),
            "parameters": [{"name": k, "default": p.default, "unit": p.unit,
                            "description": p.doc, "source": p.source}
                           for k, p in entry.parameters.items()],
            "variants": list(entry.variants),
            "default_variant": entry.default_variant,
            "outputs": [{"label": label, "unit": entry.output_units.get(label, ""),
                         "paths": {v: paths.get(label) for v, paths in entry.outputs.items()}}
                        for label in labels],
            "experiment": {"t_stop": exp.t_stop, "solver": exp.solver, "rtol": exp.rtol,
                           "atol": exp.atol, "dt": exp.dt},
            "expected": dict(entry.expected),
        }

    def parts(self, name: str, variant: str | None = None) -> list[dict]:
        """The top-level parts of one variant: path, class, documentation."""
        entry = self._entry(name)
        model = entry.build(variant or entry.default_variant)
        out = []
        for path, part in model.components.items():
            cls = type(part)
            out.append({"path": path, "class": cls.__name__,
                        "module": cls.__module__,
                        "doc": inspect.cleandoc(cls.__doc__ or "")})
        return out

    def diagram(self, name: str, variant: str | None = None) -> str:
        """The domain-coloured schematic of one variant, as SVG text."""
        from mechatron.report.diagram import DOT_HINT, diagram_dot
        entry = self._entry(name)
        variant = variant or entry.default_variant
        source = diagram_dot(entry.build(variant), f"{entry.name} ({variant})")
        dot = shutil.which("dot")
        if dot is None:
            raise FileNotFoundError(DOT_HINT)
        run = subprocess.run([dot, "-Tsvg"], input=source, capture_output=True, text=True,
                             timeout=60)
        if run.returncode != 0:
            raise ModelError(f"model '{name}': Graphviz failed to draw the diagram: "
                             f"{run.stderr.strip()}", path=name)
        svg = run.stdout
        return svg[svg.find("<svg"):]             # drop the XML prolog and doctype

    def library(self) -> list[dict]:
        """The component library by section (walked once)."""
        with self._lock:
            if self._library is None:
                from mechatron.library.catalog import sections
                found = sections()
                self._library = [s.as_dict() for s in found]
                for s, sec in zip(self._library, found):
                    for c, info in zip(s["components"], sec.components):
                        c["doc"] = inspect.cleandoc(info.cls.__doc__ or "")
            return self._library

    # ------------------------------------------------------------------ runs
    def compiled(self, name: str, variant: str | None = None):
        """``(entry, compiled model)`` of one variant, compiled on first use only."""
        entry = self._entry(name)
        variant = variant or entry.default_variant
        if variant not in entry.variants:
            raise ModelError(f"model '{name}': no variant '{variant}'. Variants: "
                             f"{', '.join(entry.variants)}.", path=name)
        key = (entry.name, variant)
        with self._model_lock(key):
            if key not in self._compiled:
                self._compiled[key] = (entry, mt.compile_model(entry.build(variant)))
        return self._compiled[key]

    def _model_lock(self, key: tuple[str, str]) -> threading.Lock:
        """The lock of one compiled model: it is compiled once, and simulated by one
        request at a time (its functions and caches are shared)."""
        with self._lock:
            return self._compile_locks.setdefault(key, threading.Lock())

    def parameters(self, name: str, variant: str | None = None) -> list[dict]:
        """The compiled model's parameters, which a live change may set: instance path,
        SI unit, default value."""
        _, cm = self.compiled(name, variant)
        return [{"path": p, "unit": u, "default": float(v)}
                for p, u, v in zip(cm.param_names, cm.param_units, cm.p0)]

    def simulate(self, name: str, variant: str | None = None, params: dict | None = None,
                 t_stop: float | None = None, label: str | None = None,
                 replace: str | None = None) -> Run:
        """Simulate one variant with parameters changed by instance path (numbers in SI
        or quantity strings such as ``"400 uH"``); the model is compiled once and kept.
        ``replace`` names a run whose place (id) the new log takes."""
        entry, cm = self.compiled(name, variant)
        variant = variant or entry.default_variant
        params = {str(k): v for k, v in (params or {}).items() if str(v).strip() != ""}
        p = cm.parameter_vector(params)          # checks names, units, bounds
        index = {n: i for i, n in enumerate(cm.param_names)}
        changed = {k: float(p[index[k]]) for k in params}
        exp = entry.experiment
        stop = exp.t_stop if t_stop is None else float(t_stop)
        if not np.isfinite(stop) or stop <= 0:
            raise ParameterError(f"model '{name}': the stop time must be a positive number "
                                 f"of seconds, got {t_stop!r}.", path=name)
        with self._model_lock((entry.name, variant)):
            start = time.perf_counter()
            res = mt.simulate(cm, stop, solver=exp.solver, dt=exp.dt, rtol=exp.rtol,
                              atol=exp.atol, params=changed)
            seconds = time.perf_counter() - start
        if label is None:
            label = f"{entry.name} ({variant})" + "".join(
                f", {k}={v:g}" for k, v in changed.items())
        with self._lock:
            if replace is not None:
                self.run(replace)                # must exist
                run_id = replace
            else:
                run_id = f"r{next(self._ids)}"
            run = Run(run_id, label, res, "simulation", entry.name, variant, changed,
                      event_times(res), seconds)
            self._runs[run_id] = run
            self._trim()
        return run

    def load(self, path, label: str | None = None) -> Run:
        """Load a simlog (``.csv`` or ``.parquet``, first column ``t``) as a run."""
        path = Path(path)
        if not path.exists():
            raise FileNotFoundError(f"{path}: no such file. A relative path starts in the "
                                    f"folder the explorer was started from, {Path.cwd()}.")
        if path.is_dir():
            raise DataError(f"{path}: is a folder, not a simlog. Give a .csv or .parquet "
                            "file whose first column is t.", path=str(path))
        try:
            res = SimResult.load(path)
        except (DataError, OSError):
            raise
        except Exception as exc:  # noqa: BLE001 - e.g. pyarrow on a file that is not Parquet
            raise DataError(f"{path}: not a simlog ({type(exc).__name__}: {exc}). Give a "
                            ".csv or .parquet file whose first column is t.",
                            path=str(path)) from exc
        with self._lock:
            run_id = f"r{next(self._ids)}"
            run = Run(run_id, label or path.name, res, "file", res.model_name,
                      events=event_times(res))
            self._runs[run_id] = run
            self._trim()
        return run

    def add_result(self, res: SimResult, label: str = "") -> Run:
        """Offer a :class:`SimResult` made in Python as a run."""
        if not isinstance(res, SimResult):
            raise TypeError(f"add_result: expected a SimResult, got {type(res).__name__}.")
        with self._lock:
            run_id = f"r{next(self._ids)}"
            run = Run(run_id, label or res.model_name or run_id, res, "file", res.model_name,
                      events=event_times(res))
            self._runs[run_id] = run
            self._trim()
        return run

    def load_bytes(self, data: bytes, filename: str) -> Run:
        """Load a simlog sent by the page (a file chosen in the browser)."""
        suffix = Path(filename).suffix.lower()
        if suffix not in (".csv", ".parquet"):
            raise DataError(f"{filename}: cannot load a simlog from a '{suffix or 'no'}' "
                            "file; give a .csv or .parquet file whose first column is t.",
                            path=filename)
        with tempfile.TemporaryDirectory(prefix="mechatron-explore-") as tmp:
            path = Path(tmp) / ("upload" + suffix)
            path.write_bytes(data)
            run = self.load(path, label=Path(filename).name)
        return run

    # ------------------------------------------------------------------ studies
    def load_study(self, path) -> dict:
        """Open the JSON result of ``mechatron estimate|sensitivity|optimize --out DIR``."""
        from mechatron.explore.studies import read_study
        path = Path(path)
        if not path.is_file():
            raise FileNotFoundError(f"{path}: no such file. A relative path starts in the "
                                    f"folder the explorer was started from, {Path.cwd()}.")
        with self._lock:
            study_id = f"s{next(self._ids)}"
        study = read_study(path, study_id)
        with self._lock:
            self._studies[study_id] = study
        return study.as_dict()

    def studies(self) -> list[dict]:
        with self._lock:
            return [s.as_dict() for s in self._studies.values()]

    def study_image(self, study_id: str, name: str) -> bytes:
        """One plot of a study (a PNG file listed by the study)."""
        with self._lock:
            study = self._studies.get(study_id)
        if study is None:
            raise KeyError(f"no study '{study_id}'. Open its .json first.")
        if name not in study.images:
            raise KeyError(f"study '{study_id}' has no plot '{name}'; plots: "
                           f"{', '.join(study.images) or 'none'}.")
        return (study.folder / name).read_bytes()

    def runs(self) -> list[dict]:
        with self._lock:
            return [r.summary() for r in self._runs.values()]

    def run(self, run_id: str) -> Run:
        with self._lock:
            run = self._runs.get(run_id)
            known = ", ".join(self._runs) or "none"
        if run is None:
            raise KeyError(f"no run '{run_id}' (runs: {known}). It may have been removed; "
                           "reload the page.")
        return run

    def remove(self, run_id: str) -> None:
        with self._lock:
            self.run(run_id)
            del self._runs[run_id]

    def variables(self, run_id: str) -> dict:
        """Names, units and descriptions of every variable of a run (no values)."""
        res = self.run(run_id).result
        units, docs = res.units, res.descriptions
        return {"names": res.names, "units": [units[n] for n in res.names],
                "descriptions": [docs[n] for n in res.names]}

    def signal(self, run_id: str, name: str, width: int, t0: float | None = None,
               t1: float | None = None, minus: str | None = None) -> dict:
        """One variable in a time window, decimated to ``width`` pixel columns; with
        ``minus``, its difference to the same variable of that run (interpolated
        linearly onto this run's times; undefined outside that run's time span)."""
        if not 1 <= width <= MAX_WIDTH:
            raise ValueError(f"signal: width must be 1 to {MAX_WIDTH} pixels, got {width}.")
        run = self.run(run_id)
        res = run.result
        y = res[name]
        unit = res.units[name]
        if minus is not None:
            ref = self.run(minus).result
            if name not in ref:
                raise KeyError(f"{name}: not logged in run '{minus}', so no difference to "
                               "it. Compare variables both runs have.")
            if unit and ref.units[name] and unit != ref.units[name]:
                raise ValueError(f"{name}: unit {unit} in run '{run_id}' but "
                                 f"{ref.units[name]} in run '{minus}'; no difference.")
            unit = unit or ref.units[name]
            inside = (res.t >= ref.t[0]) & (res.t <= ref.t[-1])
            y = np.where(inside, y - np.interp(res.t, ref.t, ref[name]), np.nan)
        t, v, dropped = decimate(res.t, y, width, t0, t1)
        part = window(res.t, t0, t1)
        return {"run": run_id, "name": name, "unit": unit, "t": t, "y": v, "minus": minus,
                "decimated": dropped, "n_window": int(part.stop - part.start)}

    def export(self, run_id: str, names: list[str], fmt: str, t0: float | None = None,
               t1: float | None = None) -> bytes:
        """The chosen variables of a run in a time window, as CSV or Parquet bytes."""
        if fmt not in ("csv", "parquet"):
            raise ValueError(f"export: format must be csv or parquet, got '{fmt}'.")
        if not names:
            raise ValueError("export: no variable chosen. Plot or tick at least one.")
        res = self.run(run_id).result
        sel = res.select(*names)
        part = window(res.t, t0, t1)
        if t0 is not None or t1 is not None:      # exactly the window, no margin samples
            t = res.t[part]
            keep = (t >= (t0 if t0 is not None else -np.inf)) & \
                   (t <= (t1 if t1 is not None else np.inf))
            rows = np.flatnonzero(keep) + part.start
            sel = SimResult(res.t[rows], sel.values[:, rows], sel.names,
                            [sel.units[n] for n in sel.names], model_name=res.model_name,
                            descriptions={n: d for n, d in sel.descriptions.items() if d})
        with tempfile.TemporaryDirectory(prefix="mechatron-explore-") as tmp:
            path = Path(tmp) / f"export.{fmt}"
            sel.save(path)
            return path.read_bytes()

    def _trim(self) -> None:
        def size() -> int:
            return sum(r.result.nbytes for r in self._runs.values())   # no values computed
        while len(self._runs) > MAX_RUNS or (len(self._runs) > 1 and size() > MAX_BYTES):
            del self._runs[next(iter(self._runs))]


