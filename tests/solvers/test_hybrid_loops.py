"""Algebraic loops of blocks: linear ones solved symbolically, nonlinear ones by the
solver, singular ones reported with the blocks in the loop."""

import numpy as np
import pytest

import mechatron as mt
from mechatron.library import blocks

T = np.linspace(0, 1, 11)


def feedback_loop(k, function=None):
    """e = r - g(k e): a sum whose output feeds back through a gain (and a function)."""
    m = mt.System("loop")
    r = m.add("r", blocks.Sine(amplitude=2.0, f=1.0))
    s = m.add("sum", blocks.Subtract())
    g = m.add("gain", blocks.Gain(k=k))
    m.connect(r.y, s.u1)
    m.connect(s.y, g.u)
    if function:
        f = m.add("fn", blocks.MathFunction(function))
        m.connect(g.y, f.u)
        m.connect(f.y, s.u2)
    else:
        m.connect(g.y, s.u2)
    return m


def test_linear_loop_of_blocks_is_solved_exactly():
    res = mt.simulate(feedback_loop(3.0), 1.0, t_out=T)
    r = 2.0 * np.sin(2 * np.pi * T)
    np.testing.assert_allclose(res["sum.y"], r / (1 + 3.0), atol=1e-14)


def test_nonlinear_loop_of_blocks_is_solved_by_the_solver():
    cm = mt.compile_model(feedback_loop(0.5, "tanh"))
    assert cm.nz == 1        # one tearing variable left to the DAE solver
    res = mt.simulate(cm, 1.0, t_out=T)
    e, r = res["sum.y"], 2.0 * np.sin(2 * np.pi * T)
    np.testing.assert_allclose(e + np.tanh(0.5 * e), r, atol=1e-6)
    assert np.ptp(e) > 1.0


def test_singular_loop_names_the_blocks_in_it():
    with pytest.raises(mt.errors.StructuralError,
                       match=r"algebraic loop through sum, gain has no unique solution"
                       ) as err:
        mt.compile_model(feedback_loop(-1.0))     # e = r + e: no solution
    assert set(err.value.variables) == {"sum", "gain"}


def test_loop_broken_by_a_unit_delay_compiles_and_runs():
    m = mt.System("dloop")
    r = m.add("r", blocks.Constant(value=1.0))
    s = m.add("sum", blocks.Subtract())
    g = m.add("gain", blocks.Gain(k=-1.0))
    d = m.add("delay", blocks.UnitDelay(Ts=0.1))
    m.connect(r.y, s.u1)
    m.connect(s.y, g.u)
    m.connect(g.y, d.u)
    m.connect(d.y, s.u2)
    res = mt.simulate(m, 0.5, t_out=np.arange(5) * 0.1 + 0.05)
    # e_k = 1 + e_k-1: the accumulating sum 1, 2, 3, ...
    np.testing.assert_allclose(res["sum.y"], [1, 2, 3, 4, 5], atol=1e-12)
