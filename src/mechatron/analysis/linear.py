"""Linearization and trimming of a compiled model (Simulink's ``linearize`` and
``findop``, Modelica tools' ``linearize``).

At an operating point ``(t, x, z, p)`` of the compiled DAE ``x' = f(t, x, z, p)``,
``0 = g(t, x, z, p)``, ``y = h(t, x, z, p)``, with inputs ``u`` chosen among the slots of
``p`` (parameters and external inputs), the algebraic variables are eliminated exactly::

    A = f_x - f_z g_z^-1 g_x        B = f_u - f_z g_z^-1 g_u
    C = h_x - h_z g_z^-1 g_x        D = h_u - h_z g_z^-1 g_u

from the compiled functions' exact (automatic) derivatives; modes of event relations are
held at the operating point. The result is a python-control ``StateSpace`` with the
states, inputs and outputs named by instance path.

:func:`trim` finds an operating point at rest (``x' = 0``): given targets for some
variables and free inputs, it solves the steady-state equations by Newton's method on the
exact Jacobian and refuses to return a point whose residual did not converge.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import casadi as ca
import numpy as np

from mechatron.compiler.compiled import CompiledModel
from mechatron.core.component import Component
from mechatron.errors import SimulationError
from mechatron.solvers.initial import initialize

__all__ = ["OperatingPoint", "linearize", "trim", "linear_matrices"]


@dataclass
class OperatingPoint:
    """A point of the compiled model: time, states, algebraic variables, parameters."""

    t: float
    x: np.ndarray          # the integration state X (continuous states, then modes)
    z: np.ndarray
    p: np.ndarray
    #: every logged variable's value at the point, by instance path
    values: dict[str, float] = field(default_factory=dict)
    #: largest residual of the steady-state equations (trim only)
    residual: float | None = None

    def __getitem__(self, name: str) -> float:
        return self.values[name]


def _compiled(model) -> CompiledModel:
    if isinstance(model, CompiledModel):
        return model
    if isinstance(model, Component):
        from mechatron.compiler.pipeline import compile_model
        return compile_model(model)
    raise TypeError(f"expected a Component or CompiledModel, got {model!r}.")


def _values(cm: CompiledModel, t, X, z, p) -> dict[str, float]:
    y = np.asarray(cm.f_out(t, X, z, p), dtype=float).ravel()
    return dict(zip(cm.names, y.tolist()))


def operating_point(model, at=None, *, params: dict | None = None,
                    t0: float = 0.0) -> OperatingPoint:
    """The point to linearize at: ``None`` the consistent initial point; a number, the
    state reached by simulating the default way up to that time; a dict of state values
    (instance paths) applied to the initial point; or an :class:`OperatingPoint`."""
    cm = _compiled(model)
    if isinstance(at, OperatingPoint):
        return at
    p = cm.parameter_vector(params)
    X, z, _ = initialize(cm, p, t0)
    t = t0
    if isinstance(at, (int, float)) and not isinstance(at, bool):
        if cm.nr:
            # a simlog holds the states, not the event modes reached at that time
            raise SimulationError(f"model '{cm.name}': linearizing at a time needs the "
                                  "event modes reached then, which a simulation log does "
                                  "not keep; pass the state values as a dict instead.",
                                  path=cm.name)
        from mechatron.solvers.simulate import simulate
        res = simulate(cm, float(at), params=params, t0=t0)
        t = float(at)
        X = np.asarray(X, dtype=float).copy()
        for k, name in enumerate(cm.state_names):
            X[k] = res.final(name)
        z = np.array([res.final(n) for n in cm.alg_names], dtype=float)
    elif isinstance(at, dict):
        X = np.asarray(X, dtype=float).copy()
        index = {n: k for k, n in enumerate(cm.state_names)}
        unknown = sorted(set(at) - set(index))
        if unknown:
            raise SimulationError(f"model '{cm.name}': {', '.join(unknown)} are not states "
                                  f"of the compiled model. States: "
                                  f"{', '.join(cm.state_names[:12])}.", path=cm.name)
        for name, value in at.items():
            X[index[name]] = float(value)
    elif at is not None:
        raise TypeError(f"linearize: 'at' must be None, a time, a dict of state values or "
                        f"an OperatingPoint, got {at!r}.")
    X, z, p = (np.asarray(v, dtype=float).ravel() for v in (X, z, p))
    return OperatingPoint(t, X, z, p, _values(cm, t, X, z, p))


def _slots(cm: CompiledModel, inputs) -> list[int]:
    index = {n: k for k, n in enumerate(cm.param_names)}
    bad = [u for u in inputs if u not in index]
    if bad:
        import difflib
        hint = {u: difflib.get_close_matches(u, cm.param_names, 2) for u in bad}
        raise SimulationError(
            f"model '{cm.name}': cannot use {', '.join(bad)} as input(s): not a parameter or "
            "external input of the compiled model"
            + "".join(f" ('{u}': did you mean {', '.join(v)}?)" for u, v in hint.items() if v)
            + ". Inputs are parameters (e.g. a source's voltage) or external inputs.",
            path=cm.name)
    return [index[u] for u in inputs]


def _rows(cm: CompiledModel, outputs) -> list[int]:
    index = {n: k for k, n in enumerate(cm.names)}
    bad = [y for y in outputs if y not in index]
    if bad:
        raise SimulationError(f"model '{cm.name}': no logged variable {', '.join(bad)}.",
                              path=cm.name)
    return [index[y] for y in outputs]


def linear_matrices(model, at=None, *, inputs=(), outputs=None, params=None):
    """``(A, B, C, D, point)`` as NumPy arrays (see the module docstring); ``outputs``
    defaults to the states."""
    cm = _compiled(model)
    op = operating_point(cm, at, params=params)
    nx, nz = cm.nx, cm.nz
    u_idx = _slots(cm, list(inputs))
    outputs = list(cm.state_names) if outputs is None else list(outputs)
    y_idx = _rows(cm, outputs)
    x = ca.MX.sym("x", nx)
    z = ca.MX.sym("z", nz)
    u = ca.MX.sym("u", len(u_idx))
    p = ca.MX(ca.DM(op.p))
    for j, k in enumerate(u_idx):
        p[k] = u[j]
    X = ca.vertcat(x, ca.DM(op.x[nx:])) if op.x.size > nx else x
    f = cm.f_ode(op.t, X, z, p)[:nx]
    g = cm.f_alg(op.t, X, z, p) if nz else ca.MX(0, 1)
    h = cm.f_out(op.t, X, z, p)[y_idx] if y_idx else ca.MX(0, 1)     # one call
    parts = [ca.jacobian(e, v) for e in (f, g, h) for v in (x, z, u)]
    J = ca.Function("linearization", [x, z, u], parts)
    vals = J(op.x[:nx], op.z, op.p[u_idx] if u_idx else np.zeros(0))
    fx, fz, fu, gx, gz, gu, hx, hz, hu = (np.asarray(ca.DM(v), dtype=float) for v in vals)
    if nz:
        cond = np.linalg.cond(gz) if gz.size else 1.0
        if not np.isfinite(cond) or cond > 1e14:
            raise SimulationError(f"model '{cm.name}': the algebraic equations are singular "
                                  f"at the operating point (condition number {cond:.3g}); "
                                  "the algebraic variables cannot be eliminated there.",
                                  path=cm.name)
        sx = np.linalg.solve(gz, gx)
        su = np.linalg.solve(gz, gu)
        A, B = fx - fz @ sx, fu - fz @ su
        C, D = hx - hz @ sx, hu - hz @ su
    else:
        A, B, C, D = fx, fu, hx, hu
    A, B, C, D = (np.atleast_2d(m).reshape(r, c) for m, r, c in
                  ((A, nx, nx), (B, nx, len(u_idx)), (C, len(y_idx), nx),
                   (D, len(y_idx), len(u_idx))))
    return A, B, C, D, op


def linearize(model, at=None, *, inputs=(), outputs=None, params=None):
    """The linearized model at an operating point, as a python-control ``StateSpace``.

    Parameters
    ----------
    model : Component or CompiledModel
    at : None, float, dict or OperatingPoint
        None: the consistent initial point; a time: the state a default simulation
        reaches then; a dict: state values (instance paths) applied to the initial point;
        an :class:`OperatingPoint` (from :func:`trim`).
    inputs : list of str
        Parameters or external inputs that become the system's inputs, e.g.
        ``["source.V"]``.
    outputs : list of str, optional
        Logged variables that become its outputs (default: the states).
    params : dict, optional
        Parameter values of the operating point.

    Returns
    -------
    control.StateSpace
        Its signals are named by instance path with ``_`` for ``.`` (python-control does
        not allow dots); the paths are its ``state_paths``, ``input_paths`` and
        ``output_paths``, the operating point its ``operating_point``.
    """
    import control
    cm = _compiled(model)
    A, B, C, D, op = linear_matrices(cm, at, inputs=inputs, outputs=outputs, params=params)
    outputs = list(cm.state_names) if outputs is None else list(outputs)
    sys = control.ss(A, B, C, D, states=_labels(cm.state_names), inputs=_labels(inputs),
                     outputs=_labels(outputs), name=cm.name)
    sys.operating_point = op
    sys.state_paths, sys.input_paths = list(cm.state_names), list(inputs)
    sys.output_paths = outputs
    return sys


def _labels(paths) -> list[str]:
    """python-control's signal names cannot hold '.': instance paths with '_' instead
    (the paths themselves are kept as ``state_paths``, ``input_paths``,
    ``output_paths``); a clash is resolved by numbering."""
    out, seen = [], set()
    for path in paths:
        label = path.replace(".", "_").replace("(", "_").replace(")", "")
        base, k = label, 1
        while label in seen:
            k += 1
            label = f"{base}_{k}"
        seen.add(label)
        out.append(label)
    return out


def trim(model, *, targets: dict | None = None, free=(), params: dict | None = None,
         t: float = 0.0, tol: float = 1e-10, max_iter: int = 50) -> OperatingPoint:
    """An equilibrium (``x' = 0``, the algebraic equations met) where each variable of
    ``targets`` (instance path -> value) holds its value, found by moving the states, the
    algebraic variables and the ``free`` parameters or inputs.

    The unknowns and equations must match in number: one free input per target. Newton's
    method on the exact Jacobian, from the consistent initial point; a point whose
    residual is not below ``tol`` (relative to the residual's scale) after ``max_iter``
    steps is an error naming the equation with the largest residual, never a result.
    """
    cm = _compiled(model)
    targets = dict(targets or {})
    op = operating_point(cm, None, params=params, t0=t)
    nx, nz = cm.nx, cm.nz
    u_idx = _slots(cm, list(free))
    y_idx = _rows(cm, list(targets))
    if len(u_idx) != len(y_idx):
        raise SimulationError(f"model '{cm.name}': trim needs one free input per target, got "
                              f"{len(y_idx)} target(s) and {len(u_idx)} free input(s).",
                              path=cm.name)
    x, z, u = ca.MX.sym("x", nx), ca.MX.sym("z", nz), ca.MX.sym("u", len(u_idx))
    p = ca.MX(ca.DM(op.p))
    for j, k in enumerate(u_idx):
        p[k] = u[j]
    X = ca.vertcat(x, ca.DM(op.x[nx:])) if op.x.size > nx else x
    target = ca.DM([float(v) for v in targets.values()])
    y = cm.f_out(t, X, z, p)[y_idx] if y_idx else ca.MX(0, 1)          # one call
    r = ca.vertcat(cm.f_ode(t, X, z, p)[:nx], cm.f_alg(t, X, z, p) if nz else ca.MX(0, 1),
                   y - target)
    w = ca.vertcat(x, z, u)
    F = ca.Function("trim", [w], [r, ca.jacobian(r, w)])
    names = ([f"der({n}) == 0" for n in cm.state_names] +
             [f"algebraic equation {k} ({n})" for k, n in enumerate(cm.alg_names)] +
             [f"{n} == {v:g}" for n, v in targets.items()])
    wk = np.concatenate([op.x[:nx], op.z, op.p[u_idx] if u_idx else np.zeros(0)])
    scale = 1.0
    for _ in range(max_iter):
        rv, Jv = (np.asarray(v, dtype=float) for v in F(wk))
        rv = rv.ravel()
        scale = max(scale, float(np.max(np.abs(rv))) if rv.size else 1.0)
        if rv.size == 0 or np.max(np.abs(rv)) <= tol * scale:
            break
        step, *_ = np.linalg.lstsq(Jv, -rv, rcond=None)
        wk = wk + step
    else:
        rv = np.asarray(F(wk)[0], dtype=float).ravel()
        k = int(np.argmax(np.abs(rv)))
        raise SimulationError(f"model '{cm.name}': trim did not converge in {max_iter} Newton "
                              f"steps; largest residual {abs(rv[k]):.3g} in {names[k]}. Try "
                              "other targets or free inputs, or a start value near the "
                              "equilibrium.", path=cm.name)
    Xk = op.x.copy()
    Xk[:nx] = wk[:nx]
    zk = wk[nx:nx + nz]
    pk = op.p.copy()
    pk[u_idx] = wk[nx + nz:]
    res = float(np.max(np.abs(np.asarray(F(wk)[0], dtype=float)))) if wk.size else 0.0
    return OperatingPoint(t, Xk, zk, pk, _values(cm, t, Xk, zk, pk), residual=res)
