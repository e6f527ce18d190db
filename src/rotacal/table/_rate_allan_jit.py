"""Numba twin of :func:`rotacal.table.rate_allan_sums.allan_sums` (imports Numba).

Imported only for long records (:func:`rotacal._jit.use_numba`), compiled on first use and cached
on disk. It walks the record once in tiles of :data:`TILE` terms that stay in the L1 cache and,
per tile, forms ω once per pulse for every cluster size and sums the squared differences, where
the NumPy twin takes each cluster size over the whole record by slices; the sums differ by
rounding only (≤ 1e-12 relative; the caller adds the block sums exactly with ``math.fsum`` either
way).

Both inner loops are plain unit-stride loops over slices so that LLVM turns them into SIMD
code: NumPy's error model (a zero Δt gives ±inf or NaN, as in the NumPy twin, instead of a
per-term zero test that keeps the division scalar) and slices taken before the loop (an index
``i + k`` would be checked for wrap-around, which turns the loads into gathers). Measured on
10⁷ pulses × 22 cluster sizes: 0.30 s → 0.05 s of CPU.
"""

from __future__ import annotations

import numpy as np
from numba import njit

#: Terms per tile: t, a and ω of a tile (3 × 8 kB, plus the k carried) fit the L1 data cache.
TILE = 1024


@njit(cache=True, nogil=True, fastmath={"reassoc", "nsz"}, error_model="numpy")
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
    the blocks aligned on ``block``·b; every cluster size visits a tile of :data:`TILE` terms
    (of ``block`` when that is not a multiple of it) before the next."""
    lo = firsts.min()
    hi = stops.max()
    nblocks = (hi - lo + block - 1) // block
    out = np.zeros((ks.size, nblocks))
    step = TILE if block % TILE == 0 else block  # a tile lies in one block
    omega = np.empty(step + ks.max())
    for b0 in range(lo, hi, step):
        b1 = b0 + step
        ob = (b0 - lo) // block
        for c in range(ks.size):
            k = ks[c]
            j0 = max(b0, firsts[c])
            j1 = min(b1, stops[c])
            if j1 <= j0:
                continue
            m = j1 - j0 + k  # ω of terms j0 … j1 − 1 + k
            t0, t1 = t[j0 : j0 + m], t[j0 + k : j0 + k + m]
            a0, a1 = a[j0 : j0 + m], a[j0 + k : j0 + k + m]
            for i in range(m):
                omega[i] = (a1[i] - a0[i]) / (t1[i] - t0[i])
            later = omega[k:m]
            s = 0.0
            for i in range(j1 - j0):
                d = later[i] - omega[i]
                s += d * d
            out[c, ob] += s
    return out
