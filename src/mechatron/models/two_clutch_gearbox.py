"""A two-clutch gearbox: a DC motor drives a load through one of two gear stages, each
behind its own disc clutch; at ``t_shift`` the first clutch opens while the second closes
(a power-shift from gear 1 to gear 2, as in a dual-clutch transmission).

Parts (library): the motor ``machines.DCPermanentMagnet`` on a constant supply ``V``;
two ``rotational.Clutch`` (stuck/slip, MSL's) between the motor shaft and the gear
stages ``rotational.IdealGear`` (ratios ``r1 > r2``, motor speed over load speed); both
stages drive the load (``Inertia`` ``J_L`` with the angle as a state, MSL's ``phi``,
and a viscous drag ``D_L``). The clutch forces are signals: clutch 1 pressed with ``F_n``
until ``t_shift``, released linearly over ``t_overlap`` while clutch 2 is pressed the same
way (``blocks.Ramp``).

With a clutch locked and the other open, the drive is a DC motor on a load seen through
the ratio ``r``; in steady state (both shafts at constant speed)::

    w_m = (k V / R) / (k^2 / R + B_v + D_L / r^2),   w_L = w_m / r,   i = (V - k w_m) / R

During the overlap clutch 2 slips (dissipating ``tau w_slip``) until the motor has been
pulled down to the new ratio, then locks; clutch 1 opens. Limitations: rigid shafts,
lossless gears (no tooth friction), a clutch's torque limit ``peak mu n R F_n`` must exceed
the motor's (it does for the defaults).
"""

from __future__ import annotations

import mechatron as mt
from mechatron.library import blocks
from mechatron.library import electrical as el
from mechatron.library import machines
from mechatron.library import rotational as rot
from mechatron.models.entry import Experiment, ModelEntry, ParameterInfo
from mechatron.models.registry import register

__all__ = ["build_acausal", "steady_state", "ENTRY"]

CHOSEN = "chosen: a 24 V drive with a two-speed power-shift gearbox"


def build_acausal(V, R, L, k, J, B_v, r1, r2, J_L, D_L, F_n, mu, peak, R_c, t_shift,
                  t_overlap):
    """The gearbox as a network of library parts."""
    s = mt.System("two_clutch_gearbox", doc="DC motor, two clutches, two gears, load")
    s.add("supply", el.DCVoltageSource(V=V))
    s.add("ground", el.ElectricalReference())
    motor = s.add("motor", machines.DCPermanentMagnet(R=R, L=L, k=k, J=J, B_v=B_v))
    s.add("housing", rot.RotationalReference())
    c1 = s.add("clutch1", rot.Clutch(mu=mu, peak=peak, R=R_c, n=2))
    c2 = s.add("clutch2", rot.Clutch(mu=mu, peak=peak, R=R_c, n=2))
    g1 = s.add("gear1", rot.IdealGear(ratio=r1))
    g2 = s.add("gear2", rot.IdealGear(ratio=r2))
    load = s.add("load", rot.Inertia(J=J_L, use_phi=True))
    drag = s.add("drag", rot.RotationalDamper(D=D_L))
    # clutch 1: F_n, released from t_shift over t_overlap; clutch 2: the complement
    s.add("press1", blocks.Ramp(initial=F_n, slope=-F_n / t_overlap, start=t_shift,
                                duration=t_overlap))
    s.add("press2", blocks.Ramp(initial=0.0, slope=F_n / t_overlap, start=t_shift,
                                duration=t_overlap))
    s.connect(s.supply.p, motor.p)
    s.connect(s.supply.n, motor.n, s.ground.port)
    s.connect(motor.flange, c1.A, c2.A)
    s.connect(c1.B, g1.A)
    s.connect(c2.B, g2.A)
    s.connect(g1.B, g2.B, load.port, drag.A)
    s.connect(motor.support, drag.B, s.housing.port)
    s.connect(s.press1.y, c1.f_n)
    s.connect(s.press2.y, c2.f_n)
    return s


def steady_state(V, R, k, B_v, D_L, ratio, **_):
    """Motor speed, load speed and current with one gear of ``ratio`` engaged."""
    w_m = (k * V / R) / (k ** 2 / R + B_v + D_L / ratio ** 2)
    return {"w_m": w_m, "w_L": w_m / ratio, "i": (V - k * w_m) / R}


_PARAMS = {
    "V": ParameterInfo("V", 24.0, "Supply voltage", CHOSEN),
    "R": ParameterInfo("Ohm", 0.5, "Armature resistance", CHOSEN),
    "L": ParameterInfo("H", 1e-3, "Armature inductance", CHOSEN),
    "k": ParameterInfo("V*s/rad", 0.05, "Motor constant", CHOSEN),
    "J": ParameterInfo("kg*m^2", 1e-4, "Rotor and input shaft inertia", CHOSEN),
    "B_v": ParameterInfo("N*m*s/rad", 1e-5, "Motor viscous friction", CHOSEN),
    "r1": ParameterInfo("1", 3.0, "Gear 1 ratio (motor over load speed)", CHOSEN),
    "r2": ParameterInfo("1", 1.5, "Gear 2 ratio", CHOSEN),
    "J_L": ParameterInfo("kg*m^2", 0.002, "Load inertia", CHOSEN),
    "D_L": ParameterInfo("N*m*s/rad", 0.002, "Load drag coefficient", CHOSEN),
    "F_n": ParameterInfo("N", 200.0, "Clutch normal force when pressed", CHOSEN),
    "mu": ParameterInfo("1", 0.3, "Clutch friction coefficient", CHOSEN),
    "peak": ParameterInfo("1", 1.2, "Static over kinetic friction coefficient (> 1: the "
                          "slip starts decisively at breakaway)", CHOSEN),
    "R_c": ParameterInfo("m", 0.05, "Clutch effective radius (two surfaces)", CHOSEN),
    "t_shift": ParameterInfo("s", 1.0, "Start of the shift", CHOSEN),
    "t_overlap": ParameterInfo("s", 0.1, "Duration of the clutch overlap", CHOSEN),
}

_DEFAULTS = {name: info.default for name, info in _PARAMS.items()}
_FINAL = steady_state(**_DEFAULTS, ratio=_DEFAULTS["r2"])

ENTRY = register(ModelEntry(
    name="two_clutch_gearbox",
    description=("DC motor, two stuck/slip disc clutches and two gear stages driving one "
                 "load; a power-shift from gear 1 to gear 2 with overlapping clutches."),
    parameters=_PARAMS,
    variants={"acausal": build_acausal},
    outputs={"acausal": {"w_m": "motor.inertia.w", "w_L": "load.w",
                         "i": "motor.inductor.i", "phi_L": "load.phi"}},
    output_units={"w_m": "rad/s", "w_L": "rad/s", "i": "A", "phi_L": "rad"},
    experiment=Experiment(t_stop=4.0, rtol=1e-9, atol=1e-11),
    expected={key: _FINAL[key] for key in ("w_m", "w_L", "i")},
    expected_tolerance=1e-5,
    variant_tolerance=1e-6,
    tags=("motor", "gear", "clutch", "stick-slip", "events", "issue 18"),
))
