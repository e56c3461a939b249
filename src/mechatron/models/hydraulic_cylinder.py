"""Valve-controlled hydraulic cylinder: a constant-pressure supply feeds a double-acting
cylinder through a 4-way directional valve; the cylinder moves a mass against a weight.

The supply keeps ``P_s`` over the tank; the critically centred 4-way valve opens P->A and
B->T for a positive spool ``x_v``, P->B and A->T for a negative one, each path a
sharp-edged orifice of area ``A_max |x_v| / x_max`` (closed paths leak through
``A_leak``). The spool steps from ``+x_s`` to ``-x_s`` at ``t_rev``: the cylinder extends,
then retracts. Cap-side area ``area_A``, rod-side annulus ``area_B``; the load is a mass
``M`` with viscous friction ``b`` and a constant weight ``F_L`` pulling the rod in.

Equations (chamber volumes ``V_A = V_dead + area_A x``, ``V_B = V_dead + area_B (stroke -
x)``, flows from :func:`~mechatron.library.hydraulic.orifice_flow`)::

    (V_A / beta) dp_A/dt = q_PA - q_AT - area_A v
    (V_B / beta) dp_B/dt = q_PB - q_BT + area_B v
    M dv/dt = p_A area_A - p_B area_B - b v - F_L,   dx/dt = v

In the steady motion the chambers no longer compress: ``q_PA - q_AT = area_A v``,
``q_BT - q_PB = area_B v`` and the force balance holds with ``dv/dt = 0``; with the
turbulent orifice law these are three algebraic equations in ``(v, p_A, p_B)``, solved by
:func:`steady_motion` with SciPy, independently of the simulation.

Variants: ``acausal`` (library parts) and ``equation`` (the four ODEs above).
"""

from __future__ import annotations

import math

import casadi as ca
from scipy.optimize import fsolve

import mechatron as mt
from mechatron.errors import ParameterError
from mechatron.library import blocks
from mechatron.library import hydraulic as hy
from mechatron.library import translational as tr
from mechatron.library.hydraulic import ISO_VG32, orifice_flow
from mechatron.models.entry import Experiment, ModelEntry, ParameterInfo
from mechatron.models.registry import register

__all__ = ["HydraulicCylinderAcausal", "HydraulicCylinderEquation", "steady_motion"]

CYL = "ISO 3320 cylinder, 50 mm bore, 28 mm rod"
CHOSEN = "chosen: a small industrial axis"
VALVE = "chosen: a NG6 proportional valve, 10 mm^2 per path at full opening"
CD = 0.7          # discharge coefficient of the valve's paths (library default)
RE_CR = 12.0      # critical Reynolds number of the laminar transition (library default)
A_LEAK = 1e-12    # leakage area of a closed path, m^2 (library default)


def steady_motion(P_s, x_s, x_max, A_max, area_A, area_B, M, b, F_L, rho=ISO_VG32.rho,
                  nu=ISO_VG32.nu, direction=1.0) -> dict:
    """Steady piston speed and chamber pressures with the spool held at ``direction *
    x_s``: the orifice equations of the four valve paths (the open ones turbulent,
    ``q = Cd a sqrt(2 dp / rho)``, the closed ones leaking laminarly) and the force
    balance, solved with ``scipy.optimize.fsolve``."""
    a_open = A_LEAK + (A_max - A_LEAK) * min(x_s / x_max, 1.0)

    def q(area, dp):
        # turbulent above the transition pressure p_cr, laminar below it: the nearly
        # closed paths (leakage, D_h ~ 1 um) are laminar, the open ones turbulent
        p_cr = rho / 2 * (RE_CR * nu / (CD * math.sqrt(4 * area / math.pi))) ** 2
        return CD * area * math.sqrt(2 / rho) * dp / (dp * dp + p_cr * p_cr) ** 0.25

    if direction > 0:
        a_pa, a_bt, a_pb, a_at = a_open, a_open, A_LEAK, A_LEAK
    else:
        a_pa, a_bt, a_pb, a_at = A_LEAK, A_LEAK, a_open, a_open

    def residual(z):
        v, pa, pb = z[0], z[1] * P_s, z[2] * P_s
        return [(q(a_pa, P_s - pa) - q(a_at, pa) - area_A * v) / (a_open * 10),
                (q(a_pb, P_s - pb) - q(a_bt, pb) + area_B * v) / (a_open * 10),
                (pa * area_A - pb * area_B - b * v - F_L) / (P_s * area_A)]

    # a guess from the ideal valve: the loaded side near supply, the other near tank
    guess = [0.1 * direction, 0.6, 0.3] if direction > 0 else [-0.1, 0.2, 0.7]
    sol = fsolve(residual, guess, xtol=1e-13)
    if max(abs(r) for r in residual(sol)) > 1e-12:
        raise ParameterError(f"hydraulic_cylinder: the flow balance with the spool at "
                             f"{direction * x_s:g} m did not converge (residual "
                             f"{residual(sol)}). Check that the spool opening x_s > 0 and "
                             f"the areas and pressures are positive.",
                             path="hydraulic_cylinder")
    return {"v": float(sol[0]), "p_A": float(sol[1] * P_s), "p_B": float(sol[2] * P_s)}


