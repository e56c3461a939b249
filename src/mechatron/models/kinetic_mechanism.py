"""The seed's kinetic mechanism (its section 5.4, Fig. 5-15): point masses on massless rods
in an open chain of three revolute joints, driven by an external torque at the first
joint, under gravity.

The seed gives no geometry; the defaults are illustrative (three 0.5 kg masses on 0.4 m
rods, a 2 N m torque). Joint angles ``q_k`` are relative (``q_1`` from the horizontal);
the absolute link angles are ``phi_k = q_1 + ... + q_k``.

Two variants:

* ``multibody``: world, revolute joints, rods and point masses of the planar multibody
  library, the first joint actuated by a torque source;
* ``equation``: Lagrange's equations of the chain in the absolute angles,
  ``sum_j S_ij l_i l_j [cos(phi_i - phi_j) phi_j'' + sin(phi_i - phi_j) phi_j'^2]
  + S_ii g l_i cos(phi_i) = Q_i`` with ``S_ij`` the mass beyond link ``max(i, j)`` and
  ``Q = (tau, 0, 0)``.

Both log the energy balance ``E - W`` (mechanical energy minus the torque's work), which
stays at its start value, the potential energy of the initial pose.
"""

from __future__ import annotations

import math

import casadi as ca

import mechatron as mt
from mechatron.library.multibody.mechanisms import kinetic_mechanism as multibody_chain
from mechatron.models.double_pendulum import TotalEnergy
from mechatron.models.entry import Experiment, ModelEntry, ParameterInfo
from mechatron.models.registry import register

__all__ = ["KineticMechanismEquation", "WorkMeter", "initial_energy"]

G = 9.81
CHOSEN = "chosen (the seed gives no geometry)"
N = 3


class WorkMeter(mt.Component):
    """Work done by a drive: ``dW/dt = P``, the power given by the owning model."""

    W = mt.Variable("J", start=0.0, doc="Work done since t = 0")
    E_minus_W = mt.Variable("J", doc="Mechanical energy minus the work done")


class KineticMechanismEquation(mt.Component):
    """Three-link chain of point masses from Lagrange's equations in absolute angles."""

    m1 = mt.Parameter("kg", default=0.5, min=0, doc="Mass at the end of link 1")
    m2 = mt.Parameter("kg", default=0.5, min=0, doc="Mass at the end of link 2")
    m3 = mt.Parameter("kg", default=0.5, min=0, doc="Mass at the end of link 3")
    l1 = mt.Parameter("m", default=0.4, min=0, doc="Length of link 1")
    l2 = mt.Parameter("m", default=0.4, min=0, doc="Length of link 2")
    l3 = mt.Parameter("m", default=0.4, min=0, doc="Length of link 3")
    tau = mt.Parameter("N*m", default=2.0, doc="Torque on joint 1")
    g = mt.Parameter("m/s^2", default=G, min=0, doc="Gravitational acceleration")
    phi1 = mt.Variable("rad", start=0.0, doc="Absolute angle of link 1")
    phi2 = mt.Variable("rad", start=0.3, doc="Absolute angle of link 2")
    phi3 = mt.Variable("rad", start=0.6, doc="Absolute angle of link 3")
    w1 = mt.Variable("rad/s", start=0.0, doc="Angular velocity of link 1")
    w2 = mt.Variable("rad/s", start=0.0, doc="Angular velocity of link 2")
    w3 = mt.Variable("rad/s", start=0.0, doc="Angular velocity of link 3")
    q2 = mt.Variable("rad", doc="Joint 2 angle (relative)")
    q3 = mt.Variable("rad", doc="Joint 3 angle (relative)")
    W = mt.Variable("J", start=0.0, doc="Work done by the torque")
    E_minus_W = mt.Variable("J", doc="Mechanical energy minus the work done")

    def equations(self):
        m = [self.m1, self.m2, self.m3]
        l = [self.l1, self.l2, self.l3]
        phi = [self.phi1, self.phi2, self.phi3]
        w = [self.w1, self.w2, self.w3]
        beyond = [m[0] + m[1] + m[2], m[1] + m[2], m[2]]   # mass beyond each joint
        eqs = [mt.der(p) == v for p, v in zip(phi, w)]
        q = [self.tau, 0, 0]
        for i in range(N):
            lhs = beyond[i] * self.g * l[i] * ca.cos(phi[i])
            for j in range(N):
                s = beyond[max(i, j)] * l[i] * l[j]
                lhs = lhs + s * (ca.cos(phi[i] - phi[j]) * mt.der(w[j])
                                 + ca.sin(phi[i] - phi[j]) * w[j] ** 2)
            eqs.append(lhs == q[i])
        # energy: point mass k at sum_{j<=k} l_j (cos phi_j, sin phi_j)
        energy = 0
        for k in range(N):
            vx = sum(-l[j] * ca.sin(phi[j]) * w[j] for j in range(k + 1))
            vy = sum(l[j] * ca.cos(phi[j]) * w[j] for j in range(k + 1))
            y = sum(l[j] * ca.sin(phi[j]) for j in range(k + 1))
            energy = energy + 0.5 * m[k] * (vx ** 2 + vy ** 2) + m[k] * self.g * y
        return eqs + [self.q2 == self.phi2 - self.phi1, self.q3 == self.phi3 - self.phi2,
                      mt.der(self.W) == self.tau * self.w1,
                      self.E_minus_W == energy - self.W]


