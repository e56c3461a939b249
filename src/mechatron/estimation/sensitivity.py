"""Monte Carlo sensitivity analysis (the seed's section 6.2, Simulink's Sensitivity
Analyzer).

1. **Distributions** per parameter: ``uniform(low, high)``, ``normal(mean, std)``,
   ``loguniform(low, high)`` (uniform in ``log p``).
2. **Sampling** of ``N`` points: ``"random"``, ``"lhs"`` (Latin hypercube) or ``"sobol"``
   (scrambled Sobol sequence in Saltelli's scheme: two base matrices ``A``, ``B`` and the
   ``d`` matrices ``A_B^i`` (``A`` with column ``i`` from ``B``), ``N (d + 2)`` model runs,
   from which Sobol indices follow).
3. **Requirements** evaluated per sample: by default the sum of squared errors of each
   measured signal against the model (unweighted, in the signal's units, as in Simulink
   Design Optimization) and the weighted total cost of the estimation problem.
4. **Evaluation** in parallel: a local process pool (default), or a Dask cluster when its
   address is given (Dask is imported only then).
5. **Statistics** per parameter and requirement: Pearson and Spearman correlation,
   standardized regression coefficients (least squares on standardized values; their
   squares add up to the variance explained by a linear model, ``R^2``), and with Sobol
   sampling the first-order and total Sobol indices (Saltelli 2010 for ``S1``, Jansen 1999
   for ``ST``). The **ranking** orders the parameters by the total index when there is one
   (it sees non-monotonic effects, e.g. an error that is smallest in the middle of the
   range), else by ``|SRC|``; the largest value over the requirements counts.
6. **Best samples**: the parameter sets with the lowest total cost, as starting values of
   the estimation (the seed's table 6-2).

References: A. Saltelli et al., "Variance based sensitivity analysis of model output",
Comput. Phys. Commun. 181 (2010) 259-270; M. J. W. Jansen, Comput. Phys. Commun. 117
(1999) 35-43.
"""

from __future__ import annotations

import copy
import logging
import math
import os
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from mechatron._io import save_figure
from mechatron.errors import ParameterError
from mechatron.estimation.native import compiler

log = logging.getLogger(__name__)

__all__ = ["Distribution", "sample", "SensitivityResult", "run_sensitivity",
           "local_sensitivity", "sobol_indices", "sobol_intervals", "sobol_warnings",
           "standardized_regression"]


@dataclass(frozen=True)
class Distribution:
    """``kind`` is "uniform" (a = low, b = high), "normal" (a = mean, b = std) or
    "loguniform" (a = low > 0, b = high)."""

    kind: str
    a: float
    b: float

    def __post_init__(self):
        if self.kind not in ("uniform", "normal", "loguniform"):
            raise ParameterError(f"distribution '{self.kind}': use uniform, normal or "
                                 "loguniform.")
        if self.kind in ("uniform", "loguniform") and not self.a < self.b:
            raise ParameterError(f"{self.kind}({self.a:g}, {self.b:g}): low must be below "
                                 "high.")
        if self.kind == "loguniform" and self.a <= 0:
            raise ParameterError(f"loguniform({self.a:g}, {self.b:g}): low must be > 0.")
        if self.kind == "normal" and self.b <= 0:
            raise ParameterError(f"normal({self.a:g}, {self.b:g}): std must be > 0.")

    def ppf(self, u: np.ndarray) -> np.ndarray:
        """Values at cumulative probabilities ``u`` in (0, 1)."""
        u = np.asarray(u, dtype=float)
        if self.kind == "uniform":
            return self.a + (self.b - self.a) * u
        if self.kind == "loguniform":
            return np.exp(np.log(self.a) + (np.log(self.b) - np.log(self.a)) * u)
        from scipy.special import ndtri
        return self.a + self.b * ndtri(np.clip(u, 1e-12, 1 - 1e-12))


