"""Sampled trajectories of a compiled model as CasADi functions with exact derivatives.

Estimation, sensitivity analysis and response optimization all need the same thing: the
model outputs at the sample times of an experiment, as a function of the parameter vector
``p`` and the initial state ``x0``, with exact derivatives. This module builds it:

* Some entries of ``p`` are *inputs*: they are overwritten at every instant by a measured
  signal (e.g. ``source.V`` driven by the logged voltage). Between samples ``t_k`` and
  ``t_{k+1}`` an input is held (``"zoh"``, what a DAC does) or interpolated linearly
  (``"linear"``).
* Each sample interval ``h_k = t_{k+1} - t_k`` is split in ``m`` equal substeps of the
  3-stage Radau IIA method (order 5, L-stable, stiffly accurate): stage values ``X_i`` at
  ``t + c_i h`` solve ``X_i = x + h sum_j a_ij f(t + c_j h, X_j)`` and ``x_next = X_3``.
  The stage equations are solved by Newton's method to a tolerance (CasADi
  ``fast_newton``; a model linear in its states converges in one iteration). With the
  step no larger than the fastest time constant the local error is below 1e-4 of a
  decaying mode.
* Derivatives: :meth:`Trajectory.sensitivities` propagates the forward sensitivities
  ``S = dx/dtheta`` through every substep by the implicit function theorem,
  ``G_K dK = -(G_x S + G_p D)`` with ``G`` the stage residual at the converged stages:
  exact derivatives of the discrete trajectory, in one native pass. (CasADi's own AD
  through the rootfinder gives the same numbers, several times slower; the tests compare
  the two.)
* Convergence: after the rootfinder, each substep computes the correction one more
  Newton iteration would make, per stage value, in units of
  ``1e-10 + 1e-6 |K| + 1e-3 |K - x|`` (as the fixed-step solvers,
  :data:`mechatron.solvers.fixed.NEWTON_ATOL`); the largest per state and sample comes
  out with the trajectory, and a value above 1 is a
  :class:`~mechatron.errors.SimulationError` naming the sample interval and the states,
  never a result (an unconverged stage once gave a speed of 147 rad/s where 23.7 was
  right, and the fit was silently wrong).
* One sample step is stepped over the experiment by a C loop (``templates/trajectory.c``)
  that calls the step and the outputs compiled to native code, or, without a C compiler,
  by CasADi's ``mapaccum`` and ``map`` (the same numbers: the tests compare the two
  loops bit for bit). No Python runs per step.

Events
------
A model with events (``mt.sample`` clocks, discrete states, ``mt.when``, relations) is
integrated as the fixed-step solvers do it, with Radau substeps: the modes, event
counters and event times ride along with the states, the continuous dynamics read the
modes, and at the end of every substep the compiled event iteration
(``CompiledModel.f_events``) fires the clocks that are due and the conditions that became
true, applies their actions and re-reads the relations. At a sample instant the actions
read the input's new sample. The sensitivities pass through each event by the chain rule,
``S+ = dg/dx S- + dg/dp D`` with ``g`` the event map (CasADi AD through the iteration,
saturations included), computed along the ``q`` directions of ``[S-; D]`` (one forward
sweep each), not as the two Jacobians.

* **Time events** (clock ticks, relations of time, discrete states, inputs held by a
  zero-order hold) are exact, value and sensitivity, when their instants are substep ends:
  clock ticks and the switching times of relations of time are checked against the
  substep grid (:meth:`Trajectory.check_ticks`; one between substeps is an error, not a
  late update). At a fixed event time ``dg/dtheta`` is the whole sensitivity jump.
* **State events** (a relation whose distance moves with the continuous states, such as
  ``sign(v)`` or a ``Saturation`` block on a state; with ``hold="linear"`` also one on an
  input) would be found one substep late, with a sensitivity that misses the jump of the
  event time. They are refused unless the user switches on the smooth approximation
  ``smooth=w``: in the continuous dynamics the mode ``s`` of every such relation is
  replaced by ``tanh(d / w)`` (``d`` the relation's distance, in its own unit; a relation
  ``a < b`` then has the value ``(1 + tanh((b - a) / w)) / 2``). The approximation differs
  from the switched model by the width ``w``; choose it small against the signal's range
  and check the substeps resolve it (they are chosen from the stiffness it adds).

Limitations: algebraic loops left to a DAE solver are refused with a
:class:`~mechatron.errors.ModelError`; a clock period that is itself estimated is not
supported (its ticks would move with the parameter).
"""

from __future__ import annotations

import ctypes
import math
from dataclasses import dataclass
from importlib import resources

import casadi as ca
import numpy as np

import mechatron.estimation.native as _native
from mechatron.compiler.compiled import CompiledModel
from mechatron.compiler.relations import _is_unary
from mechatron.errors import DataError, ModelError, SimulationError
from mechatron.estimation.native import native
from mechatron.solvers.fixed import NEWTON_ATOL, NEWTON_RTOL, NEWTON_STEP
from mechatron.solvers.native import BuildError, build_library

__all__ = ["Trajectory", "fastest_time_constant", "choose_substeps", "check_model",
           "noise_level", "grid_fits"]

# Radau IIA, 3 stages (order 5)
_S6 = math.sqrt(6.0)
_A = (((88 - 7 * _S6) / 360, (296 - 169 * _S6) / 1800, (-2 + 3 * _S6) / 225),
      ((296 + 169 * _S6) / 1800, (88 + 7 * _S6) / 360, (-2 - 3 * _S6) / 225),
      ((16 - _S6) / 36, (16 + _S6) / 36, 1 / 9))
_C = ((4 - _S6) / 10, (4 + _S6) / 10, 1.0)


