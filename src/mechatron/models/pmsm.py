"""Permanent-magnet synchronous motor under field-oriented control (FOC).

A surface-mounted PMSM (``L_d = L_q = L_s``) with ``p`` pole pairs and magnet flux
linkage ``psi``, fed by an ideal (averaged) inverter, under cascaded control: a speed PI
with a current limit and back-calculation anti-windup sets ``i_q_ref``; two current PIs in
the rotor (d, q) frame with cross-coupling and back-EMF feed-forward set the voltages;
``i_d_ref = 0`` (maximum torque per ampere for a surface magnet). The motor starts from
rest against a constant load torque.

Two variants of the same machine and controller:

* ``dq``: the machine in the rotor frame,
  ``v_d = R i_d + L di_d/dt - p w L i_q``, ``v_q = R i_q + L di_q/dt + p w (L i_d + psi)``,
  torque ``T = 3/2 p psi i_q``;
* ``abc``: the three phase windings of a star connection (two independent currents),
  ``v_k = R i_k + L di_k/dt + e_k`` with ``e_k = -p w psi sin(theta_e - k 2pi/3)``, the
  controller's Park and inverse Park transforms written out, torque
  ``T = -p psi sum_k i_k sin(theta_e - k 2pi/3)``.

With ``L_d = L_q`` both are exact, so they agree to the integration tolerance. The steady
state is known in closed form: ``w = w_ref``, ``i_d = 0`` and
``i_q = (B w_ref + T_load) / (3/2 p psi)``.
"""

from __future__ import annotations

import math

import casadi as ca

import mechatron as mt
from mechatron.models.entry import Experiment, ModelEntry, ParameterInfo
from mechatron.models.registry import register

__all__ = ["PMSMFOCdq", "PMSMFOCabc"]

CHOSEN = "chosen: a 400 W class servo motor"
DESIGN = "controller design (bandwidths in the parameter description)"
TWO_PI_3 = 2 * math.pi / 3


class _FOC(mt.Component, partial=True):
    """Machine and controller parameters, the speed loop and the mechanics (shared)."""

    p = mt.Parameter("1", default=4.0, min=1, doc="Pole pairs")
    R = mt.Parameter("Ohm", default=0.5, min=0, doc="Phase resistance")
    L = mt.Parameter("H", default=1.2e-3, min=0, doc="Phase (synchronous) inductance")
    psi = mt.Parameter("Wb", default=0.05, min=0, doc="Magnet flux linkage")
    J = mt.Parameter("kg*m^2", default=1e-4, min=0, doc="Rotor and load inertia")
    B = mt.Parameter("N*m*s/rad", default=1e-5, min=0, doc="Viscous friction")
    w_ref = mt.Parameter("rad/s", default=300.0, doc="Speed reference (step at t = 0)")
    T_load = mt.Parameter("N*m", default=0.2, doc="Load torque (constant)")
    Kp_i = mt.Parameter("V/A", default=3.77, min=0, doc="Current PI gain")
    Ki_i = mt.Parameter("V/(A*s)", default=1571.0, min=0, doc="Current PI integral gain")
    Kp_w = mt.Parameter("A*s/rad", default=0.0419, min=0, doc="Speed PI gain")
    Ki_w = mt.Parameter("A/rad", default=1.05, min=0, doc="Speed PI integral gain")
    i_max = mt.Parameter("A", default=10.0, min=0, doc="Current limit (|i_q_ref|)")
    K_aw = mt.Parameter("1/s", default=25.0, min=0,
                        doc="Anti-windup back-calculation gain (0: none)")
    w = mt.Variable("rad/s", start=0.0, doc="Rotor speed")
    theta = mt.Variable("rad", start=0.0, doc="Rotor angle (mechanical)")
    x_w = mt.Variable("A", start=0.0, doc="Speed PI integrator state")
    x_d = mt.Variable("V", start=0.0, doc="d-current PI integrator state")
    x_q = mt.Variable("V", start=0.0, doc="q-current PI integrator state")
    iq_ref = mt.Variable("A", doc="q-current reference (limited)")
    i_d = mt.Variable("A", doc="d-axis current")
    i_q = mt.Variable("A", doc="q-axis current")
    v_d = mt.Variable("V", doc="d-axis voltage command")
    v_q = mt.Variable("V", doc="q-axis voltage command")
    T = mt.Variable("N*m", doc="Electromagnetic torque")

    def equations(self):
        e_w = self.w_ref - self.w
        unlimited = self.Kp_w * e_w + self.x_w
        we = self.p * self.w
        e_d = 0.0 - self.i_d
        e_q = self.iq_ref - self.i_q
        return [self.iq_ref == ca.fmin(ca.fmax(unlimited, -self.i_max), self.i_max),
                # back-calculation anti-windup: the integrator bleeds off the excess
                mt.der(self.x_w) == self.Ki_w * e_w
                + self.K_aw * (self.iq_ref - unlimited),
                mt.der(self.x_d) == self.Ki_i * e_d,
                mt.der(self.x_q) == self.Ki_i * e_q,
                self.v_d == self.Kp_i * e_d + self.x_d - we * self.L * self.i_q,
                self.v_q == self.Kp_i * e_q + self.x_q + we * (self.L * self.i_d + self.psi),
                mt.der(self.theta) == self.w,
                self.J * mt.der(self.w) == self.T - self.B * self.w - self.T_load]


