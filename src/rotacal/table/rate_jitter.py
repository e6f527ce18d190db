"""White timing noise of a pulse train, estimated from the train itself (GUM §4.2, Type A;
Kokuyama et al. 2015, §3 and §5)."""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

from rotacal._jit import use_numba
from rotacal.encoder.pulses import (
    check_pulses_per_rev,
)
from rotacal.errors import CaptureError

__all__ = ["JitterSums", "timing_jitter"]

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


#: Pulses per block of :class:`JitterSums` (the 2m + 3 carried pulses are joined to each).
_JITTER_BLOCK = 1 << 18


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
    sums = JitterSums(t.size, pulses_per_rev)
    sums.update(t)
    return sums.result()


class JitterSums:
    """:func:`timing_jitter` over a stream of the n pulse times of one train, fed in order:
    the same filtered values (the last 2m + 3 pulses carried), their squares summed per chunk."""

    def __init__(self, n: int, pulses_per_rev: int, *, jit: bool | None = None) -> None:
        self.m = check_pulses_per_rev(pulses_per_rev)
        self.n = int(n)
        self.jit = use_numba(self.n, jit)
        h = _PULSE_FILTER
        if self.n >= 2 * self.m + 2 * h.size:
            self.span = 2 * self.m + h.size - 1  # pulses one filtered value reaches past its own
        elif self.n >= 2 * h.size:
            self.span = h.size - 1
        else:
            raise CaptureError(
                f"{self.n} pulses are too few to estimate the timing noise; record more."
            )
        self._tail = np.zeros(0)
        self._parts: list[float] = []
        self.count = 0

    def update(self, t: FloatArray) -> None:
        """Add the next pulse times (s), in blocks that stay in cache."""
        if self.jit:
            from rotacal.table._rate_stream_jit import jitter_square_sum

            same = self.span > _PULSE_FILTER.size - 1
            # values that start in the carried tail on it and the chunk's first `span` pulses,
            # the rest on the chunk itself (no copy of the chunk)
            for x in (np.concatenate((self._tail, t[: self.span])), t):
                total, count = jitter_square_sum(x, self.m, same)
                if count > 0:
                    self._parts.append(total)
                    self.count += count
            if t.size >= self.span:
                self._tail = t[t.size - self.span :].copy()
            else:
                x = np.concatenate((self._tail, t))
                self._tail = x[max(x.size - self.span, 0) :]
            return
        for start in range(0, t.size, _JITTER_BLOCK):
            self._update(t[start : start + _JITTER_BLOCK])

    def _update(self, t: FloatArray) -> None:
        x = np.concatenate((self._tail, t))
        if x.size > self.span:
            m = self.m
            if self.span > _PULSE_FILTER.size - 1:
                d = x[2 * m :] - 2.0 * x[m:-m] + x[: -2 * m]
                e = d[3:] - 3.0 * d[2:-1] + 3.0 * d[1:-2] - d[:-3]
            else:
                e = x[3:] - 3.0 * x[2:-1] + 3.0 * x[1:-2] - x[:-3]
            self._parts.append(float(np.dot(e, e)))
            self.count += e.size
        self._tail = x[max(x.size - self.span, 0) :].copy()

    def merge(self, other: JitterSums) -> None:
        """Add the terms another block of the same train summed (each term in one block)."""
        self._parts.append(math.fsum(other._parts))
        self.count += other.count

    def result(self) -> tuple[float, float, bool]:
        """(σ_t, its degrees of freedom, graduation-free) as :func:`timing_jitter` returns."""
        return _jitter_of(self.count, math.fsum(self._parts) / self.count, self.m, self.span > 3)


def _jitter_of(
    count: int, mean_square: float, m: int, same_line: bool
) -> tuple[float, float, bool]:
    h = _PULSE_FILTER
    if same_line:
        norm = float(np.sum(_REV_FILTER**2) * np.sum(h**2))
        # the same-line difference correlates values m and 2m apart, the pulse filter 1 … 3
        lag_r = (np.arange(_REV_FILTER.size * 2 - 1) - (_REV_FILTER.size - 1)) * m
        lag_p = np.arange(h.size * 2 - 1) - (h.size - 1)
        lags = (lag_r[:, None] + lag_p[None, :]).ravel()
        rho = np.outer(_rho(_REV_FILTER), _rho(h)).ravel()
        dof = _dof_of_mean_square(count, lags, rho)
    else:
        norm = float(np.sum(h**2))
        dof = _dof_of_mean_square(count, np.arange(h.size * 2 - 1) - (h.size - 1), _rho(h))
    return math.sqrt(mean_square / norm), dof, same_line
