"""Real-time readiness of a model: the Simscape HIL workflow as one function.

1. **Reference.** A variable-step run at tight tolerance on the sample grid of the target
   rate (``1/rate``).
2. **Zero crossings.** Events of the reference, by component: a fixed-step solver does not
   locate them, so each one costs up to one step of timing error.
3. **Stiffness.** Eigenvalues ``lambda`` of the state Jacobian ``d der(x)/dx`` (algebraic
   unknowns eliminated: ``A = f_x - f_z g_z^-1 g_x``) at points of the reference. A
   method is stable at step ``h`` when ``|R(h lambda)| <= 1`` for every eigenvalue, with
   ``R`` its stability function (explicit Runge-Kutta: ``R(z) = 1 + z b^T (I - z A)^-1
   1``; theta methods: ``(1 + (1-theta) z) / (1 - theta z)``; Euler extrapolation: the
   Aitken-Neville combination of ``(1 - z/n)^-n``). The explicit methods are recommended
   when they are stable at the sample step; otherwise the model is stiff at that rate and
   an implicit method is recommended.
4. **Sweep.** Every fixed-step method at steps ``T/m`` (``m`` steps per sample period) and,
   for the implicit ones, each Newton iteration count: maximum error against the reference
   (relative to each output's peak).
5. **Timing.** The generated C of each (method, iterations) is compiled and timed; the
   real-time margin at the rate is ``1 - m t_step rate`` (the share of each period left).
6. **Recommendation.** The cheapest configuration whose error is within the tolerance and
   whose margin is at least ``min_margin``.

Limitations: errors are measured on the sample grid only; the timing is that of this
machine's processor (a target's must be measured there: ``mechatron codegen --arm`` reports
its code size); the stability analysis is linear (at the sampled points of the reference).
"""

from __future__ import annotations

import math
import tempfile
from dataclasses import asdict, dataclass, field
from pathlib import Path

import casadi as ca
import numpy as np

import mechatron as mt
from mechatron.compiler.compiled import CompiledModel
from mechatron.errors import MechatronError, RunTooLargeError, SimulationError
from mechatron.solvers.fixed import (METHODS, ExplicitMethod, ExtrapolatedMethod,
                                     ImplicitMethod)
from mechatron.solvers.initial import initialize

__all__ = ["rtcheck", "RTCheck", "Candidate", "stability_function", "stable_step",
           "jacobian_eigenvalues"]

EXPLICIT = tuple(k for k, m in METHODS.items() if isinstance(m, ExplicitMethod))
IMPLICIT = tuple(k for k in METHODS if k not in EXPLICIT)


@dataclass
class Candidate:
    """One configuration of the sweep."""

    solver: str
    dt: float
    iterations: int | None          # None for explicit methods
    steps_per_period: int
    max_error: float                # inf when the run diverged
    stable: bool                    # linear stability at the sampled points
    ns_per_step: float | None = None
    margin: float | None = None     # share of the sample period left, at the rate
    ok: bool = False                # error and margin within the limits

    @property
    def explicit(self) -> bool:
        return self.solver in EXPLICIT


@dataclass
class RTCheck:
    """The result of :func:`rtcheck`; ``as_dict()`` for JSON."""

    model: str
    rate: float
    t_stop: float
    tolerance: float
    min_margin: float
    outputs: list[str]
    reference: dict
    zero_crossings: dict[str, int]
    event_times: dict[str, float]
    eigenvalues: list[complex]
    stiffness: dict
    candidates: list[Candidate]
    recommended: Candidate | None
    reasons: list[str] = field(default_factory=list)

    def as_dict(self) -> dict:
        d = asdict(self)
        d["eigenvalues"] = [[float(np.real(v)), float(np.imag(v))] for v in self.eigenvalues]
        for c in d["candidates"] + ([d["recommended"]] if d["recommended"] else []):
            c["max_error"] = c["max_error"] if math.isfinite(c["max_error"]) else None
        return d


