"""Brushless DC motor with six-step (trapezoidal) commutation and a PI speed loop.

The drive of issue 6 (the seed built it in Simscape, without parameters; the values here
are *chosen*: a small 24 V motor). Its parts:

* a three-phase star winding with a **trapezoidal back EMF** and a one-pole-pair rotor: the
  library's :class:`~mechatron.library.machines.PMSM` with ``emf="trapezoidal"`` (its
  rotor inertia and bearing friction carry the drive's ``J`` and ``B``);
* a three-phase inverter of three legs (:class:`InverterLeg`, a subsystem used three
  times), each two N-channel MOSFETs with body diodes (library
  :class:`~mechatron.library.electrical.NMOSFET`) fed by a DC supply, each gate driven by
  an ideal isolated gate driver (:class:`GateDriver`);
* three **Hall sensors** 120 electrical degrees apart, which split the turn into six
  60-degree sectors (:class:`HallSensors`);
* **six-step commutation** (:class:`SixStepCommutation`): per sector one phase is
  connected to the positive rail, one to the negative rail, the third floats;
* a **PI speed controller** (:class:`SpeedPI`) whose output is the PWM duty cycle of the
  phase connected to the positive rail.

Commutation table (electrical angle ``theta_e = p theta``; the Hall edges and the
commutations are at ``30 + 60 k`` degrees, in the middle of the back-EMF flat tops)::

    sector  angle (deg)   Hall (a b c)   high  low   floating
      1      30 ..  90      1 0 1          A     B      C
      2      90 .. 150      1 0 0          A     C      B
      3     150 .. 210      1 1 0          B     C      A
      4     210 .. 270      0 1 0          B     A      C
      5     270 .. 330      0 1 1          C     A      B
      6     330 ..  30      0 0 1          C     B      A

PWM modes (chosen when the model is built, by the parameter ``f_pwm``):

* ``f_pwm = 0`` (default): **averaged** PWM. The gates follow the commutation table only
  (events at the six commutations per electrical turn) and the DC link carries the
  duty-weighted voltage ``d V_dc`` (an averaged chopper). This is the exact average of
  synchronous (complementary) PWM while the PWM leg conducts continuously; it differs
  from it only in where the floating phase's diodes clamp during a commutation
  (at ``d V_dc`` instead of ``V_dc``).
* ``f_pwm > 0``: **switched** PWM at ``f_pwm``. The phase on the positive rail is
  switched by a centre-aligned (triangular carrier) comparator, with synchronous
  rectification: while its high-side switch is off, its low-side switch is on. Every edge
  is an event; about ``2 f_pwm`` events per second, so slower to simulate.

Variants:

* ``acausal``: the physical network (library MOSFETs, DC source, rotational parts) and
  the user components of this module;
* ``inputs``: the same network without the speed controller, driven from outside: the
  duty cycle ``d`` (start 0) and the load torque ``T_load`` (start: the parameter
  ``T_load``), opposing rotation, are the model's external inputs, for an outside
  controller (HIL, an FMU importer, estimation). An open-loop plant, so it is not compared
  with the closed-loop variants (``driven_variants``); its test closes the loop around it
  with :class:`SpeedPI`;
* ``equation``: the same drive as one set of equations: phase currents of the winding,
  the inverter legs as piecewise-linear switch and diode conductances solved in closed
  form per leg, the gate logic written from the Hall signals (not from the sector
  table), the mechanics and the controller.

Known analytic facts (checked by the tests): with 120-degree conduction two phases carry
``+I`` and ``-I`` on the flat tops of their back EMFs, so ``T = 2 k_e I``; the steady
speed is the reference (integral action); the Hall sector runs 1, 2, ..., 6 in order for
positive rotation, each sector spanning 60 electrical degrees.

Numerics: the floating phase is an inductance in series with two open switches, a time
constant of ``4 L G_off``; with ``G_off = 1 mS`` (4 us, a leakage of at most
``G_off V_dc`` = 24 mA in the floating phase) the explicit Runge-Kutta method that
``solver="auto"`` picks for ODEs with events takes about 10 us steps, so 0.1 s of the
averaged drive costs about a second. A smaller ``G_off`` is more faithful and
proportionally slower. The averaged variants agree to about 1e-6, the switched ones
likewise (every PWM edge is an event of both).
"""