def sample(dists: dict, n: int, method: str = "lhs", seed: int = 0):
    """``n`` points of the joint distribution (independent parameters).

    Returns ``X`` of shape ``(n, d)``; for ``"sobol"`` returns the Saltelli design
    ``(A, B, AB)`` with ``AB`` of shape ``(d, n, d)``."""
    d = len(dists)
    names = list(dists)
    rng = np.random.default_rng(seed)
    if method == "random":
        U = rng.random((n, d))
    elif method == "lhs":
        from scipy.stats import qmc
        U = qmc.LatinHypercube(d=d, seed=rng).random(n)
    elif method == "sobol":
        from scipy.stats import qmc
        m = int(math.ceil(math.log2(max(n, 2))))
        UU = qmc.Sobol(d=2 * d, scramble=True, seed=rng).random_base2(m)[:n]
        A = _map(dists, names, UU[:, :d])
        Bm = _map(dists, names, UU[:, d:])
        AB = np.repeat(A[None, :, :], d, axis=0)
        for i in range(d):
            AB[i, :, i] = Bm[:, i]
        return A, Bm, AB
    else:
        raise ParameterError(f"sampling '{method}': use random, lhs or sobol.")
    return _map(dists, names, U)


def _map(dists, names, U):
    return np.column_stack([dists[nm].ppf(U[:, j]) for j, nm in enumerate(names)])


# ------------------------------------------------------------------------------ statistics
def standardized_regression(X: np.ndarray, y: np.ndarray):
    """``(SRC, R^2)``: coefficients of ``(y - mean)/std`` regressed on the standardized
    columns of ``X``."""
    Xs = (X - X.mean(0)) / X.std(0)
    ys = (y - y.mean()) / (y.std() or 1.0)
    A = np.column_stack([Xs, np.ones(len(y))])
    coef, *_ = np.linalg.lstsq(A, ys, rcond=None)
    pred = A @ coef
    r2 = 1 - np.sum((ys - pred) ** 2) / max(np.sum((ys - ys.mean()) ** 2), 1e-300)
    return coef[:-1], float(r2)


def regression_intervals(X: np.ndarray, Y: np.ndarray, *, resamples: int = 200,
                         level: float = 0.95, seed: int = 0):
    """Bootstrap intervals of the standardized regression coefficients of a Monte Carlo
    run: rows resampled with replacement, :func:`standardized_regression` recomputed;
    ``(low, high)``, each ``(d, n_req)`` (the central ``level`` range)."""
    n, d = X.shape
    low, high = np.full((d, Y.shape[1]), np.nan), np.full((d, Y.shape[1]), np.nan)
    if n < d + 2:
        return low, high
    rng = np.random.default_rng(seed)
    q = [50 * (1 - level), 50 * (1 + level)]
    for a in range(Y.shape[1]):
        draws = []
        for _ in range(resamples):
            k = rng.integers(0, n, n)
            if np.any(X[k].std(0) == 0):
                continue
            draws.append(standardized_regression(X[k], Y[k, a])[0])
        if draws:
            low[:, a], high[:, a] = np.percentile(np.array(draws), q, axis=0)
    return low, high


#: Monte Carlo samples per parameter (plus one) below which regression coefficients are
#: flagged as unreliable.
SAMPLES_PER_PARAMETER = 10


def sobol_indices(fA: np.ndarray, fB: np.ndarray, fAB: np.ndarray):
    """First-order and total Sobol indices from the Saltelli design outputs.

    ``S1_i = mean(fB (fAB_i - fA)) / V``,  ``ST_i = mean((fA - fAB_i)^2) / (2 V)`` with
    ``V`` the variance of ``[fA, fB]``."""
    V = np.var(np.concatenate([fA, fB]))
    if V <= 0:
        return np.zeros(len(fAB)), np.zeros(len(fAB))
    S1 = np.array([np.mean(fB * (fi - fA)) / V for fi in fAB])
    ST = np.array([0.5 * np.mean((fA - fi) ** 2) / V for fi in fAB])
    return S1, ST


def sobol_intervals(fA: np.ndarray, fB: np.ndarray, fAB: np.ndarray, *,
                    resamples: int = 500, level: float = 0.95, seed: int = 0):
    """Bootstrap confidence intervals of :func:`sobol_indices`.

    The ``n`` rows of the design are resampled with replacement ``resamples`` times (the
    same rows for ``fA``, ``fB`` and every ``fAB_i``) and the indices recomputed; the
    interval is the central ``level`` range of the recomputed values (percentile
    bootstrap, as SALib does). Returns ``(S1_low, S1_high, ST_low, ST_high)``, each of
    length ``d``.
    """
    n, d = len(fA), len(fAB)
    out = [np.full(d, np.nan) for _ in range(4)]
    if n < 2:
        return tuple(out)
    idx = np.random.default_rng(seed).integers(0, n, size=(resamples, n))
    a, b = fA[idx], fB[idx]                               # (resamples, n)
    V = np.var(np.concatenate([a, b], axis=1), axis=1)    # (resamples,)
    V = np.where(V > 0, V, np.nan)
    q = [50 * (1 - level), 50 * (1 + level)]
    if np.all(np.isnan(V)):
        return tuple(out)
    for i in range(d):                                    # memory: one parameter at once
        ab = fAB[i][idx]
        S1 = np.mean(b * (ab - a), axis=1) / V
        ST = 0.5 * np.mean((a - ab) ** 2, axis=1) / V
        (out[0][i], out[1][i]), (out[2][i], out[3][i]) = (np.nanpercentile(S1, q),
                                                          np.nanpercentile(ST, q))
    return tuple(out)


