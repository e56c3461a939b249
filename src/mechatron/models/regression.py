"""Regression runs of the model database: every model against its expected values, its
variants against each other, as batch tasks.

For each model (:func:`check_model`): every variant simulated on a common grid with the
experiment's solver and tolerances (:func:`~mechatron.models.compare.compare_variants`),
the reference variant's final values compared with the entry's ``expected`` values
(relative error, limit ``expected_tolerance``), and the largest deviation of the other
variants from the reference (relative to the reference's peak, limit
``variant_tolerance``). :func:`run_regression` runs the models as tasks of
:func:`mechatron.batch.map_blocks`: in this process, on local worker processes, or on a
Dask cluster (a task whose worker dies is rerun elsewhere); the rows come back in the
order of the names, with the same numbers wherever they ran (the wall times aside).

Local worker processes are forked from this one and find every entry here. On a Dask
cluster the entries travel with the tasks (once per worker, pickled by value where they
must be): a worker's own database lacks an entry registered at run time
(``mechatron.models.register``), and may come from another installation.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Sequence

__all__ = ["check_model", "run_regression", "POINTS"]

#: Points of the common output grid of a regression run.
POINTS = 201


def _relative(deviation: float, scale: float) -> float:
    from mechatron.models.compare import relative
    return relative(deviation, scale)


def check_model(name, *, points: int = POINTS) -> dict:
    """One model's regression row: ``model``, ``variants``, ``reference``, ``expected``
    (per label: ``value``, ``expected``, ``rel_error``), ``expected_worst`` and
    ``expected_tolerance``, ``variants_worst`` (0 for one variant) and
    ``variant_tolerance``, ``passed``, ``error`` (None, or the failure's message) and
    ``wall_time_s`` (simulation wall time of the variants). ``name`` is a database
    name or the `ModelEntry` itself."""
    import mechatron as mt
    from mechatron.errors import MechatronError
    from mechatron.models.compare import compare_variants
    from mechatron.models.entry import ModelEntry
    entry = name if isinstance(name, ModelEntry) else mt.models.get(name)
    row = {"model": entry.name, "variants": [], "reference": None, "expected": {},
           "expected_worst": math.nan, "expected_tolerance": entry.expected_tolerance,
           "variants_worst": math.nan, "variant_tolerance": entry.variant_tolerance,
           "passed": False, "error": None, "wall_time_s": 0.0}
    try:
        cmp = compare_variants(entry, points=points)
    except (MechatronError, ArithmeticError, RuntimeError) as exc:
        row["error"] = f"{type(exc).__name__}: {exc}"
        return row
    ref = cmp.results[cmp.reference]
    paths = entry.output_paths(cmp.reference)
    for label, want in entry.expected.items():
        got = float(ref.final(paths[label]))
        row["expected"][label] = {"value": got, "expected": float(want),
                                  "rel_error": _relative(abs(got - want), abs(want))}
    worst_expected = max((e["rel_error"] for e in row["expected"].values()), default=0.0)
    worst = cmp.worst()
    row.update(variants=list(cmp.results), reference=cmp.reference,
               expected_worst=worst_expected, variants_worst=worst,
               passed=bool(worst_expected <= entry.expected_tolerance
                           and (len(cmp.results) < 2 or worst <= entry.variant_tolerance)),
               wall_time_s=sum(r.stats.wall_time for r in cmp.results.values()))
    return row


def _check_block(shared, name):
    points, entries = shared
    t0 = time.perf_counter()
    row = check_model(entries.get(name, name), points=points)
    row["task_wall_time_s"] = time.perf_counter() - t0
    return row


def run_regression(names: Sequence[str] | None = None, *, points: int = POINTS,
                   workers: int | None = 1, client=None, address: str | None = None,
                   progress: Callable[[int, int], None] | None = None) -> list[dict]:
    """The regression rows (:func:`check_model`) of the models ``names`` (default: the
    whole database), one batch task per model.

    Parameters
    ----------
    names : sequence of str, optional
        Database names (checked here first); every model if omitted.
    points : int
        Points of each model's common output grid.
    workers, client, address, progress
        Where to run: see :func:`mechatron.batch.map_blocks` (``workers=None``: one
        process per core).

    Returns
    -------
    list of dict
        In the order of ``names``.
    """
    import mechatron as mt
    from mechatron.batch import map_blocks
    entries = mt.models.list() if names is None else \
        [mt.models.get(n) for n in names]                # unknown names fail here
    names = [e.name for e in entries]
    # a cluster's workers get the entries themselves (see the module's docstring)
    shipped = {e.name: e for e in entries} if client is not None or address else {}
    return map_blocks(_check_block, (int(points), shipped), names, workers=workers,
                      client=client, address=address, progress=progress)
