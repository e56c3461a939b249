"""Random electrical networks built from random subsystem classes (mechatron.compiler.folding,
mechatron.compiler.nodes): each is compiled with its subsystems wired by their plans
and with every port written out, with its nodes formed on arrays and set by set, and
drawn in two orders; every way gives the same model and the same logged values.

A network has a source behind a resistor, a leak resistor from every node to the
reference (so that every node has a path to it), and instances of two to four
subsystem classes made for the seed: each with two or three pins, a parameter or two
passed on to its parts (unchanged, scaled, or not at all), resistor, series RC and
series RL branches between its pins and nodes of its own, and in some seeds an instance
of an earlier class as a part (a plan within a plan). Every capacitor is in series with
a resistor and every node meets a resistor, so no network needs index reduction and
each has the same states however it is drawn."""

from __future__ import annotations

import random

import numpy as np
import pytest

import mechatron as mt
from mechatron.compiler.flatten import flatten
from mechatron.library import blocks
from mechatron.library import electrical as el
from tests.compiler.test_folding import assert_same, unfolded
from tests.compiler.test_nodes import flattened, flattened_planned

#: the seeds drawn; 32 and 142 draw networks where only the written-out form keeps an
#: algebraic loop (its states once started elsewhere: see solvers.initial)
SEEDS = [*range(12), 32, 142]
T_END = 0.02

_R = (0.5, 1.0, 2.0, 5.0)
_C = (1e-3, 2e-3, 5e-3)
_L = (1e-3, 5e-3)


def _branch(rng, ns: dict, name: str, kind: str, a: str, b: str, wires: dict) -> None:
    """Parts of one branch between nodes ``a`` and ``b`` of a class (``wires``: node ->
    the pins on it, as attribute paths), in ``ns``; a series branch's middle node is
    a node of its own, inside every instance."""
    value = rng.choice(("own", "passed", "scaled"))
    r_value = {"own": rng.choice(_R), "passed": ns["Rb"], "scaled": ns["Rb"] * 2}[value]
    ns[f"{name}r"] = el.Resistor(R=r_value)
    ends = [(f"{name}r", "p"), (f"{name}r", "n")]
    if kind == "RC":
        ns[f"{name}c"] = el.Capacitor(C=ns["Cb"] if rng.random() < 0.5 else rng.choice(_C))
        wires[f"{name}m"] = [(f"{name}r", "n"), (f"{name}c", "p")]
        ends[1] = (f"{name}c", "n")
    elif kind == "RL":
        ns[f"{name}l"] = el.Inductor(L=rng.choice(_L))
        wires[f"{name}m"] = [(f"{name}r", "n"), (f"{name}l", "p")]
        ends[1] = (f"{name}l", "n")
    if rng.random() < 0.5:
        ends.reverse()
    wires[a].append(ends[0])
    wires[b].append(ends[1])


def random_class(rng, name: str, earlier: list) -> type:
    """A subsystem class: two or three pins, parameters ``Rb`` and ``Cb`` passed on to
    some parts, a tree of branches over its pins, two branches from each node of its
    own (the first a resistor), and perhaps an instance of a class of ``earlier``."""
    ns = {"Rb": mt.Parameter("Ohm", default=rng.choice(_R), min=0, doc="Branch resistance"),
          "Cb": mt.Parameter("F", default=rng.choice(_C), min=0, doc="Branch capacitance")}
    pins = [f"p{k}" for k in range(rng.choice((2, 3)))]
    for pin in pins:
        ns[pin] = el.Pin(doc=f"Pin {pin}")
    wires: dict[str, list] = {pin: [(pin,)] for pin in pins}
    n_branch = 0

    def branch(a, b, kind=None):
        nonlocal n_branch
        _branch(rng, ns, f"b{n_branch}", kind or rng.choice(("R", "RC", "RL")), a, b,
                wires)
        n_branch += 1

    for k in range(1, len(pins)):            # a tree over the pins
        branch(pins[rng.randrange(k)], pins[k])
    for k in range(rng.choice((0, 1, 2))):   # nodes of its own, each met by two branches
        node = f"x{k}"
        wires[node] = []
        others = [n for n in wires if n != node]
        a, b = rng.sample(others, 2) if len(others) > 1 else (others[0], others[0])
        branch(node, a, "R")
        branch(node, b)
    if rng.random() < 0.5:
        branch(*rng.sample(pins, 2))
    if earlier and rng.random() < 0.4:      # a subsystem within: its pins on our nodes
        inner = rng.choice(earlier)
        ns["sub"] = inner(Rb=ns["Rb"]) if rng.random() < 0.5 else inner()
        nodes = list(wires)
        for pin in inner.pin_names:
            wires[rng.choice(nodes)].append(("sub", pin))
    order = list(wires.items())
    rng.shuffle(order)
    plan = [members[::-1] if rng.random() < 0.5 else members for _, members in order]

    def equations(self):
        def port(path):
            obj = self
            for step in path:
                obj = getattr(obj, step)
            return obj
        return [mt.connect(*map(port, members)) for members in plan if len(members) > 1]

    ns["equations"] = equations
    cls = type(name, (mt.Component,), ns)
    cls.pin_names = tuple(pins)
    cls.nested = "sub" in ns
    return cls


