"""Every variant of a database model on the same output grid, and how far they differ.

Used by ``mechatron compare``, ``mechatron report`` and the database tests.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from mechatron.models.entry import ModelEntry
from mechatron.results import SimResult
from mechatron.solvers import simulate

__all__ = ["Comparison", "compare_variants", "max_deviation", "relative", "COMPARE_POINTS"]

#: Points of the common output grid.
COMPARE_POINTS = 1001


def relative(deviation: float, scale: float) -> float:
    if scale > 0:
        return deviation / scale
    return 0.0 if deviation == 0 else math.inf


def max_deviation(y: np.ndarray, y_ref: np.ndarray) -> tuple[float, float]:
    """Largest absolute deviation, and the same relative to the largest ``|y_ref|``."""
    dev = float(np.max(np.abs(y - y_ref))) if y.size else 0.0
    return dev, relative(dev, float(np.max(np.abs(y_ref))) if y_ref.size else 0.0)


@dataclass
class Comparison:
    """The runs of every variant and their deviations from the first (the reference)."""

    entry: ModelEntry
    results: dict[str, SimResult]
    #: variant -> label -> {"max_abs": ..., "max_rel": ...}, for every variant but the first
    deviations: dict[str, dict[str, dict[str, float]]] = field(default_factory=dict)
    #: variant -> labels of the reference it has no output for
    missing: dict[str, list[str]] = field(default_factory=dict)

    @property
    def reference(self) -> str:
        return next(iter(self.results))

    @property
    def labels(self) -> list[str]:
        return list(self.entry.output_paths(self.reference))

    def worst(self) -> float:
        """Largest relative deviation over every variant and output (0 for one variant)."""
        return max((d["max_rel"] for per in self.deviations.values() for d in per.values()),
                   default=0.0)

    def final(self) -> dict[str, dict[str, float]]:
        return {v: {label: r.final(path) for label, path in
                    self.entry.output_paths(v).items()} for v, r in self.results.items()}

    def figure(self):
        """An overlay plot of every output, one axis per output (a matplotlib Figure)."""
        import matplotlib.pyplot as plt
        labels = self.labels
        fig, axes = plt.subplots(len(labels), 1, figsize=(8.0, 2.4 * len(labels)),
                                 sharex=True, squeeze=False, layout="constrained")
        styles = ["-", "--", ":", "-."]
        for axis, label in zip(axes[:, 0], labels):
            for k, (v, res) in enumerate(self.results.items()):
                p = self.entry.output_paths(v).get(label)
                if p is not None:
                    axis.plot(res.t, res[p], styles[k % len(styles)], label=f"{v} ({p})")
            unit = self.entry.output_units.get(label, "") or "1"
            axis.set_ylabel(f"{label} [{unit}]")
            axis.grid(True, alpha=0.3)
            axis.legend(loc="best", fontsize="small")
        axes[-1, 0].set_xlabel("t [s]")
        fig.suptitle(f"{self.entry.name}: variants compared")
        return fig


def compare_variants(entry: ModelEntry, *, params: dict | None = None,
                     t_stop: float | None = None, solver: str | None = None,
                     dt: float | None = None, rtol: float | None = None,
                     atol: float | None = None, points: int = COMPARE_POINTS,
                     variants: list[str] | None = None, progress=None) -> Comparison:
    """Simulate every variant of ``entry`` (default: its experiment's settings) on a common
    grid of ``points`` output times and measure each output's deviation from the first.

    A variant with external inputs runs on the entry's ``reference_inputs`` (the signals
    that reproduce the built-in sources); ``driven_variants`` (open-loop plants for an
    outside controller) are left out unless named in ``variants``.
    ``progress(done, total)`` is called after each variant's run."""
    exp = entry.experiment
    params = params or {}
    t_stop = exp.t_stop if t_stop is None else t_stop
    grid = np.linspace(0.0, t_stop, points)
    variants = list(variants or [v for v in entry.variants
                                 if v not in entry.driven_variants])
    results = {}
    for v in variants:
        results[v] = simulate(entry.build(v, **params), t_stop,
                              solver=solver or exp.solver,
                              dt=dt if dt is not None else exp.dt,
                              rtol=exp.rtol if rtol is None else rtol,
                              atol=exp.atol if atol is None else atol, t_out=grid,
                              inputs=entry.inputs_for(v, t_stop, **params))
        if progress is not None:
            progress(len(results), len(variants))
    cmp = Comparison(entry, results)
    ref = variants[0]
    ref_paths = entry.output_paths(ref)
    for v in variants[1:]:
        paths = entry.output_paths(v)
        cmp.missing[v] = [label for label in ref_paths if label not in paths]
        cmp.deviations[v] = {}
        for label, ref_path in ref_paths.items():
            if label in paths:
                dev, rel = max_deviation(results[v][paths[label]], results[ref][ref_path])
                cmp.deviations[v][label] = {"max_abs": dev, "max_rel": rel}
    return cmp
