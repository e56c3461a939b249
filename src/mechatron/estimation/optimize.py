"""Response optimization: tune design variables (controller gains) to meet requirements
(the seed's section 6.4, Simulink Design Optimization's Response Optimizer).

Requirements
------------
* :class:`StepResponse` on a signal: the envelope of Simulink's "Check Step Response
  Characteristics" block. With ``y0`` the initial and ``yf`` the final value and
  ``A = yf - y0``::

      lower(t) = y0 + (rise_pct/100) A      for rise_time <= t < settling_time
               = yf - (settling_pct/100) |A| for t >= settling_time
      upper(t) = yf + (overshoot_pct/100) |A| for t < settling_time
               = yf + (settling_pct/100) |A| for t >= settling_time

  (written for a positive step; mirrored for a negative one).
* :class:`SignalBound`: ``lower <= y(t) <= upper`` over a time window (e.g. ``|i| <= 3 A``).
* :class:`Tracking`: the integral of the squared error to a reference, the objective.

Every requirement is imposed on every point of the evaluation grid, so the problem is a
nonlinear program with two design variables and a few thousand inequality constraints;
it is solved by sequential quadratic programming (SciPy's SLSQP) with exact gradients from
the forward sensitivities of the trajectory (:mod:`.discretize`). Without a
:class:`Tracking` requirement, the objective is the squared error to the step's final
value, which makes the fastest response that meets the envelope the optimum.

:func:`verify` re-simulates the result with ``mechatron.simulate`` (variable-step CVODES,
not the optimizer's fixed-grid Radau) and measures rise time, overshoot, settling time and
signal bounds on a fine grid with plain NumPy.
"""

from __future__ import annotations

import logging
import math
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

import mechatron as mt
from mechatron._io import save_figure
from mechatron.errors import ParameterError
from mechatron.estimation.bounds import at_bounds, check_bounds, describe_at_bounds
from mechatron.estimation.discretize import Trajectory, choose_substeps, fastest_time_constant

log = logging.getLogger(__name__)

__all__ = ["DesignVariable", "StepResponse", "SignalBound", "Tracking", "ResponseProblem",
           "ResponseResult", "optimize_response", "verify", "step_metrics"]


@dataclass
class DesignVariable:
    """A tunable parameter: path, starting value, bounds, scale (SI)."""

    name: str
    initial: float | None = None
    min: float = -math.inf
    max: float = math.inf
    scale: float | None = None

    def __post_init__(self):
        check_bounds(self, "design variable")


@dataclass
class StepResponse:
    """Step-response envelope on ``signal`` (see the module docstring)."""

    signal: str
    final: float
    initial: float = 0.0
    t_step: float = 0.0
    rise_time: float = math.inf
    rise_pct: float = 80.0
    overshoot_pct: float = 5.0
    settling_time: float = math.inf
    settling_pct: float = 2.0

    def envelope(self, t: np.ndarray):
        A = self.final - self.initial
        s = 1.0 if A >= 0 else -1.0
        a = abs(A)
        tt = t - self.t_step
        lo = np.full(t.shape, -np.inf)
        hi = np.full(t.shape, np.inf)
        rising = (tt >= self.rise_time) & (tt < self.settling_time)
        settled = tt >= self.settling_time
        before = (tt >= 0) & (tt < self.settling_time)
        # in units of the positive step s*(y - y0)
        lo[rising] = self.rise_pct / 100 * a
        lo[settled] = a - self.settling_pct / 100 * a
        hi[before] = a + self.overshoot_pct / 100 * a
        hi[settled] = a + self.settling_pct / 100 * a
        return s, lo, hi

    def describe(self) -> str:
        return (f"{self.signal}: step {self.initial:g} -> {self.final:g}; rise "
                f"{self.rise_pct:g}% by {self.rise_time:g} s, overshoot <= "
                f"{self.overshoot_pct:g}%, settle {self.settling_pct:g}% by "
                f"{self.settling_time:g} s")


@dataclass
class SignalBound:
    """``lower <= signal(t) <= upper`` for ``t_start <= t <= t_end``."""

    signal: str
    lower: float = -math.inf
    upper: float = math.inf
    t_start: float = 0.0
    t_end: float = math.inf

    def describe(self) -> str:
        return f"{self.lower:g} <= {self.signal} <= {self.upper:g}"


