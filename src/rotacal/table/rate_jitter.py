"""White timing noise of a pulse train, estimated from the train itself (GUM §4.2, Type A;
Kokuyama et al. 2015, §3 and §5)."""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

from rotacal.encoder.pulses import (
    check_pulses_per_rev,
)
from rotacal.errors import CaptureError

__all__ = ["timing_jitter"]

FloatArray = NDArray[np.float64]

#: Difference filters of the timing-jitter estimate: across revolutions (the same line, so the
#: graduation cancels) and along the pulses (removes the table's slow rate changes).
_REV_FILTER = np.array([1.0, -2.0, 1.0])
_PULSE_FILTER = np.array([1.0, -3.0, 3.0, -1.0])


def _rho(h: FloatArray) -> FloatArray:
    """Autocorrelation of white noise filtered by ``h``, lags −(r−1) … r−1."""
    r = np.correlate(h, h, mode="full")
    return r / r[h.size - 1]


def _dof_of_mean_square(n: int, lags: NDArray[np.int64], rho: FloatArray) -> float:
    """Degrees of freedom 2·E²/Var of the mean of n squared Gaussian values whose correlation is
    ``rho`` at ``lags``: n²/Σ_ℓ (n − |ℓ|)·ρ(ℓ)² (only pairs within the series count)."""
    weight = np.maximum(n - np.abs(lags), 0).astype(np.float64)
    return float(n) ** 2 / float(np.sum(weight * rho**2))


#: Filtered values per block of :func:`_same_line_mean_square` (blocks added exactly).
_JITTER_BLOCK = 1 << 16


def _same_line_mean_square(t: FloatArray, m: int) -> tuple[int, float]:
    """Number and mean square of E_j = D_{j+3} − 3D_{j+2} + 3D_{j+1} − D_j, D_j = t_{j+2m} −
    2t_{j+m} + t_j (s²), block by block: no record-long temporaries."""
    count = t.size - 2 * m - (_PULSE_FILTER.size - 1)
    parts = []
    for start in range(0, count, _JITTER_BLOCK):
        stop = min(start + _JITTER_BLOCK, count) + _PULSE_FILTER.size - 1  # D's this block needs
        d = t[start + 2 * m : stop + 2 * m] - 2.0 * t[start + m : stop + m] + t[start:stop]
        e = d[3:] - 3.0 * d[2:-1] + 3.0 * d[1:-2] - d[:-3]
        parts.append(float(np.dot(e, e)))
    return count, math.fsum(parts) / count


def timing_jitter(times_s: ArrayLike, pulses_per_rev: int) -> tuple[float, float, bool]:
    """Standard deviation of the white timing noise of a pulse train, from the train itself.

    With two whole revolutions and a few pulses to spare, the same line one and two revolutions
    later gives D_j = t_{j+2m} − 2t_{j+m} + t_j, in which the scale's graduation error cancels
    exactly (m pitches are 360° from any line) and the mean rate drops out; a third difference
    along the pulses, E_j = D_{j+3} − 3D_{j+2} + 3D_{j+1} − D_j, then suppresses the table's
    slow rate changes by (2π·f/f_pulse)³. White timing noise of variance σ_t² gives
    E[E_j²] = Σh²·σ_t² with Σh² = 6·20 = 120. Shorter trains use the third difference along the
    pulses alone, which also holds the graduation error (an upper bound, flagged by the third
    return value).

    Parameters
    ----------
    times_s : array_like, s
        Pulse times of one head (or the head-averaged times of a set of heads).
    pulses_per_rev : int
        m.

    Returns
    -------
    sigma_t : float, s
        Estimated standard deviation of the timing noise of one pulse time.
    dof : float
        Its degrees of freedom, n²/Σ_ℓ (n − |ℓ|)·ρ(ℓ)² for n differences with autocorrelation ρ
        (the filtered values are correlated; Bartlett 1946) — only the pairs inside the series
        count, which matters when it is shorter than the lag 2m of the same-line difference.
    graduation_free : bool
        True when the graduation cancelled (two revolutions available).

    Raises
    ------
    CaptureError
        Fewer than 8 pulses.

    References
    ----------
    JCGM 100:2008 (GUM) §4.2 (Type A evaluation); Kokuyama et al. (2015) §3, the head output
    s_i(k) = kΔθ + 360i/n + a_i(k), a(k) periodic in k with period m, and §5 ("nearly-white
    electronic noise in the encoder output signals"); M. S. Bartlett, "On the theoretical
    specification of sampling properties of autocorrelated time series", J. R. Stat. Soc. Suppl.
    8 (1946) — the variance of a variance estimate from correlated values.
    """
    t = np.asarray(times_s, dtype=np.float64)
    m = check_pulses_per_rev(pulses_per_rev)
    h = _PULSE_FILTER
    if t.size >= 2 * m + 2 * h.size:
        count, mean_square = _same_line_mean_square(t, m)
        norm = float(np.sum(_REV_FILTER**2) * np.sum(h**2))
        # the same-line difference correlates values m and 2m apart, the pulse filter 1 … 3
        lag_r = (np.arange(_REV_FILTER.size * 2 - 1) - (_REV_FILTER.size - 1)) * m
        lag_p = np.arange(h.size * 2 - 1) - (h.size - 1)
        lags = (lag_r[:, None] + lag_p[None, :]).ravel()
        rho = np.outer(_rho(_REV_FILTER), _rho(h)).ravel()
        dof = _dof_of_mean_square(count, lags, rho)
        exact = True
    elif t.size >= 2 * h.size:
        e = np.convolve(t, h[::-1], mode="valid")
        mean_square = float(np.mean(e * e))
        norm = float(np.sum(h**2))
        dof = _dof_of_mean_square(e.size, np.arange(h.size * 2 - 1) - (h.size - 1), _rho(h))
        exact = False
    else:
        raise CaptureError(
            f"{t.size} pulses are too few to estimate the timing noise; record more."
        )
    sigma = math.sqrt(mean_square / norm)
    return sigma, dof, exact
