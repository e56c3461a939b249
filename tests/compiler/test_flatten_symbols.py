"""Symbols made in bulk while flattening (`compiler/flatten.py`): a column of symbols
named by instance path read from CasADi's serialized form, the variables' records made
from it, and the rows that templates read their instances' slots by. Checked against
symbols made one by one with ``casadi.SX.sym`` and against the model's own records."""

import casadi as ca
import numpy as np
import pytest

import mechatron as mt
import mechatron.compiler.flatten as fl
from mechatron.library import electrical as el

from tests.compiler.test_flatten_templates import ladder
from tests.compiler.test_folding import reading_model
from tests.compiler.test_hierarchy import Pair


NAMES = ["r1.p.v", "a.b", "x", "der_like(x)", "sub[3].v", "a" * 300, "m.r12.n.i",
         "pre(v)", "s.p.v", "s.n.i", "top"]


def test_bulk_symbols_carry_the_given_names_in_order():
    assert fl._bulk_ok(), "the serialized layout differs from this CasADi's"
    column, syms = fl._symbols(NAMES)
    assert column.shape == (len(NAMES), 1)
    assert [s.name() for s in syms] == NAMES
    assert all(s.is_symbolic() and s.is_scalar() for s in syms)
    # distinct symbols, and the column is made of exactly those
    assert len(ca.symvar(column)) == len(NAMES)
    assert all(ca.is_equal(column[k], s) for k, s in enumerate(syms))
    # the same serialized text CasADi writes for symbols made one by one
    one_by_one = ca.vertcat(*[ca.SX.sym(n) for n in NAMES])
    assert fl._serialized_column(NAMES) == one_by_one.serialize()


@pytest.mark.parametrize("per_text", [4, 11, 1000])
def test_symbols_made_in_pieces_are_one_column_in_order(monkeypatch, per_text):
    monkeypatch.setattr(fl, "_SYMBOLS_PER_TEXT", per_text)
    names = [f"{n}.{k}" for k in range(3) for n in NAMES]
    column, syms = fl._symbols(names)
    assert column.shape == (len(names), 1)
    assert [s.name() for s in syms] == names
    assert len(ca.symvar(column)) == len(names)
    assert all(ca.is_equal(column[k], s) for k, s in enumerate(syms))


def test_non_ascii_names_and_small_or_empty_columns():
    names = ["\u00e9t\u00e9.v", "\u03c9.w", "plain"] * 4
    column, syms = fl._symbols(names)
    assert [s.name() for s in syms] == names
    column, syms = fl._symbols(["one", "two"])           # made one by one
    assert [s.name() for s in syms] == ["one", "two"]
    column, syms = fl._symbols([])
    assert column.shape == (0, 1) and syms == []


def test_records_laid_out_in_bulk_match_casadi_for_any_lengths():
    # ASCII names are laid out by NumPy (`_records`), others name by name: both give
    # the text CasADi writes, for names of every length from empty to long, shuffled
    rng = np.random.default_rng(7)
    letters = np.array(list("abcxyz._0123456789"))
    names = ["x" + "".join(rng.choice(letters, size=k)) for k in rng.permutation(
        np.r_[0, 1, 2, rng.integers(3, 400, size=60)])] + [""]
    expected = ca.vertcat(*[ca.SX.sym(n) for n in names]).serialize()
    assert fl._serialized_column(names) == expected
    mixed = names[:30] + ["\u00e9" * 3] + names[30:]
    assert fl._serialized_column(mixed) == \
        ca.vertcat(*[ca.SX.sym(n) for n in mixed]).serialize()


def test_a_changed_layout_falls_back_to_one_symbol_per_call(monkeypatch):
    monkeypatch.setattr(fl, "_BULK", [False])
    column, syms = fl._symbols(NAMES)
    assert [s.name() for s in syms] == NAMES
    assert all(ca.is_equal(column[k], s) for k, s in enumerate(syms))