def random_network(seed: int, order: int = 0):
    """The network of ``seed`` and a builder of it; ``order`` shuffles the order its
    parts are added and its connections written (ports reversed, nodes written as one
    connect or as a chain of two-port connects), not the network."""
    rng = random.Random(seed)
    classes: list[type] = []
    for k in range(rng.choice((2, 3, 4))):
        classes.append(random_class(rng, f"Sub{seed}_{k}", classes))
    n_nodes = rng.choice((2, 3, 4, 5))
    nodes = ["g"] + [f"m{k}" for k in range(n_nodes)]
    volts = rng.choice((1.0, 5.0, 12.0))
    parts = [("rs", lambda: el.Resistor(R=0.5), [("s", "p"), ("m0", "n")]),
             ("gnd", el.ElectricalReference, [("g", "port")])]
    if rng.random() < 0.3:      # a source a step drives: signal sets among the nodes
        parts += [("src", el.ControlledVoltageSource, [("g", "n"), ("s", "p")]),
                  ("step", lambda: blocks.Step(t_step=T_END / 4, initial=1.0, final=volts),
                   [])]
        signals = [(("step", "y"), ("src", "u"))]
    else:
        parts.append(("src", lambda: el.DCVoltageSource(V=volts), [("g", "n"), ("s", "p")]))
        signals = []
    used = set()
    for k in range(rng.choice((2, 3, 4, 5, 6))):
        cls = rng.choice(classes)
        used.add(cls)
        given = {"Rb": rng.choice(_R)} if rng.random() < 0.3 else {}
        pins = list(cls.pin_names)
        attached = [(rng.choice(nodes), pin) for pin in pins]
        if len(pins) == 3 and rng.random() < 0.2:
            attached.pop()                  # a pin left open outside
        parts.append((f"u{k}", lambda cls=cls, given=given: cls(**given), attached))
    met = {node for _, _, attached in parts for node, _ in attached}
    for node in nodes[1:]:                  # a leak from every node met to the reference
        if node in met:
            r = rng.choice(_R)
            parts.append((f"leak_{node}", lambda r=r: el.Resistor(R=r * 10),
                          [(node, "p"), ("g", "n")]))
    shuffle = random.Random(1000 * seed + order)
    if order:
        shuffle.shuffle(parts)

    def build() -> mt.System:
        m = mt.System(f"net{seed}")
        wires: dict[str, list] = {}
        for name, make, attached in parts:
            part = m.add(name, make())
            for node, pin in attached:
                wires.setdefault(node, []).append(getattr(part, pin))
        connects = []
        for members in wires.values():
            if len(members) < 2:
                continue
            members = list(members)
            if order:
                shuffle.shuffle(members)
            if order and shuffle.random() < 0.5:
                connects += [(a, b) for a, b in zip(members, members[1:])]
            else:
                connects.append(tuple(members))
        connects += [tuple(getattr(getattr(m, a), b) for a, b in link)
                     for link in signals]
        if order:
            shuffle.shuffle(connects)
        for members in connects:
            m.connect(*members)
        return m

    # the builder is called more than once: the same shuffles each time
    state = shuffle.getstate()

    def fresh() -> mt.System:
        shuffle.setstate(state)
        return build()

    fresh.nested = any(cls.nested for cls in used)      # a plan within a plan
    return fresh


@pytest.mark.parametrize("seed", SEEDS)
def test_planned_subsystems_give_the_model_of_the_written_out_ports(seed, monkeypatch):
    build = random_network(seed)
    assert flatten(build()).folded, "no port was folded"
    # where folding leaves fewer unknowns (a port's through variable in a sum of three),
    # the two are different systems of equations integrated to rtol 1e-10: they agree
    # to about 1e-9 of each signal's scale after some hundreds of steps, not exactly
    assert_same(mt.compile_model(build()), unfolded(monkeypatch, build), T_END, tol=1e-8)


@pytest.mark.parametrize("seed", SEEDS)
def test_nodes_on_arrays_give_the_flat_model_of_set_by_set(seed, monkeypatch):
    build = random_network(seed)
    arrays, used = flattened_planned(monkeypatch, build, arrays=True)
    joined, _ = flattened_planned(monkeypatch, build, arrays=False)
    plain, _ = flattened_planned(monkeypatch, build, arrays=False, joined=False)
    assert arrays == joined == plain
    # a plan within a plan is joined set by set; any other is formed on arrays
    assert used == (not build.nested)
    # written out (no plans): the sets on arrays and set by set
    bulk, used = flattened(monkeypatch, build, bulk=True)
    assert used
    assert bulk == flattened(monkeypatch, build, bulk=False)[0]


@pytest.mark.parametrize("seed", SEEDS)
def test_a_network_drawn_in_another_order_has_the_same_states_and_values(seed):
    a = mt.compile_model(random_network(seed)())
    b = mt.compile_model(random_network(seed, order=1)())
    assert sorted(a.names) == sorted(b.names)
    assert sorted(a.state_names) == sorted(b.state_names)
    ra = mt.simulate(a, T_END, rtol=1e-10, atol=1e-12, log="all")
    rb = mt.simulate(b, T_END, rtol=1e-10, atol=1e-12, t_out=ra.t, log="all")
    for name in a.names:
        scale = max(1.0, float(np.max(np.abs(ra[name]))))
        np.testing.assert_allclose(rb[name], ra[name], rtol=0, atol=1e-8 * scale,
                                   err_msg=name)
