"""Column pivoting whose choices do not depend on floating-point rounding.

State selection picks, among candidate derivatives, columns of a numeric Jacobian that
form a well-conditioned nonsingular block (the dummy derivatives). Pivoted QR
(Businger & Golub, 1965) does this greedily: at each step it takes the column with the
largest norm after projecting out the columns already taken. When two norms are equal
in exact arithmetic (symmetric mechanisms, ``der(q) = w`` beside ``der(der(q))``), which
one LAPACK takes depends on how the BLAS kernel rounds, and so does the model that is
compiled. `pivot_columns` compares norms with a relative tolerance, `TIE_RTOL`, and
gives a tie to the column that comes first: the caller orders the columns by its rule.
"""

from __future__ import annotations

import numpy as np

__all__ = ["TIE_RTOL", "pivot_columns", "largest"]

TIE_RTOL = 1e-8
"""Two pivot scores within this relative distance of each other are equal.

Rounding moves the residual norms of a Jacobian of a few hundred columns by about
1e-14 relative, while a real difference between candidates is a ratio of physical
coefficients (lengths, gear ratios, masses), far above 1e-8."""


def pivot_columns(a, k: int, *, rtol: float = TIE_RTOL) -> list[int]:
    """Choose `k` columns of `a` greedily, by residual norm, ties to the lowest index.

    Parameters
    ----------
    a : array_like, shape (m, n)
        The matrix whose columns are chosen, most preferred column first.
    k : int
        How many columns to choose; at most ``n`` are returned.
    rtol : float, optional
        Relative tolerance under which two residual norms are a tie.

    Returns
    -------
    list of int
        Indices of the chosen columns, in the order they were chosen.

    Notes
    -----
    Step ``s`` computes the norm of every remaining column projected onto the
    orthogonal complement of the columns chosen so far (the trailing rows after ``s``
    Householder reflections; recomputed, not downdated). A norm within ``rtol`` of the
    largest one ties with it, and the lowest-index tied column is chosen. Norms below
    ``max(m, n) * eps`` times the largest column norm of `a` count as zero, so
    numerically dependent columns tie with each other too and are taken in order.
    Entries that are not finite carry no information and count as zero. Scaling `a`
    by a positive number, permuting its rows, or perturbing it by a few ulps does not
    change the result unless two norms differ by about ``rtol`` (relative).
    """
    work = np.array(a, dtype=float, copy=True)
    if work.ndim != 2:
        raise ValueError(f"pivot_columns needs a matrix, got an array of shape "
                         f"{work.shape}.")
    work[~np.isfinite(work)] = 0.0
    m, n = work.shape
    if k <= 0 or n == 0:
        return []
    floor = max(m, n) * np.finfo(float).eps * float(np.max(np.linalg.norm(work, axis=0)))
    remaining = list(range(n))
    chosen: list[int] = []
    for step in range(min(k, n)):
        block = work[step:, remaining]
        norms = np.sqrt(np.einsum("ij,ij->j", block, block)) if step < m \
            else np.zeros(len(remaining))
        norms[norms <= floor] = 0.0
        best = float(np.max(norms))
        pos = int(np.flatnonzero(norms >= best * (1.0 - rtol))[0])
        j = remaining.pop(pos)
        chosen.append(j)
        if step < m - 1 and norms[pos] > 0.0:
            _reflect(work, step, j, remaining)
    return chosen


def _reflect(work: np.ndarray, step: int, j: int, remaining: list[int]) -> None:
    """Apply the Householder reflection that zeroes ``work[step + 1:, j]`` to the
    trailing rows of the `remaining` columns."""
    x = work[step:, j]
    alpha = -np.copysign(np.linalg.norm(x), x[0])
    v = x.copy()
    v[0] -= alpha
    vv = float(v @ v)
    if vv == 0.0 or not remaining:
        return
    cols = work[step:, remaining]
    work[step:, remaining] = cols - np.outer(v, (v @ cols) * (2.0 / vv))


def largest(values, limit: int, *, floor: float = 0.0, rtol: float = TIE_RTOL) -> list[int]:
    """Indices of the at most `limit` largest `values` above `floor`, largest first;
    values within `rtol` (relative) of each other tie and go in index order.

    For lists of suspects in messages: equal weights (a symmetric mechanism) are listed
    the same way on every machine.
    """
    w = np.array(values, dtype=float).ravel()
    w[~np.isfinite(w)] = 0.0
    open_ = list(np.flatnonzero(w > floor))
    out: list[int] = []
    while open_ and len(out) < limit:
        top = max(w[i] for i in open_)
        pos = next(p for p, i in enumerate(open_) if w[i] >= top * (1.0 - rtol))
        out.append(int(open_.pop(pos)))
    return out