def nested_model():
    """Two levels of subsystems with parameters passed on as expressions, a start value,
    and a part whose parameter is an expression of its parent's."""
    class Halves(mt.Component):
        R = mt.Parameter("Ohm", default=2.0, min=0, doc="Total resistance")
        p = el.Pin(doc="Input")
        n = el.Pin(doc="Output")
        a = el.Resistor(R=R / 2)
        b = el.Resistor(R=R / 2)

        def equations(self):
            return [mt.connect(self.p, self.a.p), mt.connect(self.a.n, self.b.p),
                    mt.connect(self.b.n, self.n)]

    m = mt.System("nested")
    src = m.add("src", el.DCVoltageSource(V=2.0))
    g = m.add("g", el.ElectricalReference())
    pair = m.add("pair", Pair(R=3.0, C=1e-3))
    h = m.add("h", Halves(R=4.0))
    c = m.add("c", el.Capacitor(C=1e-3, v=mt.Start(0.5, "high")))
    m.connect(src.n, g.port, pair.gnd, c.n)
    m.connect(src.p, pair.p)
    m.connect(pair.n, h.p)
    m.connect(h.n, c.p)
    return m


@pytest.mark.parametrize("build", [nested_model, reading_model])
def test_every_symbol_is_named_by_its_path_and_stacked_in_declaration_order(build):
    flat = fl.flatten(build())
    for name, v in flat.variables.items():
        assert v.sym.name() == name
        assert flat.context.unknowns[name] is v.sym
    for name, p in flat.parameters.items():
        assert p.sym.name() == name
    column = flat.stack_variables()
    syms = [v.sym for v in flat.variables.values()]
    assert column.shape == (len(syms), 1)
    assert all(ca.is_equal(column[k], s) for k, s in enumerate(syms))
    some = list(flat.variables)[::3]
    picked = flat.stack_variables(some)
    assert all(ca.is_equal(picked[k], flat.variables[n].sym) for k, n in enumerate(some))
    # each name's row, read off the records or counted: its place in declaration order
    rows = flat.variable_rows()
    assert all(rows[n] == k and rows.get(n) == k and n in rows
               for k, n in enumerate(flat.variables))
    assert rows.get("no.such.v") is None and "no.such.v" not in rows
    by_row = flat.stack_rows([rows[n] for n in some])
    assert all(ca.is_equal(by_row[k], flat.variables[n].sym) for k, n in enumerate(some))


def test_values_starts_and_bound_parameters_are_read_as_given():
    flat = fl.flatten(nested_model())
    assert flat.variables["c.v"].start == 0.5
    assert flat.variables["c.v"].priority == "high"
    assert flat.parameters["pair.R"].value == 3.0
    # parts bound to their parent's parameters are not slots of their own
    assert "h.a.R" in flat.bound_parameters and "h.a.R" not in flat.parameters
    assert flat.bound_parameters["h.a.R"].value == 2.0
    # the resistor's law v == R*i over the bound expression R/2 of h.R
    syms = [flat.variables["h.a.v"].sym, flat.variables["h.a.i"].sym,
            flat.parameters["h.R"].sym]
    law = [eq.residual for eq in flat.equations if eq.owner == "h.a" and
           {s.name() for s in ca.symvar(eq.residual)} == {"h.a.v", "h.a.i", "h.R"}]
    assert len(law) == 1
    f = ca.Function("f", syms, law)
    assert float(f(3.0, 1.5, 4.0)) == 0.0          # 3 V = (4/2 Ohm)(1.5 A)
    assert float(f(3.0, 1.0, 4.0)) == pytest.approx(1.0)    # 3 V - 2 V


def test_the_compiled_nested_model_follows_its_circuit():
    """Source 2 V, four resistors in series (1.5 + 1.5 + 2 + 2 Ohm via the pair's two
    stages and the halves), the pair's capacitors and the last capacitor: at steady
    state no current flows, so every capacitor sits at the source voltage."""
    res = mt.simulate(nested_model(), 5.0)
    assert res.final("c.v") == pytest.approx(2.0, abs=1e-6)
    assert res.final("pair.first.c.v") == pytest.approx(2.0, abs=1e-6)
    assert res.final("pair.second.c.v") == pytest.approx(2.0, abs=1e-6)


