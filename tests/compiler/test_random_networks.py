"""Random electrical networks built from random subsystem classes
(mechatron.compiler.folding, mechatron.compiler.nodes, mechatron.solvers.initial): each
is compiled with its subsystems wired by their plans and with every port written out,
with its nodes formed on arrays and set by set, and drawn in two orders; every way gives
the same model and the same logged values, and these follow the network solved by hand
(modified nodal analysis, integrated exactly).

A network has a source behind a resistor (a constant voltage, one a Step drives, or one a
Pulse drives: five events the solver locates), a leak resistor from every node to the
reference, and instances of two to four subsystem classes made for the seed: each with
two or three pins (the third sometimes open outside), parameters passed on to its parts
(unchanged, scaled, or not at all), resistor, series RC and series RL branches between
its pins and nodes of its own, and in some seeds an instance of an earlier class as a
part (a plan within a plan). Every capacitor is
in series with a resistor, every node meets a resistor and a pin left open is joined to
another by resistors and capacitors, so no network needs index reduction and the exact
solution is a linear ODE in the capacitor voltages and inductor currents. With
``loops``, lone capacitors and inductors make loops of capacitors and cut sets of
inductors, which do (those are compared among the ways of compiling, not by hand)."""

from __future__ import annotations

import random

import numpy as np
import pytest

import mechatron as mt
from mechatron.analysis.linear import linearize
from mechatron.compiler.flatten import flatten
from mechatron.library import blocks
from mechatron.library import electrical as el
from tests.compiler.random_models import assembled, assert_same_run, exact, wired_equations
from tests.compiler.test_folding import assert_same, unfolded
from tests.compiler.test_nodes import flattened, flattened_planned

#: the seeds drawn; 32 and 142 draw networks where only the written-out form keeps an
#: algebraic loop (its states once started elsewhere: see solvers.initial)
SEEDS = [*range(12), 32, 142]
#: seeds drawn with loops of capacitors and cut sets of inductors (index reduction)
LOOP_SEEDS = range(6)
#: seeds drawn with the source driven by a pulse train
PULSE_SEEDS = range(4)
T_END = 0.02

_R = (0.5, 1.0, 2.0, 5.0)
_C = (1e-3, 2e-3, 5e-3)
_L = (1e-3, 5e-3)


def _branch(rng, ns: dict, name: str, kind: str, a: str, b: str, wires: dict,
            specs: dict) -> None:
    """Parts of one branch between nodes ``a`` and ``b`` of a class (``wires``: node ->
    the pins on it, as attribute paths), in ``ns``; a series branch's middle node is
    a node of its own, inside every instance. A lone capacitor or inductor (``C``,
    ``L``) may close a loop of capacitors or a cut set of inductors: index reduction."""
    if kind in ("C", "L"):
        part = f"{name}{kind.lower()}"
        if kind == "C":
            ns[part], specs[part] = el.Capacitor(C=ns["Cb"]), ("C", ("Cb", 1.0))
        else:
            henry = rng.choice(_L)
            ns[part], specs[part] = el.Inductor(L=henry), ("L", ("lit", henry))
        ends = [(part, "p"), (part, "n")]
        rng.shuffle(ends)
        wires[a].append(ends[0])
        wires[b].append(ends[1])
        return
    value = rng.choice(("own", "passed", "scaled"))
    own = rng.choice(_R)
    r_value = {"own": own, "passed": ns["Rb"], "scaled": ns["Rb"] * 2}[value]
    ns[f"{name}r"] = el.Resistor(R=r_value)
    specs[f"{name}r"] = ("R", ("lit", own) if value == "own" else
                         ("Rb", 1.0 if value == "passed" else 2.0))
    ends = [(f"{name}r", "p"), (f"{name}r", "n")]
    if kind == "RC":
        if rng.random() < 0.5:
            ns[f"{name}c"], specs[f"{name}c"] = el.Capacitor(C=ns["Cb"]), ("C", ("Cb", 1.0))
        else:
            farad = rng.choice(_C)
            ns[f"{name}c"], specs[f"{name}c"] = el.Capacitor(C=farad), ("C", ("lit", farad))
        wires[f"{name}m"] = [(f"{name}r", "n"), (f"{name}c", "p")]
        ends[1] = (f"{name}c", "n")
    elif kind == "RL":
        henry = rng.choice(_L)
        ns[f"{name}l"], specs[f"{name}l"] = el.Inductor(L=henry), ("L", ("lit", henry))
        wires[f"{name}m"] = [(f"{name}r", "n"), (f"{name}l", "p")]
        ends[1] = (f"{name}l", "n")
    if rng.random() < 0.5:
        ends.reverse()
    wires[a].append(ends[0])
    wires[b].append(ends[1])


