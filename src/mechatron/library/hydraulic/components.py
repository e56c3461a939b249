"""Hydraulic (isothermal liquid) components: restrictions, volumes, actuators, machines,
valves, accumulators."""

import math

import casadi as ca

from mechatron.core import Component, Input, Parameter, Variable, der, if_else
from mechatron.library.hydraulic.interfaces import ISO_VG32, HydraulicPort, TwoPort
from mechatron.library.rotational.interfaces import Flange as RotationalFlange
from mechatron.library.translational.interfaces import Flange as TranslationalFlange

__all__ = ["orifice_flow", "FixedOrifice", "VariableOrifice", "ResistivePipe",
           "CompressiblePipe", "ConstantVolumeChamber", "DoubleActingCylinder",
           "FixedDisplacementPump", "FixedDisplacementMotor", "CheckValve",
           "FourWayDirectionalValve", "GasChargedAccumulator", "SpringLoadedAccumulator"]


def _rho(doc="Fluid density"):
    return Parameter("kg/m^3", default=ISO_VG32.rho, min=0, doc=doc)


def _nu(doc="Fluid kinematic viscosity"):
    return Parameter("m^2/s", default=ISO_VG32.nu, min=0, doc=doc)


def _beta(doc="Fluid bulk modulus"):
    return Parameter("Pa", default=ISO_VG32.beta, min=0, doc=doc)


def orifice_flow(area, dp, Cd, rho, nu, Re_cr):
    """Flow through a sharp-edged orifice, turbulent with a laminar transition.

    ``q = Cd area sqrt(2/rho) dp / (dp^2 + p_cr^2)^(1/4)``, with the transition pressure
    ``p_cr = rho/2 (Re_cr nu / (Cd D_h))^2`` and ``D_h = sqrt(4 area / pi)``: for
    ``|dp| >> p_cr`` this is ``Cd area sqrt(2 |dp| / rho) sign(dp)``; for ``|dp| << p_cr``
    it is linear in ``dp`` (laminar), so the square root stays smooth through ``dp = 0``.
    """
    d_h = ca.sqrt(4 * area / math.pi)
    p_cr = rho / 2 * (Re_cr * nu / (Cd * d_h)) ** 2
    return Cd * area * ca.sqrt(2 / rho) * dp / (dp ** 2 + p_cr ** 2) ** 0.25


class FixedOrifice(TwoPort):
    """Sharp-edged orifice of constant area (Simscape: Fixed Orifice).

    Equations::

        q = Cd area sqrt(2/rho) dp / (dp^2 + p_cr^2)^(1/4)
        p_cr = rho/2 (Re_cr nu / (Cd D_h))^2,   D_h = sqrt(4 area / pi)

    Turbulent ``q = Cd area sqrt(2 dp / rho)`` well above ``p_cr``, laminar (linear)
    below it; flow goes from the higher to the lower pressure. Dissipates ``dp q >= 0``.
    Limitations: constant discharge coefficient; no cavitation or choking.
    """

    area = Parameter("m^2", default=1e-5, min=0, doc="Orifice area")
    Cd = Parameter("1", default=0.7, min=0, doc="Discharge coefficient")
    Re_cr = Parameter("1", default=12.0, min=0, doc="Critical Reynolds number")
    rho = _rho()
    nu = _nu()

    def equations(self):
        return [self.q == orifice_flow(self.area, self.dp, self.Cd, self.rho, self.nu,
                                       self.Re_cr)]


class VariableOrifice(TwoPort):
    """Orifice whose area is a signal (Simscape: Orifice with a variable area).

    Equations as :class:`FixedOrifice` with ``area = max(area_in, A_leak)``; the
    leakage area keeps the orifice from closing completely (and the equations regular).
    """

    area_in = Input("m^2", doc="Commanded opening area")
    A_leak = Parameter("m^2", default=1e-12, min=0, doc="Leakage area when closed")
    Cd = Parameter("1", default=0.7, min=0, doc="Discharge coefficient")
    Re_cr = Parameter("1", default=12.0, min=0, doc="Critical Reynolds number")
    rho = _rho()
    nu = _nu()

    def equations(self):
        area = if_else(self.area_in > self.A_leak, self.area_in, self.A_leak)
        return [self.q == orifice_flow(area, self.dp, self.Cd, self.rho, self.nu,
                                       self.Re_cr)]


class ResistivePipe(TwoPort):
    """Laminar pipe friction, Hagen-Poiseuille (Simscape: Hydraulic Resistive Tube).

    Equations: ``dp = 128 mu L q / (pi D^4)`` with ``mu = rho nu``. Dissipates ``dp q``.
    Limitations: fully developed laminar flow (Re = 4 q/(pi D nu) < 2300); no fluid
    inertia, no compressibility (see :class:`CompressiblePipe`).
    """

    length = Parameter("m", default=1.0, min=0, doc="Pipe length")
    D = Parameter("m", default=0.01, min=0, doc="Inner diameter")
    rho = _rho()
    nu = _nu()

    def equations(self):
        return [self.dp == 128 * self.rho * self.nu * self.length
                / (math.pi * self.D ** 4) * self.q]