from __future__ import annotations

import math

import casadi as ca

import mechatron as mt
from mechatron.errors import ModelError
from mechatron.library import electrical as el
from mechatron.library import rotational as rot
from mechatron.library.machines import PMSM, trapezoid
from mechatron.library.electrical.interfaces import OnePort, Pin
from mechatron.library.rotational.interfaces import TwoFlange
from mechatron.models.entry import Experiment, ModelEntry, ParameterInfo
from mechatron.models.registry import register

__all__ = ["trapezoid", "HallSensors", "SixStepCommutation",
           "SpeedPI", "PWMComparator", "GateDriver", "InverterLeg", "DutyScaledSource",
           "build_acausal",
           "build_equation", "BLDCDriveEquation", "BLDCDriveEquationPWM", "COMMUTATION",
           "ENTRY"]

CHOSEN = "chosen: a small 24 V BLDC motor"
DESIGN = "chosen: controller design"
TWO_PI_3 = 2 * math.pi / 3
DEG = math.pi / 180
#: Nominal frequency the machine's open-circuit voltage is quoted at (any value: the
#: machine's flux linkage is k_e / p whatever it is)
F_NOM = 50.0

#: Six-step table: sector -> (phase on the positive rail, phase on the negative rail).
COMMUTATION = {1: ("a", "b"), 2: ("a", "c"), 3: ("b", "c"),
               4: ("b", "a"), 5: ("c", "a"), 6: ("c", "b")}
#: Hall code (4 H_a + 2 H_b + H_c) of each sector.
HALL_CODE = {1: 5, 2: 4, 3: 6, 4: 2, 5: 3, 6: 1}
#: Electrical angles of the rising edges of the Hall signals a, b, c (rad).
HALL_EDGES = (30 * DEG, 150 * DEG, 270 * DEG)


def _indicator(x, s, values=range(1, 7)):
    """1 when ``x == s``, 0 at the other integers of ``values`` (a Lagrange basis
    polynomial: exact at the integers, no relation and hence no event)."""
    out = 1
    for j in values:
        if j != s:
            out = out * (x - j) / (s - j)
    return out


# -- components -------------------------------------------------------------------------

class HallSensors(TwoFlange):
    """Three digital Hall sensors 120 electrical degrees apart, and the sector they
    encode. A sensor: it exerts no torque.

    With ``theta_e = p theta + theta_0`` (``theta`` the angle of A relative to B, its own
    state)::

        H_a == (sin(theta_e - 30 deg) > 0),  H_b == (sin(theta_e - 150 deg) > 0),
        H_c == (sin(theta_e - 270 deg) > 0)
        sector == table[4 H_a + 2 H_b + H_c]     (5, 4, 6, 2, 3, 1 -> 1, 2, ..., 6)

    so sector ``s`` spans ``theta_e`` in ``[30 + 60 (s - 1), 90 + 60 (s - 1))`` degrees and
    runs 1, 2, ..., 6 for positive rotation. Each Hall edge is an event located by the
    solver.
    """

    p = mt.Parameter("1", default=1.0, min=1, doc="Pole pairs")
    theta_0 = mt.Parameter("rad", default=0.0, doc="Electrical angle offset (sensor "
                           "mounting)")
    phi = mt.Variable("rad", start=0.0, doc="Rotor angle (mechanical), A relative to B")
    H_a = mt.Output("1", doc="Hall sensor a (0 or 1)")
    H_b = mt.Output("1", doc="Hall sensor b (0 or 1)")
    H_c = mt.Output("1", doc="Hall sensor c (0 or 1)")
    sector = mt.Output("1", doc="Sector 1..6")

    def equations(self):
        th = self.p * self.phi + self.theta_0
        hall = [ca.if_else(0 < ca.sin(th - edge), 1, 0) for edge in HALL_EDGES]
        code_of = {s: [(c >> 2) & 1, (c >> 1) & 1, c & 1] for s, c in HALL_CODE.items()}
        sector = 0
        for s, bits in code_of.items():
            term = s
            for h, bit in zip([self.H_a, self.H_b, self.H_c], bits):
                term = term * (h if bit else 1 - h)
            sector = sector + term
        return [self.tau == 0, mt.der(self.phi) == self.w,
                self.H_a == hall[0], self.H_b == hall[1], self.H_c == hall[2],
                self.sector == sector]