def check_model(cm: CompiledModel, what: str = "estimation") -> None:
    """Refuse models this module cannot differentiate through (algebraic loops)."""
    if cm.nz:
        raise ModelError(
            f"model '{cm.name}': {cm.nz} algebraic unknown(s) left to a DAE solver "
            f"({', '.join(cm.alg_names[:4])}); {what} needs an ODE model. Make the "
            f"nonlinear loop explicit (a state, or a small lag) or solve it by hand.",
            path=cm.name)


def _dist_symbols(cm: CompiledModel):
    key = "est_dist"
    if key not in cm._cache:
        t = ca.SX.sym("t")
        X = ca.SX.sym("X", cm.nX)
        p = ca.SX.sym("p", cm.p0.size)
        d = cm.f_dist(t, X, ca.SX(0, 1), p)[0] if cm.nr else ca.SX(0, 1)
        cm._cache[key] = (t, X, p, d)
    return cm._cache[key]


def discrete_states(cm: CompiledModel) -> list[int]:
    """Indices of the states that only events change (a zero derivative)."""
    key = "est_discrete"
    if key not in cm._cache:
        X = ca.SX.sym("X", cm.nX)
        f = cm.f_ode(ca.SX.sym("t"), X, ca.SX(0, 1), ca.SX.sym("p", cm.p0.size))
        cm._cache[key] = [i for i in range(cm.nx) if ca.SX(f[i]).is_zero()]
    return cm._cache[key]


def state_event_relations(cm: CompiledModel, input_index=(), hold: str = "zoh") -> list[int]:
    """Indices of the relations that are state events: the distance moves between
    events (it depends on a continuous state, or with ``hold="linear"`` on an input) and
    the mode acts on the dynamics or on another relation (a when condition, a nested
    relation). Clocks, when memories, relations of time, parameters, discrete states and
    held inputs are time events; a relation read only by the outputs is exact at the
    samples (its mode is re-read at every substep end)."""
    if not cm.nr:
        return []
    t, X, p, d = _dist_symbols(cm)
    disc = set(discrete_states(cm))
    moving = [X[i] for i in range(cm.nx) if i not in disc]
    if hold == "linear":
        moving += [p[i] for i in input_index]
    if not moving:
        return []
    f = cm.f_ode(t, X, ca.SX(0, 1), p)[:cm.nx]
    out = []
    for k, (_owner, op) in enumerate(cm.relations):
        mode = X[cm.nx + k]
        acts = ca.depends_on(f, mode) or ca.depends_on(d, mode)
        if op in ("<", "<=", "sign") and acts and ca.depends_on(d[k], ca.vertcat(*moving)):
            out.append(k)
    return out


def _blended_ode(cm: CompiledModel) -> ca.Function:
    """``f_ode`` with its logic made arithmetic: ``if_else(c, a, b)`` as
    ``c a + (1 - c) b``, ``not c`` as ``1 - c``, ``and`` as a product, ``or`` as
    ``a + b - a b``. Identical for conditions that are 0 or 1; with a relation's value
    smoothed into (0, 1) the branches blend instead of one being picked."""
    key = "est_blended"
    if key not in cm._cache:
        t = ca.SX.sym("t")
        X = ca.SX.sym("X", cm.nX)
        p = ca.SX.sym("p", cm.p0.size)
        f = cm.f_ode(t, X, ca.SX(0, 1), p)[:cm.nx]
        syms = [t, X, p]
        g = ca.Function("scan", syms, [f])
        work = {}
        outs = [None] * cm.nx
        for k in range(g.n_instructions()):
            op = g.instruction_id(k)
            o = g.instruction_output(k)
            i = g.instruction_input(k)
            if op == ca.OP_INPUT:
                work[o[0]] = syms[i[0]][i[1]]
            elif op == ca.OP_CONST:
                work[o[0]] = ca.SX(g.instruction_constant(k))
            elif op == ca.OP_OUTPUT:
                outs[o[1]] = work[i[0]]
            elif op == ca.OP_IF_ELSE_ZERO:
                work[o[0]] = work[i[0]] * work[i[1]]
            elif op == ca.OP_NOT:
                work[o[0]] = 1 - work[i[0]]
            elif op == ca.OP_AND:
                work[o[0]] = work[i[0]] * work[i[1]]
            elif op == ca.OP_OR:
                work[o[0]] = work[i[0]] + work[i[1]] - work[i[0]] * work[i[1]]
            elif _is_unary(op):
                work[o[0]] = ca.SX.unary(op, work[i[0]])
            else:
                work[o[0]] = ca.SX.binary(op, work[i[0]], work[i[1]])
        outs = [ca.SX(0) if e is None else e for e in outs]
        cm._cache[key] = ca.Function("blended_ode", syms, [ca.vertcat(*outs)])
    return cm._cache[key]


def _any_of(flags) -> ca.SX:
    out = ca.SX(0)
    for f in flags:
        out = ca.logic_or(out, f)
    return out


def clocks(cm: CompiledModel, p) -> list[tuple[int, float, float]]:
    """``(relation index, period, offset)`` of every clock at the parameter values ``p``
    (read from the clock's distance ``t - (offset + c period)`` at ``c = 0`` and 1)."""
    out = []
    ks = [k for k, (_o, op) in enumerate(cm.relations) if op == "clock"]
    if not ks:
        return out
    nx, nr = cm.nx, cm.nr
    X = np.zeros(cm.nX)
    d0 = np.array(cm.f_dist(0.0, X, np.zeros(0), p)[0], dtype=float).ravel()
    X[nx + nr:nx + 2 * nr] = 1.0
    d1 = np.array(cm.f_dist(0.0, X, np.zeros(0), p)[0], dtype=float).ravel()
    for k in ks:
        out.append((k, float(d0[k] - d1[k]), float(-d0[k])))
    return out