def initial_energy(m1, m2, m3, l1, l2, l3, q1_0, q2_0, q3_0, **_) -> float:
    """Potential energy of the initial pose (at rest)."""
    phi = [q1_0, q1_0 + q2_0, q1_0 + q2_0 + q3_0]
    l, m = [l1, l2, l3], [m1, m2, m3]
    return sum(m[k] * G * sum(l[j] * math.sin(phi[j]) for j in range(k + 1))
               for k in range(N))


def _multibody(m1, m2, m3, l1, l2, l3, tau, q1_0, q2_0, q3_0):
    model = multibody_chain(masses=(m1, m2, m3), lengths=(l1, l2, l3), torque=tau,
                            angles=(q1_0, q2_0, q3_0), g=G)
    total = model.add("total", TotalEnergy())
    meter = model.add("meter", WorkMeter())
    masses = [model.m1, model.m2, model.m3]
    model.add_equation(lambda: total.E == sum(b.E_kin + b.E_pot for b in masses))
    model.add_equation(lambda: mt.der(meter.W) == model.motor.tau_in * model.j1.w)
    model.add_equation(lambda: meter.E_minus_W == total.E - meter.W)
    return model


def _equation(m1, m2, m3, l1, l2, l3, tau, q1_0, q2_0, q3_0):
    model = KineticMechanismEquation(m1=m1, m2=m2, m3=m3, l1=l1, l2=l2, l3=l3, tau=tau,
                                     phi1=q1_0, phi2=q1_0 + q2_0,
                                     phi3=q1_0 + q2_0 + q3_0)
    model._name = "kinetic_mechanism"
    return model


_PARAMS = {
    "m1": ParameterInfo("kg", 0.5, "Point mass 1", CHOSEN),
    "m2": ParameterInfo("kg", 0.5, "Point mass 2", CHOSEN),
    "m3": ParameterInfo("kg", 0.5, "Point mass 3", CHOSEN),
    "l1": ParameterInfo("m", 0.4, "Rod 1 length", CHOSEN),
    "l2": ParameterInfo("m", 0.4, "Rod 2 length", CHOSEN),
    "l3": ParameterInfo("m", 0.4, "Rod 3 length", CHOSEN),
    "tau": ParameterInfo("N*m", 2.0, "External torque on joint 1", CHOSEN),
    "q1_0": ParameterInfo("rad", 0.0, "Initial angle of joint 1 (from horizontal)", CHOSEN),
    "q2_0": ParameterInfo("rad", 0.3, "Initial angle of joint 2 (relative)", CHOSEN),
    "q3_0": ParameterInfo("rad", 0.3, "Initial angle of joint 3 (relative)", CHOSEN),
}

ENTRY = register(ModelEntry(
    name="kinetic_mechanism",
    description=("The seed's kinetic mechanism: three point masses on massless rods in an "
                 "open chain of revolute joints, driven by a torque at the first joint."),
    parameters=_PARAMS,
    variants={"multibody": _multibody, "equation": _equation},
    outputs={"multibody": {"q1": "j1.q", "q2": "j2.q", "q3": "j3.q",
                           "E_minus_W": "meter.E_minus_W"},
             "equation": {"q1": "phi1", "q2": "q2", "q3": "q3",
                          "E_minus_W": "E_minus_W"}},
    output_units={"q1": "rad", "q2": "rad", "q3": "rad", "E_minus_W": "J"},
    experiment=Experiment(t_stop=2.0, rtol=1e-11, atol=1e-12),
    expected={"E_minus_W": initial_energy(**{k: v.default for k, v in _PARAMS.items()})},
    expected_tolerance=1e-7, variant_tolerance=1e-6,
    tags=("seed", "mechanical", "multibody", "mechanism"),
))
