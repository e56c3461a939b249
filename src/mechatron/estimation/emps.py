"""Estimation on real data: the EMPS benchmark (electro-mechanical positioning system).

Data and reference values: A. Janot, M. Gautier, M. Brunot, "Data Set and Reference Models
of EMPS", 2019 Workshop on Nonlinear System Identification Benchmarks, Eindhoven. Results
on this data must cite them.

Model (the authors')::

    M q'' = gtau vir - Fv q' - Fc sign(q') - offset

with ``sign`` smoothed as ``tanh(q'/v_eps)``, ``v_eps = 1e-4 m/s`` (the drive reverses in
a fraction of a millisecond through that band). The plant is a double integrator under
closed-loop position control, so the data cannot be fitted by simulating the plant alone
from the logged force (it drifts). We simulate the **closed loop**: the plant between
samples (RK4, 4 substeps per 1 ms sample, force held) and, at every sample ``k``, the
logged controller law evaluated on the *simulated* position::

    qf[k]  = (q[k] + q[k-1]) / 2,        dq[k] = (qf[k] - qf[k-1]) / Ts
    vir[k] = sat_10V( kv (kp (qg[k] - q[k]) - dq[k]) + pulse[k] )

(no unit delay, pulse added before the saturation: the structure that reproduces the
logged ``vir`` best, see the data's README). The reference ``qg`` (and the pulses) are the
only inputs. The parameters ``M, Fv, Fc, offset`` minimize the weighted squared errors of
the simulated position and controller output against the logged ``qm`` and ``vir``
(weights ``1/sigma^2``, ``sigma_q = 2 um``, ``sigma_vir = 0.08 V``: the residual levels of
the reference model), with exact derivatives (CasADi forward AD through the whole run) and
the Levenberg-Marquardt solver and statistics of :func:`~mechatron.estimation.estimate`.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import casadi as ca
import numpy as np

from mechatron.errors import DataError
from mechatron.estimation.data import Experiment, load_experiment

__all__ = ["load_emps", "EMPSProblem", "REFERENCE", "closed_loop", "relative_error",
           "default_data_dir"]

#: IDIM-LS reference values of the authors (symmetric friction model).
REFERENCE = {"M": 95.1089, "Fv": 203.5034, "Fc": 20.3935, "offset": -3.1648}
REFERENCE_STD = {"M": 0.1085, "Fv": 1.146, "Fc": 0.1012, "offset": 0.0444}
GTAU, KP, KV, TS, VSAT = 35.15065188, 160.18, 243.45, 1e-3, 10.0
V_EPS = 1e-4
SUBSTEPS = 4
NAMES = ["M", "Fv", "Fc", "offset"]


def default_data_dir() -> Path:
    """``<repository>/../shared/data/emps`` (where the project keeps the data; not copied
    into the repository)."""
    return Path(__file__).resolve().parents[3] / ".." / "shared" / "data" / "emps"


def load_emps(path) -> Experiment:
    """An EMPS file as an :class:`Experiment`: inputs ``qg`` (and ``pulse``), outputs
    ``qm`` and ``vir``; errors name the file, column and row."""
    path = Path(path)
    import pandas as pd
    if not path.exists():
        raise DataError(f"{path}: no such file. The EMPS data live in "
                        f"{default_data_dir()} (see its README.md).", path=str(path))
    cols = list(pd.read_csv(path, nrows=0).columns)
    inputs = {"qg": "qg_m"}
    if "pulse_V" in cols:
        inputs["pulse"] = "pulse_V"
    exp = load_experiment(path, time="t_s", inputs=inputs,
                          outputs={"qm": "qm_m", "vir": "vir_V"},
                          units={"qg": "m", "pulse": "V", "qm": "m", "vir": "V"},
                          sigma={"qm": 2e-6, "vir": 0.08})
    dt = np.diff(exp.t)
    bad = np.flatnonzero(np.abs(dt - TS) > 1e-6)
    if bad.size:
        raise DataError(f"{exp.where('t_s', bad[0] + 1)}: sample interval {dt[bad[0]]:g} s; "
                        f"the EMPS controller runs at Ts = {TS:g} s.", path=str(path))
    return exp


def _sat(x, a):
    return ca.fmin(ca.fmax(x, -a), a)


def closed_loop(exp: Experiment) -> ca.Function:
    """``F(theta = [M, Fv, Fc, offset]) -> (q (N,), vir (N,))``: the closed loop over
    ``exp`` (see the module docstring)."""
    n = exp.n
    th = ca.SX.sym("theta", 4)
    M, Fv, Fc, off = th[0], th[1], th[2], th[3]
    x = ca.SX.sym("x", 4)                  # q, v, q[k-1], qf[k-1]
    qg = ca.SX.sym("qg")
    pulse = ca.SX.sym("pulse")
    q, v, q_prev, qf_prev = x[0], x[1], x[2], x[3]
    qf = 0.5 * q + 0.5 * q_prev
    dq = (qf - qf_prev) / TS
    vir = _sat(KV * (KP * (qg - q) - dq) + pulse, VSAT)

    def f(qq, vv):
        return vv, (GTAU * vir - Fv * vv - Fc * ca.tanh(vv / V_EPS) - off) / M
    h = TS / SUBSTEPS
    qq, vv = q, v
    for _ in range(SUBSTEPS):
        k1 = f(qq, vv)
        k2 = f(qq + h / 2 * k1[0], vv + h / 2 * k1[1])
        k3 = f(qq + h / 2 * k2[0], vv + h / 2 * k2[1])
        k4 = f(qq + h * k3[0], vv + h * k3[1])
        qq = qq + h / 6 * (k1[0] + 2 * k2[0] + 2 * k3[0] + k4[0])
        vv = vv + h / 6 * (k1[1] + 2 * k2[1] + 2 * k3[1] + k4[1])
    step = ca.Function("emps_step", [x, ca.vertcat(qg, pulse, th)],
                       [ca.vertcat(qq, vv, q, qf), ca.vertcat(q, vir)])
    run = step.mapaccum("emps_run", n)
    qm0 = float(exp.outputs["qm"][0])
    x0 = ca.DM([qm0, 0.0, qm0, qm0])
    T = ca.MX.sym("theta", 4)
    pulses = exp.inputs.get("pulse", np.zeros(n))
    U = ca.DM(np.vstack([exp.inputs["qg"], pulses]))
    _, Y = run(x0, ca.vertcat(U, ca.repmat(T, 1, n)))
    return ca.Function("emps_closed_loop", [T], [Y[0, :].T, Y[1, :].T])


class EMPSProblem:
    """The closed-loop output-error problem on one EMPS file, in the interface that
    :func:`~mechatron.estimation.estimate` solves (parameters ``M, Fv, Fc, offset``)."""

    def __init__(self, exp: Experiment, initial=None):
        self.experiments = [exp]
        self.names = list(NAMES)
        init = dict(M=60.0, Fv=100.0, Fc=10.0, offset=0.0)
        init.update(initial or {})
        self.initial = np.array([init[n] for n in NAMES], dtype=float)
        self.scales = [abs(v) or 10.0 for v in self.initial]
        self.bounds = (np.array([1.0, 0.0, 0.0, -math.inf]), np.full(4, math.inf))

        class _Free:
            def __init__(self, name):
                self.name = name
        self.free = [_Free(n) for n in NAMES[:3]] + [_Free("offset")]
        self.sigma = np.array([exp.sigma["qm"], exp.sigma["vir"]])
        self.F = closed_loop(exp)
        T = ca.MX.sym("theta", 4)
        q, vir = self.F(T)
        r = ca.vertcat((q - ca.DM(exp.outputs["qm"])) / self.sigma[0],
                       (vir - ca.DM(exp.outputs["vir"])) / self.sigma[1])
        self._fj = ca.Function("emps_residual", [T], [r, ca.jacobian(r, T)])
        self.n_residuals = 2 * exp.n
        self.bound = [{"exp": exp, "out_labels": ["qm", "vir"],
                       "Ym": [exp.outputs["qm"], exp.outputs["vir"]],
                       "sigma": self.sigma}]

    def jacobian(self, theta):
        r, j = self._fj(theta)
        return r.full().ravel(), j.full()

    def residuals(self, theta):
        return self.jacobian(theta)[0]

    def refine(self, theta, ratio=1.0):
        return False

    def simulate(self, theta=None):
        theta = self.initial if theta is None else theta
        q, vir = self.F(theta)
        return [{"qm": q.full().ravel(), "vir": vir.full().ravel()}]


def relative_error(measured, simulated, *, skip: int = 49) -> float:
    """The authors' relative error in percent, ``100 ||y - y_sim|| / ||y||`` (first
    ``skip`` samples dropped, as in their scripts)."""
    y = np.asarray(measured)[skip:]
    return float(100 * np.linalg.norm(y - np.asarray(simulated)[skip:]) / np.linalg.norm(y))


def validate(theta, exp: Experiment) -> dict:
    """Closed-loop simulation of ``exp`` with ``theta``: RMS errors and the authors'
    relative errors of position and controller output (force = gtau vir)."""
    q, vir = closed_loop(exp)(np.asarray(theta, dtype=float))
    q, vir = q.full().ravel(), vir.full().ravel()
    qm, vm = exp.outputs["qm"], exp.outputs["vir"]
    return {"rms_q_m": float(np.sqrt(np.mean((qm - q) ** 2))),
            "rms_vir_V": float(np.sqrt(np.mean((vm - vir) ** 2))),
            "relerr_position_pct": relative_error(qm, q),
            "relerr_force_pct": relative_error(vm, vir),
            "q": q, "vir": vir}


def reference_meta(data_dir=None) -> dict:
    path = Path(data_dir or default_data_dir()) / "emps_meta.json"
    return json.loads(path.read_text()) if path.exists() else {}