class SixStepCommutation(mt.Component):
    """Six-step commutation logic: gate commands (0/1) of the six switches from the
    sector (table :data:`COMMUTATION`) and the PWM signal.

    For the phase on the positive rail: high side ``= pwm``, low side ``= 1 - pwm``
    (synchronous rectification); for the phase on the negative rail: low side on; the
    floating phase: both off. With ``pwm`` held at 1 (averaged PWM) the high side
    conducts for the whole sector. The sector indicator is a Lagrange polynomial (exact at
    the integers), so the logic adds no events of its own.
    """

    sector = mt.Input("1", doc="Sector 1..6")
    pwm = mt.Input("1", doc="PWM signal of the high side (0 or 1)")
    g_ah = mt.Output("1", doc="Gate command, phase a high side")
    g_al = mt.Output("1", doc="Gate command, phase a low side")
    g_bh = mt.Output("1", doc="Gate command, phase b high side")
    g_bl = mt.Output("1", doc="Gate command, phase b low side")
    g_ch = mt.Output("1", doc="Gate command, phase c high side")
    g_cl = mt.Output("1", doc="Gate command, phase c low side")

    def equations(self):
        high = {k: 0 for k in "abc"}
        low = {k: 0 for k in "abc"}
        for s, (hi, lo) in COMMUTATION.items():
            ind = _indicator(self.sector, s)
            high[hi] = high[hi] + ind
            low[lo] = low[lo] + ind
        eqs = []
        for k in "abc":
            eqs += [getattr(self, f"g_{k}h") == high[k] * self.pwm,
                    getattr(self, f"g_{k}l") == low[k] + high[k] * (1 - self.pwm)]
        return eqs


class SpeedPI(mt.Component):
    """PI speed controller whose output is a PWM duty cycle, limited to
    ``[0, d_max]``, with back-calculation anti-windup::

        e == w_ref - w,  u == K_p e + x,  d == min(max(u, 0), d_max)
        dx/dt == K_i e + K_aw (d - u)

    The limits are ``fmin``/``fmax`` (kinks, no events).
    """

    w = mt.Input("rad/s", doc="Measured speed")
    d = mt.Output("1", doc="Duty cycle")
    w_ref = mt.Parameter("rad/s", default=150.0, doc="Speed reference")
    K_p = mt.Parameter("s/rad", default=0.005, min=0, doc="Proportional gain")
    K_i = mt.Parameter("1/rad", default=0.5, min=0, doc="Integral gain")
    K_aw = mt.Parameter("1/s", default=50.0, min=0, doc="Anti-windup gain")
    d_max = mt.Parameter("1", default=0.95, min=0, max=1, doc="Largest duty cycle")
    x = mt.Variable("1", start=0.0, doc="Integrator state")
    u = mt.Variable("1", doc="Unlimited controller output")

    def equations(self):
        e = self.w_ref - self.w
        return [self.u == self.K_p * e + self.x,
                self.d == ca.fmin(ca.fmax(self.u, 0), self.d_max),
                mt.der(self.x) == self.K_i * e + self.K_aw * (self.d - self.u)]


class PWMComparator(mt.Component):
    """Centre-aligned PWM: ``pwm == (cos(2 pi f t) > cos(pi d))``, i.e. on while the duty
    ``d`` exceeds the triangular carrier (0 at ``t = k/f``, 1 half a period later). Each
    edge is an event."""

    d = mt.Input("1", doc="Duty cycle (0..1)")
    pwm = mt.Output("1", doc="PWM signal (0 or 1)")
    f = mt.Parameter("Hz", default=8e3, min=0, doc="Carrier (switching) frequency")

    def equations(self):
        return [self.pwm == ca.if_else(ca.cos(ca.pi * self.d)
                                       < ca.cos(2 * ca.pi * self.f * self.time), 1, 0)]

    def time_scales(self):
        return [0.5 / self.f]


