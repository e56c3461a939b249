"""Two axes of a positioning table, each the seed's DC motor driving a load: the same
motor used twice, built from subsystems three levels deep.

Each axis (:class:`MotorAxis`) is a subsystem with its own ports (armature pins ``p``,
``n`` and the support flange ``support``) holding a
:class:`~mechatron.library.machines.DCPermanentMagnet` (itself a subsystem
of resistor, inductor, EMF, rotor inertia and bearing friction) rigidly coupled to a load
inertia with viscous load friction. Its parameters are the axis's own and are passed on
to the motor and the load. The table applies a voltage step to each axis (``V_x``,
``V_y``).

Per axis, with ``J_t = J + J_load`` and ``B_t = B + D_load``::

    L di/dt = V - R i - k w,      J_t dw/dt = k i - B_t w

so the final speed is ``k V / (R B_t + k^2)`` and the final current ``B_t V / (R B_t +
k^2)``. The rotor and the load are two inertias on one shaft: index reduction makes one
of them the state.

Variants: ``acausal`` (the subsystems), ``ode`` (the equations above, per axis) and
``inputs`` (the subsystems driven from outside: the armature voltages ``V_x``, ``V_y``
and the load torques ``tau_x``, ``tau_y``, opposing each load's rotation, are the model's
external inputs; their start values are the voltage steps and no load, so by default it is
the ``acausal`` table). With a load torque ``T`` the final speed of an axis is
``(k V - R T) / (R B_t + k^2)``.
"""

from __future__ import annotations

import mechatron as mt
from mechatron.library import electrical as el
from mechatron.library import machines
from mechatron.library import rotational as rot
from mechatron.library.electrical.interfaces import Pin
from mechatron.library.rotational.interfaces import Flange
from mechatron.models.entry import Experiment, ModelEntry, ParameterInfo
from mechatron.models.registry import register

__all__ = ["AxisConstants", "MotorAxis", "TwoAxisTable", "TwoAxisODE", "ENTRY"]

SEED = "seed table 6-1, calculated"
CHOSEN = "chosen: a light load per axis"


class AxisConstants(mt.Component, partial=True):
    """The constants of one axis: the seed motor and its load."""

    R = mt.Parameter("Ohm", default=7.1, min=0, doc="Armature resistance")
    L = mt.Parameter("H", default=3.408e-4, min=0, doc="Armature inductance")
    k = mt.Parameter("V*s/rad", default=0.151, min=0, doc="Motor constant")
    J = mt.Parameter("kg*m^2", default=4.8e-6, min=0, doc="Rotor inertia")
    B = mt.Parameter("N*m*s/rad", default=1.236e-4, min=0, doc="Bearing friction")
    J_load = mt.Parameter("kg*m^2", default=1e-5, min=0, doc="Load inertia")
    D_load = mt.Parameter("N*m*s/rad", default=5e-5, min=0, doc="Load viscous friction")


class MotorAxis(AxisConstants):
    """One axis: a permanent-magnet DC motor rigidly driving a load inertia with viscous
    load friction; the motor's constants are the axis's parameters."""

    p = Pin(doc="Positive armature terminal")
    n = Pin(doc="Negative armature terminal")
    support = Flange(doc="Frame of the axis")

    # inherited parameters, passed on (a class body sees only its own names)
    c = AxisConstants
    motor = machines.DCPermanentMagnet(R=c.R, L=c.L, k=c.k, J=c.J, B_v=c.B)
    load = rot.Inertia(J=c.J_load)
    load_friction = rot.RotationalDamper(D=c.D_load)
    del c

    def equations(self):
        return [mt.connect(self.p, self.motor.p), mt.connect(self.motor.n, self.n),
                mt.connect(self.motor.flange, self.load.port, self.load_friction.A),
                mt.connect(self.motor.support, self.load_friction.B, self.support)]


class TwoAxisTable(mt.Component):
    """Two identical axes under voltage steps ``V_x`` and ``V_y``."""

    supply_x = el.DCVoltageSource(V=19.2)
    supply_y = el.DCVoltageSource(V=12.0)
    x = MotorAxis()
    y = MotorAxis()
    ground = el.ElectricalReference()
    frame = rot.RotationalReference()

    def equations(self):
        return [mt.connect(self.supply_x.p, self.x.p), mt.connect(self.supply_y.p, self.y.p),
                mt.connect(self.supply_x.n, self.supply_y.n, self.x.n, self.y.n,
                           self.ground.port),
                mt.connect(self.x.support, self.y.support, self.frame.port)]


