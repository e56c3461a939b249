"""The brush DC motor of the seed (its table 6-1, calculated values), in four variants:
an acausal network, user-written ODEs, a Simulink-style block diagram, and the network
with the armature voltage ``V`` and a load torque ``tau_load`` as external inputs
(``inputs``: driven by ``simulate(inputs=...)``, FMU inputs or a HIL controller).

Armature: ``L di/dt = V - R i - k w``; rotor: ``J dw/dt = k i - B w``. A voltage step of
``V`` at ``t = 0``. The analytic final speed is ``k V / (R B + k^2)``.
"""

from __future__ import annotations

import mechatron as mt
from mechatron.library import electrical as el
from mechatron.library import electromechanical as em
from mechatron.library import rotational as rot
from mechatron.models.entry import Experiment, ModelEntry, ParameterInfo
from mechatron.models.registry import register

SEED = "seed table 6-1, calculated"


class DCMotorAcausal(mt.Component):
    """DC motor as a physical network: source, resistor, inductor, EMF, inertia, damper."""

    source = el.DCVoltageSource()
    resistor = el.Resistor()
    inductor = el.Inductor()
    emf = em.RotationalEMF()
    inertia = rot.Inertia()
    damper = rot.RotationalDamper()
    ground = el.ElectricalReference()
    fixed = rot.RotationalReference()

    def equations(self):
        return [mt.connect(self.source.p, self.resistor.p),
                mt.connect(self.resistor.n, self.inductor.p),
                mt.connect(self.inductor.n, self.emf.p),
                mt.connect(self.emf.n, self.source.n, self.ground.port),
                mt.connect(self.emf.A, self.inertia.port, self.damper.A),
                mt.connect(self.emf.B, self.damper.B, self.fixed.port)]


class SeedMotor(mt.Component, partial=True):
    """The seed DC motor's constants (table 6-1, calculated) as parameters, for the
    equation models built on that motor to inherit."""

    R = mt.Parameter("Ohm", default=7.1, min=0, doc="Armature resistance")
    L = mt.Parameter("H", default=3.408e-4, min=0, doc="Armature inductance")
    k = mt.Parameter("V*s/rad", default=0.151, min=0, doc="Motor constant")
    J = mt.Parameter("kg*m^2", default=4.8e-6, min=0, doc="Rotor inertia")
    B = mt.Parameter("N*m*s/rad", default=1.236e-4, min=0, doc="Viscous friction")


class DCMotorODE(SeedMotor):
    """DC motor as a user-written set of ODEs (the Simscape-language equivalent)."""

    V = mt.Parameter("V", default=19.2, doc="Supply voltage")
    i = mt.Variable("A", start=0.0, doc="Armature current")
    w = mt.Variable("rad/s", start=0.0, doc="Rotor speed")

    def equations(self):
        return [self.L * mt.der(self.i) == self.V - self.R * self.i - self.k * self.w,
                self.J * mt.der(self.w) == self.k * self.i - self.B * self.w]


def _blocks(V, R, L, k, J, B):
    """The "standard Simulink" model of the seed: two integrators closed by gains and sums.

    ``di/dt = (V - R i - k w) / L`` and ``dw/dt = (k i - B w) / J``: the sums form the
    armature voltage balance and the torque balance, the gains divide by ``L`` and ``J``.
    """
    from mechatron.library import blocks
    m = mt.System("dc_motor", doc="DC motor, Simulink-style block diagram")
    supply = m.add("supply", blocks.Constant(value=V))
    v_sum = m.add("v_sum", blocks.Add3(k1=1.0, k2=-R, k3=-k))
    inv_l = m.add("inv_L", blocks.Gain(k=1.0 / L))
    current = m.add("current", blocks.Integrator(y=0.0))
    t_sum = m.add("torque_sum", blocks.Add(k1=k, k2=-B))
    inv_j = m.add("inv_J", blocks.Gain(k=1.0 / J))
    speed = m.add("speed", blocks.Integrator(y=0.0))
    m.connect(supply.y, v_sum.u1)
    m.connect(current.y, v_sum.u2, t_sum.u1)
    m.connect(speed.y, v_sum.u3, t_sum.u2)
    m.connect(v_sum.y, inv_l.u)
    m.connect(inv_l.y, current.u)
    m.connect(t_sum.y, inv_j.u)
    m.connect(inv_j.y, speed.u)
    return m


