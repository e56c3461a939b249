"""The seed's DC motor (table 6-1) under closed-loop control: speed and position loops with
PI controllers and a 3 A current limit (the seed's section 6.4).

Plant (as in ``dc_motor``): ``L di/dt = V - R i - k w``, ``J dw/dt = k i - B w``,
``dphi/dt = w``.

Cascade control: an outer PI speed controller commands the current,
limited to ``+-I_max``; an inner PI current controller with back-EMF feed-forward commands
the voltage, limited to ``+-V_max`` (the database entries)::

    i_ref = sat(Kp e_w + Ki x_w, I_max),      e_w = w_ref - w
    V     = sat(Kp_i (i_ref - i) + Ki_i x_i + k w, V_max)

The current gains cancel the armature pole (``Kp_i = L w_c``, ``Ki_i = R w_c``): the
current follows ``i_ref`` as a first-order lag ``w_c / (s + w_c)`` without overshoot, so
``|i| <= I_max``. :class:`DCMotorSpeedPIVoltage` (the seed's structure, not a database
entry since it is another controller, not another formulation) drives the voltage from
the speed PI directly, ``V = sat(Kp e_w + Ki x_w, V_max)``, with no current limit: keeping
``|i| <= 3 A`` is then a requirement for the gains (``mechatron optimize``).

Both integrators have back-calculation anti-windup: ``dx/dt = e + (u_sat - u)/(K T_aw)``
with ``K`` the loop's proportional gain and ``T_aw`` a ratio (dimensionless): the
tracking time constant is ``T_t = T_aw K / K_i``, ``T_aw`` times the integral time.
The saturation is the smooth ``sat(x, a) = (sqrt((x + a)^2 + eps^2) -
sqrt((x - a)^2 + eps^2)) / 2`` with ``eps = 1e-3 a``: it never exceeds ``a``, differs from a
hard clamp by less than ``eps^2 / (4 (a - |x|))`` inside the band, and has no events (the
optimizer needs derivatives).

The position entry wraps a proportional position loop around the same speed loop:
``w_ref = sat(Kp_pos (phi_ref - phi), w_max)``.
"""

from __future__ import annotations

import casadi as ca

import mechatron as mt
from mechatron.models.dc_motor import SeedMotor
from mechatron.models.entry import Experiment, ModelEntry, ParameterInfo
from mechatron.models.registry import register

__all__ = ["DCMotorSpeedPI", "DCMotorPositionPI", "DCMotorSpeedPIVoltage", "smooth_sat"]

SEED = "seed table 6-1, calculated"


def smooth_sat(x, a, eps_rel: float = 1e-3):
    """``x`` limited to ``[-a, a]`` smoothly (see the module docstring)."""
    eps = eps_rel * a
    return 0.5 * (ca.sqrt((x + a) ** 2 + eps ** 2) - ca.sqrt((x - a) ** 2 + eps ** 2))


class _Drive(SeedMotor, partial=True):
    """The motor and the current loop shared by both controllers."""

    V_max = mt.Parameter("V", default=24.0, min=0, doc="Supply voltage limit")
    I_max = mt.Parameter("A", default=3.0, min=0, doc="Current limit")
    Kp = mt.Parameter("A*s/rad", default=0.03, min=0, doc="Speed PI proportional gain")
    Ki = mt.Parameter("A/rad", default=3.0, min=0, doc="Speed PI integral gain")
    w_c = mt.Parameter("rad/s", default=5000.0, min=0, doc="Current loop bandwidth")
    T_aw = mt.Parameter("1", default=2e-3, min=0,
                        doc="Anti-windup tracking time over the integral time K/K_i")
    i = mt.Variable("A", start=0.0, doc="Armature current")
    w = mt.Variable("rad/s", start=0.0, doc="Rotor speed")
    phi = mt.Variable("rad", start=0.0, doc="Rotor angle")
    x_w = mt.Variable("rad", start=0.0, doc="Speed error integral")
    x_i = mt.Variable("A*s", start=0.0, doc="Current error integral")
    w_ref = mt.Variable("rad/s", doc="Speed reference")
    i_ref = mt.Variable("A", doc="Current reference (limited)")
    V = mt.Variable("V", doc="Armature voltage (limited)")

    def equations(self):
        e = self.w_ref - self.w
        u = self.Kp * e + self.Ki * self.x_w
        i_ref = smooth_sat(u, self.I_max)
        kp_i, ki_i = self.L * self.w_c, self.R * self.w_c
        v_cmd = kp_i * (i_ref - self.i) + ki_i * self.x_i + self.k * self.w
        v = smooth_sat(v_cmd, self.V_max)
        return [self.i_ref == i_ref, self.V == v,
                self.L * mt.der(self.i) == self.V - self.R * self.i - self.k * self.w,
                self.J * mt.der(self.w) == self.k * self.i - self.B * self.w,
                mt.der(self.phi) == self.w,
                mt.der(self.x_w) == e + (i_ref - u) / (self.Kp * self.T_aw),
                mt.der(self.x_i) == (i_ref - self.i) + (v - v_cmd) / (kp_i * self.T_aw)]


class DCMotorSpeedPI(_Drive):
    """Speed control: PI speed loop, 3 A current limit, PI current loop (cascade)."""

    w_set = mt.Parameter("rad/s", default=100.0, doc="Speed reference step at t = 0")

    def equations(self):
        return [self.w_ref == self.w_set]


class DCMotorPositionPI(_Drive):
    """Position control: P position loop around the PI speed loop and the current loop."""

    phi_set = mt.Parameter("rad", default=6.283185307179586,
                           doc="Position reference step at t = 0")
    Kp_pos = mt.Parameter("1/s", default=100.0, min=0, doc="Position loop gain")
    w_max = mt.Parameter("rad/s", default=150.0, min=0, doc="Speed reference limit")

    def equations(self):
        return [self.w_ref == smooth_sat(self.Kp_pos * (self.phi_set - self.phi),
                                         self.w_max)]


