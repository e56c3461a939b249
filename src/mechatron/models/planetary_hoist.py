"""A hoist: a permanent-magnet DC motor lifts a mass through a planetary gear, a drum and
an elastic rope.

The motor (``machines.DCPermanentMagnet``) drives the sun of an ideal planetary set whose
ring is held; the carrier turns the drum (radius ``r``), which winds the rope. The rope is
a spring-damper with a natural length (``translational.SpringDamper``, from the mass at A
to the drum at B); gravity pulls the mass down. The supply ramps from 0 to ``V`` over
``t_ramp`` (``electrical.RampVoltage``). Up is positive.

Equations (``n = 1 + z_ring/z_sun``, the sun-to-carrier ratio with the ring held; ``L_r``
the rope length)::

    L di/dt = v(t) - R i - k w
    J dw/dt = k i - B w - r F / n            (the drum torque r F reaches the sun / n)
    dL_r/dt = r w / n - v_m,   F = c (L_r - L_0) + d dL_r/dt
    m dv_m/dt = F - m g

Steady state (lifting at constant speed, ``F = m g``)::

    T_s = r m g / n,  w = (V - R T_s / k) / (k + R B / k),  i = (T_s + B w) / k
    v_m = r w / n,    L_r = L_0 + m g / c

Limitations: the rope also pushes when slack (a spring-damper, not a rope); the gear and
the drum are massless and lossless; no brake (at rest the load turns the motor backwards).

Variants: ``acausal`` (library parts: ``RampVoltage``, ``DCPermanentMagnet``,
``IdealPlanetary``, ``WheelAndAxle``, ``SpringDamper``, ``Mass``), ``equation`` (the
equations above as one user component) and ``inputs`` (the network driven from outside:
the armature voltage ``V`` and a load force ``F_load``, pulling the mass down beside its
weight, are the model's external inputs; start values ``V`` and 0; the ramp of the other
variants is the input table ``(0, 0), (t_ramp, V)``, held). With a load force the
steady state is that of a mass ``m + F_load / g``.
"""

from __future__ import annotations

import casadi as ca

import mechatron as mt
from mechatron.library import electrical as el
from mechatron.library import machines
from mechatron.library import mechanisms as mech
from mechatron.library import rotational as rot
from mechatron.library import translational as tr
from mechatron.models.entry import Experiment, ModelEntry, ParameterInfo
from mechatron.models.registry import register

__all__ = ["build_acausal", "HoistEquation", "steady_state", "ramp_input", "ENTRY"]

CHOSEN = "chosen: a small 24 V hoist"
G_STANDARD = 9.80665


def build_acausal(V, t_ramp, R, L, k, J, B, ratio, r, c, d, L_0, m, g, *,
                  inputs: bool = False):
    """The hoist as a network of library parts; ``inputs``: the voltage and a load force
    as external inputs (the ``inputs`` variant) instead of the ramp."""
    s = mt.System("planetary_hoist", doc="DC motor, planetary gear, drum, rope, load"
                  + (", external inputs" if inputs else ""))
    if inputs:
        u = s.input("V", unit="V", start=V, doc="Armature voltage")
        f_load = s.input("F_load", unit="N", start=0.0,
                         doc="Load force on the mass, pulling down")
        supply = s.add("supply", el.ControlledVoltageSource())
        s.connect(u, supply.u)
    else:
        supply = s.add("supply", el.RampVoltage(V=V, duration=t_ramp))
    motor = s.add("motor", machines.DCPermanentMagnet(R=R, L=L, k=k, J=J, B_v=B))
    gnd = s.add("gnd", el.ElectricalReference())
    gear = s.add("gear", rot.IdealPlanetary(ratio=ratio))
    housing = s.add("housing", rot.RotationalReference())
    drum = s.add("drum", mech.WheelAndAxle(r=r))
    rope = s.add("rope", tr.SpringDamper(c=c, d=d, s_rel0=L_0,
                                         s_rel=mt.Start(L_0 + m * g / c, "low")))
    load = s.add("load", tr.Mass(m=m))
    weight = s.add("weight", tr.ConstantForce(F=-m * g))
    ground = s.add("ground", tr.TranslationalReference())
    s.connect(supply.p, motor.p)
    s.connect(supply.n, motor.n, gnd.port)
    s.connect(motor.flange, gear.sun)
    s.connect(motor.support, gear.ring, housing.port)
    s.connect(gear.carrier, drum.R)
    s.connect(drum.T, rope.B)
    s.connect(rope.A, load.port, weight.A)
    s.connect(weight.B, ground.port)
    if inputs:
        pull = s.add("pull", tr.IdealForceSource())     # reaction -F_load on the mass
        s.connect(f_load, pull.f_in)
        s.connect(pull.B, load.port)
        s.connect(pull.A, ground.port)
    return s


def _inputs(**values):
    return build_acausal(**values, inputs=True)


def ramp_input(values: dict, t_stop: float) -> dict:
    """The ``inputs`` variant's signals that reproduce the ramped supply: the voltage
    table ``(0, 0), (t_ramp, V)`` (held after it) and no load force."""
    t_ramp = values["t_ramp"]
    return {"V": ([0.0, t_ramp], [0.0, values["V"]]), "F_load": 0.0}


