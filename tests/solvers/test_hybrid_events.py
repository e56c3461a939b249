"""The event language (mt.when, mt.sample) on textbook hybrid systems with analytic
answers: re-initialization of continuous states, mode memory, unknown targets."""

import numpy as np
import pytest

import mechatron as mt

G, E, H0 = 9.81, 0.8, 1.0


class BouncingBall(mt.Component):
    """Free fall with an impact law: when ``h <= 0``, ``v := -e v``."""

    h = mt.Variable("m", start=H0, doc="Height")
    v = mt.Variable("m/s", start=0.0, doc="Velocity")
    e = mt.Parameter("1", default=E, doc="Coefficient of restitution")

    def equations(self):
        return [mt.der(self.h) == self.v, mt.der(self.v) == -G,
                mt.when(self.h <= 0, update={self.v: -self.e * self.v})]


def impact_times(n):
    t1 = np.sqrt(2 * H0 / G)
    v1 = G * t1
    gaps = [2 * E ** k * v1 / G for k in range(1, n)]
    return t1 + np.concatenate([[0.0], np.cumsum(gaps)])


def test_bouncing_ball_reinitializes_its_velocity_at_the_analytic_impacts():
    cm = mt.compile_model(BouncingBall())
    times = impact_times(5)
    for k in range(4):
        res = mt.simulate(cm, (times[k] + times[k + 1]) / 2, rtol=1e-11, atol=1e-12)
        assert abs(res.event_times[""] - times[k]) < 1e-9
        # velocity just after impact k: e^(k+1) v1 upwards, minus gravity since
        v_after = E ** (k + 1) * G * times[0] - G * (res.t[-1] - times[k])
        assert res.final("v") == pytest.approx(v_after, rel=1e-8)
    # one event per impact (the condition is left again at once, without an event)
    assert res.stats.events[""] == 4


def test_bouncing_ball_in_fixed_step_bounces_at_the_step_ends():
    res = mt.simulate(BouncingBall(), 1.0, solver="rk4", dt=1e-4)
    t_first = impact_times(1)[0]
    k = np.argmax(res["v"] > 0)            # first step after the bounce
    assert abs(res.t[k] - t_first) <= 1e-4
    # the energy after the first bounce is e^2 of the initial (to the step's resolution)
    energy = 0.5 * res["v"] ** 2 + G * res["h"]
    assert energy[k + 10] == pytest.approx(E ** 2 * G * H0, rel=2e-3)


def test_assigning_a_computed_variable_is_an_error_naming_its_equation():
    class Bad(mt.Component):
        x = mt.Variable("1", start=0.0, doc="State")
        y = mt.Variable("1", doc="Computed")

        def equations(self):
            return [mt.der(self.x) == 1.0, self.y == 2 * self.x,
                    mt.when(self.x >= 0.5, update={self.y: 0.0})]

    # an assigned variable is a discrete state (der(y) == 0): y == 2 x is one too many
    with pytest.raises(mt.errors.StructuralError,
                       match=r"3 equations for 2 unknowns.*extra equation\(s\): Bad: y =="):
        mt.compile_model(Bad())


def test_when_needs_a_single_relation_and_sample_a_clock():
    with pytest.raises(mt.errors.ModelError, match="one relation"):
        mt.when(mt.Parameter is None, update={})
    with pytest.raises(mt.errors.ModelError, match="expected a Clock"):
        mt.sample(0.1, update={})
