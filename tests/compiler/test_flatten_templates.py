"""One expression graph per component class (`compiler/flatten.py`): the equations of
every instance built from a class's template equal those built instance by instance,
alias elimination reads the same aliases off them, and messages still name each
instance."""

import casadi as ca
import numpy as np
import pytest

import mechatron as mt
import mechatron.compiler.flatten as fl
from mechatron.compiler.alias import eliminate_aliases
from mechatron.errors import UnitError
from mechatron.library import electrical as el
from mechatron.library import rotational as rot


def ladder(n):
    m = mt.System("ladder")
    src = m.add("src", el.DCVoltageSource(V=1.0))
    g = m.add("g", el.ElectricalReference())
    m.connect(src.n, g.port)
    node = src.p
    for k in range(n):
        r = m.add(f"r{k}", el.Resistor(R=1.0 + k))
        c = m.add(f"c{k}", el.Capacitor(C=1e-3 * (k + 1)))
        ind = m.add(f"l{k}", el.Inductor(L=1e-3))
        m.connect(node, r.p)
        m.connect(r.n, ind.p)
        m.connect(ind.n, c.p)
        m.connect(c.n, g.port)
        node = c.p
    return m


def drive():
    m = mt.System("drive")
    ref = m.add("ref", rot.RotationalReference())
    src = m.add("src", rot.ConstantTorque(T=1.0))
    m.connect(ref.port, src.B)
    prev = src.A
    for k in range(3):
        j = m.add(f"j{k}", rot.Inertia(J=0.1 * (k + 1)))
        s = m.add(f"s{k}", rot.RotationalSpring(k=10.0))
        d = m.add(f"d{k}", rot.RotationalDamper(D=0.5))
        m.connect(prev, j.port, s.A, d.A)
        m.connect(s.B, d.B, ref.port)
        prev = j.port
    return m


def flat_both(build, monkeypatch):
    with_templates = fl.flatten(build())
    monkeypatch.setattr(fl, "_template", lambda flat, el, templates: None)
    without = fl.flatten(build())
    monkeypatch.undo()
    return with_templates, without


@pytest.mark.parametrize("build", [lambda: ladder(4), drive])
def test_template_equations_equal_the_instance_by_instance_ones(build, monkeypatch):
    a, b = flat_both(build, monkeypatch)
    assert [str(e.origin) for e in a.equations] == [str(e.origin) for e in b.equations]
    assert any(hasattr(e.origin, "template") for e in a.equations)
    # same residuals: evaluated at one random point of every symbol, by name
    rng = np.random.default_rng(1)

    def values(flat):
        syms = [v.sym for v in flat.variables.values()] + \
            [p.sym for p in flat.parameters.values()] + \
            list(flat.context.derivative.values()) + [flat.context.time]
        names = [s.name() for s in syms]
        return syms, names

    sa, na = values(a)
    sb, nb = values(b)
    assert sorted(na) == sorted(nb)
    point = {n: rng.normal() for n in na}
    fa = ca.Function("a", [ca.vertcat(*sa)], [ca.vertcat(*[e.residual for e in a.equations])])
    fb = ca.Function("b", [ca.vertcat(*sb)], [ca.vertcat(*[e.residual for e in b.equations])])
    ra = np.array(fa([point[n] for n in na])).ravel()
    rb = np.array(fb([point[n] for n in nb])).ravel()
    np.testing.assert_allclose(ra, rb, rtol=1e-14, atol=1e-14)
    # alias elimination reads the same aliases off the templates as off the residuals
    xa, xb = eliminate_aliases(a), eliminate_aliases(b)
    assert xa.eliminated == xb.eliminated and xa.unknowns == xb.unknowns


def test_a_class_with_instance_attributes_is_flattened_instance_by_instance():
    class Scaled(el.OnePort):
        """``v = gain * R * i`` with a Python option set per instance."""

        R = mt.Parameter("Ohm", default=1.0, doc="Resistance")

        def __init__(self, gain=1.0, **kw):
            super().__init__(**kw)
            self.gain = gain

        def equations(self):
            return [self.v == self.gain * self.R * self.i]

    m = mt.System("scaled")
    src = m.add("src", el.DCCurrentSource(I=1.0))
    a = m.add("a", Scaled(gain=2.0))
    b = m.add("b", Scaled(gain=3.0))
    g = m.add("g", el.ElectricalReference())
    m.connect(g.port, src.p)
    m.connect(src.n, a.p)
    m.connect(a.n, b.p)
    m.connect(b.n, g.port)
    res = mt.simulate(m, 0.1, t_out=[0.0, 0.1])
    assert res.final("a.v") == pytest.approx(2.0) and res.final("b.v") == pytest.approx(3.0)


