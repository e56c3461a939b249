"""Ball-screw linear axis driven by the seed's DC motor.

The motor (table 6-1) turns a ball screw of lead ``lead`` and efficiency ``eta`` whose nut
carries a carriage of mass ``M`` on a guide with viscous friction ``b``. With the
transmission ``m = lead / (2 pi)`` and power flowing from the motor to the carriage, the
screw needs the torque ``m F / eta`` to push the force ``F = M v' + b v``, so the drive is
one second-order system in the motor speed:
``L di/dt = V - R i - k w`` and
``(J + M m^2 / eta) dw/dt = k i - (B + b m^2 / eta) w``, with ``v = m w``.
Final speed: ``w = k V / (R (B + b m^2 / eta) + k^2)``.

Variants: ``acausal`` (library parts), ``equation`` (the two ODEs) and ``inputs`` (the
network driven from outside: the armature voltage ``V`` and a load force ``F_load`` on
the carriage, opposing its motion, are the model's external inputs; start values ``V``
and 0, so by default it is the ``acausal`` axis). With a load force ``F`` (the motor still
driving) the final speed is ``w = (k V - R m F / eta) / (R (B + b m^2 / eta) + k^2)``.
"""

from __future__ import annotations

import math

import mechatron as mt
from mechatron.library import electrical as el
from mechatron.library import electromechanical as em
from mechatron.library import mechanisms as mech
from mechatron.library import rotational as rot
from mechatron.library import translational as tr
from mechatron.models.dc_motor import SeedMotor
from mechatron.models.entry import Experiment, ModelEntry, ParameterInfo
from mechatron.models.registry import register

__all__ = ["BallScrewAcausal", "BallScrewEquation", "final_speed"]

SEED = "seed table 6-1, calculated"
CATALOGUE = "typical small ball screw and slide"


class BallScrewAcausal(mt.Component):
    """DC motor, ball screw, carriage and guide as a network of library parts."""

    source = el.DCVoltageSource()
    resistor = el.Resistor()
    inductor = el.Inductor()
    emf = em.RotationalEMF()
    rotor = rot.Inertia()
    bearing = rot.RotationalDamper()
    screw = mech.LeadScrew()
    carriage = tr.Mass()
    guide = tr.TranslationalDamper()
    position = tr.PositionSensor()
    ground = el.ElectricalReference()
    housing = rot.RotationalReference()
    bed = tr.TranslationalReference()

    def equations(self):
        return [mt.connect(self.source.p, self.resistor.p),
                mt.connect(self.resistor.n, self.inductor.p),
                mt.connect(self.inductor.n, self.emf.p),
                mt.connect(self.emf.n, self.source.n, self.ground.port),
                mt.connect(self.emf.A, self.rotor.port, self.bearing.A, self.screw.R),
                mt.connect(self.emf.B, self.bearing.B, self.housing.port),
                mt.connect(self.screw.T, self.carriage.port, self.guide.A,
                           self.position.A),
                mt.connect(self.guide.B, self.position.B, self.bed.port)]


class BallScrewEquation(SeedMotor):
    """The axis as the motor's two ODEs with the carriage reflected through the screw."""

    V = mt.Parameter("V", default=19.2, doc="Supply voltage")
    lead = mt.Parameter("m", default=5e-3, min=0, doc="Screw lead")
    eta = mt.Parameter("1", default=0.9, min=0, max=1, doc="Screw efficiency")
    M = mt.Parameter("kg", default=2.0, min=0, doc="Carriage mass")
    b = mt.Parameter("N*s/m", default=50.0, min=0, doc="Guide viscous friction")
    i = mt.Variable("A", start=0.0, doc="Current")
    w = mt.Variable("rad/s", start=0.0, doc="Motor speed")
    x = mt.Variable("m", start=0.0, doc="Carriage position")
    v = mt.Variable("m/s", doc="Carriage velocity")

    def equations(self):
        m = self.lead / (2 * math.pi)
        return [self.L * mt.der(self.i) == self.V - self.R * self.i - self.k * self.w,
                (self.J + self.M * m ** 2 / self.eta) * mt.der(self.w)
                == self.k * self.i - (self.B + self.b * m ** 2 / self.eta) * self.w,
                self.v == m * self.w,
                mt.der(self.x) == self.v]


def final_speed(V, R, L, k, J, B, lead, eta, M, b) -> float:
    """Final motor speed in rad/s."""
    m = lead / (2 * math.pi)
    return k * V / (R * (B + b * m ** 2 / eta) + k ** 2)


