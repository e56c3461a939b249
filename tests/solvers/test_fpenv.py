"""Subnormal numbers are flushed to zero while a solver runs, and only then: the caller's
floating-point environment is the same after a run (also one that raises), and a run's
values differ from an unflushed run's by no more than the subnormals themselves."""

import numpy as np
import pytest

import mechatron as mt
from mechatron.errors import SimulationError
from mechatron.solvers import fpenv
from mechatron.solvers.fpenv import flushing_available, subnormals_flushed, subnormals_kept
from tests.solvers.test_logging import ladder

SUBNORMAL = 1e-310          # below np.finfo(float).tiny = 2.2e-308
TINY = np.finfo(float).tiny

needs_flush = pytest.mark.skipif(not flushing_available(),
                                 reason="no known fenv_t layout for this C library or "
                                        "processor: solvers run unflushed")


def flushes() -> bool:
    """Whether this thread's arithmetic now takes subnormal operands as zero."""
    return (np.array([SUBNORMAL]) * 1.0)[0] == 0.0


def test_outside_a_run_subnormals_are_numbers():
    assert not flushes()
    assert SUBNORMAL * 1.0 == SUBNORMAL


@needs_flush
def test_the_block_flushes_and_restores():
    with subnormals_flushed():
        assert flushes()
    assert not flushes()


@needs_flush
def test_the_environment_is_restored_when_the_block_raises():
    with pytest.raises(ZeroDivisionError):
        with subnormals_flushed():
            1 / 0
    assert not flushes()


@needs_flush
def test_an_inner_block_leaves_the_outer_flushing():
    with subnormals_flushed():
        with subnormals_flushed():
            assert flushes()
        assert flushes()
    assert not flushes()


@needs_flush
def test_a_long_ladder_runs_flushed_with_the_values_of_an_unflushed_run(monkeypatch):
    # each implicit step spreads the source's step along the whole ladder, decaying
    # geometrically: a band of capacitors sits below 1e-308 (3 % of the values here, three
    # quarters of them in a ladder of 10000 sections of 1 mF)
    cm = mt.compile_model(ladder(200, c=1.0))
    t_out = np.linspace(0.0, 1.0, 101)
    names = [f"c{k}.v" for k in range(200)] + [f"r{k}.i" for k in range(0, 200, 7)]
    with monkeypatch.context() as m:
        m.setattr(fpenv, "_environment", lambda: None)     # as where no layout is known
        plain = mt.simulate(cm, 1.0, t_out=t_out)
    flushed = mt.simulate(cm, 1.0, t_out=t_out)
    assert not flushes()
    a = np.array([plain[n] for n in names])
    b = np.array([flushed[n] for n in names])
    assert np.mean((a != 0) & (np.abs(a) < TINY)) > 0.01     # the unflushed run has them
    assert not np.any((b != 0) & (np.abs(b) < TINY))         # the flushed one has none
    assert plain.stats.steps == flushed.stats.steps
    # the flushed values' neighbours, near 1e-300, differ in their last digits; nothing
    # above 1e-290 does
    np.testing.assert_allclose(b, a, rtol=1e-12, atol=1e-290)


class Blowup(mt.Component):
    """``dx/dt = x^2`` from 1: infinite at t = 1."""

    x = mt.Variable("1", start=1.0, doc="State")

    def equations(self):
        return [mt.der(self.x) == self.x ** 2]


@needs_flush
@pytest.mark.parametrize("solver", ["cvodes", "rk4"])
def test_a_run_that_raises_in_the_integrator_restores_the_environment(solver):
    with pytest.raises(SimulationError):
        mt.simulate(Blowup(), 2.0, solver=solver, dt=0.01)
    assert not flushes()


@needs_flush
def test_a_kept_block_inside_a_flushed_one_keeps_subnormals():
    with subnormals_flushed():
        with subnormals_kept():
            assert not flushes()
        assert flushes()
    assert not flushes()


@needs_flush
def test_initialization_keeps_subnormals_when_the_caller_flushes_them():
    """A caller already flushing (a library built with fast-math sets the mode for the
    whole process): the diode clamp's initialization, whose IPOPT restoration fails with
    subnormals flushed, runs with them kept; the run itself flushes as always."""
    from tests.compiler.test_algebraic_loops import clamp_network, clamp_voltage
    cm = mt.compile_model(clamp_network())
    with subnormals_flushed():
        res = mt.simulate(cm, 1e-3, rtol=1e-10, atol=1e-14)
        assert flushes()
    assert res.final("d.v") == pytest.approx(clamp_voltage(), rel=1e-9)
