"""Residual sums of squares of fitted harmonic series over the samples, in one pass (private).

When the normal equations cannot resolve a fit's residual (``yᵀy − bᵀp`` is rounding), it is
summed from the samples. Several models at one frequency (the fit and its drift check) share the
cosines and sines, so they are summed together, over cache-sized chunks (NumPy) or sample by
sample (the Numba twin in :mod:`rotacal.signal._residual_jit`, for long records).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from rotacal._jit import use_numba
from rotacal.signal._result import harmonic_series_many

#: Samples per chunk of the NumPy path: the cosines, sines and model of a chunk stay in cache.
_CHUNK = 1 << 14


def residual_sums(
    t: np.ndarray,
    y: np.ndarray,
    t_ref: float,
    frequency_hz: float,
    models: Sequence[tuple[float, np.ndarray, np.ndarray, float]],
    *,
    jit: bool | None = None,
) -> list[float]:
    """``Σ (y − model)²`` for each model ``const + Σ_h a_h cos(hωτ) + b_h sin(hωτ) + D·τ``.

    Parameters
    ----------
    t : ndarray
        Sample times (s).
    y : ndarray
        Samples (unit of y).
    t_ref : float
        Reference time τ = 0 of the models (s).
    frequency_hz : float
        Fundamental f (Hz); ω = 2πf.
    models : sequence of (const, a, b, D)
        Offset (unit of y), cosine and sine coefficients of harmonics 1..H (unit of y) and drift
        D (unit of y per s).
    jit : bool, optional
        Force the Numba twin (True) or the NumPy path (False); default: by the record's size
        (:func:`rotacal._jit.use_numba`).

    Returns
    -------
    list of float
        One residual sum of squares per model (unit of y squared).

    References
    ----------
    IEEE Std 1057-2017, §4.1.3 (the residual of the sine fits, from which s² = RSS/(N − p));
    Feng et al. 2023, Sensors 23:4876, eq. (9) (the multi-harmonic model).
    """
    omega = 2.0 * math.pi * frequency_hz
    if len(models) <= 2 and use_numba(t.size, jit):
        from rotacal.signal._residual_jit import residual_sums_grid, residual_sums_jit

        consts = np.array([float(m[0]) for m in models])
        ca = np.array([np.asarray(m[1], dtype=np.float64) for m in models])
        cb = np.array([np.asarray(m[2], dtype=np.float64) for m in models])
        drifts = np.array([float(m[3]) for m in models])
        if t.size > 1:  # on a uniform grid: the table of cos/sin (falls back when off the grid)
            dt = (float(t[-1]) - float(t[0])) / (t.size - 1)
            out, on_grid = residual_sums_grid(
                t, y, float(t_ref), omega, dt, consts, ca, cb, drifts
            )
            if on_grid:
                return [float(x) for x in out]
        out = residual_sums_jit(t, y, float(t_ref), omega, consts, ca, cb, drifts)
        return [float(x) for x in out]
    sums = [0.0] * len(models)
    series = [(np.asarray(ca_i), np.asarray(cb_i), const) for const, ca_i, cb_i, _ in models]
    for s in range(0, t.size, _CHUNK):
        tau = t[s : s + _CHUNK] - t_ref
        ys = y[s : s + _CHUNK]
        for i, model in enumerate(harmonic_series_many(omega * tau, series)):
            drift = models[i][3]
            if drift:
                model += drift * tau
            r = ys - model
            sums[i] += float(r @ r)
    return sums
