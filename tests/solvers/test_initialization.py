"""Consistent initialization with start-value priorities."""

import casadi as ca
import numpy as np
import pytest

import mechatron as mt
from mechatron.errors import InitializationError
from mechatron.library import electrical as el
from mechatron.library import rotational as rot

from compiler.test_index_reduction import GearedInertias


def test_high_target_on_a_non_state_sets_the_state():
    m = GearedInertias()
    m.j2._starts["w"] = mt.Start(3.0, "high")
    res = mt.simulate(m, 1e-3, rtol=1e-10, atol=1e-12)
    assert res["j2.w"][0] == pytest.approx(3.0, rel=1e-9)
    assert res["j1.w"][0] == pytest.approx(9.0, rel=1e-9)
    entry = next(e for e in res.initialization if e["variable"] == "j2.w")
    assert entry["met"] and entry["priority"] == "high"


def test_low_target_yields_to_a_high_one_and_the_report_says_so():
    m = GearedInertias()
    m.j1._starts["w"] = mt.Start(9.0, "high")
    m.j2._starts["w"] = mt.Start(5.0, "low")
    res = mt.simulate(m, 1e-3)
    report = {e["variable"]: e for e in res.initialization}
    assert report["j1.w"]["met"]
    assert not report["j2.w"]["met"]
    assert report["j2.w"]["value"] == pytest.approx(3.0, rel=1e-6)


def test_conflicting_high_targets_name_both():
    m = mt.System("parallel")
    src = m.add("src", el.DCVoltageSource(V=1.0))
    r1 = m.add("r1", el.Resistor(R=10.0))
    c1 = m.add("c1", el.Capacitor(C=1e-3, v=1.0))
    c2 = m.add("c2", el.Capacitor(C=2e-3, v=2.0))
    g = m.add("g", el.ElectricalReference())
    m.connect(src.p, r1.p)
    m.connect(r1.n, c1.p, c2.p)
    m.connect(src.n, c1.n, c2.n, g.port)
    with pytest.raises(InitializationError, match=r"c1\.v.*c2\.v|c2\.v.*c1\.v") as info:
        mt.simulate(m, 1e-3)
    assert {"c1.v", "c2.v"} <= set(info.value.variables)


def test_state_start_values_are_used_and_reported():
    m = mt.System("decay")
    j = m.add("j", rot.Inertia(J=2.0, w="60 rpm"))
    d = m.add("d", rot.RotationalDamper(D=4.0))
    ref = m.add("ref", rot.RotationalReference())
    m.connect(j.port, d.A)
    m.connect(d.B, ref.port)
    res = mt.simulate(m, 1.0, rtol=1e-10, atol=1e-12)
    import math
    w0 = 2 * math.pi
    assert res["j.w"][0] == pytest.approx(w0)
    assert res.final("j.w") == pytest.approx(w0 * math.exp(-4.0 / 2.0), rel=1e-8)
    assert res.initialization[0]["variable"] == "j.w" and res.initialization[0]["met"]


class _Loop(mt.Component, partial=True):
    """Test-only: a state and an algebraic unknown of a nonlinear implicit equation."""

    x = mt.Variable("1", start=0.5, doc="State")
    y = mt.Variable("1", start=0.3, doc="Algebraic unknown")


class ImplicitRoot(_Loop):
    def equations(self):
        return [mt.der(self.x) == -self.y, self.y + ca.exp(self.y) == 2 + self.x]


class NoRealRoot(_Loop):
    def equations(self):
        return [mt.der(self.x) == -self.y, self.y * self.y + 1 == 0.1 * ca.sin(self.x)]


def test_a_converged_initial_point_solves_the_algebraic_equation():
    cm = mt.compile_model(ImplicitRoot())
    assert cm.alg_names == ["y"]
    res = mt.simulate(cm, 0.1)
    # nothing asks x to move: it keeps its start value, and y solves the loop from its
    # guess (a start value of its own, 0.3, that the root 0.68 does not keep)
    x0, y0 = res["x"][0], res["y"][0]
    assert x0 == 0.5
    assert y0 + np.exp(y0) == pytest.approx(2 + x0, abs=1e-8)
    assert res.initialization == []


def test_an_initial_point_that_does_not_converge_names_the_equation_not_a_conflict():
    # y^2 + 1 = 0.1 sin(x) has no real root: no target conflicts, the solve cannot
    # converge, and the message says so instead of "conflicting targets: unknown"; x is
    # held at its start value, so the least residual is 1 - 0.1 sin(0.5) = 0.952 (at y = 0)
    with pytest.raises(InitializationError,
                       match=r"'NoRealRoot': the initial point did not converge at t0 = 0 s "
                             r"\(IPOPT: .*\); largest residuals: algebraic equation 1 "
                             r"\(for y\) \(residual 0\.952\)\. Give start values closer") as e:
        mt.simulate(NoRealRoot(), 0.1)
    assert e.value.variables == ["y"]
