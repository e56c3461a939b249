"""Random mechanisms built from random subsystem classes, translational and rotational:
masses (inertias), springs, dampers and springs in series with dampers between flanges,
several masses often on one node (joined rigidly: alias elimination leaves one speed of
them), and in the rotational domain ideal gears joining shafts (two inertias a gear
joins are one body: index reduction chooses which speed is the state). Each is compiled
with its subsystems folded and written out and drawn in two orders, and every speed,
deflection and force follows the mechanism solved by hand: the balances of the groups
of nodes gears join, weighted by their ratios, with the groups' speeds and the springs'
deflections as states, the speeds of massless nodes solved from their dampers, the
linear ODE integrated by the matrix exponential.

A mechanism has a reference, a force or torque (constant, or a step) on its first node
through an ideal source, a mass and a damper to the reference on every node of its own,
and instances of two or three classes, each with two or three flanges, a mass on each
node of its own, and parts between its nodes. Every massless node (the middle of a
spring in series with a damper) meets a damper, so its speed is determined."""

from __future__ import annotations

import random

import numpy as np
import pytest

import mechatron as mt
from mechatron.library import blocks
from mechatron.library import rotational as rot
from mechatron.library import translational as tr
from tests.compiler.random_models import assembled, assert_same_run, exact, wired_equations
from tests.compiler.test_folding import assert_same, unfolded

SEEDS = range(10)
T_END = 0.5

#: each domain's parts and the names of their variables: translational masses, springs and
#: dampers, or their rotational counterparts (with gears between the shafts)
DOMAINS = {
    "translational": dict(flange=tr.Flange, mass=lambda x: tr.Mass(m=x),
                          spring=tr.TranslationalSpring,
                          damper=lambda x: tr.TranslationalDamper(b=x),
                          reference=tr.TranslationalReference, source=tr.IdealForceSource,
                          command="f_in", speed="v", flow="f", deflection="x",
                          rate_unit="N/m"),
    "rotational": dict(flange=rot.Flange, mass=lambda x: rot.Inertia(J=x),
                       spring=rot.RotationalSpring,
                       damper=lambda x: rot.RotationalDamper(D=x),
                       reference=rot.RotationalReference, source=rot.IdealTorqueSource,
                       command="tau_in", speed="w", flow="tau", deflection="phi",
                       rate_unit="N*m/rad"),
}
_RATIOS = (0.5, 2.0, 3.0)

_M = (0.5, 1.0, 2.0)
_K = (50.0, 100.0, 400.0)
_B = (1.0, 5.0, 20.0)


def random_class(rng, name: str, domain: dict) -> type:
    """A subsystem class of flanges ``f0``.. and parts between its nodes; ``kb``, its
    spring rate, passed on to some springs."""
    ns = {"kb": mt.Parameter(domain["rate_unit"], default=rng.choice(_K), min=0,
                             doc="Spring rate")}
    flanges = [f"f{k}" for k in range(rng.choice((2, 3)))]
    for f in flanges:
        ns[f] = domain["flange"](doc=f"Flange {f}")
    wires: dict[str, list] = {f: [(f,)] for f in flanges}
    specs: dict[str, tuple] = {}
    count = 0

    def part(kind, nodes):
        nonlocal count
        name_ = f"b{count}{kind.lower()}"
        count += 1
        if kind == "M":
            value = rng.choice(_M)
            ns[name_] = domain["mass"](value)
            wires[nodes[0]].append((name_, "port"))
        else:
            if kind == "K":
                passed = rng.random() < 0.5
                value = ("kb", 1.0) if passed else ("lit", rng.choice(_K))
                ns[name_] = domain["spring"](k=ns["kb"] if passed else value[1])
            else:
                value = ("lit", rng.choice(_B))
                ns[name_] = domain["damper"](value[1])
            ends = [(name_, "A"), (name_, "B")]
            rng.shuffle(ends)
            wires[nodes[0]].append(ends[0])
            wires[nodes[1]].append(ends[1])
        specs[name_] = (kind, value)
        return name_

    def branch(a, b):
        kind = rng.choice(("K", "D", "KD", "KsD"))
        if kind == "KsD":               # a spring in series with a damper: a massless node
            mid = f"n{count}"
            wires[mid] = []
            part("K", (a, mid))
            part("D", (mid, b))
        else:
            for k in kind:
                part(k, (a, b))

    for k in range(1, len(flanges)):
        branch(flanges[rng.randrange(k)], flanges[k])
    for k in range(rng.choice((0, 1, 2))):      # nodes of its own, each with a mass
        node = f"x{k}"
        wires[node] = []
        part("M", (node,))
        branch(node, rng.choice([n for n in wires if n != node]))
    for f in flanges:
        if rng.random() < 0.5:
            part("M", (f,))
    ns["equations"] = wired_equations(rng, wires)
    cls = type(name, (mt.Component,), ns)
    cls.flange_names, cls.wires, cls.specs = tuple(flanges), wires, specs
    return cls


