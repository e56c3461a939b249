"""How ``solver="auto"`` chooses: a stiffness probe on the Jacobian at the initial point.

An explicit method (Dormand-Prince, ``rk45``) must keep every step inside its stability
region, ``h |lambda| <= 3.3`` along the negative real axis, for every eigenvalue
``lambda`` of ``J = df/dx``, for the whole run, even after a fast mode has decayed. An
L-stable implicit method (Rosenbrock) only resolves that mode's transient and then steps
at the pace of what is still moving. The probe estimates both step counts over the run
from the spectrum of ``J`` at the start:

- explicit: ``span * rho / 3.3`` (``rho`` the spectral radius), or the implicit
  method's accuracy count below if that is larger;
- implicit: ``TRANSIENT_STEPS`` per fast damped mode (one whose decay ``-Re(lambda)``
  is over ``TRANSIENT`` times the rate ``1/span``: it is gone within the run), plus
  ``span * rho_kept / 0.06`` for the fastest mode that stays (slow, or oscillating:
  ``|Im| > |Re|``, which any method must resolve; 0.06 is the step, in units of
  ``1/|lambda|``, that a 5th-order method takes at ``rtol = 1e-6``), and at least the
  steps that ``max_step`` imposes and :data:`EVENT_STEPS` per tick of every sample
  clock (both methods restart at each event: a 10 kHz PWM sets the pace whatever the
  spectrum, and then the cheaper explicit step wins).

The model is called stiff when the explicit count exceeds :data:`RATIO` times the
implicit one (an implicit step costs a Jacobian and a factorization, several explicit
steps). A start point is only a sample: a model that turns stiff later (a contact that
closes) is judged by its initial state; ``solver=`` overrides the choice.
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np

from mechatron.compiler.compiled import CompiledModel

__all__ = ["Stiffness", "probe", "RATIO"]

STABILITY = 3.3          # Dormand-Prince stability limit on the negative real axis
ACCURACY = 0.06          # steps of a 5th-order method, in units of 1/|lambda| at rtol 1e-6
TRANSIENT = 100.0        # a mode decaying this many times faster than 1/span is transient
TRANSIENT_STEPS = 30     # implicit steps to follow one transient down
RATIO = 10.0             # explicit steps per implicit step at the break-even
EVENT_STEPS = 5          # steps per clock tick (restart after the event, then the step)
DENSE_LIMIT = 400        # above this state count, bound rho by Gershgorin circles


@dataclass(frozen=True)
class Stiffness:
    """Result of :func:`probe`: the verdict and the figures behind it."""

    stiff: bool
    rho: float              # spectral radius of df/dx at the start, 1/s
    rho_kept: float         # fastest mode that is not a transient, 1/s
    explicit_steps: float   # estimated steps of rk45 over the run
    implicit_steps: float   # estimated steps of an L-stable method over the run

    def reason(self) -> str:
        verdict = "stiff" if self.stiff else "not stiff"
        return (f"{verdict}: spectral radius of df/dx at t0 {self.rho:.3g} 1/s, fastest "
                f"non-transient mode {self.rho_kept:.3g} 1/s; about "
                f"{self.explicit_steps:.3g} explicit steps against "
                f"{self.implicit_steps:.3g} implicit ones")


def _jacobian(cm: CompiledModel) -> ca.Function:
    fn = cm._cache.get("jac_x")
    if fn is None:
        t, X = ca.SX.sym("t"), ca.SX.sym("X", cm.nX)
        z, p = ca.SX.sym("z", cm.nz), ca.SX.sym("p", cm.p0.size)
        f = cm.f_ode(t, X, z, p)[:cm.nx]
        fn = cm._cache["jac_x"] = ca.Function("jac_x", [t, X, z, p],
                                              [ca.densify(ca.jacobian(f, X[:cm.nx]))])
    return fn


def clock_periods(cm: CompiledModel, t0: float, X0: np.ndarray, z0: np.ndarray,
                  p: np.ndarray) -> np.ndarray:
    """Period of every sample clock of ``cm``, s: a clock's distance is ``t - t_next``
    with ``t_next = offset + c * period`` (``c`` its counter), so one more count moves it
    by one period."""
    clocks = [k for k, (_, op) in enumerate(cm.relations) if op == "clock"]
    if not clocks:
        return np.zeros(0)
    Xb = np.array(X0, dtype=float)
    Xb[cm.nx + cm.nr + np.array(clocks)] += 1.0
    d0 = np.array(cm.f_dist(t0, X0, z0, p)[0], dtype=float).ravel()
    d1 = np.array(cm.f_dist(t0, Xb, z0, p)[0], dtype=float).ravel()
    periods = (d0 - d1)[clocks]
    return periods[np.isfinite(periods) & (periods > 0)]


def probe(cm: CompiledModel, t0: float, X0: np.ndarray, z0: np.ndarray, p: np.ndarray,
          span: float, max_step: float | None = None) -> Stiffness:
    """Judge the stiffness of the ODE ``cm`` at ``(t0, X0)`` over a run of ``span`` s."""
    if cm.nx == 0:
        return Stiffness(False, 0.0, 0.0, 0.0, 0.0)
    J = np.array(_jacobian(cm)(t0, X0, z0, p), dtype=float)
    if not np.all(np.isfinite(J)):
        return Stiffness(False, float("nan"), float("nan"), 0.0, 0.0)
    floor = float(span / max_step) if max_step else 0.0
    floor = max(floor, EVENT_STEPS * span * float(np.sum(1.0 / clock_periods(cm, t0, X0,
                                                                              z0, p))))
    if cm.nx > DENSE_LIMIT:
        rho = float(np.max(np.sum(np.abs(J), axis=1)))      # Gershgorin bound
        lam = np.array([-rho])
    else:
        lam = np.linalg.eigvals(J)
        rho = float(np.max(np.abs(lam)))
    decay = -lam.real
    transient = (decay * span > TRANSIENT) & (decay >= np.abs(lam.imag))
    kept = np.abs(lam[~transient])
    rho_kept = float(kept.max()) if kept.size else 0.0
    accuracy = span * rho_kept / ACCURACY
    explicit = max(span * rho / STABILITY, accuracy, floor)
    implicit = max(TRANSIENT_STEPS * (1 + int(transient.sum())) + accuracy, floor)
    return Stiffness(bool(explicit > RATIO * implicit), rho, rho_kept, explicit, implicit)
