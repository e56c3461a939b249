"""The seed's double pendulum (its section 5.4, Lagrange equations 14-15).

Point masses ``m1``, ``m2`` on massless rods ``l1``, ``l2``; angles ``alpha1``, ``alpha2``
from the downward vertical, counter-clockwise positive. The ``equation`` variant writes the
seed's two Lagrange equations as they stand (they are right; both second derivatives
appear in each, and the compiler solves the 2x2 mass matrix symbolically). The energy
``E = T + V`` is an output: it is conserved, and its start value is known in closed form,
so the default experiment checks it. The ``multibody`` variant assembles the same pendulum
from planar multibody parts (world, revolute joints, rigid transforms, point masses); its
energy is the sum of the bodies' kinetic and potential energies.
"""

from __future__ import annotations

import math

import casadi as ca
import numpy as np

import mechatron as mt
from mechatron.library.multibody.mechanisms import double_pendulum as multibody_pendulum
from mechatron.models.entry import Experiment, ModelEntry, ParameterInfo
from mechatron.models.registry import register

__all__ = ["DoublePendulumEquation", "TotalEnergy", "energy"]

G = 9.81
SEED = "seed section 5.4 (acceptance case of issue 5)"


def energy(m1, m2, l1, l2, a1, a2, w1, w2, g=G):
    """Total energy of the double pendulum (works on floats, NumPy arrays and CasADi)."""
    cos = ca.cos if isinstance(a1, (ca.SX, ca.MX)) else np.cos
    y1 = -l1 * cos(a1)
    y2 = y1 - l2 * cos(a2)
    kinetic = (0.5 * (m1 + m2) * l1 ** 2 * w1 ** 2 + 0.5 * m2 * l2 ** 2 * w2 ** 2
               + m2 * l1 * l2 * w1 * w2 * cos(a1 - a2))
    return kinetic + m1 * g * y1 + m2 * g * y2


class DoublePendulumEquation(mt.Component):
    """Double pendulum from the Lagrange equations (seed equations 14-15):
    ``(m1+m2) l1 a1'' + m2 l2 a2'' cos(a1-a2) + m2 l2 a2'^2 sin(a1-a2) + (m1+m2) g sin a1 = 0``
    and ``l2 a2'' + l1 a1'' cos(a1-a2) - l1 a1'^2 sin(a1-a2) + g sin a2 = 0``."""

    m1 = mt.Parameter("kg", default=1.0, min=0, doc="Mass of the first point mass")
    m2 = mt.Parameter("kg", default=1.0, min=0, doc="Mass of the second point mass")
    l1 = mt.Parameter("m", default=1.0, min=0, doc="Length of the first rod")
    l2 = mt.Parameter("m", default=1.0, min=0, doc="Length of the second rod")
    g = mt.Parameter("m/s^2", default=G, min=0, doc="Gravitational acceleration")
    alpha1 = mt.Variable("rad", start=math.pi / 2, doc="Angle of rod 1 from the vertical")
    alpha2 = mt.Variable("rad", start=0.0, doc="Angle of rod 2 from the vertical")
    w1 = mt.Variable("rad/s", start=0.0, doc="Angular velocity of rod 1")
    w2 = mt.Variable("rad/s", start=0.0, doc="Angular velocity of rod 2")
    E = mt.Variable("J", doc="Total energy (kinetic + potential, zero at the pivot)")

    def equations(self):
        d = self.alpha1 - self.alpha2
        m1, m2, l1, l2 = self.m1, self.m2, self.l1, self.l2
        return [mt.der(self.alpha1) == self.w1,
                mt.der(self.alpha2) == self.w2,
                (m1 + m2) * l1 * mt.der(self.w1) + m2 * l2 * mt.der(self.w2) * ca.cos(d)
                + m2 * l2 * self.w2 ** 2 * ca.sin(d)
                + (m1 + m2) * self.g * ca.sin(self.alpha1)
                == 0,
                l2 * mt.der(self.w2) + l1 * mt.der(self.w1) * ca.cos(d)
                - l1 * self.w1 ** 2 * ca.sin(d) + self.g * ca.sin(self.alpha2) == 0,
                self.E == energy(m1, m2, l1, l2, self.alpha1, self.alpha2, self.w1,
                                 self.w2, self.g)]


class TotalEnergy(mt.Component):
    """A probe for the total mechanical energy of a mechanism; its one equation,
    ``E == sum of the bodies' E_kin + E_pot``, is added by the model that owns it."""

    E = mt.Variable("J", doc="Total mechanical energy")


def _multibody(m1, m2, l1, l2, alpha1_0, alpha2_0):
    model = multibody_pendulum(m1=m1, m2=m2, l1=l1, l2=l2, alpha1=alpha1_0,
                               alpha2=alpha2_0, g=G)
    total = model.add("total", TotalEnergy())
    model.add_equation(lambda: total.E == model.m1.E_kin + model.m1.E_pot
                       + model.m2.E_kin + model.m2.E_pot)
    return model


def _equation(m1, m2, l1, l2, alpha1_0, alpha2_0):
    model = DoublePendulumEquation(m1=m1, m2=m2, l1=l1, l2=l2, alpha1=alpha1_0,
                                   alpha2=alpha2_0)
    model._name = "double_pendulum"
    return model


ENTRY = register(ModelEntry(
    name="double_pendulum",
    description=("Double pendulum of two point masses on massless rods released from rest "
                 "(seed equations 14-15); chaotic, energy-conserving."),
    parameters={
        "m1": ParameterInfo("kg", 1.0, "Mass 1", SEED),
        "m2": ParameterInfo("kg", 1.0, "Mass 2", SEED),
        "l1": ParameterInfo("m", 1.0, "Rod 1 length", SEED),
        "l2": ParameterInfo("m", 1.0, "Rod 2 length", SEED),
        "alpha1_0": ParameterInfo("rad", math.pi / 2, "Initial angle of rod 1", SEED),
        "alpha2_0": ParameterInfo("rad", 0.0, "Initial angle of rod 2", SEED),
    },
    variants={"equation": _equation, "multibody": _multibody},
    outputs={"equation": {"alpha1": "alpha1", "alpha2": "alpha2", "E": "E"},
             "multibody": {"alpha1": "j1.q", "alpha2": "m2.frame.phi", "E": "total.E"}},
    output_units={"alpha1": "rad", "alpha2": "rad", "E": "J"},
    experiment=Experiment(t_stop=5.0, rtol=1e-11, atol=1e-12),
    # released from rest: E = m1 g y1 + m2 g y2 with y1 = -l1 cos(pi/2) = 0, y2 = -l2
    expected={"E": float(energy(1.0, 1.0, 1.0, 1.0, math.pi / 2, 0.0, 0.0, 0.0))},
    expected_tolerance=1e-8, variant_tolerance=1e-6,
    tags=("seed", "mechanical", "multibody", "pendulum"),
))
