"""Multi-start estimation: several fits from spread-out starting values, the best kept.

A least-squares cost can have several local minima: the frequency of an oscillation
fitted to a record of a few periods has one near every frequency whose oscillation lines
up with part of the record, and Levenberg-Marquardt goes to the minimum of the valley it
starts in. Multi-start runs ``K`` fits (``estimate(problem, starts=K)``):

1. **Starting points.** Start 0 is the problem's starting values (or ``initial=``);
   starts 1 to ``K - 1`` are points of a Latin hypercube (``sampling="lhs"``, the
   default: each parameter's range cut into ``K - 1`` equal strata, one point in each)
   or of a scrambled Sobol sequence (``"sobol"``) inside the bounds ``min``/``max`` of the
   decision variables, the same for the same ``seed``. A variable whose bounds are both
   positive and a factor of 100 or more apart is sampled uniformly in its logarithm (a
   decade counts as much as any other); one without two finite bounds (offsets, initial
   states, parameters with an open side) keeps its starting value in every start.
2. **Fits** as batch tasks (:func:`mechatron.batch.map_blocks`): one task per start, on
   local processes (``workers``; default one per core, at most ``K``) or on a Dask
   cluster (``client`` or ``address``; the problem is sent once to each worker, a failed
   task is retried). Each fit starts from the problem as given (its substeps as chosen
   at construction), whatever fit ran before it on the same worker, so the results do
   not depend on where or in which order the fits ran.
3. **The best fit** is the one of lowest cost, ties going to the lower start index; a
   fit that failed (a simulation that did not converge) or ended with a cost that is not
   finite is not a candidate. Its result is returned (intervals, fit figures,
   discretization, profile intervals if asked for), with every start in
   ``result.starts``: start index, starting and final values, cost, whether it
   converged, its message, iterations and simulations, or the error it failed with.

References: the same scheme as MATLAB's ``MultiStart`` with ``RandomStartPointSet``
(uniform in the bounds), here with stratified points and without artificial bounds for
unbounded variables.
"""

from __future__ import annotations

import logging
import math
import os
import time

import numpy as np

from mechatron.errors import MechatronError, ParameterError

log = logging.getLogger(__name__)

__all__ = ["start_points", "estimate_multistart", "LOG_SPAN"]

#: Ratio ``max / min`` of positive bounds from which a variable is sampled uniformly in
#: its logarithm.
LOG_SPAN = 100.0


def start_points(problem, starts: int, *, seed: int = 0, sampling: str = "lhs",
                 initial=None) -> np.ndarray:
    """The ``(starts, q)`` starting points of a multi-start estimation of ``problem``:
    row 0 its starting values (or ``initial``), the others sampled inside the bounds
    (see the module docstring)."""
    if isinstance(starts, bool) or not isinstance(starts, (int, np.integer)) or starts < 1:
        raise ParameterError(f"estimate: starts must be a whole number >= 1, got "
                             f"{starts!r}.")
    if sampling not in ("lhs", "sobol"):
        raise ParameterError(f"estimate: sampling '{sampling}': use lhs or sobol.")
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise ParameterError(f"estimate: seed must be a whole number >= 0, got {seed!r}.")
    lo, hi = problem.bounds
    x0 = np.asarray(problem.initial if initial is None else initial, dtype=float)
    if x0.shape != lo.shape or not np.all(np.isfinite(x0)):
        raise ParameterError(f"estimate: initial must be {lo.size} finite number(s), one "
                             f"per decision variable ({', '.join(problem.names)}), got "
                             f"{initial!r}.")
    x0 = np.clip(x0, lo, hi)
    X = np.repeat(x0[None, :], starts, axis=0)
    n = starts - 1
    if n == 0:
        return X
    cols = np.flatnonzero(np.isfinite(lo) & np.isfinite(hi))
    if cols.size == 0:
        raise ParameterError(
            f"estimate: multi-start samples the decision variables inside their bounds, "
            f"but none of {', '.join(problem.names)} has both a finite min and max. Give "
            "min and max to the parameters to vary (e.g. [parameters] k = { initial = 1, "
            "min = 0.1, max = 10 }), or use one start.")
    from scipy.stats import qmc
    rng = np.random.default_rng(seed)
    d = cols.size
    if sampling == "lhs":
        U = qmc.LatinHypercube(d=d, seed=rng).random(n)
    else:
        m = max(1, math.ceil(math.log2(n)))
        U = qmc.Sobol(d=d, scramble=True, seed=rng).random_base2(m)[:n]
    for j, c in enumerate(cols):
        a, b = lo[c], hi[c]
        if a > 0 and b / a >= LOG_SPAN:
            X[1:, c] = np.exp(np.log(a) + (np.log(b) - np.log(a)) * U[:, j])
        else:
            X[1:, c] = a + (b - a) * U[:, j]
    return X


