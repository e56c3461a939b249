"""State selection does not depend on rounding or numbering.

`dummy_derivatives` with a numeric picker (`pivot_columns` on the Jacobian of the rows
with respect to the candidates, as the compiler does) on small systems whose Jacobian
has exact ties. The same states and dummies must come out when the Jacobian is moved by
a few ulps (another BLAS kernel), scaled, or when equations and variables are numbered
differently (with the declaration rank carried along).
"""

from dataclasses import dataclass

import numpy as np
import pytest

from mechatron.compiler.graph import dummy_derivatives, pantelides, state_selection
from mechatron.compiler.pivoting import pivot_columns


@dataclass
class Numeric:
    """A DAE with the partial derivatives of its equations at one point.

    ``values[(e, v)]`` is d(equation e)/d(variable v). The derivative of an equation
    with respect to ``der(v)`` equals that of the equation with respect to ``v``, so
    these values give every entry of the state-selection Jacobian. ``priority`` is as
    in `dummy_derivatives` (lower: rather a state); the picker scales a column by
    ``10**(3*priority)``, like the compiler."""

    names: list[str]
    adj: list[list[int]]
    var_to_diff: list[int]
    values: dict[tuple[int, int], float]
    priority: list[float]

    @property
    def n_var(self):
        return len(self.names)


def numeric(names, var_to_diff, equations, priority=None):
    """Build from ``equations``: one dict ``{name: partial derivative}`` per equation."""
    index = {n: i for i, n in enumerate(names)}
    adj = [[index[n] for n in eq] for eq in equations]
    values = {(e, index[n]): float(d) for e, eq in enumerate(equations) for n, d in eq.items()}
    prio = [0.0] * len(names)
    for n, p in (priority or {}).items():
        prio[index[n]] = p
    return Numeric(list(names), adj, [index[d] if d else -1 for d in var_to_diff],
                   values, prio)


def select_states(sys: Numeric, *, rank=None, transform=None):
    """Pantelides, then dummy derivatives with the numeric picker. Returns the names of
    the states and of the dummy derivatives (``der(...)`` for created variables)."""
    ir = pantelides(sys.n_var, sys.adj, sys.var_to_diff)
    diff_to_var, diff_to_eq = ir.diff_to_var, ir.diff_to_eq

    def name(v):
        return sys.names[v] if v < sys.n_var else f"der({name(diff_to_var[v])})"

    def root_priority(v):
        while diff_to_var[v] != -1:
            v = diff_to_var[v]
        return sys.priority[v]

    def value(e, v):
        while diff_to_eq[e] != -1 and diff_to_var[v] != -1:
            e, v = diff_to_eq[e], diff_to_var[v]
        return sys.values.get((e, v), 0.0)

    def select(eqs, candidates, k):
        a = np.array([[value(e, v) for v in candidates] for e in eqs])
        if transform is not None:
            a = transform(a)
        scale = np.array([10.0 ** (3.0 * root_priority(v)) for v in candidates])
        return [candidates[j] for j in pivot_columns(a * scale, k)]

    dummies = dummy_derivatives(ir, select=select, priority=sys.priority, rank=rank)
    states = state_selection(ir, dummies)
    return sorted(name(v) for v in states), sorted(name(v) for v in dummies)


def renumbered(sys: Numeric, rng):
    """The same system with equations, variables and each equation's incidence in a
    random order; returns it and the declaration rank of each new variable."""
    pv = rng.permutation(sys.n_var)          # old variable v -> new index pv[v]
    pe = rng.permutation(len(sys.adj))
    names = [""] * sys.n_var
    prio = [0.0] * sys.n_var
    rank = [0] * sys.n_var
    v2d = [-1] * sys.n_var
    for v in range(sys.n_var):
        names[pv[v]] = sys.names[v]
        prio[pv[v]] = sys.priority[v]
        rank[pv[v]] = v
        v2d[pv[v]] = pv[sys.var_to_diff[v]] if sys.var_to_diff[v] != -1 else -1
    adj = [None] * len(sys.adj)
    for e, row in enumerate(sys.adj):
        adj[pe[e]] = [int(pv[v]) for v in rng.permutation(row)]
    values = {(int(pe[e]), int(pv[v])): d for (e, v), d in sys.values.items()}
    return Numeric(names, adj, v2d, values, prio), rank


def pendulum(x, y, m=1.0):
    """Cartesian pendulum at (x, y): der(x) = vx, der(y) = vy, m der(vx) = -lam x,
    m der(vy) = -lam y - m g, x^2 + y^2 = L^2 (lam = 1 at the point)."""
    return numeric(
        ["x", "y", "vx", "vy", "lam", "dx", "dy", "dvx", "dvy"],
        ["dx", "dy", "dvx", "dvy", None, None, None, None, None],
        [{"dx": 1, "vx": -1}, {"dy": 1, "vy": -1},
         {"dvx": m, "lam": x, "x": 1.0}, {"dvy": m, "lam": y, "y": 1.0},
         {"x": 2 * x, "y": 2 * y}])