class HydraulicCylinderAcausal(mt.Component):
    """Supply, 4-way valve, double-acting cylinder, load mass, friction and weight."""

    tank = hy.Reservoir(doc="Tank at atmospheric pressure")
    supply = hy.PressureSource(doc="Constant-pressure supply (pump and relief valve)")
    valve = hy.FourWayDirectionalValve(doc="4-way, 3-position directional valve")
    spool = blocks.Step(doc="Spool command: +x_s, then -x_s from t_rev")
    cylinder = hy.DoubleActingCylinder(doc="Double-acting cylinder")
    load = tr.Mass(doc="Load (piston, rod and payload)")
    friction = tr.TranslationalDamper(doc="Viscous friction of seals and guide")
    weight = tr.ConstantForce(doc="Weight of the payload, pulling the rod in")
    frame = tr.TranslationalReference()

    def equations(self):
        return [mt.connect(self.tank.port, self.supply.A, self.valve.T),
                mt.connect(self.supply.B, self.valve.P),
                mt.connect(self.valve.A, self.cylinder.A),
                mt.connect(self.valve.B, self.cylinder.B),
                mt.connect(self.spool.y, self.valve.x),
                mt.connect(self.cylinder.rod, self.load.port, self.friction.A,
                           self.weight.A),
                mt.connect(self.cylinder.case, self.friction.B, self.weight.B,
                           self.frame.port)]


class HydraulicCylinderEquation(mt.Component):
    """The same axis as four ODEs: the two chamber pressures, the speed and the
    position."""

    P_s = mt.Parameter("Pa", default=1e7, doc="Supply pressure")
    x_s = mt.Parameter("m", default=2e-4, doc="Spool opening")
    t_rev = mt.Parameter("s", default=0.25, doc="Time the spool reverses")
    x_max = mt.Parameter("m", default=1e-3, min=0, doc="Spool stroke of full opening")
    A_max = mt.Parameter("m^2", default=1e-5, min=0, doc="Area of a fully open path")
    area_A = mt.Parameter("m^2", default=1.9635e-3, min=0, doc="Cap-side piston area")
    area_B = mt.Parameter("m^2", default=1.3477e-3, min=0, doc="Rod-side annulus area")
    stroke = mt.Parameter("m", default=0.2, min=0, doc="Stroke")
    V_dead = mt.Parameter("m^3", default=2e-5, min=0, doc="Dead volume of each chamber")
    M = mt.Parameter("kg", default=50.0, min=0, doc="Load mass")
    b = mt.Parameter("N*s/m", default=2000.0, min=0, doc="Viscous friction")
    F_L = mt.Parameter("N", default=490.5, doc="Weight pulling the rod in")
    rho = mt.Parameter("kg/m^3", default=ISO_VG32.rho, min=0, doc="Fluid density")
    nu = mt.Parameter("m^2/s", default=ISO_VG32.nu, min=0, doc="Kinematic viscosity")
    beta = mt.Parameter("Pa", default=ISO_VG32.beta, min=0, doc="Bulk modulus")
    x = mt.Variable("m", start=0.1, doc="Piston position from full retraction")
    v = mt.Variable("m/s", start=0.0, doc="Piston speed")
    p_A = mt.Variable("Pa", start=0.0, doc="Cap-side pressure")
    p_B = mt.Variable("Pa", start=0.0, doc="Rod-side pressure")
    x_v = mt.Variable("m", doc="Spool position")

    def equations(self):
        s = self.x_v / self.x_max

        def area(u):
            return A_LEAK + (self.A_max - A_LEAK) * ca.fmin(ca.fmax(u, 0), 1)

        def q(a, dp):
            return orifice_flow(a, dp, CD, self.rho, self.nu, RE_CR)

        q_pa, q_bt = q(area(s), self.P_s - self.p_A), q(area(s), self.p_B)
        q_pb, q_at = q(area(-s), self.P_s - self.p_B), q(area(-s), self.p_A)
        V_A = self.V_dead + self.area_A * self.x
        V_B = self.V_dead + self.area_B * (self.stroke - self.x)
        return [self.x_v == ca.if_else(self.t_rev <= self.time, -self.x_s, self.x_s),
                V_A / self.beta * mt.der(self.p_A) == q_pa - q_at - self.area_A * self.v,
                V_B / self.beta * mt.der(self.p_B) == q_pb - q_bt + self.area_B * self.v,
                mt.der(self.x) == self.v,
                self.M * mt.der(self.v) == self.p_A * self.area_A - self.p_B * self.area_B
                - self.b * self.v - self.F_L]


