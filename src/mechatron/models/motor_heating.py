"""Motor winding heating: the seed's DC motor under load, with its winding resistance
heating a thermal mass that loses heat to the ambient, which in turn raises the resistance.

Electrical, rotational and thermal domains in one network (variant ``acausal``), and the
same physics as user-written equations (variant ``equation``):
``L di/dt = V - R(T) i - k w``, ``J dw/dt = k i - B w - T_L``,
``C dT/dt = R(T) i^2 - G (T - T_amb)``, ``R(T) = R_ref (1 + alpha (T - T_ref))``.
Time scales from 50 us (electrical) to minutes (thermal): a stiff problem for BDF.

The steady state has a closed form once ``R`` is known, and ``R`` follows from a scalar
fixed point, computed by :func:`steady_state` with no simulation.
"""

from __future__ import annotations

import mechatron as mt
from mechatron.library import electrical as el
from mechatron.library import electromechanical as em
from mechatron.library import rotational as rot
from mechatron.library import thermal as th
from mechatron.models.entry import Experiment, ModelEntry, ParameterInfo
from mechatron.models.registry import register

__all__ = ["MotorHeatingAcausal", "MotorHeatingEquation", "steady_state"]

SEED = "seed table 6-1, calculated"
CHOSEN = "chosen: a small motor's winding and housing"
COPPER = "copper, at 20 degC"


class MotorHeatingAcausal(mt.Component):
    """DC motor with a heating winding resistance, a thermal mass and cooling to ambient,
    driving an inertia against a constant load torque."""

    source = el.DCVoltageSource()
    winding = el.HeatingResistor()
    inductor = el.Inductor()
    emf = em.RotationalEMF()
    inertia = rot.Inertia()
    damper = rot.RotationalDamper()
    load = rot.ConstantTorque()
    ground = el.ElectricalReference()
    fixed = rot.RotationalReference()
    mass = th.HeatCapacitor()
    cooling = th.ThermalConductor()
    ambient = th.FixedTemperature()

    def equations(self):
        return [mt.connect(self.source.p, self.winding.p),
                mt.connect(self.winding.n, self.inductor.p),
                mt.connect(self.inductor.n, self.emf.p),
                mt.connect(self.emf.n, self.source.n, self.ground.port),
                mt.connect(self.emf.A, self.inertia.port, self.damper.A, self.load.A),
                mt.connect(self.emf.B, self.damper.B, self.load.B, self.fixed.port),
                mt.connect(self.winding.heat_port, self.mass.port, self.cooling.A),
                mt.connect(self.cooling.B, self.ambient.port)]


class MotorHeatingEquation(mt.Component):
    """The same motor as three ODEs (electrical, mechanical, thermal)."""

    V = mt.Parameter("V", default=19.2, doc="Supply voltage")
    R_ref = mt.Parameter("Ohm", default=7.1, min=0, doc="Resistance at T_ref")
    alpha = mt.Parameter("1/K", default=3.93e-3, doc="Temperature coefficient")
    T_ref = mt.Parameter("K", default=293.15, min=0, doc="Reference temperature")
    L = mt.Parameter("H", default=3.408e-4, min=0, doc="Inductance")
    k = mt.Parameter("V*s/rad", default=0.151, min=0, doc="Motor constant")
    J = mt.Parameter("kg*m^2", default=4.8e-6, min=0, doc="Inertia")
    B = mt.Parameter("N*m*s/rad", default=1.236e-4, min=0, doc="Viscous friction")
    T_L = mt.Parameter("N*m", default=0.1, doc="Load torque")
    C = mt.Parameter("J/K", default=5.0, min=0, doc="Winding thermal mass")
    G = mt.Parameter("W/K", default=0.1, min=0, doc="Thermal conductance to ambient")
    T_amb = mt.Parameter("K", default=293.15, min=0, doc="Ambient temperature")
    i = mt.Variable("A", start=0.0, doc="Current")
    w = mt.Variable("rad/s", start=0.0, doc="Speed")
    T = mt.Variable("K", start=293.15, doc="Winding temperature")
    R = mt.Variable("Ohm", doc="Winding resistance")

    def equations(self):
        return [self.R == self.R_ref * (1 + self.alpha * (self.T - self.T_ref)),
                self.L * mt.der(self.i) == self.V - self.R * self.i - self.k * self.w,
                self.J * mt.der(self.w) == self.k * self.i - self.B * self.w - self.T_L,
                self.C * mt.der(self.T) == self.R * self.i ** 2
                - self.G * (self.T - self.T_amb)]