def test_template_instances_take_their_variables_by_row():
    """A class template's instance holds each variable slot as the variable's row in
    the column of all variables: the symbols it stands for are the instance's own, by
    path, and no symbol of those variables is formed one by one while flattening."""
    flat = fl.flatten(ladder(4))
    templates = {eq.template for eq in flat.equations if isinstance(eq, fl._TemplateEquation)}
    assert {type(t) for t in templates} == {fl._Template} and len(templates) >= 2
    held = 0
    for tpl in templates:
        for path, args in zip(tpl.paths, tpl.instances):
            held += sum(isinstance(a, int) for a in args)
            names = [s.name() for s in tpl.symbols(args)[:len(tpl.relative)]]
            assert names == [path + rel for rel in tpl.relative]
    assert held
    # the variables of the template instances were taken by row, never formed alone
    formed = [n for n, v in flat.variables.items()
              if isinstance(v, fl._ColumnVariable) and v._sym is not None]
    assert not [n for n in formed if n.startswith(("r", "c", "l"))]


@pytest.mark.parametrize("build", [lambda: ladder(30), nested_model, reading_model])
def test_rows_and_numbers_kept_by_flattening_are_shared_integers(build):
    """The rows and variable numbers that flattening keeps per instance and per equation
    (a template instance's variable slots, its equations' rows) are shared integer
    objects (those `_bind_symbols` made once), not one object of their own each; a
    template's equations are held as those numbers, no object formed for them, and
    their alias hints, formed when read, name the variables each equation relates."""
    flat = fl.flatten(build())
    number = flat.variable_rows()
    named_by = {number[n]: n for n in flat.variables}    # a hint's number -> the name
    row_object: dict[int, int] = {}     # each number -> the first object met for it

    def shared(x) -> bool:
        return row_object.setdefault(x, x) is x or -5 <= x <= 256   # small ints: cached

    eqs = flat.equations
    assert type(eqs) is fl.FlatEquations
    held_rows = [r for t, r in zip(eqs.which, eqs.rows) if t >= 0]
    assert all(map(shared, held_rows))
    # formed only where variables were moved back to their place of declaration
    # (`_declaration_order`, which moves the hints by number with them): those kept
    formed = [eq for eq in eqs.given if isinstance(eq, fl._TemplateEquation)]
    assert bool(held_rows) != bool(formed)
    for eq in formed:
        hint = eq.alias
        if hint[0] in ("pair", "const") and type(hint[1]) is int:
            assert all(map(shared, hint[1:3] if hint[0] == "pair" else hint[1:2]))
    numbers = 0
    for eq in flat.equations:
        if not isinstance(eq, fl._TemplateEquation):
            continue
        assert shared(eq.row)
        hint = eq.alias
        if hint[0] in ("pair", "const") and type(hint[1]) is int:
            numbers += 1
            held = hint[1:3] if hint[0] == "pair" else hint[1:2]
            named = {named_by[x] for x in held}
            assert named <= {s.name() for s in ca.symvar(eq.residual)}
        tpl = eq.template
        for args in tpl.instances:
            assert all(shared(a) for a in args if type(a) is int)
    assert numbers
    # and the rows of the records, formed now, and the places of the names
    variables = flat.variables
    assert all(shared(variables.at(k).row) for k in range(len(variables))
               if isinstance(variables.at(k), fl._ColumnVariable))
    assert all(shared(k) for k in variables._by_name().values())


@pytest.mark.parametrize("build", [lambda: ladder(4), nested_model, reading_model])
def test_flattening_lets_go_of_what_only_binding_reads(build):
    """The list of each element's parameter rows and the shared integers' list serve
    binding and the class templates' instances alone: the flat model keeps neither (at
    10^5 sections the parameter rows held 12-25 MB of the compile's peak)."""
    flat = fl.flatten(build())
    assert flat.parameters
    assert not {"_ints", "_parameter_rows"} & set(flat.__dict__)


@pytest.mark.parametrize("build", [lambda: ladder(4), nested_model, reading_model])
def test_parameters_are_read_from_their_column(build):
    """A parameter bound in bulk holds its row in the column of all parameters: its
    symbol, read alone, is that row, named by its path; the stacked parameters are that
    column gathered in order; and the equations of class templates took their parameters
    by row, forming none alone."""
    flat = fl.flatten(build())
    params = list(flat.parameters.values())
    assert params and all(isinstance(q, fl._ColumnParameter) for q in params)
    unformed = [q for q in params if fl._PAR_SYM_SLOT.__get__(q) is None]
    stacked = flat.parameter_column()
    assert stacked.shape == (len(params), 1)
    assert [s.name() for s in ca.vertsplit(stacked)] == [q.name for q in params]
    assert all(ca.is_equal(stacked[k], q.sym) for k, q in enumerate(params))
    assert all(ca.is_equal(q.sym, q.store.column[q.row]) for q in unformed)
    if build is not nested_model and build is not reading_model:   # all from templates
        assert len(unformed) == len(params)
        # each instance holds its parameters' rows, not symbols formed alone
        templates = {eq.template for eq in flat.equations
                     if isinstance(eq, fl._TemplateEquation)}
        held = [args[:len(tpl.par_slots)] for tpl in templates for args in tpl.instances]
        assert any(held) and all(type(a) is int for slots in held for a in slots)


