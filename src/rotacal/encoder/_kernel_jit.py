"""Numba twin of the per-sample encoder chain in :mod:`rotacal.encoder._kernel` (imports Numba).

Imported only for long captures (:func:`rotacal._jit.use_numba`), compiled on first use and cached
on disk. Per sample it does, in the same floating-point operations and order, what the NumPy path
does per array: the Heydemann correction of ``_apply``, ``arctan2``, the integer cycle count of
``unwrapped_phase``, the subinterval count of ``subinterval_transitions`` and the extremes of φ.
Only ``atan2`` may differ from NumPy's by an ulp (libm against NumPy's own loop).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit


@njit(cache=True, nogil=True)
def phase_block(
    a: np.ndarray,
    b: np.ndarray,
    coefs: np.ndarray,
    carry: np.ndarray,
    has_prev: bool,
    offset: int,
    phase: np.ndarray,
    trans_idx: np.ndarray,
    trans_k: np.ndarray,
) -> int:  # pragma: no cover - compiled
    """One block: φ into ``phase``, transitions into ``trans_idx``/``trans_k``; returns their count.

    ``coefs = [p, q, 1/R_a, 1/(R_b·cos α), tan α, α ≠ 0, 2π, 1/(π/6), π]``;
    ``carry = [last wrapped phase, cycles, k of the last sample, min φ, max φ]`` is read (when
    ``has_prev``) and updated in place.
    """
    p = coefs[0]
    q = coefs[1]
    inv_ra = coefs[2]
    inv_rb = coefs[3]
    tan_a = coefs[4]
    tilted = coefs[5] != 0.0
    two_pi = coefs[6]
    inv_sub = coefs[7]
    pi = coefs[8]
    last = carry[0]
    cycles = np.int64(carry[1])
    k_prev = carry[2]
    lo = carry[3]
    hi = carry[4]
    count = 0
    for i in range(a.size):
        u = (a[i] - p) * inv_ra
        v = (b[i] - q) * inv_rb
        if tilted:
            v = v - u * tan_a
        w = math.atan2(v, u)
        if has_prev or i > 0:
            d = w - last
            if d < -pi:
                cycles += 1
            elif d > pi:
                cycles -= 1
        last = w
        ph = np.float64(cycles) * two_pi + w
        phase[i] = ph
        k = np.floor(ph * inv_sub)
        if (has_prev or i > 0) and k != k_prev:
            trans_idx[count] = offset + i
            trans_k[count] = k
            count += 1
        k_prev = k
        if ph < lo:
            lo = ph
        if ph > hi:
            hi = ph
    carry[0] = last
    carry[1] = np.float64(cycles)
    carry[2] = k_prev
    carry[3] = lo
    carry[4] = hi
    return count
