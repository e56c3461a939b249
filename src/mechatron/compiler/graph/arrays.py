"""Integer-array helpers shared by the passes that hold rows as compressed arrays."""

from __future__ import annotations

import numpy as np

__all__ = ["segments"]


def segments(ptr: np.ndarray, take: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """For the segments ``take`` of compressed rows ``ptr`` (as a CSR matrix's), in that
    order: the place of each of their entries among all entries, and the index into
    ``take`` of the segment each one belongs to."""
    counts = ptr[take + 1] - ptr[take]
    owner = np.repeat(np.arange(take.size), counts)
    within = np.arange(owner.size) - np.repeat(np.cumsum(counts) - counts, counts)
    return ptr[take][owner] + within, owner
