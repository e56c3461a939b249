"""CompiledModel: saving, loading and pickling."""

import pickle

import numpy as np
import pytest

import mechatron as mt
from mechatron.compiler.compiled import _FUNCS
from mechatron.errors import DataError
from mechatron.library import blocks
from mechatron.library import electrical as el


def _rc_stepped() -> mt.System:
    """An RC circuit driven through a step (a time event): every function is there."""
    m = mt.System("rc_stepped")
    step = m.add("step", blocks.Step(t_step=0.01, final=1.0))
    src = m.add("src", el.ControlledVoltageSource())
    r = m.add("r", el.Resistor(R=1e3))
    c = m.add("c", el.Capacitor(C=1e-5))
    g = m.add("g", el.ElectricalReference())
    m.connect(step.y, src.u)
    m.connect(src.p, r.p)
    m.connect(r.n, c.p)
    m.connect(src.n, c.n, g.port)
    return m


def _at_random_points(f, rng):
    args = [rng.uniform(0.5, 1.5, f.size_in(i)) for i in range(f.n_in())]
    out = f(*args)
    return [np.array(a) for a in (out if isinstance(out, (list, tuple)) else [out])]


def test_a_loaded_model_deserializes_each_function_when_first_read(tmp_path):
    cm = mt.compile_model(_rc_stepped())
    assert cm.nr > 0
    back = mt.CompiledModel.load(cm.save(tmp_path / "rc.mtm"))
    present = [key for key in _FUNCS if getattr(cm, key) is not None]
    assert not any(key in vars(back) for key in present)     # nothing read yet
    ours = mt.simulate(cm, 0.05, solver="rodas4")
    theirs = mt.simulate(back, 0.05, solver="rodas4")
    assert np.array_equal(ours["c.v"], theirs["c.v"]) and np.array_equal(ours.t, theirs.t)
    for key in _FUNCS:
        f, g = getattr(cm, key), getattr(back, key)
        assert (f is None) == (g is None)
        if f is not None:
            assert g.name() == f.name() and g.name_in() == f.name_in()
            for a, b in zip(_at_random_points(f, np.random.default_rng(1)),
                            _at_random_points(g, np.random.default_rng(1))):
                assert np.array_equal(a, b, equal_nan=True), key


def test_a_model_pickled_again_before_its_functions_are_read_keeps_them(tmp_path):
    cm = mt.compile_model(_rc_stepped())
    back = mt.CompiledModel.load(cm.save(tmp_path / "rc.mtm"))
    back.f_ode                                        # one read, the others not
    again = pickle.loads(pickle.dumps(back))
    for key in _FUNCS:
        f, g = getattr(cm, key), getattr(again, key)
        assert (f is None) == (g is None), key
        if f is not None:
            for a, b in zip(_at_random_points(f, np.random.default_rng(2)),
                            _at_random_points(g, np.random.default_rng(2))):
                assert np.array_equal(a, b, equal_nan=True), key


def test_a_damaged_function_is_a_data_error_when_read():
    cm = pickle.loads(pickle.dumps(mt.compile_model(_rc_stepped())))
    text = cm._serialized["f_out"]
    cm._serialized["f_out"] = text[:len(text) // 2]
    with pytest.raises(DataError, match="model 'rc_stepped': its saved function f_out "
                                        "cannot be read"):
        cm.f_out
    assert cm.f_ode is not None                       # the others still read