class GateDriver(OnePort):
    """Ideal isolated gate driver: ``v == V_g cmd`` between gate (``p``) and source
    (``n``) of a MOSFET."""

    cmd = mt.Input("1", doc="Gate command (0 or 1)")
    V_g = mt.Parameter("V", default=12.0, doc="Gate drive voltage")

    def equations(self):
        return [self.v == self.V_g * self.cmd]


class DutyScaledSource(OnePort):
    """DC link of the averaged PWM mode: ``v == d V_dc`` (an averaged chopper)."""

    d = mt.Input("1", doc="Duty cycle")
    V_dc = mt.Parameter("V", default=24.0, doc="Supply voltage")

    def equations(self):
        return [self.v == self.d * self.V_dc]


class InverterLeg(mt.Component):
    """One leg (half bridge) of the inverter, as a subsystem: a high-side and a low-side
    N-channel MOSFET with body diodes, each gate driven by an ideal isolated gate driver.

    Ports: ``dc_p`` and ``dc_n`` the DC rails, ``out`` the phase terminal; signal inputs
    ``cmd_h`` and ``cmd_l`` the gate commands (0 or 1). The MOSFET and driver parameters
    are the leg's own and passed on to its parts.
    """

    R_on = mt.Parameter("Ohm", default=0.01, min=0, doc="MOSFET on-resistance")
    G_off = mt.Parameter("S", default=1e-3, min=0, doc="MOSFET off-conductance")
    V_f = mt.Parameter("V", default=0.8, doc="Body-diode forward voltage")
    R_d = mt.Parameter("Ohm", default=0.01, min=0, doc="Body-diode on-resistance")
    V_g = mt.Parameter("V", default=12.0, doc="Gate drive voltage")

    dc_p = Pin(doc="Positive DC rail")
    dc_n = Pin(doc="Negative DC rail")
    out = Pin(doc="Phase output")
    cmd_h = mt.Input("1", doc="High-side gate command (0 or 1)")
    cmd_l = mt.Input("1", doc="Low-side gate command (0 or 1)")

    high = el.NMOSFET(R_on=R_on, G_off=G_off, V_f=V_f, R_d=R_d)
    low = el.NMOSFET(R_on=R_on, G_off=G_off, V_f=V_f, R_d=R_d)
    drv_h = GateDriver(V_g=V_g)
    drv_l = GateDriver(V_g=V_g)

    def equations(self):
        return [mt.connect(self.dc_p, self.high.p),
                mt.connect(self.high.n, self.low.p, self.out, self.drv_h.n),
                mt.connect(self.low.n, self.dc_n, self.drv_l.n),
                mt.connect(self.drv_h.p, self.high.gate),
                mt.connect(self.drv_l.p, self.low.gate),
                mt.connect(self.cmd_h, self.drv_h.cmd),
                mt.connect(self.cmd_l, self.drv_l.cmd)]


# -- the two variants ----------------------------------------------------------------------

