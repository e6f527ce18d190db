"""Numba twin of :func:`rotacal.signal._residual.residual_sums` (private; imports Numba).

Imported only when a record is long enough (:func:`rotacal._jit.use_numba`); compiled on first
use and cached on disk. Per sample it does what ``harmonic_series`` does per array: cos and sin of
θ = ωτ, the harmonics by the angle-addition recurrence with the exact cos/sin recomputed every 8
harmonics, the terms added in the same order (const, then a_h·cos, b_h·sin for h = 1..H, then
D·τ); only the order of the final sum over samples differs (≤ 1e-12 relative).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

_PART = 4096


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
    """Residual sums of squares of the models (rows of ``ca``/``cb``) over the samples."""
    n_models = consts.size
    nh = ca.shape[1]
    out = np.zeros(n_models)
    part = np.zeros(n_models)
    model = np.empty(n_models)
    for i in range(t.size):
        if i % _PART == 0:
            # partial sums of _PART samples keep the rounding of the long sum small
            for m in range(n_models):
                out[m] += part[m]
                part[m] = 0.0
        tau = t[i] - t_ref
        theta = omega * tau
        c1 = math.cos(theta)
        s1 = math.sin(theta)
        for m in range(n_models):
            model[m] = consts[m]
        ch = c1
        sh = s1
        for k in range(nh):
            hk = k + 1
            if hk > 1:
                if hk % 8 == 0:
                    ch = math.cos(hk * theta)
                    sh = math.sin(hk * theta)
                else:
                    ch, sh = ch * c1 - sh * s1, sh * c1 + ch * s1
            for m in range(n_models):
                model[m] = model[m] + ca[m, k] * ch
                model[m] = model[m] + cb[m, k] * sh
        for m in range(n_models):
            val = model[m]
            if drifts[m] != 0.0:
                val = val + drifts[m] * tau
            r = y[i] - val
            part[m] += r * r
    for m in range(n_models):
        out[m] += part[m]
    return out
