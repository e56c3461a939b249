"""Random block diagrams (Simulink-style signal blocks): gains, weighted sums,
integrators and first-order lags, each input wired to any output, a block's own among
them, so that feedback loops form, many without a state in them (algebraic loops, which
the compiler solves), and in some a zero-order hold sampling a state and driving other
blocks (clocked events). Each diagram's every output follows the diagram solved by hand
(the loops' outputs a linear function of the states, the source and the held sample,
the states' linear ODE integrated by the matrix exponential between the samples), also
drawn in another order.

Gains are at most 0.9 and sum weights at most 0.45 in size, so every algebraic loop
(``y = G y + ...``) has ``I - G`` diagonally dominant: one solution, found by any
elimination order."""

from __future__ import annotations

import random

import numpy as np
import pytest

import mechatron as mt
from mechatron.library import blocks
from tests.compiler.random_models import exact

SEEDS = range(12)
T_END = 2.0
KINDS = ("gain", "add", "int", "lag")


#: the sample time of the zero-order hold of ``random_diagram(sampled=True)``
TS = 0.15


def random_diagram(seed: int, order: int = 0, sampled: bool = False):
    """The diagram of ``seed`` and a builder of it; ``order`` shuffles the order its blocks
    are added and its connections written. ``spec``: each block ``(name, kind, params,
    inputs)``, an input the name of the block whose output drives it (``src``: the
    source); ``source``: the source's value before and after T_END / 4. With
    ``sampled``, a zero-order hold (sample time `TS`) samples a state (the output of an
    integrator or a lag, so that a sample never waits on its own effect) and drives one
    or two inputs in place of what drove them."""
    rng = random.Random(seed)
    n = rng.randint(3, 9)
    names = [f"b{k}" for k in range(n)]
    spec = []
    for name in names:
        kind = rng.choice(KINDS)
        if kind == "gain":
            params = {"k": rng.choice((-0.9, -0.5, 0.3, 0.8))}
        elif kind == "add":
            params = {"k1": rng.choice((-0.45, 0.2, 0.45)), "k2": rng.choice((-0.3, 0.4))}
        elif kind == "int":
            params = {"k": rng.choice((-1.0, 0.5, 1.0))}
        else:
            params = {"k": rng.choice((0.5, 1.0, 2.0)), "T": rng.choice((0.2, 0.5, 1.0))}
        inputs = [rng.choice(["src"] + names) for _ in range(2 if kind == "add" else 1)]
        spec.append((name, kind, params, inputs))
    high = rng.choice((1.0, 3.0))
    stepped = rng.random() < 0.5
    states = [q[0] for q in spec if q[1] in ("int", "lag")]
    if sampled and states:              # drawn apart: the diagram stays the seed's
        more = random.Random(seed + 10**6)
        spec.append(("zoh", "zoh", {"Ts": TS}, [more.choice(states)]))
        for _ in range(more.choice((1, 2))):
            name, kind, params, inputs = more.choice(spec[:-1])
            inputs[more.randrange(len(inputs))] = "zoh"
    source = (0.5, high) if stepped else (high, high)
    shuffle = random.Random(1000 * seed + order)
    make = {"gain": blocks.Gain, "add": blocks.Add, "int": blocks.Integrator,
            "lag": blocks.FirstOrder, "zoh": blocks.ZeroOrderHold}
    ports = {"gain": ("u",), "add": ("u1", "u2"), "int": ("u",), "lag": ("u",),
             "zoh": ("u",)}

    def build() -> mt.System:
        m = mt.System(f"diagram{seed}")
        made = list(spec)
        if order:
            shuffle.shuffle(made)
        if stepped:
            src = m.add("src", blocks.Step(t_step=T_END / 4, initial=source[0],
                                           final=source[1]))
        else:
            src = m.add("src", blocks.Constant(value=high))
        got = {"src": src}
        for name, kind, params, _ in made:
            got[name] = m.add(name, make[kind](**params))
        wires = [(got[driver].y, getattr(got[name], port))
                 for name, kind, _, inputs in spec
                 for port, driver in zip(ports[kind], inputs)]
        if order:
            shuffle.shuffle(wires)
        for a, b in wires:
            m.connect(*((b, a) if order and shuffle.random() < 0.5 else (a, b)))
        return m

    state = shuffle.getstate()

    def fresh() -> mt.System:
        shuffle.setstate(state)
        return build()

    fresh.spec, fresh.source = spec, source
    return fresh