def fastest_time_constant(cm: CompiledModel, p: np.ndarray, x: np.ndarray,
                          quantile: float = 0.1) -> float:
    """``1 / max |lambda|`` of the state Jacobian ``df/dx`` at ``(x, p)``.

    ``x`` may be a matrix of states (one per column, e.g. along a trajectory): the result
    is then the ``quantile`` of the per-state values, so that a stiff region crossed in a
    moment (friction at standstill) does not set the step for the whole run; the
    L-stable Radau method damps such modes whatever the step. ``inf`` for no dynamics.
    """
    check_model(cm)
    key = "est_jac"
    jf = cm._cache.get(key)
    if jf is None:
        xs = ca.SX.sym("x", cm.nx)
        ps = ca.SX.sym("p", cm.p0.size)
        # modes +1, counters and event times 0 (the continuous dynamics between events)
        rest = ca.vertcat(ca.DM.ones(cm.nr), ca.DM.zeros(2 * cm.nr))
        f = cm.f_ode(0.0, ca.vertcat(xs, rest), ca.SX(0, 1), ps)[:cm.nx]
        jf = cm._cache[key] = ca.Function("state_jacobian", [xs, ps], [ca.jacobian(f, xs)])
    X = np.asarray(x, dtype=float).reshape(cm.nx, -1)
    taus = []
    for col in X.T:
        a = np.array(jf(col, p), dtype=float)
        if a.size == 0:
            return math.inf
        lam = np.abs(np.linalg.eigvals(a))
        lam = lam[np.isfinite(lam)]
        taus.append(1.0 / lam.max() if lam.size and lam.max() > 0 else math.inf)
    finite = [v for v in taus if math.isfinite(v)]
    if not finite:
        return math.inf
    return float(np.quantile(finite, quantile)) if len(finite) > 1 else finite[0]


def choose_substeps(h_max: float, tau_min: float, *, ratio: float = 1.0,
                    max_substeps: int = 400, where: str = "") -> int:
    """Substeps per sample so that each is at most ``ratio * tau_min``.

    Raises :class:`DataError` when more than ``max_substeps`` would be needed: the data are
    sampled so coarsely that the model cannot follow between samples.
    """
    if not math.isfinite(tau_min):
        return 1
    m = max(1, math.ceil(h_max / (ratio * tau_min) - 1e-9))
    if m > max_substeps:
        raise DataError(
            f"{where}: sample interval {h_max:g} s is {h_max / tau_min:.0f} times the "
            f"model's fastest time constant ({tau_min:.3g} s at the starting values); it "
            f"would need {m} substeps per sample (limit {max_substeps}). The model cannot "
            f"follow this sample rate: measure faster, or raise max_substeps.",
            path=where)
    return m


def noise_floor(y) -> float:
    """The least noise level `noise_level` gives ``y``: 1e-4 of its range (1e-12 for a
    constant)."""
    y = np.asarray(y, dtype=float)
    span = float(np.ptp(y)) if y.size else 0.0
    return 1e-4 * span if span > 0 else 1e-12


def noise_level(y) -> float:
    """Noise level of a measured signal for the discretization error test: the robust
    (median absolute deviation) standard deviation of its second differences divided by
    sqrt(6), what white noise of that level gives; a smooth signal sampled finely adds
    little to it. At least `noise_floor`, 1e-4 of the signal's range (a 14-bit sensor:
    noise-free or quantized data would otherwise ask for an error no data can show)."""
    y = np.asarray(y, dtype=float)
    floor = noise_floor(y)
    if y.size < 5:
        return max(float(np.ptp(y)) if y.size else 0.0, floor)
    d = np.diff(y, 2)
    mad = float(np.median(np.abs(d - np.median(d))))
    return max(1.4826 * mad / math.sqrt(6.0), floor)


def grid_fits(cm: CompiledModel, t, m: int, p, input_index=()) -> bool:
    """Whether every clock tick and time-relation switch of ``cm`` falls on a substep end
    of the sample grid ``t`` with ``m`` substeps (see :meth:`Trajectory.check_ticks`),
    without building the step functions."""
    probe = object.__new__(Trajectory)
    probe.cm, probe.t, probe.substeps = cm, np.asarray(t, dtype=float), int(m)
    probe.input_index = list(input_index)
    probe.events = bool(cm.nr) and cm.f_events is not None
    try:
        probe.check_ticks(p)
    except DataError:
        return False
    return True