def sobol_warnings(names, requirements, S1, ST, intervals, n: int) -> list[str]:
    """Warnings about Sobol indices outside ``[0, 1]``, where no index can be.

    An index above 1 is always reported; a negative one only when its whole confidence
    interval is below 0 (small negative values of unimportant parameters are the
    estimator's sampling noise). Each warning names the parameter, requirement, estimate
    and interval and suggests more samples (the interval shrinks as ``1/sqrt(n)``)."""
    out = []
    if S1 is None or ST is None:
        return out
    for label, est, lo, hi in (("first-order", S1, intervals["S1_low"], intervals["S1_high"]),
                               ("total", ST, intervals["ST_low"], intervals["ST_high"])):
        for j, name in enumerate(names):
            for a, req in enumerate(requirements):
                x, l, h = est[j, a], lo[j, a], hi[j, a]
                if not math.isfinite(x):
                    continue
                if x > 1 or (x < 0 and h < 0):
                    bound = "exceeds 1" if x > 1 else "is negative beyond its interval"
                    out.append(f"{name}: {label} Sobol index for {req} is {x:+.3f} "
                               f"(95% interval [{l:+.3f}, {h:+.3f}]), which {bound}; "
                               f"indices lie in [0, 1], so this is sampling error at "
                               f"{n} base samples. Use more samples (e.g. {4 * n}, which "
                               "halves the interval).")
    return out


def _rank(x):
    order = np.argsort(x, kind="stable")
    r = np.empty(len(x))
    r[order] = np.arange(len(x))
    return r


