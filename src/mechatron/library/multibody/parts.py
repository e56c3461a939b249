"""Fixed frames, bodies and rigid connections of the planar multibody domain.

Gravity: every body carries its own gravitational acceleration ``g`` (default: standard
gravity 9.80665 m/s^2, as MSL's and Simscape Multibody's world), acting along the world's
-y axis. There is no global "world" object reaching
into the bodies (the language has no inner/outer); change ``g`` per body, or with
``params={"body.g": ...}`` at simulation time.
"""

import casadi as ca

from mechatron.core import Component, Parameter, Variable, der
from mechatron.library.multibody.interfaces import Frame, TwoFrame

__all__ = ["World", "Fixed", "Body", "PointMass", "RigidTransform", "Rod", "Weld",
           "rotate", "G_STANDARD"]

#: Standard gravity in m/s^2 (CGPM 1901, exact), the default of every body's ``g``; the
#: database models that follow the thesis set its 9.81 explicitly.
G_STANDARD = 9.80665


def rotate(phi, rx, ry):
    """The vector ``(rx, ry)`` given in a frame of angle ``phi``, resolved in the world."""
    c, s = ca.cos(phi), ca.sin(phi)
    return rx * c - ry * s, rx * s + ry * c


def cross(rx, ry, fx, fy):
    """z-component of ``r x f``."""
    return rx * fy - ry * fx


class Fixed(Component, reference=True):
    """A frame fixed in the world at ``(x0, y0)`` with angle ``phi0``.

    Equations: ``frame.x = x0``, ``frame.y = y0``, ``frame.phi = phi0``; the force and
    torque at the frame are the reactions of the ground.
    """

    frame = Frame(doc="The fixed frame")
    x0 = Parameter("m", default=0.0, doc="x-coordinate of the frame's origin")
    y0 = Parameter("m", default=0.0, doc="y-coordinate of the frame's origin")
    phi0 = Parameter("rad", default=0.0, doc="Angle of the frame")

    def equations(self):
        f = self.frame
        return [f.x == self.x0, f.y == self.y0, f.phi == self.phi0]


class World(Component, reference=True):
    """The inertial frame: origin at ``(0, 0)``, angle 0; gravity acts along -y.

    Equations: ``frame.x = 0``, ``frame.y = 0``, ``frame.phi = 0``. Every mechanism needs
    one (or a :class:`Fixed`) frame as its ground. Gravity is applied by the bodies
    themselves (each has ``g``, default 9.80665 m/s^2, along the world's -y axis).
    """

    frame = Frame(doc="The world frame")

    def equations(self):
        f = self.frame
        return [f.x == 0, f.y == 0, f.phi == 0]


class Body(Component):
    """Rigid body: mass ``m``, moment of inertia ``J`` about its centre of mass, the
    centre of mass at ``(rcm_x, rcm_y)`` in the coordinates of ``frame_a``.

    Equations (Newton-Euler about the centre of mass ``c``, gravity along -y)::

        (x, y)       = frame_a.(x, y) + R(phi) (rcm_x, rcm_y)      phi = frame_a.phi
        der(x) = vx, der(y) = vy, der(phi) = w
        m der(vx) = frame_a.fx
        m der(vy) = frame_a.fy - m g
        J der(w)  = frame_a.tau + (r_a - r_c) x f_a

    Energies: ``E_kin = m (vx^2 + vy^2)/2 + J w^2/2``, ``E_pot = m g y``.
    """

    frame_a = Frame(doc="Reference frame of the body")
    m = Parameter("kg", default=1.0, min=0, doc="Mass")
    J = Parameter("kg*m^2", default=0.0, min=0,
                  doc="Moment of inertia about the centre of mass")
    rcm_x = Parameter("m", default=0.0, doc="Centre of mass in frame_a, x-coordinate")
    rcm_y = Parameter("m", default=0.0, doc="Centre of mass in frame_a, y-coordinate")
    g = Parameter("m/s^2", default=G_STANDARD, min=0, doc="Gravity along the world's -y")
    x = Variable("m", doc="Centre of mass, x")
    y = Variable("m", doc="Centre of mass, y")
    vx = Variable("m/s", start=0.0, doc="Velocity of the centre of mass, x")
    vy = Variable("m/s", start=0.0, doc="Velocity of the centre of mass, y")
    w = Variable("rad/s", start=0.0, doc="Angular velocity")
    E_kin = Variable("J", doc="Kinetic energy")
    E_pot = Variable("J", doc="Potential energy m g y")

    def equations(self):
        f = self.frame_a
        dx, dy = rotate(f.phi, self.rcm_x, self.rcm_y)
        return [self.x == f.x + dx, self.y == f.y + dy,
                der(self.x) == self.vx, der(self.y) == self.vy, der(f.phi) == self.w,
                self.m * der(self.vx) == f.fx,
                self.m * der(self.vy) == f.fy - self.m * self.g,
                self.J * der(self.w) == f.tau + cross(-dx, -dy, f.fx, f.fy),
                self.E_kin == 0.5 * self.m * (self.vx ** 2 + self.vy ** 2)
                + 0.5 * self.J * self.w ** 2,
                self.E_pot == self.m * self.g * self.y]