class HoistEquation(mt.Component):
    """The hoist as its equations (module docstring), one user component."""

    V = mt.Parameter("V", default=24.0, doc="Supply voltage after the ramp")
    t_ramp = mt.Parameter("s", default=0.2, min=0, doc="Duration of the supply ramp")
    R = mt.Parameter("Ohm", default=0.5, min=0, doc="Armature resistance")
    L = mt.Parameter("H", default=1e-3, min=0, doc="Armature inductance")
    k = mt.Parameter("V*s/rad", default=0.05, min=0, doc="Motor constant")
    J = mt.Parameter("kg*m^2", default=2e-5, min=0, doc="Rotor inertia")
    B = mt.Parameter("N*m*s/rad", default=1e-5, min=0, doc="Motor viscous friction")
    ratio = mt.Parameter("1", default=9.0, min=0, doc="Ring teeth over sun teeth")
    r = mt.Parameter("m", default=0.02, min=0, doc="Drum radius")
    c = mt.Parameter("N/m", default=2e4, min=0, doc="Rope stiffness")
    d = mt.Parameter("N*s/m", default=50.0, min=0, doc="Rope damping")
    L_0 = mt.Parameter("m", default=1.0, min=0, doc="Unstretched rope length")
    m = mt.Parameter("kg", default=2.0, min=0, doc="Load mass")
    g = mt.Parameter("m/s^2", default=G_STANDARD, min=0, doc="Gravitational acceleration")
    i = mt.Variable("A", start=0.0, doc="Armature current")
    w = mt.Variable("rad/s", start=0.0, doc="Motor speed")
    L_r = mt.Variable("m", doc="Rope length")
    v_m = mt.Variable("m/s", start=0.0, doc="Load speed, up")
    F = mt.Variable("N", doc="Rope tension")
    v = mt.Variable("V", doc="Supply voltage")

    def equations(self):
        n = 1 + self.ratio
        v_drum = self.r * self.w / n
        return [self.v == ca.if_else(self.t_ramp <= self.time, self.V,
                                     self.V * self.time / self.t_ramp),
                self.L * mt.der(self.i) == self.v - self.R * self.i - self.k * self.w,
                self.J * mt.der(self.w) == self.k * self.i - self.B * self.w
                - self.r * self.F / n,
                mt.der(self.L_r) == v_drum - self.v_m,
                self.F == self.c * (self.L_r - self.L_0) + self.d * (v_drum - self.v_m),
                self.m * mt.der(self.v_m) == self.F - self.m * self.g]


def _equation(**values):
    start = values["L_0"] + values["m"] * values["g"] / values["c"]
    model = HoistEquation(**values, L_r=mt.Start(start, "high"))
    model._name = "planetary_hoist"
    return model


def steady_state(V, R, k, B, ratio, r, c, L_0, m, g, **_):
    """Lifting at constant speed: motor speed and current, load speed, rope length."""
    n = 1 + ratio
    t_s = r * m * g / n
    w = (V - R * t_s / k) / (k + R * B / k)
    return {"w": w, "i": (t_s + B * w) / k, "v_m": r * w / n, "L_r": L_0 + m * g / c}


_PARAMS = {
    "V": ParameterInfo("V", 24.0, "Supply voltage after the ramp", CHOSEN),
    "t_ramp": ParameterInfo("s", 0.2, "Duration of the supply ramp from 0", CHOSEN),
    "R": ParameterInfo("Ohm", 0.5, "Armature resistance", CHOSEN),
    "L": ParameterInfo("H", 1e-3, "Armature inductance", CHOSEN),
    "k": ParameterInfo("V*s/rad", 0.05, "Motor constant", CHOSEN),
    "J": ParameterInfo("kg*m^2", 2e-5, "Rotor inertia", CHOSEN),
    "B": ParameterInfo("N*m*s/rad", 1e-5, "Motor viscous friction", CHOSEN),
    "ratio": ParameterInfo("1", 9.0, "Planetary set: ring teeth over sun teeth (1:10 with "
                           "the ring held)", CHOSEN),
    "r": ParameterInfo("m", 0.02, "Drum radius", CHOSEN),
    "c": ParameterInfo("N/m", 2e4, "Rope stiffness", CHOSEN),
    "d": ParameterInfo("N*s/m", 50.0, "Rope damping", CHOSEN),
    "L_0": ParameterInfo("m", 1.0, "Unstretched rope length", CHOSEN),
    "m": ParameterInfo("kg", 2.0, "Load mass", CHOSEN),
    "g": ParameterInfo("m/s^2", G_STANDARD, "Gravitational acceleration",
                       "standard gravity (CGPM)"),
}

_DEFAULTS = {name: info.default for name, info in _PARAMS.items()}
_STEADY = steady_state(**_DEFAULTS)

ENTRY = register(ModelEntry(
    name="planetary_hoist",
    description=("A permanent-magnet DC motor lifts a mass through an ideal planetary "
                 "gear (ring held), a drum and an elastic rope, from a ramped supply."),
    parameters=_PARAMS,
    variants={"acausal": build_acausal, "equation": _equation, "inputs": _inputs},
    reference_inputs={"inputs": ramp_input},
    outputs={"acausal": {"w": "motor.inertia.w", "i": "motor.inductor.i",
                         "v_m": "load.v", "L_r": "rope.s_rel"},
             "inputs": {"w": "motor.inertia.w", "i": "motor.inductor.i",
                        "v_m": "load.v", "L_r": "rope.s_rel"},
             "equation": {"w": "w", "i": "i", "v_m": "v_m", "L_r": "L_r"}},
    output_units={"w": "rad/s", "i": "A", "v_m": "m/s", "L_r": "m"},
    experiment=Experiment(t_stop=2.0, rtol=1e-9, atol=1e-11),
    expected={key: _STEADY[key] for key in ("w", "i", "v_m", "L_r")},
    expected_tolerance=1e-6,
    variant_tolerance=1e-6,
    tags=("motor", "electromechanical", "gear", "planetary", "hoist", "issue 18"),
))