def solved_by_hand(spec: list, source: tuple, t: np.ndarray) -> dict[str, np.ndarray]:
    """Every block's output at the times ``t``: the outputs of gains and sums solved from
    their loops in terms of the states (the outputs of integrators and lags, starting at
    0), the source and the held sample, the states' linear ODE integrated exactly
    between the instants where the source steps or the hold samples its state."""
    states = [q for q in spec if q[1] in ("int", "lag")]
    algebraic = [q for q in spec if q[1] in ("gain", "add")]
    hold = [q for q in spec if q[1] == "zoh"]
    ns, na = len(states), len(algebraic)
    col = {q[0]: k for k, q in enumerate(states)}
    col.update({q[0]: ns + k for k, q in enumerate(algebraic)})
    col["src"], col["zoh"] = ns + na, ns + na + 1     # the inputs: source, held sample
    width = ns + 2                                    # [y_s, r, z]

    def weights(q) -> list[tuple[str, float]]:
        name, kind, params, inputs = q
        if kind == "add":
            return [(inputs[0], params["k1"]), (inputs[1], params["k2"])]
        return [(inputs[0], params["k"])]

    # y_alg = A [y_s, y_alg, r, z]: solved as y_alg = S [y_s, r, z]
    A = np.zeros((na, ns + na + 2))
    for j, q in enumerate(algebraic):
        for driver, w in weights(q):
            A[j, col[driver]] += w
    S = np.linalg.solve(np.eye(na) - A[:, ns:ns + na],
                        np.delete(A, np.s_[ns:ns + na], axis=1)) if na else \
        np.zeros((0, width))
    # every output over [y_s, r, z]
    Y = np.vstack([np.eye(ns, width), S, np.eye(2, width, ns)])
    D = np.zeros((ns, width))           # y_s' = D [y_s, r, z]
    for j, (name, kind, params, inputs) in enumerate(states):
        u = Y[col[inputs[0]]]
        if kind == "int":
            D[j] = params["k"] * u
        else:
            D[j] = (params["k"] * u - np.eye(1, width, j)[0]) / params["T"]
    t_step = T_END / 4
    ticks = list(np.arange(0.0, T_END, TS)) if hold else []
    edges = sorted({t_step, *ticks[1:]})
    sampled = col[hold[0][3][0]] if hold else None
    x, r, z, now = np.zeros(ns), source[0], 0.0, 0.0
    values = np.zeros((t.size, width))
    todo = list(enumerate(t))
    for edge in edges + [np.inf]:
        while todo and todo[0][1] < edge:
            k, tk = todo.pop(0)
            values[k] = np.concatenate([exact(D[:, :ns], D[:, ns:] @ (r, z), x, tk - now),
                                        [r, z]])
        if edge == np.inf:
            break
        x, now = exact(D[:, :ns], D[:, ns:] @ (r, z), x, edge - now), edge
        if edge == t_step:
            r = source[1]
        if hold and any(abs(edge - tick) < 1e-12 for tick in ticks):
            z = float((np.concatenate([x, [r, z]]) @ Y[sampled]))
    values = values @ Y.T
    return {f"{q[0]}.y": values[:, col[q[0]]] for q in spec}


@pytest.mark.parametrize("seed", SEEDS)
@pytest.mark.parametrize("order,sampled", [(0, False), (1, False), (0, True), (1, True)])
def test_random_block_diagrams_follow_the_diagram_solved_by_hand(seed, order, sampled):
    build = random_diagram(seed, order, sampled)
    # output times off the samples and the step (at an event instant, which value a log
    # holds is a convention, tested elsewhere)
    t_out = np.linspace(0.0, T_END, 41) + (0.013 if sampled else 0.0)
    res = mt.simulate(mt.compile_model(build()), T_END + 0.02, rtol=1e-10, atol=1e-12,
                      t_out=t_out, log="all")
    exact = solved_by_hand(build.spec, build.source, res.t)
    for name, values in exact.items():
        scale = max(1.0, float(np.max(np.abs(values))))
        np.testing.assert_allclose(res[name], values, rtol=0, atol=1e-7 * scale,
                                   err_msg=name)
