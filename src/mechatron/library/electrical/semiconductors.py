"""Semiconductor devices: exponential (Shockley) diode, switching MOSFETs, Zener diode,
thyristor, bipolar transistors."""

import casadi as ca

from mechatron.core import Component, Input, Parameter, Variable, when
from mechatron.library.electrical.interfaces import OnePort, Pin

__all__ = ["ExponentialDiode", "NMOSFET", "PMOSFET", "ZenerDiode", "Thyristor", "NPN", "PNP"]

K_BOLTZMANN = 1.380649e-23   # J/K (exact, SI 2019)
Q_ELECTRON = 1.602176634e-19  # C (exact, SI 2019)


class ExponentialDiode(OnePort):
    """Diode with the exponential (Shockley) characteristic and a parallel conductance
    (Simscape's ``Diode`` with the exponential model, Modelica's ``Diode``).

    Equations, with ``V_t = k_B T / q`` and ``x = v / (N V_t)``::

        i == I_s (exp(x) - 1) + G_par v                                 x <= x_max
        i == I_s (exp(x_max) (1 + x - x_max) - 1) + G_par v             x >  x_max

    Anode ``p``, cathode ``n``; ``i`` flows from anode to cathode. Above ``x_max`` the
    exponential continues along its tangent (same value and slope), which keeps the
    Newton iterations from overflowing; the switch between the two branches needs no
    event because the characteristic is continuously differentiable.

    Limitations: no series resistance (add a :class:`Resistor`), no junction capacitance,
    no reverse breakdown; temperature enters only through ``V_t`` (``I_s`` is fixed).
    """

    I_s = Parameter("A", default=1e-14, min=0, doc="Saturation current")
    N = Parameter("1", default=1.0, min=0, doc="Emission coefficient (ideality factor)")
    T = Parameter("K", default=300.15, min=0, doc="Junction temperature")
    G_par = Parameter("S", default=1e-12, min=0, doc="Parallel (leakage) conductance")
    x_max = Parameter("1", default=40.0, min=0,
                      doc="Exponent v/(N*V_t) above which the characteristic is linear")
    k_B = Parameter("J/K", default=K_BOLTZMANN, min=0, doc="Boltzmann constant")
    q_e = Parameter("C", default=Q_ELECTRON, min=0, doc="Elementary charge")
    V_t = Variable("V", doc="Thermal voltage k_B*T/q")

    def equations(self):
        x = self.v / (self.N * self.V_t)
        core = ca.exp(ca.fmin(x, self.x_max)) * (1 + ca.fmax(x - self.x_max, 0))
        return [self.V_t == self.k_B * self.T / self.q_e,
                self.i == self.I_s * (core - 1) + self.G_par * self.v]


class _SwitchingMOSFET(OnePort, partial=True):
    """Pins, gate and body diode shared by the N- and P-channel switching MOSFETs."""

    gate = Pin(doc="Gate (draws no current)")
    R_on = Parameter("Ohm", default=0.01, min=0, doc="Drain-source on-resistance (> 0)")
    G_off = Parameter("S", default=1e-6, min=0, doc="Drain-source off-conductance")
    V_f = Parameter("V", default=0.8, min=0, doc="Body-diode forward voltage")
    R_d = Parameter("Ohm", default=0.01, min=0, doc="Body-diode on-resistance (> 0)")
    v_gs = Variable("V", doc="Gate-source voltage gate.v - n.v")
    on = Variable("1", doc="1 while the channel conducts, else 0")
    i_d = Variable("A", doc="Body-diode current from anode to cathode")

    def equations(self):
        return [self.gate.i == 0, self.v_gs == self.gate.v - self.n.v]


class NMOSFET(_SwitchingMOSFET):
    """N-channel MOSFET, switch model with an anti-parallel body diode (Simscape's
    ``MOSFET (Ideal, Switching)``). Pin ``p`` is the drain, ``n`` the source.

    Equations, with ``v = p.v - n.v`` (drain-source) and ``i`` the drain current::

        gate.i == 0,  v_gs == gate.v - n.v
        on == if_else(v_gs > V_th, 1, 0)
        i_d == if_else(-v > V_f, (-v - V_f) / R_d, 0)       (body diode, source -> drain)
        i == if_else(v_gs > V_th, v / R_on, G_off v) - i_d

    The channel conducts in both directions when on. Turning on and off and the body
    diode's conduction are events located by the solver.

    Limitations: no linear (ohmic/saturation) region, no gate charge or capacitances, no
    switching losses; ``R_on`` and ``R_d`` must be > 0.
    """

    V_th = Parameter("V", default=2.0, doc="Gate-source threshold voltage")

    def equations(self):
        c = self.V_th < self.v_gs
        return [self.on == ca.if_else(c, 1, 0),
                self.i_d == ca.if_else(self.V_f < -self.v, (-self.v - self.V_f) / self.R_d,
                                       0),
                self.i == ca.if_else(c, self.v / self.R_on, self.G_off * self.v) - self.i_d]


