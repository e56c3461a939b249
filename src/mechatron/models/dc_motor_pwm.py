"""The seed's DC motor fed by a 10 kHz PWM (signal blocks driving a controlled voltage
source), beside its averaged drive.

``switched``: a PWM block of period ``1/f_pwm`` latches the duty each period and switches
the armature voltage between 0 and ``V``: two switching events per period, located by the
integrator, no Python per event. ``averaged``: the same motor fed by ``duty V``. An
integrator block logs the charge ``q = integral of i``, so the mean current over a run is
``q(T)/T``. The averaged drive's final speed is ``k duty V / (R B + k^2)``; the switched
drive's mean current equals the averaged one's to within the ripple (checked to 1% in
tests/solvers/test_hybrid_pwm.py). ``inputs``: the switched drive driven from outside,
the duty cycle ``duty`` (latched each period; start: the parameter ``duty``) and a load
torque ``tau_load`` (opposing rotation, start 0) as the model's external inputs.
"""

from __future__ import annotations

import mechatron as mt
from mechatron.library import blocks
from mechatron.library import electrical as el
from mechatron.library import electromechanical as em
from mechatron.library import rotational as rot
from mechatron.models.entry import Experiment, ModelEntry, ParameterInfo
from mechatron.models.registry import register

__all__ = ["pwm_motor"]

SEED = "seed table 6-1, calculated"


def pwm_motor(averaged: bool, *, V=19.2, R=7.1, L=3.408e-4, k=0.151, J=4.8e-6, B=1.236e-4,
              duty=0.5, f_pwm=10e3, inputs: bool = False) -> mt.System:
    """The DC motor behind a controlled voltage source, driven by a PWM of ``duty`` (or by
    its average ``duty V``); ``charge`` integrates the armature current. ``inputs``: the
    duty cycle and a load torque are external inputs (the ``inputs`` variant)."""
    m = mt.System("dc_motor_pwm")
    if inputs:
        command = m.input("duty", unit="1", start=duty, doc="Duty cycle, latched each period")
    else:
        command = m.add("duty", blocks.Constant(value=duty)).y
    drive = m.add("avg", blocks.Gain(k=V)) if averaged else \
        m.add("pwm", blocks.PWM(Ts=1 / f_pwm, amplitude=V))
    src = m.add("src", el.ControlledVoltageSource())
    sensor = m.add("sensor", el.CurrentSensor())
    r = m.add("r", el.Resistor(R=R))
    ind = m.add("l", el.Inductor(L=L))
    emf = m.add("emf", em.RotationalEMF(k=k))
    j = m.add("j", rot.Inertia(J=J))
    d = m.add("d", rot.RotationalDamper(D=B))
    g = m.add("g", el.ElectricalReference())
    f = m.add("f", rot.RotationalReference())
    charge = m.add("charge", blocks.Integrator())
    m.connect(command, drive.u)
    m.connect(drive.y, src.u)
    m.connect(src.p, sensor.p)
    m.connect(sensor.n, r.p)
    m.connect(r.n, ind.p)
    m.connect(ind.n, emf.p)
    m.connect(emf.n, src.n, g.port)
    m.connect(emf.A, j.port, d.A)
    m.connect(emf.B, d.B, f.port)
    m.connect(sensor.I, charge.u)
    if inputs:      # reaction -tau_load on the rotor
        brake = m.add("load", rot.IdealTorqueSource())
        m.connect(m.input("tau_load", unit="N*m", start=0.0,
                          doc="Load torque, opposing rotation"), brake.tau_in)
        m.connect(j.port, brake.B)
        m.connect(f.port, brake.A)
    return m


_PARAMS = {
    "V": ParameterInfo("V", 19.2, "Supply voltage (PWM amplitude)", "seed, test bench"),
    "R": ParameterInfo("Ohm", 7.1, "Armature resistance", SEED),
    "L": ParameterInfo("H", 3.408e-4, "Armature inductance", SEED),
    "k": ParameterInfo("V*s/rad", 0.151, "Motor constant", SEED),
    "J": ParameterInfo("kg*m^2", 4.8e-6, "Rotor inertia", SEED),
    "B": ParameterInfo("N*m*s/rad", 1.236e-4, "Viscous friction", SEED),
    "duty": ParameterInfo("1", 0.5, "PWM duty cycle", "chosen"),
    "f_pwm": ParameterInfo("Hz", 10e3, "PWM frequency", "chosen"),
}

ENTRY = register(ModelEntry(
    name="dc_motor_pwm",
    description=("The seed's DC motor fed by a 10 kHz PWM from signal blocks, beside the "
                 "averaged drive: switching events inside the integrator."),
    parameters=_PARAMS,
    variants={"averaged": lambda **p: pwm_motor(True, **p),
              "switched": lambda **p: pwm_motor(False, **p),
              "inputs": lambda **p: pwm_motor(False, **p, inputs=True)},
    outputs={v: {"w": "j.w", "q": "charge.y"} for v in ("averaged", "switched", "inputs")},
    output_units={"w": "rad/s", "q": "C"},
    experiment=Experiment(t_stop=0.1, rtol=1e-8, atol=1e-10),
    expected={"w": 0.151 * 0.5 * 19.2 / (7.1 * 1.236e-4 + 0.151 ** 2)},
    expected_tolerance=1e-6,
    # the current ripples by V duty (1 - duty) / (L f_pwm) = 1.4 A peak to peak, so it is
    # compared by its mean (the charge); the speed ripples by about 1.5% of its final value
    variant_tolerance=0.02,
    tags=("seed", "motor", "electromechanical", "PWM", "hybrid"),
))