def _acausal(P_s, x_s, t_rev, x_max, A_max, area_A, area_B, stroke, V_dead, M, b, F_L,
             x0):
    model = HydraulicCylinderAcausal(doc="valve-controlled cylinder, acausal network")
    model._name = "hydraulic_cylinder"
    model.supply._values["P"] = P_s
    model.valve._values.update(x_max=x_max, A_max=A_max, A_leak=A_LEAK, Cd=CD, Re_cr=RE_CR)
    model.spool._values.update(t_step=t_rev, initial=x_s, final=-x_s)
    model.cylinder._values.update(area_A=area_A, area_B=area_B, stroke=stroke,
                                  V_dead=V_dead)
    model.cylinder._set("x", x0)
    model.load._values["m"] = M
    model.load._set("v", 0.0)
    model.friction._values["b"] = b
    model.weight._values["F"] = -F_L          # pulls the rod in (towards -x)
    return model


def _equation(x0, **values):
    model = HydraulicCylinderEquation(**values, x=x0, v=0.0)
    model._name = "hydraulic_cylinder"
    return model


_PARAMS = {
    "P_s": ParameterInfo("Pa", 1e7, "Supply pressure (100 bar)", CHOSEN),
    "x_s": ParameterInfo("m", 2e-4, "Spool opening (20 % of the full stroke)", CHOSEN),
    "t_rev": ParameterInfo("s", 0.25, "Time the spool reverses", CHOSEN),
    "x_max": ParameterInfo("m", 1e-3, "Spool stroke of full opening", VALVE),
    "A_max": ParameterInfo("m^2", 1e-5, "Area of a fully open valve path", VALVE),
    "area_A": ParameterInfo("m^2", math.pi / 4 * 0.05 ** 2, "Cap-side piston area", CYL),
    "area_B": ParameterInfo("m^2", math.pi / 4 * (0.05 ** 2 - 0.028 ** 2),
                            "Rod-side annulus area", CYL),
    "stroke": ParameterInfo("m", 0.2, "Piston stroke", CYL),
    "V_dead": ParameterInfo("m^3", 2e-5, "Dead volume of each chamber with its hose",
                            CHOSEN),
    "M": ParameterInfo("kg", 50.0, "Moving mass (piston, rod and payload)", CHOSEN),
    "b": ParameterInfo("N*s/m", 2000.0, "Viscous friction of seals and guide", CHOSEN),
    "F_L": ParameterInfo("N", 50.0 * 9.81, "Weight of the payload, pulling the rod in",
                         "50 kg under standard gravity"),
    "x0": ParameterInfo("m", 0.1, "Initial piston position (mid-stroke)", CHOSEN),
}
_D = {key: info.default for key, info in _PARAMS.items()}
_RETRACT = steady_motion(_D["P_s"], _D["x_s"], _D["x_max"], _D["A_max"], _D["area_A"],
                         _D["area_B"], _D["M"], _D["b"], _D["F_L"], direction=-1.0)

ENTRY = register(ModelEntry(
    name="hydraulic_cylinder",
    description=("Valve-controlled hydraulic cylinder: a 100 bar supply drives a "
                 "double-acting cylinder and a 50 kg load through a 4-way directional "
                 "valve whose spool reverses; hydraulic and translational domains."),
    parameters=_PARAMS,
    variants={"acausal": _acausal, "equation": _equation},
    outputs={"acausal": {"x": "cylinder.x", "v": "load.v", "p_A": "cylinder.A.p",
                         "p_B": "cylinder.B.p"},
             "equation": {"x": "x", "v": "v", "p_A": "p_A", "p_B": "p_B"}},
    output_units={"x": "m", "v": "m/s", "p_A": "Pa", "p_B": "Pa"},
    experiment=Experiment(t_stop=0.5, rtol=1e-8, atol=1e-10),
    expected={"v": _RETRACT["v"], "p_A": _RETRACT["p_A"], "p_B": _RETRACT["p_B"]},
    expected_tolerance=1e-5, variant_tolerance=1e-5,
    tags=("hydraulic", "translational", "valve", "actuator"),
))
