"""Physical connection sets formed on arrays (mechatron.compiler.nodes): the same flat
model as set by set (`flatten._connections` without it), on ladders and chains written
in any order, subsystems wired connect by connect (outside elements), connector classes
mixed in one node, a port inside and outside in one set, open ports and networks
without a reference, database models whose signal sets take their places among them,
and the nodes joined across folded subsystem ports; a model of signals alone goes set
by set."""

import random

import pytest

import mechatron as mt
import mechatron.compiler.flatten as fl
from mechatron.compiler.flatten import flatten
from mechatron.errors import ModelError
from mechatron.library import blocks
from mechatron.library import electrical as el
from mechatron.library import translational as tr
from tests.compiler.test_flatten_connections import rc
from tests.compiler.test_folding import Short, deep_ladder, reading_model, two_drives
from tests.compiler.test_hierarchy import Stage


def ladder(n: int, seed: int | None = None) -> mt.System:
    """An RC ladder of ``n`` sections; with ``seed``, its parts added and its connects
    written in a shuffled order, each connect's ports reversed at random."""
    rng = random.Random(seed)
    parts = [(f"r{k}", lambda: el.Resistor(R=1.0)) for k in range(n)] + \
        [(f"c{k}", lambda: el.Capacitor(C=1e-3)) for k in range(n)]
    if seed is not None:
        rng.shuffle(parts)
    m = mt.System("ladder")
    src = m.add("src", el.DCVoltageSource(V=1.0))
    gnd = m.add("gnd", el.ElectricalReference())
    got = {name: m.add(name, make()) for name, make in parts}
    wires = [(src.n, gnd.port)]
    node = src.p
    for k in range(n):
        r, c = got[f"r{k}"], got[f"c{k}"]
        wires += [(node, r.p), (r.n, c.p), (c.n, gnd.port)]
        node = r.n
    if seed is not None:
        rng.shuffle(wires)
        wires = [w[::-1] if rng.random() < 0.5 else w for w in wires]
    for a, b in wires:
        m.connect(a, b)
    return m


def chain(n: int) -> mt.System:
    """Masses linked by springs and dampers in parallel: nodes of three members (flow
    sums) and a reference shared by the first spring and damper."""
    m = mt.System("chain")
    prev = m.add("ref", tr.TranslationalReference()).port
    for k in range(n):
        mass = m.add(f"m{k}", tr.Mass(m=1.0))
        spring = m.add(f"k{k}", tr.TranslationalSpring(k=100.0))
        damper = m.add(f"b{k}", tr.TranslationalDamper(b=1.0))
        m.connect(mass.port, spring.A, damper.A)
        m.connect(spring.B, damper.B, prev)
        prev = mass.port
    return m


def stages(n: int) -> mt.System:
    """A ladder of `Stage` subsystems: their ports are outside elements of their own
    connects when flattened without plans (`flattened`), folded with them."""
    m = mt.System("stages")
    src = m.add("src", el.DCVoltageSource(V=1.0))
    gnd = m.add("gnd", el.ElectricalReference())
    m.connect(src.n, gnd.port)
    node = src.p
    for k in range(n):
        s = m.add(f"s{k}", Stage(R=1.0 + k, C=1.0))
        m.connect(node, s.p)
        m.connect(s.gnd, gnd.port)
        node = s.n
    return m


def loop() -> mt.System:
    """Both pins of a wire on one node: a port inside and outside in one set."""
    m = mt.System("loop")
    src = m.add("src", el.DCVoltageSource(V=1.0))
    g = m.add("g", el.ElectricalReference())
    w = m.add("a", Short())         # its pins first in their node
    load = m.add("load", el.Resistor(R=2.0))
    m.connect(src.p, w.p, w.n, load.p)
    m.connect(src.n, g.port, load.n)
    return m


def reaching_in() -> mt.System:
    """A connect of the parent reaching a part inside a subsystem and its port: that
    port's inside and outside elements in one set, the first of it."""
    m = mt.System("reach")
    src = m.add("src", el.DCVoltageSource(V=1.0))
    g = m.add("g", el.ElectricalReference())
    a = m.add("a", Stage(R=1.0, C=1.0))
    m.connect(src.p, a.p)
    m.connect(a.p, a.r.p)
    m.connect(a.n, g.port, a.gnd, src.n)
    return m


