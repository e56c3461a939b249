"""Sources, math, logic and routing blocks against NumPy/SciPy evaluations."""

import numpy as np
import pytest
from scipy.interpolate import RegularGridInterpolator

import mechatron as mt
from mechatron.library import blocks

T = np.linspace(0, 1, 401)


def run(build, t=T, **kw):
    m = mt.System("sig")
    build(m)
    return mt.simulate(m, t[-1], t_out=t, rtol=1e-10, atol=1e-12, **kw)


def sines(m):
    a = m.add("a", blocks.Sine(amplitude=2.0, f=1.0))
    b = m.add("b", blocks.Sine(amplitude=1.5, f=2.0, phase=0.4, offset=0.3))
    return a, b


A = 2.0 * np.sin(2 * np.pi * T)
TABLE = np.array([[1, 2, 3], [0, -1, 4], [2, 2, 2], [5, 0, 1]], float)
B = 0.3 + 1.5 * np.sin(4 * np.pi * T + 0.4)


@pytest.mark.parametrize("block, expect", [
    (lambda: blocks.Product(), A * B),
    (lambda: blocks.Add(k1=2.0, k2=-0.5), 2 * A - 0.5 * B),
    (lambda: blocks.Subtract(), A - B),
    (lambda: blocks.Min(), np.minimum(A, B)),
    (lambda: blocks.Max(), np.maximum(A, B)),
    (lambda: blocks.Atan2(), np.arctan2(A, B)),
    (lambda: blocks.Compare(op=">="), (A >= B).astype(float)),
    (lambda: blocks.LookupTable2D(breakpoints1=[-2, 0, 1, 2], breakpoints2=[-1.5, 0, 2],
                                  table=TABLE),
     RegularGridInterpolator(([-2, 0, 1, 2], [-1.5, 0, 2]), TABLE)(
         np.column_stack([np.clip(A, -2, 2), np.clip(B, -1.5, 2)]))),
])
def test_two_input_blocks(block, expect):
    def build(m):
        a, b = sines(m)
        blk = m.add("blk", block())
        m.connect(a.y, blk.u1)
        m.connect(b.y, blk.u2)
    res = run(build)
    # a comparison is exact away from its switching instants
    away = np.abs(A - B) > 1e-9
    np.testing.assert_allclose(res["blk.y"][away], expect[away], atol=1e-9)


@pytest.mark.parametrize("block, fn", [
    (lambda: blocks.Gain(k=-2.5), lambda u: -2.5 * u),
    (lambda: blocks.Bias(bias=0.7), lambda u: u + 0.7),
    (lambda: blocks.Abs(), np.abs),
    (lambda: blocks.Sign(), np.sign),
    (lambda: blocks.MathFunction("sin"), np.sin),
    (lambda: blocks.MathFunction("exp"), np.exp),
    (lambda: blocks.MathFunction("square"), np.square),
    (lambda: blocks.MathFunction("atan"), np.arctan),
    (lambda: blocks.MathFunction("tanh"), np.tanh),
    (lambda: blocks.CompareToConstant(op="<", c=0.5), lambda u: (u < 0.5).astype(float)),
    (lambda: blocks.ToBoolean(), lambda u: (u != 0).astype(float)),
    (lambda: blocks.LookupTable1D(breakpoints=[-1, 0, 0.5, 1.5], table=[3, -1, 0, 2]),
     lambda u: np.interp(u, [-1, 0, 0.5, 1.5], [3, -1, 0, 2])),
])
def test_one_input_blocks(block, fn):
    def build(m):
        a, _ = sines(m)
        blk = m.add("blk", block())
        m.connect(a.y, blk.u)
    res = run(build)
    away = (np.abs(A) > 1e-9) & (np.abs(A - 0.5) > 1e-9)
    np.testing.assert_allclose(res["blk.y"][away], fn(A)[away], atol=1e-9)