@dataclass
class Trajectory:
    """Outputs of ``cm`` on a sample grid: ``Y = F(p, x0, U)`` as a CasADi function.

    Parameters
    ----------
    cm : CompiledModel
    t : array (N,)
        Sample times, strictly increasing.
    input_index : list of int
        Indices into ``p`` of the parameters driven by inputs (rows of ``U``).
    output_index : list of int
        Indices into the model's logged variables (``cm.names``) returned as outputs.
    substeps : int
        Radau IIA substeps per sample interval.
    hold : "zoh" or "linear"
        How an input behaves between samples.
    jit : bool
        Compile the per-sample step functions to native code
        (:func:`~mechatron.estimation.native.native`; cached on disk).
    smooth : float or None
        Width of the smooth approximation of state events (see the module docstring);
        None refuses models with state events.

    ``function(p, x0, U) -> (Y, X)``: outputs ``(n_out, N)`` and continuous states
    ``(nx, N)``; ``x0`` is the state before the events of the initial time.
    """

    cm: CompiledModel
    t: np.ndarray
    input_index: list
    output_index: list
    substeps: int = 1
    hold: str = "zoh"
    newton_tol: float = 1e-12
    jit: bool = False
    smooth: float | None = None

    def __post_init__(self):
        check_model(self.cm)
        if self.hold not in ("zoh", "linear"):
            raise DataError(f"input hold must be 'zoh' or 'linear', got {self.hold!r}.")
        if self.smooth is not None and not (isinstance(self.smooth, (int, float))
                                            and math.isfinite(self.smooth)
                                            and self.smooth > 0):
            raise DataError(f"model '{self.cm.name}': the width of the smooth event "
                            f"approximation must be a number > 0, got {self.smooth!r}.")
        self.t = np.asarray(self.t, dtype=float)
        self._sens = {}
        cm = self.cm
        self.events = bool(cm.nr) and cm.f_events is not None
        self.smoothed = state_event_relations(cm, self.input_index, self.hold)
        if self.smoothed and self.smooth is None:
            labels = cm.report.get("relation_labels") or [op for _, op in cm.relations]
            shown = "; ".join(f"{cm.relations[k][0] or cm.name}: {labels[k]}"
                              for k in self.smoothed[:4])
            raise ModelError(
                f"model '{cm.name}': {len(self.smoothed)} relation(s) switch with the "
                f"continuous states ({shown}): state events, which a sampled estimation "
                f"would place up to a substep late, with wrong sensitivities. Switch on "
                f"their smooth approximation (smooth = w: tanh(distance / w) for the "
                f"mode; [options] smooth in a problem file), or write the law smoothly "
                f"(tanh, the library's friction elements).", path=cm.name)
        self._symbols()
        self._build()

    # ------------------------------------------------------------------------------------
    def _rest0(self) -> np.ndarray:
        """Modes, counters and event times before the initial events: ordinary relations
        +1 (re-read by the event iteration), clocks and when memories -1 (so a condition
        that holds at the start rises), ``initial()`` true, ``terminal()`` false."""
        cm = self.cm
        nr = cm.nr
        modes = np.ones(nr)
        for k, (_o, op) in enumerate(cm.relations):
            if op in ("clock", "mem", "terminal"):
                modes[k] = -1.0
        modes[list(cm.report.get("when_relations", []))] = -1.0
        return np.concatenate([modes, np.zeros(nr), np.full(nr, float(self.t[0]))])

    def _symbols(self) -> None:
        """The stage residual of one substep and its rootfinder."""
        cm = self.cm
        nx, npar, nu, nr = cm.nx, cm.p0.size, len(self.input_index), cm.nr
        ns = len(_C)
        self._x = ca.SX.sym("x", nx)
        self._r = ca.SX.sym("r", 3 * nr if self.events else 0)
        self._p = ca.SX.sym("p", npar)
        self._u0 = ca.SX.sym("u0", nu)
        self._u1 = ca.SX.sym("u1", nu)
        self._h = ca.SX.sym("h")            # substep length
        self._ts = ca.SX.sym("ts")          # substep start time
        self._fa = ca.SX.sym("fa")          # substep start, as a fraction of the sample
        K = ca.SX.sym("K", ns * nx)
        res = []
        fs = []
        for i in range(ns):
            frac = self._fa + _C[i] * self._h_frac_sym()
            ti = self._ts + _C[i] * self._h
            fs.append(self._rhs(ti, K[i * nx:(i + 1) * nx], self._with_u(self._u_at(frac))))
        for i in range(ns):
            acc = 0
            for j in range(ns):
                acc = acc + _A[i][j] * fs[j]
            res.append(K[i * nx:(i + 1) * nx] - self._x - self._h * acc)
        self._K = K
        self._res = ca.vertcat(*res)
        args = [self._x, self._r, self._p, self._u0, self._u1, self._h, self._ts, self._fa,
                self._hf]
        g = ca.Function("radau_residual", [K, ca.vertcat(*args)], [self._res])
        self._newton = ca.Function("radau_correction", [K, ca.vertcat(*args)],
                                   [ca.solve(ca.jacobian(self._res, K), self._res)])
        self._solve = ca.rootfinder("radau", "fast_newton", g,
                                    {"abstol": self.newton_tol, "max_iter": 30,
                                     "error_on_fail": False})
        self._args = args
        if self.events:
            self._event_fn = self._event_function()

    def _full(self, x, r):
        """The integration state ``X = [x; modes; counters; event times]``."""
        if self.events:
            return ca.vertcat(x, r)
        return ca.vertcat(x, ca.DM.zeros(3 * self.cm.nr)) if self.cm.nr else x

    def _rhs(self, t, x, p):
        """``dx/dt`` between events, with the smoothed modes of state events."""
        cm = self.cm
        X = self._full(x, self._r)
        if not self.smoothed:
            return cm.f_ode(t, X, ca.SX(0, 1), p)[:cm.nx]
        tt, XX, pp, d = _dist_symbols(cm)
        dk = ca.substitute(ca.vertcat(*[d[k] for k in self.smoothed]),
                           ca.vertcat(tt, XX, pp), ca.vertcat(t, X, p))
        parts = list(ca.vertsplit(X))
        for j, k in enumerate(self.smoothed):
            parts[cm.nx + k] = ca.tanh(dk[j] / self.smooth)
        return _blended_ode(cm)(t, ca.vertcat(*parts), p)

    def _event_function(self) -> ca.Function:
        """``(x, r, p, u, t) -> (x+, r+, dx+/dx, dx+/dp)``: the events found at ``t``
        (input value ``u``) and the Jacobians of the new continuous state."""
        cm = self.cm
        u = ca.SX.sym("u", len(self.input_index))
        t = ca.SX.sym("t")
        pu = self._with_u(u)
        Xn = cm.f_events(t, ca.vertcat(self._x, self._r), ca.SX(0, 1), pu)
        xn = Xn[:cm.nx]
        self._event_out = (u, t, Xn)
        fire = ca.Function("sample_events", [self._x, self._r, self._p, u, t],
                           [xn, Xn[cm.nx:], ca.jacobian(xn, self._x),
                            ca.jacobian(xn, self._p)])
        # the event iteration is costly (up to 100 conditional rounds): it runs only where
        # something can happen, a clock due or a relation whose distance disagrees with
        # its mode; elsewhere the state passes unchanged (what the iteration would give)
        skip = ca.Function("no_events", [self._x, self._r, self._p, u, t],
                           [self._x, self._r, ca.DM.eye(cm.nx),
                            ca.DM.zeros(cm.nx, self._p.numel())])
        self._event_switch = ca.Function.conditional("sample_events_if", [skip], fire)
        tt, XX, pp, d = _dist_symbols(cm)
        hs = ca.SX.sym("h_substep")
        X = ca.vertcat(self._x, self._r)
        dd = ca.substitute(d, ca.vertcat(tt, XX, pp), ca.vertcat(t, X, pu))
        flags = []
        for k, (_o, op) in enumerate(cm.relations):
            mode = self._r[k]
            if op == "clock":
                flags.append(dd[k] >= -1e-6 * hs)
            elif op in ("<", "<=", "sign"):
                at_zero = 1.0 if op in ("<=", "sign") else -1.0
                new = ca.if_else(dd[k] > 0, 1, ca.if_else(dd[k] < 0, -1, at_zero))
                flags.append(new != mode)
            else:
                flags.append((dd[k] > 0) != (mode > 0))
        self._event_flag = ca.Function("events_due", [self._x, self._r, self._p, u, t, hs],
                                       [_any_of(flags)])
        return fire

    def _event_switch_sens(self, Dm: ca.DM) -> ca.Function:
        """``(due, x, r, p, u, t, S) -> (x+, r+, S+)``: the events at a substep end with
        the sensitivity carried along the directions ``[S; Dm]`` of ``(x, p)``
        (``S+ = dx+/dx S + dx+/dp Dm``), one forward sweep with ``q`` directions through
        the event iteration. (The Jacobians of `_event_function` cost ``nx`` forward and
        ``nx`` reverse sweeps, every sample where a clock ticks.)"""
        nx = self.cm.nx
        u, t, Xn = self._event_out
        S = ca.SX.sym("S", nx, Dm.size2())
        xn = Xn[:nx]
        dxn = ca.jtimes(xn, ca.vertcat(self._x, self._p), ca.vertcat(S, Dm))
        args = [self._x, self._r, self._p, u, t, S]
        fire = ca.Function("sample_events_sens", args, [xn, Xn[nx:], dxn])
        skip = ca.Function("no_events_sens", args, [self._x, self._r, S])
        return ca.Function.conditional("sample_events_sens_if", [skip], fire)

    def _substep(self, xi, args):
        """One Radau substep from ``xi``: the new state and, per state, the scaled
        correction one more Newton iteration would make (largest over the stages)."""
        nx, ns = self.cm.nx, len(_C)
        K = self._solve(ca.repmat(xi, ns, 1), args)
        delta = self._newton(K, args)
        X0 = ca.repmat(xi, ns, 1)
        tol = NEWTON_ATOL + NEWTON_RTOL * ca.fabs(K) + NEWTON_STEP * ca.fabs(K - X0)
        err = ca.fabs(delta) / tol
        e = err[:nx]
        for i in range(1, ns):
            e = ca.fmax(e, err[i * nx:(i + 1) * nx])
        return K, e

    def _h_frac_sym(self):
        # the substep length as a fraction of the sample interval
        if getattr(self, "_hf", None) is None:
            self._hf = ca.SX.sym("hf")
        return self._hf

    def _with_u(self, uval):
        p = self._p
        if not self.input_index:
            return p
        parts = [p[i] for i in range(p.size1())]
        for j, i in enumerate(self.input_index):
            parts[i] = uval[j]
        return ca.vertcat(*parts)

    def _u_at(self, frac):
        if self.hold == "zoh" or not self.input_index:
            return self._u0
        return self._u0 + frac * (self._u1 - self._u0)

    def _u_end(self, j: int, m: int):
        """The input at the end of substep ``j`` of ``m``, as the events there read it:
        the next sample at the last one (the hold switches at the sample instant)."""
        if j == m - 1 or self.hold == "linear":
            return self._u0 + (j + 1) / m * (self._u1 - self._u0) if j < m - 1 \
                else self._u1
        return self._u0

    def _outputs_sx(self):
        cm = self.cm
        tt = ca.SX.sym("t")
        y = cm.f_out(tt, self._full(self._x, self._r), ca.SX(0, 1), self._with_u(self._u0))
        yo = ca.vertcat(*[y[i] for i in self.output_index]) if self.output_index \
            else ca.SX(0, 1)
        return tt, yo

    def _sample(self, sens: bool, S=None, Dm=None):
        """The symbolic sample step from ``(x, r[, S])``: ``m`` Radau substeps, each
        followed by the events at its end."""
        cm = self.cm
        nx = cm.nx
        m = int(self.substeps)
        x, r, p, u0, u1 = self._x, self._r, self._p, self._u0, self._u1
        h = ca.SX.sym("h_sample")
        tk = ca.SX.sym("tk")
        if sens:
            GK = ca.jacobian(self._res, self._K)
            Gx = ca.jacobian(self._res, x)
            Gp = ca.jacobian(self._res, p)
            Ss = ca.SX.sym("S", nx, S.size2())
            dK = -ca.solve(GK, ca.mtimes(Gx, Ss) + ca.mtimes(Gp, Dm))
            sub = ca.Function("radau_sensitivity", [self._K, Ss, ca.vertcat(*self._args)],
                              [dK[-nx:, :]])
            if self.events:
                switch = self._event_switch_sens(Dm)
        xi, ri, Si = x, r, S
        e = ca.DM.zeros(nx, 1)
        for j in range(m):
            args = ca.vertcat(xi, ri, p, u0, u1, h / m, tk + j * h / m, j / m, 1 / m)
            K, ej = self._substep(xi, args)
            if sens:
                Si = sub(K, Si, args)
            xi = K[-nx:]
            e = ca.fmax(e, ej)
            if self.events:
                t_end = tk + h if j == m - 1 else tk + (j + 1) * h / m
                ue = self._u_end(j, m)
                due = self._event_flag(xi, ri, p, ue, t_end, h / m)
                if sens:
                    xi, ri, Si = switch(due, xi, ri, p, ue, t_end, Si)
                else:
                    xi, ri, _, _ = self._event_switch(due, xi, ri, p, ue, t_end)
        return h, tk, xi, ri, Si, e

    def _initial(self, x0, P, U0, S0=None, D=None):
        """The state after the events of the initial time (and its sensitivity)."""
        if not self.events:
            return x0, ca.MX(0, 1), S0
        r0 = ca.DM(self._rest0())
        xn, rn, jx, jp = self._event_fn(x0, r0, P, U0, float(self.t[0]))
        Sn = None if S0 is None else ca.mtimes(jx, S0) + ca.mtimes(jp, ca.DM(D))
        return xn, rn, Sn

    def _build(self) -> None:
        """The sample step and the outputs at a sample as SX functions, and their time
        loop: in C where the trajectory runs native code (`_NativeLoop`), else a CasADi
        ``mapaccum`` (built when first called, `_mx`)."""
        x, r, p, u0, u1 = self._x, self._r, self._p, self._u0, self._u1
        h, tk, xi, ri, _, e = self._sample(False)
        step = ca.Function("sample_step", [ca.vertcat(x, r), ca.vertcat(p, u0, u1, h, tk)],
                           [ca.vertcat(xi, ri), e])
        tt, yo = self._outputs_sx()
        out = ca.Function("outputs", [tt, ca.vertcat(x, r), p, u0], [yo])
        self._parts = (step, out)
        self._mx = None
        self._loop = _NativeLoop.build("trajectory", step, out, self._start()) \
            if self.jit else None

    def _start(self, D: np.ndarray | None = None) -> ca.Function:
        """``(p, x0, u0[, S0]) -> xa0``: the integration state (and sensitivities) after
        the events of the initial time."""
        cm = self.cm
        x0 = ca.MX.sym("x0", cm.nx)
        P = ca.MX.sym("p", cm.p0.size)
        U0 = ca.MX.sym("u0", len(self.input_index))
        if D is None:
            xs0, rs0, _ = self._initial(x0, P, U0)
            return ca.Function("start", [P, x0, U0], [ca.vertcat(xs0, rs0)])
        S0 = ca.MX.sym("S0", cm.nx, D.shape[1])
        xs0, rs0, Ss0 = self._initial(x0, P, U0, S0, D)
        return ca.Function("start_sens", [P, x0, U0, S0], [ca.vertcat(xs0, rs0, ca.vec(Ss0))])

    @property
    def function(self) -> ca.Function:
        """``(p, x0, U) -> (Y, X)`` as a CasADi function (its time loop a ``mapaccum``)."""
        return self._mx_functions()[0]

    def _mx_functions(self) -> tuple[ca.Function, ca.Function]:
        """The trajectory as CasADi functions, built on first use: ``(function,
        checked)``, the second with the convergence measure as a third output."""
        if self._mx is not None:
            return self._mx
        nx = self.cm.nx
        args, (Y,), Xs, E = self._casadi_loop("run", *self._parts, self._start())
        Xc = Xs[:nx, :] if self._r.numel() else Xs
        checked = ca.Function("trajectory_checked", args, [Y, Xc, E],
                              ["p", "x0", "U"], ["Y", "X", "newton"])
        function = ca.Function("trajectory", args, [Y, Xc], ["p", "x0", "U"],
                               ["Y", "X"])
        self._mx = (function, checked)
        return self._mx

    def check_ticks(self, p) -> None:
        """Raise if a clock of the model ticks between substep ends inside the
        experiment (its update would come late): time events must fall on the grid."""
        if not self.events:
            return
        m = int(self.substeps)
        grid = (self.t[:-1, None] + np.diff(self.t)[:, None] * np.arange(m) / m).ravel()
        grid = np.concatenate([grid, self.t[-1:]])
        t0, t1 = float(self.t[0]), float(self.t[-1])
        for k, period, offset in clocks(self.cm, np.asarray(p, dtype=float)):
            if not period > 0:
                continue
            first = max(0, math.ceil((t0 - offset) / period - 1e-9))
            last = math.floor((t1 - offset) / period + 1e-9)
            if last < first:
                continue
            if last - first > 50 * grid.size:
                bad = offset + (first + 0.5) * period
            else:
                ticks = offset + np.arange(first, last + 1) * period
                j = np.clip(np.searchsorted(grid, ticks), 1, grid.size - 1)
                dist = np.minimum(np.abs(grid[j] - ticks), np.abs(grid[j - 1] - ticks))
                off = dist > 1e-9 * period + 1e-12 * max(abs(t1), 1.0)
                if not off.any():
                    continue
                bad = ticks[np.argmax(off)]
            owner = self.cm.relations[k][0] or self.cm.name
            raise DataError(
                f"{owner}: the clock (period {period:g} s, offset {offset:g} s) ticks at "
                f"t = {bad:.9g} s, between the substeps of the sample grid ({m} per "
                f"sample); its update would act late. Sample the data on the clock's "
                f"ticks, or choose substeps that put every tick on a substep end.",
                path=owner)
        self._check_time_relations(np.asarray(p, dtype=float), grid)

    def _check_time_relations(self, p, grid) -> None:
        """Raise if a relation of time alone (a step at a known time) switches strictly
        between two substep ends: its distance changes sign there."""
        cm = self.cm
        t, X, pp, d = _dist_symbols(cm)
        ks = [k for k, (_o, op) in enumerate(cm.relations)
              if op in ("<", "<=", "sign") and ca.depends_on(d[k], t)
              and not ca.depends_on(d[k], X)
              and not (self.input_index and ca.depends_on(
                  d[k], ca.vertcat(*[pp[i] for i in self.input_index])))]
        if not ks:
            return
        f = ca.Function("time_relations", [t, pp], [ca.vertcat(*[d[k] for k in ks])])
        D = np.array(f.map(grid.size)(grid.reshape(1, -1), ca.repmat(ca.DM(p), 1, grid.size)))
        for row, k in zip(D, ks):
            # a switching time on a grid point, to rounding, is on the grid
            s = np.sign(np.where(np.abs(row) <= 1e-9 * np.abs(row).max(), 0.0, row))
            cross = np.flatnonzero((s[:-1] * s[1:]) < 0)
            if cross.size:
                j = cross[0]
                owner = cm.relations[k][0] or cm.name
                raise DataError(
                    f"{owner}: a relation of time switches between t = {grid[j]:.9g} s "
                    f"and {grid[j + 1]:.9g} s, inside a substep; its effect would come "
                    f"late. Put the switching time on a sample (or substep) instant.",
                    path=owner)

    def check_convergence(self, E) -> None:
        """Raise if a sample's Newton iteration did not converge. ``E`` (nx, N-1): per
        state and sample interval, the scaled correction one more iteration would make."""
        E = np.asarray(E, dtype=float).reshape(self.cm.nx, -1)
        bad = ~np.all(E <= 1.0, axis=0)                 # NaN counts as not converged
        if not bad.any():
            return
        k = int(np.argmax(bad))
        score = np.where(np.isfinite(E[:, k]), E[:, k], np.inf)
        worst = [i for i in np.argsort(-score, kind="stable")[:3] if not score[i] <= 1.0]
        names = [self.cm.state_names[i] for i in worst]
        shown = ", ".join(f"{n} ({score[i]:.3g} x its tolerance)"
                          for n, i in zip(names, worst))
        raise SimulationError(
            f"model '{self.cm.name}': the Radau IIA substeps did not converge between "
            f"t = {self.t[k]:.9g} s and {self.t[k + 1]:.9g} s (sample {k}, "
            f"{int(bad.sum())} sample interval(s) in all; Newton's next correction is "
            f"largest for {shown}). Use more substeps (a smaller step ratio), or keep the "
            "parameters in a plausible range (bounds): a stiff or wildly scaled model "
            "needs shorter steps.", path=self.cm.name, variables=names)

    def _casadi_loop(self, name: str, step: ca.Function, out: ca.Function,
                     start: ca.Function, *extra: ca.MX) -> tuple[list, list, ca.MX, ca.MX]:
        """The time loop in CasADi (where no `_NativeLoop` runs it): the start state,
        ``step`` accumulated over the sample intervals (a ``mapaccum`` named ``name``) and
        ``out`` mapped over the samples. Returns the inputs ``[p, x0, U, *extra]``, the
        outputs of ``out`` (each ``(n, N)``), the integration states ``(n, N)`` and the
        convergence measure ``(nx, N - 1)``."""
        if self.jit:
            step, out = native(step), native(out)
        N = self.t.size
        x0 = ca.MX.sym("x0", self.cm.nx)
        P = ca.MX.sym("p", self.cm.p0.size)
        U = ca.MX.sym("U", len(self.input_index), N)
        xa0 = start(P, x0, U[:, 0], *extra)
        if N > 1:
            XR, E = step.mapaccum(name, N - 1)(xa0, self._run_args(P, U))
            XA = ca.horzcat(xa0, XR)
        else:
            XA, E = xa0, ca.MX(self.cm.nx, 0)
        outs = out.map(N).call([ca.DM(self.t.reshape(1, -1)), XA, ca.repmat(P, 1, N), U])
        return [P, x0, U, *extra], outs, XA, E

    def _run_args(self, P, U):
        N = self.t.size
        return ca.vertcat(ca.repmat(P, 1, N - 1), U[:, :-1], U[:, 1:],
                          ca.DM(np.diff(self.t).reshape(1, -1)),
                          ca.DM(self.t[:-1].reshape(1, -1)))

    # ------------------------------------------------------------------------------------
    def sensitivity_function(self, D: np.ndarray) -> _Checked:
        """``(p, x0, U, S0) -> (Y, dY)``, NumPy arrays: outputs and their derivatives along
        ``q`` directions. ``D`` (npar x q) maps the directions to parameters; ``S0`` (nx x q)
        is ``dx0/dtheta``. ``dY`` is ``(n_out * q, N)``: column ``k`` holds
        ``vec(dy_k/dtheta)`` (column-major, output index fastest)."""
        D = np.asarray(D, dtype=float)
        key = D.tobytes() + bytes(str(D.shape), "ascii")
        if key in self._sens:
            return self._sens[key]
        nx, q = self.cm.nx, D.shape[1]
        x, r, p, u0 = self._x, self._r, self._p, self._u0
        Dm = ca.DM(D)
        # implicit function theorem on the stage residual G(K, x, p) = 0, and the chain
        # rule through the events at the substep ends
        S = ca.SX.sym("S", nx, q)
        h, tk, xi, ri, Si, e = self._sample(True, S, Dm)
        xa = ca.vertcat(x, r, ca.vec(S))
        step = ca.Function("sample_step_sens", [xa, ca.vertcat(p, self._u0, self._u1, h,
                                                              tk)],
                           [ca.vertcat(xi, ri, ca.vec(Si)), e])
        tt, yo = self._outputs_sx()
        dy = ca.mtimes(ca.jacobian(yo, x), S) + ca.mtimes(ca.jacobian(yo, p), Dm)
        out = ca.Function("outputs_sens", [tt, xa, p, u0], [yo, ca.vec(dy)])
        start = self._start(D)
        loop = _NativeLoop.build("trajectory_sens", step, out, start) if self.jit else None
        if loop is not None:
            f = self._sens[key] = _Checked(loop, self)
            return f
        S0 = ca.MX.sym("S0", nx, q)
        args, (Y, dY), _, E = self._casadi_loop("run_sens", step, out, start, S0)
        f = _Checked(ca.Function("trajectory_sens", args, [Y, dY, E],
                                 ["p", "x0", "U", "S0"], ["Y", "dY", "newton"]), self)
        self._sens[key] = f
        return f

    def __call__(self, p, x0, U):
        """Outputs ``(n_out, N)`` and states ``(nx, N)`` as NumPy arrays; raises
        :class:`~mechatron.errors.SimulationError` if a substep did not converge."""
        if self._loop is not None:
            Y, _, XS, E = self._loop(self, p, x0, U)
            self.check_convergence(E)
            return Y, XS[:self.cm.nx]
        Y, X, E = self._mx_functions()[1](p, x0, U)
        self.check_convergence(E)
        return Y.full(), X.full()