class CompressiblePipe(Component):
    """Laminar pipe with its fluid volume lumped at the middle (a T-section).

    Equations, with ``R = 128 mu L / (pi D^4)``, ``V = pi D^2 L / 4``::

        A.p - p = (R/2) A.q
        p - B.p = -(R/2) B.q
        (V / beta) dp/dt = A.q + B.q

    ``A.q`` is the flow into the pipe at A, ``B.q`` into the pipe at B. Stores
    ``V p^2 / (2 beta)``; dissipates the Poiseuille losses of both halves. Limitations:
    one segment (chain several for wave effects), laminar, no fluid inertia.
    """

    A = HydraulicPort(doc="Port A")
    B = HydraulicPort(doc="Port B")
    length = Parameter("m", default=1.0, min=0, doc="Pipe length")
    D = Parameter("m", default=0.01, min=0, doc="Inner diameter")
    rho = _rho()
    nu = _nu()
    beta = _beta()
    p = Variable("Pa", start=0.0, doc="Pressure of the lumped volume at mid-length")

    def equations(self):
        R = 128 * self.rho * self.nu * self.length / (math.pi * self.D ** 4)
        V = math.pi * self.D ** 2 / 4 * self.length
        return [self.A.p - self.p == R / 2 * self.A.q,
                self.p - self.B.p == -R / 2 * self.B.q,
                V / self.beta * der(self.p) == self.A.q + self.B.q]


class ConstantVolumeChamber(Component):
    """Fixed volume of compressible liquid (Simscape: Constant Volume Hydraulic Chamber).

    Equations: ``p = port.p``, ``(V / beta) dp/dt = port.q``. Stores ``V p^2 / (2 beta)``
    (linear fluid). Limitations: constant bulk modulus (no entrained air), no cavitation.
    """

    port = HydraulicPort(doc="Inlet")
    V = Parameter("m^3", default=1e-4, min=0, doc="Chamber volume")
    beta = _beta()
    p = Variable("Pa", start=0.0, doc="Chamber pressure")

    def equations(self):
        return [self.p == self.port.p, self.V / self.beta * der(self.p) == self.port.q]


class DoubleActingCylinder(Component):
    """Double-acting hydraulic cylinder with compressible chambers (Simscape: Double-Acting
    Hydraulic Cylinder).

    Hydraulic ports ``A`` (cap side, pushes the rod out) and ``B`` (rod side);
    translational flanges ``rod`` and ``case``. The piston position ``x`` (0 at full
    retraction) obeys ``dx/dt = rod.v - case.v``.

    Equations::

        q_A = area_A dx/dt + (V_A / beta) dp_A/dt,   V_A = V_dead + area_A x
        q_B = -area_B dx/dt + (V_B / beta) dp_B/dt,  V_B = V_dead + area_B (stroke - x)
        F = p_A area_A - p_B area_B                  (force on the rod along +x)
        rod.f = -F,  case.f = F

    ``q_A``, ``q_B`` flow into the chambers. Power: ``p_A q_A + p_B q_B = F dx/dt +``
    the rate of the stored compression energy. Limitations: massless piston (connect a
    Mass to ``rod``), no end stops (``x`` must stay within [0, stroke]), no leakage or
    seal friction (add a TranslationalFriction).
    """

    A = HydraulicPort(doc="Cap-side chamber port")
    B = HydraulicPort(doc="Rod-side chamber port")
    rod = TranslationalFlange(doc="Rod (piston) flange")
    case = TranslationalFlange(doc="Cylinder case flange")
    area_A = Parameter("m^2", default=2e-3, min=0, doc="Piston area on the cap side")
    area_B = Parameter("m^2", default=1e-3, min=0, doc="Annulus area on the rod side")
    stroke = Parameter("m", default=0.2, min=0, doc="Piston stroke")
    V_dead = Parameter("m^3", default=1e-5, min=0, doc="Dead volume of each chamber")
    beta = _beta()
    x = Variable("m", start=0.0, doc="Piston position from full retraction")
    F = Variable("N", doc="Hydraulic force on the rod, positive extending")

    def equations(self):
        v = der(self.x)
        V_A = self.V_dead + self.area_A * self.x
        V_B = self.V_dead + self.area_B * (self.stroke - self.x)
        return [der(self.x) == self.rod.v - self.case.v,
                self.A.q == self.area_A * v + V_A / self.beta * der(self.A.p),
                self.B.q == -self.area_B * v + V_B / self.beta * der(self.B.p),
                self.F == self.A.p * self.area_A - self.B.p * self.area_B,
                self.rod.f == -self.F,
                self.rod.f + self.case.f == 0]


