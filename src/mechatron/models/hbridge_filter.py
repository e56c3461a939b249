"""The seed's PWM-to-analog RC filter feeding an H-bridge that drives its DC motor.

In the seed's HIL set-up (section 7) the microcontroller's PWM output (``V_pwm = 5 V`` at
``f = 5 kHz``) is turned into an analog voltage for the MF624 card's input by a passive RC
low-pass filter, ``R_f = 7.5 kOhm``, ``C_f = 40 nF``, cut-off
``f_c = 1 / (2 pi R_f C_f) = 530.5 Hz`` (its equation 25). Here the filtered voltage
``v_f`` commands an H-bridge in sign-magnitude mode with a positive command, an ideal
power stage that applies ``v_m = V_bus v_f / V_pwm`` to the seed's DC motor (table 6-1).
Equations (``tau_f = R_f C_f``, ``u = V_pwm`` during the first ``D / f`` of each period
and 0 otherwise)::

    tau_f dv_f/dt = u - v_f
    L di/dt = V_bus v_f / V_pwm - R i - k w
    J dw/dt = k i - B w

The whole system is linear between the PWM edges, so its periodic steady state follows
exactly from the matrix exponentials of the two phases (:func:`periodic_steady_state`),
independently of the simulation. For the filter alone, at a rising edge and a falling
edge (``a = exp(-D T / tau_f)``, ``c = exp(-T / tau_f)``, ``T = 1/f``)::

    v_high = V_pwm (1 - a) / (1 - c),   v_low = v_high exp(-(1 - D) T / tau_f)

and its mean is exactly ``D V_pwm`` (no DC current flows into the capacitor).

Variants: ``acausal`` (PWMVoltageSource, Resistor, Capacitor, VoltageSensor, Gain,
ControlledVoltageSource, and the motor as the library's DCPermanentMagnet subsystem),
``equation`` (the three ODEs) and ``inputs`` (the network driven from outside, as a
microcontroller drives the real one: the duty cycle ``D`` is an external input, latched at
each period start by a timer-style modulator (``blocks.PWM``, edge-aligned like the fixed
source) whose output of 0 / ``V_pwm`` feeds the filter through a controlled source; a load
torque ``tau_load`` on the motor shaft, opposing rotation, is the second input; start
values ``D`` and 0, so by default it is the ``acausal`` circuit).
"""

from __future__ import annotations

import math

import casadi as ca
import numpy as np
from scipy.linalg import expm

import mechatron as mt
from mechatron.library import blocks
from mechatron.library import electrical as el
from mechatron.library import machines
from mechatron.library import rotational as rot
from mechatron.models.dc_motor import SeedMotor
from mechatron.models.entry import Experiment, ModelEntry, ParameterInfo
from mechatron.models.registry import register

__all__ = ["HBridgeFilterAcausal", "HBridgeFilterEquation", "cutoff_frequency",
           "filter_ripple", "periodic_steady_state"]

SEED_FILTER = "seed section 7.2, equation 25"
SEED_MOTOR = "seed table 6-1, calculated"
CHOSEN = "chosen"


def cutoff_frequency(R_f: float, C_f: float) -> float:
    """The RC filter's -3 dB frequency ``1 / (2 pi R C)``, Hz."""
    return 1.0 / (2 * math.pi * R_f * C_f)


def filter_ripple(V_pwm, D, f, R_f, C_f) -> dict:
    """Periodic steady state of an RC low-pass driven by a 0 / ``V_pwm`` square wave:
    the voltage at the falling edge (``high``) and at the rising edge (``low``)."""
    tau, T = R_f * C_f, 1.0 / f
    high = V_pwm * (1 - math.exp(-D * T / tau)) / (1 - math.exp(-T / tau))
    low = high * math.exp(-(1 - D) * T / tau)
    return {"high": high, "low": low, "ripple": high - low}


def _system(R_f, C_f, V_bus, V_pwm, R, L, k, J, B):
    """``A``, and ``b`` per volt of PWM output, of ``x' = A x + b u``, ``x = (v_f, i, w)``."""
    tau = R_f * C_f
    A = np.array([[-1 / tau, 0, 0],
                  [V_bus / (V_pwm * L), -R / L, -k / L],
                  [0, k / J, -B / J]])
    return A, np.array([1 / tau, 0, 0])


