"""Two-phase hybrid stepper motor in full-step (wave) drive.

Phases ``a`` and ``b`` (resistance ``R``, inductance ``L``) and a rotor with ``N`` teeth
(``N = 50``: 200 full steps per revolution, 1.8 degrees). With the rotor angle ``theta``
and speed ``w``::

    v_a = R i_a + L di_a/dt - K w sin(N theta)
    v_b = R i_b + L di_b/dt + K w cos(N theta)
    J dw/dt = -K i_a sin(N theta) + K i_b cos(N theta) - T_d sin(4 N theta) - B w

(back-EMF and torque share the constant ``K``, so the converted power balances:
``tau_e w = e_a i_a + e_b i_b``; ``T_d`` is the detent torque). With only phase ``a``
carrying ``+I`` the rotor rests at ``N theta = 0``; the wave-drive sequence
``a+, b+, a-, b-`` moves that equilibrium by ``pi / 2`` in ``N theta`` per step, so after
``n`` steps the rotor rests at ``n * 360 / (4 N)`` degrees (the detent torque vanishes
there). Linearised about a rest position with ``i = I = V / R``, the rotor is a
torsional oscillator of stiffness ``N K I + 4 N T_d`` (natural frequency
``sqrt(N K I / J)`` without detent), damped by ``B`` and by the back-EMF current of the
other phase; :func:`linearization` gives the three-state model (angle, speed, the idle
phase's current) whose eigenvalues the tests compare with the simulated ringing.

The driver applies ``+-V`` to one phase at a time: it takes its first step at
``t_start``, one more every ``1 / f_step``, and holds step ``n_steps``. Its switching
instants are events: the zero crossings of ``cos`` and ``sin`` of ``psi = pi u / 2``,
``u`` the step index, one relation per switching instant.

Variants: ``acausal`` (a :class:`HybridStepper` component with electrical pins and a
rotational flange, fed by two controlled voltage sources from a :class:`FullStepDriver`,
turning a load inertia) and ``equation`` (the ODEs in one component).
"""

from __future__ import annotations

import math

import casadi as ca
import numpy as np

import mechatron as mt
from mechatron.library import electrical as el
from mechatron.library import rotational as rot
from mechatron.library.electrical import Pin
from mechatron.library.rotational import TwoFlange
from mechatron.models.entry import Experiment, ModelEntry, ParameterInfo
from mechatron.models.registry import register

__all__ = ["HybridStepper", "FullStepDriver", "StepperAcausal", "StepperEquation",
           "linearization", "step_angle"]

NEMA17 = "typical NEMA 17 hybrid stepper, 1.5 A per phase"
CHOSEN = "chosen"


def step_angle(N: float) -> float:
    """Full-step angle ``2 pi / (4 N)``, rad."""
    return 2 * math.pi / (4 * N)


def linearization(V, R, L, K, N, T_d, J, B) -> np.ndarray:
    """State matrix about a rest position, state ``(delta theta, w, i_idle)``: the
    energised phase carries ``I = V / R`` (its current perturbation is decoupled to first
    order), the idle phase sees the back-EMF ``K w``."""
    I = V / R
    stiffness = N * K * I + 4 * N * T_d
    return np.array([[0.0, 1.0, 0.0],
                     [-stiffness / J, -B / J, K / J],
                     [0.0, -K / L, -R / L]])


def _drive(time, V, f_step, n_steps, t_start):
    """Wave-drive phase voltages ``(v_a, v_b)``.

    The step index ``u`` (clamped to the middle of step 0 before ``t_start`` and of step
    ``n_steps`` after the last step) sets ``psi = pi u / 2``; step ``u mod 4`` is
    ``a+, b+, a-, b-``, read from the signs of ``cos psi`` and ``sin psi``::

        c = [cos psi > 0],  s = [sin psi > 0]
        v_a = V (c + s - 1),  v_b = V (s - c)

    Each step boundary is the zero crossing of exactly one of the two (``cos`` at odd,
    ``sin`` at even ``u``), so no two events ever coincide.
    """
    u = ca.fmin(ca.fmax(f_step * (time - t_start) + 1, 0.5), n_steps + 0.5)
    psi = ca.pi / 2 * u
    c = ca.if_else(0 < ca.cos(psi), 1, 0)
    s = ca.if_else(0 < ca.sin(psi), 1, 0)
    return V * (c + s - 1), V * (s - c)


class FullStepDriver(mt.Component):
    """Wave (one-phase-on) full-step driver: ``+V`` on a, b, then ``-V`` on a, b, one
    step every ``1 / f_step`` from ``t_start``, holding step ``n_steps``."""

    v_a = mt.Output("V", doc="Phase a voltage command")
    v_b = mt.Output("V", doc="Phase b voltage command")
    V = mt.Parameter("V", default=3.0, doc="Phase voltage")
    f_step = mt.Parameter("Hz", default=50.0, min=0, doc="Step rate")
    n_steps = mt.Parameter("1", default=6.0, min=0, doc="Number of steps")
    t_start = mt.Parameter("s", default=0.01, doc="Time of the first step")

    def equations(self):
        v_a, v_b = _drive(self.time, self.V, self.f_step, self.n_steps, self.t_start)
        return [self.v_a == v_a, self.v_b == v_b]


