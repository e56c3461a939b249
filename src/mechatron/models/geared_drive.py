"""The seed's DC motor driving a load inertia through a gear with backlash.

Motor: the brush DC motor of the seed (its table 6-1, as ``dc_motor``). It drives an ideal
gear (speed ratio ``N = w_motor / w_gear``), whose output turns the load inertia through a
backlash of total width ``b`` (penalty contact of stiffness ``k_c`` and damping ``d_c``,
as :class:`~mechatron.library.rotational.RotationalBacklash`). The load has viscous
friction ``b_L`` and a constant load torque ``T_L`` against positive rotation. The supply
is ``+V`` until ``t_rev`` and ``-V`` after: the motor reverses, the teeth separate, cross
the dead band and meet on the other flank.

Equations (``phi``: angle of the gear output relative to the load)::

    L di/dt = v(t) - R i - k w_m
    J_m dw_m/dt = k i - B w_m - tau / N
    dphi/dt = w_m / N - w_L
    J_L dw_L/dt = tau - b_L w_L - T_L
    tau = max(k_c (phi - b/2) + d_c dphi/dt, 0)   for phi > b/2
        = min(k_c (phi + b/2) + d_c dphi/dt, 0)   for phi < -b/2,   0 otherwise

Steady states with the teeth in contact (``v = +-V``)::

    w_m = (k v / R - T_L / N) / (k^2 / R + B + b_L / N^2),  w_L = w_m / N
    i = (v - k w_m) / R,  tau = b_L w_L + T_L,  phi = +-b/2 + tau / k_c

so across the reversal the load falls behind the gear output by
``b + (tau_fwd - tau_rev) / k_c``: the dead band plus the change of tooth deflection.

Variants: ``acausal`` (library electrical and rotational parts) and ``equation`` (the
equations above as one user component).
"""

from __future__ import annotations

import casadi as ca

import mechatron as mt
from mechatron.library import electrical as el
from mechatron.library import electromechanical as em
from mechatron.library import rotational as rot
from mechatron.library.electrical.interfaces import OnePort
from mechatron.models.entry import Experiment, ModelEntry, ParameterInfo
from mechatron.models.registry import register

__all__ = ["ReversingVoltageSource", "GearedDriveEquation", "build_acausal",
           "steady_state", "ENTRY"]

SEED = "seed table 6-1, calculated"
CHOSEN = "chosen: a small gearbox and load"


class ReversingVoltageSource(OnePort):
    """Voltage source that reverses at ``t_rev``: ``v == V`` before, ``-V`` from then on
    (an event)."""

    V = mt.Parameter("V", default=19.2, doc="Voltage before the reversal")
    t_rev = mt.Parameter("s", default=0.15, doc="Time of the reversal")

    def equations(self):
        return [self.v == ca.if_else(self.t_rev <= self.time, -self.V, self.V)]


def build_acausal(V, R, L, k, J_m, B, N, b, k_c, d_c, J_L, b_L, T_L, t_rev):
    """The drive as a network of library parts."""
    m = mt.System("geared_drive", doc="DC motor, gear with backlash, load")
    source = m.add("source", ReversingVoltageSource(V=V, t_rev=t_rev))
    resistor = m.add("resistor", el.Resistor(R=R))
    inductor = m.add("inductor", el.Inductor(L=L))
    emf = m.add("emf", em.RotationalEMF(k=k))
    ground = m.add("ground", el.ElectricalReference())
    rotor = m.add("rotor", rot.Inertia(J=J_m, w=mt.Start(0.0, "low")))
    bearing = m.add("bearing", rot.RotationalDamper(D=B))
    gear = m.add("gear", rot.IdealGear(ratio=N))
    backlash = m.add("backlash", rot.RotationalBacklash(b=b, k=k_c, d=d_c))
    load = m.add("load", rot.Inertia(J=J_L, w=mt.Start(0.0, "low")))
    load_friction = m.add("load_friction", rot.RotationalDamper(D=b_L))
    load_torque = m.add("load_torque", rot.ConstantTorque(T=-T_L))
    fixed = m.add("fixed", rot.RotationalReference())
    m.connect(source.p, resistor.p)
    m.connect(resistor.n, inductor.p)
    m.connect(inductor.n, emf.p)
    m.connect(emf.n, source.n, ground.port)
    m.connect(emf.A, rotor.port, bearing.A, gear.A)
    m.connect(gear.B, backlash.A)
    m.connect(backlash.B, load.port, load_friction.A, load_torque.A)
    m.connect(emf.B, bearing.B, load_friction.B, load_torque.B, fixed.port)
    return m


