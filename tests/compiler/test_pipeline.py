"""`compile_model` as a whole (mechatron.compiler.pipeline): what a compile leaves behind."""

import gc
from collections import Counter

import pytest

import mechatron as mt
from tests.compiler.test_flatten_templates import ladder, stop_and_springs
from tests.compiler.test_folding import deep_ladder, two_drives

MODELS = {
    "templates": lambda: ladder(20),               # classes used 20 times: templates
    "hybrid": stop_and_springs,                    # pre(), impacts, templates beside
    "subsystems": deep_ladder,                     # subsystem ports folded into nodes
    "subsystem_drives": two_drives,
    "database_bldc": lambda: mt.models.get("bldc_motor").build(),   # inverter, Hall
}


@pytest.mark.parametrize("name", list(MODELS))
def test_a_compile_leaves_no_reference_cycles(name):
    """What a compile makes and drops is freed by reference counts as it goes, not left
    to the cyclic garbage collector, which is paused while compiling. The template
    equations and the folding of subsystem ports once held themselves in cycles: at
    10^5 equations the collector's first pass after the compile took 1.5 s, and until
    then the compile's garbage held its memory."""
    build = MODELS[name]
    mt.compile_model(build())       # a first compile imports modules (their classes
    model = build()                 # are cycles of their own), this one is measured
    while gc.collect():             # earlier tests' garbage, all of it: freeing some
        pass                        # (a figure's callbacks) leaves more for a next pass
    enabled = gc.isenabled()
    gc.disable()
    try:
        mt.compile_model(model)
        gc.set_debug(gc.DEBUG_SAVEALL)
        found = gc.collect()
        kinds = Counter(type(o).__name__ for o in gc.garbage)
    finally:
        gc.set_debug(0)
        gc.garbage.clear()
        if enabled:
            gc.enable()
    assert found == 0, f"{found} objects in cycles, e.g. {kinds.most_common(6)}"


def pair_chain(n: int = 15):
    """A chain of ``n`` reused two-stage RC subsystems (their ports folded)."""
    from mechatron.library import electrical as el
    from tests.compiler.test_hierarchy import Pair
    m = mt.System("pair_chain")
    src = m.add("src", el.DCVoltageSource(V=1.0))
    g = m.add("g", el.ElectricalReference())
    m.connect(src.n, g.port)
    node = src.p
    for k in range(n):
        pair = m.add(f"s{k}", Pair(R=1.0 + k, C=1e-3))
        m.connect(node, pair.p)
        m.connect(pair.gnd, g.port)
        node = pair.n
    return m


@pytest.mark.parametrize("build", [lambda: ladder(20), pair_chain])
def test_a_compile_reads_the_unknowns_and_residuals_off_their_columns(build, monkeypatch):
    """The residuals and the unknowns' symbols reach the structural analysis as columns
    (`ColumnRows`), and on a network without loops nothing reads enough of them one by
    one to form them all: each formed Python scalar costs about 260 bytes, a million of
    them at 10^5 components. The states' symbols and derivatives are read off their own
    columns, not from the unknowns' one by one."""
    import mechatron.compiler.flatten as fl
    import mechatron.compiler.structure as st
    handed, formed = [], []         # the lowering's own copies (`_own`), those formed
    own, form_all = st._own, fl.ColumnRows._form_all

    def own_watched(items):
        out = own(items)
        handed.append(out)
        return out

    def form_watched(self):
        if not self._formed and any(self is h for h in handed):
            formed.append(len(self._items))
        form_all(self)

    monkeypatch.setattr(st, "_own", own_watched)
    monkeypatch.setattr(fl.ColumnRows, "_form_all", form_watched)
    cm = mt.compile_model(build())
    assert len(cm.state_names) >= 20
    assert sum(isinstance(h, fl.ColumnRows) for h in handed) == 2   # residuals, unknowns
    assert formed == []


def test_variables_read_through_alias_elimination_take_their_factor_or_constant():
    """`_read_through` gives each variable ``scale * x[rep]`` where it is kept and the
    constant ``scale`` where it is not: checked against the same sums in NumPy, for
    factors 1, -1 and others, repeated representatives and constants (0 among them)."""
    import casadi as ca
    import numpy as np

    from mechatron.compiler.pipeline import _read_through

    rng = np.random.default_rng(3)
    n = 400
    x = ca.SX.sym("x", 60)
    rep = rng.integers(-1, 60, n)
    scale = rng.choice([1.0, -1.0, 2.5, 0.0, -0.75], n)
    kept = rep >= 0
    column = _read_through(x, rep, scale, kept)
    assert column.shape == (n, 1) and column.nnz() == n
    point = rng.normal(size=60)
    got = np.array(ca.Function("f", [x], [column])(point)).ravel()
    want = np.where(kept, scale * point[np.maximum(rep, 0)], scale)
    assert np.array_equal(got, want)


@pytest.mark.parametrize("build", [lambda: ladder(20), "bridge", "two_drives"])
def test_each_solved_unknown_is_noted_with_its_variable(build, monkeypatch):
    """The lowering notes which variable each explicitly solved symbol is
    (`Lowered.assigned_rows`: the one-equation blocks solved in bulk, the scalars, the
    torn loops' sequences and their tearing variables), and the logged column reads a
    solved unknown's expression from there instead of substituting it: each noted row
    names the variable of the symbol beside it (the unknowns as given, then the
    derivatives)."""
    import mechatron.compiler.pipeline as pl
    from tests.compiler.test_algebraic_loops import bridge

    lowered, unknowns = [], []

    def lower_watched(name, residuals, origins, names, *args, **kwargs):
        unknowns.append(list(names))
        lowered.append(lower(name, residuals, origins, names, *args, **kwargs))
        return lowered[-1]

    lower = pl.lower
    monkeypatch.setattr(pl, "lower", lower_watched)
    model = {"bridge": bridge, "two_drives": two_drives}.get(build, build)()
    mt.compile_model(model)
    low, names = lowered[0], unknowns[0]
    rows = low.assigned_rows
    assert len(rows) == low.assigned.numel() > 0
    assert len(set(rows.tolist())) == len(rows)        # each variable solved once
    for k, row in enumerate(rows.tolist()):
        symbol = low.assigned[k].name()
        assert symbol == (names[row] if row < len(names) else symbol)
        assert row < len(names) or symbol.startswith("der(")
