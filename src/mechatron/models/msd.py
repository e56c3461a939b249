"""The seed's three mass-spring-damper cases (its section 5.3, equations 11-13).

A mass ``m`` on a spring ``k_s`` and a damper ``b`` to the frame, each case in three
variants, as the seed does it:

* ``acausal``: library parts (mass, spring, damper, friction, force sources) connected;
* ``equation``: the seed's differential equation written as a user component;
* ``multibody``: a planar point mass on a prismatic joint tilted by the slope angle, with
  gravity acting on the body in the plane; the spring, damper, friction and applied force
  act on the joint's translational axis (Simscape Multibody's joint actuation).

``y`` is the mass's displacement from the spring's free length, positive in the direction
of the applied force (horizontal), down the slope (incline), or down (vertical).

Signs, checked against the physics (the seed's printed equations 12 and 13 have sign
slips): the spring and the damper always pull back, ``-k_s y - b y'``; gravity pulls down
the slope with ``m g sin(alpha)`` and presses the mass on it with ``F_N = m g cos(alpha)``
(the seed's ``mu F_N cos(alpha)`` counts the cosine twice when ``F_N`` is the weight); in
the vertical case gravity ``+m g`` pulls down and the spring ``-k_s y`` pulls up (the seed
prints ``+k_s y``, which would make the equilibrium unstable).

Coulomb friction ``mu F_N sgn(y')`` is regularised as ``mu F_N tanh(y'/v_c)`` with
``v_c = 0.01 m/s`` in every variant (Simscape's Translational Friction does the same with
its Coulomb velocity threshold): near rest the friction acts as a stiff viscous damper and
the mass creeps to the spring's equilibrium instead of sticking; stiction is not modelled.
"""

from __future__ import annotations

import math

import casadi as ca

import mechatron as mt
from mechatron.library import blocks
from mechatron.library import multibody as mb
from mechatron.library import translational as tr
from mechatron.models.entry import Experiment, ModelEntry, ParameterInfo
from mechatron.models.registry import register

__all__ = ["MSDAcausal", "MSDEquation", "G", "V_COULOMB"]

#: Gravitational acceleration, m/s^2.
G = 9.81
#: Velocity that regularises the Coulomb friction's sign function, m/s.
V_COULOMB = 0.01

CHOSEN = "chosen (the seed gives no values)"


class MSDAcausal(mt.Component):
    """Mass with spring, damper and Coulomb friction to the frame, driven by an applied
    force and by gravity's component along the motion (physical network)."""

    mass = tr.Mass()
    spring = tr.TranslationalSpring()
    damper = tr.TranslationalDamper()
    friction = tr.TranslationalFriction()
    force = tr.IdealForceSource()
    force_value = blocks.Constant()
    gravity = tr.IdealForceSource()
    gravity_value = blocks.Constant()
    frame = tr.TranslationalReference()

    def equations(self):
        return [mt.connect(self.mass.port, self.spring.A, self.damper.A, self.friction.A,
                           self.force.A, self.gravity.A),
                mt.connect(self.spring.B, self.damper.B, self.friction.B, self.force.B,
                           self.gravity.B, self.frame.port),
                mt.connect(self.force_value.y, self.force.f_in),
                mt.connect(self.gravity_value.y, self.gravity.f_in)]


class MSDEquation(mt.Component):
    """The seed's equation of motion of a mass-spring-damper with Coulomb friction on a
    slope ``alpha`` (0: horizontal; 90 degrees: hanging) under an applied force ``F``:
    ``m y'' = F - k_s y - b y' + m g sin(alpha) - mu m g cos(alpha) tanh(y'/v_c)``."""

    m = mt.Parameter("kg", default=1.0, min=0, doc="Mass")
    k_s = mt.Parameter("N/m", default=100.0, min=0, doc="Spring stiffness")
    b = mt.Parameter("N*s/m", default=2.0, min=0, doc="Damping coefficient")
    mu = mt.Parameter("1", default=0.1, min=0, doc="Coulomb friction coefficient")
    F = mt.Parameter("N", default=10.0, doc="Applied force")
    alpha = mt.Parameter("rad", default=0.0, doc="Slope angle (pi/2: vertical)")
    g = mt.Parameter("m/s^2", default=G, min=0, doc="Gravitational acceleration")
    v_c = mt.Parameter("m/s", default=V_COULOMB, min=0,
                       doc="Velocity regularising the Coulomb friction's sign")
    y = mt.Variable("m", start=0.0, doc="Displacement")
    v = mt.Variable("m/s", start=0.0, doc="Velocity")

    def equations(self):
        g_along = self.m * self.g * ca.sin(self.alpha)
        normal = self.m * self.g * ca.cos(self.alpha)
        return [mt.der(self.y) == self.v,
                self.m * mt.der(self.v) == self.F - self.k_s * self.y - self.b * self.v
                + g_along - self.mu * normal * ca.tanh(self.v / self.v_c)]


