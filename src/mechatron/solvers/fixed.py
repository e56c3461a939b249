"""Fixed-step solvers: one CasADi step function per method (docs/solvers.md).

``step(X, u, p, t) -> (X_next, y)`` advances the integration state by one step ``h`` and
returns every logged variable at the new point. Desktop simulation runs it with
``mapaccum`` (native loop, no Python per step); the C generator emits the same function,
so desktop and generated code agree to rounding.

Methods are data: explicit ones are Butcher tableaus, implicit ones take a fixed number of
Newton iterations (a fixed cost per step, as Simscape's local solvers). Modes of relations
are updated at the end of each step from the sign of their distance (no event location,
as in any real-time solver). Algebraic unknowns, where a nonlinear loop left some, are
solved by a fixed number of Newton iterations from the previous step's values.
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np

from mechatron.compiler.compiled import CompiledModel
from mechatron.errors import SimulationError
from mechatron.solvers.fpenv import subnormals_flushed

CHUNK = 2000   # steps per native fixed-step loop
#: Newton's iteration has converged when the correction one more iteration would make is
#: at most NEWTON_ATOL + NEWTON_RTOL |x| + NEWTON_STEP |x1 - x0| for every unknown (the
#: last term: a thousandth of the step's own change, well under its truncation error)
NEWTON_ATOL, NEWTON_RTOL, NEWTON_STEP = 1e-10, 1e-6, 1e-3
NEWTON_MODES = ("check", "count")

__all__ = ["METHODS", "ExplicitMethod", "ImplicitMethod", "ExtrapolatedMethod", "make_step",
           "integrate_fixed", "NEWTON_MODES"]


@dataclass(frozen=True)
class ExplicitMethod:
    """An explicit Runge-Kutta method given by its Butcher tableau."""

    name: str
    a: tuple[tuple[float, ...], ...]
    b: tuple[float, ...]
    c: tuple[float, ...]
    order: int


@dataclass(frozen=True)
class ImplicitMethod:
    """A one-step implicit method ``x1 = x0 + h*((1-theta) f(x0) + theta f(x1))`` solved
    by a fixed number of Newton iterations from an explicit Euler predictor."""

    name: str
    theta: float
    order: int


@dataclass(frozen=True)
class ExtrapolatedMethod:
    """Implicit Euler extrapolation, in the spirit of Simulink's ``ode14x``.

    One step ``h`` is taken ``len(sequence)`` times with backward Euler, as ``n_j`` equal
    substeps for each ``n_j`` of ``sequence`` (each substep solved by a fixed number of
    Newton iterations from an explicit Euler predictor), and the results ``T_j1`` are
    combined by Aitken-Neville extrapolation for an error expansion in powers of ``h``:
    ``T_j,l+1 = T_j,l + (T_j,l - T_j-1,l) / (n_j / n_j-l - 1)``. With the harmonic
    sequence ``(1, 2, 3)`` the result is of order 3; its stability function vanishes at
    infinity (stiff decay, like backward Euler). Limitation: the order assumes Newton has
    converged; with too few iterations on a strongly nonlinear model the order drops.
    """

    name: str
    sequence: tuple[int, ...]
    order: int


METHODS = {
    "euler": ExplicitMethod("euler", ((),), (1.0,), (0.0,), 1),
    "heun": ExplicitMethod("heun", ((), (1.0,)), (0.5, 0.5), (0.0, 1.0), 2),
    "rk4": ExplicitMethod("rk4", ((), (0.5,), (0.0, 0.5), (0.0, 0.0, 1.0)),
                          (1 / 6, 1 / 3, 1 / 3, 1 / 6), (0.0, 0.5, 0.5, 1.0), 4),
    "backward_euler": ImplicitMethod("backward_euler", 1.0, 1),
    "trapezoidal": ImplicitMethod("trapezoidal", 0.5, 2),
    "ode14x": ExtrapolatedMethod("ode14x", (1, 2, 3), 3),
}


def _segment(v: ca.SX, a: int, b: int) -> ca.SX:
    """``v[a:b]`` as a column; CasADi gives an empty slice the shape 1x0, which vertcat
    would count as a row."""
    return v[a:b] if b > a else ca.SX(0, 1)


def _newton_z(cm: CompiledModel, t, X, z, p, iterations: int):
    if cm.nz == 0:
        return z
    zs = ca.SX.sym("zs", cm.nz)
    gs = cm.f_alg(t, X, zs, p)
    jac = ca.jacobian(gs, zs)
    for _ in range(iterations):
        jz, gz = ca.substitute([jac, gs], [zs], [z])
        z = z - ca.solve(jz, gz)
    return z


def _scaled(delta, x1, x0=None):
    """``|delta|`` in units of the Newton tolerance (see :data:`NEWTON_ATOL`)."""
    tol = NEWTON_ATOL + NEWTON_RTOL * ca.fabs(x1)
    if x0 is not None:
        tol = tol + NEWTON_STEP * ca.fabs(x1 - x0)
    return ca.fabs(delta) / tol


def _z_error(cm: CompiledModel, t, X, z, p):
    """Scaled correction one more Newton iteration on the algebraic equations would make."""
    zs = ca.SX.sym("zs", cm.nz)
    gs = cm.f_alg(t, X, zs, p)
    jz, gz = ca.substitute([ca.jacobian(gs, zs), gs], [zs], [z])
    return _scaled(ca.solve(jz, gz), z)


def _euler_extrapolation(f, t, x0, z, h: float, sequence, iterations: int, errors=None):
    """Backward Euler over ``h`` with ``n`` substeps for each ``n`` in ``sequence``,
    extrapolated (Aitken-Neville, powers of ``h``); see :class:`ExtrapolatedMethod`.
    ``errors`` (a list) collects each substep's scaled Newton correction."""
    xs = ca.SX.sym("xs", x0.numel())
    rows = []
    for n in sequence:
        hs = h / n
        xk = x0
        for k in range(n):
            tk = t + k * hs
            fk, z = f(tk, xk, z)
            fs, _ = f(tk + hs, xs, z)
            resid = xs - xk - hs * fs
            jac = ca.jacobian(resid, xs)
            xn = xk + hs * fk
            for _ in range(max(1, iterations)):
                jx, rx = ca.substitute([jac, resid], [xs], [xn])
                xn = xn - ca.solve(jx, rx)
            if errors is not None:
                # the next correction with the last iteration's Jacobian (its
                # factorization is shared once the function is built with cse)
                rx = ca.substitute(resid, xs, xn)
                errors.append(_scaled(ca.solve(jx, rx), xn, xk))
            xk = xn
        row = [xk]
        for j in range(1, len(rows) + 1):
            ratio = n / sequence[len(rows) - j]
            row.append(row[j - 1] + (row[j - 1] - rows[-1][j - 1]) / (ratio - 1))
        rows.append(row)
    return rows[-1][-1], z


