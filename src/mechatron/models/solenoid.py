"""Solenoid actuator: a coil on an iron circuit with a variable air gap pulls a plunger
against a return spring until it hits its end stop.

A voltage ``V`` is switched onto a coil of ``N`` turns and resistance ``R`` at ``t = 0``.
The magnetic circuit is the iron path (constant reluctance ``R_fe``) in series with the
working air gap ``x`` of pole area ``A`` (reluctance ``x / (mu0 A)``), so the coil's
inductance depends on the gap:

``R_m(x) = R_fe + x / (mu0 A)``,  ``L(x) = N^2 / R_m(x)``.

The plunger (mass ``m``, viscous friction ``b``) starts at rest at the open gap ``x0``,
where the return spring ``k`` is relaxed; the end stop (penalty contact of stiffness
``k_stop`` and damping ``d_stop``) keeps the gap above the residual gap ``x_min`` (a
non-magnetic shim). Equations, with ``i`` the coil current and ``v = dx/dt``::

    d(L(x) i)/dt = V - R i                               (Faraday + Kirchhoff)
    m dv/dt = F_mag + k (x0 - x) - b v + F_stop
    F_mag = (i^2 / 2) dL/dx = -(N i)^2 / (2 mu0 A R_m(x)^2)   (co-energy force, < 0:
                                                               it closes the gap)

Variants: ``acausal`` (library parts: Resistor, ElectromagneticConverter, Reluctance,
ReluctanceForceActuator, Mass, spring, damper, TranslationalHardStop) and ``equation``
(the three ODEs above in the current, with ``L(x) di/dt = V - R i - i v dL/dx``: a
different state and formulation).

Initial current slope: ``L(x0) di/dt = V``. Final state: ``i = V/R`` and the plunger at
rest against the stop, where the magnetic pull balances the spring and the penetration of
the stop; :func:`final_state` solves that static balance with no simulation.
"""

from __future__ import annotations

import casadi as ca
from scipy.optimize import brentq

import mechatron as mt
from mechatron.errors import ParameterError
from mechatron.library import electrical as el
from mechatron.library import magnetic as mag
from mechatron.library import translational as tr
from mechatron.library.magnetic import MU0
from mechatron.models.entry import Experiment, ModelEntry, ParameterInfo
from mechatron.models.registry import register

__all__ = ["SolenoidAcausal", "SolenoidEquation", "final_state", "pull_force",
           "inductance"]

CHOSEN = "chosen: a small 12 V DC solenoid"
IRON = "iron path 0.1 m long, mu_r about 2000, section 1 cm^2"


def inductance(x: float, N: float, A: float, R_fe: float) -> float:
    """Coil inductance ``N^2 / (R_fe + x / (mu0 A))`` at the gap ``x``, H."""
    return N ** 2 / (R_fe + x / (MU0 * A))


def pull_force(i: float, x: float, N: float, A: float, R_fe: float) -> float:
    """Magnitude of the magnetic pull at current ``i`` and gap ``x`` from the co-energy
    ``W'(i, x) = L(x) i^2 / 2``: ``|dW'/dx| = (N i)^2 / (2 mu0 A R_m(x)^2)``, N."""
    rm = R_fe + x / (MU0 * A)
    return (N * i) ** 2 / (2 * MU0 * A * rm ** 2)


def final_state(V, R, N, A, R_fe, m, b, k, x0, x_min, k_stop, d_stop) -> dict:
    """Rest state: current ``V/R`` and the gap where pull, spring and stop balance."""
    i = V / R

    def balance(x):
        return k * (x0 - x) + k_stop * (x_min - x) - pull_force(i, x, N, A, R_fe)

    if balance(1e-3 * x_min) * balance(x_min) > 0:
        raise ParameterError(f"solenoid: no rest position against the end stop: the pull "
                             f"{pull_force(i, x_min, N, A, R_fe):g} N at the residual gap "
                             f"outgrows the stop (k_stop = {k_stop:g} N/m) or never "
                             f"exceeds the spring. Stiffen the stop or change V, N, k.",
                             path="solenoid")
    x = brentq(balance, 1e-3 * x_min, x_min, xtol=1e-16, rtol=1e-15)
    return {"i": i, "x": x, "F": pull_force(i, x, N, A, R_fe)}


