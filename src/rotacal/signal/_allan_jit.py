"""Numba twin of :func:`rotacal.signal._allan_fast.direct_sums` (private; imports Numba).

Imported only for long records (:func:`rotacal._jit.use_numba`); compiled on first use and cached
on disk. The sum of squared second differences is taken block by block of :data:`_BLOCK` terms,
every cluster size for one block before the next, so that the few blocks of the record it reads
stay in the cache; within a block the squares are added in any order (the compiler vectorises the
loop), and the block totals are added in order. Each block total is off by about
``_BLOCK·ε`` relative and the total by ``(N/_BLOCK)·ε`` at worst: the sums agree with the NumPy
path's (pairwise within chunks) to ≤ 1e-12 relative, not to the bit.
"""

from __future__ import annotations

import numpy as np
from numba import njit

#: Second differences per block (a block's three windows of the record stay in the L2 cache).
_BLOCK = 4096


@njit(cache=True, nogil=True, fastmath={"reassoc", "contract"})
def _block_sum(z: np.ndarray, m: int, start: int, stop: int) -> float:  # pragma: no cover
    """Σ_{i=start}^{stop−1} (z[i+2m] − 2·z[i+m] + z[i])², added in any order (vectorised).

    The three windows are sliced first: indexing ``z[i + m]`` directly would keep Numba's
    negative-index check in the loop, which stops the compiler from vectorising it (15× slower).
    """
    first = z[start:stop]
    mid = z[start + m : stop + m]
    last = z[start + 2 * m : stop + 2 * m]
    acc = 0.0
    for j in range(stop - start):
        d = last[j] - 2.0 * mid[j] + first[j]
        acc += d * d
    return acc


@njit(cache=True, nogil=True)
def direct_sums_jit(
    z: np.ndarray, ms: np.ndarray, firsts: np.ndarray
) -> np.ndarray:  # pragma: no cover - compiled
    """``S(m) = Σ_{i=f}^{N−2m−1} (z[i+2m] − 2·z[i+m] + z[i])²`` for each cluster size of ``ms``
    and its first term ``f`` of ``firsts``.

    NIST SP 1065 (Riley 2008), eq. (11): the overlapping Allan variance's sum from phase data
    ``z`` (any unit u; result u²); cluster sizes in samples, each with ``N − 2m ≥ 1``.
    """
    n = z.size
    out = np.zeros(ms.size)
    for start in range(0, n, _BLOCK):
        for k in range(ms.size):
            m = ms[k]
            begin = max(start, firsts[k])
            stop = min(n - 2 * m, start + _BLOCK)
            if stop > begin:
                out[k] += _block_sum(z, m, begin, stop)
    return out


@njit(cache=True, nogil=True)
def leaf_products_jit(zs: np.ndarray, k: int, leaf: int) -> np.ndarray:  # pragma: no cover
    """The leaves of :func:`rotacal.signal._allan_fast._half_products`: for each node ``t`` of
    ``leaf`` cluster sizes, ``h[t·leaf + m] = Σ_rows Σ_{j<m} zs[r, t·leaf + j]·zs[r, 2t·leaf + j + m]``,
    the terms in the NumPy path's order (j, then the rows)."""
    rows = zs.shape[0]
    out = np.zeros(k)
    part = np.empty(leaf)
    for t in range(k // leaf):
        u0 = t * leaf
        v0 = 2 * t * leaf
        total = np.zeros(leaf)
        for r in range(rows):
            part[:] = 0.0
            for j in range(leaf - 1):
                uj = zs[r, u0 + j]
                for m in range(j + 1, leaf):
                    part[m] += uj * zs[r, v0 + j + m]
            for m in range(leaf):
                total[m] += part[m]
        out[u0 : u0 + leaf] = total
    return out
