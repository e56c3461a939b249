"""A battery-fed BLDC drive: the database's six-step BLDC drive (``bldc_motor``) on a
lithium-ion battery instead of an ideal supply, its motor the library's
``machines.PMSM(emf="trapezoidal")``.

The battery (``electrical.Battery``: ``n_s`` cells with the library's Li-ion open-circuit
voltage over the state of charge, series resistance ``R0``, one RC branch) feeds the DC
link through an averaged buck chopper (:class:`AveragedChopper`, duty ``d`` from the PI
speed controller); the link feeds the three MOSFET legs that the Hall sectors commutate
(the ``bldc_motor`` parts: :class:`~mechatron.models.bldc.InverterLeg`,
:class:`~mechatron.models.bldc.HallSensors`,
:class:`~mechatron.models.bldc.SixStepCommutation`,
:class:`~mechatron.models.bldc.SpeedPI`).

Known facts checked by the tests: the speed settles at the reference (integral action)
while the battery sags under load; the charge drawn equals the fall of the state of
charge times the capacity; energy: chemical energy released = battery losses (``R0``,
``R1``) + the energy stored in its RC branch + everything the drive takes (as in
``bldc_motor``).
"""

from __future__ import annotations

import math

import mechatron as mt
from mechatron.library import blocks
from mechatron.library import electrical as el
from mechatron.library import machines
from mechatron.library import rotational as rot
from mechatron.library.electrical.interfaces import TwoPort
from mechatron.models.bldc import (F_NOM, HallSensors, InverterLeg, SixStepCommutation,
                                   SpeedPI)
from mechatron.models.entry import Experiment, ModelEntry, ParameterInfo
from mechatron.models.registry import register

__all__ = ["AveragedChopper", "build_acausal", "ENTRY"]

CHOSEN = "chosen: a 6-cell Li-ion pack (about 22 V) on the bldc_motor drive"
SAME = "as bldc_motor"


class AveragedChopper(TwoPort):
    """Averaged buck chopper (a DC transformer of ratio ``d``): port 1 the source side,
    port 2 the load side, lossless::

        v2 == d v1,   i1 == -d i2

    (``i1``, ``i2`` the currents into ``p1``, ``p2``), so ``v1 i1 + v2 i2 == 0``. It is
    the average over a switching period of a buck converter in continuous conduction.
    """

    d = mt.Input("1", doc="Duty cycle (0..1)")

    def equations(self):
        return [self.v2 == self.d * self.v1, self.i1 == -self.d * self.i2]


def build_acausal(n_s, Q, R0, R1, C1, SOC0, R, L, k_e, J, B, T_load, w_ref, K_p, K_i, K_aw,
                  d_max, R_on, G_off, V_f, R_d):
    """The drive as a network of library parts and the bldc_motor's components."""
    m = mt.System("battery_bldc", doc="Li-ion battery, averaged chopper, BLDC drive")
    ground = m.add("ground", el.ElectricalReference())
    battery = m.add("battery", el.Battery(n_s=n_s, Q=Q, R0=R0, R1=R1, C1=C1, SOC=SOC0))
    chopper = m.add("chopper", AveragedChopper())
    full_on = m.add("pwm_on", blocks.Constant(value=1.0))
    commutation = m.add("commutation", SixStepCommutation())
    controller = m.add("controller", SpeedPI(w_ref=w_ref, K_p=K_p, K_i=K_i, K_aw=K_aw,
                                             d_max=d_max))
    motor = m.add("motor", machines.PMSM(
        emf="trapezoidal", p=1.0, R_s=R, L_s_sigma=L, L_md=0.0, L_mq=0.0, f_s_nom=F_NOM,
        V_s_open_circuit=k_e * 2 * math.pi * F_NOM / math.sqrt(2), J_r=J, B_v=B))
    hall = m.add("hall", HallSensors())
    load = m.add("load", rot.ConstantTorque(T=-T_load))
    tacho = m.add("tacho", rot.AngularVelocitySensor())
    housing = m.add("housing", rot.RotationalReference())
    m.connect(battery.p, chopper.p1)
    m.connect(battery.n, chopper.n1, chopper.n2, ground.port)
    for k in "abc":
        leg = m.add(f"leg_{k}", InverterLeg(R_on=R_on, G_off=G_off, V_f=V_f, R_d=R_d))
        m.connect(chopper.p2, leg.dc_p)
        m.connect(leg.dc_n, chopper.n2)
        m.connect(leg.out, getattr(motor, k))
        m.connect(getattr(commutation, f"g_{k}h"), leg.cmd_h)
        m.connect(getattr(commutation, f"g_{k}l"), leg.cmd_l)
    m.connect(motor.flange, load.A, hall.A, tacho.A)
    m.connect(motor.support, load.B, hall.B, tacho.B, housing.port)
    m.connect(hall.sector, commutation.sector)
    m.connect(tacho.W, controller.w)
    m.connect(controller.d, chopper.d)
    m.connect(full_on.y, commutation.pwm)
    return m


