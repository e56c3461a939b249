"""The HIL plant of the seed's chapter 7: PWM pin -> RC low-pass -> H-bridge -> DC motor ->
incremental encoder.

Physics
-------
The controller's PWM pin (high level ``V_io``, duty ``d``) drives the seed's RC filter
(``R_f`` = 7.5 kOhm, ``C_f`` = 40 nF, time constant 0.3 ms)::

    C_f dv_c/dt = (v_pwm - v_c) / R_f

The I/O card reads ``v_c`` and drives the motor through an ideal H-bridge in locked
anti-phase, so that 50 % duty is 0 V and the armature voltage spans the supply::

    V_a = V_s (2 v_c / V_io - 1)

The motor is the database's ``dc_motor`` (seed table 6-1): ``L di/dt = V_a - R i - k w``,
``J dw/dt = k i - B w``; its shaft angle ``phi`` (``dphi/dt = w``) feeds an incremental
encoder of ``lines`` lines read in quadrature: ``count = floor(4 lines phi / 2 pi)``.

The pin voltage is a parameter of the model (``pwm.V``), set every step from the duty:
the plant step does not resolve the PWM edges (at 10 kHz one step is half a 5 kHz PWM
period) but applies the *average* of the pin voltage over the step, computed exactly from
the duty and the phase of the step within the PWM period (:func:`pwm_average`). That is
the documented simplification of this plant: the ripple inside a step is lost, its mean
is kept (the RC filter integrates the pin voltage, so its response to a step-averaged
input differs from the response to the true square wave only by the in-step ripple,
a few mV here).
"""

from __future__ import annotations

import math

import casadi as ca

import mechatron as mt
from mechatron.library import electrical as el
from mechatron.library import electromechanical as em
from mechatron.library import rotational as rot

__all__ = ["HBridge", "HILPlant", "build_plant", "pwm_average", "PLANT_DEFAULTS"]

#: Defaults of the HIL bench (seed chapter 7; motor from seed table 6-1).
PLANT_DEFAULTS = {
    "R_f": 7.5e3,      # Ohm, RC filter resistor
    "C_f": 40e-9,      # F, RC filter capacitor
    "V_io": 3.3,       # V, PWM pin high level of the microcontroller
    "V_s": 19.2,       # V, H-bridge supply (the seed's bench supply)
    "lines": 1000,     # encoder lines (x4 quadrature counts)
    "f_pwm": 5000.0,   # Hz, PWM carrier
}


class HBridge(mt.Component):
    """Ideal H-bridge in locked anti-phase, commanded by an analog voltage.

    Sense pins ``sp``/``sn`` draw no current; the output ``p``/``n`` is an ideal source
    ``v_out = V_s (2 v_in / V_io - 1)`` with ``v_in = sp.v - sn.v``: 0 V in gives
    ``-V_s``, ``V_io / 2`` gives 0 V, ``V_io`` gives ``+V_s``. No dead time, no
    current limit.
    """

    sp = el.Pin(doc="Sense input, positive")
    sn = el.Pin(doc="Sense input, negative")
    p = el.Pin(doc="Output, positive")
    n = el.Pin(doc="Output, negative")
    V_s = mt.Parameter("V", default=PLANT_DEFAULTS["V_s"], min=0, doc="Supply voltage")
    V_io = mt.Parameter("V", default=PLANT_DEFAULTS["V_io"], min=0,
                        doc="Input level commanding +V_s")
    v_out = mt.Variable("V", doc="Output voltage p.v - n.v")

    def equations(self):
        v_in = self.sp.v - self.sn.v
        return [self.sp.i == 0, self.sn.i == 0,
                self.p.i + self.n.i == 0,
                self.v_out == self.p.v - self.n.v,
                self.v_out == self.V_s * (2 * v_in / self.V_io - 1)]