def build_acausal(V_dc, R, L, k_e, J, B, T_load, w_ref, K_p, K_i, K_aw, d_max, R_on,
                  G_off, V_f, R_d, f_pwm, V_g=12.0, inputs=False):
    """The drive as a physical network (see the module docstring); ``inputs``: without
    the speed controller, the duty cycle ``d`` and the load torque ``T_load`` are the
    model's external inputs (the ``inputs`` variant)."""
    m = mt.System("bldc_motor", doc="BLDC motor, six-step commutation, "
                  + ("external duty cycle and load torque" if inputs else "PI speed loop"))
    ground = m.add("ground", el.ElectricalReference())
    if f_pwm > 0:
        supply = m.add("supply", el.DCVoltageSource(V=V_dc))
        modulator = m.add("modulator", PWMComparator(f=f_pwm))
    else:
        supply = m.add("supply", DutyScaledSource(V_dc=V_dc))
        full_on = m.add("pwm_on", mt.library.blocks.Constant(value=1.0))
    commutation = m.add("commutation", SixStepCommutation())
    if inputs:
        controller = None
        duty = m.input("d", unit="1", start=0.0, doc="Duty cycle of the PWM leg")
        torque = m.input("T_load", unit="N*m", start=T_load,
                         doc="Load torque, opposing rotation")
    else:
        controller = m.add("controller", SpeedPI(w_ref=w_ref, K_p=K_p, K_i=K_i,
                                                 K_aw=K_aw, d_max=d_max))
    # the library machine: peak phase EMF p psi w = k_e w with one pole pair, the phase
    # inductance L_s_sigma + L_md = L, the drive's inertia and friction on its rotor
    motor = m.add("motor", PMSM(emf="trapezoidal", p=1.0, R_s=R, L_s_sigma=L, L_md=0.0,
                                L_mq=0.0, f_s_nom=F_NOM,
                                V_s_open_circuit=k_e * 2 * math.pi * F_NOM / math.sqrt(2),
                                J_r=J, B_v=B))
    hall = m.add("hall", HallSensors())
    load = m.add("load", rot.IdealTorqueSource() if inputs else
                 rot.ConstantTorque(T=-T_load))
    tacho = m.add("tacho", rot.AngularVelocitySensor())
    housing = m.add("housing", rot.RotationalReference())
    m.connect(supply.n, ground.port)
    for k in "abc":   # one subsystem per phase leg
        leg = m.add(f"leg_{k}", InverterLeg(R_on=R_on, G_off=G_off, V_f=V_f, R_d=R_d,
                                            V_g=V_g))
        m.connect(supply.p, leg.dc_p)
        m.connect(leg.dc_n, supply.n)
        m.connect(leg.out, getattr(motor, k))
        m.connect(getattr(commutation, f"g_{k}h"), leg.cmd_h)
        m.connect(getattr(commutation, f"g_{k}l"), leg.cmd_l)
    # the input's torque source acts on the rotor at B: reaction -T_load, opposing
    on_rotor, on_housing = (load.B, load.A) if inputs else (load.A, load.B)
    m.connect(motor.flange, on_rotor, hall.A, tacho.A)
    m.connect(motor.support, on_housing, hall.B, tacho.B, housing.port)
    m.connect(hall.sector, commutation.sector)
    if inputs:
        m.connect(torque, load.tau_in)
        d = duty
    else:
        m.connect(tacho.W, controller.w)
        d = controller.d
    if f_pwm > 0:
        m.connect(d, modulator.d)
        m.connect(modulator.pwm, commutation.pwm)
    else:
        m.connect(d, supply.d)
        m.connect(full_on.y, commutation.pwm)
    return m