class HybridStepper(TwoFlange):
    """Two-phase hybrid stepper motor (Simscape: Stepper Motor, without saturation).

    Pins ``a_p``/``a_n`` and ``b_p``/``b_n`` (phase currents from p to n), rotor flange
    ``A`` and housing ``B`` (``w = A.w - B.w``, ``theta`` its own state). Equations in the
    module docstring; the electrical torque ``tau_e`` drives the flange at A
    (``tau = -tau_e``). Limitations: sinusoidal flux linkage, no saturation, no mutual
    coupling of the phases, no iron losses.
    """

    a_p = Pin(doc="Phase a, positive pin")
    a_n = Pin(doc="Phase a, negative pin")
    b_p = Pin(doc="Phase b, positive pin")
    b_n = Pin(doc="Phase b, negative pin")
    R = mt.Parameter("Ohm", default=2.0, min=0, doc="Phase resistance")
    L = mt.Parameter("H", default=1e-3, min=0, doc="Phase inductance")
    K = mt.Parameter("N*m/A", default=0.2, min=0, doc="Torque (and back-EMF) constant")
    N = mt.Parameter("1", default=50.0, min=1, doc="Rotor teeth")
    T_d = mt.Parameter("N*m", default=0.0, min=0, doc="Detent torque amplitude")
    i_a = mt.Variable("A", start=0.0, doc="Phase a current")
    i_b = mt.Variable("A", start=0.0, doc="Phase b current")
    theta = mt.Variable("rad", start=0.0, doc="Rotor angle, A relative to B")
    tau_e = mt.Variable("N*m", doc="Electromagnetic torque on the rotor")

    def equations(self):
        s, c = ca.sin(self.N * self.theta), ca.cos(self.N * self.theta)
        return [self.a_p.i + self.a_n.i == 0, self.i_a == self.a_p.i,
                self.b_p.i + self.b_n.i == 0, self.i_b == self.b_p.i,
                mt.der(self.theta) == self.w,
                self.a_p.v - self.a_n.v == self.R * self.i_a + self.L * mt.der(self.i_a)
                - self.K * self.w * s,
                self.b_p.v - self.b_n.v == self.R * self.i_b + self.L * mt.der(self.i_b)
                + self.K * self.w * c,
                self.tau_e == -self.K * self.i_a * s + self.K * self.i_b * c
                - self.T_d * ca.sin(4 * self.N * self.theta),
                self.tau == -self.tau_e]


class StepperAcausal(mt.Component):
    """Driver, two phase voltage sources, stepper, load inertia and friction."""

    driver = FullStepDriver()
    supply_a = el.ControlledVoltageSource(doc="Bridge of phase a (ideal)")
    supply_b = el.ControlledVoltageSource(doc="Bridge of phase b (ideal)")
    motor = HybridStepper()
    rotor = rot.Inertia(doc="Rotor and load inertia")
    friction = rot.RotationalDamper(doc="Viscous friction")
    ground_a = el.ElectricalReference()
    ground_b = el.ElectricalReference()
    housing = rot.RotationalReference()

    def equations(self):
        return [mt.connect(self.driver.v_a, self.supply_a.u),
                mt.connect(self.driver.v_b, self.supply_b.u),
                mt.connect(self.supply_a.p, self.motor.a_p),
                mt.connect(self.supply_a.n, self.motor.a_n, self.ground_a.port),
                mt.connect(self.supply_b.p, self.motor.b_p),
                mt.connect(self.supply_b.n, self.motor.b_n, self.ground_b.port),
                mt.connect(self.motor.A, self.rotor.port, self.friction.A),
                mt.connect(self.motor.B, self.friction.B, self.housing.port)]