@dataclass
class SensitivityResult:
    """Samples, requirement values, statistics, ranking and best samples."""

    names: list
    requirements: list
    X: np.ndarray
    Y: np.ndarray                      # (n, n_req)
    method: str
    pearson: np.ndarray                # (d, n_req)
    spearman: np.ndarray
    src: np.ndarray
    r2: np.ndarray                     # (n_req,)
    S1: np.ndarray | None
    ST: np.ndarray | None
    ranking: list
    best: list                         # [{name: value}] by increasing cost
    evaluations: int
    wall_time: float
    workers: int
    failed: int = 0
    extra: dict = field(default_factory=dict)
    #: Bootstrap 95% intervals: of the Sobol indices (``S1_low``, ``S1_high``, ``ST_low``,
    #: ``ST_high``) or, for random and LHS sampling, of the regression coefficients
    #: (``src_low``, ``src_high``); each ``(d, n_req)``.
    intervals: dict = field(default_factory=dict)
    #: Units of the parameters and the requirements (``""``: dimensionless), for the
    #: plots' axes.
    units: dict = field(default_factory=dict)
    #: Problems with the statistics (Sobol indices outside [0, 1], too few Monte Carlo
    #: samples for the regression), also logged.
    warnings: list = field(default_factory=list)

    @property
    def throughput(self) -> float:
        """Simulations per second (wall clock)."""
        return self.evaluations / self.wall_time if self.wall_time else math.nan

    def to_dict(self) -> dict:
        def table(m):
            return None if m is None else {
                n: dict(zip(self.requirements, map(float, row)))
                for n, row in zip(self.names, m)}
        return {"parameters": self.names, "requirements": self.requirements,
                "method": self.method, "samples": int(self.X.shape[0]),
                "evaluations": self.evaluations, "failed": self.failed,
                "wall_time_s": self.wall_time, "simulations_per_s": self.throughput,
                "workers": self.workers, "pearson": table(self.pearson),
                "spearman": table(self.spearman), "src": table(self.src),
                "r2": dict(zip(self.requirements, map(float, self.r2))),
                "sobol_first": table(self.S1), "sobol_total": table(self.ST),
                "sobol_intervals": {k: table(v) for k, v in self.intervals.items()},
                "ranking": self.ranking, "best": self.best, "warnings": self.warnings}

    def _label(self, name: str) -> str:
        unit = self.units.get(name, "")
        return f"{name} [{unit or '1'}]"

    def plot_scatter(self, path) -> Path:
        """Scatter matrix: each requirement (rows) against each parameter (columns)."""
        from matplotlib.figure import Figure
        d, r = len(self.names), len(self.requirements)
        fig = Figure(figsize=(2.0 * d + 1, 1.8 * r + 0.8), layout="constrained")
        axes = fig.subplots(r, d, sharex="col", sharey="row", squeeze=False)
        for a in range(r):
            for b in range(d):
                ax = axes[a, b]
                ax.plot(self.X[:, b], self.Y[:, a], ".", ms=2, alpha=0.5)
                ax.tick_params(labelsize=6)
                if a == r - 1:
                    ax.set_xlabel(self._label(self.names[b]), fontsize=8)
                if b == 0:
                    ax.set_ylabel(self._label(self.requirements[a]), fontsize=8)
        fig.suptitle(f"sensitivity: {self.X.shape[0]} samples ({self.method})")
        path = Path(path)
        save_figure(fig, path, dpi=80)
        return path

    def plot_tornado(self, path) -> Path:
        """Tornado chart of the ranking measure per requirement (largest on top)."""
        from matplotlib.figure import Figure
        measure = self.ST if self.ST is not None else self.src
        label = "total Sobol index" if self.ST is not None else "standardized regression coef."
        r = len(self.requirements)
        fig = Figure(figsize=(4.0 * r + 1, 0.35 * len(self.names) + 1.5),
                     layout="constrained")
        axes = fig.subplots(1, r, squeeze=False)[0]
        order = [self.names.index(n) for n in self.ranking][::-1]
        for a, ax in enumerate(axes):
            vals = measure[order, a]
            ax.barh([self.names[i] for i in order], vals,
                    color=["tab:blue" if v >= 0 else "tab:red" for v in vals])
            ax.set_title(self.requirements[a], fontsize=9)
            ax.set_xlabel(f"{label} [1]", fontsize=8)
            ax.set_ylabel("parameter", fontsize=8)
            ax.grid(True, axis="x", alpha=0.3)
        path = Path(path)
        save_figure(fig, path, dpi=80)
        return path


# ------------------------------------------------------------------------------ evaluation
def requirement_names(problem) -> list:
    labels = []
    for b in problem.bound:
        for lab in b["out_labels"]:
            if lab not in labels:
                labels.append(lab)
    return [f"sse_{lab}" for lab in labels] + ["cost"]


def _evaluate(prob, thetas) -> np.ndarray:
    names = requirement_names(prob)
    out = np.full((len(thetas), len(names)), np.nan)
    for k, theta in enumerate(thetas):
        try:
            sims = prob.simulate(theta)
        except Exception:                    # a sample the model cannot run: NaN row
            continue
        sse = {}
        for b, s in zip(prob.bound, sims):
            for r, lab in enumerate(b["out_labels"]):
                ym = b["Ym"][r]
                y = s[lab]
                sse[lab] = sse.get(lab, 0.0) + float(np.sum((y - ym) ** 2))
        cost = 0.0
        for b, s in zip(prob.bound, sims):
            for r, lab in enumerate(b["out_labels"]):
                cost += float(np.sum(((s[lab] - b["Ym"][r]) / b["sigma"][r]) ** 2))
        out[k] = [sse[n[4:]] for n in names[:-1]] + [cost]
    return out


def _units(problem, names, reqs) -> dict:
    """Units of the sampled names (parameters, ``offset:LABEL``, ``EXPERIMENT:NAME``) and
    of the requirements (``sse_LABEL`` in the output's unit squared, ``cost`` weighted by
    the noise levels: dimensionless)."""
    cm = problem.cm
    params = dict(zip(cm.param_names, cm.param_units))
    variables = dict(zip(cm.names, cm.units))

    def unit_of(name: str) -> str:
        if name in params:
            return params[name]
        head, _, tail = name.partition(":")
        if head == "offset":
            return problem._output_unit(tail)
        return params.get(tail, variables.get(tail, ""))

    def squared(unit: str) -> str:
        if not unit or unit == "1":
            return ""
        return f"{unit}^2" if unit.isalnum() else f"({unit})^2"
    out = {n: unit_of(n) for n in names}
    out.update({r: squared(problem._output_unit(r[4:])) for r in reqs if r.startswith("sse_")})
    out.update({r: "" for r in reqs if not r.startswith("sse_")})
    return out