def _same(a, b) -> bool:
    return ca.is_equal(ca.SX(a), ca.SX(b), 0)


@pytest.mark.parametrize("reads", [0, 1, 3, 40])
def test_column_rows_read_as_the_list_of_the_column_scalars(reads):
    """`ColumnRows` forms a row when read, all rows at once after many single reads, and
    otherwise behaves as the list ``vertsplit`` would give: indices from either end,
    slices, replaced and appended items, copies that do not share their changes."""
    x = ca.SX.sym("x", 50)
    column = ca.sin(x) * 2 + x[::-1]
    want = ca.vertsplit(column)
    rows = fl.ColumnRows(column)
    for k in range(reads):
        assert _same(rows[(7 * k) % 50], want[(7 * k) % 50])
    assert _same(rows[-1], want[-1]) and _same(rows[-50], want[0])
    assert all(_same(a, b) for a, b in zip(rows[10:20:3], want[10:20:3]))
    copy = rows.copy()
    rows[5] = ca.SX(3.0)
    rows.append(ca.SX(4.0))
    want_after = want[:5] + [ca.SX(3.0)] + want[6:] + [ca.SX(4.0)]
    assert len(rows) == 51 and len(copy) == 50
    assert all(_same(a, b) for a, b in zip(rows, want_after))
    assert all(_same(a, b) for a, b in zip(copy, want))
    for change in ("del", "insert"):    # the rows after it move against the column
        rows = fl.ColumnRows(column)
        assert _same(rows[1], want[1])
        if change == "del":
            del rows[0]
            assert _same(rows[0], want[1]) and _same(rows[5], want[6])
        else:
            rows.insert(2, ca.SX(9.0))
            assert _same(rows[2], 9.0) and _same(rows[3], want[2])
        assert len(rows) == 49 + 2 * (change == "insert")


def test_the_variables_read_as_a_dictionary_in_declaration_order():
    """`FlatModel.variables` holds names and records in two lists and builds its
    dictionary by name on the first read by name: it must read, change and compare as
    the dictionary it stands for, in either state."""
    items = [(f"c{k}.v", object()) for k in range(6)]
    for warm in (False, True):
        got, want = fl._Variables(), {}
        got.extend([n for n, _ in items], [r for _, r in items])
        want.update(items)
        if warm:
            assert got["c0.v"] is want["c0.v"]         # the dictionary built now
        assert list(got) == list(want) and len(got) == len(want)
        assert list(got.values()) == list(want.values())
        assert list(got.items()) == list(want.items())
        assert got == want and dict(got) == want
        new, again = object(), object()
        got["c2.v"] = want["c2.v"] = new                # replaced in place
        got["x.v"] = want["x.v"] = again                # appended
        del got["c0.v"], want["c0.v"]
        assert list(got.items()) == list(want.items())
        assert got.get("c0.v") is None and "c0.v" not in got and "c3.v" in got
        with pytest.raises(KeyError):
            got["c0.v"]
        more = fl._Variables(got.items())
        more.extend(["y.v"], [new])                     # not empty: one by one
        assert list(more) == list(want) + ["y.v"] and more["y.v"] is new


def _bulk_variables(n: int = 6):
    """`_Variables` bound in bulk as `_bind_symbols` binds them: a column of symbols,
    each variable's plan entry (shared by the instances of a class) and owner."""
    names = [f"c{k // 2}.{'v' if k % 2 == 0 else 'i'}" for k in range(n)]
    column = ca.SX.sym("x", n)
    plans = [("v", "across", "V", "voltage", 0.0, "low", "try v", "prefer"),
             ("i", "through", "A", "current", None, "low", "try i", "default")]
    got = fl._Variables()
    got.extend_bulk(names, column, [plans[k % 2] for k in range(n)],
                    [f"c{k // 2}" for k in range(n)])
    return got, names, column


