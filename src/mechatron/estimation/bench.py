"""A virtual test bench: realistic measurements of a DC motor with hidden true parameters.

The bench stands in for the seed's MechLab DoubleDrive (its chapter 6.1). A motor with
the *true* parameters (by default the seed's table 6-1) is driven by a commanded voltage
profile; what comes out is what a data logger would record:

* samples at a fixed rate ``fs``; the commanded voltage is held between samples (a DAC),
* the armature current from a current sensor with Gaussian noise (``noise`` times the
  locked-rotor current ``V/R`` of 19.2 V, i.e. 1% of full scale by default) and a constant
  offset (``current_offset``),
* the rotor angle from an incremental encoder with ``encoder_lines`` lines (4 counts per
  line, quadrature), truncated to whole counts; the speed ``w`` is the count difference
  over one sample (what a drive computes),
* friction: viscous only, or Stribeck + Coulomb + viscous (Simscape's formula, as
  :class:`~mechatron.library.rotational.RotationalFriction`).

The true motor is integrated by CVODES (BDF, rtol 1e-10) over each sample interval, an
implementation independent of the Radau discretization the estimator uses.

The model is :class:`DCMotorRig`: the motor written as ODEs with states ``i``, ``w``,
``phi``; the parameter ``locked`` = 1 holds the rotor (the locked-rotor test).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import casadi as ca
import numpy as np

import mechatron as mt
from mechatron.estimation.data import Experiment
from mechatron.models.dc_motor import SeedMotor

__all__ = ["DCMotorRig", "VirtualBench", "TABLE_6_1", "FrictionCurve", "stribeck_torque"]

#: The seed's table 6-1 (calculated parameters of the DoubleDrive motor), SI units.
TABLE_6_1 = {"R": 7.1, "L": 3.408e-4, "k": 0.151, "J": 4.8e-6, "B": 1.236e-4,
             "T_brk": 0.0118, "w_brk": 0.1, "T_C": 0.00854}


def stribeck_torque(w, T_brk, w_brk, T_C, B, np_=np):
    """Friction torque of Simscape's Rotational Friction (``w_St = w_brk sqrt 2``,
    ``w_C = w_brk / 10``)::

        tau = sqrt(2e) (T_brk - T_C) exp(-(w/w_St)^2) w/w_St + T_C tanh(w/w_C) + B w
    """
    w_st = w_brk * math.sqrt(2.0)
    x = w / w_st
    return (math.sqrt(2 * math.e) * (T_brk - T_C) * np_.exp(-x ** 2) * x
            + T_C * np_.tanh(w / (w_brk / 10)) + B * w)


class DCMotorRig(SeedMotor):
    """Brush DC motor on a test rig, as ODEs.

    ``L di/dt = V - R i - k w``;  ``J dw/dt = (1 - locked) (k i - tau_f(w))``;
    ``dphi/dt = w``, with the friction torque ``tau_f`` of :func:`stribeck_torque`
    (``T_brk = T_C = 0`` gives viscous friction only). ``locked = 1`` holds the rotor
    (the locked-rotor test: ``w`` stays at its start value 0). ``V`` is the terminal
    voltage, driven by the measured input during estimation.
    """

    V = mt.Parameter("V", default=0.0, doc="Terminal voltage")
    T_brk = mt.Parameter("N*m", default=0.0118, min=0, doc="Breakaway friction torque")
    w_brk = mt.Parameter("rad/s", default=0.1, min=0, doc="Breakaway friction velocity")
    T_C = mt.Parameter("N*m", default=0.00854, min=0, doc="Coulomb friction torque")
    locked = mt.Parameter("1", default=0.0, min=0, max=1, doc="1: rotor held (locked)")
    i = mt.Variable("A", start=0.0, doc="Armature current")
    w = mt.Variable("rad/s", start=0.0, doc="Rotor speed")
    phi = mt.Variable("rad", start=0.0, doc="Rotor angle")
    tau_f = mt.Variable("N*m", doc="Friction torque")

    def equations(self):
        tau_f = stribeck_torque(self.w, self.T_brk, self.w_brk, self.T_C, self.B, np_=ca)
        return [self.L * mt.der(self.i) == self.V - self.R * self.i - self.k * self.w,
                self.J * mt.der(self.w) == (1 - self.locked) * (self.k * self.i - tau_f),
                mt.der(self.phi) == self.w,
                self.tau_f == tau_f]


@dataclass
class FrictionCurve:
    """Steady-state points of a speed-controlled run: speed ``w`` (rad/s) and measured
    current ``i`` (A, offset removed), averaged over ``n_avg`` samples each."""

    w: np.ndarray
    i: np.ndarray
    sigma_i: float


@dataclass
class VirtualBench:
    """The DC motor test rig with hidden true parameters (see the module docstring).

    ``truth`` overrides entries of :data:`TABLE_6_1`; ``stribeck=False`` gives viscous
    friction only. ``seed`` makes the noise reproducible.
    """

    truth: dict = field(default_factory=dict)
    stribeck: bool = True
    noise: float = 0.01
    current_offset: float = 0.02
    encoder_lines: int = 1000
    v_full_scale: float = 19.2
    seed: int = 0

    def __post_init__(self):
        t = dict(TABLE_6_1)
        t.update(self.truth)
        if not self.stribeck:
            t["T_brk"] = t["T_C"] = 0.0
        self.truth = t
        self._rng = np.random.default_rng(self.seed)
        self._cm = mt.compile_model(DCMotorRig())
        self._integrators = {}

    # ------------------------------------------------------------------------------------
    @property
    def sigma_i(self) -> float:
        """Current-noise standard deviation (A)."""
        return self.noise * self.v_full_scale / self.truth["R"]

    @property
    def encoder_resolution(self) -> float:
        """Angle per encoder count (rad)."""
        return 2 * math.pi / (4 * self.encoder_lines)

    def true_params(self, **extra) -> np.ndarray:
        cm = self._cm
        values = {**self.truth, **extra}
        return cm.parameter_vector({k: v for k, v in values.items()})

    def _simulate(self, t: np.ndarray, V: np.ndarray, locked: bool) -> np.ndarray:
        """True states ``[i; w; phi]`` at ``t`` (CVODES, input held between samples)."""
        cm = self._cm
        h = float(np.median(np.diff(t)))
        if not np.allclose(np.diff(t), h, rtol=1e-9, atol=0):
            raise ValueError("the virtual bench samples uniformly")
        F = self._integrators.get(h)
        if F is None:
            x = ca.MX.sym("x", cm.nx)
            p = ca.MX.sym("p", cm.p0.size)
            dae = {"x": x, "p": p, "ode": cm.f_ode(0.0, x, ca.MX(0, 1), p)[:cm.nx]}
            F = ca.integrator("bench", "cvodes", dae, 0.0, h,
                              {"abstol": 1e-12, "reltol": 1e-10, "max_num_steps": 100000})
            F = self._integrators[h] = F
        n = t.size
        p = self.true_params(locked=1.0 if locked else 0.0)
        iv = cm.param_names.index("V")
        P = np.repeat(p.reshape(-1, 1), n - 1, axis=1)
        P[iv, :] = V[:-1]
        run = F.mapaccum("bench_run", n - 1)
        X = np.array(run(x0=np.zeros(cm.nx), p=P)["xf"], dtype=float)
        return np.hstack([np.zeros((cm.nx, 1)), X])

    def run(self, name: str, t: np.ndarray, V: np.ndarray, *, locked: bool = False) \
            -> Experiment:
        """Measure one run: commanded voltage ``V`` at the sample times ``t``. Outputs
        ``i``, ``phi`` and ``w``; with the rotor ``locked``, the current ``i`` only."""
        t = np.asarray(t, dtype=float)
        V = np.asarray(V, dtype=float)
        X = self._simulate(t, V, locked)
        names = self._cm.state_names
        i_true, w_true, phi_true = (X[names.index(s)] for s in ("i", "w", "phi"))
        i_meas = i_true + self.current_offset + self.sigma_i * self._rng.standard_normal(
            t.size)
        res = self.encoder_resolution
        phi_meas = np.floor(phi_true / res + 1e-9) * res
        w_meas = np.concatenate([[0.0], np.diff(phi_meas) / np.diff(t)])
        params = {"locked": 1.0} if locked else {}
        outputs = {"i": i_meas} if locked else {"i": i_meas, "phi": phi_meas, "w": w_meas}
        return Experiment(name=name, t=t, inputs={"V": V}, outputs=outputs,
                          units={"V": "V", "i": "A", "phi": "rad", "w": "rad/s"},
                          params=params, hold="zoh", source=f"<virtual bench: {name}>",
                          sigma={"i": self.sigma_i, "phi": res / math.sqrt(12),
                                 "w": res / math.sqrt(6) / float(np.median(np.diff(t)))})

    # -- the standard runs -----------------------------------------------------------------
    def voltage_step(self, V: float = 19.2, *, t_stop: float = 0.03, fs: float = 20e3,
                     t_step: float = 2e-3, locked: bool = False, name: str = "") \
            -> Experiment:
        """A voltage step from 0 to ``V`` at ``t_step`` (samples before it measure the
        current sensor's offset)."""
        t = np.arange(int(round(t_stop * fs)) + 1) / fs
        u = np.where(t >= t_step - 0.5 / fs, V, 0.0)
        return self.run(name or ("locked_rotor" if locked else "voltage_step"), t, u,
                        locked=locked)

    def locked_rotor(self, V: float = 19.2, *, period: float = 1e-3, cycles: int = 4,
                     fs: float = 50e3, t_first: float = 1e-3, name: str = "locked_rotor") \
            -> Experiment:
        """The locked-rotor test: the rotor held, a square wave 0 / ``V`` (``cycles``
        periods after ``t_first`` s at 0; each edge is an electrical step response)."""
        t_stop = t_first + cycles * period
        t = np.arange(int(round(t_stop * fs)) + 1) / fs
        phase = np.floor((t - t_first + 0.5 / fs) / (period / 2))
        u = np.where((t >= t_first - 0.5 / fs) & (phase % 2 == 0), V, 0.0)
        return self.run(name, t, u, locked=True)

    def multi_step(self, levels=(2.0, 24.0, 2.0, 24.0, 2.0, 24.0), *, dwell: float = 0.07,
                   fs: float = 10e3, t_first: float = 2e-3, name: str = "multi_step") \
            -> Experiment:
        """A staircase of voltage levels, each held ``dwell`` s after ``t_first`` s at 0.

        The default alternates a low and a high speed: the friction torque ``B w + T_C``
        is best separated by speeds far apart, and each step is a transient for ``J``."""
        t_stop = t_first + dwell * len(levels)
        t = np.arange(int(round(t_stop * fs)) + 1) / fs
        u = np.zeros_like(t)
        for j, level in enumerate(levels):
            u[t >= t_first + j * dwell - 0.5 / fs] = level
        return self.run(name, t, u)

    def friction_curve(self, speeds, *, n_avg: int = 2000) -> FrictionCurve:
        """Steady-state current at each speed held by a speed controller (the seed's
        Fig. 6-8): ``k i = tau_f(w)``, measured with noise averaged over ``n_avg``
        samples, the sensor offset calibrated out."""
        w = np.asarray(speeds, dtype=float)
        tr = self.truth
        tau = stribeck_torque(w, tr["T_brk"], tr["w_brk"], tr["T_C"], tr["B"])
        sig = self.sigma_i / math.sqrt(n_avg)
        i = tau / tr["k"] + sig * self._rng.standard_normal(w.size)
        return FrictionCurve(w=w, i=i, sigma_i=sig)

    def model(self):
        """A fresh :class:`DCMotorRig` (defaults = table 6-1) for estimation."""
        return DCMotorRig()