class _Checked:
    """A trajectory function whose last output is the Newton convergence measure: called
    like the CasADi function, it checks that output and returns the others as NumPy
    arrays. ``fn`` is a `_NativeLoop` or a CasADi function."""

    def __init__(self, fn, traj: Trajectory):
        self.fn = fn
        self.traj = traj

    def __call__(self, *args):
        if isinstance(self.fn, _NativeLoop):
            Y, dY, _, E = self.fn(self.traj, *args)
            self.traj.check_convergence(E)
            return Y, dY
        *outs, E = self.fn(*args)
        self.traj.check_convergence(E)
        return tuple(o.full() for o in outs)


class _NativeLoop:
    """A trajectory's time loop in C (``templates/trajectory.c``): the sample step and
    the outputs, generated by CasADi, called from a C loop over the samples. The same
    arithmetic as the ``mapaccum`` of the natively compiled step (the same C, compiler
    and flags), without CasADi's per-call work: building a ``mapaccum`` over 25 000
    samples takes some 0.2 s, and each of its steps about 1.5 us on top of the step's
    own (measured on the EMPS model, whose step takes 2.8 us).

    Called as ``loop(traj, p, x0, U[, S0])``: ``(Y, Y1, XS, E)``, the outputs
    ``(ny, N)``, the second outputs of the output function (the sensitivities; none
    without them), the integration states ``(nxa, N)`` and the convergence measure
    ``(nx, N - 1)``."""

    def __init__(self, path, start: ca.Function, sizes: dict):
        self.dll = ctypes.CDLL(str(path))
        fn = self.dll.mt_trajectory
        fn.restype = ctypes.c_int
        fn.argtypes = [ctypes.c_long] + [ctypes.c_void_p] * 8
        self.run = fn
        self.start = start
        self.sizes = sizes

    @classmethod
    def build(cls, name: str, step: ca.Function, out: ca.Function,
              start: ca.Function) -> "_NativeLoop | None":
        """The loop of ``step`` and ``out`` compiled (cached on disk), or None without a
        C compiler, when the build would exceed the native code's limit
        (:data:`~mechatron.estimation.native.MAX_BUILD_S`), or if it fails: the caller
        then builds the CasADi loop (which says why it runs interpreted)."""
        cc = _native.compiler()
        if cc is None:
            return None
        seconds = _native.build_estimate(step)[1] + _native.build_estimate(out)[1]
        if 0 < _native._limit() < seconds:
            return None
        sizes = dict(NXA=step.size1_in(0), NP=step.size1_in(1) - 2 * start.size1_in(2) - 2,
                     NU=start.size1_in(2), NE=step.size1_out(1), NY0=out.size1_out(0),
                     NY1=out.size1_out(1) if out.n_out() > 1 else 0,
                     SZ_ARG=max(step.sz_arg(), out.sz_arg(), 4),
                     SZ_RES=max(step.sz_res(), out.sz_res(), 2),
                     SZ_IW=max(step.sz_iw(), out.sz_iw()), SZ_W=max(step.sz_w(), out.sz_w()))
        try:
            cg = ca.CodeGenerator(f"{name}.c", {"with_header": False})
            cg.add(step)
            cg.add(out)
            defines = "".join(f"#define MT_{k} {v}\n" for k, v in sizes.items())
            defines += f"#define mt_step {step.name()}\n#define mt_outputs {out.name()}\n"
            template = resources.files("mechatron.estimation").joinpath(
                "templates", "trajectory.c").read_text()
            lib = build_library(cg.dump() + "\n" + defines + template, name, "jit",
                                _native.FLAGS, cc)
            return cls(lib, start, sizes)
        except (BuildError, RuntimeError, OSError):
            return None

    def __call__(self, traj: Trajectory, p, x0, U, *S0):
        z = self.sizes
        t = np.ascontiguousarray(traj.t, dtype=float)
        n = t.size
        p = np.ascontiguousarray(np.asarray(p, dtype=float).ravel())
        if p.size != z["NP"]:
            raise ValueError(f"model '{traj.cm.name}': the trajectory takes {z['NP']} "
                             f"parameter values, got {p.size}.")
        U = np.asarray(U, dtype=float).reshape(z["NU"], n)
        xa0 = np.ascontiguousarray(np.asarray(
            self.start(p, np.asarray(x0, dtype=float).ravel(), U[:, 0], *S0),
            dtype=float).ravel())
        Ut = np.ascontiguousarray(U.T)
        XS = np.empty((n, z["NXA"]))
        Y0 = np.empty((n, z["NY0"]))
        Y1 = np.empty((n, z["NY1"]))
        E = np.empty((max(n - 1, 0), z["NE"]))
        status = self.run(n, *(a.ctypes.data for a in (xa0, p, Ut, t, XS, Y0, Y1, E)))
        if status:
            cm = traj.cm
            if status < 0:
                raise MemoryError(f"model '{cm.name}': no memory for the trajectory's "
                                  "work arrays.")
            k = status - 1 if status <= n else status - n - 1
            what = "the sample step from" if status <= n else "the outputs at"
            raise SimulationError(
                f"model '{cm.name}': {what} t = {t[k]:.9g} s (sample {k}) failed in the "
                "compiled code (a singular linear solve or a failed event iteration). "
                "Check the parameters for values the model cannot run with, or use more "
                "substeps.", path=cm.name)
        return Y0.T, Y1.T, XS.T, E.T
