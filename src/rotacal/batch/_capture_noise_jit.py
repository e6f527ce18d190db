"""Numba twin of the long cluster sizes' sums of :mod:`rotacal.batch.capture_noise` (private;
imports Numba).

Imported only where :func:`rotacal._jit.use_numba` says the work pays for it; compiled on first
use and cached on disk. The second differences follow their recurrence in one loop (the NumPy
twin takes a cumulative sum of the increments per piece, then the squares with a dot product):
the pieces' sums agree with the twin's to ≤ 1e-12 relative, not to the bit.
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True, nogil=True)
def piece_squares_jit(
    d0: float, r0: np.ndarray, r1: np.ndarray, r2: np.ndarray, piece: int
) -> np.ndarray:  # pragma: no cover
    """Σ d_i² over each piece of ``piece`` terms, d_0 = d0 (not included) and d_{i+1} = d_i +
    (r2_i − r1_i) − (r1_i − r0_i): the sums of
    :func:`rotacal.batch.capture_noise._piece_squares`."""
    n = r0.size
    parts = np.empty((n + piece - 1) // piece)
    d = d0
    for p in range(parts.size):
        lo = p * piece
        hi = min(n, lo + piece)
        a = r0[lo:hi]
        b = r1[lo:hi]
        c = r2[lo:hi]
        acc = 0.0
        for j in range(hi - lo):
            d += (c[j] - b[j]) - (b[j] - a[j])
            acc += d * d
        parts[p] = acc
    return parts