class _Machine(Component, partial=True):
    """Hydraulic ports ``A`` (inlet) and ``B`` (outlet); rotational ``shaft`` and
    ``case``; ``w = shaft.w - case.w``; ``q`` flows from A to B through the machine."""

    A = HydraulicPort(doc="Inlet (low pressure for a pump)")
    B = HydraulicPort(doc="Outlet (high pressure for a pump)")
    shaft = RotationalFlange(doc="Shaft")
    case = RotationalFlange(doc="Case (mounting)")
    D = Parameter("m^3/rad", default=1e-6, min=0, doc="Displacement per radian")
    k_leak = Parameter("m^3/(s*Pa)", default=0.0, min=0,
                       doc="Laminar leakage coefficient from B to A")
    w = Variable("rad/s", doc="Shaft speed relative to the case")
    q = Variable("m^3/s", doc="Flow from A to B through the machine")

    def equations(self):
        return [self.w == self.shaft.w - self.case.w,
                self.q == self.A.q,
                self.A.q + self.B.q == 0,
                self.shaft.tau + self.case.tau == 0]


class FixedDisplacementPump(_Machine):
    """Fixed-displacement pump (Simscape: Fixed-Displacement Pump).

    Equations, with the pressure rise ``dp = B.p - A.p``::

        q = D w - k_leak dp          (delivered from A to B)
        shaft.tau = D dp             (torque the drive must supply)

    Lossless for ``k_leak = 0`` (``dp q = shaft.tau w``); leakage dissipates
    ``k_leak dp^2``. Limitations: no mechanical friction, constant displacement.
    """

    dp = Variable("Pa", doc="Pressure rise, B.p - A.p")

    def equations(self):
        return [self.dp == self.B.p - self.A.p,
                self.q == self.D * self.w - self.k_leak * self.dp,
                self.shaft.tau == self.D * self.dp]


class FixedDisplacementMotor(_Machine):
    """Fixed-displacement hydraulic motor (Simscape: Fixed-Displacement Motor).

    Equations, with the pressure drop ``dp = A.p - B.p``::

        q = D w + k_leak dp          (flow from A to B, leakage bypassing the rotor)
        shaft.tau = -D dp            (the motor drives the load at the shaft)

    Power: ``dp q + shaft.tau w = k_leak dp^2 >= 0``. Limitations: no friction.
    """

    dp = Variable("Pa", doc="Pressure drop, A.p - B.p")

    def equations(self):
        return [self.dp == self.A.p - self.B.p,
                self.q == self.D * self.w + self.k_leak * self.dp,
                self.shaft.tau == -self.D * self.dp]


class CheckValve(TwoPort):
    """Check valve (Simscape: Check Valve): opens from A to B.

    The opening area rises linearly from ``A_leak`` at ``dp = p_crack`` to ``A_max`` at
    ``dp = p_open`` (``dp = A.p - B.p``) and the flow is that of :func:`orifice_flow`.
    The two corners of the area curve are events. Limitations: quasi-static poppet (no
    poppet dynamics, no hysteresis); ``p_open`` must exceed ``p_crack``.
    """

    A_max = Parameter("m^2", default=1e-5, min=0, doc="Area when fully open")
    A_leak = Parameter("m^2", default=1e-12, min=0, doc="Leakage area when closed")
    p_crack = Parameter("Pa", default=1e5, min=0, doc="Cracking pressure")
    p_open = Parameter("Pa", default=2e5, min=0, doc="Pressure difference of full opening")
    Cd = Parameter("1", default=0.7, min=0, doc="Discharge coefficient")
    Re_cr = Parameter("1", default=12.0, min=0, doc="Critical Reynolds number")
    rho = _rho()
    nu = _nu()
    area = Variable("m^2", doc="Opening area")

    def equations(self):
        s = (self.dp - self.p_crack) / (self.p_open - self.p_crack)
        frac = if_else(self.dp <= self.p_crack, 0, if_else(self.dp >= self.p_open, 1, s))
        return [self.area == self.A_leak + (self.A_max - self.A_leak) * frac,
                self.q == orifice_flow(self.area, self.dp, self.Cd, self.rho, self.nu,
                                       self.Re_cr)]