class _BLDCEquations(mt.Component, partial=True):
    """The whole drive as equations (the ``equation`` variant); the subclasses add the DC
    link and the PWM signal.

    Hall signals and gate logic::

        H_a = (sin(theta - 30 deg) > 0), H_b = (sin(theta - 150 deg) > 0),
        H_c = (sin(theta - 270 deg) > 0)
        high_a = H_a (1 - H_b),  low_a = (1 - H_a) H_b     (and cyclically b, c)

    (the six-step table written in Hall signals). Inverter leg ``k``: the high and low
    switches are conductances ``G = 1/R_on`` (on) or ``G_off`` (off), each with a body
    diode ``max(v - V_f, 0)/R_d`` in parallel; Kirchhoff's current law at the leg's node
    with the phase current ``i_k`` leaving it::

        G_h (V_p - u_k) - D(u_k - V_p) = i_k + G_l u_k - D(-u_k)

    is solved in closed form: ``u0 = (G_h V_p - i_k)/(G_h + G_l)`` without diodes; the
    high (low) diode conducts exactly when ``u0 > V_p + V_f`` (``u0 < -V_f``), and then
    ``u_k = (G_h V_p + (V_p + V_f)/R_d - i_k)/(G_h + G_l + 1/R_d)``
    (``(G_h V_p - i_k - V_f/R_d)/(G_h + G_l + 1/R_d)``). Winding:
    ``L di_k/dt = u_k - v_n - R i_k - e_k`` for k = a, b with ``i_c = -i_a - i_b`` and the
    star point ``v_n = (sum u_k - sum e_k)/3``; ``e_k = k_e w f(theta - k 2pi/3)``;
    ``T = k_e sum f_k i_k``; ``J dw/dt = T - B w - T_load``; the PI speed controller as in
    :class:`SpeedPI`. The sector is computed from the angle by a formula of its own
    (``1 + floor(((theta - 30 deg) mod 360 deg) / 60 deg)``), an independent check of the
    Hall decoding.
    """

    V_dc = mt.Parameter("V", default=24.0, doc="Supply voltage")
    R = mt.Parameter("Ohm", default=0.5, min=0, doc="Phase resistance")
    L = mt.Parameter("H", default=1e-3, min=0, doc="Phase inductance")
    k_e = mt.Parameter("V*s/rad", default=0.05, min=0, doc="Back-EMF constant per phase")
    J = mt.Parameter("kg*m^2", default=1e-4, min=0, doc="Rotor and load inertia")
    B = mt.Parameter("N*m*s/rad", default=1e-5, min=0, doc="Viscous friction")
    T_load = mt.Parameter("N*m", default=0.05, doc="Load torque")
    w_ref = mt.Parameter("rad/s", default=150.0, doc="Speed reference")
    K_p = mt.Parameter("s/rad", default=0.005, min=0, doc="Speed PI proportional gain")
    K_i = mt.Parameter("1/rad", default=0.5, min=0, doc="Speed PI integral gain")
    K_aw = mt.Parameter("1/s", default=50.0, min=0, doc="Anti-windup gain")
    d_max = mt.Parameter("1", default=0.95, min=0, max=1, doc="Largest duty cycle")
    R_on = mt.Parameter("Ohm", default=0.01, min=0, doc="Switch on-resistance")
    G_off = mt.Parameter("S", default=1e-3, min=0, doc="Switch off-conductance")
    V_f = mt.Parameter("V", default=0.8, min=0, doc="Body-diode forward voltage")
    R_d = mt.Parameter("Ohm", default=0.01, min=0, doc="Body-diode on-resistance")
    i_a = mt.Variable("A", start=0.0, doc="Phase a current")
    i_b = mt.Variable("A", start=0.0, doc="Phase b current")
    i_c = mt.Variable("A", doc="Phase c current")
    w = mt.Variable("rad/s", start=0.0, doc="Rotor speed")
    theta = mt.Variable("rad", start=0.0, doc="Rotor angle (electrical = mechanical)")
    x = mt.Variable("1", start=0.0, doc="PI integrator state")
    d = mt.Variable("1", doc="Duty cycle")
    V_p = mt.Variable("V", doc="Positive DC-link rail")
    pwm = mt.Variable("1", doc="PWM signal of the high side")
    T = mt.Variable("N*m", doc="Electromagnetic torque")
    sector = mt.Variable("1", doc="Sector 1..6 (from the angle)")
    v_n = mt.Variable("V", doc="Star point potential")
    u_a = mt.Variable("V", doc="Phase a terminal potential")
    u_b = mt.Variable("V", doc="Phase b terminal potential")
    u_c = mt.Variable("V", doc="Phase c terminal potential")

    def equations(self):
        th = self.theta
        hall = [ca.if_else(0 < ca.sin(th - edge), 1, 0) for edge in HALL_EDGES]
        currents = [self.i_a, self.i_b, self.i_c]
        terminals = [self.u_a, self.u_b, self.u_c]
        shapes = [trapezoid(th - k * TWO_PI_3) for k in range(3)]
        emfs = [self.k_e * self.w * f for f in shapes]
        g_on, g_off, g_d = 1 / self.R_on, self.G_off, 1 / self.R_d
        eqs = []
        for k in range(3):
            h_k, h_next = hall[k], hall[(k + 1) % 3]
            high = h_k * (1 - h_next)
            low = (1 - h_k) * h_next
            on_h = high * self.pwm
            on_l = low + high * (1 - self.pwm)
            gh = on_h * g_on + (1 - on_h) * g_off
            gl = on_l * g_on + (1 - on_l) * g_off
            i_k, vp = currents[k], self.V_p
            u0 = (gh * vp - i_k) / (gh + gl)
            u_up = (gh * vp + (vp + self.V_f) * g_d - i_k) / (gh + gl + g_d)
            u_dn = (gh * vp - i_k - self.V_f * g_d) / (gh + gl + g_d)
            u = ca.if_else(vp + self.V_f < u0, u_up, ca.if_else(u0 < -self.V_f, u_dn, u0))
            eqs.append(terminals[k] == u)
        e = self.w_ref - self.w
        u_pi = self.K_p * e + self.x
        frac = (th - HALL_EDGES[0]) / (2 * ca.pi)
        return eqs + [
            self.i_c == -(self.i_a + self.i_b),
            self.v_n == (sum(terminals) - sum(emfs)) / 3,
            self.L * mt.der(self.i_a) == self.u_a - self.v_n - self.R * self.i_a - emfs[0],
            self.L * mt.der(self.i_b) == self.u_b - self.v_n - self.R * self.i_b - emfs[1],
            self.T == self.k_e * sum(f * i for f, i in zip(shapes, currents)),
            mt.der(self.theta) == self.w,
            self.J * mt.der(self.w) == self.T - self.B * self.w - self.T_load,
            self.d == ca.fmin(ca.fmax(u_pi, 0), self.d_max),
            mt.der(self.x) == self.K_i * e + self.K_aw * (self.d - u_pi),
            self.sector == 1 + ca.floor(6 * (frac - ca.floor(frac)))]


