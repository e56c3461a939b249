"""The planar multibody domain: the :class:`Frame` connector and the two-frame partial.

A frame is a point of a body with an orientation. Its across variables are the position
``(x, y)`` of its origin in the world and its angle ``phi`` (counter-clockwise from the
world's x-axis); its through variables are the force ``(fx, fy)`` and the torque ``tau``
(about the frame's origin, counter-clockwise positive), all resolved in the world frame.

Sign convention (as in every domain, docs/modeling.md): the force and torque of a frame are what the connection
exerts **on** the component at that frame. Connected frames share position and angle;
their forces and torques sum to zero (Newton's third law). The power flowing into a
component through a frame is ``fx*der(x) + fy*der(y) + tau*der(phi)``.

Velocities and accelerations are not carried by the connector: components write
``der(...)`` of positions and angles, and the compiler's index reduction differentiates
the kinematic constraints as far as the dynamics need them.
"""

from mechatron.core import Across, Component, Connector, Domain, Through

__all__ = ["MULTIBODY", "Frame", "TwoFrame"]

_HINT = ("Is a multibody frame left unconnected, or a mechanism without a World (or "
         "Fixed) frame?")

MULTIBODY = Domain("multibody", "position x, y (m) and angle phi (rad)",
                   "force fx, fy (N) and torque tau (N*m)", color="#7a7a7a",
                   needs_reference=False, hint=_HINT)


class Frame(Connector, domain=MULTIBODY):
    """Planar frame: origin ``(x, y)`` and angle ``phi`` in the world; force ``(fx, fy)``
    and torque ``tau`` exerted on the component at this frame, resolved in the world."""

    x = Across("m", doc="x-coordinate of the frame's origin in the world", hint=_HINT)
    y = Across("m", doc="y-coordinate of the frame's origin in the world", hint=_HINT)
    phi = Across("rad", doc="Angle of the frame's x-axis from the world's x-axis (CCW)",
                 hint=_HINT)
    fx = Through("N", doc="Force on the component at this frame, world x-component")
    fy = Through("N", doc="Force on the component at this frame, world y-component")
    tau = Through("N*m", doc="Torque on the component about this frame's origin (CCW)")


class TwoFrame(Component, partial=True):
    """Two frames, ``frame_a`` and ``frame_b``: the base of rods, joints, springs and
    relative sensors."""

    frame_a = Frame(doc="Frame a")
    frame_b = Frame(doc="Frame b")