def random_mechanism(seed: int, order: int = 0, domain: str = "translational"):
    """The mechanism of ``seed`` and a builder of it (see `random_network` of
    test_random_networks for ``order``), with ``parts()``: every mass, spring, damper and
    gear as ``(path, kind, value, node A, node B)`` (B None for a mass), from what the
    generator wrote down; and ``force``: the force before and after T_END / 4. In the
    rotational domain, gears join some shafts to earlier ones (a forest: no loop of
    gears), each pair of inertias so joined one rigid body for the index reduction."""
    rng = random.Random(seed)
    kit = DOMAINS[domain]
    classes = [random_class(rng, f"Mech{seed}_{k}", kit) for k in range(rng.choice((2, 3)))]
    nodes = [f"m{k}" for k in range(rng.choice((2, 3, 4)))]
    newton = rng.choice((1.0, 5.0, 20.0))
    parts = [("ref", kit["reference"], [("g", "port")]),
             ("push", kit["source"], [("m0", "A"), ("g", "B")])]
    top = []
    if domain == "rotational":
        for k in range(1, len(nodes)):
            if rng.random() < 0.6:
                ratio, other = rng.choice(_RATIOS), rng.choice(nodes[:k])
                parts.append((f"gear_{k}", lambda r=ratio: rot.IdealGear(ratio=r),
                              [(nodes[k], "A"), (other, "B")]))
                top.append((f"gear_{k}", "G", ratio, nodes[k], other))
    if rng.random() < 0.4:
        parts.append(("cmd", lambda: blocks.Step(t_step=T_END / 4, initial=0.0,
                                                 final=newton), []))
        force = (0.0, newton)
    else:
        parts.append(("cmd", lambda: blocks.Constant(value=newton), []))
        force = (newton, newton)
    for node in nodes:
        m, b = rng.choice(_M), rng.choice(_B)
        parts.append((f"mass_{node}", lambda m=m: kit["mass"](m), [(node, "port")]))
        parts.append((f"drag_{node}", lambda b=b: kit["damper"](b),
                      [(node, "A"), ("g", "B")]))
        top += [(f"mass_{node}", "M", m, node, None), (f"drag_{node}", "D", b, node, "g")]
    instances = []
    for k in range(rng.choice((2, 3, 4))):
        cls = rng.choice(classes)
        given = {"kb": rng.choice(_K)} if rng.random() < 0.3 else {}
        attached = [(rng.choice(nodes + ["g"]), f) for f in cls.flange_names]
        parts.append((f"u{k}", lambda cls=cls, given=given: cls(**given), attached))
        instances.append((f"u{k}", cls, given.get("kb"), {f: n for n, f in attached}))
    fresh = assembled(f"mech{seed}", parts, [(("cmd", "y"), ("push", kit["command"]))],
                      seed, order)

    def all_parts() -> list[tuple]:
        out = list(top)

        def expand(cls, path, kb, outer):
            kb = cls._declarations["kb"].default if kb is None else kb
            node_of = {node: outer.get(node) or f"{path}.{node}" for node in cls.wires}
            ends = {}
            for node, members in cls.wires.items():
                for member in members:
                    if len(member) == 2:
                        ends[member] = node_of[node]
            for name, (kind, value) in cls.specs.items():
                x = value if kind == "M" else value[1] * (kb if value[0] == "kb" else 1.0)
                if kind == "M":
                    out.append((f"{path}.{name}", "M", x, ends[(name, "port")], None))
                else:
                    out.append((f"{path}.{name}", kind, x, ends[(name, "A")],
                                ends[(name, "B")]))

        for path, cls, kb, attached in instances:
            expand(cls, path, kb, attached)
        return out

    fresh.parts, fresh.force, fresh.kit = all_parts, force, kit
    return fresh


