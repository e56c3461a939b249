"""Inverted pendulum on a cart, balanced by state feedback.

A cart of mass ``M`` (viscous friction ``b`` to the ground) carries a point mass ``m`` on a
massless rod of length ``l``, hinged on the cart; ``theta`` is the rod's angle from the
upright, positive when the mass is ahead of the cart (``+x``). A force ``F`` on the cart
comes from the state feedback ``F = -K (x - x_ref, x', theta, theta')`` with ``K`` the
linear-quadratic regulator of the upright linearisation (weights ``Q = diag(10, 1, 100,
1)``, ``R = 0.1``), computed when the model is built. Released at ``theta0`` from rest,
the controller rights the pendulum and moves the cart to ``x_ref``.

Equations of motion (Lagrange, with ``T = 1/2 (M+m) x'^2 + m l x' theta' cos(theta)
+ 1/2 m l^2 theta'^2`` and ``V = m g l cos(theta)``):
``(M+m) x'' + m l theta'' cos(theta) - m l theta'^2 sin(theta) = F - b x'`` and
``m l x'' cos(theta) + m l^2 theta'' - m g l sin(theta) = 0``.
"""

from __future__ import annotations

import casadi as ca
import numpy as np
from scipy.linalg import solve_continuous_are

import mechatron as mt
from mechatron.models.entry import Experiment, ModelEntry, ParameterInfo
from mechatron.models.registry import register

__all__ = ["CartPendulumEquation", "linearization", "lqr_gain", "Q", "R"]

G = 9.81
CHOSEN = "chosen: a laboratory cart-pole"
Q = np.diag([10.0, 1.0, 100.0, 1.0])
R = np.array([[0.1]])


def linearization(M: float, m: float, l: float, b: float) -> tuple[np.ndarray, np.ndarray]:
    """``A, B`` of the upright linearisation, state ``(x, x', theta, theta')``, input F."""
    a = np.array([[0, 1, 0, 0],
                  [0, -b / M, -m * G / M, 0],
                  [0, 0, 0, 1],
                  [0, b / (M * l), (M + m) * G / (M * l), 0]])
    bb = np.array([[0], [1 / M], [0], [-1 / (M * l)]])
    return a, bb


def lqr_gain(M: float, m: float, l: float, b: float) -> np.ndarray:
    """The LQR gain ``K`` (1 x 4) for the weights :data:`Q`, :data:`R`."""
    a, bb = linearization(M, m, l, b)
    p = solve_continuous_are(a, bb, Q, R)
    return np.linalg.solve(R, bb.T @ p)


class CartPendulumEquation(mt.Component):
    """Cart-pole from Lagrange's equations with LQR state feedback on the cart force."""

    M = mt.Parameter("kg", default=1.0, min=0, doc="Cart mass")
    m = mt.Parameter("kg", default=0.2, min=0, doc="Pendulum point mass")
    l = mt.Parameter("m", default=0.5, min=0, doc="Rod length")
    b = mt.Parameter("N*s/m", default=0.1, min=0, doc="Cart viscous friction")
    x_ref = mt.Parameter("m", default=0.5, doc="Cart position reference")
    k_x = mt.Parameter("N/m", default=0.0, doc="Feedback gain on the position")
    k_v = mt.Parameter("N*s/m", default=0.0, doc="Feedback gain on the velocity")
    k_th = mt.Parameter("N/rad", default=0.0, doc="Feedback gain on the angle")
    k_w = mt.Parameter("N*s/rad", default=0.0, doc="Feedback gain on the angular velocity")
    g = mt.Parameter("m/s^2", default=G, min=0, doc="Gravitational acceleration")
    x = mt.Variable("m", start=0.0, doc="Cart position")
    v = mt.Variable("m/s", start=0.0, doc="Cart velocity")
    theta = mt.Variable("rad", start=0.1, doc="Rod angle from the upright")
    w = mt.Variable("rad/s", start=0.0, doc="Rod angular velocity")
    F = mt.Variable("N", doc="Force on the cart")

    def equations(self):
        M, m, l = self.M, self.m, self.l
        s, c = ca.sin(self.theta), ca.cos(self.theta)
        return [mt.der(self.x) == self.v,
                mt.der(self.theta) == self.w,
                self.F == -(self.k_x * (self.x - self.x_ref) + self.k_v * self.v
                            + self.k_th * self.theta + self.k_w * self.w),
                (M + m) * mt.der(self.v) + m * l * mt.der(self.w) * c
                - m * l * self.w ** 2 * s == self.F - self.b * self.v,
                m * l * mt.der(self.v) * c + m * l ** 2 * mt.der(self.w)
                - m * self.g * l * s == 0]


def _equation(M, m, l, b, x_ref, theta0):
    k = lqr_gain(M, m, l, b).ravel()
    model = CartPendulumEquation(M=M, m=m, l=l, b=b, x_ref=x_ref, k_x=k[0], k_v=k[1],
                                 k_th=k[2], k_w=k[3], theta=theta0)
    model._name = "cart_pendulum"
    return model


ENTRY = register(ModelEntry(
    name="cart_pendulum",
    description=("Inverted pendulum on a cart balanced by LQR state feedback: released at "
                 "an angle, it is righted while the cart moves to its reference."),
    parameters={
        "M": ParameterInfo("kg", 1.0, "Cart mass", CHOSEN),
        "m": ParameterInfo("kg", 0.2, "Pendulum point mass", CHOSEN),
        "l": ParameterInfo("m", 0.5, "Rod length", CHOSEN),
        "b": ParameterInfo("N*s/m", 0.1, "Cart viscous friction", CHOSEN),
        "x_ref": ParameterInfo("m", 0.5, "Cart position reference", CHOSEN),
        "theta0": ParameterInfo("rad", 0.1, "Initial rod angle from the upright", CHOSEN),
    },
    variants={"equation": _equation},
    outputs={"equation": {"x": "x", "theta": "theta", "F": "F"}},
    output_units={"x": "m", "theta": "rad", "F": "N"},
    experiment=Experiment(t_stop=15.0, rtol=1e-10, atol=1e-12),
    expected={"x": 0.5},
    expected_tolerance=1e-6,
    tags=("mechanical", "control", "pendulum"),
))