def make_step(cm: CompiledModel, method: str, dt: float, iterations: int = 3, *,
              check: bool = False) -> ca.Function:
    """The step function of ``method`` with step ``dt`` (cached on the model).

    ``check=True`` adds a third output ``newton``: for every state and algebraic unknown,
    the correction that one more Newton iteration would make, in units of its tolerance
    (see :data:`NEWTON_ATOL`); above 1 the fixed iteration count has not converged. The
    first two outputs are the same expressions as without it (code generation and the
    real-time runner use the two-output function)."""
    if method not in METHODS:
        raise SimulationError(f"unknown fixed-step solver '{method}'. Choose one of "
                              f"{', '.join(METHODS)}.")
    if not dt or dt <= 0:
        raise SimulationError(f"solver '{method}' needs a step size dt > 0, got {dt!r}.")
    key = ("step", method, float(dt), int(iterations)) + (("check",) if check else ())
    if key in cm._cache:
        return cm._cache[key]
    m = METHODS[method]
    nx, nr, nz = cm.nx, cm.nr, cm.nz
    Xa = ca.SX.sym("x", cm.nX + nz)        # [x; modes; counters; t_event; z guess]
    u = ca.SX.sym("u", 0)
    p = ca.SX.sym("p", cm.p0.size)
    t = ca.SX.sym("t")
    h = float(dt)
    x0 = _segment(Xa, 0, nx)
    rest = _segment(Xa, nx, cm.nX)
    zg = _segment(Xa, cm.nX, cm.nX + nz)

    def f(tt, xx, zz):
        X = ca.vertcat(xx, rest)
        zz = _newton_z(cm, tt, X, zz, p, iterations)
        return _segment(cm.f_ode(tt, X, zz, p), 0, nx), zz

    if isinstance(m, ExplicitMethod):
        ks = []
        z = zg
        for i, ci in enumerate(m.c):
            xi = x0
            for j, aij in enumerate(m.a[i]):
                if aij:
                    xi = xi + h * aij * ks[j]
            k, z = f(t + ci * h, xi, z)
            ks.append(k)
        x1 = x0
        for bi, k in zip(m.b, ks):
            x1 = x1 + h * bi * k
        e_x = ca.DM.zeros(nx, 1)
    elif isinstance(m, ExtrapolatedMethod):
        errors = []
        x1, z = _euler_extrapolation(f, t, x0, zg, h, m.sequence, iterations,
                                     errors if check else None)
        e_x = errors[0] if errors else ca.DM.zeros(nx, 1)
        for e in errors[1:]:
            e_x = ca.fmax(e_x, e)
    else:
        f0, z = f(t, x0, zg)
        x1 = x0 + h * f0
        xs = ca.SX.sym("xs", nx)
        fs, _ = f(t + h, xs, z)
        resid = xs - x0 - h * ((1 - m.theta) * f0 + m.theta * fs)
        jac = ca.jacobian(resid, xs)
        for _ in range(max(1, iterations)):
            jx, rx = ca.substitute([jac, resid], [xs], [x1])
            x1 = x1 - ca.solve(jx, rx)
        if check:
            rx = ca.substitute(resid, xs, x1)
            e_x = _scaled(ca.solve(jx, rx), x1, x0)
    z1 = _newton_z(cm, t + h, ca.vertcat(x1, rest), z if nz else zg, p, iterations) \
        if nz else zg
    modes, counters, tlast = (_segment(rest, 0, nr), _segment(rest, nr, 2 * nr),
                              _segment(rest, 2 * nr, 3 * nr))
    if nr and cm.f_events is not None:
        # relations re-read, clock ticks due and conditions that became true, with their
        # actions (discrete updates at the sample instants that the step lands on)
        Xn = cm.f_events(t + h, ca.vertcat(x1, rest), z1, p)
    elif nr:
        d, _ = cm.f_dist(t + h, ca.vertcat(x1, rest), z1, p)
        le = ca.DM([1.0 if op in ("<=", "sign") else 0.0 for _, op in cm.relations])
        new = ca.vertcat(*[ca.if_else(d[k] > 0, 1, ca.if_else(d[k] < 0, -1, 2 * le[k] - 1))
                           for k in range(nr)])
        changed = new != modes
        counters = counters + changed
        tlast = ca.vertcat(*[ca.if_else(changed[k], t + h, tlast[k]) for k in range(nr)])
        modes = new
    if not (nr and cm.f_events is not None):
        Xn = ca.vertcat(x1, modes, counters, tlast)
    y = cm.f_out(t + h, Xn, z1, p)
    if check:
        e_z = _z_error(cm, t + h, ca.vertcat(x1, rest), z1, p) if nz else ca.SX(0, 1)
        step = ca.Function(f"step_{method}", [Xa, u, p, t],
                           [ca.vertcat(Xn, z1), y, ca.vertcat(e_x, e_z)],
                           ["x", "u", "p", "t"], ["x_next", "y", "newton"], {"cse": True})
    else:
        step = ca.Function(f"step_{method}", [Xa, u, p, t], [ca.vertcat(Xn, z1), y],
                           ["x", "u", "p", "t"], ["x_next", "y"])
    cm._cache[key] = step
    return step