def _acausal(V, R, L, k, J, B, lead, eta, M, b):
    m = BallScrewAcausal(doc="ball-screw axis, acausal network")
    m._name = "ball_screw_axis"
    m.source._values["V"] = V
    m.resistor._values["R"] = R
    m.inductor._values["L"] = L
    m.emf._values["k"] = k
    m.rotor._values["J"] = J
    m.bearing._values["D"] = B
    m.screw._values.update(lead=lead, eta=eta)
    m.carriage._values["m"] = M
    m.guide._values["b"] = b
    return m


def _inputs(V, R, L, k, J, B, lead, eta, M, b):
    """The axis driven from outside: a controlled voltage source on the armature and a
    force source on the carriage (reaction ``-F_load`` on the carriage)."""
    m = mt.System("ball_screw_axis", doc="ball-screw axis with external inputs")
    u = m.input("V", unit="V", start=V, doc="Armature voltage")
    f_load = m.input("F_load", unit="N", start=0.0, doc="Load force, opposing motion")
    source = m.add("source", el.ControlledVoltageSource())
    resistor = m.add("resistor", el.Resistor(R=R))
    inductor = m.add("inductor", el.Inductor(L=L))
    emf = m.add("emf", em.RotationalEMF(k=k))
    rotor = m.add("rotor", rot.Inertia(J=J))
    bearing = m.add("bearing", rot.RotationalDamper(D=B))
    screw = m.add("screw", mech.LeadScrew(lead=lead, eta=eta))
    carriage = m.add("carriage", tr.Mass(m=M))
    guide = m.add("guide", tr.TranslationalDamper(b=b))
    position = m.add("position", tr.PositionSensor())
    load = m.add("load", tr.IdealForceSource())
    ground = m.add("ground", el.ElectricalReference())
    housing = m.add("housing", rot.RotationalReference())
    bed = m.add("bed", tr.TranslationalReference())
    m.connect(u, source.u)
    m.connect(f_load, load.f_in)
    m.connect(source.p, resistor.p)
    m.connect(resistor.n, inductor.p)
    m.connect(inductor.n, emf.p)
    m.connect(emf.n, source.n, ground.port)
    m.connect(emf.A, rotor.port, bearing.A, screw.R)
    m.connect(emf.B, bearing.B, housing.port)
    m.connect(screw.T, carriage.port, guide.A, position.A, load.B)
    m.connect(guide.B, position.B, load.A, bed.port)
    return m


def _equation(**values):
    m = BallScrewEquation(**values)
    m._name = "ball_screw_axis"
    return m


_PARAMS = {
    "V": ParameterInfo("V", 19.2, "Supply voltage step at t = 0", "seed, test bench"),
    "R": ParameterInfo("Ohm", 7.1, "Armature resistance", SEED),
    "L": ParameterInfo("H", 3.408e-4, "Armature inductance", SEED),
    "k": ParameterInfo("V*s/rad", 0.151, "Motor constant", SEED),
    "J": ParameterInfo("kg*m^2", 4.8e-6, "Rotor inertia", SEED),
    "B": ParameterInfo("N*m*s/rad", 1.236e-4, "Motor viscous friction", SEED),
    "lead": ParameterInfo("m", 5e-3, "Screw lead (travel per revolution)", CATALOGUE),
    "eta": ParameterInfo("1", 0.9, "Screw efficiency, motor driving", CATALOGUE),
    "M": ParameterInfo("kg", 2.0, "Carriage mass", CATALOGUE),
    "b": ParameterInfo("N*s/m", 50.0, "Guide viscous friction", CATALOGUE),
}
_W = final_speed(**{k: v.default for k, v in _PARAMS.items()})

ENTRY = register(ModelEntry(
    name="ball_screw_axis",
    description=("Linear axis: the seed's DC motor drives a carriage through a ball screw "
                 "with efficiency; electrical, rotational and translational domains."),
    parameters=_PARAMS,
    variants={"acausal": _acausal, "equation": _equation, "inputs": _inputs},
    outputs={"acausal": {"w": "rotor.w", "v": "carriage.v", "x": "position.x",
                         "i": "inductor.i"},
             "inputs": {"w": "rotor.w", "v": "carriage.v", "x": "position.x",
                        "i": "inductor.i"},
             "equation": {"w": "w", "v": "v", "x": "x", "i": "i"}},
    output_units={"w": "rad/s", "v": "m/s", "x": "m", "i": "A"},
    experiment=Experiment(t_stop=0.1, rtol=1e-10, atol=1e-12),
    expected={"w": _W, "v": _W * 5e-3 / (2 * math.pi)},
    expected_tolerance=1e-6, variant_tolerance=1e-8,
    tags=("electromechanical", "motor", "translational", "axis"),
))