class HILPlant(mt.Component):
    """PWM pin (as its step average) -> RC filter -> H-bridge -> DC motor -> encoder angle."""

    pwm = el.DCVoltageSource(doc="PWM pin, its average over the current step")
    r_f = el.Resistor(doc="RC filter resistor")
    c_f = el.Capacitor(doc="RC filter capacitor")
    bridge = HBridge()
    resistor = el.Resistor()
    inductor = el.Inductor()
    emf = em.RotationalEMF()
    inertia = rot.Inertia()
    damper = rot.RotationalDamper()
    encoder = rot.AngularVelocitySensor(doc="Shaft angle for the encoder")
    ground = el.ElectricalReference()
    fixed = rot.RotationalReference()

    def equations(self):
        g = self.ground.port
        return [mt.connect(self.pwm.p, self.r_f.p),
                mt.connect(self.r_f.n, self.c_f.p, self.bridge.sp),
                mt.connect(self.pwm.n, self.c_f.n, self.bridge.sn, self.bridge.n,
                           self.emf.n, g),
                mt.connect(self.bridge.p, self.resistor.p),
                mt.connect(self.resistor.n, self.inductor.p),
                mt.connect(self.inductor.n, self.emf.p),
                mt.connect(self.emf.A, self.inertia.port, self.damper.A, self.encoder.A),
                mt.connect(self.emf.B, self.damper.B, self.encoder.B, self.fixed.port)]


def build_plant(**overrides) -> HILPlant:
    """The plant with the motor of ``mt.models.get("dc_motor")`` and the bench defaults.

    Keyword arguments override ``R_f, C_f, V_io, V_s`` and the motor's ``R, L, k, J, B``.
    """
    motor = {k: v.default for k, v in mt.models.get("dc_motor").parameters.items()}
    known = set(motor) | {"R_f", "C_f", "V_io", "V_s"}
    bad = sorted(set(overrides) - known)
    if bad:
        raise TypeError(f"build_plant: unknown parameter(s) {', '.join(bad)}; valid: "
                        f"{', '.join(sorted(known))}.")
    v = {**motor, **{k: PLANT_DEFAULTS[k] for k in ("R_f", "C_f", "V_io", "V_s")},
         **overrides}
    m = HILPlant(doc="HIL plant: RC filter, H-bridge, DC motor, encoder")
    m._name = "hil_plant"
    m.pwm._values["V"] = 0.0
    m.r_f._values["R"] = v["R_f"]
    m.c_f._values["C"] = v["C_f"]
    # start at the filter's 50 % duty level, 0 V at the armature: the motor at rest
    m.c_f._starts["v"] = mt.Start(v["V_io"] / 2, "high")
    m.bridge._values["V_s"] = v["V_s"]
    m.bridge._values["V_io"] = v["V_io"]
    m.resistor._values["R"] = v["R"]
    m.inductor._values["L"] = v["L"]
    m.emf._values["k"] = v["k"]
    m.inertia._values["J"] = v["J"]
    m.damper._values["D"] = v["B"]
    return m


#: Above this many PWM periods per plant step, :func:`pwm_average` uses its closed form.
MAX_UNROLLED_PERIODS = 16


def pwm_average(duty, k, dt: float, f_pwm: float, v_high: float):
    """Mean pin voltage over plant step ``k`` (``[k dt, (k+1) dt]``) of an edge-aligned
    PWM of period ``T = 1/f_pwm`` whose pulse ``[jT, jT + duty T]`` starts every period.

    ``duty`` and ``k`` are CasADi expressions (SX). The high time inside the step is the
    sum over the periods ``j`` the step touches of ``|[jT, jT + d T] & [t0, t1]|``, with
    ``d`` clipped to [0, 1]; exact for any ratio of ``dt`` to ``T``.
    """
    T = 1.0 / f_pwm
    n_periods = int(math.ceil(dt / T)) + 1
    t0 = k * dt
    t1 = t0 + dt
    if n_periods > MAX_UNROLLED_PERIODS:
        # a slow plant step spans many periods: the closed form of the high time since 0,
        # H(t) = n d T + min(t - n T, d T) with n = floor(t / T), instead of one term per
        # period (at 1 Hz and a 5 kHz carrier, 5,000 terms and a megabyte of C)
        d = ca.fmin(ca.fmax(duty, 0), 1)

        def since_zero(t):
            n = ca.floor(t / T + 1e-9)
            return n * d * T + ca.fmax(ca.fmin(t - n * T, d * T), 0)
        return v_high * (since_zero(t1) - since_zero(t0)) / dt
    j0 = ca.floor(t0 / T + 1e-9)       # guard against k*dt/T landing just below an integer
    d = ca.fmin(ca.fmax(duty, 0), 1)
    high = 0
    for j in range(n_periods):
        a = (j0 + j) * T
        high = high + ca.fmax(ca.fmin(a + d * T, t1) - ca.fmax(a, t0), 0)
    return v_high * high / dt