def random_class(rng, name: str, earlier: list, loops: bool = False) -> type:
    """A subsystem class: two or three pins, parameters ``Rb`` and ``Cb`` passed on to
    some parts, a tree of branches over its pins, two branches from each node of its
    own (the first a resistor), and perhaps an instance of a class of ``earlier``; with
    ``loops``, lone capacitors and inductors among the branches too."""
    kinds = ("R", "RC", "RL", "C", "L") if loops else ("R", "RC", "RL")
    ns = {"Rb": mt.Parameter("Ohm", default=rng.choice(_R), min=0, doc="Branch resistance"),
          "Cb": mt.Parameter("F", default=rng.choice(_C), min=0, doc="Branch capacitance")}
    pins = [f"p{k}" for k in range(rng.choice((2, 3)))]
    for pin in pins:
        ns[pin] = el.Pin(doc=f"Pin {pin}")
    wires: dict[str, list] = {pin: [(pin,)] for pin in pins}
    specs: dict[str, tuple] = {}
    n_branch = 0

    def branch(a, b, kind=None):
        nonlocal n_branch
        _branch(rng, ns, f"b{n_branch}", kind or rng.choice(kinds), a, b, wires, specs)
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
        passed = rng.random() < 0.5
        ns["sub"] = inner(Rb=ns["Rb"]) if passed else inner()
        nodes = list(wires)
        for pin in inner.pin_names:
            wires[rng.choice(nodes)].append(("sub", pin))
    ns["equations"] = wired_equations(rng, wires)
    cls = type(name, (mt.Component,), ns)
    cls.pin_names = tuple(pins)
    cls.nested = "sub" in ns
    # what `netlist` reads: the nodes with the pins on each, each part's kind and value
    cls.wires, cls.specs = wires, specs
    # a pin that may be left open outside: one that resistors and capacitors inside join
    # to another pin (else inductors alone would join it to the network, a cut set of
    # inductors that needs index reduction)
    cls.may_open = {pin: _joined_to_another(pin, pins, wires, specs) for pin in pins}
    cls.sub = (inner, passed) if cls.nested else None
    return cls


def _joined_to_another(pin: str, pins: list, wires: dict, specs: dict) -> bool:
    """Whether the resistors and capacitors of a class join ``pin`` to another pin
    (a subsystem within not counted)."""
    ends: dict[str, list] = {}
    for node, members in wires.items():
        for member in members:
            if len(member) == 2 and member[0] != "sub":
                ends.setdefault(member[0], []).append(node)
    links: dict[str, set] = {}
    for part, (a, b) in ends.items():
        if specs[part][0] in ("R", "C"):
            links.setdefault(a, set()).add(b)
            links.setdefault(b, set()).add(a)
    seen, todo = {pin}, [pin]
    while todo:
        for nxt in links.get(todo.pop(), ()):
            if nxt not in seen:
                seen.add(nxt)
                todo.append(nxt)
    return any(other in seen for other in pins if other != pin)


#: the pulse train of ``random_network(pulses=True)``: five edges in T_END
PULSE = {"period": T_END / 3, "width": 0.4, "delay": T_END / 10}


def _pulse_stretches(amplitude: float) -> list[tuple[float, float]]:
    """The pulse train `PULSE` as (from time, value) stretches up to T_END."""
    out, k = [(0.0, 0.0)], 0
    while True:
        on = PULSE["delay"] + k * PULSE["period"]
        if on >= T_END:
            return out
        out += [(on, amplitude), (on + PULSE["width"] * PULSE["period"], 0.0)]
        k += 1