# ------------------------------------------------------------------------ stability
def stability_function(method: str, z) -> np.ndarray:
    """``R(z)``: one step of ``method`` on ``x' = lambda x`` multiplies ``x`` by
    ``R(h lambda)`` (exact for the implicit methods when Newton has converged, which one
    iteration does on a linear problem)."""
    m = METHODS[method]
    z = np.asarray(z, dtype=complex)
    if isinstance(m, ExplicitMethod):
        s = len(m.b)
        A = np.zeros((s, s))
        for i, row in enumerate(m.a):
            A[i, :len(row)] = row
        b = np.array(m.b)
        out = np.empty(z.shape, dtype=complex)
        for idx, zi in np.ndenumerate(z):
            out[idx] = 1 + zi * b @ np.linalg.solve(np.eye(s) - zi * A, np.ones(s))
        return out
    if isinstance(m, ImplicitMethod):
        return (1 + (1 - m.theta) * z) / (1 - m.theta * z)
    if isinstance(m, ExtrapolatedMethod):
        rows: list[list[np.ndarray]] = []
        for n in m.sequence:
            row = [(1 - z / n) ** (-n)]
            for j in range(1, len(rows) + 1):
                ratio = n / m.sequence[len(rows) - j]
                row.append(row[j - 1] + (row[j - 1] - rows[-1][j - 1]) / (ratio - 1))
            rows.append(row)
        return rows[-1][-1]
    raise MechatronError(f"no stability function for method '{method}'.")


def _stable(method: str, h: float, eigs: np.ndarray) -> bool:
    if eigs.size == 0:
        return True
    return bool(np.all(np.abs(stability_function(method, h * eigs)) <= 1 + 1e-9))


def stable_step(method: str, eigs, h_max: float = 1.0) -> float:
    """Largest step (up to ``h_max``) at which ``method`` is stable for ``eigs`` (by
    bisection on a log scale; ``h_max`` when stable there)."""
    eigs = np.asarray(eigs, dtype=complex)
    eigs = eigs[np.abs(eigs) > 0]
    if _stable(method, h_max, eigs):
        return h_max
    lo, hi = 0.0, h_max
    for _ in range(80):
        mid = math.sqrt(max(lo, 1e-300) * hi) if lo > 0 else hi / 1e3
        if _stable(method, mid, eigs):
            lo = mid
        else:
            hi = mid
        if lo > 0 and hi / lo < 1 + 1e-6:
            break
    return lo


# ------------------------------------------------------------------------ Jacobian
def jacobian_eigenvalues(cm: CompiledModel, p, points) -> np.ndarray:
    """Eigenvalues of ``d der(x)/dx`` at each ``(t, X, z)`` of ``points``, concatenated."""
    nx, nz = cm.nx, cm.nz
    if nx == 0:
        return np.zeros(0, dtype=complex)
    xs = ca.SX.sym("xs", nx)
    rest = ca.SX.sym("rest", cm.nX - nx)
    zs = ca.SX.sym("zs", nz)
    t = ca.SX.sym("t")
    X = ca.vertcat(xs, rest)
    f = cm.f_ode(t, X, zs, p)[:nx]
    A = ca.jacobian(f, xs)
    znew = zs
    if nz:
        g = cm.f_alg(t, X, zs, p)
        gz = ca.jacobian(g, zs)
        A = A - ca.mtimes(ca.jacobian(f, zs), ca.solve(gz, ca.jacobian(g, xs)))
        znew = zs - ca.solve(gz, g)
    F = ca.Function("state_jacobian", [t, xs, rest, zs], [A, znew])
    out = []
    for tk, Xk, zk in points:
        Xk = np.asarray(Xk, dtype=float)
        zk = np.asarray(zk, dtype=float)
        for _ in range(5 if nz else 1):    # a few Newton steps to the consistent z
            Ak, zn = F(tk, Xk[:nx], Xk[nx:], zk)
            zk = np.array(zn, dtype=float).ravel()
        Ak = np.array(F(tk, Xk[:nx], Xk[nx:], zk)[0], dtype=float)
        if np.all(np.isfinite(Ak)):
            out.append(np.linalg.eigvals(Ak))
    return np.concatenate(out) if out else np.zeros(0, dtype=complex)


