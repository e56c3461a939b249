"""Planar multibody mechanics: frames with position (x, y) and angle as across variables,
force (fx, fy) and torque as through variables.

A :class:`Frame` is a point of a body with an orientation; its ``fx, fy, tau`` are the
load exerted on the component at that frame, resolved in the world. Connected frames
share position and angle, their loads sum to zero. Two-frame components name their ports
``frame_a`` and ``frame_b``; one-frame components ``frame``, except :class:`Body`
(``frame_a``). Joints have an optional 1-D flange ``axis`` in their actuated variants.
Gravity acts along the world's -y axis with each body's ``g``. See docs/multibody.md.
"""

from mechatron.library.multibody.forces import (Damper, Spring, SpringDamper, WorldForce,
                                                WorldTorque)
from mechatron.library.multibody.interfaces import MULTIBODY, Frame, TwoFrame
from mechatron.library.multibody.joints import (ActuatedPrismatic, ActuatedRevolute,
                                                Prismatic, Revolute)
from mechatron.library.multibody.parts import (Body, Fixed, PointMass, RigidTransform, Rod,
                                               Weld, World)
from mechatron.library.multibody.sensors import (AccelerationSensor, ForceSensor,
                                                 PositionSensor, RelativeAngleSensor,
                                                 VelocitySensor)

__all__ = ["MULTIBODY", "Frame", "TwoFrame", "World", "Fixed", "Body", "PointMass",
           "RigidTransform", "Rod", "Weld", "Revolute", "ActuatedRevolute", "Prismatic",
           "ActuatedPrismatic", "Spring", "Damper", "SpringDamper", "WorldForce",
           "WorldTorque", "PositionSensor", "VelocitySensor", "AccelerationSensor",
           "RelativeAngleSensor", "ForceSensor", "mechanisms"]


def __getattr__(name):
    # the mechanisms import other domains' libraries: loaded on first use
    if name == "mechanisms":
        import importlib
        return importlib.import_module("mechatron.library.multibody.mechanisms")
    raise AttributeError(f"module 'mechatron.library.multibody' has no attribute {name!r}")
