"""Numba twin of the sequential part of the encoder chain in :mod:`rotacal.encoder._kernel`
(imports Numba).

Imported only for long captures (:func:`rotacal._jit.use_numba`), compiled on first use and cached
on disk. The per-sample arithmetic that vectorises (the Heydemann correction and ``arctan2``)
stays in NumPy, whose SIMD ``arctan2`` is several times faster than the scalar libm ``atan2`` a
compiled loop calls (that call made the former all-Numba pass slower than NumPy); the Heydemann
correction before it is one compiled pass into reused buffers (NumPy's takes five passes and
three fresh arrays a block), and this loop does what carries state from sample to sample: the integer cycle count of ``unwrapped_phase``, the
subinterval count of ``subinterval_transitions`` and the extremes of φ, in the same
floating-point operations, so both paths give the same numbers bit for bit.
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True, nogil=True)
def correct_block(
    a: np.ndarray, b: np.ndarray, coefs: np.ndarray, tilted: bool, u: np.ndarray, v: np.ndarray
) -> None:  # pragma: no cover - compiled
    """The Heydemann correction of one block into ``u``, ``v`` in one pass: the operations of
    :func:`rotacal.encoder.heydemann.correct_quadrature` in its order (``u = (a − p)·(1/R_a)``,
    ``v = (b − q)·(1/(R_b cos α))``, then ``v −= u·tan α`` when ``tilted``), so the same bits.

    ``coefs = [p, q, 1/R_a, 1/(R_b cos α), tan α]`` (signal unit, 1/signal unit, 1).
    """
    p = coefs[0]
    q = coefs[1]
    ka = coefs[2]
    kb = coefs[3]
    ta = coefs[4]
    for i in range(a.size):
        ui = (a[i] - p) * ka
        vi = (b[i] - q) * kb
        if tilted:
            vi = vi - ui * ta
        u[i] = ui
        v[i] = vi


@njit(cache=True, nogil=True)
def phase_block(
    wrapped: np.ndarray,
    consts: np.ndarray,
    carry: np.ndarray,
    has_prev: bool,
    offset: int,
    phase: np.ndarray,
    trans_idx: np.ndarray,
    trans_k: np.ndarray,
) -> int:  # pragma: no cover - compiled
    """One block: φ into ``phase``, transitions into ``trans_idx``/``trans_k``; returns their count.

    ``wrapped`` is ``arctan2(v, u)`` of the block's corrected signals (rad);
    ``consts = [2π, 1/(π/6), π]``; ``carry = [last wrapped phase, cycles, k of the last sample,
    min φ, max φ]`` is read (when ``has_prev``) and updated in place.
    """
    two_pi = consts[0]
    inv_sub = consts[1]
    pi = consts[2]
    last = carry[0]
    cycles = np.int64(carry[1])
    k_prev = carry[2]
    lo = carry[3]
    hi = carry[4]
    count = 0
    for i in range(wrapped.size):
        w = wrapped[i]
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