def _theta_rows(problem, names, X) -> np.ndarray:
    """Full decision vectors: the problem's starting values with ``names`` set from X."""
    base = problem.initial
    idx = [problem.names.index(n) for n in names]
    T = np.repeat(base[None, :], X.shape[0], axis=0)
    T[:, idx] = X
    return T


def evaluate(problem, names, X, *, workers: int | None = None, address: str | None = None,
             client=None, progress=None) -> np.ndarray:
    """Requirement values at the rows of ``X`` (parameters ``names``), in parallel: on
    local processes, or on a Dask cluster (``client``, or the scheduler at ``address``),
    through :func:`mechatron.batch.map_blocks` (the problem sent once per worker, blocks
    retried, results in order: the same values as a local run)."""
    from mechatron.batch import map_blocks
    T = _theta_rows(problem, names, X)
    n = len(T)
    workers = workers if workers is not None else (os.cpu_count() or 1)
    if client is None and not address and n < 8:
        workers = 1
    chunks = max(1, min(n, 4 * max(workers, 1)))
    blocks = np.array_split(np.arange(n), chunks)
    sizes = np.cumsum([len(b) for b in blocks])
    tick = (lambda k, _total: progress(int(sizes[k - 1]), n)) if progress else None
    results = map_blocks(_evaluate, problem, [T[b] for b in blocks], workers=workers,
                         client=client, address=address, progress=tick)
    out = np.full((n, len(requirement_names(problem))), np.nan)
    for blk, res in zip(blocks, results):
        out[blk] = res
    return out