class PMOSFET(_SwitchingMOSFET):
    """P-channel MOSFET, switch model with an anti-parallel body diode. Pin ``p`` is the
    drain, ``n`` the source; in a high-side switch the current flows from ``n`` to ``p``
    (``i < 0``).

    Equations, with ``v = p.v - n.v`` (drain-source) and ``i`` the drain current::

        gate.i == 0,  v_gs == gate.v - n.v
        on == if_else(v_gs < V_th, 1, 0)                     (V_th < 0)
        i_d == if_else(v > V_f, (v - V_f) / R_d, 0)         (body diode, drain -> source)
        i == if_else(v_gs < V_th, v / R_on, G_off v) + i_d

    Limitations: as :class:`NMOSFET`.
    """

    V_th = Parameter("V", default=-2.0, doc="Gate-source threshold voltage (negative)")

    def equations(self):
        c = self.v_gs < self.V_th
        return [self.on == ca.if_else(c, 1, 0),
                self.i_d == ca.if_else(self.V_f < self.v, (self.v - self.V_f) / self.R_d, 0),
                self.i == ca.if_else(c, self.v / self.R_on, self.G_off * self.v) + self.i_d]


class ZenerDiode(OnePort):
    """Piecewise-linear Zener diode: conducts forward above ``Vf`` and in reverse
    breakdown below ``-Vz`` (Simscape's ``Zener Diode`` with the piecewise-linear model;
    MSL's ``ZDiode`` is its exponential counterpart).

    Equations, with ``v = p.v - n.v`` (anode ``p``, cathode ``n``)::

        i == (v - Vf) / R_on + G_off Vf          v >  Vf          (forward)
        i == (v + Vz) / R_z - G_off Vz           v < -Vz          (breakdown)
        i == G_off v                             otherwise        (blocking)

    The characteristic is continuous; both knees are events. A Zener regulator with a
    series resistor ``R_s`` from a supply ``V_s > Vz`` holds the cathode at
    ``Vz + R_z (V_s - Vz - R_s G_off Vz) / (R_s + R_z)`` (to first order in ``G_off``).
    """

    Vz = Parameter("V", default=5.1, min=0, doc="Breakdown (Zener) voltage, reverse")
    Vf = Parameter("V", default=0.7, min=0, doc="Forward voltage")
    R_on = Parameter("Ohm", default=0.01, min=0, doc="Forward on-resistance (> 0)")
    R_z = Parameter("Ohm", default=1.0, min=0, doc="Resistance in breakdown (> 0)")
    G_off = Parameter("S", default=1e-8, min=0, doc="Off conductance")

    def equations(self):
        fwd = self.Vf < self.v
        rev = self.v < -self.Vz
        return [self.i == ca.if_else(fwd, (self.v - self.Vf) / self.R_on + self.G_off * self.Vf,
                                     ca.if_else(rev, (self.v + self.Vz) / self.R_z
                                                - self.G_off * self.Vz, self.G_off * self.v))]


class Thyristor(OnePort):
    """Ideal thyristor (MSL's ``IdealThyristor``, Simscape's ``Thyristor`` piecewise
    linear): blocks until it is fired while forward biased, then conducts until its
    current falls to zero. Anode ``p``, cathode ``n``.

    Equations, with the latched state ``on`` (start 0)::

        i == (v - V_knee) / R_on + G_off V_knee      on
        i == G_off v                                 not on
        when min(fire - 0.5, v - V_knee) > 0:  on := 1    (fired while forward biased)
        when i < 0:                            on := 0    (the current dies: it turns off)

    Firing and turning off are events. Limitations: no holding current, no gate current,
    no recovery time; a gate held high when the anode becomes forward biased fires it
    (as MSL's); a device fired at ``t = 0`` needs the gate to rise after the start.
    """

    fire = Input("1", doc="Gate signal; a rise above 0.5 while forward biased fires it")
    V_knee = Parameter("V", default=0.0, min=0, doc="Forward knee voltage")
    R_on = Parameter("Ohm", default=1e-5, min=0, doc="On resistance (> 0)")
    G_off = Parameter("S", default=1e-5, min=0, doc="Off conductance")
    on = Variable("1", start=0.0, doc="1 while conducting (latched), else 0")

    def equations(self):
        conducting = 0.5 < self.on
        return [self.i == ca.if_else(conducting, (self.v - self.V_knee) / self.R_on
                                     + self.G_off * self.V_knee, self.G_off * self.v),
                when(0 < ca.fmin(self.fire - 0.5, self.v - self.V_knee),
                     update={self.on: 1.0}),
                when(self.i < 0, update={self.on: 0.0})]