ATTRIBUTES = ("name", "owner", "kind", "unit", "doc", "start", "priority", "hint",
              "state_select")


def test_variables_bound_in_bulk_form_a_record_only_when_one_is_read():
    """A variable bound in bulk has no record until it is read; read by place or by
    name it is formed once (the same object after), reads as the class plan says, and
    `column_of` gives what the records would give, before any is formed, with some
    changed, and with all formed."""
    got, names, column = _bulk_variables()
    columns = {a: fl.column_of(got, a) for a in ATTRIBUTES}
    assert got._records == [None] * 6                  # nothing formed by reading those
    first = got.at(2)
    assert got.at(2) is first and got["c1.v"] is first and got.get("c1.v") is first
    assert (first.name, first.row, first.owner, first.kind, first.unit) == \
        ("c1.v", 2, "c1", "across", "V")
    assert ca.is_equal(first.sym, column[2])
    first.start, first.priority = 1.5, "high"          # a start given to the instance
    columns["start"][2], columns["priority"][2] = 1.5, "high"
    assert {a: fl.column_of(got, a) for a in ATTRIBUTES} == columns
    assert sum(r is not None for r in got._records) == 1
    # stacked from the column without forming the rest
    gathered = fl._gathered(got)
    assert all(ca.is_equal(gathered[k], column[k]) for k in range(6))
    assert sum(r is not None for r in got._records) == 1
    records = list(got.values())                        # all formed, in order
    assert [r.name for r in records] == names and records[2] is first
    assert {a: [getattr(r, a) for r in records] for a in ATTRIBUTES} == columns
    assert {a: fl.column_of(got, a) for a in ATTRIBUTES} == columns


def test_variables_put_back_in_declaration_order_stay_unformed_and_read_the_same():
    """The variables of ports bound on first read go back to where they are declared
    (`_declaration_order`): the others stay unformed, each reading its class plan and
    its row in the column, and they read as the records formed from them."""
    flat = fl.flatten(reading_model())
    variables = flat.variables
    given = [n for n, r in zip(variables, variables._records) if r is not None]
    assert given and len(given) < len(variables) // 4      # the late ports' alone
    columns = {a: fl.column_of(variables, a) for a in ATTRIBUTES}
    stacked = flat.stack_variables()
    assert [r is not None for r in variables._records].count(True) == len(given)
    records = list(variables.values())
    assert {a: [getattr(r, a) for r in records] for a in ATTRIBUTES} == columns
    assert [stacked[k].name() for k in range(stacked.numel())] == list(variables)
    assert all(ca.is_equal(stacked[k], r.sym) for k, r in enumerate(records))


def test_variables_bound_in_bulk_read_and_change_as_the_dictionary_of_their_records():
    """Replaced, appended, deleted, and bound in bulk after others: the same as the
    dictionary of the records formed one by one."""
    got, names, column = _bulk_variables()
    want = dict(zip(names, [got.at(k) for k in range(6)]))
    got, _, _ = _bulk_variables()
    other = fl._Variables()
    other.update(want)
    got["c1.i"] = want["c1.i"] = other["c1.i"] = object()     # replaced in place
    assert fl.column_of(got, "name") == names
    got["x.v"] = want["x.v"] = want["c0.v"]                    # appended
    assert [type(r).__name__ for r in got.values()][:3] == ["_ColumnVariable"] * 3
    assert [r.name if hasattr(r, "name") else r for r in got.values()] == \
        [r.name if hasattr(r, "name") else r for r in want.values()]
    del got["c0.i"], want["c0.i"]
    assert list(got) == list(want) and [got[n].row if hasattr(got[n], "row") else None
                                        for n in got] == \
        [want[n].row if hasattr(want[n], "row") else None for n in want]
    assert "c0.i" not in got and got.get("c0.i") is None
    # bound in bulk after others: formed at once, each reading its own column's row
    later = fl._Variables([("a.v", want["c0.v"])])
    later.extend_bulk(["b.v", "b.i"], column[:2], [("v",) * 8, ("i",) * 8], ["b", "b"])
    assert later._records[1].row == 0 and later._records[2].row == 1
    assert list(later) == ["a.v", "b.v", "b.i"] and later["b.i"].owner == "b"


