"""Ideal sensors of the planar multibody domain. Every output is resolved in the world
frame. Absolute sensors take no load (``frame.f = 0``, ``frame.tau = 0``); the force
sensor is a rigid cut that passes the load through and measures it."""

from mechatron.core import Component, Output, Variable, der
from mechatron.library.multibody.interfaces import Frame, TwoFrame

__all__ = ["PositionSensor", "VelocitySensor", "AccelerationSensor", "RelativeAngleSensor",
           "ForceSensor"]


class _AbsoluteSensor(Component, partial=True):
    frame = Frame(doc="Measured frame")

    def equations(self):
        f = self.frame
        return [f.fx == 0, f.fy == 0, f.tau == 0]


class PositionSensor(_AbsoluteSensor):
    """Position and angle of a frame: ``x = frame.x``, ``y = frame.y``,
    ``phi = frame.phi``."""

    x = Output("m", doc="x-coordinate of the frame's origin")
    y = Output("m", doc="y-coordinate of the frame's origin")
    phi = Output("rad", doc="Angle of the frame")

    def equations(self):
        f = self.frame
        return [self.x == f.x, self.y == f.y, self.phi == f.phi]


class VelocitySensor(_AbsoluteSensor):
    """Velocity of a frame's origin and its angular velocity: ``vx = der(frame.x)``,
    ``vy = der(frame.y)``, ``w = der(frame.phi)``."""

    vx = Output("m/s", doc="Velocity, x")
    vy = Output("m/s", doc="Velocity, y")
    w = Output("rad/s", doc="Angular velocity")

    def equations(self):
        f = self.frame
        return [self.vx == der(f.x), self.vy == der(f.y), self.w == der(f.phi)]


class AccelerationSensor(_AbsoluteSensor):
    """Acceleration of a frame's origin and its angular acceleration:
    ``ax = der(der(frame.x))``, ``ay``, ``alpha`` alike."""

    ax = Output("m/s^2", doc="Acceleration, x")
    ay = Output("m/s^2", doc="Acceleration, y")
    alpha = Output("rad/s^2", doc="Angular acceleration")
    vx = Variable("m/s", doc="Velocity, x")
    vy = Variable("m/s", doc="Velocity, y")
    w = Variable("rad/s", doc="Angular velocity")

    def equations(self):
        f = self.frame
        return [self.vx == der(f.x), self.vy == der(f.y), self.w == der(f.phi),
                self.ax == der(self.vx), self.ay == der(self.vy), self.alpha == der(self.w)]


class RelativeAngleSensor(TwoFrame):
    """Angle of ``frame_b`` relative to ``frame_a`` and its rate:
    ``phi_rel = frame_b.phi - frame_a.phi``, ``w_rel = der(phi_rel)``. No load."""

    phi_rel = Output("rad", doc="Relative angle")
    w_rel = Output("rad/s", doc="Relative angular velocity")

    def equations(self):
        a, b = self.frame_a, self.frame_b
        return [self.phi_rel == b.phi - a.phi, self.w_rel == der(self.phi_rel),
                a.fx == 0, a.fy == 0, a.tau == 0, b.fx == 0, b.fy == 0, b.tau == 0]


class ForceSensor(TwoFrame):
    """Constraint (cut) force and torque: a rigid cut between ``frame_a`` and ``frame_b``
    (same position and angle) that passes the load through and measures the load that
    the side at ``frame_a`` exerts on the side at ``frame_b``::

        fx = frame_a.fx,  fy = frame_a.fy,  tau = frame_a.tau  (about the common origin)
    """

    fx = Output("N", doc="Cut force, x")
    fy = Output("N", doc="Cut force, y")
    tau = Output("N*m", doc="Cut torque")

    def equations(self):
        a, b = self.frame_a, self.frame_b
        return [b.x == a.x, b.y == a.y, b.phi == a.phi,
                a.fx + b.fx == 0, a.fy + b.fy == 0, a.tau + b.tau == 0,
                self.fx == a.fx, self.fy == a.fy, self.tau == a.tau]
