"""Mechanical rotational domain: across = angular velocity w (rad/s), through = torque tau
(N*m).

Two-flange components have flanges ``A`` and ``B``: ``w = A.w - B.w`` and ``tau`` is the
torque flowing into the component at ``A`` (and out at ``B``); ``tau * w > 0`` is power
absorbed. One-flange components (inertia, reference) have a single flange ``port``; gears
name their flanges ``A`` (input), ``B`` (output) and ``S`` (support, where it has one).
Angles, where a component needs them (springs, stops, sensors), are its own states: A
relative to B in the older parts (``phi``), B relative to A (MSL's ``phi_rel``) in the
MSL-named ``SpringDamper`` and ``ElastoBacklash``. ``IdealPlanetary`` has flanges ``sun``,
``carrier``, ``ring``.
"""

from mechatron.library.rotational.components import (AngularVelocitySensor, IdealGear,
                                                      IdealTorqueSource, Inertia,
                                                      InertiaWithAngle,
                                                      RotationalDamper, RotationalFriction,
                                                      RotationalReference, RotationalSpring)
from mechatron.library.rotational.compliant import ElastoBacklash, SpringDamper
from mechatron.library.rotational.encoders import HallSensor, IncrementalEncoder
from mechatron.library.rotational.gears import IdealPlanetary, LossyGear, SimpleGear
from mechatron.library.rotational.friction import (BearingFriction, Brake, Clutch,
                                                    OneWayClutch, PartialFriction)
from mechatron.library.rotational.interfaces import Flange, TwoFlange
from mechatron.library.rotational.nonlinear import (FanLoad, FrictionClutch,
                                                     RotationalBacklash, RotationalHardStop)
from mechatron.library.rotational.sensors import AngleSensor, PowerSensor, TorqueSensor
from mechatron.library.rotational.sources import (ConstantTorque, IdealAngleSource,
                                                   IdealAngularVelocitySource)

__all__ = ["Flange", "TwoFlange", "Inertia", "InertiaWithAngle", "RotationalSpring", "RotationalDamper",
           "RotationalFriction", "IdealGear", "RotationalReference", "IdealTorqueSource",
           "AngularVelocitySensor",
           "RotationalHardStop", "RotationalBacklash", "FrictionClutch", "FanLoad",
           "LossyGear", "SimpleGear", "IdealAngularVelocitySource", "IdealAngleSource",
           "ConstantTorque", "TorqueSensor", "AngleSensor", "PowerSensor",
           "SpringDamper", "ElastoBacklash", "IdealPlanetary", "IncrementalEncoder",
           "HallSensor",
           "PartialFriction", "Clutch", "Brake", "OneWayClutch", "BearingFriction"]