def _acausal(V, R, L, k, J, B):
    m = DCMotorAcausal(
        doc="DC motor, acausal network")
    m._name = "dc_motor"
    m.source._values["V"] = V
    m.resistor._values["R"] = R
    m.inductor._values["L"] = L
    m.emf._values["k"] = k
    m.inertia._values["J"] = J
    m.damper._values["D"] = B
    return m


def _inputs(V, R, L, k, J, B):
    """The acausal network driven from outside: the armature voltage ``V`` and the load
    torque ``tau_load`` (opposing the rotation) are the model's external inputs (their
    defaults: the step ``V`` and no load), for ``simulate(inputs=...)``, FMUs and HIL."""
    m = mt.System("dc_motor", doc="DC motor, acausal network with external inputs")
    u = m.input("V", unit="V", start=V, doc="Armature voltage")
    load = m.input("tau_load", unit="N*m", start=0.0, doc="Load torque, opposing rotation")
    source = m.add("source", el.ControlledVoltageSource())
    resistor = m.add("resistor", el.Resistor(R=R))
    inductor = m.add("inductor", el.Inductor(L=L))
    emf = m.add("emf", em.RotationalEMF(k=k))
    inertia = m.add("inertia", rot.Inertia(J=J))
    damper = m.add("damper", rot.RotationalDamper(D=B))
    brake = m.add("load", rot.IdealTorqueSource())    # reaction -tau_load on the shaft
    ground = m.add("ground", el.ElectricalReference())
    fixed = m.add("fixed", rot.RotationalReference())
    m.connect(u, source.u)
    m.connect(load, brake.tau_in)
    m.connect(source.p, resistor.p)
    m.connect(resistor.n, inductor.p)
    m.connect(inductor.n, emf.p)
    m.connect(emf.n, source.n, ground.port)
    m.connect(emf.A, inertia.port, damper.A, brake.B)
    m.connect(emf.B, damper.B, brake.A, fixed.port)
    return m


def _ode(V, R, L, k, J, B):
    m = DCMotorODE(V=V, R=R, L=L, k=k, J=J, B=B)
    m._name = "dc_motor"
    return m


ENTRY = register(ModelEntry(
    name="dc_motor",
    description=("Brush DC motor under a voltage step: armature R-L circuit, back EMF and "
                 "torque constant k, rotor inertia J with viscous friction B."),
    parameters={
        "V": ParameterInfo("V", 19.2, "Supply voltage step at t = 0", "seed, test bench"),
        "R": ParameterInfo("Ohm", 7.1, "Armature resistance", SEED),
        "L": ParameterInfo("H", 3.408e-4, "Armature inductance", SEED),
        "k": ParameterInfo("V*s/rad", 0.151, "Motor constant (torque and back EMF)", SEED),
        "J": ParameterInfo("kg*m^2", 4.8e-6, "Rotor inertia", SEED),
        "B": ParameterInfo("N*m*s/rad", 1.236e-4, "Viscous friction coefficient", SEED),
    },
    variants={"acausal": _acausal, "ode": _ode, "blocks": _blocks, "inputs": _inputs},
    outputs={"acausal": {"w": "inertia.w", "i": "inductor.i"},
             "ode": {"w": "w", "i": "i"},
             "inputs": {"w": "inertia.w", "i": "inductor.i"},
             "blocks": {"w": "speed.y", "i": "current.y"}},
    output_units={"w": "rad/s", "i": "A"},
    experiment=Experiment(t_stop=0.5, rtol=1e-8, atol=1e-10),
    expected={"w": 0.151 * 19.2 / (7.1 * 1.236e-4 + 0.151 ** 2),
              "i": 1.236e-4 * 19.2 / (7.1 * 1.236e-4 + 0.151 ** 2)},
    expected_tolerance=1e-5,
    variant_tolerance=1e-8,
    tags=("seed", "electromechanical", "motor"),
))