class _BJT(Component, partial=True):
    """Pins and the Ebers-Moll transport model shared by NPN and PNP."""

    C = Pin(doc="Collector")
    B = Pin(doc="Base")
    E = Pin(doc="Emitter")
    beta_F = Parameter("1", default=100.0, min=0, doc="Forward current gain")
    beta_R = Parameter("1", default=1.0, min=0, doc="Reverse current gain")
    I_s = Parameter("A", default=1e-16, min=0, doc="Transport saturation current")
    N = Parameter("1", default=1.0, min=0, doc="Emission coefficient")
    T = Parameter("K", default=300.15, min=0, doc="Junction temperature")
    x_max = Parameter("1", default=40.0, min=0,
                      doc="Exponent above which the junction laws continue linearly")
    G_min = Parameter("S", default=1e-12, min=0, doc="Leakage conductance of each junction")
    k_B = Parameter("J/K", default=K_BOLTZMANN, min=0, doc="Boltzmann constant")
    q_e = Parameter("C", default=Q_ELECTRON, min=0, doc="Elementary charge")
    V_t = Variable("V", doc="Thermal voltage k_B*T/q")
    v_be = Variable("V", doc="Base-emitter voltage B.v - E.v")
    v_bc = Variable("V", doc="Base-collector voltage B.v - C.v")

    def _exp(self, v):
        x = v / (self.N * self.V_t)
        return ca.exp(ca.fmin(x, self.x_max)) * (1 + ca.fmax(x - self.x_max, 0))

    def _currents(self, sign):
        """Collector and base currents into the device for junction voltages times
        ``sign`` (+1 NPN, -1 PNP)."""
        e_f = self._exp(sign * self.v_be) - 1
        e_r = self._exp(sign * self.v_bc) - 1
        i_c = sign * (self.I_s * (e_f - e_r) - self.I_s / self.beta_R * e_r) \
            - self.G_min * self.v_bc
        i_b = sign * (self.I_s / self.beta_F * e_f + self.I_s / self.beta_R * e_r) \
            + self.G_min * (self.v_be + self.v_bc)
        return i_c, i_b

    def equations(self):
        return [self.V_t == self.k_B * self.T / self.q_e,
                self.v_be == self.B.v - self.E.v,
                self.v_bc == self.B.v - self.C.v,
                self.C.i + self.B.i + self.E.i == 0]


class NPN(_BJT):
    """NPN bipolar transistor, static Ebers-Moll (transport) model (MSL's
    ``Semiconductors.NPN`` without its capacitances and Early effect).

    Equations, with ``V_t = k_B T / q``, ``e(v) = exp(v / (N V_t))`` (continued along its
    tangent above ``x_max``, as :class:`ExponentialDiode`)::

        C.i == I_s (e(v_be) - e(v_bc)) - I_s/beta_R (e(v_bc) - 1) - G_min v_bc
        B.i == I_s/beta_F (e(v_be) - 1) + I_s/beta_R (e(v_bc) - 1) + G_min (v_be + v_bc)
        E.i == -(C.i + B.i)

    Currents flow into the device at each pin. In the forward-active region
    (``v_be > 0``, ``v_bc < 0``) ``C.i = beta_F B.i`` and ``C.i = I_s exp(v_be/V_t)``.
    Limitations: no junction or diffusion capacitances, no Early effect, no series
    resistances, no breakdown.
    """

    def equations(self):
        i_c, i_b = self._currents(1.0)
        return [self.C.i == i_c, self.B.i == i_b]


class PNP(_BJT):
    """PNP bipolar transistor, static Ebers-Moll model, the mirror of :class:`NPN`.

    Equations, with ``e(v)`` as for :class:`NPN`::

        C.i == -(I_s (e(-v_be) - e(-v_bc)) - I_s/beta_R (e(-v_bc) - 1)) - G_min v_bc
        B.i == -(I_s/beta_F (e(-v_be) - 1) + I_s/beta_R (e(-v_bc) - 1)) + G_min (v_be + v_bc)
        E.i == -(C.i + B.i)

    In the forward-active region (``v_eb > 0``, ``v_cb < 0``) current leaves at the
    collector: ``-C.i = beta_F (-B.i)``.
    """

    def equations(self):
        i_c, i_b = self._currents(-1.0)
        return [self.C.i == i_c, self.B.i == i_b]
