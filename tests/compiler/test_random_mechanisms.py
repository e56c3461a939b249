"""Random translational mechanisms built from random subsystem classes: masses, springs,
dampers and springs in series with dampers between flanges, several masses often on one
node (joined rigidly: alias elimination leaves one velocity of them). Each is
compiled with its subsystems folded and written out and drawn in two orders, and every
velocity, spring deflection and force follows the mechanism solved by hand: the node
balances with the masses' velocities and the springs' deflections as states, the
velocities of massless nodes solved from their dampers, the linear ODE integrated by the
matrix exponential.

A mechanism has a reference, a force (constant, or a step) on its first node through
an ideal force source, a mass and a damper to the reference on every node of its own,
and instances of two or three classes, each with two or three flanges, a mass on each
node of its own, and parts between its nodes. Every massless node (the middle of a
spring in series with a damper) meets a damper, so its velocity is determined."""

from __future__ import annotations

import random

import numpy as np
import pytest
from scipy.linalg import expm

import mechatron as mt
from mechatron.library import blocks
from mechatron.library import translational as tr
from tests.compiler.test_folding import assert_same, unfolded

SEEDS = range(10)
T_END = 0.5

_M = (0.5, 1.0, 2.0)
_K = (50.0, 100.0, 400.0)
_B = (1.0, 5.0, 20.0)


def random_class(rng, name: str) -> type:
    """A subsystem class of flanges ``f0``.. and parts between its nodes; ``kb``, its
    spring rate, passed on to some springs."""
    ns = {"kb": mt.Parameter("N/m", default=rng.choice(_K), min=0, doc="Spring rate")}
    flanges = [f"f{k}" for k in range(rng.choice((2, 3)))]
    for f in flanges:
        ns[f] = tr.Flange(doc=f"Flange {f}")
    wires: dict[str, list] = {f: [(f,)] for f in flanges}
    specs: dict[str, tuple] = {}
    count = 0

    def part(kind, nodes):
        nonlocal count
        name_ = f"b{count}{kind.lower()}"
        count += 1
        if kind == "M":
            value = rng.choice(_M)
            ns[name_] = tr.Mass(m=value)
            wires[nodes[0]].append((name_, "port"))
        else:
            if kind == "K":
                passed = rng.random() < 0.5
                value = ("kb", 1.0) if passed else ("lit", rng.choice(_K))
                ns[name_] = tr.TranslationalSpring(k=ns["kb"] if passed else value[1])
            else:
                value = ("lit", rng.choice(_B))
                ns[name_] = tr.TranslationalDamper(b=value[1])
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
    order = list(wires.values())
    rng.shuffle(order)
    plan = [members[::-1] if rng.random() < 0.5 else members for members in order]

    def equations(self):
        def port(path):
            obj = self
            for step in path:
                obj = getattr(obj, step)
            return obj
        return [mt.connect(*map(port, members)) for members in plan if len(members) > 1]

    ns["equations"] = equations
    cls = type(name, (mt.Component,), ns)
    cls.flange_names, cls.wires, cls.specs = tuple(flanges), wires, specs
    return cls


