"""Hand-written NumPy right-hand sides of the reference mechanisms, for SciPy's
``solve_ivp``: independent implementations that the tests and the benchmarks compare the
multibody models with. They share no code with the acausal components.

- :func:`double_pendulum_rhs`: the Lagrange equations (seed eqs. 14-15), absolute angles
  from the downward vertical, state ``(a1, a2, w1, w2)``.
- :func:`four_bar_rhs`: the four-bar of :func:`~mechatron.library.multibody.mechanisms.
  four_bar` reduced to its one degree of freedom, the crank angle ``theta``, by the
  closed-form position analysis and Lagrange's equation
  ``M(theta) theta'' + M'(theta) theta'^2 / 2 + dV/dtheta = tau - D theta'``,
  state ``(theta, theta')``.
"""

from __future__ import annotations

import math

import numpy as np

#: Standard gravity (m/s^2), the bodies' default ``g``; written here again, not imported,
#: so that the references share nothing with the components.
G = 9.80665

__all__ = ["double_pendulum_rhs", "double_pendulum_energy", "four_bar_rhs",
           "FourBarGeometry"]


def double_pendulum_rhs(t, s, m1=1.0, m2=1.0, l1=1.0, l2=1.0, g=G):
    """``d/dt (a1, a2, w1, w2)`` of the double pendulum (point masses, massless rods)."""
    a1, a2, w1, w2 = s
    d = a1 - a2
    c, sn = math.cos(d), math.sin(d)
    # [(m1+m2) l1, m2 l2 c; l1 c, l2] [w1'; w2'] = rhs
    a11, a12 = (m1 + m2) * l1, m2 * l2 * c
    a21, a22 = l1 * c, l2
    b1 = -m2 * l2 * w2 * w2 * sn - (m1 + m2) * g * math.sin(a1)
    b2 = l1 * w1 * w1 * sn - g * math.sin(a2)
    det = a11 * a22 - a12 * a21
    return [w1, w2, (b1 * a22 - a12 * b2) / det, (a11 * b2 - a21 * b1) / det]


def double_pendulum_energy(a1, a2, w1, w2, m1=1.0, m2=1.0, l1=1.0, l2=1.0, g=G):
    """Total energy (kinetic + potential, zero at the pivot's height)."""
    v2sq = (l1 * w1) ** 2 + (l2 * w2) ** 2 + 2 * l1 * l2 * w1 * w2 * np.cos(a1 - a2)
    y1 = -l1 * np.cos(a1)
    y2 = y1 - l2 * np.cos(a2)
    return 0.5 * m1 * (l1 * w1) ** 2 + 0.5 * m2 * v2sq + g * (m1 * y1 + m2 * y2)


class FourBarGeometry:
    """Kinematics of the four-bar ``A(0,0) - B - C - D(d,0)`` as functions of the crank
    angle, with the first and second derivatives of the coupler angle ``p2`` and of the
    angle ``p3`` of the vector from C to D, from the loop equation
    ``a e(theta) + b e(p2) + c e(p3) = (d, 0)``, ``e(p) = (cos p, sin p)``."""

    def __init__(self, a, b, c, d, branch=1):
        self.a, self.b, self.c, self.d, self.branch = a, b, c, d, branch

    def angles(self, theta):
        a, b, c, d = self.a, self.b, self.c, self.d
        bx, by = a * math.cos(theta), a * math.sin(theta)
        ex, ey = d - bx, -by
        e = math.hypot(ex, ey)
        gamma = math.acos(max(-1.0, min(1.0, (b * b + e * e - c * c) / (2 * b * e))))
        p2 = math.atan2(ey, ex) + self.branch * gamma
        cx, cy = bx + b * math.cos(p2), by + b * math.sin(p2)
        return p2, math.atan2(-cy, d - cx)

    def rates(self, theta):
        """``(p2, p3, p2', p3', p2'', p3'')``, derivatives with respect to theta."""
        a, b, c = self.a, self.b, self.c
        p2, p3 = self.angles(theta)
        # d/dtheta of the loop: b e'(p2) p2' + c e'(p3) p3' = -a e'(theta)
        m = np.array([[-b * math.sin(p2), -c * math.sin(p3)],
                      [b * math.cos(p2), c * math.cos(p3)]])
        r1 = np.array([a * math.sin(theta), -a * math.cos(theta)])
        d2, d3 = np.linalg.solve(m, r1)
        # second derivative: b (e'(p2) p2'' - e(p2) p2'^2) + c (...) = a e(theta)
        r2 = np.array([a * math.cos(theta) + b * math.cos(p2) * d2 ** 2
                       + c * math.cos(p3) * d3 ** 2,
                       a * math.sin(theta) + b * math.sin(p2) * d2 ** 2
                       + c * math.sin(p3) * d3 ** 2])
        dd2, dd3 = np.linalg.solve(m, r2)
        return p2, p3, d2, d3, dd2, dd3


def four_bar_rhs(geom: FourBarGeometry, density=1.0, torque=1.0, damping=0.1, g=G):
    """The reduced ODE of the torque-driven four-bar with uniform bars (mass
    ``density * L``, ``J = m L^2 / 12`` about the centre). Returns ``f(t, s)``."""
    a, b, c = geom.a, geom.b, geom.c
    ms = [density * a, density * b, density * c]
    js = [mi * li * li / 12 for mi, li in zip(ms, (a, b, c))]

    def rhs(t, s):
        theta, w = s
        p2, p3, d2, d3, dd2, dd3 = geom.rates(theta)
        ang = [(theta, 1.0, 0.0), (p2, d2, dd2), (p3, d3, dd3)]

        def e(p):
            return np.array([math.cos(p), math.sin(p)])

        def ep(p):
            return np.array([-math.sin(p), math.cos(p)])

        # centres of mass: r_i = sum of full links before + half of link i; their first
        # and second derivatives with respect to theta
        lengths = (a, b, c)
        dr, ddr = [], []
        acc1, acc2 = np.zeros(2), np.zeros(2)
        for (p, dp, ddp), length in zip(ang, lengths):
            d1 = ep(p) * dp
            d2_ = -e(p) * dp * dp + ep(p) * ddp
            dr.append(acc1 + 0.5 * length * d1)
            ddr.append(acc2 + 0.5 * length * d2_)
            acc1 = acc1 + length * d1
            acc2 = acc2 + length * d2_
        mass = sum(mi * float(v @ v) for mi, v in zip(ms, dr)) \
            + sum(ji * dp * dp for ji, (_, dp, _) in zip(js, ang))
        dmass = sum(2 * mi * float(v @ dv) for mi, v, dv in zip(ms, dr, ddr)) \
            + sum(2 * ji * dp * ddp for ji, (_, dp, ddp) in zip(js, ang))
        dpot = g * sum(mi * v[1] for mi, v in zip(ms, dr))
        alpha = (torque - damping * w - 0.5 * dmass * w * w - dpot) / mass
        return [w, alpha]

    return rhs