def solved_by_hand(parts: list, force: tuple, t: np.ndarray,
                   kit: dict = DOMAINS["translational"]) -> dict[str, np.ndarray]:
    """The mechanism's speeds, deflections and forces at the times ``t`` (named as
    ``kit``'s variables): each group of nodes that gears join moves as one, at a speed of
    its own times each node's ratio to it; the states are the speeds of the groups with
    mass (their mass the nodes' reflected through the ratios) and the springs'
    deflections, the speeds of the massless nodes solved from their balances (linear in
    the states); the source pushes node ``m0``. A gear's own torque does no work on its
    group, so the balances of a group's nodes add, each weighted by its ratio."""
    nodes = sorted({n for *_, a, b in parts for n in (a, b) if n not in (None, "g")})
    # groups and ratios: a gear's A turns at `ratio` times its B
    links: dict[str, list] = {n: [] for n in nodes}
    for _, kind, ratio, a, b in parts:
        if kind == "G":
            links[a].append((b, 1.0 / ratio))
            links[b].append((a, ratio))
    group, rho = {}, {}
    for n in nodes:
        if n in group:
            continue
        group[n], rho[n], todo = n, 1.0, [n]
        while todo:
            here = todo.pop()
            for other, factor in links[here]:
                if other not in group:
                    group[other], rho[other] = n, rho[here] * factor
                    todo.append(other)
    mass = dict.fromkeys(nodes, 0.0)
    for _, kind, value, a, _ in parts:
        if kind == "M" and a != "g":        # a mass on the reference stays at rest
            mass[a] += value
    roots = sorted(set(group.values()))
    inertia = {r: sum(mass[n] * rho[n] ** 2 for n in nodes if group[n] == r) for r in roots}
    heavy = [r for r in roots if inertia[r] > 0]
    light = [r for r in roots if inertia[r] == 0]       # massless single nodes
    springs = [q for q in parts if q[1] == "K"]
    dampers = [q for q in parts if q[1] == "D"]
    nh, nl, ns, nn = len(heavy), len(light), len(springs), len(nodes)
    at = {n: k for k, n in enumerate(nodes)}
    # each node's speed over the group speeds z = [heavy, light]
    zcol = {r: k for k, r in enumerate(heavy + light)}
    T = np.zeros((nn, nh + nl))
    for n in nodes:
        T[at[n], zcol[group[n]]] = rho[n]
    # the force into each node over [node speeds, deflections, force]
    F = np.zeros((nn, nn + ns + 1))
    for _, _, b, a, bb in dampers:          # b (v_a - v_b) leaves a, enters bb
        for node, sign in ((a, -1.0), (bb, 1.0)):
            if node == "g":
                continue
            for other, s2 in ((a, 1.0), (bb, -1.0)):
                if other != "g":
                    F[at[node], at[other]] += sign * s2 * b
    for j, (_, _, k, a, bb) in enumerate(springs):
        for node, sign in ((a, -1.0), (bb, 1.0)):
            if node != "g":
                F[at[node], nn + j] += sign * k
    F[at["m0"], nn + ns] += 1.0             # the source pushes node m0
    # over [z, deflections, force], each group's balance (its nodes' weighted by ratio)
    lift = np.zeros((nn + ns + 1, nh + nl + ns + 1))
    lift[:nn, :nh + nl] = T
    lift[nn:, nh + nl:] = np.eye(ns + 1)
    G = (T.T @ F) @ lift                    # rows: heavy groups, then light nodes
    # light speeds from their balances: 0 = G_l [z_h, z_l, x, f]
    rest = np.delete(G[nh:], np.s_[nh:nh + nl], axis=1)    # over [z_h, x, f]
    light_of = -np.linalg.solve(G[nh:, nh:nh + nl], rest) if nl else \
        np.zeros((0, nh + ns + 1))
    Z = np.vstack([np.eye(nh, nh + ns + 1), light_of])      # z over [z_h, x, f]
    full = np.zeros((nh + nl + ns + 1, nh + ns + 1))        # [z, x, f] over [z_h, x, f]
    full[:nh + nl] = Z
    full[nh + nl:, nh:] = np.eye(ns + 1)
    deriv = np.zeros((nh + ns, nh + ns + 1))
    deriv[:nh] = (G[:nh] @ full) / np.array([inertia[r] for r in heavy])[:, None]
    V = T @ Z                               # node speeds over [z_h, x, f]
    for j, (_, _, _, a, bb) in enumerate(springs):
        for node, sign in ((a, 1.0), (bb, -1.0)):
            if node != "g":
                deriv[nh + j] += sign * V[at[node]]
    n_s = nh + ns
    states = np.zeros((t.size, n_s))
    t_step = T_END / 4
    for k, tk in enumerate(t):
        x = exact(deriv[:, :-1], deriv[:, -1] * force[0], np.zeros(n_s), min(tk, t_step))
        if tk > t_step:
            x = exact(deriv[:, :-1], deriv[:, -1] * force[1], x, tk - t_step)
        states[k] = x
    f = np.where(t >= t_step, force[1], force[0])
    zf = np.hstack([states, f[:, None]])    # [z_h, x, f] at each time
    v = zf @ V.T
    speed = {n: v[:, at[n]] for n in nodes}
    speed["g"] = np.zeros(t.size)
    w, fl, dx = kit["speed"], kit["flow"], kit["deflection"]
    out = {}
    for path, kind, value, a, b in parts:
        if kind == "M":
            out[f"{path}.{w}"] = speed[a]
        elif kind == "D":
            out[f"{path}.{fl}"] = value * (speed[a] - speed[b])
        elif kind == "G":
            out[f"{path}.A.{w}"], out[f"{path}.B.{w}"] = speed[a], speed[b]
    for j, (path, _, k, a, b) in enumerate(springs):
        out[f"{path}.{dx}"] = zf[:, nh + j]
        out[f"{path}.{fl}"] = k * zf[:, nh + j]
        out[f"{path}.A.{w}"] = speed[a]
    return out


CASES = [(s, "translational") for s in SEEDS] + [(s, "rotational") for s in SEEDS]


@pytest.mark.parametrize("seed,domain", CASES)
def test_random_mechanisms_follow_the_balances_solved_by_hand(seed, domain):
    build = random_mechanism(seed, domain=domain)
    res = mt.simulate(mt.compile_model(build()), T_END, rtol=1e-10, atol=1e-12,
                      t_out=np.linspace(0.0, T_END, 51), log="all")
    exact = solved_by_hand(build.parts(), build.force, res.t, build.kit)
    for name, values in exact.items():
        scale = max(1.0, float(np.max(np.abs(values))))
        np.testing.assert_allclose(res[name], values, rtol=0, atol=1e-7 * scale,
                                   err_msg=name)


@pytest.mark.parametrize("seed,domain", CASES)
def test_random_mechanisms_folded_match_written_out_and_any_order(seed, domain,
                                                                  monkeypatch):
    build = random_mechanism(seed, domain=domain)
    folded = mt.compile_model(build())
    assert_same(folded, unfolded(monkeypatch, build), T_END, tol=1e-8)
    other = mt.compile_model(random_mechanism(seed, order=1, domain=domain)())
    assert_same_run(folded, other, T_END)