@subnormals_flushed()
def integrate_fixed(cm: CompiledModel, t0: float, t_stop: float, dt: float, X0, z0, p, *,
                    method: str, iterations: int = 3, inputs=None, newton: str = "check"):
    """Run ``make_step`` from ``t0`` to ``t_stop``; return ``(t, Y, X_final, unconverged)``.

    ``inputs`` (:class:`mechatron.solvers.inputs.Inputs`, optional) gives the external
    inputs, sampled at the start of each step and held over it (zero-order hold): each
    step's ``p`` column carries them into the native loop.

    ``newton``: every step's Newton iterations (implicit methods, algebraic unknowns) are
    checked (``make_step(check=True)``). ``"check"`` raises a
    :class:`~mechatron.errors.SimulationError` at the first step that did not converge,
    naming its time and the unknowns furthest from convergence; ``"count"`` (a real-time
    target, which takes the fixed iteration count whatever happens) runs on and returns
    the number of such steps as ``unconverged``."""
    if newton not in NEWTON_MODES:
        raise SimulationError(f"model '{cm.name}': newton must be one of "
                              f"{', '.join(NEWTON_MODES)}, got {newton!r}.", path=cm.name)
    n = int(round((t_stop - t0) / dt))
    if n < 1:
        raise SimulationError(f"t_stop - t0 = {t_stop - t0:g} s is shorter than one step "
                              f"dt = {dt:g} s.")
    step = make_step(cm, method, dt, iterations, check=True)
    times = t0 + dt * np.arange(n)
    xa = np.concatenate([X0, z0])
    ys = []
    unconverged = 0
    # native loops of at most CHUNK steps: building a mapaccum costs time growing with its
    # length, so long runs reuse one chunk function (Python runs once per chunk, not step)
    for start in range(0, n, CHUNK):
        m = min(CHUNK, n - start)
        key = ("run", method, float(dt), int(iterations), m)
        run = cm._cache.get(key)
        if run is None:
            run = cm._cache[key] = step.mapaccum("run", m)
        pm = (np.repeat(p.reshape(-1, 1), m, axis=1) if inputs is None
              else inputs.columns(p, times[start:start + m]))
        xs, y, err = run(xa, ca.DM.zeros(0, m), pm, times[start:start + m].reshape(1, -1))
        err = np.array(err, dtype=float).reshape(-1, m)
        bad = ~np.all(err <= 1.0, axis=0)          # NaN counts as not converged
        if bad.any():
            if newton == "check":
                k = int(np.argmax(bad))
                raise _not_converged(cm, method, dt, iterations, times[start + k] + dt,
                                     err[:, k])
            unconverged += int(bad.sum())
        xs = np.array(xs, dtype=float).reshape(-1, m)
        xa = xs[:, -1]
        ys.append(np.array(y, dtype=float).reshape(-1, m))
    p0 = p if inputs is None else inputs.columns(p, t0)[:, 0]
    y0 = np.array(cm.f_out(t0, X0, z0, p0), dtype=float).reshape(-1, 1)
    Y = np.hstack([y0] + ys)
    t = np.concatenate([[t0], t0 + dt * np.arange(1, n + 1)])
    return t, Y, xa[:cm.nX], unconverged


def _not_converged(cm: CompiledModel, method: str, dt: float, iterations: int, t: float,
                   err: np.ndarray) -> SimulationError:
    names = list(cm.state_names) + list(cm.alg_names)
    score = np.where(np.isfinite(err), err, np.inf)
    worst = [i for i in np.argsort(-score, kind="stable")[:3] if not score[i] <= 1.0]
    shown = ", ".join(f"{names[i]} ({score[i]:.3g} x its tolerance)" for i in worst)
    return SimulationError(
        f"model '{cm.name}': {method}: Newton's iteration did not converge in "
        f"{iterations} iteration(s) at t = {t:.9g} s (dt = {dt:g} s); the next correction "
        f"is largest for {shown}. Take a smaller step dt or more iterations "
        f"(iterations={max(iterations, 1) * 2}); for a real-time target, which keeps the "
        "fixed count, pass newton='count' to count such steps instead "
        "(stats.unconverged_steps).", path=cm.name, variables=[names[i] for i in worst])
