"""Semiconductor devices: exponential (Shockley) diode and switching MOSFETs."""

import casadi as ca

from mechatron.core import Parameter, Variable
from mechatron.library.electrical.interfaces import OnePort, Pin

__all__ = ["ExponentialDiode", "NMOSFET", "PMOSFET"]

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