class SolenoidAcausal(mt.Component):
    """Coil, magnetic circuit with a moving air gap, plunger, return spring and end stop
    as a network of library parts."""

    source = el.DCVoltageSource(doc="Supply switched on at t = 0")
    winding = el.Resistor(doc="Coil resistance")
    coil = mag.ElectromagneticConverter(doc="The coil's N turns")
    iron = mag.Reluctance(doc="Iron path")
    gap = mag.ReluctanceForceActuator(doc="Working air gap and its pull on the plunger")
    plunger = tr.Mass(doc="Plunger (armature)")
    spring = tr.TranslationalSpring(doc="Return spring, relaxed at the open gap")
    friction = tr.TranslationalDamper(doc="Viscous friction of the guide")
    stop = tr.TranslationalHardStop(doc="End stops: residual gap and back stop")
    ground = el.ElectricalReference()
    mground = mag.MagneticReference()
    frame = tr.TranslationalReference()

    def equations(self):
        return [mt.connect(self.source.p, self.winding.p),
                mt.connect(self.winding.n, self.coil.p),
                mt.connect(self.coil.n, self.source.n, self.ground.port),
                mt.connect(self.coil.B, self.iron.A),
                mt.connect(self.iron.B, self.gap.A),
                mt.connect(self.gap.B, self.coil.A, self.mground.port),
                mt.connect(self.gap.rod, self.plunger.port, self.spring.A,
                           self.friction.A, self.stop.A),
                mt.connect(self.gap.case, self.spring.B, self.friction.B, self.stop.B,
                           self.frame.port)]


def _stop_force(x, v, x_min, x_max, k_stop, d_stop):
    """Force of the end stops on the plunger along +x (pushes only)."""
    lower = k_stop * (x_min - x) - d_stop * v
    upper = k_stop * (x - x_max) + d_stop * v
    return (ca.if_else(x < x_min, ca.if_else(lower > 0, lower, 0), 0)
            - ca.if_else(x > x_max, ca.if_else(upper > 0, upper, 0), 0))


class SolenoidEquation(mt.Component):
    """The solenoid as three ODEs in the coil current, the gap and the plunger speed."""

    V = mt.Parameter("V", default=12.0, doc="Supply voltage")
    R = mt.Parameter("Ohm", default=30.0, min=0, doc="Coil resistance")
    N = mt.Parameter("1", default=500.0, min=0, doc="Turns")
    A = mt.Parameter("m^2", default=1e-4, min=0, doc="Pole face area")
    R_fe = mt.Parameter("A/Wb", default=4e5, min=0, doc="Iron path reluctance")
    m = mt.Parameter("kg", default=0.01, min=0, doc="Plunger mass")
    b = mt.Parameter("N*s/m", default=0.5, min=0, doc="Viscous friction")
    k = mt.Parameter("N/m", default=100.0, min=0, doc="Return spring rate")
    x0 = mt.Parameter("m", default=3e-3, min=0, doc="Open gap (spring relaxed)")
    x_min = mt.Parameter("m", default=2e-4, min=0, doc="Residual gap at the stop")
    x_max = mt.Parameter("m", default=4e-3, min=0, doc="Gap at the back stop")
    k_stop = mt.Parameter("N/m", default=1e8, min=0, doc="Stop contact stiffness")
    d_stop = mt.Parameter("N*s/m", default=500.0, min=0, doc="Stop contact damping")
    mu0 = mt.Parameter("H/m", default=MU0, min=0, doc="Vacuum permeability")
    i = mt.Variable("A", start=0.0, doc="Coil current")
    x = mt.Variable("m", start=3e-3, doc="Air gap")
    v = mt.Variable("m/s", start=0.0, doc="Gap rate dx/dt")
    L = mt.Variable("H", doc="Coil inductance L(x)")
    F = mt.Variable("N", doc="Magnetic force along +x (negative: closing)")

    def equations(self):
        rm = self.R_fe + self.x / (self.mu0 * self.A)
        dL_dx = -self.N ** 2 / (rm ** 2 * self.mu0 * self.A)
        return [self.L == self.N ** 2 / rm,
                self.F == 0.5 * self.i ** 2 * dL_dx,
                self.L * mt.der(self.i) == self.V - self.R * self.i
                - self.i * dL_dx * self.v,
                mt.der(self.x) == self.v,
                self.m * mt.der(self.v) == self.F + self.k * (self.x0 - self.x)
                - self.b * self.v
                + _stop_force(self.x, self.v, self.x_min, self.x_max, self.k_stop,
                              self.d_stop)]


