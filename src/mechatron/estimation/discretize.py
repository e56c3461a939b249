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
* One sample step is mapped over the experiment with ``mapaccum`` (a native loop) and the
  outputs are evaluated on every sample with ``map``. No Python runs per step.

Limitations: models with event relations (``if_else`` on states, modes) or algebraic loops
left to a DAE solver are refused with a :class:`~mechatron.errors.ModelError`; write
friction and saturations smoothly (``tanh``, the library's ``RotationalFriction``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import casadi as ca
import numpy as np

from mechatron.compiler.compiled import CompiledModel
from mechatron.errors import DataError, ModelError, SimulationError
from mechatron.estimation.native import native
from mechatron.solvers.fixed import NEWTON_ATOL, NEWTON_RTOL, NEWTON_STEP

__all__ = ["Trajectory", "fastest_time_constant", "choose_substeps", "check_model"]

# Radau IIA, 3 stages (order 5)
_S6 = math.sqrt(6.0)
_A = (((88 - 7 * _S6) / 360, (296 - 169 * _S6) / 1800, (-2 + 3 * _S6) / 225),
      ((296 + 169 * _S6) / 1800, (88 + 7 * _S6) / 360, (-2 - 3 * _S6) / 225),
      ((16 - _S6) / 36, (16 + _S6) / 36, 1 / 9))
_C = ((4 - _S6) / 10, (4 + _S6) / 10, 1.0)


def check_model(cm: CompiledModel, what: str = "estimation") -> None:
    """Refuse models this module cannot differentiate through."""
    if cm.nr or cm.nz:
        raise ModelError(
            f"model '{cm.name}': {cm.nr} event relation(s) and {cm.nz} algebraic "
            f"unknown(s); {what} needs a smooth ODE model (no if_else on variables, no "
            f"algebraic loops). Write friction and limits smoothly (tanh, "
            f"RotationalFriction) or use a model variant without events.", path=cm.name)


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
        f = cm.f_ode(0.0, xs, ca.SX(0, 1), ps)
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

    ``function(p, x0, U) -> (Y, X)``: outputs ``(n_out, N)`` and states ``(nx, N)``.
    """

    cm: CompiledModel
    t: np.ndarray
    input_index: list
    output_index: list
    substeps: int = 1
    hold: str = "zoh"
    newton_tol: float = 1e-12
    jit: bool = False

    def __post_init__(self):
        check_model(self.cm)
        if self.hold not in ("zoh", "linear"):
            raise DataError(f"input hold must be 'zoh' or 'linear', got {self.hold!r}.")
        self.t = np.asarray(self.t, dtype=float)
        self._sens = {}
        self._symbols()
        self.function = self._build()

    # ------------------------------------------------------------------------------------
    def _symbols(self) -> None:
        """The stage residual of one substep and its rootfinder."""
        cm = self.cm
        nx, npar, nu = cm.nx, cm.p0.size, len(self.input_index)
        ns = len(_C)
        self._x = ca.SX.sym("x", nx)
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
            fs.append(cm.f_ode(self._ts + _C[i] * self._h, K[i * nx:(i + 1) * nx],
                               ca.SX(0, 1), self._with_u(self._u_at(frac)))[:nx])
        for i in range(ns):
            acc = 0
            for j in range(ns):
                acc = acc + _A[i][j] * fs[j]
            res.append(K[i * nx:(i + 1) * nx] - self._x - self._h * acc)
        self._K = K
        self._res = ca.vertcat(*res)
        args = [self._x, self._p, self._u0, self._u1, self._h, self._ts, self._fa,
                self._hf]
        g = ca.Function("radau_residual", [K, ca.vertcat(*args)], [self._res])
        self._newton = ca.Function("radau_correction", [K, ca.vertcat(*args)],
                                   [ca.solve(ca.jacobian(self._res, K), self._res)])
        self._solve = ca.rootfinder("radau", "fast_newton", g,
                                    {"abstol": self.newton_tol, "max_iter": 30,
                                     "error_on_fail": False})
        self._args = args

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

    def _outputs_sx(self):
        cm = self.cm
        tt = ca.SX.sym("t")
        y = cm.f_out(tt, self._x, ca.SX(0, 1), self._with_u(self._u0))
        yo = ca.vertcat(*[y[i] for i in self.output_index]) if self.output_index \
            else ca.SX(0, 1)
        return tt, yo

    def _build(self) -> ca.Function:
        cm = self.cm
        nx, npar, nu = cm.nx, cm.p0.size, len(self.input_index)
        m = int(self.substeps)
        x, p, u0, u1 = self._x, self._p, self._u0, self._u1
        h = ca.SX.sym("h_sample")
        tk = ca.SX.sym("tk")
        xi = x
        e = ca.DM.zeros(nx, 1)
        for j in range(m):
            K, ej = self._substep(xi, ca.vertcat(xi, p, u0, u1, h / m, tk + j * h / m,
                                                 j / m, 1 / m))
            xi = K[-nx:]
            e = ca.fmax(e, ej)
        step = ca.Function("sample_step", [x, ca.vertcat(p, u0, u1, h, tk)], [xi, e])
        if self.jit:
            step = native(step)
        N = self.t.size
        x0 = ca.MX.sym("x0", nx)
        P = ca.MX.sym("p", npar)
        U = ca.MX.sym("U", nu, N)
        if N > 1:
            Xr, E = step.mapaccum("run", N - 1)(x0, self._run_args(P, U))
            Xs = ca.horzcat(x0, Xr)
        else:
            Xs, E = x0, ca.MX(nx, 0)
        tt, yo = self._outputs_sx()
        out = ca.Function("outputs", [tt, x, p, u0], [yo])
        if self.jit:
            out = native(out)
        out = out.map(N)
        Y = out(ca.DM(self.t.reshape(1, -1)), Xs, ca.repmat(P, 1, N), U)
        self._checked = ca.Function("trajectory_checked", [P, x0, U], [Y, Xs, E],
                                    ["p", "x0", "U"], ["Y", "X", "newton"])
        return ca.Function("trajectory", [P, x0, U], [Y, Xs], ["p", "x0", "U"], ["Y", "X"])

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

    def _run_args(self, P, U):
        N = self.t.size
        return ca.vertcat(ca.repmat(P, 1, N - 1), U[:, :-1], U[:, 1:],
                          ca.DM(np.diff(self.t).reshape(1, -1)),
                          ca.DM(self.t[:-1].reshape(1, -1)))

    # ------------------------------------------------------------------------------------
    def sensitivity_function(self, D: np.ndarray) -> ca.Function:
        """``(p, x0, U, S0) -> (Y, dY)``: outputs and their derivatives along ``q``
        directions. ``D`` (npar x q) maps the directions to parameters; ``S0`` (nx x q)
        is ``dx0/dtheta``. ``dY`` is ``(n_out * q, N)``: column ``k`` holds
        ``vec(dy_k/dtheta)`` (column-major, output index fastest)."""
        D = np.asarray(D, dtype=float)
        key = D.tobytes() + bytes(str(D.shape), "ascii")
        if key in self._sens:
            return self._sens[key]
        cm = self.cm
        nx, npar, nu = cm.nx, cm.p0.size, len(self.input_index)
        q = D.shape[1]
        m = int(self.substeps)
        x, p, u0, u1 = self._x, self._p, self._u0, self._u1
        Dm = ca.DM(D)
        # implicit function theorem on the stage residual G(K, x, p) = 0
        GK = ca.jacobian(self._res, self._K)
        Gx = ca.jacobian(self._res, x)
        Gp = ca.jacobian(self._res, p)
        S = ca.SX.sym("S", nx, q)
        dK = -ca.solve(GK, ca.mtimes(Gx, S) + ca.mtimes(Gp, Dm))
        sub = ca.Function("radau_sensitivity", [self._K, S, ca.vertcat(*self._args)],
                          [dK[-nx:, :]])
        h = ca.SX.sym("h_sample")
        tk = ca.SX.sym("tk")
        xi, Si = x, S
        e = ca.DM.zeros(nx, 1)
        for j in range(m):
            args = ca.vertcat(xi, p, u0, u1, h / m, tk + j * h / m, j / m, 1 / m)
            K, ej = self._substep(xi, args)
            Si = sub(K, Si, args)
            xi = K[-nx:]
            e = ca.fmax(e, ej)
        xa = ca.vertcat(x, ca.vec(S))
        step = ca.Function("sample_step_sens", [xa, ca.vertcat(p, u0, u1, h, tk)],
                           [ca.vertcat(xi, ca.vec(Si)), e])
        if self.jit:
            step = native(step)
        N = self.t.size
        x0 = ca.MX.sym("x0", nx)
        S0 = ca.MX.sym("S0", nx, q)
        P = ca.MX.sym("p", npar)
        U = ca.MX.sym("U", nu, N)
        xa0 = ca.vertcat(x0, ca.vec(S0))
        if N > 1:
            XR, E = step.mapaccum("run_sens", N - 1)(xa0, self._run_args(P, U))
            XA = ca.horzcat(xa0, XR)
        else:
            XA, E = xa0, ca.MX(nx, 0)
        tt, yo = self._outputs_sx()
        dy = ca.mtimes(ca.jacobian(yo, x), S) + ca.mtimes(ca.jacobian(yo, p), Dm)
        out = ca.Function("outputs_sens", [tt, xa, p, u0], [yo, ca.vec(dy)])
        if self.jit:
            out = native(out)
        out = out.map(N)
        Y, dY = out(ca.DM(self.t.reshape(1, -1)), XA, ca.repmat(P, 1, N), U)
        f = _Checked(ca.Function("trajectory_sens", [P, x0, U, S0], [Y, dY, E],
                                 ["p", "x0", "U", "S0"], ["Y", "dY", "newton"]), self)
        self._sens[key] = f
        return f

    def __call__(self, p, x0, U):
        """Outputs ``(n_out, N)`` and states ``(nx, N)`` as NumPy arrays; raises
        :class:`~mechatron.errors.SimulationError` if a substep did not converge."""
        Y, X, E = self._checked(p, x0, U)
        self.check_convergence(E)
        return Y.full(), X.full()


class _Checked:
    """A trajectory function whose last output is the Newton convergence measure: called
    like the CasADi function, it checks that output and returns the others."""

    def __init__(self, fn: ca.Function, traj: Trajectory):
        self.fn = fn
        self.traj = traj

    def __call__(self, *args):
        *outs, E = self.fn(*args)
        self.traj.check_convergence(E)
        return tuple(outs)