def random_mechanism(seed: int, order: int = 0):
    """The mechanism of ``seed`` and a builder of it (see `random_network` of
    test_random_networks for ``order``), with ``parts()``: every mass, spring and damper
    as ``(path, kind, value, node A, node B)`` (B None for a mass), from what the
    generator wrote down; and ``force``: the force before and after T_END / 4."""
    rng = random.Random(seed)
    classes = [random_class(rng, f"Mech{seed}_{k}") for k in range(rng.choice((2, 3)))]
    nodes = [f"m{k}" for k in range(rng.choice((2, 3, 4)))]
    newton = rng.choice((1.0, 5.0, 20.0))
    parts = [("ref", tr.TranslationalReference, [("g", "port")]),
             ("push", tr.IdealForceSource, [("m0", "A"), ("g", "B")])]
    top = []
    if rng.random() < 0.4:
        parts.append(("cmd", lambda: blocks.Step(t_step=T_END / 4, initial=0.0,
                                                 final=newton), []))
        force = (0.0, newton)
    else:
        parts.append(("cmd", lambda: blocks.Constant(value=newton), []))
        force = (newton, newton)
    for node in nodes:
        m, b = rng.choice(_M), rng.choice(_B)
        parts.append((f"mass_{node}", lambda m=m: tr.Mass(m=m), [(node, "port")]))
        parts.append((f"drag_{node}", lambda b=b: tr.TranslationalDamper(b=b),
                      [(node, "A"), ("g", "B")]))
        top += [(f"mass_{node}", "M", m, node, None), (f"drag_{node}", "D", b, node, "g")]
    instances = []
    for k in range(rng.choice((2, 3, 4))):
        cls = rng.choice(classes)
        given = {"kb": rng.choice(_K)} if rng.random() < 0.3 else {}
        attached = [(rng.choice(nodes + ["g"]), f) for f in cls.flange_names]
        parts.append((f"u{k}", lambda cls=cls, given=given: cls(**given), attached))
        instances.append((f"u{k}", cls, given.get("kb"), {f: n for n, f in attached}))
    shuffle = random.Random(1000 * seed + order)
    if order:
        shuffle.shuffle(parts)

    def build() -> mt.System:
        m = mt.System(f"mech{seed}")
        wires: dict[str, list] = {}
        for name, make, attached in parts:
            part = m.add(name, make())
            for node, pin in attached:
                wires.setdefault(node, []).append(getattr(part, pin))
        connects = []
        for members in wires.values():
            members = list(members)
            if order:
                shuffle.shuffle(members)
            connects.append(tuple(members))
        connects.append((m.cmd.y, m.push.f_in))
        if order:
            shuffle.shuffle(connects)
        for members in connects:
            m.connect(*members)
        return m

    state = shuffle.getstate()

    def fresh() -> mt.System:
        shuffle.setstate(state)
        return build()

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

    fresh.parts, fresh.force = all_parts, force
    return fresh