def _error_or_worse(record) -> bool:
    """Drops the warnings of the single fits (bounds, identifiability): the chosen fit's
    are logged again once it is known."""
    return record.levelno >= logging.ERROR


def _fit_start(problem, job) -> dict:
    """One start (a batch task): ``job`` is ``(start index, starting point, keywords
    of estimate)``. The problem's substeps are put back afterwards, so the next start on
    this worker begins from the same discretization."""
    from mechatron.estimation.problem import estimate, passing_only
    k, theta0, kwargs = job
    state = problem.substep_state()
    t0 = time.perf_counter()
    row = {"start": int(k), "initial": dict(zip(problem.names, map(float, theta0))),
           "parameters": None, "cost": math.inf, "converged": False, "message": "",
           "iterations": 0, "evaluations": 0, "wall_time_s": 0.0, "error": None}
    res = substeps = None
    try:
        with passing_only(_error_or_worse):
            res = estimate(problem, initial=theta0, **kwargs)
        substeps = [b["substeps"] for b in problem.bound]
        res.problem = None                          # not sent back: the caller has it
        row.update(parameters=res.parameters,
                   cost=float(res.cost) if np.isfinite(res.cost) else math.inf,
                   converged=bool(res.success), message=res.message,
                   iterations=int(res.iterations), evaluations=int(res.evaluations))
    except (MechatronError, np.linalg.LinAlgError, ArithmeticError, RuntimeError) as exc:
        # RuntimeError: CasADi's report of a failure inside its own code
        row["error"] = f"{type(exc).__name__}: {exc}"
        row["message"] = "failed"
        res = None
    finally:
        problem.restore_substeps(state)
    row["wall_time_s"] = time.perf_counter() - t0
    return {"row": row, "result": res, "substeps": substeps}


def estimate_multistart(problem, *, starts: int = 8, seed: int = 0, sampling: str = "lhs",
                        workers: int | None = None, address: str | None = None,
                        client=None, progress=None, initial=None, profile=(),
                        **kwargs):
    """Multi-start estimation (see the module docstring); ``estimate(problem,
    starts=K, ...)`` calls it. ``kwargs`` are the further keywords of
    :func:`~mechatron.estimation.problem.estimate` (``max_iterations``, ``covariance``,
    ...), the same for every start; ``profile`` intervals are computed for the best fit
    only. ``progress(done, starts)`` is called as the fits arrive, in start order.

    Returns the best fit's :class:`~mechatron.estimation.problem.EstimationResult`, with
    ``starts`` (every start) and ``best_start``; its ``wall_time`` is that of the whole
    multi-start run."""
    from mechatron.batch import map_blocks
    from mechatron.estimation.problem import profile_intervals
    start = time.perf_counter()
    X = start_points(problem, starts, seed=seed, sampling=sampling, initial=initial)
    kwargs.pop("callback", None)
    jobs = [(k, X[k], dict(kwargs)) for k in range(starts)]
    if client is None and not address:
        workers = min(starts, workers if workers is not None else (os.cpu_count() or 1))
    out = map_blocks(_fit_start, problem, jobs, workers=workers, client=client,
                     address=address, progress=progress)
    rows = [o["row"] for o in out]
    ok = [k for k, r in enumerate(rows) if r["error"] is None and math.isfinite(r["cost"])]
    if not ok:
        raise MechatronError(
            f"estimate: all {starts} starts failed; the first: "
            f"{rows[0]['error'] or 'cost not finite'}. Check the bounds (the sampled "
            "starts lie anywhere inside them) and the model at the starting values.")
    best = min(ok, key=lambda k: (rows[k]["cost"], k))
    res = out[best]["result"]
    problem.restore_substeps(out[best]["substeps"])
    res.problem = problem
    res.starts = rows
    res.best_start = best
    if profile:
        from scipy.special import stdtrit
        from mechatron.estimation.uncertainty import bartlett_critical
        dof = max(problem.n_residuals - len(res.names), 1)
        tq = bartlett_critical(res.bandwidth_fraction) if res.covariance == "hac" \
            else float(stdtrit(dof, 0.975))
        res.profile_ci95 = profile_intervals(problem, res.values, profile,
                                             s2=res.cost / dof, tq=tq, std=res.std,
                                             std_white=res.std_white)
    res.wall_time = time.perf_counter() - start
    reached = sum(1 for k in ok if rows[k]["cost"] <= res.cost * (1 + 1e-6) + 1e-300)
    log.info("estimate: %d starts, best is start %d (cost %.6g), reached by %d; %d failed",
             starts, best, res.cost, reached, starts - len(ok))
    from mechatron.estimation.bounds import describe_at_bounds
    if res.at_bound:
        log.warning("estimate: %s", describe_at_bounds(res.at_bound, "estimate"))
    for name, why in res.flags.items():
        log.warning("estimate: %s %s", name, why)
    for w in res.warnings:
        log.warning("estimate: %s", w, extra={"in_summary": True})
    return res
