"""Mechanical translational domain: across = velocity v (m/s), through = force f (N).

Two-flange components have flanges ``A`` and ``B``: ``v = A.v - B.v``, ``f`` is the force
flowing into the component at ``A`` (and out at ``B``); ``f * v > 0`` is power absorbed.
One-flange components (mass, reference) have a single ``port``. Positions, where a
component needs them (springs, stops, sensors), are its own states: A relative to B in
the older parts (``x``), the length from A to B (MSL's ``s_rel``) in the MSL-named
``SpringDamper`` and ``ElastoGap``.
"""

from mechatron.library.translational.components import (IdealForceSource, Mass,
                                                         MassWithPosition, MotionSensor,
                                                         TranslationalDamper,
                                                         TranslationalFriction,
                                                         TranslationalReference,
                                                         TranslationalSpring)
from mechatron.library.translational.compliant import ElastoGap, SpringDamper
from mechatron.library.translational.friction import (Brake, MassWithStopAndFriction,
                                                       PartialFriction, SupportFriction)
from mechatron.library.translational.interfaces import Flange, TwoFlange
from mechatron.library.translational.nonlinear import PreloadedSpring, TranslationalHardStop
from mechatron.library.translational.sensors import (AccelerationSensor, ForceSensor,
                                                      PositionSensor,
                                                      TranslationalPowerSensor,
                                                      VelocitySensor)
from mechatron.library.translational.sources import (ConstantForce, IdealPositionSource,
                                                      IdealVelocitySource)

__all__ = ["Flange", "TwoFlange", "Mass", "MassWithPosition", "TranslationalSpring", "TranslationalDamper",
           "TranslationalFriction", "TranslationalReference", "IdealForceSource",
           "MotionSensor",
           "TranslationalHardStop", "PreloadedSpring", "IdealVelocitySource",
           "IdealPositionSource", "ConstantForce", "PositionSensor", "VelocitySensor",
           "AccelerationSensor", "ForceSensor", "TranslationalPowerSensor",
           "SpringDamper", "ElastoGap",
           "PartialFriction", "SupportFriction", "Brake", "MassWithStopAndFriction"]