def test_logical_operators_on_boolean_signals():
    for op, fn in (("and", np.logical_and), ("or", np.logical_or), ("xor", np.logical_xor),
                   ("nand", lambda a, b: ~(a & b)), ("nor", lambda a, b: ~(a | b))):
        def build(m):
            a, b = sines(m)
            ca_ = m.add("ca", blocks.CompareToConstant(op=">", c=0.0))
            cb = m.add("cb", blocks.CompareToConstant(op=">", c=0.5))
            lo = m.add("lo", blocks.LogicalOperator(op))
            nt = m.add("nt", blocks.Not())
            m.connect(a.y, ca_.u)
            m.connect(b.y, cb.u)
            m.connect(ca_.y, lo.u1)
            m.connect(cb.y, lo.u2)
            m.connect(lo.y, nt.u)
        res = run(build)
        away = (np.abs(A) > 1e-9) & (np.abs(B - 0.5) > 1e-9)
        expect = fn(A > 0, B > 0.5).astype(float)
        np.testing.assert_array_equal(res["lo.y"][away], expect[away])
        np.testing.assert_array_equal(res["nt.y"][away], 1 - expect[away])


def test_switch_and_multiport_switch_route_their_inputs():
    def build(m):
        a, b = sines(m)
        sel = m.add("sel", blocks.Ramp(slope=3.0, initial=1.0))     # 1 -> 4 over 1 s
        sw = m.add("sw", blocks.Switch(threshold=0.0))
        ms = m.add("ms", blocks.MultiportSwitch(n=3))
        c = m.add("c", blocks.Constant(value=-7.0))
        m.connect(a.y, sw.u1, ms.u1)
        m.connect(b.y, sw.u2, ms.u2)
        m.connect(c.y, sw.u3, ms.u3)
        m.connect(sel.y, ms.c)
    res = run(build)
    away = np.abs(B) > 1e-9
    np.testing.assert_allclose(res["sw.y"][away], np.where(B >= 0, A, -7.0)[away],
                               atol=1e-9)
    c = 1 + 3 * T
    k = np.clip(np.floor(c + 0.5), 1, 3)
    expect = np.choose(k.astype(int) - 1, [A, B, np.full_like(A, -7.0)])
    away = np.abs(c - np.round(c - 0.5) - 0.5) > 1e-6
    np.testing.assert_allclose(res["ms.y"][away], expect[away], atol=1e-9)
    assert res.stats.events["ms"] == 2         # switches to u2 at c = 1.5, u3 at 2.5


def test_chirp_and_measured_data_sources():
    tdata = np.array([0.0, 0.2, 0.35, 0.6, 1.0])
    ydata = np.array([1.0, -0.5, 2.0, 2.0, 0.0])

    def build(m):
        m.add("ch", blocks.Chirp(amplitude=1.5, f0=1.0, f1=5.0, T=1.0))
        m.add("data", blocks.FromData(time=tdata, values=ydata))
    t = np.linspace(0, 1.2, 241)
    res = run(build, t=t)
    np.testing.assert_allclose(res["ch.y"], 1.5 * np.sin(2 * np.pi * (t + 2.0 * t ** 2)),
                               atol=1e-12)
    np.testing.assert_allclose(res["data.y"], np.interp(t, tdata, ydata), atol=1e-12)


def test_bad_tables_and_names_are_clear_errors():
    with pytest.raises(mt.errors.DataError, match="time must increase strictly"):
        blocks.FromData(time=[0, 1, 1], values=[0, 1, 2])
    with pytest.raises(mt.errors.DataError, match="not finite"):
        blocks.FromData(time=[0, 1, 2], values=[0, np.nan, 2])
    with pytest.raises(mt.errors.DataError, match="table must hold 3"):
        blocks.LookupTable1D(breakpoints=[0, 1, 2], table=[1, 2])
    with pytest.raises(mt.errors.ModelError, match="unknown function 'sine'"):
        blocks.MathFunction("sine")
    with pytest.raises(mt.errors.ModelError, match="improper transfer function"):
        blocks.TransferFunction(num=[1, 0, 0], den=[1, 1])
    with pytest.raises(TypeError, match="unexpected keyword 'gain'"):
        blocks.Gain(gain=2.0)