def test_a_dimension_error_in_a_class_used_twice_names_an_instance():
    class WrongInductor(el.OnePort):
        """``v = L i`` (the der() is missing on purpose)."""

        L = mt.Parameter("H", default=1.0, doc="Inductance")

        def equations(self):
            return [self.v == self.L * self.i]

    m = mt.System("twice")
    v = m.add("v", el.DCVoltageSource(V=1.0))
    a = m.add("a", WrongInductor())
    b = m.add("b", WrongInductor())
    g = m.add("g", el.ElectricalReference())
    m.connect(v.p, a.p)
    m.connect(a.n, b.p)
    m.connect(b.n, v.n, g.port)
    with pytest.raises(UnitError, match=r"WrongInductor 'a': v == \(L\*i\): the left side "
                                        r"is V .*Is a der\(\) missing\?"):
        mt.compile_model(m)


class Branch(mt.Component):
    """A resistor passed its parent's parameter unchanged, from p to n."""

    R = mt.Parameter("Ohm", default=1.0, doc="Resistance")
    p = el.Pin(doc="Top")
    n = el.Pin(doc="Bottom")
    a = el.Resistor(R=R)

    def equations(self):
        return [mt.connect(self.p, self.a.p), mt.connect(self.a.n, self.n)]


def test_parameters_passed_on_unchanged_reach_each_instance(monkeypatch):
    """Parts whose parameter is their parent's (``R=R``) are instantiated from the
    template with the parent's symbol (its row in the parameter column): each branch
    carries V/R, also after a parameter change at run time, and the residuals are those
    of flattening without templates."""
    def build():
        m = mt.System("branches")
        src = m.add("src", el.DCVoltageSource(V=6.0))
        g = m.add("g", el.ElectricalReference())
        m.connect(src.n, g.port)
        for k, r in enumerate((1.0, 2.0, 3.0)):
            s = m.add(f"s{k}", Branch(R=r))
            m.connect(src.p, s.p)
            m.connect(s.n, g.port)
        return m
    flat = fl.flatten(build())
    template = next(e.origin.template for e in flat.equations
                    if e.owner == "s0.a" and hasattr(e.origin, "template"))
    # every instance's resistance is a row of the parameter column: its branch's
    column = flat.__dict__["_parameter_column"]
    assert [[column[r].name() for r in b] for b in template.par_bases] == \
        [["s0.R"], ["s1.R"], ["s2.R"]]
    res = mt.simulate(build(), 0.01, params={"s1.R": 4.0})
    for k, r in enumerate((1.0, 4.0, 3.0)):
        np.testing.assert_allclose(res[f"s{k}.a.i"], 6.0 / r, rtol=1e-12)
    with_templates, without = flat_both(build, monkeypatch)
    assert [str(e.residual) for e in with_templates.equations] == \
        [str(e.residual) for e in without.equations]


def _hints_by_path(flat):
    """Each template equation's alias hint, its variables named by path: a numbered
    hint through the model's variables, and the class's own hint with the instance's
    path (what `_Template.add` gives when the numbers are not known)."""
    names = list(flat.variables)
    out = []
    for eq in flat.equations:
        origin = eq.origin
        if not isinstance(origin, fl._TemplateOrigin) or eq.alias[0] == "none":
            continue
        hint = eq.alias
        assert isinstance(hint[1], int)                    # bound in bulk: numbers
        given = (hint[0], names[hint[1]], names[hint[2]], hint[3]) \
            if hint[0] == "pair" else (hint[0], names[hint[1]], hint[2])
        own = origin.template.hints[origin.k]
        prefix = eq.owner + "." if eq.owner else ""
        expected = (own[0], prefix + own[1][1:], prefix + own[2][1:], own[3]) \
            if own[0] == "pair" else (own[0], prefix + own[1][1:], own[2])
        out.append((given, expected))
    return out


def test_numbered_alias_hints_name_the_variables_of_the_class_hint():
    """Also in a model whose variables are moved after binding (a subsystem's pin read
    by an equation goes back to its place of declaration)."""
    from tests.compiler.test_folding import deep_ladder, reading_model
    for build in (lambda: ladder(3), drive, deep_ladder, reading_model):
        pairs = _hints_by_path(fl.flatten(build()))
        assert pairs
        for given, expected in pairs:
            assert given == expected


