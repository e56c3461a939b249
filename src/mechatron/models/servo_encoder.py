"""DC-motor position servo with incremental-encoder feedback and a discrete PD controller.

The seed's DC motor (table 6-1) turns a shaft whose angle ``theta`` is read by an
incremental encoder of ``lines`` lines per revolution, decoded in quadrature: the counter
holds ``n = floor(theta / q)`` with the count ``q = 2 pi / (4 lines)``. A digital
controller samples the counter every ``Ts`` and applies, through an ideal power stage
limited to ``+-V_max``, the PD law (backward-difference derivative)::

    e_k = theta_ref - q n_k
    u_k = min(max(Kp e_k + Kd (e_k - e_k-1) / Ts, -V_max), V_max)     (held for Ts)
    L di/dt = u - R i - k w,   J dw/dt = k i - B w,   dtheta/dt = w

The quantization shapes the end of the move. If ``theta_ref`` is a whole number of
counts, every shaft angle in ``[theta_ref, theta_ref + q)`` reads zero error, so the
servo stops somewhere inside that count: the final error is bounded by one count. If
``theta_ref`` lies between two counts, the error never reads zero and the servo hunts
across the count boundary in a limit cycle.

The plant is linear and the controller's output is held between ticks, so the sampled
loop is exactly ``x_k+1 = Phi x_k + Gamma u_k``: :func:`sampled_response` computes it
with matrix exponentials and NumPy, an implementation independent of the simulation.

Variant: ``acausal`` (Step reference, :class:`IncrementalEncoder`, blocks.Subtract,
blocks.DiscretePID, controlled voltage source, motor parts).
"""

from __future__ import annotations

import math

import casadi as ca
import numpy as np
from scipy.linalg import expm

import mechatron as mt
from mechatron.library import blocks
from mechatron.library import electrical as el
from mechatron.library import electromechanical as em
from mechatron.library import rotational as rot
from mechatron.library.rotational import TwoFlange
from mechatron.models.entry import Experiment, ModelEntry, ParameterInfo
from mechatron.models.registry import register

__all__ = ["IncrementalEncoder", "ServoEncoder", "count", "sampled_response"]

SEED = "seed table 6-1, calculated"
CHOSEN = "chosen: a 500-line encoder and a 1 kHz controller"


def count(lines: float) -> float:
    """Angle of one quadrature count, ``2 pi / (4 lines)``, rad."""
    return 2 * math.pi / (4 * lines)


class IncrementalEncoder(TwoFlange):
    """Quadrature-decoded incremental encoder: no torque; its counter holds
    ``n = floor(phi / q)``, ``q = 2 pi / (4 lines)``, with ``phi`` the angle of A relative
    to B (its own state, start 0). Outputs the count ``n`` and the measured angle
    ``q n``. Limitations: ideal edges (no jitter, no missed counts); ``floor`` is not an
    event, so read the outputs with a sampled block (as a controller's timer capture
    does), not in a continuous equation.
    """

    lines = mt.Parameter("1", default=500.0, min=1, doc="Lines per revolution")
    phi = mt.Variable("rad", start=0.0, doc="Shaft angle, A relative to B")
    n = mt.Output("1", doc="Counter value floor(phi / q)")
    angle = mt.Output("rad", doc="Measured angle q n")

    def equations(self):
        q = 2 * ca.pi / (4 * self.lines)
        return [self.tau == 0, mt.der(self.phi) == self.w,
                self.n == ca.floor(self.phi / q),
                self.angle == q * self.n]


class ServoEncoder(mt.Component):
    """Position servo: reference, encoder, discrete PD, power stage and DC motor."""

    reference = blocks.Step(doc="Position reference, rad")
    error = blocks.Subtract(doc="Reference minus measured angle")
    controller = blocks.DiscretePID(doc="Discrete PD with output limits")
    stage = el.ControlledVoltageSource(doc="Power stage (ideal, limited by the PD)")
    resistor = el.Resistor(doc="Armature resistance")
    inductor = el.Inductor(doc="Armature inductance")
    emf = em.RotationalEMF()
    rotor = rot.Inertia(doc="Rotor")
    bearing = rot.RotationalDamper(doc="Viscous friction")
    encoder = IncrementalEncoder()
    ground = el.ElectricalReference()
    housing = rot.RotationalReference()

    def equations(self):
        return [mt.connect(self.reference.y, self.error.u1),
                mt.connect(self.encoder.angle, self.error.u2),
                mt.connect(self.error.y, self.controller.u),
                mt.connect(self.controller.y, self.stage.u),
                mt.connect(self.stage.p, self.resistor.p),
                mt.connect(self.resistor.n, self.inductor.p),
                mt.connect(self.inductor.n, self.emf.p),
                mt.connect(self.emf.n, self.stage.n, self.ground.port),
                mt.connect(self.emf.A, self.rotor.port, self.bearing.A, self.encoder.A),
                mt.connect(self.emf.B, self.bearing.B, self.encoder.B,
                           self.housing.port)]


