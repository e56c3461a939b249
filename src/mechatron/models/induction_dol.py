"""Direct-on-line start of a squirrel-cage induction motor (MSL's example
``Electrical.Machines.Examples.InductionMachines.IMC_DOL``, with the library's
``machines.InductionMachine`` and MSL's data record).

A three-phase 50 Hz supply of ``V`` RMS per phase winding is switched onto the motor at
rest; it accelerates its rotor and a load inertia ``J_L`` against a fan load (torque
``T_nom (w / w_nom)^2``) to the speed where the motor's torque meets the load's. The
supply is star-connected with a grounded neutral (MSL's example feeds a delta winding the
same 100 V per winding).

Steady state (:func:`steady_state`, from the T-equivalent circuit alone: RMS phasors,
slip ``s``)::

    Z_r = R_r / s + j X_r_sigma,   Z = R_s + j X_s_sigma + (j X_m || Z_r)
    T(s) = 3 |I_r|^2 R_r / s / (w_s / p) = T_nom (w / w_nom)^2,   w = (1 - s) w_s / p

which with MSL's data is its nominal point, 161.4 N*m at 1440.45 rpm.
"""

from __future__ import annotations

import math

from scipy.optimize import brentq

import mechatron as mt
from mechatron.library import electrical as el
from mechatron.library import machines
from mechatron.library import rotational as rot
from mechatron.models.entry import Experiment, ModelEntry, ParameterInfo
from mechatron.models.registry import register

__all__ = ["build_acausal", "steady_state", "ENTRY"]

MSL = "MSL 4 IM_SquirrelCageData / IMC_DOL"
_K = math.sqrt(1 - 0.0667)


def build_acausal(V, f, p, R_s, R_r, L_s_sigma, L_r_sigma, L_m, J_r, J_L, T_nom, w_nom):
    """The start-up as a network of library parts."""
    s = mt.System("induction_dol", doc="Induction motor started direct on line, fan load")
    s.add("ground", el.ElectricalReference())
    s.add("fixed", rot.RotationalReference())
    im = s.add("motor", machines.InductionMachine(p=p, R_s=R_s, R_r=R_r,
                                                  L_s_sigma=L_s_sigma,
                                                  L_r_sigma=L_r_sigma, L_m=L_m, J_r=J_r))
    for k, name in enumerate("abc"):
        src = s.add(f"v_{name}", el.ACVoltageSource(V_amp=math.sqrt(2) * V, f=f,
                                                    phase=math.pi / 2 - k * 2 * math.pi / 3))
        s.connect(src.p, getattr(im, name))
        s.connect(src.n, s.ground.port)
    load = s.add("load", rot.Inertia(J=J_L, w=0.0))
    fan = s.add("fan", rot.FanLoad(T_nom=T_nom, w_nom=w_nom))
    s.connect(im.flange, load.port, fan.A)
    s.connect(im.support, fan.B, s.fixed.port)
    return s


def steady_state(V, f, p, R_s, R_r, L_s_sigma, L_r_sigma, L_m, T_nom, w_nom, **_):
    """Speed, torque and RMS stator current where the motor meets the fan load."""
    w_s = 2 * math.pi * f
    X_s, X_r, X_m = w_s * L_s_sigma, w_s * L_r_sigma, w_s * L_m

    def torque_current(s):
        z_r = R_r / s + 1j * X_r
        z = R_s + 1j * X_s + 1j * X_m * z_r / (1j * X_m + z_r)
        i_s = V / z
        i_r = i_s * 1j * X_m / (1j * X_m + z_r)
        return 3 * abs(i_r) ** 2 * R_r / s / (w_s / p), abs(i_s)

    def balance(s):
        w = (1 - s) * w_s / p
        return torque_current(s)[0] - T_nom * (w / w_nom) ** 2

    s = brentq(balance, 1e-6, 0.2, xtol=1e-15, rtol=1e-15)
    T, I = torque_current(s)
    return {"w": (1 - s) * w_s / p, "T": T, "I_rms": I}


_PARAMS = {
    "V": ParameterInfo("V", 100.0, "Supply voltage per phase winding, RMS", MSL),
    "f": ParameterInfo("Hz", 50.0, "Supply frequency", MSL),
    "p": ParameterInfo("1", 2.0, "Pole pairs", MSL),
    "R_s": ParameterInfo("Ohm", 0.03, "Stator resistance per phase", MSL),
    "R_r": ParameterInfo("Ohm", 0.04, "Rotor resistance (stator side)", MSL),
    "L_s_sigma": ParameterInfo("H", 3 * (1 - _K) / (2 * math.pi * 50), "Stator stray "
                               "inductance", MSL),
    "L_r_sigma": ParameterInfo("H", 3 * (1 - _K) / (2 * math.pi * 50), "Rotor stray "
                               "inductance", MSL),
    "L_m": ParameterInfo("H", 3 * _K / (2 * math.pi * 50), "Main-field inductance", MSL),
    "J_r": ParameterInfo("kg*m^2", 0.29, "Rotor inertia", MSL),
    "J_L": ParameterInfo("kg*m^2", 0.29, "Load inertia", MSL),
    "T_nom": ParameterInfo("N*m", 161.4, "Fan torque at w_nom", MSL),
    "w_nom": ParameterInfo("rad/s", 1440.45 * 2 * math.pi / 60, "Nominal load speed "
                           "(1440.45 rpm)", MSL),
}

_FINAL = steady_state(**{k: v.default for k, v in _PARAMS.items()})

ENTRY = register(ModelEntry(
    name="induction_dol",
    description=("Squirrel-cage induction motor (MSL's data) started direct on line "
                 "against a fan load, as MSL's IMC_DOL."),
    parameters=_PARAMS,
    variants={"acausal": build_acausal},
    outputs={"acausal": {"w": "load.w", "T": "motor.airgap.T"}},
    output_units={"w": "rad/s", "T": "N*m"},
    experiment=Experiment(t_stop=1.5, rtol=1e-9, atol=1e-9),
    expected={"w": _FINAL["w"], "T": _FINAL["T"]},
    # the torque ripples at twice the supply frequency until the start transient has
    # decayed (1.5 s: below 1e-5 of its value)
    expected_tolerance=1e-5,
    variant_tolerance=1e-6,
    tags=("motor", "induction", "AC", "electromechanical", "MSL example", "issue 18"),
))
