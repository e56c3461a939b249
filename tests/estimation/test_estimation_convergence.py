"""The Radau transcription of estimation refuses to return unconverged stages: a sample
whose Newton iteration did not converge is an error naming the interval and the state."""

import casadi as ca
import numpy as np
import pytest
from scipy.integrate import solve_ivp

import mechatron as mt
from mechatron.errors import SimulationError
from mechatron.estimation.discretize import Trajectory

K, X0 = 1e4, 10.0


class Atan(mt.Component):
    """``dx/dt = -k atan(x)`` from x = 10: Newton on atan overshoots from far away."""

    x = mt.Variable("1", start=X0, doc="State")
    k = mt.Parameter("1/s", default=K, doc="Rate")

    def equations(self):
        return [mt.der(self.x) == -self.k * ca.atan(self.x)]


def trajectory(dt, substeps):
    cm = mt.compile_model(Atan())
    t = np.arange(6) * dt
    return cm, t, Trajectory(cm, t, [], [cm.names.index("x")], substeps=substeps)


def test_an_unconverged_sample_is_an_error_not_a_result():
    cm, t, tr = trajectory(1e-2, 1)        # h k = 100 from x = 10: Newton diverges
    with pytest.raises(SimulationError, match=r"Radau IIA substeps did not converge "
                                              r"between t = 0 s and 0\.01 s \(sample 0, "
                                              r".*largest for x \(") as info:
        tr(cm.p0, np.array([X0]), np.zeros((0, t.size)))
    assert info.value.variables == ["x"]
    # what it used to return: far above the start value of a decaying state
    Y, _ = tr.function(cm.p0, np.array([X0]), np.zeros((0, t.size)))
    assert np.max(np.array(Y)) > 10 * X0
    # the sensitivities are checked as well
    with pytest.raises(SimulationError, match="did not converge"):
        tr.sensitivity_function(np.eye(1))(cm.p0, np.array([X0]), np.zeros((0, t.size)),
                                           np.zeros((1, 1)))


def test_converged_samples_are_returned_unchanged_and_accurate():
    cm, t, tr = trajectory(1e-4, 4)
    Y, X = tr(cm.p0, np.array([X0]), np.zeros((0, t.size)))
    Yu, _ = tr.function(cm.p0, np.array([X0]), np.zeros((0, t.size)))
    np.testing.assert_array_equal(Y, np.array(Yu))
    ref = solve_ivp(lambda _, x: -K * np.arctan(x), (0, t[-1]), [X0], method="Radau",
                    t_eval=t, rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(Y[0], ref.y[0], rtol=1e-6)
