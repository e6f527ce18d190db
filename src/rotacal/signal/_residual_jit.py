"""Numba twin of :func:`rotacal.signal._residual.residual_sums` (private; imports Numba).

Imported only when a record is long enough (:func:`rotacal._jit.use_numba`); compiled on first
use and cached on disk. Per sample: θ = ω·(t − t_ref) as the NumPy path forms it; cos θ and sin θ
exactly every :data:`_RESYNC` samples and in between by rotating the previous pair through
δ = θᵢ − θᵢ₋₁ (exact by Sterbenz's lemma while θ keeps its sign within a factor 2), with cos δ and
sin δ from their Taylor series to δ⁹ (the next term below 3·10⁻¹⁷ for |δ| ≤ 0.1 rad; a larger
step takes the exact functions); the harmonics by the angle-addition recurrence; the terms added
in the NumPy path's order. The rotation rounds by about an ulp per step, so the residual sums
agree with the NumPy path's to ≤ 1e-12 relative, not to the bit.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

#: Samples between exact cos/sin (the rotation's rounding walks ~√n ulps in between).
_RESYNC = 64
#: Partial sums of this many samples keep the rounding of the long sum small.
_PART = 4096
#: Largest step δ (rad) rotated with the Taylor series.
_MAX_STEP = 0.1


@njit(cache=True, nogil=True, inline="always")
def _cos_sin(theta: float, theta_prev: float, c1: float, s1: float, exact: bool) -> tuple:
    """cos θ and sin θ: exact, or the previous pair rotated through δ = θ − θ_prev."""
    d = theta - theta_prev
    if exact or abs(d) > _MAX_STEP:
        return math.cos(theta), math.sin(theta)
    d2 = d * d
    cd = 1.0 - d2 / 2.0 * (1.0 - d2 / 12.0 * (1.0 - d2 / 30.0 * (1.0 - d2 / 56.0)))
    sd = d * (1.0 - d2 / 6.0 * (1.0 - d2 / 20.0 * (1.0 - d2 / 42.0 * (1.0 - d2 / 72.0))))
    return c1 * cd - s1 * sd, s1 * cd + c1 * sd


@njit(cache=True, nogil=True)
def residual_sums_jit(
    t: np.ndarray,
    y: np.ndarray,
    t_ref: float,
    omega: float,
    consts: np.ndarray,
    ca: np.ndarray,
    cb: np.ndarray,
    drifts: np.ndarray,
) -> np.ndarray:  # pragma: no cover - compiled
    """Residual sums of squares of one or two models (rows of ``ca``/``cb``) over the samples.

    With one model the second row repeats the first (its sum is discarded by the caller); the
    two models are kept in scalars so that they stay in registers.
    """
    nh = ca.shape[1]
    two = consts.size > 1
    j = 1 if two else 0
    ca0, cb0, ca1, cb1 = ca[0], cb[0], ca[j], cb[j]
    const0, const1 = consts[0], consts[j]
    drift0, drift1 = drifts[0], drifts[j]
    out0 = 0.0
    out1 = 0.0
    part0 = 0.0
    part1 = 0.0
    c1 = 1.0
    s1 = 0.0
    theta_prev = 0.0
    for i in range(t.size):
        tau = t[i] - t_ref
        theta = omega * tau
        c1, s1 = _cos_sin(theta, theta_prev, c1, s1, i % _RESYNC == 0)
        theta_prev = theta
        if i % _PART == 0:
            out0 += part0
            out1 += part1
            part0 = 0.0
            part1 = 0.0
        m0 = const0
        m1 = const1
        ch = c1
        sh = s1
        for k in range(nh):
            if k > 0:
                ch, sh = ch * c1 - sh * s1, sh * c1 + ch * s1
            m0 = m0 + ca0[k] * ch
            m0 = m0 + cb0[k] * sh
            m1 = m1 + ca1[k] * ch
            m1 = m1 + cb1[k] * sh
        if drift0 != 0.0:
            m0 = m0 + drift0 * tau
        if drift1 != 0.0:
            m1 = m1 + drift1 * tau
        r0 = y[i] - m0
        r1 = y[i] - m1
        part0 += r0 * r0
        part1 += r1 * r1
    out = np.empty(consts.size)
    out[0] = out0 + part0
    if two:
        out[1] = out1 + part1
    return out