_PARAMS = {
    "n_s": ParameterInfo("1", 6.0, "Cells in series", CHOSEN),
    "Q": ParameterInfo("A*h", 2.5, "Capacity", CHOSEN),
    "R0": ParameterInfo("Ohm", 0.1, "Series resistance of the pack", CHOSEN),
    "R1": ParameterInfo("Ohm", 0.06, "RC branch resistance of the pack", CHOSEN),
    "C1": ParameterInfo("F", 500.0, "RC branch capacitance of the pack", CHOSEN),
    "SOC0": ParameterInfo("1", 0.8, "State of charge at the start", CHOSEN),
    "R": ParameterInfo("Ohm", 0.5, "Phase resistance", SAME),
    "L": ParameterInfo("H", 1e-3, "Phase inductance", SAME),
    "k_e": ParameterInfo("V*s/rad", 0.05, "Back-EMF constant per phase", SAME),
    "J": ParameterInfo("kg*m^2", 1e-4, "Rotor and load inertia", SAME),
    "B": ParameterInfo("N*m*s/rad", 1e-5, "Viscous friction", SAME),
    "T_load": ParameterInfo("N*m", 0.05, "Constant load torque", SAME),
    "w_ref": ParameterInfo("rad/s", 150.0, "Speed reference", SAME),
    "K_p": ParameterInfo("s/rad", 0.005, "Speed PI proportional gain", SAME),
    "K_i": ParameterInfo("1/rad", 0.5, "Speed PI integral gain", SAME),
    "K_aw": ParameterInfo("1/s", 50.0, "Anti-windup gain", SAME),
    "d_max": ParameterInfo("1", 0.95, "Largest duty cycle", SAME),
    "R_on": ParameterInfo("Ohm", 0.01, "MOSFET on-resistance", SAME),
    "G_off": ParameterInfo("S", 1e-3, "MOSFET off-conductance", SAME),
    "V_f": ParameterInfo("V", 0.8, "Body-diode forward voltage", SAME),
    "R_d": ParameterInfo("Ohm", 0.01, "Body-diode on-resistance", SAME),
}

ENTRY = register(ModelEntry(
    name="battery_bldc",
    description=("BLDC drive on a Li-ion battery: Battery (OCV over SOC, R0, RC), averaged "
                 "chopper, six-MOSFET inverter, Hall sensors, six-step commutation, PI "
                 "speed control, the library's trapezoidal PMSM."),
    parameters=_PARAMS,
    variants={"acausal": build_acausal},
    outputs={"acausal": {"w": "motor.inertia.w", "SOC": "battery.SOC", "v_bat": "battery.v",
                         "i_bat": "battery.i", "d": "controller.d"}},
    output_units={"w": "rad/s", "SOC": "1", "v_bat": "V", "i_bat": "A", "d": "1"},
    experiment=Experiment(t_stop=0.15, rtol=1e-8, atol=1e-10),
    expected={"w": 150.0},
    # the speed is the reference up to the commutation ripple (< 0.1 %), as bldc_motor's
    expected_tolerance=2e-3,
    variant_tolerance=1e-6,
    tags=("motor", "BLDC", "battery", "power electronics", "control", "events",
          "issue 18"),
))
