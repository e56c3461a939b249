"""The logged variables: evaluated on the output grid, all at once or on demand.

The output function is mapped over a fixed chunk of points (building a CasADi ``Map`` costs
time growing with its size, so one chunk function is built once and reused) and evaluated
through CasADi's buffer interface straight into views of NumPy arrays.

Selective logging (``simulate(log=...)``): a variable-step run keeps its trajectory (the
integration state ``X``, the algebraic unknowns ``z`` and the parameters at every output
time) and the variables asked for; any other variable of the simlog is computed from that
trajectory when it is first read, by :class:`OutputColumns` with the compiled output
function, so memory grows with states x time points, not variables x time points. The
values are those a full log holds: the same function on the same numbers.
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from mechatron.compiler.compiled import CompiledModel
from mechatron.solvers.fpenv import subnormals_flushed

__all__ = ["evaluate_outputs", "evaluate_point", "OutputColumns", "SMALL_LOG"]

CHUNK = 64            # output points per mapped evaluation, for large models
CHUNK_VALUES = 16384  # small models map more points at once: about this many values
#: A log of at most this many values (8 MB) is computed whole on its first read of a
#: variable that was not logged; a larger one computes only the variables read.
SMALL_LOG = 1 << 20


def chunk_size(n_logged: int) -> int:
    """Points per mapped evaluation: CHUNK for large models, more for small ones (fewer
    calls), bounded so that building the map stays cheap."""
    return int(min(1024, max(CHUNK, CHUNK_VALUES // max(1, n_logged))))


def _mapped(f: ca.Function, m: int, cache: dict, key):
    entry = cache.get((key, m))
    if entry is None:
        fm = f.map(m, "serial")
        buf, evaluate = fm.buffer()
        entry = cache[(key, m)] = (fm, buf, evaluate)
    return entry


def _evaluate(f: ca.Function, n_y: int, t: np.ndarray, X: np.ndarray, Z: np.ndarray,
              p: np.ndarray, cache: dict, key) -> np.ndarray:
    """``f(t, X, z, p)`` (``n_y`` outputs) at every point: array (n_y, n_points)."""
    n = t.size
    nX, nz = X.shape[0], Z.shape[0]
    tt = np.ascontiguousarray(t, dtype=float)
    Xf = np.asarray(X, dtype=float).ravel(order="F")
    Zf = np.asarray(Z, dtype=float).ravel(order="F")
    Pf = np.asarray(p, dtype=float).ravel(order="F") if np.ndim(p) == 2 else None
    out = np.empty(n_y * n)
    tiles: dict[int, np.ndarray] = {}
    # building the map costs time growing with the inputs as well as the outputs
    step = chunk_size(max(n_y, nX + nz + (np.size(p) // n if Pf is not None else np.size(p))))
    for k in range(0, n, step):
        m = min(step, n - k)
        _, buf, evaluate = _mapped(f, m, cache, key)
        pm = tiles.get(m) if Pf is None else Pf[k * Pf.size // n:(k + m) * Pf.size // n]
        if pm is None:
            pm = tiles[m] = np.tile(np.asarray(p, dtype=float), m)
        buf.set_arg(0, memoryview(tt[k:k + m]))
        buf.set_arg(1, memoryview(Xf[k * nX:(k + m) * nX]))
        buf.set_arg(2, memoryview(Zf[k * nz:(k + m) * nz]))
        buf.set_arg(3, memoryview(pm))
        buf.set_res(0, memoryview(out[k * n_y:(k + m) * n_y]))
        evaluate()
    return out.reshape(n, n_y).T


def evaluate_point(f: ca.Function, args) -> np.ndarray:
    """``f(*args)``'s first output as a flat array, through the buffer interface (no
    casadi.DM: converting one of many entries costs memory and time)."""
    arrays = [np.ascontiguousarray(np.ravel(a), dtype=float) for a in args]
    out = np.empty(f.nnz_out(0))
    buf, evaluate = f.buffer()
    for k, a in enumerate(arrays):
        buf.set_arg(k, memoryview(a))
    buf.set_res(0, memoryview(out))
    evaluate()
    return out


@subnormals_flushed()
def evaluate_outputs(cm: CompiledModel, t: np.ndarray, X: np.ndarray, Z: np.ndarray,
                     p: np.ndarray) -> np.ndarray:
    """Every logged variable at every point: array (n_logged, n_points).

    ``X`` is (nX, n) and ``Z`` is (nz, n), one column per point; ``p`` is one vector, or
    one column per point (a model driven by external inputs).
    """
    return _evaluate(cm.f_out, len(cm.names), t, X, Z, p, cm._cache, "out")


class OutputColumns:
    """Variables of a simlog computed on demand from a logged trajectory.

    Parameters
    ----------
    f_out : casadi.Function
        The compiled output function ``(t, X, z, p) -> y`` (one entry per variable).
    t : numpy.ndarray, shape (n,)
        Output times.
    X, Z : numpy.ndarray, shapes (nX, n) and (nz, n)
        Integration state and algebraic unknowns at each output time.
    p : numpy.ndarray
        Parameter vector, or one column per output time.
    cache : dict, optional
        Where the output function's expression graph is kept once built (the compiled
        model's cache, so that every result of a model shares it).

    Calling it with row indices of ``f_out``'s output returns those variables, shape
    (len(rows), n). A few rows are computed by a function of their own, cut from the
    output function's expression graph (only the operations they need); many rows by
    the whole output function, chunk by chunk. Instances pickle (the CasADi function
    serializes) so a :class:`~mechatron.results.SimResult` can travel to another process.
    """

    def __init__(self, f_out: ca.Function, t: np.ndarray, X: np.ndarray, Z: np.ndarray,
                 p: np.ndarray, cache: dict | None = None):
        self.f_out = f_out
        self.t, self.X, self.Z, self.p = t, X, Z, p
        self._cache: dict = {}
        self._shared = cache if cache is not None else {}

    @staticmethod
    def expression(f_out: ca.Function, cache: dict):
        """``(inputs, y)``: the SX symbols of ``f_out`` and its output expression, built
        once and kept in ``cache``."""
        expr = cache.get(("out_expr", id(f_out)))
        if expr is None:
            sym = f_out.sx_in()
            expr = cache[("out_expr", id(f_out))] = (sym, f_out.call(sym)[0])
        return expr

    @property
    def n_out(self) -> int:
        return int(self.f_out.nnz_out(0))

    @property
    def nbytes(self) -> int:
        """Bytes of the trajectory kept to compute the variables."""
        return int(sum(np.asarray(a).nbytes for a in (self.t, self.X, self.Z, self.p)))

    def __getstate__(self):
        state = dict(self.__dict__)
        state["_cache"], state["_shared"] = {}, {}
        return state

    @subnormals_flushed()
    def __call__(self, rows) -> np.ndarray:
        rows = np.asarray(rows, dtype=np.int64).ravel()
        n_all = self.n_out
        args = (self.t, self.X, self.Z, self.p)
        if rows.size == 0:
            return np.empty((0, self.t.size))
        if rows.size * 4 >= n_all or not self.f_out.is_a("SXFunction"):
            return self._all_rows(rows, n_all)
        sub = self._subset(rows)
        return _evaluate(sub, rows.size, *args, self._cache, ("sub", rows.tobytes()))

    def last(self) -> np.ndarray:
        """Every variable at the last output time (one evaluation)."""
        k = self.t.size - 1
        p = self.p[:, k] if np.ndim(self.p) == 2 else self.p
        return evaluate_point(self.f_out, [self.t[k], self.X[:, k], self.Z[:, k], p])

    def _all_rows(self, rows: np.ndarray, n_all: int) -> np.ndarray:
        """Rows of the whole output, computed over chunks of points so that the whole
        table is never held when only some rows are wanted."""
        n = self.t.size
        if rows.size == n_all and np.array_equal(rows, np.arange(n_all)):
            return _evaluate(self.f_out, n_all, self.t, self.X, self.Z, self.p,
                             self._shared, "out")
        out = np.empty((rows.size, n), order="F")   # filled by blocks of columns
        chunk = chunk_size(n_all)     # slices of whole chunks: the mapped function reused
        step = chunk * max(1, SMALL_LOG // (n_all * chunk))
        for k in range(0, n, step):
            cols = slice(k, min(n, k + step))
            p = self.p[:, cols] if np.ndim(self.p) == 2 else self.p
            block = _evaluate(self.f_out, n_all, self.t[cols], self.X[:, cols],
                              self.Z[:, cols], p, self._shared, "out")   # F-ordered
            out[:, cols] = block.T[:, rows].T
        return out

    def _subset(self, rows: np.ndarray) -> ca.Function:
        """A function of the selected rows only: the output expression (built once) cut
        to what they depend on."""
        sym, y = self.expression(self.f_out, self._shared)
        return ca.Function("out_rows", sym, [ca.densify(y[rows.tolist()])])
