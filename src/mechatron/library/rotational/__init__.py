"""Mechanical rotational domain: across = angular velocity w (rad/s), through = torque tau
(N*m).

Two-flange components have flanges ``A`` and ``B``: ``w = A.w - B.w`` and ``tau`` is the
torque flowing into the component at ``A`` (and out at ``B``); ``tau * w > 0`` is power
absorbed. One-flange components (inertia, reference) have a single flange ``port``.
Angles, where a component needs them (springs), are its own states.
"""

from mechatron.library.rotational.components import (AngularVelocitySensor, IdealGear,
                                                      IdealTorqueSource, Inertia,
                                                      RotationalDamper, RotationalFriction,
                                                      RotationalReference, RotationalSpring)
from mechatron.library.rotational.interfaces import Flange, TwoFlange

__all__ = ["Flange", "TwoFlange", "Inertia", "RotationalSpring", "RotationalDamper",
           "RotationalFriction", "IdealGear", "RotationalReference", "IdealTorqueSource",
           "AngularVelocitySensor"]