def random_network(seed: int, order: int = 0, loops: bool = False, pulses: bool = False):
    """The network of ``seed`` and a builder of it; ``order`` shuffles the order its
    parts are added and its connections written (ports reversed, nodes written as one
    connect or as a chain of two-port connects), not the network; ``pulses`` drives the
    source by a pulse train (five events) instead of what the seed draws."""
    rng = random.Random(seed)
    classes: list[type] = []
    for k in range(rng.choice((2, 3, 4))):
        classes.append(random_class(rng, f"Sub{seed}_{k}", classes, loops))
    n_nodes = rng.choice((2, 3, 4, 5))
    nodes = ["g"] + [f"m{k}" for k in range(n_nodes)]
    volts = rng.choice((1.0, 5.0, 12.0))
    parts = [("rs", lambda: el.Resistor(R=0.5), [("s", "p"), ("m0", "n")]),
             ("gnd", el.ElectricalReference, [("g", "port")])]
    # the network as `netlist` reads it: (path, kind, value, p node, n node) of the parts
    # at the top, (path, class, given Rb, pin -> node) of the instances, the source's
    # voltage as (from time, value) stretches
    top = [("rs", "R", 0.5, "s", "m0")]
    instances = []
    if rng.random() < 0.3 or pulses:    # a driven source: signal sets among the nodes
        parts.append(("src", el.ControlledVoltageSource, [("g", "n"), ("s", "p")]))
        signals = [(("drive", "y"), ("src", "u"))]
        if pulses:
            parts.append(("drive", lambda: blocks.Pulse(amplitude=volts, **PULSE), []))
            source = _pulse_stretches(volts)
        else:
            parts.append(("drive", lambda: blocks.Step(t_step=T_END / 4, initial=1.0,
                                                       final=volts), []))
            source = [(0.0, 1.0), (T_END / 4, volts)]
    else:
        parts.append(("src", lambda: el.DCVoltageSource(V=volts), [("g", "n"), ("s", "p")]))
        signals = []
        source = [(0.0, volts)]
    used = set()
    for k in range(rng.choice((2, 3, 4, 5, 6))):
        cls = rng.choice(classes)
        used.add(cls)
        given = {"Rb": rng.choice(_R)} if rng.random() < 0.3 else {}
        pins = list(cls.pin_names)
        attached = [(rng.choice(nodes), pin) for pin in pins]
        if len(pins) == 3 and rng.random() < 0.2 and cls.may_open[pins[-1]]:
            attached.pop()                  # a pin left open outside
        parts.append((f"u{k}", lambda cls=cls, given=given: cls(**given), attached))
        instances.append((f"u{k}", cls, given.get("Rb"),
                          {pin: node for node, pin in attached}))
    met = {node for _, _, attached in parts for node, _ in attached}
    for node in nodes[1:]:                  # a leak from every node met to the reference
        if node in met:
            r = rng.choice(_R)
            parts.append((f"leak_{node}", lambda r=r: el.Resistor(R=r * 10),
                          [(node, "p"), ("g", "n")]))
            top.append((f"leak_{node}", "R", r * 10, node, "g"))
    fresh = assembled(f"net{seed}", parts, signals, seed, order)
    fresh.nested = any(cls.nested for cls in used)      # a plan within a plan
    fresh.netlist = lambda: netlist(top, instances)
    fresh.source = source
    return fresh


def netlist(top: list, instances: list) -> list[tuple]:
    """Every resistor, capacitor and inductor of a network, ``(path, kind, value, p node,
    n node)``, read from what the generator wrote down (not from the model): each
    instance's nodes named by its path, a pin's node the node outside it (its own if
    the pin is open outside), the values passed on through the levels."""
    out = list(top)

    def expand(cls, path, rb, outer):
        rb = cls._declarations["Rb"].default if rb is None else rb
        cb = cls._declarations["Cb"].default
        node_of = {node: outer.get(node) or f"{path}.{node}" for node in cls.wires}
        ends, inner_outer = {}, {}
        for node, members in cls.wires.items():
            for member in members:
                if member[0] == "sub":
                    inner_outer[member[1]] = node_of[node]
                elif len(member) == 2:
                    ends[member] = node_of[node]
        for part, (kind, (source, x)) in cls.specs.items():
            value = x if source == "lit" else x * (rb if source == "Rb" else cb)
            out.append((f"{path}.{part}", kind, value, ends[(part, "p")],
                        ends[(part, "n")]))
        if cls.sub is not None:
            inner, passed = cls.sub
            expand(inner, f"{path}.sub", rb if passed else None, inner_outer)

    for path, cls, rb, attached in instances:
        expand(cls, path, rb, attached)
    return out