def spring_chain(n: int = 8):
    """Masses on springs and dampers in parallel from a fixed reference, the last
    spring stretched at the start (a start value with priority)."""
    from mechatron.library import translational as tr
    m = mt.System("spring_chain")
    prev = m.add("ref", tr.TranslationalReference()).port
    for k in range(n):
        mass = m.add(f"m{k}", tr.Mass(m=1.0 + k))
        start = {"x": mt.Start(0.01, "high")} if k == n - 1 else {}
        spring = m.add(f"k{k}", tr.TranslationalSpring(k=1e4, **start))
        damper = m.add(f"b{k}", tr.TranslationalDamper(b=50.0))
        m.connect(mass.port, spring.A, damper.A)
        m.connect(spring.B, damper.B, prev)
        prev = mass.port
    return m


@pytest.mark.parametrize("build", [lambda: ladder(12), spring_chain])
def test_a_compile_of_instances_bound_in_bulk_reads_no_variable_by_name(build, monkeypatch):
    """Every pass reads the variables of a model bound in bulk by row (alias
    elimination and the dimension check take a differentiated variable's row from its
    class template), so a compile never builds the dictionary of all their names: a
    million names entered cost 0.6 us each. The compiled model is the same."""
    built = []
    by_name = fl._Variables._by_name

    def watched(self):
        if self._index is None:
            built.append(len(self))
        return by_name(self)

    want = mt.compile_model(build())
    monkeypatch.setattr(fl._Variables, "_by_name", watched)
    got = mt.compile_model(build())
    assert built == []
    assert got.state_names == want.state_names and got.alg_names == want.alg_names
    assert got.names == want.names and got.units == want.units


@pytest.mark.parametrize("build", [lambda: ladder(12), spring_chain])
def test_a_compile_of_instances_bound_in_bulk_forms_no_record_it_does_not_need(
        build, monkeypatch):
    """Every pass reads what the variables' classes declare off the class plans
    (`column_of`): a compile forms the records of the variables with a start value
    alone (alias elimination merges them: the springs' elongations; none in the
    ladder), and the model is the one compiled from records formed beforehand."""
    import mechatron.compiler.pipeline as pipeline

    flats = []
    flatten = pipeline.flatten

    def kept(*args, **kwargs):
        flats.append(flatten(*args, **kwargs))
        return flats[-1]

    def formed_first(*args, **kwargs):
        flat = flatten(*args, **kwargs)
        flat.variables.records()
        return flat

    monkeypatch.setattr(pipeline, "flatten", formed_first)
    want = mt.compile_model(build())
    monkeypatch.setattr(pipeline, "flatten", kept)
    got = mt.compile_model(build())
    variables = flats[0].variables
    formed = [n for n, r in zip(variables, variables._records) if r is not None]
    starts = fl.column_of(variables, "start")
    assert formed == [n for n, start in zip(variables, starts) if start is not None]
    assert got.state_names == want.state_names and got.alg_names == want.alg_names
    assert got.names == want.names and got.units == want.units
    a, b = mt.simulate(want, 0.01, log="all"), mt.simulate(got, 0.01, log="all")
    assert all(np.array_equal(a[n], b[n]) for n in want.names)


def _parts(kind):
    a, b = ca.SX.sym("a", 5), ca.SX.sym("b", 3)
    return {"symbols": [a, b],
            "expressions and a scalar": [2 * a + 1, ca.SX.sym("s"), ca.sin(b)],
            "an empty part": [a, ca.SX(0, 1), b],
            "one part": [a * 3],
            "a structural zero": [a, ca.SX(ca.Sparsity.triplet(4, 1, [0, 2], [0, 0]),
                                            ca.vertcat(b[0], b[1]))],
            "a matrix": [ca.SX.sym("m", 2, 2), ca.SX.sym("n", 1, 2)]}[kind]


@pytest.mark.parametrize("kind", ["symbols", "expressions and a scalar", "an empty part",
                                  "one part", "a structural zero", "a matrix"])