def periodic_steady_state(V_pwm, D, f, R_f, C_f, V_bus, R, L, k, J, B) -> dict:
    """Exact periodic state ``(v_f, i, w)`` at a rising edge of the PWM, from the matrix
    exponentials of the on and off phases."""
    A, b = _system(R_f, C_f, V_bus, V_pwm, R, L, k, J, B)
    n = len(b)

    def flow(u, tau):
        aug = np.zeros((n + 1, n + 1))
        aug[:n, :n], aug[:n, n] = A, b * u
        E = expm(aug * tau)
        return E[:n, :n], E[:n, n]

    P1, g1 = flow(V_pwm, D / f)
    P0, g0 = flow(0.0, (1 - D) / f)
    x0 = np.linalg.solve(np.eye(n) - P0 @ P1, P0 @ g1 + g0)
    return {"v_f": float(x0[0]), "i": float(x0[1]), "w": float(x0[2])}


class HBridgeFilterAcausal(mt.Component):
    """PWM output, RC filter, analog input, H-bridge power stage and DC motor."""

    pwm = el.PWMVoltageSource(doc="Microcontroller PWM output")
    r_f = el.Resistor(doc="Filter resistor")
    c_f = el.Capacitor(doc="Filter capacitor")
    sense = el.VoltageSensor(doc="Analog input of the I/O card (ideal, no load)")
    bridge_gain = blocks.Gain(doc="Power stage gain V_bus / V_pwm")
    bridge = el.ControlledVoltageSource(doc="H-bridge, averaged (ideal power stage)")
    motor = machines.DCPermanentMagnet(doc="The seed's DC motor (a library subsystem)")
    ground = el.ElectricalReference()
    bridge_ground = el.ElectricalReference()
    housing = rot.RotationalReference()

    def equations(self):
        return [mt.connect(self.pwm.p, self.r_f.p),
                mt.connect(self.r_f.n, self.c_f.p, self.sense.p),
                mt.connect(self.pwm.n, self.c_f.n, self.sense.n, self.ground.port),
                mt.connect(self.sense.V, self.bridge_gain.u),
                mt.connect(self.bridge_gain.y, self.bridge.u),
                mt.connect(self.bridge.p, self.motor.p),
                mt.connect(self.motor.n, self.bridge.n, self.bridge_ground.port),
                mt.connect(self.motor.support, self.housing.port)]


class HBridgeFilterEquation(SeedMotor):
    """The filter and the motor as three ODEs with the PWM written out."""

    V_pwm = mt.Parameter("V", default=5.0, doc="PWM high level")
    D = mt.Parameter("1", default=0.3, min=0, max=1, doc="Duty cycle")
    f = mt.Parameter("Hz", default=5e3, min=0, doc="PWM frequency")
    R_f = mt.Parameter("Ohm", default=7.5e3, min=0, doc="Filter resistance")
    C_f = mt.Parameter("F", default=40e-9, min=0, doc="Filter capacitance")
    V_bus = mt.Parameter("V", default=19.2, doc="H-bridge supply")
    v_f = mt.Variable("V", start=0.0, doc="Filtered voltage")
    i = mt.Variable("A", start=0.0, doc="Armature current")
    w = mt.Variable("rad/s", start=0.0, doc="Speed")
    u = mt.Variable("V", doc="PWM output")

    def equations(self):
        # on while the phase within the period lies in (0, D): the window centred at
        # pi D, i.e. cos(phase - pi D) > cos(pi D) (a continuous distance, so the
        # edges are located as events)
        phase = 2 * ca.pi * self.f * self.time
        on = ca.cos(ca.pi * self.D) < ca.cos(phase - ca.pi * self.D)
        return [self.u == ca.if_else(on, self.V_pwm, 0),
                self.R_f * self.C_f * mt.der(self.v_f) == self.u - self.v_f,
                self.L * mt.der(self.i) == self.V_bus / self.V_pwm * self.v_f
                - self.R * self.i - self.k * self.w,
                self.J * mt.der(self.w) == self.k * self.i - self.B * self.w]


def _acausal(V_pwm, D, f, R_f, C_f, V_bus, R, L, k, J, B):
    model = HBridgeFilterAcausal(doc="PWM, RC filter, H-bridge and DC motor")
    model._name = "hbridge_rc_filter"
    model.pwm._values.update(V_on=V_pwm, V_off=0.0, f=f, duty=D, delay=0.0)
    model.r_f._values["R"] = R_f
    model.c_f._values["C"] = C_f
    model.c_f._set("v", 0.0)
    model.bridge_gain._values["k"] = V_bus / V_pwm
    model.motor._values.update(R=R, L=L, k=k, J=J, B_v=B)
    model.motor.inductor._set("i", 0.0)
    model.motor.inertia._set("w", 0.0)
    return model


