"""The compiler changes that mechanisms need, tested on small systems: state preference
(``Variable(state_select=...)``) and tearing that never divides by a coefficient which
vanishes in some configuration."""

import math

import casadi as ca
import numpy as np
import pytest

import mechatron as mt
from mechatron.library.multibody import mechanisms as mech
from mechatron.library.multibody.reference import double_pendulum_rhs


def pendulum_class(select):
    class Pendulum(mt.Component):
        """Cartesian pendulum with its angle: ``x = L sin(th)``, ``y = -L cos(th)``,
        ``m x'' = -T x / L``, ``m y'' = -T y / L - m g``."""

        L = mt.Parameter("m", default=1.0, doc="Length")
        g = mt.Parameter("m/s^2", default=9.81, doc="Gravity")
        th = mt.Variable("rad", start=0.0, state_select=select, doc="Angle")
        x = mt.Variable("m", doc="x")
        y = mt.Variable("m", doc="y")
        vx = mt.Variable("m/s", doc="x velocity")
        vy = mt.Variable("m/s", doc="y velocity")
        T = mt.Variable("N/kg", doc="Rod tension per unit mass")

        def equations(self):
            return [self.x == self.L * ca.sin(self.th), self.y == -self.L * ca.cos(self.th),
                    mt.der(self.x) == self.vx, mt.der(self.y) == self.vy,
                    mt.der(self.vx) == -self.T * self.x / self.L,
                    mt.der(self.vy) == -self.T * self.y / self.L - self.g]
    return Pendulum


def test_state_select_prefer_keeps_the_angle_as_a_state():
    plain = mt.compile_model(pendulum_class("default")(th=mt.Start(0.3, "low")))
    preferred = mt.compile_model(pendulum_class("prefer")(th=mt.Start(0.3, "low")))
    assert "th" not in plain.state_names        # the structural default is Cartesian
    assert "th" in preferred.state_names
    assert preferred.nx == 2


def test_preferred_angle_state_carries_the_pendulum_over_the_top():
    """Released at the bottom with enough speed to loop: x passes through +-L, where a
    Cartesian state would be singular; with the angle as state the run goes through and
    conserves energy."""
    cls = pendulum_class("prefer")
    pend = cls(th=0.0, vx=7.0)                  # v^2 > 4 g L: it loops
    res = mt.simulate(pend, 3.0, rtol=1e-10, atol=1e-12)
    assert res["th"][-1] > 2 * math.pi
    e = 0.5 * (res["vx"] ** 2 + res["vy"] ** 2) + 9.81 * res["y"]
    assert np.max(np.abs(e - e[0])) < 1e-7 * abs(e[0])


@pytest.mark.parametrize("a1, a2", [(math.pi / 2, 0.0), (0.0, 0.0), (math.pi, 0.0),
                                    (0.3, -2.0), (math.pi / 2, math.pi / 2)])
def test_compiled_double_pendulum_is_finite_in_every_configuration(a1, a2):
    """The torn loops of the double pendulum hold sin/cos coefficients of the joint
    angles; solving for them would give 0/0 where they vanish (links vertical or
    horizontal). The compiled derivative must match the Lagrange equations there."""
    cm = mt.compile_model(mech.double_pendulum())
    index = {n: k for k, n in enumerate(cm.state_names)}
    w1, w2 = 0.7, -1.1
    x = np.zeros(cm.nx)
    x[index["j1.q"]], x[index["j2.q"]] = a1, a2 - a1
    x[index["j1.w"]], x[index["j2.w"]] = w1, w2 - w1
    xdot = np.array(cm.f_ode(0.0, x, [], cm.p0), dtype=float).ravel()
    assert np.all(np.isfinite(xdot))
    ref = double_pendulum_rhs(0.0, [a1, a2, w1, w2])
    assert xdot[index["j1.w"]] == pytest.approx(ref[2], abs=1e-12)
    assert xdot[index["j2.w"]] == pytest.approx(ref[3] - ref[2], abs=1e-12)
