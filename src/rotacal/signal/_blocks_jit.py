"""Numba twin of the block moments of :class:`rotacal.signal._blocks.HarmonicFitAccumulator`
(private; imports Numba).

Imported only for long records (:func:`rotacal._jit.use_numba`), compiled on first use and cached
on disk. For full blocks of m samples it forms what the NumPy path forms with one matrix product
per 256 blocks: ``Q[r, k] = Σ_i (y[r·m + i] − y0)·V[i, k]`` and ``Σ (y − y0)²``, summed in
sample order within SIMD lanes (the NumPy path's BLAS sums in its own order: ≤ 1e-12 relative
apart). The BLAS product on many small blocks is slow where BLAS runs several threads on a busy
machine; this loop is not.
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True, nogil=True, fastmath={"reassoc", "contract"})
def block_moments(
    y: np.ndarray, y0: float, v: np.ndarray, q: np.ndarray
) -> float:  # pragma: no cover - compiled
    """Moments of ``q.shape[0]`` full blocks of ``v.shape[0]`` samples into ``q``; returns
    ``Σ (y − y0)²`` over them.

    Each block's centred samples are formed once; the moments are then dot products of them
    with the columns of V (held transposed, contiguous), four columns per loop so that each
    sample is loaded once for four products (each product still summed alone, in SIMD lanes
    reassociated as BLAS forms them too).
    """
    m = v.shape[0]
    kk = v.shape[1]
    vt = np.ascontiguousarray(v.T)
    yc = np.empty(m)
    s2 = 0.0
    grouped = kk - kk % 4
    for r in range(q.shape[0]):
        base = r * m
        part = 0.0
        for i in range(m):
            d = y[base + i] - y0
            yc[i] = d
            part += d * d
        for k in range(0, grouped, 4):
            c0 = vt[k]
            c1 = vt[k + 1]
            c2 = vt[k + 2]
            c3 = vt[k + 3]
            a0 = 0.0
            a1 = 0.0
            a2 = 0.0
            a3 = 0.0
            for i in range(m):
                d = yc[i]
                a0 += d * c0[i]
                a1 += d * c1[i]
                a2 += d * c2[i]
                a3 += d * c3[i]
            q[r, k] = a0
            q[r, k + 1] = a1
            q[r, k + 2] = a2
            q[r, k + 3] = a3
        for k in range(grouped, kk):
            col = vt[k]
            acc = 0.0
            for i in range(m):
                acc += yc[i] * col[i]
            q[r, k] = acc
        s2 += part
    return s2