def _describe_eig(lam: complex) -> str:
    if abs(lam.imag) > 1e-9 * abs(lam):
        return f"{lam.real:.3g} {'+' if lam.imag >= 0 else '-'} {abs(lam.imag):.3g}j 1/s"
    return f"{lam.real:.3g} 1/s"


# ------------------------------------------------------------------------ the check
def _max_error(fixed: np.ndarray, ref: np.ndarray) -> float:
    scale = np.maximum(np.max(np.abs(ref), axis=1), 1e-300)
    err = np.max(np.abs(fixed - ref), axis=1) / scale
    return float(np.max(err)) if np.all(np.isfinite(fixed)) else math.inf


def rtcheck(model, *, rate: float, t_stop: float | None = None, params: dict | None = None,
            outputs=None, solvers=None, substeps=(1, 2, 4), iterations=(1, 2, 3),
            tolerance: float = 1e-3, min_margin: float = 0.5, measure: bool = True,
            timing_steps: int = 200_000, workdir=None, progress=None) -> RTCheck:
    """Check a model for real time at ``rate`` Hz (see the module docstring).

    Parameters
    ----------
    model : Component or CompiledModel
    rate : float
        Sample rate of the real-time loop in Hz; the sample step is ``T = 1/rate``.
    t_stop : float, optional
        Length of the reference run (default: 1000 sample periods).
    params : dict, optional
        Parameter values by instance path.
    outputs : list of str, optional
        Variables whose error counts (default: the continuous states that are logged,
        else every logged variable).
    solvers : list of str, optional
        Methods to sweep (default: all of :data:`mechatron.solvers.METHODS`).
    substeps : tuple of int
        Steps per sample period ``m``: the step sizes swept are ``T/m``.
    iterations : tuple of int
        Newton iteration counts swept for the implicit methods.
    tolerance : float
        Largest acceptable error, relative to each output's peak.
    min_margin : float
        Smallest acceptable share of the sample period left after the steps.
    measure : bool
        Compile and time the generated C (else the timing columns stay empty and the
        recommendation uses the operation count).
    progress : callable, optional
        Called as ``progress(done, total, what)`` after the reference run, each fixed-step
        run of the sweep and each C build and timing (the command line shows a bar).
    """
    if not (isinstance(rate, (int, float)) and math.isfinite(rate) and rate > 0):
        raise SimulationError(f"rtcheck: the rate must be a number of Hz > 0, got {rate!r}.")
    cm = model if isinstance(model, CompiledModel) else mt.compile_model(model)
    solvers = list(solvers or METHODS)
    unknown = [s for s in solvers if s not in METHODS]
    if unknown:
        raise SimulationError(f"rtcheck: unknown fixed-step solver(s) {', '.join(unknown)}. "
                              f"Choose among {', '.join(METHODS)}.")
    T = 1.0 / rate
    t_stop = 1000 * T if t_stop is None else float(t_stop)
    n = int(round(t_stop / T))
    if n < 2:
        raise SimulationError(f"rtcheck: t_stop = {t_stop:g} s is shorter than two sample "
                              f"periods ({T:g} s).")
    stride = max(1, math.ceil(n / 20000))         # at most ~20000 comparison points
    grid = np.arange(0, n + 1, stride) * T
    t_stop = float(grid[-1])
    p = cm.parameter_vector(params)

    runs = sum(1 if s in EXPLICIT else len(tuple(iterations)) for s in solvers) \
        * len(tuple(substeps))
    builds = (sum(1 if s in EXPLICIT else len(tuple(iterations)) for s in solvers)
              if measure else 0)
    total = 1 + runs + builds
    tell = progress or (lambda done, total, what: None)
    ref = mt.simulate(cm, t_stop, params=params, rtol=1e-10, atol=1e-12, t_out=grid)
    tell(1, total, "reference run")
    if outputs is None:
        outputs = [s for s in cm.state_names if s in ref.names] or list(ref.names)
    missing = [o for o in outputs if o not in ref.names]
    if missing:
        raise SimulationError(f"rtcheck: model '{cm.name}' logs no variable "
                              f"{', '.join(missing)}.", variables=missing)
    R = np.vstack([ref[o] for o in outputs])

    # stiffness at points of the reference
    X0, z0, _ = initialize(cm, p, 0.0)
    points = [(0.0, X0, z0)]
    if all(s in ref.names for s in cm.state_names):
        for k in np.linspace(0, len(ref.t) - 1, 6).astype(int)[1:]:
            Xk = np.array(X0, dtype=float).copy()
            Xk[:cm.nx] = [ref[s][k] for s in cm.state_names]
            points.append((float(ref.t[k]), Xk, z0))
    eigs = jacobian_eigenvalues(cm, p, points)
    stiffness = _stiffness(eigs, T, solvers)

    candidates: list[Candidate] = []
    for solver in solvers:
        its = (None,) if solver in EXPLICIT else tuple(iterations)
        for it in its:
            for m in substeps:
                h = T / m
                try:
                    run = mt.simulate(cm, t_stop, solver=solver, dt=h, params=params,
                                      iterations=it or 1, newton="count")
                    idx = np.arange(0, len(run.t), m * stride)
                    F = np.vstack([run[o][idx] for o in outputs])
                    err = _max_error(F, R) if F.shape == R.shape else math.inf
                except RunTooLargeError:
                    raise                 # not a divergence: the check is too long
                except SimulationError:
                    err = math.inf
                candidates.append(Candidate(solver, h, it, m, err,
                                            _stable(solver, h, eigs)))
                tell(1 + len(candidates), total, f"{solver} dt {h:.3g} s")
    _timing(cm, candidates, params, measure, timing_steps, workdir, rate,
            lambda k, what: tell(1 + runs + k, total, what))
    for c in candidates:
        c.ok = (c.max_error <= tolerance
                and (c.margin is None or c.margin >= min_margin))
    recommended, reasons = _recommend(candidates, stiffness, tolerance, min_margin, T)
    return RTCheck(model=cm.name, rate=float(rate), t_stop=t_stop, tolerance=tolerance,
                   min_margin=min_margin, outputs=list(outputs),
                   reference={"solver": ref.stats.solver, "rtol": 1e-10, "atol": 1e-12,
                              "points": int(len(grid)), "steps": ref.stats.steps},
                   zero_crossings=dict(ref.stats.events), event_times=dict(ref.event_times),
                   eigenvalues=list(eigs), stiffness=stiffness, candidates=candidates,
                   recommended=recommended, reasons=reasons)