def test_columns_stacked_by_slices_are_casadis_vertcat(kind):
    """`stack_columns` is `casadi.vertcat`: the same shape, sparsity and expressions,
    whether it copies dense columns by slices or hands other parts to `vertcat`."""
    parts = _parts(kind)
    got, want = fl.stack_columns(*parts), ca.vertcat(*parts)
    assert got.shape == want.shape and got.sparsity() == want.sparsity()
    assert ca.is_equal(got, want, 2)
    free = ca.symvar(want)
    f = ca.Function("f", free, [got - want])
    point = np.random.default_rng(1).normal(size=len(free))
    assert np.all(np.array(f(*point)) == 0.0)


@pytest.mark.parametrize("build", [lambda: ladder(6), spring_chain, reading_model])
def test_the_derivatives_read_by_row_are_the_ones_named(build):
    """The derivative of each variable read by its row (class templates note the rows of
    the derivatives they make) is the symbol the build context holds under its name,
    None where it has none; the column holds those symbols in order. Once a derivative
    is made by name alone, rows no longer cover them all, and none is read by row. The
    rows follow the variables when the folding of subsystem ports reorders them."""
    flat = fl.flatten(build())
    names = list(flat.variables)
    rows = list(range(len(names)))[::-1]                 # any order of rows
    got = flat.derivatives_by_row(rows)
    assert got is not None
    ders, column = got
    want = [flat.context.derivative.get(names[k]) for k in rows]
    assert [d is None for d in ders] == [w is None for w in want]
    assert any(d is not None for d in ders)
    assert all(d is w for d, w in zip(ders, want) if w is not None)
    assert ca.is_equal(column, ca.vertcat(*[w for w in want if w is not None]), 1)
    flat.context.der_symbol(names[0] + "_by_name")
    assert flat.derivatives_by_row(rows) is None


@pytest.mark.parametrize("build", [lambda: ladder(6), spring_chain])
def test_a_compile_reading_derivatives_by_name_gives_the_same_model(build, monkeypatch):
    """The derivatives read by row or by name compile to the same model."""
    want = mt.compile_model(build())
    monkeypatch.setattr(fl.FlatModel, "derivatives_by_row", lambda self, rows: None)
    got = mt.compile_model(build())
    assert got.state_names == want.state_names and got.alg_names == want.alg_names
    assert got.names == want.names
    for f in ("f_ode", "f_out"):
        a, b = getattr(want, f), getattr(got, f)
        args = [np.full(a.size_in(i), 0.3 + 0.1 * i) for i in range(a.n_in())]
        assert np.array_equal(np.array(a(*args)), np.array(b(*args)))


@pytest.mark.parametrize("build", [lambda: ladder(5), spring_chain, nested_model])
def test_flow_sums_are_rows_of_one_column_and_say_what_alias_elimination_would_read(build):
    """The flow sums of connection sets are the rows of one column, formed as scalars
    only when read, and gathered from it (`stack_residuals`). A sum of three terms or
    more says it is no alias: exactly what alias elimination reads off its residual."""
    from mechatron.compiler.alias import _read_alias

    flat = fl.flatten(build())
    sums = [eq for eq in flat.equations if isinstance(eq, fl._SumEquation)]
    assert sums and len({id(eq.column) for eq in sums}) == 1
    column = sums[0].column
    assert ca.is_equal(fl.stack_residuals(sums), column[[eq.row for eq in sums]], 1)
    said = 0
    for eq in sums:
        read = _read_alias(eq.residual, flat.variable_rows())
        if eq.alias is not None:
            said += 1
            assert eq.alias == ("none",) and read is None
            assert len(ca.symvar(eq.residual)) >= 3
    assert said


def passed_on_model():
    """Parameters passed on unchanged through two levels (``R=R``: `Pair` to its stages to
    their parts), and a component with parameters and ports but no variables of its own
    whose equations read them."""

    class Leak(mt.Component):
        G = mt.Parameter("S", default=0.5)
        p = el.Pin()
        n = el.Pin()

        def equations(self):
            return [self.p.i == self.G * (self.p.v - self.n.v), self.p.i + self.n.i == 0]

    m = mt.System("passed_on")
    src = m.add("src", el.DCVoltageSource(V=2.0))
    gnd = m.add("gnd", el.ElectricalReference())
    pair = m.add("pair", Pair(R=4.0, C=1e-3))
    leak = m.add("leak", Leak())
    m.connect(src.n, gnd.port)
    m.connect(src.p, pair.p)
    m.connect(pair.gnd, gnd.port)
    m.connect(pair.n, leak.p)
    m.connect(leak.n, gnd.port)
    return m