class FourWayDirectionalValve(Component):
    """Critically centred 4-way, 3-position directional valve driven by the spool
    displacement (Simscape: 4-Way Directional Valve).

    Ports ``P`` (supply), ``T`` (tank), ``A``, ``B``. For ``x > 0`` the paths P->A and
    B->T open, for ``x < 0`` the paths P->B and A->T; each path is an orifice of area
    ``A_leak + (A_max - A_leak) clip(+-x / x_max, 0, 1)`` (:func:`orifice_flow`).

    Equations: ``P.q = q_PA + q_PB``, ``A.q = q_AT - q_PA``, ``B.q = q_BT - q_PB``,
    ``T.q = -q_AT - q_BT``. Limitations: no spool dynamics (drive ``x`` with a filtered
    signal), no flow forces, zero overlap.
    """

    P = HydraulicPort(doc="Supply port")
    T = HydraulicPort(doc="Tank (return) port")
    A = HydraulicPort(doc="Actuator port A")
    B = HydraulicPort(doc="Actuator port B")
    x = Input("m", doc="Spool displacement")
    x_max = Parameter("m", default=1e-3, min=0, doc="Spool stroke of full opening")
    A_max = Parameter("m^2", default=1e-5, min=0, doc="Area of a fully open path")
    A_leak = Parameter("m^2", default=1e-12, min=0, doc="Leakage area of a closed path")
    Cd = Parameter("1", default=0.7, min=0, doc="Discharge coefficient")
    Re_cr = Parameter("1", default=12.0, min=0, doc="Critical Reynolds number")
    rho = _rho()
    nu = _nu()
    q_PA = Variable("m^3/s", doc="Flow from P to A")
    q_PB = Variable("m^3/s", doc="Flow from P to B")
    q_AT = Variable("m^3/s", doc="Flow from A to T")
    q_BT = Variable("m^3/s", doc="Flow from B to T")

    def _area(self, s):
        frac = if_else(s <= 0, 0, if_else(s >= 1, 1, s))
        return self.A_leak + (self.A_max - self.A_leak) * frac

    def equations(self):
        s = self.x / self.x_max
        a_pos, a_neg = self._area(s), self._area(-s)

        def flow(area, a, b):
            return orifice_flow(area, a.p - b.p, self.Cd, self.rho, self.nu, self.Re_cr)

        return [self.q_PA == flow(a_pos, self.P, self.A),
                self.q_BT == flow(a_pos, self.B, self.T),
                self.q_PB == flow(a_neg, self.P, self.B),
                self.q_AT == flow(a_neg, self.A, self.T),
                self.P.q == self.q_PA + self.q_PB,
                self.A.q == self.q_AT - self.q_PA,
                self.B.q == self.q_BT - self.q_PB,
                self.T.q == -self.q_AT - self.q_BT]


class GasChargedAccumulator(Component):
    """Gas-charged (bladder/piston) accumulator with a polytropic gas (Simscape:
    Gas-Charged Accumulator).

    Equations, with the liquid volume ``V`` (0 when empty) and absolute pressures::

        dV/dt = port.q
        (port.p + p_atm) (V_total - V)^n = (p_pr + p_atm) V_total^n

    Stores the gas compression energy ``int (p + p_atm) dV`` less the atmospheric work.
    Limitations: valid while ``p >= p_pr`` (``V >= 0``): below the precharge the real
    accumulator is empty and this model extrapolates the gas law; liquid compressibility
    and gas heat exchange are neglected (``n = 1`` isothermal, ``n = 1.4`` adiabatic).
    """

    port = HydraulicPort(doc="Liquid port")
    V_total = Parameter("m^3", default=1e-3, min=0, doc="Total (gas) volume")
    p_pr = Parameter("Pa", default=1e6, min=0, doc="Precharge pressure (gauge)")
    n = Parameter("1", default=1.4, min=1, doc="Polytropic exponent of the gas")
    p_atm = Parameter("Pa", default=101325.0, min=0, doc="Atmospheric pressure")
    V = Variable("m^3", start=0.0, doc="Liquid volume")

    def equations(self):
        ratio = self.V_total / (self.V_total - self.V)
        return [der(self.V) == self.port.q,
                self.port.p == (self.p_pr + self.p_atm) * ratio ** self.n - self.p_atm]


class SpringLoadedAccumulator(Component):
    """Spring-loaded piston accumulator (Simscape: Spring-Loaded Accumulator).

    Equations: ``dV/dt = port.q``, ``port.p = p_pr + k V / area^2`` (the piston of area
    ``area`` compresses a spring of rate ``k`` by ``V / area``). Stores
    ``p_pr V + k V^2 / (2 area^2)``. Limitations: valid for ``V >= 0`` (no end stops),
    massless piston.
    """

    port = HydraulicPort(doc="Liquid port")
    k = Parameter("N/m", default=1e5, min=0, doc="Spring rate")
    area = Parameter("m^2", default=2e-3, min=0, doc="Piston area")
    p_pr = Parameter("Pa", default=0.0, min=0, doc="Preload pressure")
    V = Variable("m^3", start=0.0, doc="Liquid volume")

    def equations(self):
        return [der(self.V) == self.port.q,
                self.port.p == self.p_pr + self.k * self.V / self.area ** 2]
