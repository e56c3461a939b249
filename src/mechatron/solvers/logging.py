"""Evaluating every logged variable on the output grid, into NumPy without copies.

The output function is mapped over a fixed chunk of points (building a CasADi ``Map`` costs
time growing with its size, so one chunk function is built once and reused) and evaluated
through CasADi's buffer interface straight into views of NumPy arrays.
"""

from __future__ import annotations

import numpy as np

from mechatron.compiler.compiled import CompiledModel

__all__ = ["evaluate_outputs"]

CHUNK = 64            # output points per mapped evaluation, for large models
CHUNK_VALUES = 16384  # small models map more points at once: about this many values


def chunk_size(n_logged: int) -> int:
    """Points per mapped evaluation: CHUNK for large models, more for small ones (fewer
    calls), bounded so that building the map stays cheap."""
    return int(min(1024, max(CHUNK, CHUNK_VALUES // max(1, n_logged))))


def _mapped(cm: CompiledModel, m: int):
    key = ("out", m)
    entry = cm._cache.get(key)
    if entry is None:
        f = cm.f_out.map(m, "serial")
        buf, evaluate = f.buffer()
        entry = cm._cache[key] = (f, buf, evaluate)
    return entry


def evaluate_outputs(cm: CompiledModel, t: np.ndarray, X: np.ndarray, Z: np.ndarray,
                     p: np.ndarray) -> np.ndarray:
    """Every logged variable at every point: array (n_logged, n_points).

    ``X`` is (nX, n) and ``Z`` is (nz, n), one column per point; ``p`` is one vector, or
    one column per point (a model driven by external inputs).
    """
    n = t.size
    n_y = len(cm.names)
    nX, nz = X.shape[0], Z.shape[0]
    tt = np.ascontiguousarray(t, dtype=float)
    Xf = np.asarray(X, dtype=float).ravel(order="F")
    Zf = np.asarray(Z, dtype=float).ravel(order="F")
    Pf = np.asarray(p, dtype=float).ravel(order="F") if np.ndim(p) == 2 else None
    out = np.empty(n_y * n)
    tiles: dict[int, np.ndarray] = {}
    step = chunk_size(n_y)
    for k in range(0, n, step):
        m = min(step, n - k)
        _, buf, evaluate = _mapped(cm, m)
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
