"""Heat ports of the machines (``use_heat_port=True``): the losses leave at the port, so
over a start-up the electrical energy in equals the mechanical energy out, plus the heat
taken by a heat capacitor on the port, plus the change of the magnetic and kinetic energy
stored in the machine. Without the option there is no port (today's models unchanged)."""

import math

import numpy as np
import pytest

import mechatron as mt
from mechatron.library import electrical as el
from mechatron.library import machines
from mechatron.library import rotational as rot
from mechatron.library import thermal as th

C_TH = 100.0        # J/K of the heat capacitor on the port
T0 = 293.15


def rig(machine, supplies, T_load=0.0, D_load=0.0, J_load=0.0):
    """``machine`` fed at its pins by ``supplies`` (pin name -> voltage source), its heat
    port on a heat capacitor, its shaft on a damper and a constant torque (and a load
    inertia)."""
    m = mt.System("rig")
    m.add("ground", el.ElectricalReference())
    m.add("fixed", rot.RotationalReference())
    mm = m.add("m", machine)
    for pin, src in supplies.items():
        s = m.add(f"v_{pin}", src)
        m.connect(s.p, getattr(mm, pin))
        m.connect(s.n, m.ground.port)
    for pin in ("n", "ne"):                 # the DC machines' return pins
        if pin in mm.ports:
            m.connect(mm.ports[pin], m.ground.port)
    cap = m.add("cap", th.HeatCapacitor(C=C_TH, T=T0))
    m.connect(mm.heat_port, cap.port)
    damper = m.add("damper", rot.RotationalDamper(D=D_load))
    torque = m.add("torque", rot.ConstantTorque(T=-T_load))
    m.connect(mm.flange, damper.A, torque.A)
    if J_load:
        m.connect(mm.flange, m.add("load", rot.Inertia(J=J_load, w=0.0)).port)
    m.connect(mm.support, damper.B, torque.B, m.fixed.port)
    return m


def three_phase(V_amp, f=50.0):
    return {k: el.ACVoltageSource(V_amp=V_amp, f=f, phase=math.pi / 2 - n * 2 * math.pi / 3)
            for n, k in enumerate("abc")}


def dc_pm():
    return rig(machines.DCPermanentMagnet(use_heat_port=True),
               {"p": el.DCVoltageSource(V=19.2)}, D_load=1e-4), 0.05, \
        lambda r: 0.5 * 3.408e-4 * r["m.inductor.i"] ** 2 + 0.5 * 4.8e-6 * r["m.inertia.w"] ** 2


def dc_excited():
    mach = machines.DCElectricalExcited(use_heat_port=True, B_v=0.5)
    return rig(mach, {"p": el.DCVoltageSource(V=50.0), "pe": el.DCVoltageSource(V=100.0)},
               D_load=2.0), 0.3, \
        lambda r: 0.5 * 0.0015 * r["m.l_a.i"] ** 2 + 0.5 * 1.0 * r["m.l_e.i"] ** 2 \
        + 0.5 * 0.15 * r["m.inertia.w"] ** 2


def dc_series():
    mach = machines.DCSeries(use_heat_port=True, B_v=0.5)
    return rig(mach, {"p": el.DCVoltageSource(V=50.0)}, D_load=2.0), 0.3, \
        lambda r: 0.5 * 0.002 * r["m.l_a.i"] ** 2 + 0.5 * 0.15 * r["m.inertia.w"] ** 2


def dc_shunt():
    mach = machines.DCShunt(use_heat_port=True, B_v=0.5)
    return rig(mach, {"p": el.DCVoltageSource(V=50.0)}, D_load=2.0), 0.3, \
        lambda r: 0.5 * 0.0015 * r["m.l_a.i"] ** 2 + 0.5 * 1.0 * r["m.l_e.i"] ** 2 \
        + 0.5 * 0.15 * r["m.inertia.w"] ** 2


L_PM = 0.4 / (2 * math.pi * 50)


def pmsm(emf):
    def build():
        mach = machines.PMSM(use_heat_port=True, emf=emf, B_v=0.5)
        # the shaft runs up with the supply at a low frequency (0.5 Hz): a synchronous
        # start, losses in R_s and the bearings
        model = rig(mach, three_phase(10.0, f=0.5), D_load=1.0)
        if emf == "sinusoidal":
            def stored(r):
                return 0.75 * L_PM * (r["m.airgap.i_d"] ** 2 + r["m.airgap.i_q"] ** 2) \
                    + 0.5 * 0.29 * r["m.inertia.w"] ** 2
        else:
            def stored(r):
                i = [r[f"m.airgap.i_{k}"] for k in "abc"]
                return 0.5 * L_PM * sum(x ** 2 for x in i) + 0.5 * 0.29 * r["m.inertia.w"] ** 2
        return model, 0.5, stored
    return build


def induction():
    mach = machines.InductionMachine(use_heat_port=True, B_v=0.05)

    def stored(r):
        a = "m.airgap."
        psi_i = sum(r[a + f"psi_{x}_{ab}"] * r[a + f"i_{x}_{ab}"]
                    for x in "sr" for ab in ("alpha", "beta"))
        return 0.75 * psi_i + 0.5 * 0.29 * r["m.inertia.w"] ** 2
    return rig(mach, three_phase(math.sqrt(2) * 100.0), D_load=0.5), 0.3, stored


CASES = {"DCPermanentMagnet": dc_pm, "DCElectricalExcited": dc_excited,
         "DCSeries": dc_series, "DCShunt": dc_shunt, "PMSM": pmsm("sinusoidal"),
         "TrapezoidalPMSM": pmsm("trapezoidal"), "InductionMachine": induction}


@pytest.mark.parametrize("name", CASES)
def test_energy_balance_through_the_heat_port(name):
    model, t_stop, stored = CASES[name]()
    t = np.linspace(0.0, t_stop, 40001)
    r = mt.simulate(model, t_stop, t_out=t, rtol=1e-10, atol=1e-10)
    pins = [k for k in ("p", "pe", "a", "b", "c") if f"v_{k}.v" in r.names]
    p_el = sum(r[f"v_{k}.v"] * -r[f"v_{k}.i"] for k in pins)      # out of the sources
    w = r["m.flange.w"] - r["m.support.w"]
    p_mech = -r["m.flange.tau"] * w                               # delivered at the shaft
    e_el = np.trapezoid(p_el, t)
    e_mech = np.trapezoid(p_mech, t)
    heat = C_TH * (r.final("cap.T") - T0)
    e_stored = stored(r)
    assert heat > 0.005 * e_el and e_mech > 0.005 * e_el     # every term is exercised
    assert e_el == pytest.approx(e_mech + heat + e_stored[-1] - e_stored[0], rel=2e-5)
    # the heat flow is the losses at every instant: never into the machine
    assert np.all(r["m.heat_port.Q"] <= 1e-9)


def test_without_the_option_there_is_no_port():
    assert not hasattr(machines.DCPermanentMagnet(), "heat_port")
    assert type(machines.DCShunt(use_heat_port=True)) is machines.DCShuntWithHeatPort
    assert type(machines.PMSM(emf="trapezoidal", use_heat_port=True)) is \
        machines.TrapezoidalPMSMWithHeatPort
    assert "heat_port" in machines.InductionMachine(use_heat_port=True).ports