def _inputs(V_pwm, D, f, R_f, C_f, V_bus, R, L, k, J, B):
    """The circuit with the duty cycle and a load torque as external inputs."""
    m = mt.System("hbridge_rc_filter", doc="PWM, RC filter, H-bridge and DC motor, "
                  "external duty cycle and load torque")
    duty = m.input("D", unit="1", start=D, doc="Duty cycle, latched at each PWM period")
    load = m.input("tau_load", unit="N*m", start=0.0, doc="Load torque, opposing rotation")
    modulator = m.add("modulator", blocks.PWM(Ts=1.0 / f, amplitude=V_pwm))
    pwm = m.add("pwm", el.ControlledVoltageSource(doc="Microcontroller PWM output"))
    r_f = m.add("r_f", el.Resistor(R=R_f))
    c_f = m.add("c_f", el.Capacitor(C=C_f, v=0.0))
    sense = m.add("sense", el.VoltageSensor())
    gain = m.add("bridge_gain", blocks.Gain(k=V_bus / V_pwm))
    bridge = m.add("bridge", el.ControlledVoltageSource())
    motor = m.add("motor", machines.DCPermanentMagnet(R=R, L=L, k=k, J=J, B_v=B))
    brake = m.add("load", rot.IdealTorqueSource())    # reaction -tau_load on the shaft
    ground = m.add("ground", el.ElectricalReference())
    bridge_ground = m.add("bridge_ground", el.ElectricalReference())
    housing = m.add("housing", rot.RotationalReference())
    motor.inductor._set("i", 0.0)
    motor.inertia._set("w", 0.0)
    m.connect(duty, modulator.u)
    m.connect(modulator.y, pwm.u)
    m.connect(load, brake.tau_in)
    m.connect(pwm.p, r_f.p)
    m.connect(r_f.n, c_f.p, sense.p)
    m.connect(pwm.n, c_f.n, sense.n, ground.port)
    m.connect(sense.V, gain.u)
    m.connect(gain.y, bridge.u)
    m.connect(bridge.p, motor.p)
    m.connect(motor.n, bridge.n, bridge_ground.port)
    m.connect(motor.flange, brake.B)
    m.connect(motor.support, brake.A, housing.port)
    return m


def _equation(**values):
    model = HBridgeFilterEquation(**values)
    model._name = "hbridge_rc_filter"
    return model


_PARAMS = {
    "V_pwm": ParameterInfo("V", 5.0, "PWM high level of the microcontroller output",
                           "seed section 7, PIC EduKit 5 V logic"),
    "D": ParameterInfo("1", 0.3, "Duty cycle", CHOSEN),
    "f": ParameterInfo("Hz", 5e3, "PWM frequency", SEED_FILTER),
    "R_f": ParameterInfo("Ohm", 7.5e3, "Filter resistance", SEED_FILTER),
    "C_f": ParameterInfo("F", 40e-9, "Filter capacitance", SEED_FILTER),
    "V_bus": ParameterInfo("V", 19.2, "H-bridge supply voltage", "seed, test bench"),
    "R": ParameterInfo("Ohm", 7.1, "Armature resistance", SEED_MOTOR),
    "L": ParameterInfo("H", 3.408e-4, "Armature inductance", SEED_MOTOR),
    "k": ParameterInfo("V*s/rad", 0.151, "Motor constant", SEED_MOTOR),
    "J": ParameterInfo("kg*m^2", 4.8e-6, "Rotor inertia", SEED_MOTOR),
    "B": ParameterInfo("N*m*s/rad", 1.236e-4, "Viscous friction", SEED_MOTOR),
}
_PSS = periodic_steady_state(**{key: info.default for key, info in _PARAMS.items()})

ENTRY = register(ModelEntry(
    name="hbridge_rc_filter",
    description=("The seed's PWM-to-analog RC filter (7.5 kOhm, 40 nF, cut-off 530.5 Hz) "
                 "at 5 kHz, its output commanding an H-bridge that drives the seed's DC "
                 "motor."),
    parameters=_PARAMS,
    variants={"acausal": _acausal, "equation": _equation, "inputs": _inputs},
    outputs={"acausal": {"v_f": "c_f.v", "i": "motor.inductor.i", "w": "motor.inertia.w"},
             "inputs": {"v_f": "c_f.v", "i": "motor.inductor.i", "w": "motor.inertia.w"},
             "equation": {"v_f": "v_f", "i": "i", "w": "w"}},
    output_units={"v_f": "V", "i": "A", "w": "rad/s"},
    # 150 whole PWM periods: the motor's mechanical time constant is 1.4 ms, and the run
    # ends on a rising edge, where the periodic state is known exactly
    # explicit Runge-Kutta with located events: the system is not stiff (fastest time
    # constant 48 us, PWM period 200 us), and the Rosenbrock plugin misses a falling edge
    # here (reported)
    experiment=Experiment(t_stop=0.03, solver="rk45", rtol=1e-8, atol=1e-10),
    expected=dict(_PSS),
    expected_tolerance=1e-5, variant_tolerance=1e-5,
    tags=("electrical", "filter", "pwm", "hil", "motor", "events"),
))