def test_parameters_passed_on_unchanged_are_their_parents_symbols():
    flat = fl.flatten(passed_on_model())
    for key, unit, value, part in (("R", "Ohm", 4.0, "r"), ("C", "F", 1e-3, "c")):
        sym = flat.parameters[f"pair.{key}"].sym
        for stage in ("pair.first", "pair.second"):
            for path in (f"{stage}.{key}", f"{stage}.{part}.{key}"):
                bound = flat.bound_parameters[path]
                assert bound.value == value and bound.unit == unit
                assert bound.expr is sym        # the top symbol itself, formed once
    assert flat.bound_parameters["pair.first.r.R"].binding == "R of 'pair.first'"
    # the resistor's law reads the top parameter; the leak's law its own G
    for owner, name in (("pair.first.r", "pair.R"), ("pair.second.c", "pair.C"),
                        ("leak", "leak.G")):
        used = {s.name() for eq in flat.equations if eq.owner == owner
                for s in ca.symvar(eq.residual)}
        assert name in used


def test_a_value_passed_on_is_checked_against_each_parts_bounds_and_recorded():
    """A value passed on unchanged (``R=R``) down two levels meets the bounds of every
    part that takes it, each named where it is; the records of the bindings, formed when
    read, hold each part's value, unit and binding, in the order they were bound."""
    m = mt.System("negative")
    src = m.add("src", el.DCVoltageSource(V=1.0))
    gnd = m.add("gnd", el.ElectricalReference())
    pair = m.add("pair", Pair(R=-5.0, C=1e-3))
    m.connect(src.n, gnd.port)
    m.connect(src.p, pair.p)
    m.connect(pair.gnd, gnd.port)
    with pytest.raises(mt.errors.ParameterError) as info:
        mt.compile_model(m)
    lines = [line.strip() for line in str(info.value).splitlines()[1:]]
    assert lines == [f"{who}: R must be >= 0, got -5." for who in (
        "Pair 'pair'", "Stage 'pair.first'", "Resistor 'pair.first.r'",
        "Stage 'pair.second'", "Resistor 'pair.second.r'")]

    flat = fl.flatten(passed_on_model())
    bound = flat.bound_parameters
    assert list(bound) == [f"pair.{stage}{part}.{key}" for stage in ("first", "second")
                           for key, part in (("R", ""), ("C", ""), ("R", ".r"),
                                             ("C", ".c"))]
    assert flat.bound_parameters is bound       # formed once
    first = bound["pair.first.R"]
    assert (first.value, first.unit, first.owner, first.binding) == (
        4.0, "Ohm", "pair.first", "R of 'pair'")


def test_the_passed_on_model_follows_its_circuit():
    """Steady state: no current through the capacitors, so 2 V drives the series
    resistors (4 + 4 Ohm) and the leak (2 Ohm): 0.2 A, and the leak sees 0.4 V."""
    res = mt.simulate(passed_on_model(), 0.5)
    assert res.final("leak.p.i") == pytest.approx(0.2, rel=1e-6)
    assert res.final("pair.second.c.v") == pytest.approx(0.4, rel=1e-6)
    assert res.final("pair.first.r.i") == pytest.approx(0.2, rel=1e-6)


def test_the_components_are_held_as_lists_until_read_by_path(monkeypatch):
    """`FlatModel.components` (path -> class name) is made a dictionary only when read:
    a compile does not read it; read, it names every component of the tree."""
    import mechatron.compiler.pipeline as pipeline
    model = ladder(30)
    want = {el.path: type(el).__name__ for el in fl._walk(model)
            if isinstance(el, mt.Component)}
    flat = fl.flatten(ladder(30))
    comps = flat.components
    assert comps._dict is None and len(comps) == len(want) and comps
    kept = {}
    monkeypatch.setattr(pipeline, "flatten",
                        lambda *a, **k: kept.setdefault("flat", fl.flatten(*a, **k)))
    mt.compile_model(ladder(30))
    assert kept["flat"].components._dict is None
    assert comps["r3"] == want["r3"] and dict(comps) == want
    comps["extra"] = "Thing"
    comps.add("more", "Other")
    assert len(comps) == len(want) + 2 and comps["more"] == "Other"