def test_numbered_connection_aliases_name_members_of_their_set():
    """A connection's alias by number names, through the model's variables, the same
    variable of two members of its set; also after variables were moved back to their
    place of declaration (a pin read by an equation) and with folded ports (by path)."""
    from tests.compiler.test_folding import deep_ladder, reading_model
    for build in (lambda: ladder(3), drive, deep_ladder, reading_model):
        flat = fl.flatten(build())
        names = list(flat.variables)
        numbered = 0
        for a, b, _, origin in flat.aliases:
            if not origin.startswith("connect("):
                continue                       # a signal connection: by path
            members = origin[len("connect("):-1].split(", ")
            pa, pb = (names[x] if isinstance(x, int) else x for x in (a, b))
            numbered += isinstance(a, int)
            assert pa.rsplit(".", 1)[1] == pb.rsplit(".", 1)[1], (pa, pb)
            assert pa.rsplit(".", 1)[0] in members and pb.rsplit(".", 1)[0] in members
        assert numbered


def test_template_residuals_are_gathered_from_their_class_column():
    """`stack_residuals` gathers the rows of template equations from their classes'
    columns without forming each residual, and takes a residual set since as it is."""
    flat = fl.flatten(drive())
    eqs = flat.equations
    lazy = [eq for eq in eqs if isinstance(eq, fl._TemplateEquation)]
    assert lazy and all(fl._RESIDUAL_SLOT.__get__(eq) is None for eq in lazy)
    mixed = list(reversed(eqs))                   # any order, both kinds
    replaced = lazy[1]
    mixed_column = fl.stack_residuals(mixed)
    replaced.residual = 7.0 * replaced.residual   # as pre's replacement does
    after = fl.stack_residuals(mixed)
    one_by_one = ca.vertcat(*[eq.residual for eq in mixed])
    x = ca.symvar(ca.vertcat(one_by_one, mixed_column))
    values = np.random.default_rng(6).uniform(0.5, 2.0, len(x))
    f = ca.Function("f", x, [mixed_column, after, one_by_one])
    before_v, after_v, want = (np.asarray(v).ravel() for v in f(*values))
    np.testing.assert_array_equal(after_v, want)
    row = next(i for i, eq in enumerate(mixed) if eq is replaced)
    np.testing.assert_allclose(want[row], 7.0 * before_v[row], rtol=1e-15)
    keep = np.arange(len(mixed)) != row
    np.testing.assert_array_equal(before_v[keep], want[keep])


def stop_and_springs():
    """A mass against stops (its impact reads ``pre(v)``) on a chain of springs, dampers
    and masses: classes used twice, built from templates beside equations that `pre`'s
    replacement rewrites."""
    from mechatron.library import translational as tr
    m = mt.System("stop_and_springs")
    g = m.add("g", tr.TranslationalReference())
    body = m.add("body", tr.MassWithStopAndFriction(m=1.5, s_min=-0.3, s_max=0.2, e=0.5,
                                                     F_C=10.0, F_brk=12.0))
    prev = body.port
    for k in range(2):
        s = m.add(f"s{k}", tr.TranslationalSpring(k=100.0 * (k + 1)))
        d = m.add(f"d{k}", tr.TranslationalDamper(b=2.0 + k))
        mass = m.add(f"m{k}", tr.Mass(m=0.5 * (k + 1)))
        m.connect(prev, s.A, d.A)
        m.connect(s.B, d.B, mass.port)
        prev = mass.port
    f = m.add("f", tr.ConstantForce(F=30.0))
    m.connect(prev, f.A)
    m.connect(f.B, g.port)
    return m