def _acausal(V, R, N, A, R_fe, m, b, k, x0, x_min, k_stop, d_stop):
    model = SolenoidAcausal(doc="solenoid actuator, acausal network")
    model._name = "solenoid"
    model.source._values["V"] = V
    model.winding._values["R"] = R
    model.coil._values["N"] = N
    model.iron._values["R"] = R_fe
    model.gap._values["area"] = A
    model.gap._set("x", x0)
    model.plunger._values["m"] = m
    model.plunger._set("v", 0.0)
    model.spring._values["k"] = k
    model.spring._set("x", 0.0)            # relaxed at the open gap
    model.friction._values["b"] = b
    model.stop._values.update(lower=x_min, upper=x0 + 1e-3, k=k_stop, d=d_stop)
    model.stop._set("x", x0)               # the stop measures the gap itself
    return model


def _equation(**values):
    model = SolenoidEquation(**values, x_max=values["x0"] + 1e-3, x=values["x0"])
    model._name = "solenoid"
    return model


_PARAMS = {
    "V": ParameterInfo("V", 12.0, "Supply voltage step at t = 0", CHOSEN),
    "R": ParameterInfo("Ohm", 30.0, "Coil resistance (0.4 A steady current)", CHOSEN),
    "N": ParameterInfo("1", 500.0, "Coil turns", CHOSEN),
    "A": ParameterInfo("m^2", 1e-4, "Pole face area of the air gap", CHOSEN),
    "R_fe": ParameterInfo("A/Wb", 4e5, "Reluctance of the iron path", IRON),
    "m": ParameterInfo("kg", 0.01, "Plunger mass", CHOSEN),
    "b": ParameterInfo("N*s/m", 0.5, "Viscous friction of the plunger guide", CHOSEN),
    "k": ParameterInfo("N/m", 100.0, "Return spring rate", CHOSEN),
    "x0": ParameterInfo("m", 3e-3, "Open air gap, return spring relaxed", CHOSEN),
    "x_min": ParameterInfo("m", 2e-4, "Residual gap (non-magnetic shim) at the end stop",
                           CHOSEN),
    "k_stop": ParameterInfo("N/m", 1e8, "Contact stiffness of the end stop",
                            "chosen: penalty contact, 0.4 um under the full pull"),
    "d_stop": ParameterInfo("N*s/m", 500.0, "Contact damping of the end stop",
                            "chosen: a quarter of critical damping with the plunger"),
}
_FINAL = final_state(**{key: info.default for key, info in _PARAMS.items()})

ENTRY = register(ModelEntry(
    name="solenoid",
    description=("Solenoid actuator: a voltage step on a coil whose air gap closes as the "
                 "magnetic pull drives the plunger against a spring onto its end stop; "
                 "electrical, magnetic and translational domains."),
    parameters=_PARAMS,
    variants={"acausal": _acausal, "equation": _equation},
    outputs={"acausal": {"i": "winding.i", "x": "gap.x", "v": "plunger.v", "F": "gap.F"},
             "equation": {"i": "i", "x": "x", "v": "v", "F": "F"}},
    output_units={"i": "A", "x": "m", "v": "m/s", "F": "N"},
    experiment=Experiment(t_stop=0.1, rtol=1e-8, atol=1e-10),
    expected={"i": _FINAL["i"], "x": _FINAL["x"], "F": -_FINAL["F"]},
    expected_tolerance=1e-5, variant_tolerance=1e-5,
    tags=("electromagnetic", "magnetic", "translational", "actuator", "events"),
))