def snapshot(flat) -> dict:
    """What the connections pass leaves in a flat model, as text; the aliases also by
    the names of their variables (they hold rows)."""
    names = list(flat.variables)

    def named(v):
        return names[v] if type(v) is int else v

    return {"aliases": [tuple(map(str, a)) for a in flat.aliases],
            "aliases_by_name": [(named(a), named(b), s, o) for a, b, s, o in flat.aliases],
            "equations": [(str(e.residual), str(e.origin), str(e.alias),
                           getattr(e, "uniform", None)) for e in flat.equations],
            "sets": [list(map(str, s)) for s in flat.connection_sets],
            "variables": list(flat.variables)}


def flattened(monkeypatch, build, *, bulk: bool) -> tuple[dict | None, bool]:
    """(snapshot of ``build()`` flattened, whether the sets were formed on arrays); the
    snapshot is None and the message is returned instead when flattening fails."""
    used = []
    original = fl.physical_nodes

    def spy(flat, joined, *signals):
        got = original(flat, joined, *signals) if bulk else None
        used.append(got is not None)
        return got

    with monkeypatch.context() as m:
        m.setattr(fl, "physical_nodes", spy)
        m.setattr(fl, "plan_subsystems", lambda model, elements: ({}, {}))
        try:
            return snapshot(flatten(build())), any(used)
        except ModelError as exc:
            return str(exc), any(used)


@pytest.mark.parametrize("build", [
    lambda: ladder(7), lambda: ladder(7, seed=1), lambda: ladder(7, seed=2),
    lambda: chain(5), lambda: stages(4), lambda: rc(True), lambda: rc(False), loop, reaching_in],
    ids=["ladder", "ladder_shuffled_1", "ladder_shuffled_2", "chain", "stages",
         "mixed_pins_node_of_three", "mixed_pins", "loop",
         "port_inside_and_outside"])
def test_sets_on_arrays_give_the_flat_model_of_set_by_set(build, monkeypatch):
    bulk, used = flattened(monkeypatch, build, bulk=True)
    plain, _ = flattened(monkeypatch, build, bulk=False)
    assert used, "the sets were not formed on arrays"
    assert bulk == plain


def test_a_ladder_drawn_in_another_order_has_the_same_sets(monkeypatch):
    ordered, _ = flattened(monkeypatch, lambda: ladder(6), bulk=True)
    shuffled, _ = flattened(monkeypatch, lambda: ladder(6, seed=3), bulk=True)
    assert shuffled["sets"] == ordered["sets"]
    assert shuffled["aliases_by_name"] == ordered["aliases_by_name"]


def open_port() -> mt.System:
    m = ladder(2)
    m.add("loose", el.Resistor(R=1.0))
    m.connect(m.loose.p, m.r1.n)
    return m


def no_reference() -> mt.System:
    m = mt.System("floating")
    a = m.add("a", el.Resistor(R=1.0))
    b = m.add("b", el.Capacitor(C=1.0))
    m.connect(a.p, b.p)
    m.connect(a.n, b.n)
    return m


@pytest.mark.parametrize("build, words", [
    (open_port, "port 'loose.n' (electrical) is not connected"),
    (no_reference, "has no reference")], ids=["open_port", "no_reference"])
def test_problems_are_reported_as_set_by_set(build, words, monkeypatch):
    bulk, used = flattened(monkeypatch, build, bulk=True)
    plain, _ = flattened(monkeypatch, build, bulk=False)
    assert used
    assert isinstance(bulk, str) and words in bulk
    assert bulk == plain


@pytest.mark.parametrize("name, variant", [
    ("dc_motor", "inputs"), ("dc_motor_pwm", "switched"), ("bldc_motor", "acausal"),
    ("buck_converter", "switched"), ("hydraulic_cylinder", "acausal"),
    ("servo_encoder", "acausal"), ("two_axis", "inputs")])
def test_signal_sets_take_their_places_among_the_sets_on_arrays(name, variant,
                                                                  monkeypatch):
    """A model with signals: its physical sets formed on arrays, its signal sets set by
    set in their places (the sets, their aliases and problems in the same order)."""
    model = lambda: mt.models.get(name).build(variant=variant)    # noqa: E731
    bulk, used = flattened(monkeypatch, model, bulk=True)
    assert used
    assert any("signal" in str(s).lower() for s in bulk["sets"])
    assert bulk == flattened(monkeypatch, model, bulk=False)[0]


def shuffled_stages(seed: int) -> mt.System:
    """`stages` with its parts added and its connects written in a shuffled order, each
    connect's ports reversed at random."""
    rng = random.Random(seed)
    m = mt.System("stages")
    names = ["src", "gnd", *(f"s{k}" for k in range(5))]
    rng.shuffle(names)
    made = {"src": lambda: el.DCVoltageSource(V=1.0), "gnd": el.ElectricalReference}
    got = {name: m.add(name, made.get(name, lambda: Stage(R=2.0, C=0.5))())
           for name in names}
    wires = [(got["src"].n, got["gnd"].port)]
    node = got["src"].p
    for k in range(5):
        s = got[f"s{k}"]
        wires += [(node, s.p), (s.gnd, got["gnd"].port)]
        node = s.n
    rng.shuffle(wires)
    for a, b in wires:
        m.connect(*((b, a) if rng.random() < 0.5 else (a, b)))
    return m