@dataclass
class Tracking:
    """Minimize ``weight * integral (signal - reference)^2 dt`` (``reference``: a number
    or a function of time)."""

    signal: str
    reference: object = 0.0
    weight: float = 1.0

    def values(self, t):
        return np.asarray(self.reference(t) if callable(self.reference)
                          else np.full(t.shape, float(self.reference)), dtype=float)


class ResponseProblem:
    """Model, design variables, requirements and the evaluation grid.

    ``signals`` maps the requirement's signal names to logged variables of the model (by
    default a signal name is a variable path). The evaluation grid has ``n_points`` points
    over ``[0, t_stop]`` and ``n_points / 4`` more over its first 2% (where a step's fast
    transients, e.g. the current peak, are). Each constraint is tightened by ``margin``
    (relative to the requirement's size) so that the optimum, which sits on an active
    bound, still meets it when re-simulated on a finer grid by another solver."""

    def __init__(self, model, design, requirements, *, t_stop: float, n_points: int = 1001,
                 signals=None, fixed=None, substeps: int | None = None, jit="auto",
                 margin: float = 1e-3):
        from mechatron.estimation.native import compiler
        self.cm = model if isinstance(model, mt.CompiledModel) else mt.compile_model(model)
        cm = self.cm
        self.design = [d if isinstance(d, DesignVariable) else DesignVariable(**d)
                       if isinstance(d, dict) else DesignVariable(d) for d in design]
        self.requirements = list(requirements)
        self.signals = dict(signals or {})
        self.margin = float(margin)
        # uniform, plus a dense start: fast transients (current peaks) follow the step
        self.t = np.unique(np.concatenate([np.linspace(0.0, t_stop, n_points),
                                           np.linspace(0.0, 0.02 * t_stop, n_points // 4)]))
        self.base = cm.parameter_vector(fixed or {})
        pindex = {n: i for i, n in enumerate(cm.param_names)}
        problems = []
        for d in self.design:
            if d.name not in pindex:
                problems.append(f"design variable '{d.name}' is not a parameter of "
                                f"'{cm.name}': {cm.not_a_parameter(d.name)}")
                continue
            if d.initial is None:
                d.initial = float(self.base[pindex[d.name]])
            if d.scale is None:
                d.scale = abs(d.initial) or 1.0
        names = sorted({r.signal for r in self.requirements})
        for s in names:
            if self.signals.get(s, s) not in cm.names:
                problems.append(f"requirement signal '{s}' is not a logged variable of "
                                f"'{cm.name}'.")
        if problems:
            raise ParameterError(" ".join(problems), problems=problems, path=cm.name)
        self.signal_names = names
        p0 = self.parameters(self.x0)
        if substeps is None:
            tau = fastest_time_constant(cm, p0, np.asarray(cm.x_start[:cm.nx]))
            substeps = choose_substeps(float(np.diff(self.t).max()), tau, ratio=1.0,
                                       where=f"{cm.name}: evaluation grid")
        self.substeps = substeps
        use_jit = (n_points * substeps >= 4000 and compiler() is not None) \
            if jit == "auto" else bool(jit)
        self.traj = Trajectory(cm, self.t, [], [cm.names.index(self.signals.get(s, s))
                                               for s in names],
                               substeps=substeps, jit=use_jit)
        self.D = np.zeros((cm.p0.size, len(self.design)))
        for j, d in enumerate(self.design):
            self.D[pindex[d.name], j] = 1.0
        self._sens = self.traj.sensitivity_function(self.D)
        self._cache = {}

    @property
    def x0(self) -> np.ndarray:
        return np.array([d.initial for d in self.design])

    @property
    def scales(self) -> np.ndarray:
        return np.array([d.scale for d in self.design])

    def parameters(self, x) -> np.ndarray:
        p = self.base.copy()
        for d, v in zip(self.design, x):
            p[self.cm.param_names.index(d.name)] = v
        return p

    def evaluate(self, x):
        """Signals ``{name: y}`` and their derivatives ``{name: dy/dx (N, q)}`` at ``x``."""
        key = tuple(np.round(np.asarray(x, dtype=float), 15))
        if key in self._cache:
            return self._cache[key]
        q = len(self.design)
        Y, dY = self._sens(self.parameters(x), np.asarray(self.cm.x_start[:self.cm.nx]),
                           np.zeros((0, self.t.size)), np.zeros((self.cm.nx, q)))
        n = len(self.signal_names)
        ys = {s: Y[r] for r, s in enumerate(self.signal_names)}
        ds = {s: dY[r::n, :].T for r, s in enumerate(self.signal_names)}
        self._cache = {key: (ys, ds)}
        return ys, ds

    # -- the nonlinear program -------------------------------------------------------------
    def objective(self, x):
        ys, ds = self.evaluate(x)
        dt = np.gradient(self.t)
        f, g = 0.0, np.zeros(len(self.design))
        tracks = [r for r in self.requirements if isinstance(r, Tracking)]
        if not tracks:
            tracks = [Tracking(r.signal, r.final, 1.0) for r in self.requirements
                      if isinstance(r, StepResponse)]
        for r in tracks:
            e = ys[r.signal] - r.values(self.t)
            norm = max(float(np.max(np.abs(r.values(self.t)))), 1e-12) ** 2 * self.t[-1]
            f += r.weight * float(np.sum(e ** 2 * dt)) / norm
            g += r.weight * 2 * (e * dt) @ ds[r.signal] / norm
        return f, g

    def constraints(self, x):
        """``c(x) >= 0`` (scaled by each requirement's size) and its Jacobian."""
        ys, ds = self.evaluate(x)
        cs, js = [], []
        for r in self.requirements:
            y, dy = ys[r.signal], ds[r.signal]
            if isinstance(r, StepResponse):
                s, lo, hi = r.envelope(self.t)
                a = max(abs(r.final - r.initial), 1e-12)
                z = s * (y - r.initial)
                dz = s * dy
                m = np.isfinite(lo)
                cs.append((z[m] - lo[m]) / a)
                js.append(dz[m] / a)
                m = np.isfinite(hi)
                cs.append((hi[m] - z[m]) / a)
                js.append(-dz[m] / a)
            elif isinstance(r, SignalBound):
                w = (self.t >= r.t_start) & (self.t <= r.t_end)
                size = max(abs(r.lower) if math.isfinite(r.lower) else 0.0,
                           abs(r.upper) if math.isfinite(r.upper) else 0.0, 1e-12)
                if math.isfinite(r.upper):
                    cs.append((r.upper - y[w]) / size)
                    js.append(-dy[w] / size)
                if math.isfinite(r.lower):
                    cs.append((y[w] - r.lower) / size)
                    js.append(dy[w] / size)
        if not cs:
            return np.zeros(0), np.zeros((0, len(self.design)))
        return np.concatenate(cs) - self.margin, np.vstack(js)


@dataclass
class ResponseResult:
    names: list
    initial: np.ndarray
    values: np.ndarray
    objective_initial: float
    objective: float
    max_violation_initial: float
    max_violation: float
    history: list
    iterations: int
    wall_time: float
    success: bool
    message: str
    problem: ResponseProblem = field(repr=False, default=None)
    #: Design variables that ended on a bound: ``{name: {"side", "bound"}}`` (see
    #: :func:`~mechatron.estimation.bounds.at_bounds`); such a value is not an interior
    #: optimum.
    at_bound: dict = field(default_factory=dict)
    #: Requirements whose constraints are active at the optimum (slack below 1e-3 of
    #: their size): they, not the objective alone, decide the gains.
    active: list = field(default_factory=list)

    @property
    def parameters(self) -> dict:
        return dict(zip(self.names, map(float, self.values)))

    def to_dict(self) -> dict:
        return {"parameters": self.parameters,
                "initial": dict(zip(self.names, map(float, self.initial))),
                "at_bound": self.at_bound, "active": self.active,
                "objective_initial": self.objective_initial, "objective": self.objective,
                "max_violation_initial": self.max_violation_initial,
                "max_violation": self.max_violation, "iterations": self.iterations,
                "wall_time_s": self.wall_time, "success": self.success,
                "message": self.message,
                "trajectory": [{"iteration": h["iteration"], "objective": h["objective"],
                                "max_violation": h["max_violation"],
                                "parameters": dict(zip(self.names, h["x"]))}
                               for h in self.history]}

    def plot(self, path, verification: dict | None = None) -> Path:
        """Signals before and after with the requirement bounds."""
        from matplotlib.figure import Figure
        prob = self.problem
        before, _ = prob.evaluate(self.initial)
        after, _ = prob.evaluate(self.values)
        sigs = prob.signal_names
        fig = Figure(figsize=(8, 2.4 * len(sigs) + 0.8), layout="constrained")
        axes = fig.subplots(len(sigs), 1, sharex=True, squeeze=False)[:, 0]
        for ax, s in zip(axes, sigs):
            ax.plot(prob.t, before[s], "--", color="tab:red", label="start")
            ax.plot(prob.t, after[s], "-", color="tab:blue", label="optimized")
            for r in prob.requirements:
                if r.signal != s:
                    continue
                if isinstance(r, StepResponse):
                    sg, lo, hi = r.envelope(prob.t)
                    ax.plot(prob.t, r.initial + sg * lo, ":", color="k", lw=1)
                    ax.plot(prob.t, r.initial + sg * hi, ":", color="k", lw=1,
                            label="envelope")
                elif isinstance(r, SignalBound):
                    for v in (r.lower, r.upper):
                        if math.isfinite(v):
                            ax.axhline(v, color="k", ls=":", lw=1)
            unit = prob.cm.units[prob.cm.names.index(prob.signals.get(s, s))]
            ax.set_ylabel(f"{s} [{unit or '1'}]")
            ax.grid(True, alpha=0.3)
        for ax in axes:                  # each row's own curves (envelopes differ)
            ax.legend(fontsize="small")
        axes[-1].set_xlabel("t [s]")
        fig.suptitle("response optimization")
        path = Path(path)
        save_figure(fig, path, dpi=90)
        return path


def optimize_response(problem: ResponseProblem, *, max_iterations: int = 100,
                      tol: float = 1e-9, callback=None) -> ResponseResult:
    """Solve ``problem`` with SLSQP and exact gradients; ``callback(k, x, f, viol)`` after
    each iteration."""
    from scipy.optimize import minimize
    prob = problem
    sc = prob.scales
    lo = np.array([d.min for d in prob.design]) / sc
    hi = np.array([d.max for d in prob.design]) / sc
    history = []
    start = time.perf_counter()

    def fun(z):
        f, g = prob.objective(z * sc)
        return f, g * sc

    def cons(z):
        return prob.constraints(z * sc)[0]

    def cons_jac(z):
        return prob.constraints(z * sc)[1] * sc

    def viol(x):
        c = prob.constraints(x)[0] + prob.margin
        return float(max(0.0, -c.min())) if c.size else 0.0

    def record(z):
        x = z * sc
        f = prob.objective(x)[0]
        v = viol(x)
        history.append({"iteration": len(history), "x": x.tolist(), "objective": f,
                        "max_violation": v})
        if callback is not None:
            callback(len(history) - 1, x, f, v)

    z0 = prob.x0 / sc
    record(z0)
    f0, v0 = history[0]["objective"], history[0]["max_violation"]
    sol = minimize(fun, z0, jac=True, method="SLSQP",
                   bounds=list(zip(np.where(np.isfinite(lo), lo, None),
                                   np.where(np.isfinite(hi), hi, None))),
                   constraints=[{"type": "ineq", "fun": cons, "jac": cons_jac}],
                   options={"maxiter": max_iterations, "ftol": tol}, callback=record)
    x = sol.x * sc
    if not history or history[-1]["x"] != x.tolist():
        record(sol.x)
    names = [d.name for d in prob.design]
    hits = at_bounds(names, x, [d.min for d in prob.design], [d.max for d in prob.design],
                     [d.scale for d in prob.design])
    message = str(sol.message)
    if hits:
        log.warning("optimize: %s", describe_at_bounds(hits, "gain"))
    active = active_requirements(prob, x)
    if active:
        log.info("optimize: active requirement(s), which decide the optimum: %s",
                 ", ".join(active))
    return ResponseResult(names=names, initial=prob.x0, values=x,
                          objective_initial=f0, objective=prob.objective(x)[0],
                          max_violation_initial=v0, max_violation=viol(x),
                          history=history, iterations=int(sol.nit),
                          wall_time=time.perf_counter() - start,
                          success=bool(sol.success) and viol(x) <= 1e-6,
                          message=message, problem=prob, at_bound=hits, active=active)


def _requirement_label(r) -> str:
    kind = {"StepResponse": "step envelope", "SignalBound": "bound"}.get(type(r).__name__,
                                                                       type(r).__name__)
    return f"{r.signal} {kind}"


def active_requirements(problem: ResponseProblem, x, tol: float = 1e-3) -> list[str]:
    """The requirements whose constraints hold with a slack below ``tol`` (relative to
    each requirement's size, beyond the problem's ``margin``) at ``x``: the optimum sits on them, so relaxing one changes
    it (a Lagrange multiplier would be nonzero). Tracking objectives are never active."""
    import copy
    out = []
    for r in problem.requirements:
        if isinstance(r, Tracking):
            continue
        one = copy.copy(problem)
        one.requirements = [r]
        c = one.constraints(np.asarray(x, dtype=float))[0]      # tightened by margin
        if c.size and float(c.min()) <= tol:
            out.append(_requirement_label(r))
    return out


# ---------------------------------------------------------------------- verification
def step_metrics(t, y, y0: float, yf: float, settling_pct: float = 2.0) -> dict:
    """Rise time (10-90%), overshoot (% of the step), settling time (last exit from the
    +-settling_pct band), from samples: plain NumPy, no solver involved."""
    t = np.asarray(t, dtype=float)
    A = yf - y0
    z = (np.asarray(y, dtype=float) - y0) / A
    def first(level):
        k = np.flatnonzero(z >= level)
        if not k.size:
            return math.inf
        k = k[0]
        if k == 0:
            return float(t[0])
        return float(np.interp(level, [z[k - 1], z[k]], [t[k - 1], t[k]]))
    outside = np.flatnonzero(np.abs(z - 1) > settling_pct / 100)
    settle = float(t[min(outside[-1] + 1, len(t) - 1)]) if outside.size else float(t[0])
    if outside.size and outside[-1] == len(t) - 1:
        settle = math.inf
    return {"rise_time_s": first(0.9) - first(0.1),
            "overshoot_pct": float(max(0.0, (z.max() - 1) * 100)),
            "settling_time_s": settle, "final": float(y[-1])}


def verify(problem: ResponseProblem, x, *, n_points: int = 20001, rtol: float = 1e-9,
           atol: float = 1e-11) -> dict:
    """Simulate ``x`` with ``mechatron.simulate`` (CVODES) on a fine grid and check every
    requirement; returns ``{"rows": [...], "all_met": bool, "signals": {...}}``."""
    cm = problem.cm
    params = {d.name: float(v) for d, v in zip(problem.design, x)}
    params.update({n: float(v) for n, v in zip(cm.param_names, problem.base)
                   if n not in params and v != cm.p0[cm.param_names.index(n)]})
    t = np.linspace(0, problem.t[-1], n_points)
    res = mt.simulate(cm, float(problem.t[-1]), params=params, rtol=rtol, atol=atol,
                      t_out=t)
    sig = {s: np.asarray(res[problem.signals.get(s, s)]) for s in problem.signal_names}
    rows = []
    for r in problem.requirements:
        y = sig[r.signal]
        if isinstance(r, StepResponse):
            m = step_metrics(t - r.t_step, y, r.initial, r.final, r.settling_pct)
            tr_ = first_crossing(t - r.t_step, (y - r.initial) / (r.final - r.initial),
                                 r.rise_pct / 100)
            rows.append({"requirement": f"{r.signal} overshoot", "value": m["overshoot_pct"],
                         "limit": r.overshoot_pct, "unit": "%",
                         "met": m["overshoot_pct"] <= r.overshoot_pct + 1e-6})
            if math.isfinite(r.rise_time):
                rows.append({"requirement": f"{r.signal} reaches {r.rise_pct:g}%",
                             "value": tr_, "limit": r.rise_time, "unit": "s",
                             "met": tr_ <= r.rise_time})
            if math.isfinite(r.settling_time):
                rows.append({"requirement": f"{r.signal} settling ({r.settling_pct:g}%)",
                             "value": m["settling_time_s"], "limit": r.settling_time,
                             "unit": "s", "met": m["settling_time_s"] <= r.settling_time})
        elif isinstance(r, SignalBound):
            w = (t >= r.t_start) & (t <= r.t_end)
            if math.isfinite(r.upper):
                v = float(np.max(y[w]))
                rows.append({"requirement": f"max {r.signal}", "value": v, "limit": r.upper,
                             "unit": "", "met": v <= r.upper})
            if math.isfinite(r.lower):
                v = float(np.min(y[w]))
                rows.append({"requirement": f"min {r.signal}", "value": v, "limit": r.lower,
                             "unit": "", "met": v >= r.lower})
    return {"rows": rows, "all_met": all(r["met"] for r in rows), "t": t, "signals": sig}


def first_crossing(t, z, level) -> float:
    k = np.flatnonzero(np.asarray(z) >= level)
    if not k.size:
        return math.inf
    k = k[0]
    return float(t[k]) if k == 0 else float(np.interp(level, [z[k - 1], z[k]],
                                                      [t[k - 1], t[k]]))
