"""Sums of squared phase differences of the modified, Hadamard and total deviations (private
kernels of :mod:`rotacal.signal.deviations`).

Each function takes the phase ``x`` (any unit u, best line removed) and cluster sizes ``ms`` and
returns, per cluster size, the sum of squares (u²) that the deviation divides by its count of
terms; whole-array NumPy in cache-sized chunks, O(N) per cluster size. References: NIST SP 1065
(Riley 2008), eqs. (14) (modified Allan variance), (18) (overlapping Hadamard variance) and (25)
(total variance, with the reflected extension of the phase).
"""

from __future__ import annotations

import numpy as np

#: Terms per chunk: a chunk's temporaries stay in the cache.
_CHUNK = 1 << 14


def combination_sums(
    z: np.ndarray,
    ms: np.ndarray,
    coeffs: tuple[float, ...],
    firsts: np.ndarray,
    count: np.ndarray,
) -> np.ndarray:
    """``Σ_{i=f}^{f+c−1} (Σ_k coeffs[k]·z[i + k·m])²`` for each cluster size ``m`` of ``ms``,
    its first index ``f`` of ``firsts`` and its number of terms ``c`` of ``count``.

    ``z`` in any unit u; the result in u². The caller guarantees ``f ≥ 0`` and
    ``f + c − 1 + (len(coeffs) − 1)·m < len(z)``.
    """
    out = np.empty(ms.size)
    buf = np.empty(_CHUNK)
    tmp = np.empty(_CHUNK)
    for idx, (m, f, c) in enumerate(zip(ms.tolist(), firsts.tolist(), count.tolist(), strict=True)):
        acc = 0.0
        for s in range(f, f + c, _CHUNK):
            e = min(f + c, s + _CHUNK)
            b, t = buf[: e - s], tmp[: e - s]
            np.multiply(z[s:e], coeffs[0], out=b)
            for k in range(1, len(coeffs)):
                np.multiply(z[s + k * m : e + k * m], coeffs[k], out=t)
                b += t
            np.multiply(b, b, out=b)
            acc += float(b.sum())  # pairwise summation within the chunk
        out[idx] = acc
    return out


def modified_sums(x: np.ndarray, ms: np.ndarray) -> np.ndarray:
    """``Σ_{j=0}^{N−3m} (Σ_{i=j}^{j+m−1} (x_{i+2m} − 2x_{i+m} + x_i))²`` for each ``m``.

    The inner sums are differences of the running sum C of the second differences
    (``C[j+m−1] − C[j−1]``). Summing the second differences, not the phase twice (as the
    classic double-cumsum form does), keeps the running sum as small as the terms it
    differences: its rounding stays ~ε·√N relative instead of growing with the record's drift.
    """
    n = x.size
    out = np.empty(ms.size)
    work = np.empty(n)
    buf = np.empty(_CHUNK)
    for idx, m in enumerate(ms.tolist()):
        length = n - 2 * m
        c = work[:length]
        np.multiply(x[m : n - m], -2.0, out=c)
        c += x[2 * m :]
        c += x[:length]
        np.cumsum(c, out=c)
        acc = float(c[m - 1]) ** 2
        for s in range(0, length - m, _CHUNK):
            e = min(length - m, s + _CHUNK)
            b = buf[: e - s]
            np.subtract(c[s + m : e + m], c[s:e], out=b)
            np.multiply(b, b, out=b)
            acc += float(b.sum())  # not BLAS's dot: its threads' start-up dominated (5×)
        out[idx] = acc
    return out


def hadamard_sums(x: np.ndarray, ms: np.ndarray) -> np.ndarray:
    """``Σ_{i=0}^{N−3m−1} (x_{i+3m} − 3x_{i+2m} + 3x_{i+m} − x_i)²`` for each ``m``."""
    return combination_sums(
        x, ms, (-1.0, 3.0, -3.0, 1.0), np.zeros(ms.size, dtype=np.int64), x.size - 3 * ms
    )


def total_sums(x: np.ndarray, ms: np.ndarray) -> np.ndarray:
    """``Σ_{i=1}^{N−2} (x*_{i−m} − 2x*_i + x*_{i+m})²`` for each ``m`` (0-based i), with ``x*``
    the phase extended by reflection at both ends: ``x*_{−j} = 2x_0 − x_j`` and
    ``x*_{N−1+j} = 2x_{N−1} − x_{N−1−j}`` (NIST SP 1065, §5.2.11)."""
    n = x.size
    mx = int(ms.max())
    left = 2.0 * x[0] - x[mx:0:-1]
    right = 2.0 * x[-1] - x[n - 2 : n - 2 - mx : -1] if n - 2 - mx >= 0 else None
    if right is None:  # mx = n − 1 reaches x_0 itself
        right = 2.0 * x[-1] - x[n - 2 :: -1]
    ext = np.concatenate((left, x, right))
    firsts = mx + 1 - ms
    return combination_sums(ext, ms, (1.0, -2.0, 1.0), firsts, np.full(ms.size, n - 2))