class StepperEquation(mt.Component):
    """The stepper, its driver and load as ODEs in one component."""

    V = mt.Parameter("V", default=3.0, doc="Phase voltage")
    f_step = mt.Parameter("Hz", default=50.0, min=0, doc="Step rate")
    n_steps = mt.Parameter("1", default=6.0, min=0, doc="Number of steps")
    t_start = mt.Parameter("s", default=0.01, doc="Time of the first step")
    R = mt.Parameter("Ohm", default=2.0, min=0, doc="Phase resistance")
    L = mt.Parameter("H", default=1e-3, min=0, doc="Phase inductance")
    K = mt.Parameter("N*m/A", default=0.2, min=0, doc="Torque constant")
    N = mt.Parameter("1", default=50.0, min=1, doc="Rotor teeth")
    T_d = mt.Parameter("N*m", default=0.0, min=0, doc="Detent torque amplitude")
    J = mt.Parameter("kg*m^2", default=5e-5, min=0, doc="Rotor and load inertia")
    B = mt.Parameter("N*m*s/rad", default=1e-4, min=0, doc="Viscous friction")
    i_a = mt.Variable("A", start=0.0, doc="Phase a current")
    i_b = mt.Variable("A", start=0.0, doc="Phase b current")
    theta = mt.Variable("rad", start=0.0, doc="Rotor angle")
    w = mt.Variable("rad/s", start=0.0, doc="Rotor speed")
    v_a = mt.Variable("V", doc="Phase a voltage")
    v_b = mt.Variable("V", doc="Phase b voltage")

    def equations(self):
        v_a, v_b = _drive(self.time, self.V, self.f_step, self.n_steps, self.t_start)
        s, c = ca.sin(self.N * self.theta), ca.cos(self.N * self.theta)
        return [self.v_a == v_a, self.v_b == v_b,
                self.L * mt.der(self.i_a) == self.v_a - self.R * self.i_a
                + self.K * self.w * s,
                self.L * mt.der(self.i_b) == self.v_b - self.R * self.i_b
                - self.K * self.w * c,
                mt.der(self.theta) == self.w,
                self.J * mt.der(self.w) == -self.K * self.i_a * s + self.K * self.i_b * c
                - self.T_d * ca.sin(4 * self.N * self.theta) - self.B * self.w]


def _acausal(V, f_step, n_steps, t_start, R, L, K, N, T_d, J, B):
    model = StepperAcausal(doc="hybrid stepper in wave drive, acausal network")
    model._name = "stepper_motor"
    model.driver._values.update(V=V, f_step=f_step, n_steps=n_steps, t_start=t_start)
    model.motor._values.update(R=R, L=L, K=K, N=N, T_d=T_d)
    model.motor._set("i_a", V / R)           # phase a energised long before: at rest
    model.motor._set("i_b", 0.0)
    model.motor._set("theta", 0.0)
    model.rotor._values["J"] = J
    model.rotor._set("w", 0.0)
    model.friction._values["D"] = B
    return model


def _equation(**values):
    model = StepperEquation(**values, i_a=values["V"] / values["R"], i_b=0.0, theta=0.0,
                            w=0.0)
    model._name = "stepper_motor"
    return model


_PARAMS = {
    "V": ParameterInfo("V", 3.0, "Phase voltage (1.5 A at standstill)", NEMA17),
    "f_step": ParameterInfo("Hz", 50.0, "Step rate", CHOSEN),
    "n_steps": ParameterInfo("1", 6.0, "Number of full steps commanded", CHOSEN),
    "t_start": ParameterInfo("s", 0.01, "Time of the first step", CHOSEN),
    "R": ParameterInfo("Ohm", 2.0, "Phase resistance", NEMA17),
    "L": ParameterInfo("H", 1e-3, "Phase inductance", NEMA17),
    "K": ParameterInfo("N*m/A", 0.2, "Torque constant per phase", NEMA17),
    "N": ParameterInfo("1", 50.0, "Rotor teeth (200 full steps per revolution)", NEMA17),
    "T_d": ParameterInfo("N*m", 0.01, "Detent torque amplitude", NEMA17),
    "J": ParameterInfo("kg*m^2", 5e-5, "Rotor and load inertia", CHOSEN),
    "B": ParameterInfo("N*m*s/rad", 1e-4, "Viscous friction", CHOSEN),
}
_D = {key: info.default for key, info in _PARAMS.items()}

ENTRY = register(ModelEntry(
    name="stepper_motor",
    description=("Two-phase hybrid stepper motor (1.8 degree) in wave full-step drive: "
                 "six steps at 50 steps/s, each ringing at the rotor's natural "
                 "frequency; electrical and rotational domains."),
    parameters=_PARAMS,
    variants={"acausal": _acausal, "equation": _equation},
    outputs={"acausal": {"theta": "motor.theta", "w": "rotor.w", "i_a": "motor.i_a",
                         "i_b": "motor.i_b"},
             "equation": {"theta": "theta", "w": "w", "i_a": "i_a", "i_b": "i_b"}},
    output_units={"theta": "rad", "w": "rad/s", "i_a": "A", "i_b": "A"},
    experiment=Experiment(t_stop=0.25, rtol=1e-8, atol=1e-10),
    # six steps (a+ -> b+ a- b- a+ b+ a-): phase a carries -V/R, the rotor rests at
    # 6 * 1.8 degrees
    expected={"theta": _D["n_steps"] * step_angle(_D["N"]), "i_a": -_D["V"] / _D["R"]},
    expected_tolerance=1e-6, variant_tolerance=1e-5,
    tags=("electromechanical", "motor", "stepper", "events"),
))