def test_a_hybrid_model_compiles_the_same_with_and_without_templates(monkeypatch):
    """Template residuals formed when read (`_TemplateEquation`) and gathered from their
    columns, with `pre` replaced in the other equations: the same model as instance by
    instance."""
    flat = fl.flatten(stop_and_springs())
    assert flat.context.pre
    assert any(isinstance(eq, fl._TemplateEquation) for eq in flat.equations)
    with_templates = mt.compile_model(stop_and_springs())
    monkeypatch.setattr(fl, "_template", lambda flat, el, templates: None)
    without = mt.compile_model(stop_and_springs())
    monkeypatch.undo()
    assert with_templates.state_names == without.state_names
    assert with_templates.alg_names == without.alg_names
    assert with_templates.names == without.names
    assert with_templates.relations == without.relations
    rng = np.random.default_rng(7)
    for name in ("f_ode", "f_alg", "f_out", "f_zero"):
        fa, fb = getattr(with_templates, name), getattr(without, name)
        args = [rng.uniform(0.5, 1.5, fa.size_in(i)) for i in range(fa.n_in())]
        for a, b in zip(fa(*args) if fa.n_out() > 1 else [fa(*args)],
                        fb(*args) if fb.n_out() > 1 else [fb(*args)]):
            np.testing.assert_allclose(np.asarray(a), np.asarray(b), rtol=1e-12,
                                       atol=1e-12, err_msg=name)


class Watched(mt.Component):
    """A capacitor from p to n whose voltage rate the parent reads: its derivative is
    made by the parent's equations, before the capacitor's template instance is added."""

    p = el.Pin(doc="Top")
    n = el.Pin(doc="Bottom")
    rate = mt.Variable("V/s", doc="Voltage rate of the capacitor")
    c = el.Capacitor(C=2e-3)

    def equations(self):
        return [mt.connect(self.p, self.c.p), mt.connect(self.c.n, self.n),
                self.rate == mt.der(self.c.v)]


@pytest.mark.parametrize("watched", [(), (1,), (0, 2)])
def test_derivatives_made_before_their_instance_give_the_same_residuals(watched,
                                                                          monkeypatch):
    """Template instances take their derivative symbols from the column made in bulk
    (`_template_derivatives`) by row; when an instance's derivative was made before (by
    the equations of its parent), its template stacks the symbols one by one instead.
    Either way: the residuals of flattening without templates, and an RC discharge."""
    def build():
        m = mt.System("watched")
        g = m.add("g", el.ElectricalReference())
        src = m.add("src", el.DCVoltageSource(V=2.0))
        m.connect(src.n, g.port)
        for k in range(3):
            r = m.add(f"r{k}", el.Resistor(R=10.0 * (k + 1)))
            m.connect(src.p, r.p)
            if k in watched:
                w = m.add(f"w{k}", Watched())
                m.connect(r.n, w.p)
                m.connect(w.n, g.port)
            else:
                c = m.add(f"c{k}", el.Capacitor(C=2e-3))
                m.connect(r.n, c.p)
                m.connect(c.n, g.port)
        return m
    flat = fl.flatten(build())
    template = next(e.origin.template for e in flat.equations
                    if e.owner in ("c0", "w0.c") and hasattr(e.origin, "template"))
    assert (min(template.der_rows) >= 0) == (not watched)
    with_templates, without = flat_both(build, monkeypatch)
    assert [str(e.residual) for e in with_templates.equations] == \
        [str(e.residual) for e in without.equations]
    res = mt.simulate(build(), 0.05)
    for k in range(3):
        tau = 10.0 * (k + 1) * 2e-3
        v = res[f"w{k}.c.v" if k in watched else f"c{k}.v"]
        np.testing.assert_allclose(v, 2.0 * (1 - np.exp(-res.t / tau)), atol=2e-5)
        if k in watched:
            np.testing.assert_allclose(res[f"w{k}.rate"], 2.0 / tau * np.exp(-res.t / tau),
                                       rtol=1e-3, atol=1e-2)


def _origins_both(build, monkeypatch):
    """Alias elimination's origins of ``build()``: as an `Origins`, and as the list of
    each kept equation's own origin (what it was before, the reference)."""
    import mechatron.compiler.alias as alias_pass
    lazy = eliminate_aliases(fl.flatten(build())).origins
    monkeypatch.setattr(alias_pass, "Origins", lambda kept: [eq.origin for eq in kept])
    plain = eliminate_aliases(fl.flatten(build())).origins
    monkeypatch.undo()
    return lazy, plain


def _same_origin(a, b) -> bool:
    """The same origin read off two flattenings of one model."""
    return (type(a) is type(b) and str(a) == str(b)
            and getattr(a, "where", None) == getattr(b, "where", None)
            and (getattr(a, "template", None) is None) ==
            (getattr(b, "template", None) is None))


