"""Quarter-car suspension on a sinusoidal road.

A sprung mass ``m_s`` (a quarter of the body) on a suspension spring ``k_s`` and damper
``b_s``, an unsprung mass ``m_u`` (wheel, axle) on the tyre stiffness ``k_t``, driven by the
road height ``z_r = A sin(2 pi f t)``. Displacements from the static equilibrium (gravity
drops out), positive up:
``m_s z_s'' = -k_s (z_s - z_u) - b_s (z_s' - z_u')`` and
``m_u z_u'' = k_s (z_s - z_u) + b_s (z_s' - z_u') - k_t (z_u - z_r)``.

The steady state is the road sine times the transfer function ``H(j w) = Z_s / Z_r``, so
the final body height is known in closed form (:func:`steady_body_height`) once the
start transient has decayed.
"""

from __future__ import annotations

import math

import numpy as np

import mechatron as mt
from mechatron.library import blocks
from mechatron.library import translational as tr
from mechatron.models.entry import Experiment, ModelEntry, ParameterInfo
from mechatron.models.registry import register

__all__ = ["QuarterCarAcausal", "QuarterCarEquation", "body_response", "steady_body_height"]

TEXTBOOK = "typical passenger-car values"


class QuarterCarAcausal(mt.Component):
    """Quarter car as a translational network: two masses, suspension spring and damper,
    tyre spring, road as a position source."""

    body = tr.Mass()
    wheel = tr.Mass()
    spring = tr.TranslationalSpring()
    damper = tr.TranslationalDamper()
    tyre = tr.TranslationalSpring()
    road = tr.IdealPositionSource()
    profile = blocks.Sine()
    height = tr.PositionSensor()
    ground = tr.TranslationalReference()

    def equations(self):
        return [mt.connect(self.body.port, self.spring.A, self.damper.A, self.height.A),
                mt.connect(self.spring.B, self.damper.B, self.wheel.port, self.tyre.A),
                mt.connect(self.tyre.B, self.road.A),
                mt.connect(self.road.B, self.height.B, self.ground.port),
                mt.connect(self.profile.y, self.road.x_ref)]


class QuarterCarEquation(mt.Component):
    """Quarter car as two second-order ODEs with the road as a function of time."""

    m_s = mt.Parameter("kg", default=250.0, min=0, doc="Sprung mass")
    m_u = mt.Parameter("kg", default=35.0, min=0, doc="Unsprung mass")
    k_s = mt.Parameter("N/m", default=16000.0, min=0, doc="Suspension stiffness")
    b_s = mt.Parameter("N*s/m", default=1000.0, min=0, doc="Suspension damping")
    k_t = mt.Parameter("N/m", default=160000.0, min=0, doc="Tyre stiffness")
    A = mt.Parameter("m", default=0.01, min=0, doc="Road amplitude")
    f = mt.Parameter("Hz", default=2.0, min=0, doc="Road frequency")
    z_s = mt.Variable("m", start=0.0, doc="Body height")
    v_s = mt.Variable("m/s", start=0.0, doc="Body velocity")
    z_u = mt.Variable("m", start=0.0, doc="Wheel height")
    v_u = mt.Variable("m/s", start=0.0, doc="Wheel velocity")
    z_r = mt.Variable("m", doc="Road height")

    def equations(self):
        import casadi as ca
        suspension = self.k_s * (self.z_s - self.z_u) + self.b_s * (self.v_s - self.v_u)
        return [self.z_r == self.A * ca.sin(2 * math.pi * self.f * self.time),
                mt.der(self.z_s) == self.v_s,
                mt.der(self.z_u) == self.v_u,
                self.m_s * mt.der(self.v_s) == -suspension,
                self.m_u * mt.der(self.v_u) == suspension
                - self.k_t * (self.z_u - self.z_r)]


def body_response(m_s, m_u, k_s, b_s, k_t, omega: float) -> complex:
    """``H(j omega) = Z_s / Z_r`` from the Laplace-transformed equations of motion."""
    s = 1j * omega
    c = b_s * s + k_s
    a = np.array([[m_s * s ** 2 + c, -c], [-c, m_u * s ** 2 + c + k_t]])
    z = np.linalg.solve(a, np.array([0.0, k_t]))
    return complex(z[0])


def steady_body_height(m_s, m_u, k_s, b_s, k_t, A, f, t) -> float:
    """Body height at time ``t`` in the periodic steady state."""
    h = body_response(m_s, m_u, k_s, b_s, k_t, 2 * math.pi * f)
    return float(abs(h) * A * math.sin(2 * math.pi * f * t + np.angle(h)))


def _acausal(m_s, m_u, k_s, b_s, k_t, A, f):
    m = QuarterCarAcausal(doc="quarter car, acausal network")
    m._name = "quarter_car"
    m.body._values["m"] = m_s
    m.wheel._values["m"] = m_u
    m.spring._values["k"] = k_s
    m.damper._values["b"] = b_s
    m.tyre._values["k"] = k_t
    m.profile._values.update(amplitude=A, f=f)
    return m


def _equation(**values):
    m = QuarterCarEquation(**values)
    m._name = "quarter_car"
    return m


_PARAMS = {
    "m_s": ParameterInfo("kg", 250.0, "Sprung mass (a quarter of the body)", TEXTBOOK),
    "m_u": ParameterInfo("kg", 35.0, "Unsprung mass (wheel, hub, axle share)", TEXTBOOK),
    "k_s": ParameterInfo("N/m", 16000.0, "Suspension spring stiffness", TEXTBOOK),
    "b_s": ParameterInfo("N*s/m", 1000.0, "Suspension damping", TEXTBOOK),
    "k_t": ParameterInfo("N/m", 160000.0, "Tyre vertical stiffness", TEXTBOOK),
    "A": ParameterInfo("m", 0.01, "Road amplitude", "chosen"),
    "f": ParameterInfo("Hz", 2.0, "Road frequency (near the body resonance)", "chosen"),
}
T_STOP = 20.0

ENTRY = register(ModelEntry(
    name="quarter_car",
    description=("Quarter-car suspension (body, wheel, spring, damper, tyre) excited by a "
                 "sinusoidal road; the body's steady motion follows the transfer function."),
    parameters=_PARAMS,
    variants={"acausal": _acausal, "equation": _equation},
    outputs={"acausal": {"z_s": "height.x", "v_s": "body.v", "v_u": "wheel.v"},
             "equation": {"z_s": "z_s", "v_s": "v_s", "v_u": "v_u"}},
    output_units={"z_s": "m", "v_s": "m/s", "v_u": "m/s"},
    experiment=Experiment(t_stop=T_STOP, rtol=1e-10, atol=1e-12),
    expected={"z_s": steady_body_height(**{k: v.default for k, v in _PARAMS.items()},
                                        t=T_STOP)},
    expected_tolerance=1e-6, variant_tolerance=1e-7,
    tags=("mechanical", "translational", "vehicle"),
))