def nodal_system(parts: list):
    """The network by modified nodal analysis: each capacitor's voltage and each inductor's
    current are the states ``s``, the node voltages, capacitor currents and the source's
    current ``y`` are solved from them and the source voltage ``V`` (a linear system,
    ``y = MN s + Mc V``), and ``s' = F s + g V``. Returns ``(F, g, MN, Mc, at, caps,
    inds)``: ``at`` each node's row in ``y``, ``caps`` and ``inds`` the parts in the
    order of the states."""
    nodes = sorted({n for *_, a, b in parts for n in (a, b)} - {"g"})
    at = {n: k for k, n in enumerate(nodes)}
    caps = [q for q in parts if q[1] == "C"]
    inds = [q for q in parts if q[1] == "L"]
    n, nc, nl = len(nodes), len(caps), len(inds)
    # unknowns y = node voltages, capacitor currents, source current; states s = capacitor
    # voltages, inductor currents; M y = N s + c V
    M = np.zeros((n + nc + 1, n + nc + 1))
    N = np.zeros((n + nc + 1, nc + nl))
    c = np.zeros(n + nc + 1)

    def leave(node, column, sign, matrix):  # a current leaving `node` into a branch
        if node != "g":
            matrix[at[node], column] += sign

    for path, kind, value, a, b in parts:
        if kind == "R":
            for x, y_, sign in ((a, a, 1), (a, b, -1), (b, a, -1), (b, b, 1)):
                if x != "g" and y_ != "g":
                    M[at[x], at[y_]] += sign / value
    for j, (path, _, value, a, b) in enumerate(caps):
        leave(a, n + j, 1.0, M)
        leave(b, n + j, -1.0, M)
        row = n + j                  # v_a - v_b = the capacitor's voltage
        for node, sign in ((a, 1.0), (b, -1.0)):
            if node != "g":
                M[row, at[node]] += sign
        N[row, j] = 1.0
    for j, (path, _, value, a, b) in enumerate(inds):
        leave(a, nc + j, -1.0, N)    # moved to the right-hand side
        leave(b, nc + j, 1.0, N)
    leave("s", n + nc, 1.0, M)       # the source, p on "s", n on the reference
    M[n + nc, at["s"]] = 1.0
    c[n + nc] = 1.0
    solve = np.linalg.solve
    MN, Mc = solve(M, N), solve(M, c)
    # s' = P y: a capacitor's current over C, an inductor's voltage over L
    P = np.zeros((nc + nl, n + nc + 1))
    for j, (_, _, value, a, b) in enumerate(caps):
        P[j, n + j] = 1.0 / value
    for j, (_, _, value, a, b) in enumerate(inds):
        for node, sign in ((a, 1.0), (b, -1.0)):
            if node != "g":
                P[nc + j, at[node]] = sign / value
    return P @ MN, P @ Mc, MN, Mc, at, caps, inds


def nodal_solution(parts: list, source: list, t: np.ndarray) -> dict[str, np.ndarray]:
    """The network solved by hand (`nodal_system`), the states' linear ODE integrated
    exactly (the matrix exponential of each stretch of constant source voltage,
    ``source``: (from time, value) in order). Returns each part's pin voltages and
    current at the times ``t``, by the names Mechatron logs. A capacitor or inductor
    starts at 0, as their start values."""
    F, g, MN, Mc, at, caps, inds = nodal_system(parts)
    n, nc, nl = len(at), len(caps), len(inds)
    states = np.zeros((t.size, nc + nl))
    starts = np.array([a for a, _ in source])
    for k, tk in enumerate(t):
        # exact: the ODE s' = F s + g V, V constant on each stretch
        s = np.zeros(nc + nl)
        for j, (begin, value) in enumerate(source):
            if begin >= tk:
                break
            end = min(tk, source[j + 1][0]) if j + 1 < len(source) else tk
            s = exact(F, g * value, s, end - begin)
        states[k] = s
    # a stretch's value from its first instant on (blocks.Step: final where t_step <= t)
    volts = np.array([v for _, v in source])[np.searchsorted(starts, t, side="right") - 1]
    y = states @ MN.T + np.outer(volts, Mc)
    v = np.zeros((t.size, n + 1))
    v[:, :n] = y[:, :n]              # the last column: the reference, 0
    col = {**at, "g": n}
    out = {}
    for path, kind, value, a, b in parts:
        out[f"{path}.p.v"], out[f"{path}.n.v"] = v[:, col[a]], v[:, col[b]]
        if kind == "R":
            out[f"{path}.i"] = (v[:, col[a]] - v[:, col[b]]) / value
    for j, (path, *_) in enumerate(caps):
        out[f"{path}.i"] = y[:, n + j]
    for j, (path, *_) in enumerate(inds):
        out[f"{path}.i"] = states[:, nc + j]
    return out


@pytest.mark.parametrize("seed,loops", [(s, False) for s in SEEDS] +
                         [(s, True) for s in LOOP_SEEDS])
def test_planned_subsystems_give_the_model_of_the_written_out_ports(seed, loops,
                                                                    monkeypatch):
    build = random_network(seed, loops=loops)
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


