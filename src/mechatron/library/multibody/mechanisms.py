"""Ready-made mechanisms built from the multibody parts, and their equation-model and
closed-form counterparts (used by the tests, the benchmarks and the model database).

Each builder is a function of the physical parameters that returns a fresh model
(:class:`mechatron.System`), so it can be called once per variant or parameter set.

Angles of the pendulums are measured from the downward vertical (the seed's alpha_1,
alpha_2); the links of :func:`double_pendulum` hang along -y of their joint's frame.
"""

from __future__ import annotations

import math

import casadi as ca
import numpy as np

from mechatron.core import Component, Parameter, Start, System, Variable, der
from mechatron.errors import ModelError
from mechatron.library import blocks
from mechatron.library import rotational as rot
from mechatron.library import translational as tr
from mechatron.library.multibody.joints import (ActuatedPrismatic, ActuatedRevolute,
                                                Prismatic, Revolute)
from mechatron.library.multibody.parts import (G_STANDARD, Body, Fixed, PointMass,
                                               RigidTransform, Rod, World)

__all__ = ["double_pendulum", "DoublePendulumLagrange", "four_bar", "four_bar_angles",
           "slider_crank", "slider_crank_position", "incline", "incline_1d",
           "kinetic_mechanism"]


# ---------------------------------------------------------------------- double pendulum
def double_pendulum(m1: float = 1.0, m2: float = 1.0, l1: float = 1.0, l2: float = 1.0,
                    alpha1: float = math.pi / 2, alpha2: float = 0.0,
                    g: float = G_STANDARD, name: str = "double_pendulum") -> System:
    """Double pendulum of point masses on massless rods (the seed's Fig. 5-13).

    ``world -> j1 -> rod1 -> m1 -> j2 -> rod2 -> m2``; ``alpha1``, ``alpha2`` are the
    initial absolute angles from the downward vertical, at rest. The joint angles are
    ``j1.q = alpha1`` and ``j2.q = alpha2 - alpha1`` (relative).
    """
    m = System(name)
    world = m.add("world", World())
    j1 = m.add("j1", Revolute(q=alpha1, w=0.0))
    rod1 = m.add("rod1", RigidTransform(ry=-l1))
    mass1 = m.add("m1", PointMass(m=m1, g=g))
    j2 = m.add("j2", Revolute(q=alpha2 - alpha1, w=0.0))
    rod2 = m.add("rod2", RigidTransform(ry=-l2))
    mass2 = m.add("m2", PointMass(m=m2, g=g))
    m.connect(world.frame, j1.frame_a)
    m.connect(j1.frame_b, rod1.frame_a)
    m.connect(rod1.frame_b, mass1.frame, j2.frame_a)
    m.connect(j2.frame_b, rod2.frame_a)
    m.connect(rod2.frame_b, mass2.frame)
    return m


class DoublePendulumLagrange(Component):
    """Equation model of the double pendulum: the Lagrange equations (seed eqs. 14-15)::

        (m1 + m2) l1 a1'' + m2 l2 a2'' cos(a1 - a2) + m2 l2 a2'^2 sin(a1 - a2)
            + (m1 + m2) g sin a1 = 0
        l2 a2'' + l1 a1'' cos(a1 - a2) - l1 a1'^2 sin(a1 - a2) + g sin a2 = 0

    with absolute angles ``a1``, ``a2`` from the downward vertical.
    """

    m1 = Parameter("kg", default=1.0, min=0, doc="Mass 1")
    m2 = Parameter("kg", default=1.0, min=0, doc="Mass 2")
    l1 = Parameter("m", default=1.0, min=0, doc="Length of rod 1")
    l2 = Parameter("m", default=1.0, min=0, doc="Length of rod 2")
    g = Parameter("m/s^2", default=G_STANDARD, min=0, doc="Gravity")
    a1 = Variable("rad", start=math.pi / 2, priority="high", doc="Angle of rod 1")
    a2 = Variable("rad", start=0.0, priority="high", doc="Angle of rod 2")
    w1 = Variable("rad/s", start=0.0, priority="high", doc="der(a1)")
    w2 = Variable("rad/s", start=0.0, priority="high", doc="der(a2)")
    E = Variable("J", doc="Total energy")

    def equations(self):
        m1, m2, l1, l2, g = self.m1, self.m2, self.l1, self.l2, self.g
        d = self.a1 - self.a2
        dw1, dw2 = der(self.w1), der(self.w2)
        y1 = -l1 * ca.cos(self.a1)
        y2 = y1 - l2 * ca.cos(self.a2)
        v2sq = (l1 * self.w1) ** 2 + (l2 * self.w2) ** 2 \
            + 2 * l1 * l2 * self.w1 * self.w2 * ca.cos(d)
        return [der(self.a1) == self.w1, der(self.a2) == self.w2,
                (m1 + m2) * l1 * dw1 + m2 * l2 * dw2 * ca.cos(d)
                + m2 * l2 * self.w2 ** 2 * ca.sin(d) + (m1 + m2) * g * ca.sin(self.a1) == 0,
                l2 * dw2 + l1 * dw1 * ca.cos(d) - l1 * self.w1 ** 2 * ca.sin(d)
                + g * ca.sin(self.a2) == 0,
                self.E == 0.5 * m1 * (l1 * self.w1) ** 2 + 0.5 * m2 * v2sq
                + m1 * g * y1 + m2 * g * y2]


