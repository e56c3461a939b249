"""What the random models of the compiler's tests share (test_random_networks,
test_random_mechanisms, test_random_block_diagrams): the connections of a random
subsystem class, a model assembled from parts wired to named nodes in a shuffled
order, and the exact solution of a linear ODE over a stretch of constant input."""

from __future__ import annotations

import random

import numpy as np
from scipy.linalg import expm

import mechatron as mt


def wired_equations(rng: random.Random, wires: dict):
    """``equations()`` of a class whose nodes ``wires`` (node -> the ports on it, as
    attribute paths from the instance) are connected, the nodes written in a random
    order and each node's ports in random direction."""
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

    return equations


def assembled(name: str, parts: list, links: list, seed: int, order: int):
    """A builder of the model ``name`` of ``parts`` ``(name, make, [(node, port)])``,
    the ports on each node connected, and ``links`` ``((part, port), (part, port))``
    connected as well. With ``order``, the parts are added and the connections written
    in an order shuffled from ``seed`` and ``order`` (ports reversed, a node written as
    one connect or as a chain of two-port connects): the same model drawn otherwise.
    Each call of the builder makes the same model, drawn the same way."""
    shuffle = random.Random(1000 * seed + order)
    parts = list(parts)
    if order:
        shuffle.shuffle(parts)

    def build() -> mt.System:
        m = mt.System(name)
        wires: dict[str, list] = {}
        for part_name, make, attached in parts:
            part = m.add(part_name, make())
            for node, port in attached:
                wires.setdefault(node, []).append(getattr(part, port))
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
        connects += [tuple(getattr(getattr(m, a), b) for a, b in link) for link in links]
        if order:
            shuffle.shuffle(connects)
        for members in connects:
            m.connect(*members)
        return m

    state = shuffle.getstate()

    def fresh() -> mt.System:
        shuffle.setstate(state)
        return build()

    return fresh


def assert_same_run(a, b, t_end: float, tol: float = 1e-8) -> None:
    """The compiled models ``a`` and ``b`` (one model drawn two ways) log the same
    variables, simulated to rtol 1e-10, within ``tol`` of each signal's scale."""
    assert sorted(a.names) == sorted(b.names)
    ra = mt.simulate(a, t_end, rtol=1e-10, atol=1e-12, log="all")
    rb = mt.simulate(b, t_end, rtol=1e-10, atol=1e-12, t_out=ra.t, log="all")
    for name in a.names:
        scale = max(1.0, float(np.max(np.abs(ra[name]))))
        np.testing.assert_allclose(rb[name], ra[name], rtol=0, atol=tol * scale,
                                   err_msg=name)


def exact(F: np.ndarray, f: np.ndarray, x0: np.ndarray, dt: float) -> np.ndarray:
    """``x(dt)`` of ``x' = F x + f`` (``f`` constant) from ``x0``: the exponential of the
    augmented matrix."""
    m = F.shape[0]
    A = np.zeros((m + 1, m + 1))
    A[:m, :m], A[:m, m] = F * dt, np.asarray(f, dtype=float) * dt
    return (expm(A) @ np.append(x0, 1.0))[:m]
