"""Numba twin of :func:`rotacal.table.rate_allan_sums.allan_block_sums` (imports Numba).

Imported only for long records (:func:`rotacal._jit.use_numba`), compiled on first use and cached
on disk. Per block of terms it forms ω once per pulse and sums the squared differences, where the
NumPy twin forms them by whole-array slices; the block sums differ by rounding only (≤ 1e-12
relative; the caller adds them exactly with ``math.fsum`` either way).
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True, nogil=True, fastmath={"reassoc", "nsz"})
def block_sums(
    t: np.ndarray, a: np.ndarray, k: int, first: int, stop: int, block: int
) -> np.ndarray:  # pragma: no cover - compiled
    """Σ (ω_{j+k} − ω_j)² over each block of terms j = first … stop − 1 (``block`` terms each),
    ω_j = (a[j+k] − a[j])/(t[j+k] − t[j])."""
    count = stop - first
    nblocks = (count + block - 1) // block
    out = np.empty(nblocks)
    omega = np.empty(block + k)
    for b in range(nblocks):
        j0 = first + b * block
        j1 = min(j0 + block, stop)
        width = j1 - j0 + k
        for i in range(width):
            j = j0 + i
            omega[i] = (a[j + k] - a[j]) / (t[j + k] - t[j])
        s = 0.0
        for i in range(j1 - j0):
            d = omega[i + k] - omega[i]
            s += d * d
        out[b] = s
    return out
