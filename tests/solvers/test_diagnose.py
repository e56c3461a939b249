"""A run whose values stop being finite names the variable, the operation and the values
that broke it (replayed from the compiled functions), not just "not finite"."""

import casadi as ca
import numpy as np
import pytest

import mechatron as mt
from mechatron.errors import SimulationError
from mechatron.solvers.diagnose import first_nonfinite


class LogOfFalling(mt.Component):
    x = mt.Variable("1", start=1.0, doc="Falls at unit rate")
    y = mt.Variable("1", doc="log(x): breaks when x < 0 (t > 1)")

    def equations(self):
        return [mt.der(self.x) == -1.0, self.y == ca.log(self.x)]


class DividedByZero(mt.Component):
    x = mt.Variable("1", start=1.0, doc="Rises until x = 2 at t = 1")
    k = mt.Parameter("1", default=0.0, doc="Zero: divides")

    def equations(self):
        return [mt.der(self.x) == (self.x - self.x + 1.0) / self.k]


@pytest.mark.parametrize("solver", ["auto", "cvodes", "rk4"])
def test_a_log_of_a_negative_number_is_named_with_its_value_and_time(solver):
    with pytest.raises(SimulationError) as info:
        mt.simulate(LogOfFalling(), 2.0, solver=solver, dt=0.01)
    text = str(info.value)
    assert "y: log of a negative number" in text
    t_bad = float(text.split("from t = ")[1].split(" s")[0])
    assert 1.0 - 0.011 <= t_bad <= 1.0 + 0.011      # x crosses zero at t = 1
    assert info.value.variables == ["y"]


def test_a_division_by_zero_in_a_derivative_is_named():
    with pytest.raises(SimulationError, match=r"der\(x\): division by zero \(1 / 0\), at "
                                              r"t = 0 s"):
        mt.simulate(DividedByZero(), 1.0, solver="rk4", dt=0.1)


def test_the_replay_finds_the_first_broken_operation_and_what_it_reaches():
    a = ca.SX.sym("a")
    f = ca.Function("f", [a], [ca.vertcat(a + 1, ca.sqrt(a), 2 * ca.sqrt(a), a * a)])
    what, first, reached = first_nonfinite(f, [-4.0])
    assert what == "square root of a negative number, sqrt(-4)"
    assert (first, reached) == (1, 2)
    assert first_nonfinite(f, [4.0]) is None
    # a non-finite input is no operation's fault
    assert first_nonfinite(f, [np.nan]) is None


class LogInALoop(mt.Component):
    x = mt.Variable("1", start=-1.0, doc="Negative from the start")
    y = mt.Variable("1", doc="log(x): not finite")
    z = mt.Variable("1", start=1.0, doc="Algebraic: z^3 + z = y")

    def equations(self):
        return [mt.der(self.x) == -1.0, self.y == ca.log(self.x),
                self.z ** 3 + self.z == self.y]


def test_a_dae_solver_failing_at_the_start_names_the_equation():
    with pytest.raises(SimulationError, match=r"At the start: the algebraic equation solved "
                                              r"for z: log of a negative number, log\(-1\)"):
        mt.simulate(LogInALoop(), 1.0, solver="idas")