# ----------------------------------------------------------------------------- four-bar
def four_bar_angles(theta: float, a: float, b: float, c: float, d: float,
                    branch: int = 1) -> tuple[float, float]:
    """Closed-form position analysis of a four-bar: ground pivots ``A = (0, 0)`` and
    ``D = (d, 0)``, crank ``AB`` (length ``a``, angle ``theta``), coupler ``BC`` (``b``),
    rocker ``CD`` (``c``). Returns the absolute angles ``(phi_BC, phi_CD)`` of the
    coupler and of the vector from C to D; ``branch = +1`` puts C above the line BD.

    Raises ``ModelError`` when the loop cannot close at ``theta``.
    """
    bx, by = a * math.cos(theta), a * math.sin(theta)
    ex, ey = d - bx, -by
    e = math.hypot(ex, ey)
    if e > b + c or e < abs(b - c) or e == 0.0:
        raise ModelError(f"four_bar: the loop cannot close at crank angle {theta:g} rad "
                         f"(|BD| = {e:g} m, links b = {b:g}, c = {c:g}). Choose another "
                         "crank angle or link lengths.")
    # C = B + b * (cos, sin)(angle(BD) + branch * gamma), law of cosines at B
    gamma = math.acos(max(-1.0, min(1.0, (b * b + e * e - c * c) / (2 * b * e))))
    phi_bc = math.atan2(ey, ex) + branch * gamma
    cx, cy = bx + b * math.cos(phi_bc), by + b * math.sin(phi_bc)
    phi_cd = math.atan2(-cy, d - cx)
    return phi_bc, phi_cd


def four_bar(a: float = 0.2, b: float = 0.6, c: float = 0.5, d: float = 0.6,
             theta0: float = math.pi / 3, torque: float = 1.0, damping: float = 0.1,
             density: float = 1.0, g: float = G_STANDARD,
             name: str = "four_bar") -> System:
    """Crank-rocker four-bar linkage driven by a constant torque on the crank with a
    viscous damper on the crank axis (so the crank settles to a mean speed).

    Loop: ``ground(A) -> j1 -> crank(a) -> j2 -> coupler(b) -> j3 -> rocker(c) -> j4 ->
    ground(D)``. Each link is a uniform bar (:class:`Body`, mass ``density * L`` in kg,
    ``J = m L^2/12``) on a massless :class:`Rod`. The initial joint angles close the loop
    (open branch); the crank angle ``j1.q`` is the preferred state.
    """
    phi2, phi3 = four_bar_angles(theta0, a, b, c, d)
    m = System(name)
    world = m.add("world", World())
    ground_d = m.add("ground_d", Fixed(x0=d))
    j1 = m.add("j1", ActuatedRevolute(q=theta0, w=0.0))
    j2 = m.add("j2", Revolute(q=Start(phi2 - theta0, "low"), w=Start(0.0, "none")))
    j3 = m.add("j3", Revolute(q=Start(phi3 - phi2, "low"), w=Start(0.0, "none")))
    j4 = m.add("j4", Revolute(q=Start(-phi3, "low"), w=Start(0.0, "none")))
    links = []
    for key, length in (("crank", a), ("coupler", b), ("rocker", c)):
        rod = m.add(key, Rod(L=length))
        mass = density * length
        body = m.add(f"{key}_body", Body(m=mass, J=mass * length ** 2 / 12,
                                         rcm_x=length / 2, g=g))
        m.connect(rod.frame_a, body.frame_a)
        links.append(rod)
    crank, coupler, rocker = links
    m.connect(world.frame, j1.frame_a)
    m.connect(j1.frame_b, crank.frame_a)
    m.connect(crank.frame_b, j2.frame_a)
    m.connect(j2.frame_b, coupler.frame_a)
    m.connect(coupler.frame_b, j3.frame_a)
    m.connect(j3.frame_b, rocker.frame_a)
    m.connect(rocker.frame_b, j4.frame_a)
    m.connect(j4.frame_b, ground_d.frame)
    # drive: constant torque and a damper on the crank axis, referenced to the ground
    cmd = m.add("torque_cmd", blocks.Constant(value=torque))
    src = m.add("motor", rot.IdealTorqueSource())
    damper = m.add("bearing", rot.RotationalDamper(D=damping))
    ref = m.add("axis_ref", rot.RotationalReference())
    m.connect(cmd.y, src.tau_in)
    m.connect(src.A, damper.A, j1.axis)
    m.connect(src.B, damper.B, ref.port)
    return m