def _stiffness(eigs: np.ndarray, T: float, solvers) -> dict:
    if eigs.size == 0:
        return {"fastest": None, "slowest": None, "ratio": None, "fastest_time_constant": None,
                "stable_step": {}, "explicit_stable_at_rate": True}
    re = np.abs(eigs.real)
    decaying = re[re > 0]
    fastest = eigs[np.argmax(np.abs(eigs))]
    slowest = decaying.min() if decaying.size else None
    ratio = float(decaying.max() / decaying.min()) if decaying.size else None
    limits = {s: stable_step(s, eigs, h_max=T) for s in solvers}
    explicit_ok = any(limits[s] >= T for s in solvers if s in EXPLICIT)
    return {"fastest": [float(fastest.real), float(fastest.imag)],
            "fastest_text": _describe_eig(complex(fastest)),
            "slowest_rate": None if slowest is None else float(slowest),
            "ratio": ratio,
            "fastest_time_constant": float(1.0 / np.abs(fastest)),
            "h_lambda_at_rate": float(np.abs(fastest) * T),
            "stable_step": {s: float(v) for s, v in limits.items()},
            "explicit_stable_at_rate": bool(explicit_ok)}


def _timing(cm, candidates, params, measure, steps, workdir, rate, tell=None) -> None:
    """ns per step of the compiled C of each (solver, iterations), and the margins."""
    if not measure:
        return
    from mechatron.codegen import build, generate_c, measure_ns_per_step
    cache: dict = {}
    with tempfile.TemporaryDirectory(prefix="mechatron_rtcheck_") as tmp:
        base = Path(workdir) if workdir is not None else Path(tmp)
        for c in candidates:
            key = (c.solver, c.iterations)
            if key not in cache:
                d = base / f"{c.solver}_{c.iterations or 0}"
                code = generate_c(cm, d, solver=c.solver, dt=c.dt,
                                  iterations=c.iterations or 1, params=params)
                build(code)
                cache[key] = measure_ns_per_step(code, steps=steps)["ns_per_step"]
                if tell is not None:
                    tell(len(cache), f"C of {c.solver} built and timed")
            c.ns_per_step = cache[key]
            c.margin = 1.0 - c.steps_per_period * c.ns_per_step * 1e-9 * rate