def run_sensitivity(problem, dists: dict, *, n: int = 256, method: str = "sobol",
                    seed: int = 0, workers: int | None = None, address: str | None = None,
                    best: int = 5, progress=None, native: bool = True,
                    client=None) -> SensitivityResult:
    """Sample ``dists`` (parameter name of ``problem`` -> :class:`Distribution`), evaluate
    the requirements, and compute the statistics (see the module docstring).

    ``native`` compiles the step functions to C first when a compiler is present (see
    :mod:`.native`; the results are the same). ``client`` (a ``distributed.Client``) or
    ``address`` runs the samples on a Dask cluster (see :func:`evaluate`)."""
    names = list(dists)
    # the statistics regress on the independent samples (A and B for Sobol): they need
    # more of them than parameters plus one
    per_sample = 2 if method == "sobol" else 1
    least = max(2, -(-(len(names) + 2) // per_sample))
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < least:
        raise ParameterError(f"sensitivity: {n!r} base samples for {len(names)} "
                             f"parameter(s) with {method} sampling; give at least {least} "
                             "(the regression needs more samples than parameters), better "
                             "64 or more.")
    unknown = [nm for nm in names if nm not in problem.names]
    if unknown:
        raise ParameterError(f"sensitivity: {', '.join(unknown)} not among the problem's "
                             f"free parameters ({', '.join(problem.names)}).")
    start = time.perf_counter()
    if native and compiler() is not None:
        problem = copy.copy(problem)          # do not change the caller's problem
        problem.bound = [dict(b) for b in problem.bound]
        problem._init = dict(problem._init)
        problem.use_native()
    reqs = requirement_names(problem)
    d = len(names)
    if method == "sobol":
        A, Bm, AB = sample(dists, n, "sobol", seed)
        X = np.vstack([A, Bm, AB.reshape(-1, d)])
    else:
        X = sample(dists, n, method, seed)
    Y = evaluate(problem, names, X, workers=workers, address=address, client=client,
                 progress=progress)
    used_workers = 0 if address else (workers if workers is not None else os.cpu_count())
    ok = np.all(np.isfinite(Y), axis=1)
    failed = int(np.sum(~ok))
    # statistics on the independent samples (A and B for Sobol)
    base = slice(0, 2 * n) if method == "sobol" else slice(0, len(X))
    Xs, Ys = X[base][ok[base]], Y[base][ok[base]]
    pear = np.zeros((d, len(reqs)))
    spear = np.zeros((d, len(reqs)))
    src = np.zeros((d, len(reqs)))
    r2 = np.zeros(len(reqs))
    for a in range(len(reqs)):
        y = Ys[:, a]
        for j in range(d):
            pear[j, a] = np.corrcoef(Xs[:, j], y)[0, 1]
            spear[j, a] = np.corrcoef(_rank(Xs[:, j]), _rank(y))[0, 1]
        src[:, a], r2[a] = standardized_regression(Xs, y)
    S1 = ST = None
    intervals, warnings = {}, []
    if method != "sobol":
        lo, hi = regression_intervals(Xs, Ys, seed=seed)
        intervals = {"src_low": lo, "src_high": hi}
        need = SAMPLES_PER_PARAMETER * (d + 1)
        if len(Xs) < need:
            width = float(np.nanmax(hi - lo)) if np.any(np.isfinite(hi - lo)) else math.inf
            warnings.append(f"sensitivity: {len(Xs)} Monte Carlo samples for {d} "
                            f"parameter(s) are too few for the regression coefficients "
                            f"(widest 95% interval {width:.3g}); use at least {need} "
                            f"({SAMPLES_PER_PARAMETER} per parameter and one).")
            log.warning(warnings[-1])
    if method == "sobol":
        fA, fB = Y[:n], Y[n:2 * n]
        fAB = Y[2 * n:].reshape(d, n, len(reqs))
        keep = np.all(np.isfinite(fA), 1) & np.all(np.isfinite(fB), 1) & \
            np.all(np.isfinite(fAB), axis=(0, 2))
        S1 = np.zeros((d, len(reqs)))
        ST = np.zeros((d, len(reqs)))
        intervals = {k: np.full((d, len(reqs)), np.nan)
                     for k in ("S1_low", "S1_high", "ST_low", "ST_high")}
        for a in range(len(reqs)):
            S1[:, a], ST[:, a] = sobol_indices(fA[keep, a], fB[keep, a], fAB[:, keep, a])
            bounds = sobol_intervals(fA[keep, a], fB[keep, a], fAB[:, keep, a], seed=seed)
            for k, v in zip(("S1_low", "S1_high", "ST_low", "ST_high"), bounds):
                intervals[k][:, a] = v
        warnings = sobol_warnings(names, reqs, S1, ST, intervals, int(np.sum(keep)))
        for w in warnings:
            log.warning(w)
    measure = ST if ST is not None else np.abs(src)
    # rank by the requirements on the measured signals (the total cost repeats them)
    score = np.nanmax(np.abs(measure[:, :-1] if len(reqs) > 1 else measure), axis=1)
    ranking = [names[j] for j in np.argsort(-score, kind="stable")]
    # best among the independent samples (for Sobol, the rows of A and B: the A_B rows
    # repeat all but one of their columns)
    indep = np.arange(2 * n) if method == "sobol" else np.arange(len(X))
    order = indep[np.argsort(np.where(ok[indep], Y[indep, -1], np.inf))][:best]
    best_sets = [dict(zip(names, map(float, X[k]))) | {"cost": float(Y[k, -1])}
                 for k in order]
    return SensitivityResult(names=names, requirements=reqs, X=X, Y=Y, method=method,
                             pearson=pear, spearman=spear, src=src, r2=r2, S1=S1, ST=ST,
                             ranking=ranking, best=best_sets, evaluations=len(X),
                             wall_time=time.perf_counter() - start,
                             workers=int(used_workers or 0), failed=failed,
                             intervals=intervals, warnings=warnings,
                             units=_units(problem, names, reqs))


def local_sensitivity(problem, names, *, rel_step: float = 1e-3) -> dict:
    """Finite-difference local sensitivity at the starting values: for each parameter
    ``p`` and measured signal ``l``, ``||y_l(p (1+h)) - y_l(p (1-h))|| / (2 h ||y_l||)``
    (relative change of the signal per relative change of the parameter)."""
    theta0 = problem.initial
    base = problem.simulate(theta0)
    out = {}
    for name in names:
        j = problem.names.index(name)
        hp, hm = theta0.copy(), theta0.copy()
        hp[j] *= 1 + rel_step
        hm[j] *= 1 - rel_step
        sp, sm = problem.simulate(hp), problem.simulate(hm)
        vals = {}
        for b, s0, a, c in zip(problem.bound, base, sp, sm):
            for lab in b["out_labels"]:
                num = np.linalg.norm(a[lab] - c[lab]) / (2 * rel_step)
                vals[lab] = vals.get(lab, 0.0) + num / max(np.linalg.norm(s0[lab]), 1e-300)
        out[name] = vals
    return out