def steady_state(V, R_ref, alpha, T_ref, L, k, J, B, T_L, C, G, T_amb):
    """Final current, speed, temperature and resistance, by fixed-point iteration on R."""
    R = R_ref
    for _ in range(200):
        # i = (T_L + B w) / k and V = R i + k w  =>  linear in (i, w)
        w = (V - R * T_L / k) / (k + R * B / k)
        i = (T_L + B * w) / k
        T = T_amb + R * i ** 2 / G
        R_new = R_ref * (1 + alpha * (T - T_ref))
        if abs(R_new - R) < 1e-15 * R:
            break
        R = R_new
    return {"i": i, "w": w, "T": T, "R": R}


def _acausal(V, R_ref, alpha, T_ref, L, k, J, B, T_L, C, G, T_amb):
    m = MotorHeatingAcausal(doc="DC motor with winding heating, acausal network")
    m._name = "motor_heating"
    m.source._values["V"] = V
    m.winding._values.update(R_ref=R_ref, alpha=alpha, T_ref=T_ref)
    m.inductor._values["L"] = L
    m.emf._values["k"] = k
    m.inertia._values["J"] = J
    m.damper._values["D"] = B
    m.load._values["T"] = -T_L                 # a load: it opposes positive rotation
    m.mass._values["C"] = C
    m.mass._set("T", T_amb)             # start at ambient (high priority)
    m.cooling._values["G"] = G
    m.ambient._values["T"] = T_amb
    return m


def _equation(**values):
    m = MotorHeatingEquation(**values, T=values["T_amb"])
    m._name = "motor_heating"
    return m


_PARAMS = {
    "V": ParameterInfo("V", 19.2, "Supply voltage", "seed, test bench"),
    "R_ref": ParameterInfo("Ohm", 7.1, "Winding resistance at T_ref", SEED),
    "alpha": ParameterInfo("1/K", 3.93e-3, "Temperature coefficient of resistance", COPPER),
    "T_ref": ParameterInfo("K", 293.15, "Reference temperature of R_ref", COPPER),
    "L": ParameterInfo("H", 3.408e-4, "Armature inductance", SEED),
    "k": ParameterInfo("V*s/rad", 0.151, "Motor constant", SEED),
    "J": ParameterInfo("kg*m^2", 4.8e-6, "Rotor inertia", SEED),
    "B": ParameterInfo("N*m*s/rad", 1.236e-4, "Viscous friction", SEED),
    "T_L": ParameterInfo("N*m", 0.1, "Load torque", CHOSEN),
    "C": ParameterInfo("J/K", 5.0, "Thermal mass of the winding", CHOSEN),
    "G": ParameterInfo("W/K", 0.1, "Thermal conductance winding to ambient", CHOSEN),
    "T_amb": ParameterInfo("K", 293.15, "Ambient temperature", CHOSEN),
}
_SS = steady_state(**{k: v.default for k, v in _PARAMS.items()})

ENTRY = register(ModelEntry(
    name="motor_heating",
    description=("DC motor under load whose winding heats up: electrical, rotational and "
                 "thermal domains coupled through a temperature-dependent resistance."),
    parameters=_PARAMS,
    variants={"acausal": _acausal, "equation": _equation},
    outputs={"acausal": {"i": "inductor.i", "w": "inertia.w", "T": "mass.T",
                         "R": "winding.R"},
             "equation": {"i": "i", "w": "w", "T": "T", "R": "R"}},
    output_units={"i": "A", "w": "rad/s", "T": "K", "R": "Ohm"},
    experiment=Experiment(t_stop=1200.0, rtol=1e-10, atol=1e-10),
    expected={k: _SS[k] for k in ("i", "w", "T", "R")},
    expected_tolerance=1e-6, variant_tolerance=1e-7,
    tags=("electromechanical", "thermal", "motor", "multi-domain"),
))