class BLDCDriveEquation(_BLDCEquations):
    """``equation`` variant, averaged PWM: ``V_p = d V_dc``, the high side always on."""

    def equations(self):
        return [self.V_p == self.d * self.V_dc, self.pwm == 1]


class BLDCDriveEquationPWM(_BLDCEquations):
    """``equation`` variant, switched PWM: ``V_p = V_dc`` and the centre-aligned PWM
    signal ``pwm = (cos(2 pi f_pwm t) > cos(pi d))``."""

    f_pwm = mt.Parameter("Hz", default=8e3, min=0, doc="PWM (carrier) frequency")

    def equations(self):
        return [self.V_p == self.V_dc,
                self.pwm == ca.if_else(ca.cos(ca.pi * self.d)
                                       < ca.cos(2 * ca.pi * self.f_pwm * self.time), 1, 0)]

    def time_scales(self):
        return [0.5 / self.f_pwm]


def build_equation(f_pwm, **values):
    """The drive as equations (see :class:`_BLDCEquations`)."""
    if f_pwm > 0:
        model = BLDCDriveEquationPWM(f_pwm=f_pwm, **values)
    else:
        model = BLDCDriveEquation(**values)
    model._name = "bldc_motor"
    return model


def _check(values):
    if values["f_pwm"] < 0:
        raise ModelError(f"model 'bldc_motor': f_pwm must be >= 0 (0: averaged PWM), got "
                         f"{values['f_pwm']!r}. Give a switching frequency such as "
                         "'8 kHz', or 0.", path="bldc_motor")
    return values


def _acausal(**values):
    return build_acausal(**_check(values))


def _equation(**values):
    return build_equation(**_check(values))


def _inputs(**values):
    return build_acausal(**_check(values), inputs=True)


