"""A solenoid actuator whose iron saturates: a coil on a steel yoke pulls a plunger across
a cylindrical working gap against a return spring, onto a non-magnetic stop.

The magnetic circuit, from library flux tubes: the coil (``ElectromagneticConverter``,
``N`` turns, resistance ``R``) drives flux through the steel yoke and plunger
(``SaturatingReluctance`` of free-cutting steel 9SMnPb28 after MSL's material data,
length ``l_fe``, section ``A``) and the working gap (``HollowCylinderAxialFluxForce``,
solid, radius ``r``, length ``x``: the plunger's travel), with a leakage path around the
gap (``Leakage``, quarter cylinder of length ``l_leak``) in parallel to it. The gap's
reluctance force pulls the plunger (``Mass``, with MSL's ``s``) against the return spring
(``SpringDamper``, relaxed at the open gap ``x0``) onto the stop (``ElastoGap`` at the
residual gap ``x_min``, a shim). ``V`` is switched on at ``t = 0``.

Equations (``U`` the gap's mmf, ``phi_g = mu0 A U / x`` and ``phi_l = G_l U`` the gap
and leakage fluxes)::

    N dphi/dt = V - R i,      phi = phi_g + phi_l
    N i = H_fe(phi / A) l_fe + U,   H_fe(B) = B / (mu0 mu_r(B))   (mu_r: MSL's approximation)
    m dv/dt = -mu0 A U^2 / (2 x^2) + c (x0 - x) + F_stop(x) - d v,   dx/dt = v

At rest against the stop (:func:`final_state`, no simulation): ``i = V/R`` and the pull
balances the spring and the stop's penetration ``x_min - x``. With ``N V / R = 2400 A``
the steel runs at about 1.94 T, far beyond its permeability peak (1.49 T), and pulls
153 N: a linear yoke of the initial permeability (400) would promise about 1.7 kN.

Variants: ``acausal`` (the library parts above) and ``equation`` (the equations above as
one user component, :class:`SolenoidEquations`: the flux as the state instead of the
tubes' network).
"""

from __future__ import annotations

import math

import casadi as ca
from scipy.optimize import brentq

import mechatron as mt
from mechatron.library import electrical as el
from mechatron.library import magnetic as mag
from mechatron.library import translational as tr
from mechatron.library.magnetic import MU0, SOFT_MAGNETIC
from mechatron.library.rotational.compliant import limited_contact
from mechatron.models.entry import Experiment, ModelEntry, ParameterInfo
from mechatron.models.registry import register

__all__ = ["build_acausal", "SolenoidEquations", "final_state", "ENTRY"]

CHOSEN = "chosen: a 24 V pull solenoid, plunger 12 mm diameter"
MATERIAL = "Steel_9SMnPb28"
LEAK_K = 0.52                       # quarter-cylinder leakage permeance per mu0 and metre


def build_acausal(V, R, N, l_fe, r, l_leak, x0, x_min, m, c, d, c_stop, d_stop):
    """The actuator as a network of library parts."""
    area = math.pi * r ** 2
    s = mt.System("saturating_solenoid", doc="Coil, saturating yoke, moving gap, plunger")
    s.add("supply", el.DCVoltageSource(V=V))
    s.add("r_coil", el.Resistor(R=R))
    s.add("coil", mag.ElectromagneticConverter(N=N))
    s.add("ground", el.ElectricalReference())
    s.add("iron", mag.SaturatingReluctance(material=MATERIAL, l=l_fe, area=area))
    s.add("gap", mag.HollowCylinderAxialFluxForce(r_o=r, x=x0))
    s.add("leak", mag.Leakage(shape="quarter_cylinder", l=l_leak))
    s.add("mref", mag.MagneticReference())
    s.add("plunger", tr.Mass(m=m, v=0.0, s=x0))
    s.add("spring", tr.SpringDamper(c=c, d=d, s_rel0=x0, s_rel=x0))
    s.add("stop", tr.ElastoGap(c=c_stop, d=d_stop, s_rel0=x_min, s_rel=x0))
    s.add("case", tr.TranslationalReference())
    s.connect(s.supply.p, s.r_coil.p)
    s.connect(s.r_coil.n, s.coil.p)
    s.connect(s.coil.n, s.supply.n, s.ground.port)
    s.connect(s.coil.B, s.iron.A)
    s.connect(s.iron.B, s.gap.A, s.leak.A)
    s.connect(s.gap.B, s.leak.B, s.coil.A, s.mref.port)
    s.connect(s.gap.rod, s.plunger.port, s.spring.B, s.stop.B)
    s.connect(s.gap.case, s.spring.A, s.stop.A, s.case.port)
    return s


