"""Numba twins of the per-pulse loops of the streamed rate analysis (imports Numba).

Imported only for long records (:func:`rotacal._jit.use_numba`), compiled on first use and cached
on disk: the same arithmetic per pulse as the NumPy code of :class:`rotacal.table.rate_jitter.
JitterSums` and :class:`rotacal.table.rate_stream._RatePoints`, in one pass without record-long
temporaries; sums are taken in another order (≤ 1e-12 relative, the tests run both).

Each works through tiles of :data:`TILE` values held in small buffers, in unit-stride loops over
slices that LLVM turns into SIMD code. Only the sums of squares may be reassociated
(:func:`_square_sum`): the differences of pulse times cancel all but a few digits (seconds of
record, nanoseconds of jitter), so they are evaluated exactly as NumPy writes them.
"""

from __future__ import annotations

import numpy as np
from numba import njit

#: Values per tile (the buffers stay in the L1 data cache).
TILE = 1024


@njit(cache=True, nogil=True, fastmath={"reassoc", "nsz"})
def _square_sum(e: np.ndarray, n: int) -> float:  # pragma: no cover - compiled
    """Σ e[i]², i < n, in any order (SIMD partial sums)."""
    s = 0.0
    for i in range(n):
        s += e[i] * e[i]
    return s


@njit(cache=True, nogil=True)
def jitter_square_sum(
    x: np.ndarray, m: int, same_line: bool
) -> tuple[float, int]:  # pragma: no cover - compiled
    """Σ E_j² and the number of terms: E_j = D_{j+3} − 3D_{j+2} + 3D_{j+1} − D_j with D_j =
    x_{j+2m} − 2x_{j+m} + x_j (same line), or D_j = x_j (along the pulses)."""
    reach = 2 * m if same_line else 0
    count = x.size - reach - 3
    if count <= 0:
        return 0.0, 0
    d = np.empty(TILE + 3)
    e = np.empty(TILE)
    s = 0.0
    for j0 in range(0, count, TILE):
        n = min(TILE, count - j0)
        if same_line:
            x0 = x[j0 : j0 + n + 3]
            x1 = x[j0 + m : j0 + m + n + 3]
            x2 = x[j0 + 2 * m : j0 + 2 * m + n + 3]
            for i in range(n + 3):
                d[i] = x2[i] - 2.0 * x1[i] + x0[i]
            dd = d
        else:
            dd = x[j0 : j0 + n + 3]
        d0, d1, d2, d3 = dd[0:n], dd[1 : n + 1], dd[2 : n + 2], dd[3 : n + 3]
        for i in range(n):
            e[i] = d3[i] - 3.0 * d2[i] + 3.0 * d1[i] - d0[i]
        s += _square_sum(e, n)
    return s, count


@njit(cache=True, nogil=True, error_model="numpy")
def block_rates(
    t: np.ndarray, a: np.ndarray, nom: np.ndarray, average: int, blocks: int, both: bool
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:  # pragma: no cover - compiled
    """Per block of ``average`` intervals: the mean interval centre, the mean of the rates
    Δa/Δt, and of Δnom/Δt when ``both``."""
    t_avg = np.empty(blocks)
    rate = np.empty(blocks)
    rate_nom = np.empty(blocks) if both else rate
    per_tile = max(1, TILE // average)  # blocks per tile
    w = per_tile * average
    centre = np.empty(w)
    r = np.empty(w)
    rn = np.empty(w)
    for b0 in range(0, blocks, per_tile):
        nb = min(per_tile, blocks - b0)
        i0 = b0 * average
        n = nb * average
        ta, tb = t[i0 : i0 + n], t[i0 + 1 : i0 + n + 1]
        aa, ab = a[i0 : i0 + n], a[i0 + 1 : i0 + n + 1]
        for i in range(n):  # the intervals' centres and rates (SIMD)
            dt = tb[i] - ta[i]
            centre[i] = ta[i] + 0.5 * dt
            r[i] = (ab[i] - aa[i]) / dt
        if both:
            na, nb_ = nom[i0 : i0 + n], nom[i0 + 1 : i0 + n + 1]
            for i in range(n):
                rn[i] = (nb_[i] - na[i]) / (tb[i] - ta[i])
        for b in range(nb):  # each block's sums in order
            st = 0.0
            sr = 0.0
            sn = 0.0
            for i in range(b * average, (b + 1) * average):
                st += centre[i]
                sr += r[i]
                if both:
                    sn += rn[i]
            t_avg[b0 + b] = st / average
            rate[b0 + b] = sr / average
            if both:
                rate_nom[b0 + b] = sn / average
    return t_avg, rate, rate_nom
