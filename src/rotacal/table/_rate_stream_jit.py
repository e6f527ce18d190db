"""Numba twins of the per-pulse loops of the streamed rate analysis (imports Numba).

Imported only for long records (:func:`rotacal._jit.use_numba`), compiled on first use and cached
on disk: the same arithmetic per pulse as the NumPy code of :class:`rotacal.table.rate_jitter.
JitterSums` and :class:`rotacal.table.rate_stream._RatePoints`, in one pass without temporaries;
sums are taken in another order (≤ 1e-12 relative, the tests run both).
"""

from __future__ import annotations

import numpy as np
from numba import njit


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
    s = 0.0
    for j in range(count):
        if same_line:
            d0 = x[j + 2 * m] - 2.0 * x[j + m] + x[j]
            d1 = x[j + 1 + 2 * m] - 2.0 * x[j + 1 + m] + x[j + 1]
            d2 = x[j + 2 + 2 * m] - 2.0 * x[j + 2 + m] + x[j + 2]
            d3 = x[j + 3 + 2 * m] - 2.0 * x[j + 3 + m] + x[j + 3]
        else:
            d0, d1, d2, d3 = x[j], x[j + 1], x[j + 2], x[j + 3]
        e = d3 - 3.0 * d2 + 3.0 * d1 - d0
        s += e * e
    return s, count


@njit(cache=True, nogil=True)
def block_rates(
    t: np.ndarray, a: np.ndarray, nom: np.ndarray, average: int, blocks: int, both: bool
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:  # pragma: no cover - compiled
    """Per block of ``average`` intervals: the mean interval centre, the mean of the rates
    Δa/Δt, and of Δnom/Δt when ``both``."""
    t_avg = np.empty(blocks)
    rate = np.empty(blocks)
    rate_nom = np.empty(blocks) if both else rate
    for b in range(blocks):
        i0 = b * average
        st = 0.0
        sr = 0.0
        sn = 0.0
        for i in range(i0, i0 + average):
            dt = t[i + 1] - t[i]
            st += t[i] + 0.5 * dt
            sr += (a[i + 1] - a[i]) / dt
            if both:
                sn += (nom[i + 1] - nom[i]) / dt
        t_avg[b] = st / average
        rate[b] = sr / average
        if both:
            rate_nom[b] = sn / average
    return t_avg, rate, rate_nom