class SolenoidEquations(mt.Component):
    """The actuator as its equations (the ``equation`` variant): the coil's flux ``phi``
    (through the steel, gap plus leakage), the gap ``x`` and the plunger speed ``v`` as
    states; the gap's mmf and the current explicit in them::

        U == phi / (mu0 A / x + mu0 0.52 l_leak),   N i == H_fe(phi / A) l_fe + U
        N dphi/dt == V - R i
        m dv/dt == -mu0 A U^2 / (2 x^2) + c (x0 - x) - d v + F_stop,   dx/dt == v

    with ``F_stop`` MSL's limited contact law at the penetration ``x_min - x``.
    """

    V = mt.Parameter("V", default=24.0, doc="Supply voltage")
    R = mt.Parameter("Ohm", default=10.0, min=0, doc="Coil resistance")
    N = mt.Parameter("1", default=1000.0, min=0, doc="Coil turns")
    l_fe = mt.Parameter("m", default=0.08, min=0, doc="Flux path length in steel")
    r = mt.Parameter("m", default=0.006, min=0, doc="Plunger radius")
    l_leak = mt.Parameter("m", default=0.038, min=0, doc="Leakage path length")
    x0 = mt.Parameter("m", default=3e-3, min=0, doc="Open gap")
    x_min = mt.Parameter("m", default=3e-4, min=0, doc="Residual gap at the stop")
    m = mt.Parameter("kg", default=0.02, min=0, doc="Plunger mass")
    c = mt.Parameter("N/m", default=2000.0, min=0, doc="Return spring rate")
    d = mt.Parameter("N*s/m", default=2.0, min=0, doc="Plunger friction")
    c_stop = mt.Parameter("N/m", default=1e7, min=0, doc="Stop stiffness")
    d_stop = mt.Parameter("N*s/m", default=200.0, min=0, doc="Stop damping")
    mu0 = mt.Parameter("H/m", default=MU0, min=0, doc="Vacuum permeability")
    B_max = mt.Parameter("T", default=SOFT_MAGNETIC[MATERIAL].B_max, min=0,
                         doc="Flux density of the steel's largest permeability")
    phi = mt.Variable("Wb", start=0.0, doc="Flux through the coil and the steel")
    x = mt.Variable("m", doc="Gap")
    v = mt.Variable("m/s", start=0.0, doc="Plunger speed, opening the gap")
    U = mt.Variable("A", doc="Magnetomotive force across the gap")
    i = mt.Variable("A", doc="Coil current")
    phi_g = mt.Variable("Wb", doc="Flux across the gap")
    B_fe = mt.Variable("T", doc="Flux density in the steel")
    mu_r = mt.Variable("1", doc="Relative permeability of the steel")
    F = mt.Variable("N", doc="Reluctance force on the plunger, opening")

    def equations(self):
        mat = SOFT_MAGNETIC[MATERIAL]
        area = ca.pi * self.r ** 2
        G_g = self.mu0 * area / self.x
        b_n = ca.fabs(self.B_fe) / self.B_max
        return [self.B_fe == self.phi / area,
                self.mu_r == 1 + (mat.mu_i - 1 + mat.c_a * b_n)
                / (1 + mat.c_b * b_n + b_n ** mat.n),
                self.U == self.phi / (G_g + self.mu0 * LEAK_K * self.l_leak),
                self.phi_g == G_g * self.U,
                self.N * self.i == self.B_fe / (self.mu0 * self.mu_r) * self.l_fe + self.U,
                self.N * mt.der(self.phi) == self.V - self.R * self.i,
                self.F == -self.mu0 * area * self.U ** 2 / (2 * self.x ** 2),
                mt.der(self.x) == self.v,
                self.m * mt.der(self.v) == self.F + self.c * (self.x0 - self.x)
                - self.d * self.v
                + limited_contact(self.x_min - self.x, -self.v, self.c_stop, self.d_stop)]


