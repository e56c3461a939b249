"""Consistent initialization (docs/compiler.md, docs/solvers.md).

States take their start values, also when an algebraic loop remains: its algebraic unknowns
are then solved with the states held (their start values only guesses). When a start value
targets a variable that is not a state (the velocity of the second of two geared inertias,
the voltage of the second of two parallel capacitors) or initial equations are given, the
initial point solves a least-deviation problem: the DAE constraints and every ``high``
target hold exactly, ``low`` targets as closely as possible, and ``none`` start values only
regularise. Conflicting ``high`` targets are found from the dependent rows of the
constraint Jacobian and named.
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from mechatron.compiler.compiled import CompiledModel
from mechatron.errors import InitializationError
from mechatron.solvers.fpenv import subnormals_kept

__all__ = ["initialize", "initial_modes"]


def initial_modes(cm: CompiledModel, t0: float, x: np.ndarray, z: np.ndarray,
                  p: np.ndarray, counters: np.ndarray | None = None) -> np.ndarray:
    """Modes of the relations at the initial point, iterated to a fixed point (a relation
    whose distance depends on another's mode), at most MAX_ROUNDS rounds."""
    from mechatron.core.events import MAX_ROUNDS
    nr = cm.nr
    if nr == 0:
        return np.zeros(0)
    modes = np.ones(nr)
    le = np.array([op in ("<=", "sign") for _, op in cm.relations])
    counters = np.zeros(nr) if counters is None else counters
    f = cm.f_dist2 if cm.f_dist2 is not None else cm.f_dist

    def read(modes):
        X = np.concatenate([x, modes, counters, np.full(nr, t0)])
        d, d_dot, *more = (np.array(v, dtype=float).ravel() for v in f(t0, X, z, p))
        # on the boundary, the direction of motion decides (to second order); at rest,
        # the relation's op
        rest = le if not more else np.where(more[0] > 0, True, np.where(more[0] < 0,
                                                                         False, le))
        at_zero = np.where(d_dot > 0, True, np.where(d_dot < 0, False, rest))
        return np.where((d > 0) | ((d == 0) & at_zero), 1.0, -1.0)

    before = None
    for _ in range(MAX_ROUNDS):
        new = read(modes)
        if before is not None and np.array_equal(new, before):
            # a cycle of period two (two sliding modes pointing into each other): re-read
            # one relation at a time, each seeing the ones already re-read
            new = modes.copy()
            for k in range(nr):
                new[k] = read(new)[k]
        if np.array_equal(new, modes):
            return modes
        last, before, modes = new != modes, modes, new
    labels = cm.report.get("relation_labels") or [op for _, op in cm.relations]
    bad = [f"{cm.relations[k][0] or cm.name}: {labels[k]}" for k in np.nonzero(last)[0]]
    raise InitializationError(
        f"model '{cm.name}': the modes of the relations have no consistent value at "
        f"t0 = {t0:g} s; after {MAX_ROUNDS} rounds these still change: "
        f"{'; '.join(bad[:6])}. Gate the relations by the mode they depend on, or add "
        "hysteresis.", variables=[cm.relations[k][0] for k in np.nonzero(last)[0]],
        path=cm.name)


@subnormals_kept()
def initialize(cm: CompiledModel, p: np.ndarray, t0: float = 0.0):
    """Return ``(X0, z0, report)``: the initial integration state, algebraic values, and
    one entry per start-value target (variable, target, priority, value, met)."""
    x = cm.x_start.copy()
    z = cm.z_start.copy()
    modes = initial_modes(cm, t0, x, z, p)
    report = []
    if cm.nz or cm.targets or cm.f_init is not None:
        x, z = _solve(cm, p, t0, x, z, modes)
        modes = initial_modes(cm, t0, x, z, p)
    nr = cm.nr
    X0 = np.concatenate([x, modes, np.zeros(nr), np.full(nr, t0)])
    if cm.report.get("event_actions"):
        # ticks due at t0 and their actions (the first sample of every block at offset 0),
        # then the modes at the point after them
        # a when condition that holds at t0 acts at t0 (a relay starts on above its
        # on-point): its mode is taken as false before, so the check sees it rise
        X0[[cm.nx + k for k in cm.report.get("when_relations", [])]] = -1.0
        # the initial event: an event of no relation (index -1), iterated as any other
        X0 = np.array(cm.f_transition(-1, t0, X0, z, p)[0], dtype=float).ravel()
        _check_loop(cm, X0, "at the initial time")
        plain = np.array([op != "clock" for _, op in cm.relations])
        X0[cm.nx + nr:cm.nx + 2 * nr][plain] = 0.0      # only ticks count at t0
        X0[cm.nx + 2 * nr:][plain] = t0
        counters = X0[cm.nx + nr:cm.nx + 2 * nr]
        X0[cm.nx:cm.nx + nr] = initial_modes(cm, t0, X0[:cm.nx], z, p, counters)
    y = np.array(cm.f_out(t0, X0, z, p), dtype=float).ravel() if cm.targets else None
    for k in _targeted_states(cm):
        report.append(_entry(cm.state_names[k], cm.x_start[k], cm.x_priority[k], x[k]))
    for name, idx, value, prio in cm.targets:
        report.append(_entry(name, value, prio, float(y[idx])))
    return X0, z, report


def _targeted_states(cm: CompiledModel) -> list[int]:
    """The states whose start value has a priority (found once per model)."""
    found = cm._cache.get("targeted_states")
    if found is None:
        found = cm._cache["targeted_states"] = [
            k for k, prio in enumerate(cm.x_priority) if prio in ("high", "low")]
    return found


def _entry(name, target, priority, value) -> dict:
    met = abs(value - target) <= 1e-6 * (1.0 + abs(target))
    return {"variable": name, "target": float(target), "priority": priority,
            "value": float(value), "met": bool(met)}


def _solve(cm: CompiledModel, p, t0, x0, z0, modes):
    nx, nz, nr = cm.nx, cm.nz, cm.nr
    # with no initial equation and no target on another variable, nothing asks a state to
    # leave its start value: the states keep them, as in a model without an algebraic
    # loop, and the loop is solved for the algebraic unknowns alone (were the states
    # free, the guesses of the algebraic unknowns would pull them: the same network
    # would start elsewhere as its equations were torn differently)
    held = cm.f_init is None and not cm.targets
    w = ca.SX.sym("w", nz if held else nx + nz)
    xs = ca.DM(x0) if held else w[:nx] if nx else ca.SX(0, 1)
    zs = w if held else w[nx:] if nz else ca.SX(0, 1)
    X = ca.vertcat(xs, ca.DM(modes), ca.DM.zeros(nr), ca.DM.ones(nr) * t0)
    y = cm.f_out(t0, X, zs, ca.DM(p))
    hard, hard_names, soft = [], [], []
    if nz:
        hard.append(cm.f_alg(t0, X, zs, ca.DM(p)))
        hard_names += [f"algebraic equation {k + 1} (for {cm.alg_names[k]})"
                       for k in range(nz)]
    if cm.f_init is not None:
        hard.append(cm.f_init(t0, X, zs, ca.DM(p)))
        hard_names += [f"initial equation '{text}'" for text in
                       cm.report.get("initial_equations", [])]
    states = () if held else cm.state_names     # held: constants, no term of theirs
    for k, name in enumerate(states):
        prio = cm.x_priority[k]
        if prio == "high":
            hard.append(xs[k] - x0[k])
            hard_names.append(f"{name} = {x0[k]:g} (high)")
        elif prio == "low":
            soft.append(xs[k] - x0[k])
        else:
            soft.append(1e-3 * (xs[k] - x0[k]))
    for k in range(nz):
        soft.append(1e-3 * (zs[k] - z0[k]))
    for name, idx, value, prio in cm.targets:
        if prio == "high":
            hard.append(y[idx] - value)
            hard_names.append(f"{name} = {value:g} (high)")
        else:
            soft.append(y[idx] - value)
    g = ca.vertcat(*hard) if hard else ca.SX(0, 1)
    f = ca.sumsqr(ca.vertcat(*soft)) if soft else ca.SX(0)
    w0 = z0 if held else np.concatenate([x0, z0])
    ng = g.numel()
    g_fun = ca.Function("init_g", [w], [g])
    if ng > w.numel():
        # more hard targets than unknowns: they can only hold if they agree; the least
        # squares point tells, and the dependent rows name the conflict
        from scipy.optimize import least_squares
        jac_fun = ca.Function("init_jac", [w], [ca.jacobian(g, w)])
        sol = least_squares(lambda v: np.array(g_fun(v), dtype=float).ravel(), w0,
                            jac=lambda v: np.array(jac_fun(v), dtype=float), xtol=1e-14,
                            ftol=1e-14, gtol=1e-14)
        wv, status = sol.x, sol.message
    else:
        solver = ca.nlpsol("init", "ipopt", {"x": w, "f": f, "g": g},
                           {"ipopt.print_level": 0, "print_time": False, "ipopt.sb": "yes",
                            "ipopt.tol": 1e-12, "ipopt.constr_viol_tol": 1e-10})
        wv = np.array(solver(x0=w0, lbg=0, ubg=0)["x"], dtype=float).ravel()
        status = f"IPOPT: {solver.stats().get('return_status', 'unknown')}"
    resid = np.abs(np.array(g_fun(wv), dtype=float)).ravel() if ng else np.zeros(0)
    viol = float(resid.max()) if ng else 0.0
    if viol > 1e-7:
        suspects = _conflicts(g, w, wv, hard_names)
        if suspects:
            raise InitializationError(
                f"model '{cm.name}': no initial point meets every high-priority target "
                f"(violation {viol:.3g}). Conflicting targets: {', '.join(suspects)}. "
                "Lower the priority of one of them, or make them consistent.",
                variables=[s.split(" = ")[0] for s in suspects], path=cm.name)
        _not_converged(cm, t0, resid, hard_names, status, nx)
    return (x0, wv) if held else (wv[:nx], wv[nx:])


def _not_converged(cm, t0, resid, names, status, nx):
    """The constraints are independent (no conflict) but the solve did not meet them: its
    Newton iterations did not converge (no real root near the start values, or none)."""
    worst = [i for i in np.argsort(-resid, kind="stable")[:3] if resid[i] > 1e-7]
    shown = ", ".join(f"{names[i]} (residual {resid[i]:.3g})" for i in worst)
    unknowns = list(cm.alg_names) or list(cm.state_names)
    raise InitializationError(
        f"model '{cm.name}': the initial point did not converge at t0 = {t0:g} s "
        f"({status}); largest residuals: {shown}. Give start values closer to a solution "
        f"(start= of {', '.join(unknowns[:4])}{' ...' if len(unknowns) > 4 else ''}), "
        "check that the equations have a real solution for these parameters, or lower "
        "the priority of a target.", path=cm.name,
        variables=[names[i].split(" (for ")[-1].rstrip(")").split(" = ")[0]
                   for i in worst])


def _conflicts(g, w, wv, names) -> list[str]:
    """High-priority targets among the dependent rows of the constraint Jacobian (none:
    the constraints are independent, so they do not conflict)."""
    jac = np.array(ca.Function("j", [w], [ca.jacobian(g, w)])(wv), dtype=float)
    u, s, _ = np.linalg.svd(jac)
    # left null space of J: rows that are linear combinations of others
    tol = 1e-9 * (s[0] if s.size else 1.0)
    rank = int(np.sum(s > tol))
    involved = set()
    for k in range(rank, jac.shape[0]):
        vec = u[:, k]
        involved.update(np.nonzero(np.abs(vec) > 1e-6)[0].tolist())
    return [names[i] for i in sorted(involved)
            if "(high)" in names[i] or names[i].startswith("initial equation")]


def _check_loop(cm: CompiledModel, X: np.ndarray, where: str) -> None:
    """Raise if the event iteration found no fixed point (see compiler.events)."""
    from mechatron.compiler.compiled import LOOP_FLAG
    nx, nr = cm.nx, cm.nr
    bad = [k for k in range(nr) if X[nx + nr + k] >= 0.75 * LOOP_FLAG]
    if bad:
        from mechatron.solvers.hybrid import loop_message
        raise InitializationError(loop_message(cm, bad, where), path=cm.name,
                                  variables=[cm.relations[k][0] for k in bad])