def inertia_chain(n, ratio=1.0):
    """``n`` equal inertias, each coupled to the next by a gear ``w_k = ratio w_{k+1}``."""
    names = ([f"w{k}" for k in range(n)] + [f"tau{k}" for k in range(n - 1)]
             + [f"dw{k}" for k in range(n)])
    eqs = []
    for k in range(n):
        eq = {f"dw{k}": 0.5}
        if k:
            eq[f"tau{k - 1}"] = ratio
        if k < n - 1:
            eq[f"tau{k}"] = -1.0
        eqs.append(eq)
    eqs += [{f"w{k}": 1.0, f"w{k + 1}": -ratio} for k in range(n - 1)]
    return numeric(names, [f"dw{k}" for k in range(n)] + [None] * (2 * n - 1), eqs)


def joint_and_body(priority=True):
    """A revolute joint (angle q, rate w, preferred states) that turns a body whose
    frame has its own angle phi and rate wb: der(q) = w, J der(w) = tau_j,
    der(phi) = wb, Jb der(wb) = tau_b, phi = q, tau_j + tau_b = 0. In miniature, the
    double pendulum that chose der(q) instead of w as a state on some BLAS kernels:
    after the body's columns are taken, der(der(q)) and der(w) tie exactly."""
    return numeric(
        ["q", "w", "tau_j", "phi", "wb", "tau_b", "dq", "dw", "dphi", "dwb"],
        ["dq", "dw", None, "dphi", "dwb", None, None, None, None, None],
        [{"dq": 1, "w": -1}, {"dw": 0.1, "tau_j": -1}, {"dphi": 1, "wb": -1},
         {"dwb": 0.1, "tau_b": -1}, {"phi": 1, "q": -1}, {"tau_j": 1, "tau_b": 1}],
        priority={"q": -1.5, "w": -1.5} if priority else None)


S45 = np.sqrt(0.5)
CASES = {
    # (system, states the rule gives)
    "pendulum at 45 degrees": (pendulum(S45, -S45), ["vx", "x"]),
    "pendulum near the bottom": (pendulum(0.6, -0.8), ["vx", "x"]),
    "pendulum near the side": (pendulum(0.8, -0.6), ["vy", "y"]),
    "rigid inertias 1:1": (inertia_chain(2), ["w0"]),
    "chain of six rigid inertias 1:1": (inertia_chain(6), ["w0"]),
    "gear 3:1": (inertia_chain(2, ratio=3.0), ["w0"]),
    "joint turning a body": (joint_and_body(), ["q", "w"]),
}


@pytest.mark.parametrize("case", CASES)
def test_the_rule_and_the_numbers_give_these_states(case):
    sys, expected = CASES[case]
    states, _ = select_states(sys)
    assert states == expected


def test_the_joint_keeps_its_rate_not_the_derivative_of_its_angle():
    # the tie between der(der(q)) (created by index reduction) and der(w): the created
    # one becomes the dummy, so w is the state, not der(q)
    states, dummies = select_states(joint_and_body())
    assert "der(dq)" in dummies and "dw" not in dummies
    assert "dq" not in states


@pytest.mark.parametrize("case", CASES)
@pytest.mark.parametrize("seed", range(4))
def test_selection_survives_rounding_and_scaling(case, seed):
    sys, _ = CASES[case]
    expected = select_states(sys)
    rng = np.random.default_rng(seed)

    def ulps(a):
        return a + rng.integers(-4, 5, size=a.shape) * np.spacing(np.abs(a))

    assert select_states(sys, transform=ulps) == expected
    factor = 10.0 ** rng.uniform(-6, 6)
    assert select_states(sys, transform=lambda a: a * factor) == expected
    assert select_states(sys, transform=lambda a: a[rng.permutation(a.shape[0])]) \
        == expected


@pytest.mark.parametrize("case", CASES)
@pytest.mark.parametrize("seed", range(6))
def test_selection_does_not_depend_on_the_numbering(case, seed):
    sys, _ = CASES[case]
    expected = select_states(sys)
    other, rank = renumbered(sys, np.random.default_rng(seed))
    assert select_states(other, rank=rank) == expected


def test_declaration_rank_decides_an_exact_tie():
    # two equal inertias on a 1:1 gear: only the declaration order can choose; the one
    # declared first stays a state, whatever its index
    sys = inertia_chain(2)
    assert select_states(sys)[0] == ["w0"]
    rank = list(range(sys.n_var))
    rank[0], rank[1] = rank[1], rank[0]     # w1 declared before w0
    assert select_states(sys, rank=rank)[0] == ["w1"]


def test_rank_must_cover_the_original_variables():
    sys = inertia_chain(2)
    ir = pantelides(sys.n_var, sys.adj, sys.var_to_diff)
    with pytest.raises(ValueError, match="rank must give every original variable"):
        dummy_derivatives(ir, rank=[0, 1])
