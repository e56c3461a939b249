"""Results of ``mechatron estimate``, ``sensitivity`` and ``optimize`` (the JSON document
and the plots they write with ``--out DIR``) as tables and images for the explorer.

A study is read from its ``estimate.json``, ``sensitivity.json`` or ``optimize.json``; its
kind is recognised from the document's keys, and its plots are the PNG files of the same
folder whose names start with the kind (``estimate_fit.png``...).
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path

from mechatron.errors import DataError

__all__ = ["Study", "read_study", "KINDS"]

#: Keys that identify each kind of result document.
KINDS = {"estimate": {"parameters", "ci95", "std", "nrmse"},
         "sensitivity": {"parameters", "requirements", "ranking"},
         "optimize": {"parameters", "objective", "max_violation"}}


@dataclass
class Study:
    """One result document: its kind, summary lines, tables and plots."""

    id: str
    label: str
    kind: str
    folder: Path
    summary: list[str]
    tables: list[dict]                 # {"title", "headers", "rows"}
    images: list[str] = field(default_factory=list)   # file names in ``folder``
    warnings: list[str] = field(default_factory=list)

    def as_dict(self) -> dict:
        return {"id": self.id, "label": self.label, "kind": self.kind,
                "summary": self.summary, "tables": self.tables, "images": self.images,
                "warnings": self.warnings}


def _num(x) -> str:
    if x is None:
        return "-"
    if isinstance(x, bool) or not isinstance(x, (int, float)):
        return str(x)
    if not math.isfinite(x):
        return str(x)
    return f"{x:.6g}"


def read_study(path: Path, study_id: str) -> Study:
    """Read a result document written by ``mechatron estimate|sensitivity|optimize --out``.

    Raises
    ------
    DataError
        If the file is not JSON or not one of those documents.
    """
    try:
        doc = json.loads(path.read_text(encoding="utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise DataError(f"{path}: not a JSON document ({exc}). Open the .json that "
                        "`mechatron estimate|sensitivity|optimize --out DIR` writes.",
                        path=str(path)) from None
    kind = next((k for k, keys in KINDS.items()
                 if isinstance(doc, dict) and keys <= set(doc)), None)
    if kind is None:
        raise DataError(f"{path}: not a result of `mechatron estimate`, `sensitivity` or "
                        "`optimize` (none of their keys). Open the .json those commands "
                        "write with --out DIR.", path=str(path))
    build = {"estimate": _estimate, "sensitivity": _sensitivity, "optimize": _optimize}[kind]
    summary, tables = build(doc)
    images = sorted(p.name for p in path.parent.glob(f"{kind}_*.png"))
    return Study(study_id, path.name if path.parent == Path(".") else
                 f"{path.parent.name}/{path.name}", kind, path.parent, summary, tables,
                 images, [str(w) for w in doc.get("warnings", [])])


def _estimate(doc: dict):
    names = list(doc["parameters"])
    rows = []
    for name in names:
        value = doc["parameters"][name]
        lo, hi = doc["ci95"].get(name, [None, None])
        std = doc["std"].get(name)
        rel = f"{100 * std / abs(value):.2f} %" if std is not None and value else "-"
        bound = doc.get("at_bound", {}).get(name)
        note = f"at {'lower' if bound.get('side') == 'min' else 'upper'} bound" if bound else ""
        rows.append([name, _num(doc["initial"].get(name)), _num(value), _num(lo), _num(hi),
                     rel, note])
    fit = []
    for experiment, signals in doc["nrmse"].items():
        before = doc.get("nrmse_initial", {}).get(experiment, {})
        for signal, after in signals.items():
            fit.append([experiment, signal, _num(before.get(signal)), _num(after)])
    corr = doc.get("correlation", {})
    tables = [{"title": "Parameters with 95 % intervals",
               "headers": ["parameter", "start", "estimate", "95 % low", "95 % high",
                           "rel. std", "note"], "rows": rows},
              {"title": "Fit: normalised RMS error of each measured signal (0 = perfect)",
               "headers": ["experiment", "signal", "before", "after"], "rows": fit}]
    if corr.get("names"):
        tables.append({"title": "Correlation of the estimates",
                       "headers": ["", *corr["names"]],
                       "rows": [[n, *[_num(v) for v in row]]
                                for n, row in zip(corr["names"], corr["matrix"])]})
    summary = [f"cost {_num(doc.get('cost_initial'))} -> {_num(doc.get('cost'))}; "
               f"{doc.get('iterations')} iterations, {doc.get('evaluations')} simulations, "
               f"{_num(doc.get('wall_time_s'))} s; {doc.get('message', '')}"]
    if doc.get("config"):
        summary.append(f"problem file: {doc['config']}")
    return summary, tables


def _sensitivity(doc: dict):
    reqs = doc["requirements"]
    ranking = doc.get("ranking") or doc["parameters"]
    tables = []
    for key, title in (("sobol_total", "Total Sobol index (share of the variance, with "
                                       "interactions)"),
                       ("sobol_first", "First-order Sobol index"),
                       ("src", "Standardised regression coefficient"),
                       ("spearman", "Spearman rank correlation")):
        data = doc.get(key)
        if data:
            tables.append({"title": title, "headers": ["parameter", *reqs],
                           "rows": [[p, *[_num(data.get(p, {}).get(r)) for r in reqs]]
                                    for p in ranking]})
    best = doc.get("best") or []
    if best:
        heads = list(best[0])
        tables.append({"title": "Best samples", "headers": heads,
                       "rows": [[_num(b.get(h)) for h in heads] for b in best]})
    summary = [f"{doc.get('evaluations')} simulations ({doc.get('method')}, "
               f"{doc.get('samples')} samples), {doc.get('failed', 0)} failed, "
               f"{_num(doc.get('wall_time_s'))} s; ranking: {', '.join(ranking)}"]
    return summary, tables


def _optimize(doc: dict):
    rows = [[name, _num(doc.get("initial", {}).get(name)), _num(value)]
            for name, value in doc["parameters"].items()]
    summary = [f"objective {_num(doc.get('objective_initial'))} -> "
               f"{_num(doc.get('objective'))}; largest violation "
               f"{_num(doc.get('max_violation_initial'))} -> "
               f"{_num(doc.get('max_violation'))}; {doc.get('iterations')} iterations; "
               f"{doc.get('message', '')}"]
    return summary, [{"title": "Parameters", "headers": ["parameter", "start", "optimized"],
                      "rows": rows}]
