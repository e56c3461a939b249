"""Tearing of an algebraic loop.

A block of the BLT form (see `mechatron.compiler.graph.blt`) is a set of equations
solved simultaneously for as many variables. Tearing picks a few *tearing variables*
and orders most equations into a *sequence*, each solved explicitly for one variable
from the tearing variables, earlier sequence variables and variables outside the block
(knowns); the remaining *residual* equations, as many as the tearing variables, close
the loop. A Newton iteration then works on the tearing variables only.

Whether equation ``e`` may be solved explicitly for ``v`` is the caller's knowledge
(e.g. ``v`` appears linearly with a constant, nonzero coefficient), passed as the
predicate ``solvable(e, v)``.
"""

from __future__ import annotations

import heapq
from collections.abc import Callable, Sequence
from dataclasses import dataclass

__all__ = ["Tearing", "tear"]


@dataclass
class Tearing:
    """A torn block.

    Attributes
    ----------
    sequence : list of tuple of (int, int)
        ``(e, v)`` pairs: solve equation ``e`` for ``v``, in this order.
    residuals : list of int
        Equations evaluated as residuals once the sequence has run.
    tearing_vars : list of int
        Variables guessed by the outer iteration; as many as `residuals`.
    """

    sequence: list[tuple[int, int]]
    residuals: list[int]
    tearing_vars: list[int]


def tear(block_eqs: Sequence[int], block_vars: Sequence[int],
         adj: Sequence[Sequence[int]], solvable: Callable[[int, int], bool]) -> Tearing:
    """Tear a square block into an explicit sequence and residual equations.

    Parameters
    ----------
    block_eqs : sequence of int
        Equations of the block.
    block_vars : sequence of int
        Unknowns of the block, as many as `block_eqs`. Variables of `adj` outside the
        block are known.
    adj : sequence of sequence of int
        ``adj[e]`` lists the variables of equation ``e``.
    solvable : callable
        ``solvable(e, v)`` tells whether equation ``e`` can be solved explicitly for
        ``v``; asked only for block variables of block equations.

    Returns
    -------
    Tearing
        Every block variable is either a tearing variable or solved by exactly one
        sequence pair; every block equation is either in the sequence or a residual;
        ``len(residuals) == len(tearing_vars)``. Each sequence equation uses only
        known variables, tearing variables and variables solved earlier in the
        sequence. A single equation is returned as a one-pair sequence when solvable,
        else as a residual with its variable torn.

    Raises
    ------
    ValueError
        If the block is not square or lists an equation or variable twice.

    Notes
    -----
    Causalization with a greedy choice of tearing variables, after Cellier &
    Kofman, *Continuous System Simulation* (2006), ch. 7:

    - an equation with a single unknown left, solvable for it, is solved next
      (forward);
    - an unknown left in a single equation, solvable for it, is solved from that
      equation after all others (backward);
    - an equation without unknowns becomes a residual;
    - when nothing applies, the unknown to tear is the one that cannot be solved from
      any remaining equation if there is one, else the one in the most remaining
      equations, ties broken by the number of equations it would make solvable (among
      the first few tied unknowns, by index).

    The cost is ``O(m log n)`` for ``m`` incidences of the block.
    """
    eqs = list(block_eqs)
    variables = list(block_vars)
    if len(eqs) != len(variables):
        raise ValueError(f"a block must be square, got {len(eqs)} equations and "
                         f"{len(variables)} variables.")
    if len(set(eqs)) != len(eqs) or len(set(variables)) != len(variables):
        raise ValueError("a block lists an equation or a variable twice.")
    return _Causalization(eqs, variables, adj, solvable).run()


_TIES = 8
"""Most tied tearing candidates whose gain is compared."""