def _recommend(candidates, stiffness, tolerance, min_margin, T):
    reasons = []
    fast = stiffness.get("fastest_text")
    if fast is not None:
        limits = stiffness["stable_step"]
        rk = {s: limits[s] for s in EXPLICIT if s in limits}
        reasons.append(f"fastest eigenvalue {fast} (time constant "
                       f"{stiffness['fastest_time_constant']:.3g} s); at the sample step "
                       f"T = {T:.3g} s, h|lambda| = {stiffness['h_lambda_at_rate']:.3g}"
                       + (f"; stiffness ratio {stiffness['ratio']:.3g}"
                          if stiffness.get("ratio") else ""))
        if rk:
            best = max(rk, key=rk.get)
            if stiffness["explicit_stable_at_rate"]:
                reasons.append(f"explicit methods are stable at T ({best} up to "
                               f"{rk[best]:.3g} s): the model is not stiff at this rate, "
                               "so an explicit method (no Newton iterations) is preferred")
            else:
                reasons.append(f"explicit methods need h <= {rk[best]:.3g} s ({best}) for "
                               f"stability, {T / rk[best]:.3g}x smaller than T: the model is "
                               "stiff at this rate, so an implicit method is recommended "
                               "(backward Euler and ode14x damp the fast modes; the "
                               "trapezoidal rule keeps them ringing)")
    else:
        reasons.append("no continuous states with dynamics: any method is exact")
    ok = [c for c in candidates if c.ok]
    if not ok:
        reasons.append(f"no configuration meets error <= {tolerance:g}"
                       + (f" with margin >= {min_margin:.0%}" if any(
                           c.margin is not None for c in candidates) else "")
                       + "; lower the rate, relax the tolerance, or simplify the model")
        finite = [c for c in candidates if math.isfinite(c.max_error)]
        return (min(finite, key=lambda c: c.max_error) if finite else None), reasons
    prefer_explicit = stiffness.get("explicit_stable_at_rate", True)
    pool = [c for c in ok if c.explicit == prefer_explicit] or ok

    def cost(c):
        per_step = c.ns_per_step if c.ns_per_step is not None else 1.0
        return (c.steps_per_period * per_step, c.iterations or 0, c.max_error)

    best = min(pool, key=cost)
    text = (f"recommended: {best.solver}, step {best.dt:.3g} s "
            f"({best.steps_per_period} per sample)"
            + (f", {best.iterations} Newton iteration(s)" if best.iterations else "")
            + f": error {best.max_error:.2e} <= {tolerance:g}")
    if best.margin is not None:
        text += f", {best.ns_per_step:.0f} ns per step, margin {best.margin:.1%} of the period"
    reasons.append(text)
    return best, reasons