def _builders(alpha: float, with_force: bool, with_friction: bool):
    def acausal(m, k_s, b, mu=0.0, F=0.0):
        model = MSDAcausal(doc="mass-spring-damper, acausal network")
        model._name = "msd"
        model.mass._values["m"] = m
        model.spring._values["k"] = k_s
        model.damper._values["b"] = b
        normal = m * G * math.cos(alpha)
        coulomb = mu * normal if with_friction else 0.0
        # Simscape's friction with the breakaway force equal to the Coulomb force: no
        # Stribeck bump, F_C tanh(v / (v_brk/10)) with v_brk/10 = V_COULOMB.
        model.friction._values.update(F_brk=coulomb, F_C=coulomb, v_brk=10 * V_COULOMB,
                                      b=0.0)
        model.force_value._values["value"] = F if with_force else 0.0
        model.gravity_value._values["value"] = m * G * math.sin(alpha)
        return model

    def equation(m, k_s, b, mu=0.0, F=0.0):
        model = MSDEquation(m=m, k_s=k_s, b=b, mu=mu if with_friction else 0.0,
                            F=F if with_force else 0.0, alpha=alpha)
        model._name = "msd"
        return model

    def multibody(m, k_s, b, mu=0.0, F=0.0):
        model = mt.System("msd", doc="mass-spring-damper, planar multibody")
        world = model.add("world", mb.World())
        # the joint's axis points down the slope: gravity pulls along +y with m g sin(alpha)
        joint = model.add("joint", mb.ActuatedPrismatic(angle=-alpha, s=0.0, v=0.0))
        mass = model.add("mass", mb.PointMass(m=m, g=G))
        normal = m * G * math.cos(alpha)
        coulomb = mu * normal if with_friction else 0.0
        spring = model.add("spring", tr.TranslationalSpring(k=k_s))
        damper = model.add("damper", tr.TranslationalDamper(b=b))
        friction = model.add("friction", tr.TranslationalFriction(
            F_brk=coulomb, F_C=coulomb, v_brk=10 * V_COULOMB, b=0.0))
        force = model.add("force", tr.ConstantForce(F=F if with_force else 0.0))
        ground = model.add("ground", tr.TranslationalReference())
        model.connect(world.frame, joint.frame_a)
        model.connect(joint.frame_b, mass.frame)
        model.connect(joint.axis, spring.A, damper.A, friction.A, force.A)
        model.connect(spring.B, damper.B, friction.B, force.B, ground.port)
        return model

    return {"acausal": acausal, "equation": equation, "multibody": multibody}


def _params(with_force: bool, with_friction: bool) -> dict[str, ParameterInfo]:
    out = {"m": ParameterInfo("kg", 1.0, "Mass", CHOSEN),
           "k_s": ParameterInfo("N/m", 100.0, "Spring stiffness", CHOSEN),
           "b": ParameterInfo("N*s/m", 2.0, "Damping coefficient", CHOSEN)}
    if with_friction:
        out["mu"] = ParameterInfo("1", 0.1, "Coulomb friction coefficient", CHOSEN)
    if with_force:
        out["F"] = ParameterInfo("N", 10.0, "Applied force (constant from t = 0)", CHOSEN)
    return out


_OUTPUTS = {"acausal": {"y": "spring.x", "v": "mass.v"},
            "equation": {"y": "y", "v": "v"},
            "multibody": {"y": "joint.s", "v": "joint.v"}}
_EXPERIMENT = Experiment(t_stop=20.0, rtol=1e-10, atol=1e-12)
_TAGS = ("seed", "mechanical", "translational", "multibody", "mass-spring-damper")

ALPHA_INCLINE = math.radians(60.0)

register(ModelEntry(
    name="msd_horizontal",
    description=("Seed case 1: a force F on a mass on a horizontal surface with a spring, "
                 "a damper and Coulomb friction mu m g (equation 11)."),
    parameters=_params(True, True),
    variants=_builders(0.0, True, True),
    outputs=_OUTPUTS, output_units={"y": "m", "v": "m/s"},
    experiment=_EXPERIMENT,
    expected={"y": 10.0 / 100.0},     # at rest on the spring: y = F / k_s
    expected_tolerance=1e-6, variant_tolerance=1e-6, tags=_TAGS))

register(ModelEntry(
    name="msd_incline",
    description=("Seed case 2: a force F down a 60 degree incline on a mass with a spring, "
                 "a damper, gravity and Coulomb friction mu m g cos(60 deg) (equation 12)."),
    parameters=_params(True, True),
    variants=_builders(ALPHA_INCLINE, True, True),
    outputs=_OUTPUTS, output_units={"y": "m", "v": "m/s"},
    experiment=_EXPERIMENT,
    expected={"y": (10.0 + 1.0 * G * math.sin(ALPHA_INCLINE)) / 100.0},
    expected_tolerance=1e-6, variant_tolerance=1e-6, tags=_TAGS))

register(ModelEntry(
    name="msd_vertical",
    description=("Seed case 3: a mass hanging under gravity from a spring, with a damper "
                 "(equation 13, sign of the spring force corrected)."),
    parameters=_params(False, False),
    variants=_builders(math.pi / 2, False, False),
    outputs=_OUTPUTS, output_units={"y": "m", "v": "m/s"},
    experiment=_EXPERIMENT,
    expected={"y": 1.0 * G / 100.0},  # static deflection m g / k_s
    expected_tolerance=1e-6, variant_tolerance=1e-6, tags=_TAGS))