def driven_drives() -> mt.System:
    """`two_drives` fed by a controlled source that a step drives: signal sets among the
    joined nodes."""
    m = two_drives()
    step = m.add("step", blocks.Step(t_step=0.1, final=2.0))
    src = m.add("boost", el.ControlledVoltageSource())
    r = m.add("r", el.Resistor(R=10.0))
    m.connect(step.y, src.u)
    m.connect(src.p, r.p)
    m.connect(r.n, m.d1.p)
    m.connect(src.n, m.g.port)
    return m


def drives_and_stage() -> mt.System:
    """`two_drives` with a `Stage` across the supply, its output open: two classes
    planned in one model."""
    m = two_drives()
    s = m.add("filter", Stage(R=4.0, C=1e-3))
    m.connect(s.p, m.src.p)
    m.connect(m.g.port, s.gnd)
    return m


def floating_stages() -> mt.System:
    """Stages without a reference."""
    m = mt.System("floating")
    a = m.add("a", Stage(R=1.0, C=1.0))
    b = m.add("b", Stage(R=1.0, C=1.0))
    m.connect(a.n, b.p)
    m.connect(a.gnd, b.gnd, b.n)
    return m


def flattened_planned(monkeypatch, build, *, arrays: bool,
                      joined: bool = True) -> tuple[dict | str, bool]:
    """(snapshot of ``build()`` flattened with its subsystems planned, the folded ports'
    columns with it, or the message it fails with; whether `planned_nodes` formed the
    nodes). Without ``arrays`` the nodes are joined set by set (`folding.join_planned`),
    read on arrays (`joined_nodes`) with ``joined``."""
    used = []
    original, original_joined = fl.planned_nodes, fl.joined_nodes

    def spy(*args):
        got = original(*args) if arrays else None
        used.append(got is not None)
        return got

    with monkeypatch.context() as m:
        m.setattr(fl, "planned_nodes", spy)
        m.setattr(fl, "joined_nodes", lambda flat, groups: joined and original_joined(
            flat, groups))
        try:
            flat = flatten(build())
        except ModelError as exc:
            return str(exc), any(used)
    assert flat.folded, "no port was folded"
    f = flat.folded
    return {**snapshot(flat), "folded": (f.names, f.units, f.docs, f.position, f.order,
                                         f.term_ptr.tolist(), f.term_rows.tolist())}, \
        any(used)


@pytest.mark.parametrize("build", [
    lambda: stages(5), lambda: shuffled_stages(1), lambda: shuffled_stages(2), two_drives,
    driven_drives, drives_and_stage, floating_stages],
    ids=["stages", "stages_shuffled_1", "stages_shuffled_2", "two_drives", "with_signals",
         "two_classes", "no_reference"])
def test_nodes_joined_on_arrays_give_the_flat_model_of_set_by_set(build, monkeypatch):
    """Subsystems wired by their plan: the nodes joined across their folded ports formed
    on arrays, joined set by set and read on arrays, and all set by set."""
    arrays, used = flattened_planned(monkeypatch, build, arrays=True)
    joined, _ = flattened_planned(monkeypatch, build, arrays=False)
    plain, _ = flattened_planned(monkeypatch, build, arrays=False, joined=False)
    assert used, "the nodes were not formed on arrays"
    assert arrays == joined == plain


@pytest.mark.parametrize("build", [deep_ladder, reading_model],
                         ids=["subsystem_in_subsystem", "port_read_by_an_equation"])
def test_nodes_joined_set_by_set_where_arrays_do_not_reach(build, monkeypatch):
    """A plan's set holding a folded port of a subsystem within, or a planned port read
    by an equation (a member itself, bound late): joined set by set, read on arrays."""
    arrays, used = flattened_planned(monkeypatch, build, arrays=True)
    plain, _ = flattened_planned(monkeypatch, build, arrays=False, joined=False)
    assert not used
    assert arrays == plain


def test_a_model_of_signals_alone_goes_set_by_set(monkeypatch):
    model = lambda: mt.models.get("dc_motor").build(variant="blocks")   # noqa: E731
    bulk, used = flattened(monkeypatch, model, bulk=True)
    assert not used
    assert bulk == flattened(monkeypatch, model, bulk=False)[0]
