"""Numba twin of the block moments of :class:`rotacal.signal._blocks.HarmonicFitAccumulator`
(private; imports Numba).

Imported only for long records (:func:`rotacal._jit.use_numba`), compiled on first use and cached
on disk. For full blocks of m samples it forms what the NumPy path forms with one matrix product
per 256 blocks: ``Q[r, k] = Σ_i (y[r·m + i] − y0)·V[i, k]`` and ``Σ (y − y0)²``, summed in sample
order (the NumPy path's BLAS sums in its own order: ≤ 1e-12 relative apart). The BLAS product on
many small blocks is slow where BLAS runs several threads on a busy machine; this loop is not.
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True, nogil=True)
def block_moments(
    y: np.ndarray, y0: float, v: np.ndarray, q: np.ndarray
) -> float:  # pragma: no cover - compiled
    """Moments of ``q.shape[0]`` full blocks of ``v.shape[0]`` samples into ``q``; returns
    ``Σ (y − y0)²`` over them."""
    m = v.shape[0]
    kk = v.shape[1]
    s2 = 0.0
    acc = np.empty(kk)
    for r in range(q.shape[0]):
        for k in range(kk):
            acc[k] = 0.0
        base = r * m
        part = 0.0
        for i in range(m):
            yc = y[base + i] - y0
            part += yc * yc
            for k in range(kk):
                acc[k] += yc * v[i, k]
        for k in range(kk):
            q[r, k] = acc[k]
        s2 += part
    return s2
