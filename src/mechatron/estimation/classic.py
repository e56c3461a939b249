"""The classic motor tests of the seed's section 6.1, done on measured data.

Each test uses one physical relation on the part of a measurement where it holds:

* **Locked-rotor resistance.** Rotor held, ``w = 0``; once the current has settled,
  ``di/dt = 0`` and ``V = R i``, so ``R = mean(V) / mean(i - i_offset)``. The sensor offset
  ``i_offset`` is the mean current before the first voltage step.
* **Electrical time constant.** Rotor held, a voltage step: ``L di/dt + R i = V`` gives
  ``i(t) = i_inf (1 - exp(-(t - t0)/tau_e))`` with ``tau_e = L/R``, hence ``L = R tau_e``.
  Fitted by nonlinear least squares on every rising edge.
* **Motor constant and friction.** Free running at constant speed: ``V = R i + k w`` gives
  ``k = (V - R i) / w``; the torque balance ``k i = B w + T_C`` at several speeds gives the
  viscous coefficient ``B`` (slope) and the Coulomb torque ``T_C`` (intercept). With one
  speed only, ``B = k i / w`` (the seed's formula, which lumps Coulomb friction into B).
* **Mechanical time constant.** Free running, a voltage step from rest: with the
  electrical transient much faster, ``J dw/dt = k (V - k w)/R - B w - T_C``, a first-order
  response with ``tau_m = J R / (k^2 + R B)``, hence ``J = tau_m (k^2 + R B) / R``. (The
  seed writes ``J = B tau_m``, which holds for a current-driven motor only; with voltage
  drive the back EMF adds the damping ``k^2/R``, here 25 times ``B``.)
* **Stribeck friction.** Steady-state torque ``k i`` against speed (speed-controlled runs,
  the seed's Fig. 6-8), fitted with the Stribeck curve of
  :func:`~mechatron.estimation.bench.stribeck_torque` (``T_brk``, ``w_brk``, ``T_C``,
  ``B``).

Every function returns a :class:`ClassicResult` (value, its standard error where the fit
gives one, and the numbers used).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from mechatron.errors import DataError
from mechatron.estimation.data import Experiment

__all__ = ["ClassicResult", "sensor_offset", "locked_rotor_resistance",
           "electrical_time_constant", "free_running_constants",
           "mechanical_time_constant", "fit_stribeck", "steady_levels"]


@dataclass
class ClassicResult:
    """One identified quantity: ``value``, its standard error ``std`` (NaN if none) and
    ``details`` (intermediate numbers, for the report)."""

    name: str
    value: float
    unit: str
    std: float = math.nan
    details: dict = field(default_factory=dict)


def _edges(V: np.ndarray) -> np.ndarray:
    """Sample indices where the (held) voltage changes."""
    return np.flatnonzero(np.abs(np.diff(V)) > 1e-9 * max(1.0, np.abs(V).max())) + 1


def sensor_offset(exp: Experiment, current: str = "i", voltage: str = "V") -> float:
    """Mean current before the first voltage change (the motor is at rest, unpowered)."""
    V = exp.signal(voltage)
    e = _edges(V)
    first = e[0] if e.size else exp.n
    if first < 3 or np.any(V[:first] != 0):
        return 0.0
    return float(np.mean(exp.signal(current)[:first]))


def steady_levels(exp: Experiment, voltage: str = "V", settle: float = 0.5):
    """``(V level, slice)`` for each constant-voltage interval, keeping its last
    ``1 - settle`` fraction (the settled part)."""
    V = exp.signal(voltage)
    bounds = np.concatenate([[0], _edges(V), [exp.n]])
    out = []
    for a, b in zip(bounds[:-1], bounds[1:]):
        if b - a < 4:
            continue
        start = a + int(math.ceil(settle * (b - a)))
        out.append((float(V[a]), slice(start, b)))
    return out


def locked_rotor_resistance(exp: Experiment, *, current: str = "i", voltage: str = "V",
                            settle: float = 0.5) -> ClassicResult:
    """``R = V / (i - offset)`` over the settled parts of the powered intervals."""
    off = sensor_offset(exp, current, voltage)
    i = exp.signal(current) - off
    V = exp.signal(voltage)
    num, den, parts = 0.0, 0.0, []
    for level, sl in steady_levels(exp, voltage, settle):
        if level == 0:
            continue
        num += np.sum(V[sl])
        den += np.sum(i[sl])
        parts.append(np.mean(V[sl]) / np.mean(i[sl]))
    if not parts:
        raise DataError(f"{exp.source}: column '{voltage}': no powered interval long enough "
                        "to settle; the locked-rotor test needs a voltage step.",
                        path=exp.source)
    R = num / den
    std = float(np.std(parts, ddof=1) / math.sqrt(len(parts))) if len(parts) > 1 else math.nan
    return ClassicResult("R", float(R), "Ohm", std,
                         {"offset_A": off, "intervals": len(parts), "per_interval": parts})


def electrical_time_constant(exp: Experiment, R: float, *, current: str = "i",
                             voltage: str = "V") -> ClassicResult:
    """``tau_e`` from every rising edge of a locked-rotor run, and ``L = R tau_e``.

    The returned value is ``L``; ``details["tau_e"]`` is the time constant."""
    from scipy.optimize import curve_fit
    off = sensor_offset(exp, current, voltage)
    i = exp.signal(current) - off
    V = exp.signal(voltage)
    t = exp.t
    edges = _edges(V)
    bounds = np.concatenate([edges, [exp.n]])
    taus = []
    for a, b in zip(bounds[:-1], bounds[1:]):
        if V[a] <= V[a - 1] or b - a < 6:
            continue
        tt = t[a:b] - t[a]                   # the new voltage is held from t[a] on
        yy = i[a:b]
        i_inf0 = float(np.mean(yy[len(yy) // 2:]))
        tau0 = max(float(np.interp(0.632 * i_inf0, yy, tt)) if i_inf0 > 0 else tt[1],
                   tt[1] / 10)

        def model(x, i_inf, tau):
            return i_inf * (1 - np.exp(-x / tau))
        try:
            (i_inf, tau), _ = curve_fit(model, tt, yy, p0=(i_inf0, tau0), maxfev=2000)
        except RuntimeError:
            continue
        taus.append(abs(tau))
    if not taus:
        raise DataError(f"{exp.source}: column '{voltage}': no rising voltage edge with a "
                        "settled response; the test needs a locked-rotor step.",
                        path=exp.source)
    tau = float(np.mean(taus))
    std = float(np.std(taus, ddof=1) / math.sqrt(len(taus))) if len(taus) > 1 else math.nan
    return ClassicResult("L", R * tau, "H", R * std if std == std else math.nan,
                         {"tau_e_s": tau, "edges": len(taus), "per_edge_s": taus})


def free_running_constants(exp: Experiment, R: float, *, current: str = "i",
                           voltage: str = "V", speed: str = "w", settle: float = 0.6):
    """``k``, ``B`` and ``T_C`` from the settled speed and current of each voltage level.

    Returns ``(k, B, T_C)`` results; with a single powered level ``T_C`` is NaN and ``B``
    is the seed's ``k i / w``."""
    off = sensor_offset(exp, current, voltage)
    i = exp.signal(current) - off
    w = exp.signal(speed)
    Vs, is_, ws = [], [], []
    for level, sl in steady_levels(exp, voltage, settle):
        if level == 0:
            continue
        Vs.append(level)
        is_.append(float(np.mean(i[sl])))
        ws.append(float(np.mean(w[sl])))
    if not Vs:
        raise DataError(f"{exp.source}: column '{voltage}': no powered interval; the "
                        "free-running test needs a voltage step.", path=exp.source)
    Vs, is_, ws = map(np.array, (Vs, is_, ws))
    ks = (Vs - R * is_) / ws
    k = float(np.mean(ks))
    tau = k * is_
    if len(Vs) >= 2:
        A = np.column_stack([ws, np.ones_like(ws)])
        (B, T_C), *_ = np.linalg.lstsq(A, tau, rcond=None)
    else:
        B, T_C = float(tau[0] / ws[0]), math.nan
    det = {"levels_V": Vs.tolist(), "i_A": is_.tolist(), "w_rad_s": ws.tolist(),
           "offset_A": off}
    return (ClassicResult("k", k, "V*s/rad",
                          float(np.std(ks, ddof=1) / math.sqrt(len(ks))) if len(ks) > 1
                          else math.nan, det),
            ClassicResult("B", float(B), "N*m*s/rad", math.nan, det),
            ClassicResult("T_C", float(T_C), "N*m", math.nan, det))