class PointMass(Component):
    """Point mass ``m`` at the origin of ``frame``; takes no torque.

    Equations: ``der(x) = vx``, ``der(y) = vy``, ``m der(vx) = frame.fx``,
    ``m der(vy) = frame.fy - m g``, ``frame.tau = 0``.

    Limitation: the mass does not fix the frame's angle; connect it to something that
    does (a rod, a body, a joint), or the model is under-determined.
    """

    frame = Frame(doc="Frame at the mass")
    m = Parameter("kg", default=1.0, min=0, doc="Mass")
    g = Parameter("m/s^2", default=G_STANDARD, min=0, doc="Gravity along the world's -y")
    vx = Variable("m/s", start=0.0, doc="Velocity, x")
    vy = Variable("m/s", start=0.0, doc="Velocity, y")
    E_kin = Variable("J", doc="Kinetic energy")
    E_pot = Variable("J", doc="Potential energy m g y")

    def equations(self):
        f = self.frame
        return [der(f.x) == self.vx, der(f.y) == self.vy,
                self.m * der(self.vx) == f.fx,
                self.m * der(self.vy) == f.fy - self.m * self.g,
                f.tau == 0,
                self.E_kin == 0.5 * self.m * (self.vx ** 2 + self.vy ** 2),
                self.E_pot == self.m * self.g * f.y]


class RigidTransform(TwoFrame):
    """Massless rigid connection: ``frame_b`` sits at ``(rx, ry)`` in ``frame_a``'s
    coordinates, rotated by ``angle``.

    Equations::

        frame_b.(x, y) = frame_a.(x, y) + R(frame_a.phi) (rx, ry)
        frame_b.phi    = frame_a.phi + angle
        f_a + f_b = 0,   tau_a + tau_b + r_ab x f_b = 0      (massless: no net load)
    """

    rx = Parameter("m", default=0.0, doc="Offset of frame_b in frame_a, x")
    ry = Parameter("m", default=0.0, doc="Offset of frame_b in frame_a, y")
    angle = Parameter("rad", default=0.0, doc="Rotation of frame_b relative to frame_a")

    def equations(self):
        a, b = self.frame_a, self.frame_b
        dx, dy = rotate(a.phi, self.rx, self.ry)
        return [b.x == a.x + dx, b.y == a.y + dy, b.phi == a.phi + self.angle,
                a.fx + b.fx == 0, a.fy + b.fy == 0,
                a.tau + b.tau + cross(dx, dy, b.fx, b.fy) == 0]


class Rod(TwoFrame):
    """Massless rod of length ``L`` along ``frame_a``'s x-axis (a :class:`RigidTransform`
    with ``rx = L``, ``ry = 0``); ``frame_b`` has the same angle as ``frame_a``."""

    L = Parameter("m", default=1.0, min=0, doc="Length")

    def equations(self):
        a, b = self.frame_a, self.frame_b
        dx, dy = rotate(a.phi, self.L, 0.0)
        return [b.x == a.x + dx, b.y == a.y + dy, b.phi == a.phi,
                a.fx + b.fx == 0, a.fy + b.fy == 0,
                a.tau + b.tau + cross(dx, dy, b.fx, b.fy) == 0]


class Weld(TwoFrame):
    """Rigid connection of two frames at the same place and angle (a zero transform)::

        frame_b.(x, y, phi) = frame_a.(x, y, phi),   f_a + f_b = 0,   tau_a + tau_b = 0
    """

    def equations(self):
        a, b = self.frame_a, self.frame_b
        return [b.x == a.x, b.y == a.y, b.phi == a.phi,
                a.fx + b.fx == 0, a.fy + b.fy == 0, a.tau + b.tau == 0]