def sampled_response(theta_ref, lines, Ts, Kp, Kd, V_max, R, L, k, J, B, t_stop,
                     quantize=True):
    """The sampled loop in NumPy: the motor's exact zero-order-hold discretisation over
    ``Ts`` and the encoder and PD at the ticks ``k Ts``. Returns the tick times and the
    state ``(i, w, theta)`` and voltage ``u`` at each tick (``u`` is applied from it)."""
    A = np.array([[-R / L, -k / L, 0.0], [k / J, -B / J, 0.0], [0.0, 1.0, 0.0]])
    b = np.array([1 / L, 0.0, 0.0])
    aug = np.zeros((4, 4))
    aug[:3, :3], aug[:3, 3] = A, b
    E = expm(aug * Ts)
    Phi, Gamma = E[:3, :3], E[:3, 3]
    q = count(lines)
    steps = int(round(t_stop / Ts))
    x = np.zeros(3)
    e_prev = 0.0
    X, U = np.zeros((steps + 1, 3)), np.zeros(steps + 1)
    for j in range(steps + 1):
        measured = q * math.floor(x[2] / q) if quantize else x[2]
        e = theta_ref - measured
        u = min(max(Kp * e + Kd * (e - e_prev) / Ts, -V_max), V_max)
        X[j], U[j] = x, u
        x = Phi @ x + Gamma * u
        e_prev = e
    return np.arange(steps + 1) * Ts, X, U


def _acausal(theta_ref, lines, Ts, Kp, Kd, V_max, R, L, k, J, B):
    model = ServoEncoder(doc="position servo with incremental encoder, discrete PD")
    model._name = "servo_encoder"
    model.reference._values.update(t_step=0.0, initial=theta_ref, final=theta_ref)
    model.controller._values.update(Kp=Kp, Ki=0.0, Kd=Kd, y_min=-V_max, y_max=V_max,
                                    Ts=Ts, offset=0.0)
    model.resistor._values["R"] = R
    model.inductor._values["L"] = L
    model.inductor._set("i", 0.0)
    model.emf._values["k"] = k
    model.rotor._values["J"] = J
    model.rotor._set("w", 0.0)
    model.bearing._values["D"] = B
    model.encoder._values["lines"] = lines
    model.encoder._set("phi", 0.0)
    return model


_LINES = 500.0
_PARAMS = {
    "theta_ref": ParameterInfo("rad", 1000 * count(_LINES),
                               "Position reference (1000 counts, half a revolution)",
                               CHOSEN),
    "lines": ParameterInfo("1", _LINES, "Encoder lines per revolution (2000 counts)",
                           CHOSEN),
    "Ts": ParameterInfo("s", 1e-3, "Controller sample time", CHOSEN),
    "Kp": ParameterInfo("V/rad", 100.0, "Proportional gain",
                        "chosen: settles in 50 ms without a limit cycle"),
    "Kd": ParameterInfo("V*s/rad", 0.3, "Derivative gain",
                        "chosen: settles in 50 ms without a limit cycle"),
    "V_max": ParameterInfo("V", 19.2, "Power stage voltage limit", "seed, test bench"),
    "R": ParameterInfo("Ohm", 7.1, "Armature resistance", SEED),
    "L": ParameterInfo("H", 3.408e-4, "Armature inductance", SEED),
    "k": ParameterInfo("V*s/rad", 0.151, "Motor constant", SEED),
    "J": ParameterInfo("kg*m^2", 4.8e-6, "Rotor inertia", SEED),
    "B": ParameterInfo("N*m*s/rad", 1.236e-4, "Viscous friction", SEED),
}
_D = {key: info.default for key, info in _PARAMS.items()}
_T, _X, _U = sampled_response(**_D, t_stop=0.1)

ENTRY = register(ModelEntry(
    name="servo_encoder",
    description=("DC-motor position servo whose feedback is an incremental encoder's "
                 "quantized angle, with a 1 kHz discrete PD controller."),
    parameters=_PARAMS,
    variants={"acausal": _acausal},
    outputs={"acausal": {"theta": "encoder.phi", "w": "rotor.w", "i": "inductor.i",
                         "u": "controller.y", "n": "encoder.n"}},
    output_units={"theta": "rad", "w": "rad/s", "i": "A", "u": "V", "n": "1"},
    experiment=Experiment(t_stop=0.1, rtol=1e-9, atol=1e-11),
    # the servo stops inside the reference's count (final value from the sampled loop
    # in NumPy, sampled_response)
    expected={"theta": float(_X[-1, 2]), "n": 1000.0},
    expected_tolerance=1e-6,
    tags=("electromechanical", "motor", "servo", "discrete", "encoder", "quantization"),
))