FET = "chosen: a 40 V logic-level MOSFET class"
_PARAMS = {
    "V_dc": ParameterInfo("V", 24.0, "DC supply voltage", CHOSEN),
    "R": ParameterInfo("Ohm", 0.5, "Phase resistance", CHOSEN),
    "L": ParameterInfo("H", 1e-3, "Phase inductance", CHOSEN),
    "k_e": ParameterInfo("V*s/rad", 0.05, "Back-EMF constant per phase (peak e/w); the "
                         "torque constant is 2 k_e", CHOSEN),
    "J": ParameterInfo("kg*m^2", 1e-4, "Rotor and load inertia (rotor 1e-5, load 9e-5)",
                       CHOSEN),
    "B": ParameterInfo("N*m*s/rad", 1e-5, "Viscous friction", CHOSEN),
    "T_load": ParameterInfo("N*m", 0.05, "Constant load torque (from t = 0)", CHOSEN),
    "w_ref": ParameterInfo("rad/s", 150.0, "Speed reference (step at t = 0)", CHOSEN),
    "K_p": ParameterInfo("s/rad", 0.005, "Speed PI proportional gain (duty per rad/s)",
                         DESIGN + " (2 % settling in about 40 ms, no overshoot, on the "
                         "averaged DC-motor equivalent)"),
    "K_i": ParameterInfo("1/rad", 0.5, "Speed PI integral gain", DESIGN),
    "K_aw": ParameterInfo("1/s", 50.0, "Anti-windup back-calculation gain", DESIGN),
    "d_max": ParameterInfo("1", 0.95, "Largest duty cycle (bootstrap gate drivers need "
                           "an off time)", DESIGN),
    "R_on": ParameterInfo("Ohm", 0.01, "MOSFET on-resistance", FET),
    "G_off": ParameterInfo("S", 1e-3, "MOSFET off-conductance: large for a real part; "
                           "it sets the floating phase's time constant 4 L G_off (4 us), "
                           "which limits the explicit integrator's step", FET),
    "V_f": ParameterInfo("V", 0.8, "Body-diode forward voltage", FET),
    "R_d": ParameterInfo("Ohm", 0.01, "Body-diode on-resistance", FET),
    "f_pwm": ParameterInfo("Hz", 0.0, "PWM frequency; 0 selects averaged PWM (duty-"
                           "weighted DC link), > 0 switched PWM with synchronous "
                           "rectification (e.g. 8 kHz; about 2 f_pwm events per second)",
                           CHOSEN),
}

_OUTPUTS = {
    "acausal": {"sector": "hall.sector", "w": "motor.inertia.w", "i_a": "motor.airgap.i_a",
                "i_b": "motor.airgap.i_b", "i_c": "motor.airgap.i_c", "T": "motor.airgap.T",
                "d": "controller.d"},
    "equation": {"sector": "sector", "w": "w", "i_a": "i_a", "i_b": "i_b", "i_c": "i_c",
                 "T": "T", "d": "d"},
    "inputs": {"sector": "hall.sector", "w": "motor.inertia.w", "i_a": "motor.airgap.i_a",
               "i_b": "motor.airgap.i_b", "i_c": "motor.airgap.i_c", "T": "motor.airgap.T",
               "d": "d"},
}

ENTRY = register(ModelEntry(
    name="bldc_motor",
    description=("Brushless DC motor: three-phase star winding with trapezoidal back EMF, "
                 "six-MOSFET inverter with body diodes on a DC supply, three Hall sensors, "
                 "six-step commutation, PI speed control with (averaged or switched) PWM, "
                 "constant load torque."),
    parameters=_PARAMS,
    variants={"acausal": _acausal, "equation": _equation, "inputs": _inputs},
    driven_variants=("inputs",),
    outputs=_OUTPUTS,
    output_units={"sector": "1", "w": "rad/s", "i_a": "A", "i_b": "A", "i_c": "A",
                  "T": "N*m", "d": "1"},
    # explicit Runge-Kutta (the auto choice for ODEs with events); its step is limited
    # by the floating phase's 4 us time constant, not by the tolerance
    experiment=Experiment(t_stop=0.1, rtol=1e-8, atol=1e-10),
    expected={"w": 150.0},
    # the speed is the reference up to the commutation ripple (< 0.1 %)
    expected_tolerance=2e-3,
    variant_tolerance=1e-5,
    tags=("motor", "electromechanical", "power electronics", "control", "BLDC", "events"),
))
