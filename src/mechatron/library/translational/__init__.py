"""Mechanical translational domain: across = velocity v (m/s), through = force f (N).

Two-flange components have flanges ``A`` and ``B``: ``v = A.v - B.v``, ``f`` is the force
flowing into the component at ``A``. One-flange components have a single ``port``.
Positions, where a component needs them (springs, sensors), are its own states.
"""

from mechatron.library.translational.components import (IdealForceSource, Mass, MotionSensor,
                                                         TranslationalDamper,
                                                         TranslationalFriction,
                                                         TranslationalReference,
                                                         TranslationalSpring)
from mechatron.library.translational.interfaces import Flange, TwoFlange

__all__ = ["Flange", "TwoFlange", "Mass", "TranslationalSpring", "TranslationalDamper",
           "TranslationalFriction", "TranslationalReference", "IdealForceSource",
           "MotionSensor"]
