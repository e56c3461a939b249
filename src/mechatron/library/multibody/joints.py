"""Joints of the planar multibody domain: revolute and prismatic, free or with a 1-D
flange (``axis``) for actuation, springs, dampers, friction and sensing.

The joint coordinate (``q`` in rad, ``s`` in m) and its rate (``w``, ``v``) are the
joint's own variables; the compiler prefers them as states, as Modelica does with
``StateSelect.prefer`` on joint coordinates (see docs/multibody.md).

The 1-D flange works in joint coordinates: its across variable is the joint rate
(``axis.w = w`` or ``axis.v = v``), its through variable the torque or force that drives
the joint (positive in the direction of positive ``q`` or ``s``). The 1-D network on the
axis is relative: its reference (a ``RotationalReference`` or
``TranslationalReference``) stands for ``frame_a``'s body, which takes the reaction
through ``frame_a``. A free joint transmits no torque (force) along its axis.
"""

import casadi as ca

from mechatron.core import Parameter, Variable, der
from mechatron.library.multibody.interfaces import TwoFrame
from mechatron.library.multibody.parts import cross
from mechatron.library.rotational.interfaces import Flange as RotationalFlange
from mechatron.library.translational.interfaces import Flange as TranslationalFlange

__all__ = ["Revolute", "ActuatedRevolute", "Prismatic", "ActuatedPrismatic"]


class PartialRevolute(TwoFrame, partial=True):
    """Kinematics and load balance of a revolute joint (a pin at the frames' origin)::

        frame_b.(x, y) = frame_a.(x, y),   frame_b.phi = frame_a.phi + q
        der(q) = w,   der(w) = a
        f_a + f_b = 0,                     tau_a + tau_b = 0
    """

    q = Variable("rad", start=0.0, state_select="prefer",
                 doc="Joint angle, frame_b relative to frame_a")
    w = Variable("rad/s", start=0.0, state_select="prefer",
                 doc="Joint angular velocity der(q)")
    a = Variable("rad/s^2", doc="Joint angular acceleration der(w)")

    def equations(self):
        a, b = self.frame_a, self.frame_b
        return [b.x == a.x, b.y == a.y, b.phi == a.phi + self.q, der(self.q) == self.w,
                der(self.w) == self.a,
                a.fx + b.fx == 0, a.fy + b.fy == 0, a.tau + b.tau == 0]


class Revolute(PartialRevolute):
    """Free revolute joint: no torque about its axis (``frame_b.tau = 0``).

    Set the initial angle and rate with ``Revolute(q=..., w=...)`` (high priority).
    """

    def equations(self):
        return [self.frame_b.tau == 0]


class ActuatedRevolute(PartialRevolute):
    """Revolute joint with a rotational flange ``axis``: ``axis.w = w`` and the torque
    into ``axis`` drives the joint: ``frame_b.tau = -axis.tau`` (so the body at
    ``frame_b`` receives ``+axis.tau``, the one at ``frame_a`` the reaction)."""

    axis = RotationalFlange(doc="Joint axis (angular velocity w, driving torque)")

    def equations(self):
        return [self.axis.w == self.w, self.frame_b.tau == -self.axis.tau]


class PartialPrismatic(TwoFrame, partial=True):
    """Kinematics and load balance of a prismatic joint sliding along the unit vector
    ``e`` at ``angle`` from ``frame_a``'s x-axis::

        frame_b.(x, y) = frame_a.(x, y) + s e,   e = (cos(phi_a + angle), sin(...))
        frame_b.phi = frame_a.phi,   der(s) = v,   der(v) = a
        f_a + f_b = 0,               tau_a + tau_b + (s e) x f_b = 0

    The force along the axis is ``f_axis = -f_b . e``.
    """

    angle = Parameter("rad", default=0.0, doc="Direction of the axis in frame_a")
    s = Variable("m", start=0.0, state_select="prefer",
                 doc="Joint position, frame_b relative to frame_a")
    v = Variable("m/s", start=0.0, state_select="prefer", doc="Joint velocity der(s)")
    a = Variable("m/s^2", doc="Joint acceleration der(v)")

    def _axis(self):
        th = self.frame_a.phi + self.angle
        return ca.cos(th), ca.sin(th)

    def equations(self):
        a, b = self.frame_a, self.frame_b
        ex, ey = self._axis()
        return [b.x == a.x + self.s * ex, b.y == a.y + self.s * ey, b.phi == a.phi,
                der(self.s) == self.v, der(self.v) == self.a,
                a.fx + b.fx == 0, a.fy + b.fy == 0,
                a.tau + b.tau + cross(self.s * ex, self.s * ey, b.fx, b.fy) == 0]


class Prismatic(PartialPrismatic):
    """Free prismatic joint: no force along its axis (``f_b . e = 0``).

    Set the initial position and velocity with ``Prismatic(s=..., v=...)``.
    """

    def equations(self):
        ex, ey = self._axis()
        return [self.frame_b.fx * ex + self.frame_b.fy * ey == 0]


class ActuatedPrismatic(PartialPrismatic):
    """Prismatic joint with a translational flange ``axis``: ``axis.v = v`` and the force
    into ``axis`` drives the joint: ``f_b . e = -axis.f``."""

    axis = TranslationalFlange(doc="Joint axis (velocity v, driving force)")

    def equations(self):
        ex, ey = self._axis()
        return [self.axis.v == self.v,
                self.frame_b.fx * ex + self.frame_b.fy * ey == -self.axis.f]