# -------------------------------------------------------------------------- slider-crank
def slider_crank_position(theta, r: float, l: float, offset: float = 0.0):
    """Slider position of a slider-crank (crank pivot at the origin, slider on the line
    ``y = offset``): ``x = r cos(theta) + sqrt(l^2 - (r sin(theta) - offset)^2)``."""
    theta = np.asarray(theta, dtype=float)
    return r * np.cos(theta) + np.sqrt(l ** 2 - (r * np.sin(theta) - offset) ** 2)


def slider_crank(r: float = 0.1, l: float = 0.3, omega: float = 2 * math.pi,
                 theta0: float = 0.3, m_slider: float = 0.5, m_rod: float = 0.2,
                 g: float = G_STANDARD, name: str = "slider_crank") -> System:
    """Slider-crank driven at the imposed crank speed ``omega`` (an ideal angular
    velocity source on the crank axis). Crank ``r`` pivots at the world origin; the
    connecting rod ``l`` (a uniform bar of mass ``m_rod``) ends at the slider (a point
    mass ``m_slider`` on a prismatic joint along the world's x-axis)."""
    if l <= r:
        raise ModelError(f"slider_crank: the rod ({l:g} m) must be longer than the crank "
                         f"({r:g} m) for the crank to turn fully.")
    bx, by = r * math.cos(theta0), r * math.sin(theta0)
    x_s = float(slider_crank_position(theta0, r, l))
    phi_rod = math.atan2(-by, x_s - bx)
    m = System(name)
    world = m.add("world", World())
    rail = m.add("rail", Fixed())
    j1 = m.add("j1", ActuatedRevolute(q=theta0))
    crank = m.add("crank", Rod(L=r))
    j2 = m.add("j2", Revolute(q=Start(phi_rod - theta0, "low"), w=Start(0.0, "none")))
    rod = m.add("rod", Rod(L=l))
    rod_body = m.add("rod_body", Body(m=m_rod, J=m_rod * l ** 2 / 12, rcm_x=l / 2, g=g))
    j3 = m.add("j3", Revolute(q=Start(-phi_rod, "low"), w=Start(0.0, "none")))
    slider = m.add("slider", Prismatic(s=Start(x_s, "low"), v=Start(0.0, "none")))
    mass = m.add("slider_mass", PointMass(m=m_slider, g=g))
    m.connect(world.frame, j1.frame_a)
    m.connect(j1.frame_b, crank.frame_a)
    m.connect(crank.frame_b, j2.frame_a)
    m.connect(j2.frame_b, rod.frame_a, rod_body.frame_a)
    m.connect(rod.frame_b, j3.frame_a)
    m.connect(rail.frame, slider.frame_a)
    m.connect(slider.frame_b, j3.frame_b, mass.frame)
    speed = m.add("speed_cmd", blocks.Constant(value=omega))
    src = m.add("drive", rot.IdealAngularVelocitySource())
    ref = m.add("axis_ref", rot.RotationalReference())
    m.connect(speed.y, src.w_ref)
    m.connect(src.A, j1.axis)
    m.connect(src.B, ref.port)
    return m