class GearedDriveEquation(mt.Component):
    """The geared drive as its equations (module docstring), one user component."""

    V = mt.Parameter("V", default=19.2, doc="Supply voltage (before the reversal)")
    R = mt.Parameter("Ohm", default=7.1, min=0, doc="Armature resistance")
    L = mt.Parameter("H", default=3.408e-4, min=0, doc="Armature inductance")
    k = mt.Parameter("V*s/rad", default=0.151, min=0, doc="Motor constant")
    J_m = mt.Parameter("kg*m^2", default=4.8e-6, min=0, doc="Rotor inertia")
    B = mt.Parameter("N*m*s/rad", default=1.236e-4, min=0, doc="Motor viscous friction")
    N = mt.Parameter("1", default=10.0, min=0, doc="Gear ratio w_m / w_gear")
    b = mt.Parameter("rad", default=0.05, min=0, doc="Backlash (total dead band)")
    k_c = mt.Parameter("N*m/rad", default=100.0, min=0, doc="Tooth contact stiffness")
    d_c = mt.Parameter("N*m*s/rad", default=0.5, min=0, doc="Tooth contact damping")
    J_L = mt.Parameter("kg*m^2", default=1e-3, min=0, doc="Load inertia")
    b_L = mt.Parameter("N*m*s/rad", default=5e-3, min=0, doc="Load viscous friction")
    T_L = mt.Parameter("N*m", default=0.02, doc="Load torque against positive rotation")
    t_rev = mt.Parameter("s", default=0.15, doc="Time of the voltage reversal")
    i = mt.Variable("A", start=0.0, doc="Armature current")
    w_m = mt.Variable("rad/s", start=0.0, doc="Motor speed")
    phi = mt.Variable("rad", start=0.0, doc="Gear output angle relative to the load")
    w_L = mt.Variable("rad/s", start=0.0, doc="Load speed")
    tau = mt.Variable("N*m", doc="Torque through the backlash (gear output to load)")
    v = mt.Variable("V", doc="Supply voltage")

    def equations(self):
        rate = self.w_m / self.N - self.w_L
        push = self.k_c * (self.phi - self.b / 2) + self.d_c * rate       # upper flank
        pull = self.k_c * (self.phi + self.b / 2) + self.d_c * rate       # lower flank
        upper = ca.if_else(self.phi - self.b / 2 > 0, ca.if_else(push > 0, push, 0), 0)
        lower = ca.if_else(-self.b / 2 - self.phi > 0, ca.if_else(-pull > 0, -pull, 0), 0)
        return [self.v == ca.if_else(self.t_rev <= self.time, -self.V, self.V),
                self.L * mt.der(self.i) == self.v - self.R * self.i - self.k * self.w_m,
                self.J_m * mt.der(self.w_m) == self.k * self.i - self.B * self.w_m
                - self.tau / self.N,
                mt.der(self.phi) == rate,
                self.tau == upper - lower,
                self.J_L * mt.der(self.w_L) == self.tau - self.b_L * self.w_L - self.T_L]


def _equation(**values):
    model = GearedDriveEquation(**values)
    model._name = "geared_drive"
    return model


def steady_state(V, R, k, B, N, b, k_c, b_L, T_L, **_):
    """Steady state with the teeth in contact under the supply voltage ``V`` (signed):
    motor speed, current, load speed, backlash torque and deflection ``phi``."""
    w_m = (k * V / R - T_L / N) / (k * k / R + B + b_L / N ** 2)
    w_L = w_m / N
    tau = b_L * w_L + T_L
    side = 1.0 if tau > 0 else -1.0
    return {"w_m": w_m, "i": (V - k * w_m) / R, "w_L": w_L, "tau": tau,
            "phi": side * b / 2 + tau / k_c}


_PARAMS = {
    "V": ParameterInfo("V", 19.2, "Supply voltage, reversed at t_rev", "seed, test bench"),
    "R": ParameterInfo("Ohm", 7.1, "Armature resistance", SEED),
    "L": ParameterInfo("H", 3.408e-4, "Armature inductance", SEED),
    "k": ParameterInfo("V*s/rad", 0.151, "Motor constant", SEED),
    "J_m": ParameterInfo("kg*m^2", 4.8e-6, "Rotor inertia", SEED),
    "B": ParameterInfo("N*m*s/rad", 1.236e-4, "Motor viscous friction", SEED),
    "N": ParameterInfo("1", 10.0, "Gear ratio, motor speed / gear output speed", CHOSEN),
    "b": ParameterInfo("rad", 0.05, "Backlash, total dead band at the gear output",
                       CHOSEN),
    "k_c": ParameterInfo("N*m/rad", 100.0, "Tooth contact stiffness", CHOSEN),
    "d_c": ParameterInfo("N*m*s/rad", 0.5, "Tooth contact damping (1.4 times critical "
                         "for the reduced inertia)", CHOSEN),
    "J_L": ParameterInfo("kg*m^2", 1e-3, "Load inertia", CHOSEN),
    "b_L": ParameterInfo("N*m*s/rad", 5e-3, "Load viscous friction", CHOSEN),
    "T_L": ParameterInfo("N*m", 0.02, "Constant load torque against positive rotation",
                         CHOSEN),
    "t_rev": ParameterInfo("s", 0.15, "Time of the voltage reversal", CHOSEN),
}

_DEFAULTS = {name: info.default for name, info in _PARAMS.items()}
_REVERSED = steady_state(**dict(_DEFAULTS, V=-_DEFAULTS["V"]))

ENTRY = register(ModelEntry(
    name="geared_drive",
    description=("The seed's DC motor driving a load inertia through a gear with "
                 "backlash, against viscous friction and a constant load torque; the "
                 "supply reverses, the teeth cross the dead band."),
    parameters=_PARAMS,
    variants={"acausal": build_acausal, "equation": _equation},
    outputs={"acausal": {"w_m": "rotor.w", "i": "inductor.i", "w_L": "load.w",
                         "phi": "backlash.phi", "tau": "backlash.tau"},
             "equation": {"w_m": "w_m", "i": "i", "w_L": "w_L", "phi": "phi",
                          "tau": "tau"}},
    output_units={"w_m": "rad/s", "i": "A", "w_L": "rad/s", "phi": "rad", "tau": "N*m"},
    experiment=Experiment(t_stop=0.3, rtol=1e-8, atol=1e-10),
    expected={"w_m": _REVERSED["w_m"], "i": _REVERSED["i"], "w_L": _REVERSED["w_L"],
              "phi": _REVERSED["phi"], "tau": _REVERSED["tau"]},
    expected_tolerance=1e-5,
    variant_tolerance=1e-6,
    tags=("seed", "motor", "electromechanical", "gear", "backlash", "events"),
))