def mechanical_time_constant(exp: Experiment, R: float, k: float, B: float,
                             L: float = 0.0, *, speed: str = "w",
                             voltage: str = "V") -> ClassicResult:
    """``J`` from the speed response to the first voltage step from rest.

    The response of ``w`` to a voltage step is that of ``k / (L J s^2 + (L B + R J) s +
    R B + k^2)`` (Coulomb friction only shifts the final value). For a system without
    zeros the area between the final value and the normalized response is the sum of the
    time constants, ``tau_m + tau_e = (L B + R J) / (R B + k^2)``, hence
    ``J = (A (R B + k^2) - L B) / R`` with ``A = integral (1 - w/w_inf) dt``. An encoder
    speed (count difference over each sample) integrates exactly to the angle, so the
    area is exact up to one count. With ``L = 0`` this is the first-order ``tau_m`` of
    the seed. The value returned is ``J``; ``details["tau_sum_s"]`` is ``A``."""
    V = exp.signal(voltage)
    w = exp.signal(speed)
    t = exp.t
    e = _edges(V)
    if not e.size:
        raise DataError(f"{exp.source}: column '{voltage}': no voltage step.",
                        path=exp.source)
    a = e[0]
    b = e[1] if e.size > 1 else exp.n
    if b - a < 20:
        raise DataError(f"{exp.source}: column '{voltage}', row {exp.rows[a]}: the first "
                        f"step lasts {b - a} samples; too short to settle.", path=exp.source)
    tail = slice(a + int(0.7 * (b - a)), b)
    w_inf = float(np.mean(w[tail]))
    # w[k] (k > a) is the mean speed over [t[k-1], t[k]]
    dt = np.diff(t[a:b])
    area = float(np.sum((1 - w[a + 1:b] / w_inf) * dt))
    J = (area * (R * B + k ** 2) - L * B) / R
    return ClassicResult("J", float(J), "kg*m^2", math.nan,
                         {"tau_sum_s": area, "w_inf_rad_s": w_inf,
                          "tau_m_s": area - (L / R if L else 0.0)})


