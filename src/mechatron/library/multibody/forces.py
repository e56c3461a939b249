"""Force elements of the planar multibody domain: point-to-point spring and damper, and
force and torque sources driven by signals.

A frame's through variables are the load exerted **on the component**; a force element
that pushes a body with ``F`` therefore has ``frame.f = -F`` (Newton's third law at the
connection).
"""

import casadi as ca

from mechatron.core import Component, Input, Parameter, Variable, der
from mechatron.library.multibody.interfaces import Frame, TwoFrame

__all__ = ["Spring", "Damper", "SpringDamper", "WorldForce", "WorldTorque"]


class PartialLineForce(TwoFrame, partial=True):
    """A force ``f`` along the line from ``frame_a`` to ``frame_b`` (tension positive:
    it pulls the frames together); no torques.

    Equations, with ``d = r_b - r_a``, ``L = |d|``, ``e = d / L``::

        frame_b.f = f e,   frame_a.f = -f e,   frame_a.tau = frame_b.tau = 0

    Limitation: the direction is undefined at ``L = 0`` (coincident frames).
    """

    L = Variable("m", doc="Distance between the frames' origins")
    f = Variable("N", doc="Tension (positive pulls the frames together)")

    def equations(self):
        a, b = self.frame_a, self.frame_b
        dx, dy = b.x - a.x, b.y - a.y
        return [self.L == ca.sqrt(dx ** 2 + dy ** 2),
                b.fx == self.f * dx / self.L, b.fy == self.f * dy / self.L,
                a.fx == -b.fx, a.fy == -b.fy, a.tau == 0, b.tau == 0]


class Spring(PartialLineForce):
    """Linear spring between two frames' origins: ``f = k (L - L0)``; stores
    ``E = k (L - L0)^2 / 2``."""

    k = Parameter("N/m", default=1.0, min=0, doc="Spring rate")
    L0 = Parameter("m", default=0.0, min=0, doc="Unstretched length")
    E = Variable("J", doc="Stored energy")

    def equations(self):
        return [self.f == self.k * (self.L - self.L0),
                self.E == 0.5 * self.k * (self.L - self.L0) ** 2]


class Damper(PartialLineForce):
    """Linear damper between two frames' origins: ``f = d der(L)``; dissipates
    ``d der(L)^2``."""

    d = Parameter("N*s/m", default=1.0, min=0, doc="Damping coefficient")

    def equations(self):
        return [self.f == self.d * der(self.L)]


class SpringDamper(PartialLineForce):
    """Spring and damper in parallel: ``f = k (L - L0) + d der(L)``."""

    k = Parameter("N/m", default=1.0, min=0, doc="Spring rate")
    L0 = Parameter("m", default=0.0, min=0, doc="Unstretched length")
    d = Parameter("N*s/m", default=1.0, min=0, doc="Damping coefficient")

    def equations(self):
        return [self.f == self.k * (self.L - self.L0) + self.d * der(self.L)]


class WorldForce(Component):
    """Force ``(fx_in, fy_in)``, resolved in the world, applied at the origin of the
    connected frame: ``frame.fx = -fx_in``, ``frame.fy = -fy_in``, ``frame.tau = 0``."""

    frame = Frame(doc="Frame the force acts on")
    fx_in = Input("N", doc="Force, world x-component")
    fy_in = Input("N", doc="Force, world y-component")

    def equations(self):
        f = self.frame
        return [f.fx == -self.fx_in, f.fy == -self.fy_in, f.tau == 0]


class WorldTorque(Component):
    """Torque ``tau_in`` (counter-clockwise) applied to the connected frame:
    ``frame.tau = -tau_in``, no force."""

    frame = Frame(doc="Frame the torque acts on")
    tau_in = Input("N*m", doc="Torque (counter-clockwise)")

    def equations(self):
        f = self.frame
        return [f.fx == 0, f.fy == 0, f.tau == -self.tau_in]