# ------------------------------------------------------------------------------ incline
def incline(m: float = 2.0, k: float = 50.0, d: float = 3.0,
            angle: float = math.radians(60), s0: float = 0.2, g: float = G_STANDARD,
            name: str = "incline") -> System:
    """A point mass on a prismatic joint along an incline at ``angle`` to the horizontal,
    with a translational spring (rest at ``s = 0``) and damper on the joint's axis.

    The 1-D equation along the incline is ``m s'' = -k s - d s' - m g sin(angle)``;
    :func:`incline_1d` builds it from translational parts. Starts at ``s = s0``, at rest.
    """
    sys_ = System(name)
    world = sys_.add("world", World())
    slope = sys_.add("slope", RigidTransform(angle=angle))
    joint = sys_.add("joint", ActuatedPrismatic(s=s0, v=0.0))
    mass = sys_.add("mass", PointMass(m=m, g=g))
    spring = sys_.add("spring", tr.TranslationalSpring(k=k, x=s0))
    damper = sys_.add("damper", tr.TranslationalDamper(b=d))
    ref = sys_.add("ref", tr.TranslationalReference())
    sys_.connect(world.frame, slope.frame_a)
    sys_.connect(slope.frame_b, joint.frame_a)
    sys_.connect(joint.frame_b, mass.frame)
    sys_.connect(joint.axis, spring.A, damper.A)
    sys_.connect(spring.B, damper.B, ref.port)
    return sys_


def incline_1d(m: float = 2.0, k: float = 50.0, d: float = 3.0,
               angle: float = math.radians(60), s0: float = 0.2, g: float = G_STANDARD,
               name: str = "incline_1d") -> System:
    """The 1-D translational model of :func:`incline`: a mass with a spring, a damper and
    the constant force ``-m g sin(angle)`` (gravity along the incline)."""
    sys_ = System(name)
    mass = sys_.add("mass", tr.Mass(m=m, v=0.0))
    spring = sys_.add("spring", tr.TranslationalSpring(k=k, x=s0))
    damper = sys_.add("damper", tr.TranslationalDamper(b=d))
    weight = sys_.add("weight_cmd", blocks.Constant(value=-m * g * math.sin(angle)))
    src = sys_.add("weight", tr.IdealForceSource())
    ref = sys_.add("ref", tr.TranslationalReference())
    sys_.connect(weight.y, src.f_in)
    sys_.connect(mass.port, spring.A, damper.A, src.A)
    sys_.connect(spring.B, damper.B, src.B, ref.port)
    return sys_


# ------------------------------------------------------------------- kinetic mechanism
def kinetic_mechanism(masses=(0.5, 0.5, 0.5), lengths=(0.4, 0.4, 0.4),
                      torque: float = 2.0, angles=(0.0, 0.3, 0.3), g: float = G_STANDARD,
                      name: str = "kinetic_mechanism") -> System:
    """The seed's kinetic mechanism in the form the thesis describes (Fig. 5-15): point
    masses on massless rods in an open chain of revolute joints, driven by a torque at
    the first joint. ``angles`` are the initial joint angles (relative, from the world's
    x-axis for the first). The seed gives no geometry; the defaults are illustrative."""
    if not (len(masses) == len(lengths) == len(angles)) or not masses:
        raise ModelError("kinetic_mechanism: masses, lengths and angles need one entry "
                         f"per link, got {len(masses)}, {len(lengths)}, {len(angles)}.")
    m = System(name)
    world = m.add("world", World())
    prev = world.frame
    for k, (mk, lk, qk) in enumerate(zip(masses, lengths, angles), start=1):
        joint = m.add(f"j{k}", ActuatedRevolute(q=qk, w=0.0) if k == 1
                      else Revolute(q=qk, w=0.0))
        rod = m.add(f"rod{k}", Rod(L=lk))
        mass = m.add(f"m{k}", PointMass(m=mk, g=g))
        m.connect(prev, joint.frame_a)
        m.connect(joint.frame_b, rod.frame_a)
        m.connect(rod.frame_b, mass.frame)
        prev = mass.frame
    cmd = m.add("torque_cmd", blocks.Constant(value=torque))
    src = m.add("motor", rot.IdealTorqueSource())
    ref = m.add("axis_ref", rot.RotationalReference())
    m.connect(cmd.y, src.tau_in)
    m.connect(src.A, m.j1.axis)
    m.connect(src.B, ref.port)
    return m