class TwoAxisODE(AxisConstants):
    """Both axes as equations (both with the same constants)."""

    V_x = mt.Parameter("V", default=19.2, doc="Supply voltage of axis x")
    V_y = mt.Parameter("V", default=12.0, doc="Supply voltage of axis y")
    i_x = mt.Variable("A", start=0.0, doc="Armature current, axis x")
    w_x = mt.Variable("rad/s", start=0.0, doc="Speed, axis x")
    i_y = mt.Variable("A", start=0.0, doc="Armature current, axis y")
    w_y = mt.Variable("rad/s", start=0.0, doc="Speed, axis y")

    def equations(self):
        J_t, B_t = self.J + self.J_load, self.B + self.D_load
        out = []
        for V, i, w in ((self.V_x, self.i_x, self.w_x), (self.V_y, self.i_y, self.w_y)):
            out += [self.L * mt.der(i) == V - self.R * i - self.k * w,
                    J_t * mt.der(w) == self.k * i - B_t * w]
        return out


def _acausal(V_x, V_y, R, L, k, J, B, J_load, D_load):
    m = TwoAxisTable(doc="Two-axis table from subsystems")
    m._name = "two_axis"
    m.supply_x._values["V"] = V_x
    m.supply_y._values["V"] = V_y
    for axis in (m.x, m.y):
        axis._values.update(R=R, L=L, k=k, J=J, B=B, J_load=J_load, D_load=D_load)
    return m


def _inputs(V_x, V_y, R, L, k, J, B, J_load, D_load):
    """The table driven from outside: per axis a controlled voltage source on the
    armature and a torque source on the load shaft (reaction ``-tau`` on the load)."""
    m = mt.System("two_axis", doc="Two-axis table with external inputs")
    ground = m.add("ground", el.ElectricalReference())
    frame = m.add("frame", rot.RotationalReference())
    for ax, V in (("x", V_x), ("y", V_y)):
        v = m.input(f"V_{ax}", unit="V", start=V, doc=f"Armature voltage, axis {ax}")
        tau = m.input(f"tau_{ax}", unit="N*m", start=0.0,
                      doc=f"Load torque, axis {ax}, opposing rotation")
        supply = m.add(f"supply_{ax}", el.ControlledVoltageSource())
        axis = m.add(ax, MotorAxis(R=R, L=L, k=k, J=J, B=B, J_load=J_load, D_load=D_load))
        brake = m.add(f"load_{ax}", rot.IdealTorqueSource())
        m.connect(v, supply.u)
        m.connect(tau, brake.tau_in)
        m.connect(supply.p, axis.p)
        m.connect(supply.n, axis.n, ground.port)
        m.connect(axis.load.port, brake.B)
        m.connect(axis.support, brake.A, frame.port)
    return m


def _ode(**values):
    m = TwoAxisODE(**values)
    m._name = "two_axis"
    return m


def _final(V, R=7.1, k=0.151, B=1.236e-4, D_load=5e-5):
    B_t = B + D_load
    return k * V / (R * B_t + k * k), B_t * V / (R * B_t + k * k)


ENTRY = register(ModelEntry(
    name="two_axis",
    description=("Two axes of a positioning table, each the seed's DC motor (one "
                 "subsystem, used twice) rigidly driving a load inertia with friction; "
                 "voltage steps per axis."),
    parameters={
        "V_x": ParameterInfo("V", 19.2, "Supply voltage step of axis x", "seed, test bench"),
        "V_y": ParameterInfo("V", 12.0, "Supply voltage step of axis y", CHOSEN),
        "R": ParameterInfo("Ohm", 7.1, "Armature resistance", SEED),
        "L": ParameterInfo("H", 3.408e-4, "Armature inductance", SEED),
        "k": ParameterInfo("V*s/rad", 0.151, "Motor constant", SEED),
        "J": ParameterInfo("kg*m^2", 4.8e-6, "Rotor inertia", SEED),
        "B": ParameterInfo("N*m*s/rad", 1.236e-4, "Bearing friction", SEED),
        "J_load": ParameterInfo("kg*m^2", 1e-5, "Load inertia per axis", CHOSEN),
        "D_load": ParameterInfo("N*m*s/rad", 5e-5, "Load viscous friction per axis",
                                CHOSEN),
    },
    variants={"acausal": _acausal, "ode": _ode, "inputs": _inputs},
    outputs={"acausal": {"w_x": "x.load.w", "w_y": "y.load.w",
                         "i_x": "x.motor.inductor.i", "i_y": "y.motor.inductor.i"},
             "inputs": {"w_x": "x.load.w", "w_y": "y.load.w",
                        "i_x": "x.motor.inductor.i", "i_y": "y.motor.inductor.i"},
             "ode": {"w_x": "w_x", "w_y": "w_y", "i_x": "i_x", "i_y": "i_y"}},
    output_units={"w_x": "rad/s", "w_y": "rad/s", "i_x": "A", "i_y": "A"},
    experiment=Experiment(t_stop=0.3, rtol=1e-8, atol=1e-10),
    expected={"w_x": _final(19.2)[0], "w_y": _final(12.0)[0],
              "i_x": _final(19.2)[1], "i_y": _final(12.0)[1]},
    expected_tolerance=1e-5,
    variant_tolerance=1e-8,
    tags=("seed", "electromechanical", "motor", "subsystems"),
))
