"""Numba twin of :func:`rotacal.table.rate_allan_sums.allan_sums` (imports Numba).

Imported only for long records (:func:`rotacal._jit.use_numba`), compiled on first use and cached
on disk. It walks the record once in cache-sized blocks and, per block, forms ω once per pulse for
every cluster size and sums the squared differences, where the NumPy twin takes each cluster
size over the whole record by slices; the block sums differ by rounding only (≤ 1e-12 relative;
the caller adds them exactly with ``math.fsum`` either way).
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True, nogil=True, fastmath={"reassoc", "nsz"})
def block_sums(
    t: np.ndarray,
    a: np.ndarray,
    ks: np.ndarray,
    firsts: np.ndarray,
    stops: np.ndarray,
    block: int,
) -> np.ndarray:  # pragma: no cover - compiled
    """Σ (ω_{j+k} − ω_j)² per cluster size k = ks[c] over each block of ``block`` terms of
    j = firsts[c] … stops[c] − 1, ω_j = (a[j+k] − a[j])/(t[j+k] − t[j]); shape (C, blocks),
    the blocks aligned on ``block``·b so that every cluster size visits the record together."""
    lo = firsts.min()
    hi = stops.max()
    nblocks = (hi - lo + block - 1) // block
    out = np.zeros((ks.size, nblocks))
    omega = np.empty(block + ks.max())
    for b in range(nblocks):
        b0 = lo + b * block
        b1 = b0 + block
        for c in range(ks.size):
            k = ks[c]
            j0 = max(b0, firsts[c])
            j1 = min(b1, stops[c])
            if j1 <= j0:
                continue
            for i in range(j1 - j0 + k):
                j = j0 + i
                omega[i] = (a[j + k] - a[j]) / (t[j + k] - t[j])
            s = 0.0
            for i in range(j1 - j0):
                d = omega[i + k] - omega[i]
                s += d * d
            out[c, b] = s
    return out
