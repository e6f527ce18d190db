"""Checks of the pulses per revolution a self-calibration is given: the period of the data
(autocorrelation of the head differences or of one head's angle error) and, with three or more
heads, the closure of the fit under other counts (Kokuyama et al. 2015, §3)."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from rotacal.encoder.selfcal_fit import _data_shifts, _gls, _parseval_ss
from rotacal.errors import CaptureError

FloatArray = NDArray[np.float64]

__all__ = ["check_period"]

#: Correlation thresholds of the pulses-per-revolution check (see check_period).
_PERIODIC = 0.8


def fast_length(n: int) -> int:
    """The least 5-smooth number (2^a·3^b·5^c) ≥ n: what ``scipy.fft.next_fast_len(n,
    real=True)`` gives, without importing scipy.fft (0.2 s, numpy.f2py with it) in every rate
    and self-calibration command."""
    best = 1
    while best < n:
        best *= 2
    p5 = 1
    while p5 < 2 * best:
        p35 = p5
        while p35 < 2 * best:
            p = p35
            while p < n:  # the least power of two times p35 that reaches n
                p *= 2
            best = min(best, p)
            p35 *= 3
        p5 *= 5
    return best


def _autocorrelation(x: FloatArray, lags: int) -> FloatArray:
    """Σ_i x_i·x_{i+ℓ} for ℓ = 0 … lags − 1, by a zero-padded FFT of a fast length ≥ 2N.

    The spectrum's power is formed in place: the whole-record FFT is the largest array of a
    long capture, and a power of two ≥ 2N was up to 4N long with a product array beside it.
    NumPy's FFT is the same pocketfft as scipy.fft's (equal to the bit at these lengths).
    """
    size = fast_length(2 * x.size)
    f = np.fft.rfft(x, size)
    power = f.real**2
    power += f.imag**2
    del f
    return np.asarray(np.fft.irfft(power, size)[:lags], dtype=np.float64)


def check_period(signal: FloatArray, m: int, *, coarse: bool = True) -> bool:
    """Refuse a pulses-per-revolution that contradicts the period of the deviation.

    ``signal`` is indexed by head-0 pulse (the head-averaged difference ≈ −a(j), or a single
    head's angle error). A scale's deviation repeats once per revolution, so when the signal is
    strongly periodic its correlation at lag m must be about as high as at its best lag. A
    deviation dominated by order k also repeats at m/k: that alone is no fault, so only a lag m
    that is clearly worse than the best is refused. Records too short to reach lag m are not
    judged here (the closure test of :func:`self_calibrate` covers them). ``coarse=False`` keeps
    only the test of the sharp spike the random graduation errors leave at one revolution: for a
    single head, whose angle error also holds the table's (smooth) rate fluctuation.

    Returns True when the data confirm m (a strong correlation or a graduation spike at lag m),
    False when they cannot (a record too short to reach lag m, a deviation too weak).
    """
    x = signal - signal.mean()
    n = x.size
    # lags from m/8 up to what leaves a quarter of the record (or of m) overlapping
    lo, hi = max(2, m // 8), n - max(m // 4, n // 4)
    if not lo <= m <= hi:
        return False
    acf = _autocorrelation(x, hi + 1)
    c2 = np.cumsum(x**2)
    lags = np.arange(lo, hi + 1)
    # normalise by the energy of both overlapping parts
    head_energy = c2[n - 1 - lags]
    tail_energy = c2[-1] - np.concatenate(([0.0], c2))[lags]
    with np.errstate(invalid="ignore", divide="ignore"):
        corr = acf[lags] / np.sqrt(head_energy * tail_energy)
    corr = np.nan_to_num(corr)
    spike_at_m = _check_fine_period(corr, lags, m)
    best = float(corr.max())
    at_m = float(corr[m - lo])
    if not coarse:
        return spike_at_m
    if best < _PERIODIC or at_m >= best - 0.1:
        return spike_at_m or at_m >= _PERIODIC
    # the shortest lag at a local peak (nearly) as high as the best one: a smooth deviation
    # gives broad peaks, so the flank of a peak must not count
    from scipy.signal import find_peaks  # only to name the period found: a 1–2 s import

    peaks, _ = find_peaks(corr, height=best - 0.02, prominence=0.1)
    first = int(peaks[0]) if peaks.size else int(np.argmax(corr))
    near = slice(max(0, first - m // 20), first + m // 20 + 1)
    period = int(lags[near][np.argmax(corr[near])])
    raise CaptureError(
        f"the scale's deviation repeats every {period} pulses of head_0, not every {m} "
        f"(correlation {best:.2f} against {at_m:.2f}): check --pulses-per-rev."
    )


def _check_fine_period(corr: FloatArray, lags: NDArray[np.int64], m: int) -> bool:
    """The random graduation errors put a sharp spike on the correlation at exactly one
    revolution (and its multiples); refuse an m whose lag has none while another lag has one.
    Returns True when lag m carries such a spike (m confirmed)."""
    idx = np.arange(1, corr.size - 1)
    spike = corr[idx] - 0.5 * (corr[idx - 1] + corr[idx + 1])
    spread = 1.4826 * float(np.median(np.abs(spike - np.median(spike))))
    if spread <= 0:
        return False
    strong = np.flatnonzero(spike > 10 * spread)
    if strong.size == 0:
        return False
    found = int(lags[idx[strong[0]]])  # the shortest lag with a spike: one revolution
    pos = m - int(lags[0]) - 1
    at_m = float(spike[pos]) if 0 <= pos < spike.size else 0.0
    # at m's own lag there must be a spike of the same kind (noise alone reaches ~3 spreads)
    if found != m and at_m < 0.3 * float(spike[strong[0]]):
        raise CaptureError(
            f"the scale's graduation pattern repeats every {found} pulses of head_0, not every "
            f"{m}: check --pulses-per-rev."
        )
    return at_m > 10 * spread


def _one_revolution_closure(diff: FloatArray, m: int, rotation: str) -> float:
    """rms closure residual of the fit on the first m head-0 pulses, taking m as the period."""
    one = diff[:, :m]
    shifts = _data_shifts(one.shape[0] + 1, m, rotation, one.mean(axis=1))
    spec = np.fft.rfft(one - one.mean(axis=1, keepdims=True), axis=-1)
    _, resid = _gls(spec, shifts, m)
    return float(np.sqrt(_parseval_ss(resid, m) / one.size))


def _check_pulses_per_rev_by_closure(diff: FloatArray, m: int, *, near: bool) -> None:
    """Refuse m when another count per revolution explains the head differences far better.

    With three or more heads the model over-determines the deviation, so a wrong m (a mistyped
    count, edges counted twice) leaves a closure residual that a right one does not. Tried: m/4,
    m/3, m/2 (a multiple of the true count repeats with it, so the period tests cannot see it),
    and, when ``near``, also m ± 1…3, 2m, 3m and 4m (records too short for the period tests).
    """
    n_pulses = diff.shape[1]
    factors = (0.25, 1 / 3, 0.5, 2.0, 3.0, 4.0) if near else (0.25, 1 / 3, 0.5)
    candidates = {round(m * f) for f in factors}
    if near:
        candidates |= {m + d for d in (-3, -2, -1, 1, 2, 3)}
    heads = diff.shape[0] + 1
    candidates = {c for c in candidates if heads <= c <= n_pulses}
    if not candidates:
        return

    # judge every count in the sense that suits it best, whatever the user forced
    def closure(c: int) -> float:
        return min(_one_revolution_closure(diff, c, sense) for sense in ("forward", "reverse"))

    own = closure(m)
    scores = {c: closure(c) for c in sorted(candidates)}
    best = min(scores, key=lambda c: scores[c])
    if scores[best] < 0.5 * own:
        raise CaptureError(
            f"the head differences fit {best} pulses per revolution far better than {m} "
            f"(closure residual {scores[best]:.3g} against {own:.3g} arcsec): check "
            "--pulses-per-rev."
        )