class DCMotorSpeedPIVoltage(SeedMotor):
    """The seed's structure: the speed PI drives the voltage directly (no current limit).

    ``V = sat(Kp e + Ki x, V_max)`` with ``e = w_set - w`` and anti-windup."""

    V_max = mt.Parameter("V", default=24.0, min=0, doc="Supply voltage limit")
    Kp = mt.Parameter("V*s/rad", default=0.05, min=0, doc="Speed PI proportional gain")
    Ki = mt.Parameter("V/rad", default=5.0, min=0, doc="Speed PI integral gain")
    T_aw = mt.Parameter("1", default=2e-3, min=0,
                        doc="Anti-windup tracking time over the integral time K/K_i")
    w_set = mt.Parameter("rad/s", default=100.0, doc="Speed reference step at t = 0")
    i = mt.Variable("A", start=0.0, doc="Armature current")
    w = mt.Variable("rad/s", start=0.0, doc="Rotor speed")
    x_w = mt.Variable("rad", start=0.0, doc="Speed error integral")
    V = mt.Variable("V", doc="Armature voltage (limited)")

    def equations(self):
        e = self.w_set - self.w
        u = self.Kp * e + self.Ki * self.x_w
        v = smooth_sat(u, self.V_max)
        return [self.V == v,
                self.L * mt.der(self.i) == self.V - self.R * self.i - self.k * self.w,
                self.J * mt.der(self.w) == self.k * self.i - self.B * self.w,
                mt.der(self.x_w) == e + (v - u) / (self.Kp * self.T_aw)]


_MOTOR = {
    "R": ParameterInfo("Ohm", 7.1, "Armature resistance", SEED),
    "L": ParameterInfo("H", 3.408e-4, "Armature inductance", SEED),
    "k": ParameterInfo("V*s/rad", 0.151, "Motor constant", SEED),
    "J": ParameterInfo("kg*m^2", 4.8e-6, "Rotor inertia", SEED),
    "B": ParameterInfo("N*m*s/rad", 1.236e-4, "Viscous friction coefficient", SEED),
    "V_max": ParameterInfo("V", 24.0, "Supply voltage limit", "design choice"),
}
_LOOPS = {
    "I_max": ParameterInfo("A", 3.0, "Current limit", "seed 6.4: |i| <= 3 A"),
    "Kp": ParameterInfo("A*s/rad", 0.03, "Speed PI proportional gain",
                        "about J w_s / k, w_s = 1000 rad/s"),
    "Ki": ParameterInfo("A/rad", 3.0, "Speed PI integral gain", "PI zero at 100 rad/s"),
    "w_c": ParameterInfo("rad/s", 5000.0, "Current loop bandwidth", "design choice"),
}


def _speed_cascade(R, L, k, J, B, V_max, I_max, Kp, Ki, w_c, w_set):
    m = DCMotorSpeedPI(R=R, L=L, k=k, J=J, B=B, V_max=V_max, I_max=I_max, Kp=Kp, Ki=Ki,
                       w_c=w_c, w_set=w_set)
    m._name = "dc_motor_speed_pi"
    return m


def _position(R, L, k, J, B, V_max, I_max, Kp, Ki, w_c, phi_set, Kp_pos, w_max):
    m = DCMotorPositionPI(R=R, L=L, k=k, J=J, B=B, V_max=V_max, I_max=I_max, Kp=Kp,
                          Ki=Ki, w_c=w_c, phi_set=phi_set, Kp_pos=Kp_pos, w_max=w_max)
    m._name = "dc_motor_position_pi"
    return m


SPEED = register(ModelEntry(
    name="dc_motor_speed_pi",
    description=("DC motor speed control (seed 6.4): PI speed loop, 3 A current limit, PI "
                 "current loop with back-EMF feed-forward; a 100 rad/s reference step."),
    parameters={**_MOTOR, **_LOOPS,
                "w_set": ParameterInfo("rad/s", 100.0, "Speed reference step at t = 0",
                                       "test case")},
    variants={"cascade": _speed_cascade},
    outputs={"cascade": {"w": "w", "i": "i", "V": "V"}},
    output_units={"w": "rad/s", "i": "A", "V": "V"},
    experiment=Experiment(t_stop=0.1, rtol=1e-8, atol=1e-10),
    expected={"w": 100.0},
    expected_tolerance=1e-4,
    tags=("seed", "electromechanical", "motor", "control"),
))

POSITION = register(ModelEntry(
    name="dc_motor_position_pi",
    description=("DC motor position control: P position loop (speed limit 150 rad/s) "
                 "around the PI speed loop with a 3 A current limit; a one-turn step."),
    parameters={**_MOTOR, **_LOOPS,
                "phi_set": ParameterInfo("rad", 6.283185307179586,
                                         "Position reference step at t = 0", "test case"),
                "Kp_pos": ParameterInfo("1/s", 100.0, "Position loop gain",
                                        "a fifth of the speed loop bandwidth"),
                "w_max": ParameterInfo("rad/s", 150.0, "Speed reference limit",
                                       "below the no-load speed at 24 V")},
    variants={"cascade": _position},
    outputs={"cascade": {"phi": "phi", "w": "w", "i": "i"}},
    output_units={"phi": "rad", "w": "rad/s", "i": "A"},
    experiment=Experiment(t_stop=0.2, rtol=1e-8, atol=1e-10),
    expected={"phi": 6.283185307179586},
    expected_tolerance=1e-3,
    tags=("seed", "electromechanical", "motor", "control"),
))