class _Causalization:
    """The working state of one `tear` call, on local indices."""

    def __init__(self, eqs: list[int], variables: list[int],
                 adj: Sequence[Sequence[int]], solvable: Callable[[int, int], bool]):
        self.eqs = eqs
        self.variables = variables
        local = {v: j for j, v in enumerate(variables)}
        self.rows = [list(dict.fromkeys(local[v] for v in adj[e] if v in local))
                     for e in eqs]
        self.solvable = [{j for j in row if solvable(eqs[i], variables[j])}
                         for i, row in enumerate(self.rows)]
        self.cols: list[list[int]] = [[] for _ in variables]
        for i, row in enumerate(self.rows):
            for j in row:
                self.cols[j].append(i)
        self.unknowns = [len(row) for row in self.rows]
        self.occurrences = [len(col) for col in self.cols]
        self.solvable_in = [0] * len(variables)
        for sol in self.solvable:
            for j in sol:
                self.solvable_in[j] += 1
        self.eq_done = [False] * len(eqs)
        self.var_done = [False] * len(variables)
        self.n_open = len(variables)
        self.forward: list[tuple[int, int]] = []
        self.backward: list[tuple[int, int]] = []
        self.residuals: list[int] = []
        self.torn: list[int] = []
        self.eq_queue = [i for i, n in enumerate(self.unknowns) if n <= 1]
        self.var_queue = [j for j, n in enumerate(self.occurrences) if n == 1]
        self.heap = [self._key(j) for j in range(len(variables))]
        heapq.heapify(self.heap)

    def run(self) -> Tearing:
        """Causalize until every variable is known; return the result in global indices."""
        self._propagate()
        while self.n_open:
            j = self._tearing_choice()
            self.torn.append(j)
            self._know(j)
            self._propagate()
        sequence = self.forward + self.backward[::-1]
        return Tearing(sequence=[(self.eqs[i], self.variables[j]) for i, j in sequence],
                       residuals=[self.eqs[i] for i in self.residuals],
                       tearing_vars=[self.variables[j] for j in self.torn])

    def _propagate(self) -> None:
        """Apply the forward, backward and residual rules until none applies."""
        while self.eq_queue or self.var_queue:
            while self.eq_queue:
                self._try_forward(self.eq_queue.pop())
            if self.var_queue:
                self._try_backward(self.var_queue.pop())

    def _try_forward(self, i: int) -> None:
        """Solve equation `i` for its last unknown, or make it a residual."""
        if self.eq_done[i]:
            return
        if self.unknowns[i] == 0:
            self._close(i)
            self.residuals.append(i)
            return
        j = next(j for j in self.rows[i] if not self.var_done[j])
        if j in self.solvable[i]:
            self._close(i)
            self.forward.append((i, j))
            self._know(j)

    def _try_backward(self, j: int) -> None:
        """Solve the single remaining equation of unknown `j` for it, last."""
        if self.var_done[j] or self.occurrences[j] != 1:
            return
        i = next(i for i in self.cols[j] if not self.eq_done[i])
        if j in self.solvable[i]:
            self._close(i)
            self.backward.append((i, j))
            self._know(j)

    def _close(self, i: int) -> None:
        """Remove equation `i` from the remaining ones."""
        self.eq_done[i] = True
        for j in self.rows[i]:
            if self.var_done[j]:
                continue
            self.occurrences[j] -= 1
            if j in self.solvable[i]:
                self.solvable_in[j] -= 1
            if self.occurrences[j] == 1:
                self.var_queue.append(j)
            heapq.heappush(self.heap, self._key(j))

    def _know(self, j: int) -> None:
        """Mark variable `j` as known (solved or torn)."""
        self.var_done[j] = True
        self.n_open -= 1
        for i in self.cols[j]:
            if self.eq_done[i]:
                continue
            self.unknowns[i] -= 1
            if self.unknowns[i] <= 1:
                self.eq_queue.append(i)

    def _key(self, j: int) -> tuple[bool, int, int]:
        """Heap key of unknown `j`: forced first, then most occurrences, then index."""
        return (self.solvable_in[j] != 0, -self.occurrences[j], j)

    def _tearing_choice(self) -> int:
        """The unknown to tear next: best key, ties broken by gain."""
        tied: list[tuple[bool, int, int]] = []
        while self.heap and len(tied) < _TIES:
            key = self.heap[0]
            if self.var_done[key[2]] or key != self._key(key[2]):
                heapq.heappop(self.heap)
            elif tied and key[:2] != tied[0][:2]:
                break
            else:
                tied.append(heapq.heappop(self.heap))
        best = max(tied, key=lambda key: (self._gain(key[2]), -key[2]))
        for key in tied:
            if key is not best:
                heapq.heappush(self.heap, key)
        return best[2]

    def _gain(self, j: int) -> int:
        """Equations that would become solvable for their last unknown if `j` were known."""
        gain = 0
        for i in self.cols[j]:
            if self.eq_done[i] or self.unknowns[i] != 2:
                continue
            other = next(k for k in self.rows[i] if k != j and not self.var_done[k])
            gain += other in self.solvable[i]
        return gain