def solved_by_hand(parts: list, force: tuple, t: np.ndarray) -> dict[str, np.ndarray]:
    """The mechanism's velocities, deflections and forces at the times ``t``: states the
    velocities of the nodes with mass and the springs' deflections, the velocities of
    the massless nodes solved from their balances (linear in the states), the force of
    the source on node ``m0``."""
    nodes = sorted({n for *_, a, b in parts for n in (a, b) if n not in (None, "g")})
    mass = {n: 0.0 for n in nodes}
    for _, kind, value, a, _ in parts:
        if kind == "M" and a != "g":
            mass[a] += value
    heavy = [n for n in nodes if mass[n] > 0]
    light = [n for n in nodes if mass[n] == 0]
    springs = [q for q in parts if q[1] == "K"]
    dampers = [q for q in parts if q[1] == "D"]
    nh, nl, ns = len(heavy), len(light), len(springs)
    col = {n: k for k, n in enumerate(heavy + light)}    # velocities: heavy, then light
    # the force into each node, as a matrix over [velocities, deflections, force]
    nv = nh + nl
    F = np.zeros((nv, nv + ns + 1))
    for _, _, b, a, bb in dampers:          # b (v_a - v_b) leaves a, enters bb
        for node, sign in ((a, -1.0), (bb, 1.0)):
            if node == "g":
                continue
            for other, s2 in ((a, 1.0), (bb, -1.0)):
                if other != "g":
                    F[col[node], col[other]] += sign * s2 * b
    for j, (_, _, k, a, bb) in enumerate(springs):
        for node, sign in ((a, -1.0), (bb, 1.0)):
            if node != "g":
                F[col[node], nv + j] += sign * k
    F[col["m0"], nv + ns] += 1.0            # the source pushes node m0
    # light velocities from their balances: 0 = F_l [v_h, v_l, x, f]
    A_ll = F[nh:, nh:nv]
    rest = np.delete(F[nh:], np.s_[nh:nv], axis=1)       # over [v_h, x, f]
    light_of = -np.linalg.solve(A_ll, rest) if nl else np.zeros((0, nh + ns + 1))
    # every velocity over [v_h, x, f]
    V = np.vstack([np.eye(nh, nh + ns + 1), light_of])
    # state derivatives: M v_h' = F_h V..., x_j' = v_a - v_b
    full = np.zeros((nv + ns + 1, nh + ns + 1))     # [v, x, f] over [v_h, x, f]
    full[:nv] = V
    full[nv:nv + ns, nh:nh + ns] = np.eye(ns)
    full[nv + ns, nh + ns] = 1.0
    deriv = np.zeros((nh + ns, nh + ns + 1))
    deriv[:nh] = (F[:nh] @ full) / np.array([mass[n] for n in heavy])[:, None]
    for j, (_, _, _, a, bb) in enumerate(springs):
        for node, sign in ((a, 1.0), (bb, -1.0)):
            if node != "g":
                deriv[nh + j] += sign * V[col[node]]
    n_s = nh + ns
    out_states = np.zeros((t.size, n_s))
    t_step = T_END / 4
    for k, tk in enumerate(t):
        s = _exact(deriv, force[0], np.zeros(n_s), min(tk, t_step))
        if tk > t_step:
            s = _exact(deriv, force[1], s, tk - t_step)
        out_states[k] = s
    f = np.where(t >= t_step, force[1], force[0])
    z = np.hstack([out_states, f[:, None]])             # [v_h, x, f] at each time
    v = z @ V.T
    vel = {n: v[:, col[n]] for n in nodes}
    vel["g"] = np.zeros(t.size)
    out = {}
    for path, kind, value, a, b in parts:
        if kind == "M":
            out[f"{path}.v"] = vel[a]
        elif kind == "D":
            out[f"{path}.f"] = value * (vel[a] - vel[b])
    for j, (path, _, k, a, b) in enumerate(springs):
        out[f"{path}.x"] = z[:, nh + j]
        out[f"{path}.f"] = k * z[:, nh + j]
        out[f"{path}.A.v"] = vel[a]
    return out


def _exact(D: np.ndarray, f: float, s0: np.ndarray, dt: float) -> np.ndarray:
    """``s(dt)`` of ``s' = D[:, :-1] s + D[:, -1] f`` from ``s0``."""
    m = D.shape[0]
    A = np.zeros((m + 1, m + 1))
    A[:m, :m], A[:m, m] = D[:, :-1] * dt, D[:, -1] * f * dt
    return (expm(A) @ np.append(s0, 1.0))[:m]


@pytest.mark.parametrize("seed", SEEDS)
def test_random_mechanisms_follow_the_balances_solved_by_hand(seed):
    build = random_mechanism(seed)
    res = mt.simulate(mt.compile_model(build()), T_END, rtol=1e-10, atol=1e-12,
                      t_out=np.linspace(0.0, T_END, 51), log="all")
    exact = solved_by_hand(build.parts(), build.force, res.t)
    for name, values in exact.items():
        scale = max(1.0, float(np.max(np.abs(values))))
        np.testing.assert_allclose(res[name], values, rtol=0, atol=1e-7 * scale,
                                   err_msg=name)


@pytest.mark.parametrize("seed", SEEDS)
def test_random_mechanisms_folded_match_written_out_and_any_order(seed, monkeypatch):
    build = random_mechanism(seed)
    folded = mt.compile_model(build())
    assert_same(folded, unfolded(monkeypatch, build), T_END, tol=1e-8)
    other = mt.compile_model(random_mechanism(seed, order=1)())
    assert sorted(other.names) == sorted(folded.names)
    a = mt.simulate(folded, T_END, rtol=1e-10, atol=1e-12, log="all")
    b = mt.simulate(other, T_END, rtol=1e-10, atol=1e-12, t_out=a.t, log="all")
    for name in folded.names:
        scale = max(1.0, float(np.max(np.abs(a[name]))))
        np.testing.assert_allclose(b[name], a[name], rtol=0, atol=1e-8 * scale,
                                   err_msg=name)