def backlash_chain():
    """Inertias coupled through backlash elements: a class template whose equations hold
    a relation (the contact law's if_else), used three times."""
    m = mt.System("backlash_chain")
    ref = m.add("ref", rot.RotationalReference())
    src = m.add("src", rot.ConstantTorque(T=1.0))
    m.connect(ref.port, src.B)
    prev = src.A
    for k in range(3):
        gap = m.add(f"b{k}", rot.ElastoBacklash(c=1e3, d=1.0, b=0.01))
        body = m.add(f"j{k}", rot.Inertia(J=0.1))
        m.connect(prev, gap.A)
        m.connect(gap.B, body.port)
        prev = body.port
    return m


@pytest.mark.parametrize("build", [lambda: ladder(5), drive, stop_and_springs,
                                   backlash_chain])
def test_origins_are_formed_when_read_and_read_as_the_equations_own(build, monkeypatch):
    """`Origins` holds a template equation's origin as two numbers and forms it when
    read: read, replaced, appended, inserted, deleted and copied, it reads as the list
    of the kept equations' own origins does; and the residuals that the relation scan
    picks are the same either way."""
    from mechatron.compiler.relations import _candidates
    lazy, plain = _origins_both(build, monkeypatch)
    assert isinstance(lazy, fl.Origins) and len(lazy) == len(plain)
    held = int((lazy.which >= 0).sum())      # held as numbers: those not read before
    assert held or build is stop_and_springs
    assert all(_same_origin(a, b) for a, b in zip(lazy, plain))
    assert all(_same_origin(lazy[k], plain[k]) for k in (-1, -len(plain), len(plain) // 2))
    assert [str(o) for o in lazy[1:4]] == [str(o) for o in plain[1:4]]
    scanned = _candidates(lazy)
    assert scanned == _candidates(list(lazy)) == _candidates(plain)
    if build is backlash_chain:      # the rows of the template with a relation
        assert any(lazy.which[k] >= 0 for k in scanned)
    with pytest.raises(IndexError):
        lazy[len(plain)]
    # changed as a list: the copy changes, the original does not
    mine, ref = lazy.copy(), list(plain)
    for seq in (mine, ref):
        seq[2] = "replaced"
        seq.append("appended")
        seq[-1] = "appended again"
    assert [str(o) for o in mine] == [str(o) for o in ref]
    assert len(lazy) == len(plain) and str(lazy[2]) == str(plain[2])
    assert _candidates(mine) == _candidates(ref)
    for seq in (mine, ref):
        seq.insert(1, "inserted")
        del seq[3]
    assert [str(o) for o in mine] == [str(o) for o in ref]


def test_a_flow_sums_row_holds_no_more_variables_than_its_terms_say():
    """`Origins.terms`: after alias elimination each kept flow sum's row holds at most
    as many variables as the sum had terms (the reference node's all of its branches);
    a row replaced since is no longer counted, and a copy counts on its own."""
    flat = fl.flatten(ladder(6))
    result = eliminate_aliases(flat)
    origins, stacked = result.origins, result.stacked
    unknowns = ca.vertcat(*ca.symvar(stacked))
    counts = np.diff(np.asarray(ca.jacobian_sparsity(stacked, unknowns).get_crs()[0]))
    told = np.flatnonzero(origins.terms >= 0)
    assert told.size >= 6                           # a node per section, the reference
    assert (counts[told] <= origins.terms[told]).all()
    assert origins.terms.max() >= 6                 # the reference node's sum
    assert (origins.terms[origins.which >= 0] == -1).all()   # template rows: not sums
    k = int(told[0])
    mine = origins.copy()
    mine[k] = "replaced"
    assert mine.terms[k] == -1 and origins.terms[k] >= 0


def _eager(monkeypatch):
    """Class templates form every instance's residuals during flattening, on the
    instances' own variables (alias elimination then substitutes them), as before
    residuals were deferred."""
    monkeypatch.setattr(fl._Template, "defer",
                        lambda self, flat: self.instantiate(flat))


@pytest.mark.parametrize("build", [lambda: ladder(4), drive, stop_and_springs])
def test_residuals_formed_on_alias_replacements_equal_the_substituted_ones(build,
                                                                          monkeypatch):
    """A class template's residuals are formed once, by alias elimination, on its
    instances' arguments with the eliminated variables replaced, and only the rows
    some instance keeps: the same residuals, expression for expression, as forming
    all of them on the variables and substituting."""
    deferred = fl.flatten(build())
    pending = deferred.__dict__["_pending_templates"]
    assert pending and all(t.column is None for t in pending)
    a = eliminate_aliases(deferred)
    assert all(t.column is not None or t.pending is None for t in pending)
    # the rows that are aliases are never formed
    formed = [t for t in pending if t.column is not None]
    assert formed and all(t.replaced for t in formed)
    assert any(t.column.numel() < t.n_eq * len(t.instances) for t in formed)
    _eager(monkeypatch)
    eager = fl.flatten(build())
    assert "_pending_templates" not in eager.__dict__
    b = eliminate_aliases(eager)
    assert a.unknowns == b.unknowns and a.eliminated == b.eliminated
    assert a.stacked.shape == b.stacked.shape
    # expression for expression (the two flattenings made symbols of their own)
    assert [str(r) for r in ca.vertsplit(a.stacked)] == \
        [str(r) for r in ca.vertsplit(b.stacked)]
    # and value for value, each symbol given a value by its name
    xa, xb = ca.symvar(a.stacked), ca.symvar(b.stacked)
    assert sorted(s.name() for s in xa) == sorted(s.name() for s in xb)
    rng = np.random.default_rng(11)
    point = {s.name(): rng.uniform(0.5, 2.0) for s in xa}
    va = ca.Function("a", xa, [a.stacked])(*[point[s.name()] for s in xa])
    vb = ca.Function("b", xb, [b.stacked])(*[point[s.name()] for s in xb])
    np.testing.assert_array_equal(np.asarray(va), np.asarray(vb))


@pytest.mark.parametrize("build", [lambda: ladder(4), drive, stop_and_springs])
def test_a_model_compiles_the_same_with_residuals_formed_early_or_late(build, monkeypatch):
    late = mt.compile_model(build())
    _eager(monkeypatch)
    early = mt.compile_model(build())
    assert late.state_names == early.state_names and late.alg_names == early.alg_names
    assert late.names == early.names
    rng = np.random.default_rng(12)
    for name in ("f_ode", "f_alg", "f_out"):
        fa, fb = getattr(late, name), getattr(early, name)
        args = [rng.uniform(0.5, 1.5, fa.size_in(i)) for i in range(fa.n_in())]
        np.testing.assert_array_equal(np.asarray(fa(*args)), np.asarray(fb(*args)),
                                      err_msg=name)


def test_reading_a_deferred_residual_forms_its_class_and_the_check_does_not():
    """A residual read before alias elimination (a message, a test) forms its class's
    column on the instances' own variables; the dimension check reads the first
    instance only and forms no column."""
    from mechatron.compiler.dimensions import dimension_problems
    flat = fl.flatten(ladder(3))
    pending = flat.__dict__["_pending_templates"]
    assert dimension_problems(flat) == []
    assert all(t.column is None for t in pending)
    eq = next(e for e in flat.equations if isinstance(e, fl._TemplateEquation)
              and e.row >= e.template.n_eq)
    r = eq.residual
    assert eq.template.column is not None and not eq.template.replaced
    instance, k = divmod(eq.row, eq.template.n_eq)
    own = ca.vertcat(*eq.template.symbols(eq.template.instances[instance]))
    want = eq.template.fun(own)[k]
    x = ca.symvar(ca.vertcat(r, want))
    point = np.random.default_rng(13).uniform(0.5, 2.0, len(x))
    got = ca.Function("f", x, [r, want])(*point)
    assert float(got[0]) == float(got[1])
    # alias elimination then forms the others and takes the formed one as it is
    eliminate_aliases(flat)
    assert all(t.pending is None for t in pending)


def test_a_residual_read_after_alias_elimination_is_the_one_written():
    """After alias elimination a class's column holds its residuals with the variables
    replaced, and only the rows kept; each equation still reads its residual as
    written, on its instance's variables, whether kept or eliminated."""
    flat = fl.flatten(ladder(3))
    written = fl.flatten(ladder(3))
    eliminate_aliases(flat)
    pairs = [(a, b) for a, b in zip(flat.equations, written.equations)
             if isinstance(a, fl._TemplateEquation)]
    assert any(a.template.replaced for a, _ in pairs)
    assert [str(a.residual) for a, _ in pairs] == [str(b.residual) for _, b in pairs]


def test_a_templates_equations_are_held_as_numbers_and_formed_when_read():
    """`FlatModel.equations` holds a class template's equations as numbers (no object
    each) and forms one when read, the same object on every read, so that what is set
    on it stays; appending and deleting the last ones keep the numbers, an insertion
    before the end holds every equation as an object, in the same order."""
    flat = fl.flatten(ladder(3))
    eqs = flat.equations
    assert type(eqs) is fl.FlatEquations
    numbered = [k for k, t in enumerate(eqs.which) if t >= 0]
    assert len(numbered) > len(eqs) // 2 and not any(
        isinstance(eq, fl._TemplateEquation) for eq in eqs.given)
    k = numbered[5]
    tpl, row = eqs.templates[eqs.which[k]], eqs.rows[k]
    eq = eqs[k]
    assert type(eq) is fl._TemplateEquation and (eq.template, eq.row) == (tpl, row)
    assert eq.owner == tpl.paths[row // tpl.n_eq] and eq.alias == tpl.hint(row)
    assert eqs[k] is eq and eqs[k - len(eqs)] is eq and eqs.which[k] == -1
    marker = ca.SX.sym("marker")
    eq.residual = marker
    assert eqs[k].residual is marker
    texts = [str(e.origin) for e in list(eqs)]
    before = len(eqs)
    extra = fl.FlatEquation(ca.SX.sym("x"), "extra", "")
    eqs.append(extra)
    eqs += [extra]
    assert len(eqs) == before + 2 and eqs[-1] is extra
    del eqs[before:]
    assert len(eqs) == before and eqs.plain is None and extra not in eqs.held()
    eqs.insert(3, extra)
    assert eqs.plain is not None and eqs[3] is extra
    del eqs[3]
    assert [str(e.origin) for e in eqs] == texts and eqs[k].residual is marker


def _alias_both(build):
    """Alias elimination of ``build()`` with the templates' equations held as numbers,
    and with every equation formed as an object first (the list it read before)."""
    numbered = eliminate_aliases(fl.flatten(build()))
    flat = fl.flatten(build())
    flat.equations = list(flat.equations)
    return numbered, eliminate_aliases(flat)


def reading_model():
    from tests.compiler.test_folding import reading_model as build
    return build()


@pytest.mark.parametrize("build", [lambda: ladder(5), drive, stop_and_springs,
                                   backlash_chain, reading_model])
def test_alias_elimination_on_numbers_equals_it_on_the_equations(build):
    """Alias elimination reads the templates' hints as arrays and keeps their rows as
    numbers: the same classes, representatives, kept equations (residual, origin,
    owner, in order) and starts as reading every equation as an object."""
    a, b = _alias_both(build)
    assert a.unknowns == b.unknowns and dict(a.eliminated) == dict(b.eliminated)
    assert a.starts == b.starts and a.n_before == b.n_before
    assert a.owners == b.owners
    assert [str(o) for o in a.origins] == [str(o) for o in b.origins]
    assert [str(r) for r in ca.vertsplit(a.stacked)] == \
        [str(r) for r in ca.vertsplit(b.stacked)]


def _formed_at_once(monkeypatch):
    """Each template row formed as an object when its instance is added, its hint read
    then (the equations held as objects, as before `FlatEquations` held numbers)."""
    monkeypatch.setattr(fl.FlatEquations, "add_rows",
                        lambda self, tpl, first, last, ints:
                        self.extend(map(tpl.equation, range(first, last))))


def deep_ladder():
    from tests.compiler.test_folding import deep_ladder as build
    return build()


def two_drives():
    from tests.compiler.test_folding import two_drives as build
    return build()


@pytest.mark.parametrize("build", [reading_model, deep_ladder, two_drives])
def test_hints_held_as_numbers_follow_variables_put_back_in_place(build, monkeypatch):
    """Variables of ports bound on first read are put back where they are declared
    (`_declaration_order`), which renumbers them: the hints a template's rows give by
    number then follow their variables, as the hints formed at once and renumbered one
    by one do (the same classes and kept equations after alias elimination)."""
    flat = fl.flatten(build())
    assert any(t >= 0 for t in flat.equations.which)
    a = eliminate_aliases(flat)
    _formed_at_once(monkeypatch)
    b = eliminate_aliases(fl.flatten(build()))
    assert a.unknowns == b.unknowns and dict(a.eliminated) == dict(b.eliminated)
    assert [str(o) for o in a.origins] == [str(o) for o in b.origins]
    assert [str(r) for r in ca.vertsplit(a.stacked)] == \
        [str(r) for r in ca.vertsplit(b.stacked)]