def fit_stribeck(w, torque) -> dict:
    """Fit ``T_brk, w_brk, T_C, B`` of the Stribeck curve to torque-speed points.

    Returns a dict of :class:`ClassicResult` by name."""
    from scipy.optimize import least_squares
    from mechatron.estimation.bench import stribeck_torque
    w = np.asarray(w, dtype=float)
    tq = np.asarray(torque, dtype=float)
    if w.size < 4:
        raise DataError(f"fit_stribeck: {w.size} torque-speed points; at least 4 are "
                        "needed for 4 parameters.")
    fast = np.abs(w) > 0.3 * np.abs(w).max()
    slope, icpt = np.polyfit(np.abs(w[fast]), np.abs(tq[fast]), 1)
    T_C0 = max(icpt, 1e-12)
    peak = np.argmax(np.abs(tq))
    T_b0 = max(abs(tq[peak]), 1.05 * T_C0)
    w_b0 = max(abs(w[peak]), 1e-6)
    x0 = np.array([T_b0, w_b0, T_C0, max(slope, 1e-12)])

    def res(x):
        return (stribeck_torque(w, *(x * x0)) - tq) / (np.abs(tq).max())
    sol = least_squares(res, np.ones(4), bounds=(1e-6, np.inf), xtol=1e-14, ftol=1e-14)
    vals = sol.x * x0
    dof = max(w.size - 4, 1)
    s2 = float(sol.fun @ sol.fun) / dof
    try:
        std = np.sqrt(np.clip(np.diag(s2 * np.linalg.inv(sol.jac.T @ sol.jac)), 0, None)) * x0
    except np.linalg.LinAlgError:
        std = np.full(4, math.nan)
    names = [("T_brk", "N*m"), ("w_brk", "rad/s"), ("T_C", "N*m"), ("B", "N*m*s/rad")]
    return {n: ClassicResult(n, float(v), u, float(s))
            for (n, u), v, s in zip(names, vals, std)}