def _equation(**values):
    model = SolenoidEquations(**values, x=mt.Start(values["x0"], "high"))
    model._name = "saturating_solenoid"
    return model


def final_state(V, R, N, l_fe, r, l_leak, x0, x_min, c, c_stop, **_):
    """Rest against the stop, from the static balance alone: current, gap, gap flux,
    flux density in the steel and the pull."""
    mat = SOFT_MAGNETIC[MATERIAL]
    area = math.pi * r ** 2
    i = V / R

    def gap_mmf(x):         # Ampere's law around the circuit, solved for the gap's mmf
        def residual(U):
            phi = U * (MU0 * area / x + MU0 * LEAK_K * l_leak)
            B = phi / area
            return B / (MU0 * mat.mu_r(B)) * l_fe + U - N * i
        return brentq(residual, 0.0, N * i, xtol=1e-13, rtol=1e-15)

    def pull(x):
        return MU0 * area * gap_mmf(x) ** 2 / (2 * x ** 2)

    x = brentq(lambda x: pull(x) - c * (x0 - x) - c_stop * (x_min - x),
               x_min * 0.5, x_min, xtol=1e-16, rtol=1e-15)
    U = gap_mmf(x)
    phi_g = MU0 * area * U / x
    B_fe = (phi_g + MU0 * LEAK_K * l_leak * U) / area
    return {"i": i, "x": x, "phi": phi_g, "B_fe": B_fe, "F": -pull(x)}


_PARAMS = {
    "V": ParameterInfo("V", 24.0, "Supply voltage (switched on at t = 0)", CHOSEN),
    "R": ParameterInfo("Ohm", 10.0, "Coil resistance", CHOSEN),
    "N": ParameterInfo("1", 1000.0, "Coil turns", CHOSEN),
    "l_fe": ParameterInfo("m", 0.08, "Length of the flux path in steel (yoke and "
                          "plunger)", CHOSEN),
    "r": ParameterInfo("m", 0.006, "Plunger radius (gap and steel section pi r^2)", CHOSEN),
    "l_leak": ParameterInfo("m", 0.038, "Length of the leakage path around the gap "
                            "(the plunger's circumference)", CHOSEN),
    "x0": ParameterInfo("m", 3e-3, "Open gap (spring relaxed)", CHOSEN),
    "x_min": ParameterInfo("m", 3e-4, "Residual gap at the stop (non-magnetic shim)",
                           CHOSEN),
    "m": ParameterInfo("kg", 0.02, "Plunger mass", CHOSEN),
    "c": ParameterInfo("N/m", 2000.0, "Return spring rate", CHOSEN),
    "d": ParameterInfo("N*s/m", 2.0, "Viscous friction of the plunger", CHOSEN),
    "c_stop": ParameterInfo("N/m", 1e7, "Stop stiffness", CHOSEN),
    "d_stop": ParameterInfo("N*s/m", 200.0, "Stop damping (limited as MSL's ElastoGap)",
                            CHOSEN),
}

_FINAL = final_state(**{k: p.default for k, p in _PARAMS.items()})

ENTRY = register(ModelEntry(
    name="saturating_solenoid",
    description=("Pull solenoid with a saturating steel yoke (MSL's material "
                 "approximation), a moving cylindrical gap with its reluctance force, "
                 "leakage, a return spring and an elastic stop."),
    parameters=_PARAMS,
    variants={"acausal": build_acausal, "equation": _equation},
    outputs={"acausal": {"i": "r_coil.i", "x": "gap.x", "phi": "gap.phi",
                         "B_fe": "iron.B_flux", "F": "gap.F"},
             "equation": {"i": "i", "x": "x", "phi": "phi_g", "B_fe": "B_fe", "F": "F"}},
    output_units={"i": "A", "x": "m", "phi": "Wb", "B_fe": "T", "F": "N"},
    experiment=Experiment(t_stop=0.2, rtol=1e-9, atol=1e-12),
    expected=_FINAL,
    expected_tolerance=1e-6,
    variant_tolerance=1e-6,
    tags=("actuator", "magnetic", "saturation", "electromechanical", "contact",
          "issue 18"),
))