@pytest.mark.parametrize("seed,loops", [(s, False) for s in SEEDS] +
                         [(s, True) for s in LOOP_SEEDS])
def test_a_network_drawn_in_another_order_has_the_same_states_and_values(seed, loops):
    a = mt.compile_model(random_network(seed, loops=loops)())
    b = mt.compile_model(random_network(seed, order=1, loops=loops)())
    if not loops:       # where index reduction chooses, declaration order breaks ties
        assert sorted(a.state_names) == sorted(b.state_names)
    assert_same_run(a, b, T_END)


@pytest.mark.parametrize("seed,pulses", [(s, False) for s in SEEDS] +
                         [(s, True) for s in PULSE_SEEDS])
def test_random_networks_follow_the_nodal_analysis(seed, pulses):
    """Every pin voltage and part current against the network solved by hand; with
    ``pulses``, across the five edges of a pulse train (events the solver locates)."""
    build = random_network(seed, pulses=pulses)
    res = mt.simulate(mt.compile_model(build()), T_END, rtol=1e-10, atol=1e-12, log="all",
                      t_out=np.linspace(0.0, T_END, 41))
    exact = nodal_solution(build.netlist(), build.source, res.t)
    assert len(exact) > 10
    for name, values in exact.items():
        scale = max(1.0, float(np.max(np.abs(values))))
        np.testing.assert_allclose(res[name], values, rtol=0, atol=1e-7 * scale,
                                   err_msg=name)


@pytest.mark.parametrize("solver", ["rosenbrock", "rk45", "rodas4"])
def test_an_edge_on_an_output_time_is_logged_after_the_edge(solver):
    """Seed 2's pulse train falls at t = 0.018000000000000002, one of the output times:
    its indicator is zero there, and the crossing is seen in the next interval. Every
    solver logs the network after the edge at that time, as the nodal analysis has it
    (CasADi's Rosenbrock plug-in logged the state before it: the source's voltage 100 %
    off)."""
    build = random_network(2, pulses=True)
    t_out = np.linspace(0.0, T_END, 41)
    edges = [t for t, _ in build.source[1:]]
    assert set(edges) & set(t_out.tolist())
    res = mt.simulate(mt.compile_model(build()), T_END, solver=solver, t_out=t_out,
                      log="all")
    exact = nodal_solution(build.netlist(), build.source, res.t)
    for name, values in exact.items():
        scale = max(1.0, float(np.max(np.abs(values))))
        np.testing.assert_allclose(res[name], values, rtol=0, atol=1e-5 * scale,
                                   err_msg=name)


#: seeds whose source is a constant one (its voltage a parameter, the input linearized)
DC_SEEDS = [s for s in range(16) if len(random_network(s).source) == 1]


@pytest.mark.parametrize("seed", DC_SEEDS)
def test_random_networks_linearize_to_the_nodal_system(seed):
    """The linearization from the source's voltage to every node's voltage: the same
    poles and the same steady-state gains as the network solved by hand (where there is
    a steady state: a node that capacitors alone join to the rest keeps its charge, a
    pole at 0)."""
    build = random_network(seed)         # a constant source: its voltage a parameter
    cm = mt.compile_model(build())
    F, g, MN, Mc, at, caps, inds = nodal_system(build.netlist())
    pins = {}                            # one logged pin voltage per node
    for path, _, _, a, b in build.netlist():
        pins.setdefault(a, f"{path}.p.v")
        pins.setdefault(b, f"{path}.n.v")
    nodes = [n for n in at if n in pins]
    sys = linearize(cm, inputs=["src.V"], outputs=[pins[n] for n in nodes])
    A, B, C, D = (np.asarray(x) for x in (sys.A, sys.B, sys.C, sys.D))
    assert A.shape == F.shape
    if F.size:
        poles = np.sort_complex(np.linalg.eigvals(F))
        np.testing.assert_allclose(np.sort_complex(np.linalg.eigvals(A)), poles,
                                   rtol=1e-8, atol=1e-8 * np.max(np.abs(poles)))
        if np.min(np.abs(poles)) <= 1e-9 * np.max(np.abs(poles)):
            return                       # a charge kept: no steady state to compare
        steady = MN @ np.linalg.solve(F, -g) + Mc
        gain = (C @ np.linalg.solve(A, -B) + D).ravel()
    else:                                # no states: the resistive network's gains
        steady, gain = Mc, D.ravel()
    np.testing.assert_allclose(gain, [steady[at[n]] for n in nodes], rtol=1e-9, atol=1e-12)