class PMSMFOCdq(_FOC):
    """PMSM with FOC, machine in the rotor (d, q) frame."""

    def equations(self):
        we = self.p * self.w
        return [self.L * mt.der(self.i_d) == self.v_d - self.R * self.i_d
                + we * self.L * self.i_q,
                self.L * mt.der(self.i_q) == self.v_q - self.R * self.i_q
                - we * (self.L * self.i_d + self.psi),
                self.T == 1.5 * self.p * self.psi * self.i_q]


class PMSMFOCabc(_FOC):
    """PMSM with FOC, machine as three star-connected phase windings."""

    i_a = mt.Variable("A", start=0.0, doc="Phase a current")
    i_b = mt.Variable("A", start=0.0, doc="Phase b current")
    i_c = mt.Variable("A", doc="Phase c current")

    def equations(self):
        th = self.p * self.theta
        angles = [th, th - TWO_PI_3, th + TWO_PI_3]
        currents = [self.i_a, self.i_b, self.i_c]
        # inverse Park: phase voltage commands; e_k: back EMF of phase k
        v = [self.v_d * ca.cos(a) - self.v_q * ca.sin(a) for a in angles]
        e = [-self.p * self.w * self.psi * ca.sin(a) for a in angles]
        # star point: the neutral voltage makes the three currents sum to zero; for a
        # balanced machine it is the mean of (v_k - e_k), which is 0 here, so two phase
        # equations and i_c = -(i_a + i_b) describe the winding.
        return [self.L * mt.der(self.i_a) == v[0] - self.R * self.i_a - e[0],
                self.L * mt.der(self.i_b) == v[1] - self.R * self.i_b - e[1],
                self.i_c == -(self.i_a + self.i_b),
                # Park transform of the measured currents (amplitude-invariant)
                self.i_d == 2 / 3 * sum(i * ca.cos(a) for i, a in zip(currents, angles)),
                self.i_q == -2 / 3 * sum(i * ca.sin(a) for i, a in zip(currents, angles)),
                self.T == -self.p * self.psi * sum(i * ca.sin(a)
                                                    for i, a in zip(currents, angles))]


def _builder(cls):
    def build(**values):
        model = cls(**values)
        model._name = "pmsm_foc"
        return model
    return build


_PARAMS = {
    "p": ParameterInfo("1", 4.0, "Pole pairs", CHOSEN),
    "R": ParameterInfo("Ohm", 0.5, "Phase resistance", CHOSEN),
    "L": ParameterInfo("H", 1.2e-3, "Phase inductance (L_d = L_q)", CHOSEN),
    "psi": ParameterInfo("Wb", 0.05, "Magnet flux linkage", CHOSEN),
    "J": ParameterInfo("kg*m^2", 1e-4, "Rotor and load inertia", CHOSEN),
    "B": ParameterInfo("N*m*s/rad", 1e-5, "Viscous friction", CHOSEN),
    "w_ref": ParameterInfo("rad/s", 300.0, "Speed reference step", CHOSEN),
    "T_load": ParameterInfo("N*m", 0.2, "Load torque (from t = 0)", CHOSEN),
    "Kp_i": ParameterInfo("V/A", 3.77, "Current PI gain, L * 2 pi 500 Hz", DESIGN),
    "Ki_i": ParameterInfo("V/(A*s)", 1571.0, "Current PI integral gain, R * 2 pi 500 Hz",
                          DESIGN),
    "Kp_w": ParameterInfo("A*s/rad", 0.0419, "Speed PI gain, J 2 pi 20 Hz / (1.5 p psi)",
                          DESIGN),
    "Ki_w": ParameterInfo("A/rad", 1.05, "Speed PI integral gain, Kp_w * 2 pi 20 Hz / 5",
                          DESIGN),
    "i_max": ParameterInfo("A", 10.0, "Current limit", CHOSEN),
    "K_aw": ParameterInfo("1/s", 25.0, "Anti-windup back-calculation gain, Ki_w / Kp_w",
                          DESIGN),
}

ENTRY = register(ModelEntry(
    name="pmsm_foc",
    description=("Permanent-magnet synchronous motor with field-oriented control: speed PI "
                 "with current limit and anti-windup, d/q current PIs with decoupling, a "
                 "load torque; in the rotor frame and as three phase windings."),
    parameters=_PARAMS,
    variants={"dq": _builder(PMSMFOCdq), "abc": _builder(PMSMFOCabc)},
    outputs={v: {"w": "w", "i_q": "i_q", "T": "T", "v_q": "v_q"} for v in ("dq", "abc")},
    output_units={"w": "rad/s", "i_q": "A", "T": "N*m", "v_q": "V"},
    experiment=Experiment(t_stop=1.0, rtol=1e-9, atol=1e-10),
    expected={"w": 300.0, "i_q": (1e-5 * 300.0 + 0.2) / (1.5 * 4 * 0.05),
              "T": 1e-5 * 300.0 + 0.2},
    expected_tolerance=1e-6, variant_tolerance=1e-6,
    tags=("motor", "electromechanical", "control", "FOC"),
))
