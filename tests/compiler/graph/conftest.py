"""Small DAEs shared by the graph tests, given as integer incidence.

Each fixture returns a `System`: ``names[v]`` names variable ``v``, ``adj[e]`` lists the
variables of equation ``e``, ``var_to_diff[v]`` is the index of ``der(v)`` or -1.
"""

from dataclasses import dataclass

import pytest


@dataclass
class System:
    names: list[str]
    adj: list[list[int]]
    var_to_diff: list[int]

    @property
    def n_var(self) -> int:
        return len(self.names)

    def index(self, name: str) -> int:
        return self.names.index(name)


@pytest.fixture
def pendulum() -> System:
    """Planar pendulum in Cartesian coordinates (index 3)."""
    names = ["x", "y", "vx", "vy", "lam", "dx", "dy", "dvx", "dvy"]
    adj = [
        [5, 2],     # 0: der(x) = vx
        [6, 3],     # 1: der(y) = vy
        [7, 4, 0],  # 2: m der(vx) = -lam x
        [8, 4, 1],  # 3: m der(vy) = -lam y - m g
        [0, 1],     # 4: x^2 + y^2 = L^2
    ]
    return System(names, adj, [5, 6, 7, 8, -1, -1, -1, -1, -1])


@pytest.fixture
def inertias() -> System:
    """Two inertias coupled rigidly through a 3:1 gear (index 2)."""
    names = ["w1", "w2", "tau", "dw1", "dw2"]
    adj = [
        [3, 2],  # 0: J1 der(w1) = tau_drive - tau
        [4, 2],  # 1: J2 der(w2) = 3 tau
        [0, 1],  # 2: w1 = 3 w2
    ]
    return System(names, adj, [3, 4, -1, -1, -1])


@pytest.fixture
def capacitor() -> System:
    """Capacitor directly across an ideal voltage source u(t) (index 2)."""
    names = ["v", "i", "dv"]
    adj = [
        [0],     # 0: v = u(t)
        [1, 2],  # 1: i = C der(v)
    ]
    return System(names, adj, [2, -1, -1])


@pytest.fixture
def rc() -> System:
    """Resistor and capacitor in series on a voltage source (an ODE, index 1)."""
    names = ["v", "i", "dv"]
    adj = [
        [1, 0],  # 0: R i = u(t) - v
        [1, 2],  # 1: i = C der(v)
    ]
    return System(names, adj, [2, -1, -1])


def make_inertia_chain(n: int) -> System:
    """``n`` inertias rigidly coupled in a row (index 2): equation k is
    ``J der(w_k) = tau_{k-1} - tau_k``; then ``w_k = w_{k+1}`` for each coupling.
    Variables: w (n), tau (n - 1), der(w) (n)."""
    w, tau = list(range(n)), list(range(n, 2 * n - 1))
    dw = list(range(2 * n - 1, 3 * n - 1))
    adj = [[dw[k]] + ([tau[k - 1]] if k else []) + ([tau[k]] if k < n - 1 else [])
           for k in range(n)]
    adj += [[w[k], w[k + 1]] for k in range(n - 1)]
    names = ([f"w{k}" for k in w] + [f"tau{k}" for k in range(n - 1)]
             + [f"der(w{k})" for k in range(n)])
    return System(names, adj, dw + [-1] * (2 * n - 1))


@pytest.fixture
def inertia_chain():
    """Factory: ``inertia_chain(n)`` builds :func:`make_inertia_chain`."""
    return make_inertia_chain
