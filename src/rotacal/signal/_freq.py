"""Start value of the fundamental frequency (private; public wrapper in ``sinefit``)."""

from __future__ import annotations

import math

import numpy as np

from rotacal.errors import CaptureError
from rotacal.signal._checks import MIN_PERIODS

_FFT_POINTS = 1 << 16
_PAD_POINTS = 1 << 18
_DEC_POINTS = 1 << 20
_LS_POINTS = 4096
_LS_MAX_PERIODS = 64.0


def _block_mean(x: np.ndarray, d: int) -> np.ndarray:
    if d <= 1:
        return x
    nb = x.size // d
    return x[: nb * d].reshape(nb, d).mean(axis=1)


def _fft_peak(y: np.ndarray, dt: float) -> float:
    """Frequency (Hz) of the largest spectral peak, interpolated on the log spectrum.

    The record is treated as uniformly sampled with step ``dt``; bins of less than half a
    period in the record are ignored (they are the offset and drift).
    """
    n = y.size
    x = y - y.mean()
    x = x * np.hanning(n) if n >= 64 else x
    # zero-padded 8x for the interpolation, but not past _PAD_POINTS unless the record needs
    # more (then 2x): a start value within ~1e-3 bin leaves the fit's steps unchanged, and the
    # 2^21-point transform of 160,000 block means took 30 ms
    nfft = 1 << math.ceil(math.log2(max(min(8 * n, _PAD_POINTS), 2 * n)))
    mag = np.abs(np.fft.rfft(x, nfft))
    df = 1.0 / (nfft * dt)
    lo = max(1, math.ceil(0.5 / (n * dt) / df))
    if lo >= mag.size - 1:
        raise CaptureError("the record is too short to estimate a frequency; supply more samples.")
    k = lo + int(np.argmax(mag[lo:-1]))
    if k > lo:
        la, lb, lc = np.log(mag[k - 1 : k + 2] + 1e-300)
        den = la - 2.0 * lb + lc
        delta = 0.5 * (la - lc) / den if den < 0 else 0.0
    else:
        delta = 0.0
    return (k + delta) * df


def _sine_rss(t: np.ndarray, y: np.ndarray, f: float) -> float:
    """Residual sum of squares of the best ``C + a cos + b sin`` at frequency ``f`` (Hz)."""
    th = 2.0 * math.pi * f * t
    a = np.column_stack([np.ones_like(t), np.cos(th), np.sin(th)])
    _, res, rank, _ = np.linalg.lstsq(a, y, rcond=None)
    if rank < 3 or res.size == 0:
        r = y - a @ np.linalg.lstsq(a, y, rcond=None)[0]
        return float(r @ r)
    return float(res[0])


def _ls_refine(t: np.ndarray, y: np.ndarray, f_c: float, span: float) -> float:
    """Refine ``f_c`` by minimising the single-sine residual over ±1.5 bins (Hz)."""
    tc = t - 0.5 * (t[0] + t[-1])
    yc = y - y.mean()
    nyq = 0.5 * (t.size - 1) / span
    lo = max(0.5 / span, f_c - 1.5 / span)
    hi = min(f_c + 1.5 / span, 0.9 * nyq)
    if not hi > lo:
        return f_c
    grid = np.linspace(lo, hi, 31)
    rss = np.array([_sine_rss(tc, yc, f) for f in grid])
    i = int(np.argmin(rss))
    a, b = grid[max(i - 1, 0)], grid[min(i + 1, grid.size - 1)]
    from scipy.optimize import minimize_scalar  # ~0.3 s to import: only when a fit needs it

    res = minimize_scalar(
        lambda f: _sine_rss(tc, yc, f),
        bounds=(a, b),
        method="bounded",
        options={"xatol": 1e-6 / span},
    )
    return float(res.x) if res.fun <= rss[i] else float(grid[i])


def estimate_frequency_unchecked(t: np.ndarray, y: np.ndarray) -> float:
    """Fundamental frequency (Hz) of ``y(t)``; ``t`` increasing and finite, ``y`` finite."""
    n = t.size
    if n < 8:
        raise CaptureError(
            f"the record holds {n} samples; at least 8 are needed to estimate a frequency."
        )
    span = float(t[-1] - t[0])
    dt = span / (n - 1)
    seg = min(n, _FFT_POINTS)
    f_seg = _fft_peak(y[:seg], dt)
    if seg == n:
        d, yd, f_c = 1, y, f_seg
    else:
        if f_seg * dt * seg >= 8.0:  # many periods in the first segment: a fast signal
            d = max(1, int(1.0 / (16.0 * f_seg * dt)))
            # at most _DEC_POINTS block means (~65,000 periods, from the start): their transform
            # costs as much as the fit beyond it, and a start within ~1e-3 bin of the record
            # needs no more (the fit's steps are the same)
            yd = _block_mean(y[: _DEC_POINTS * d], d)
        else:  # a slow signal: decimate the whole record by block means
            d = -(-n // _FFT_POINTS)
            yd = _block_mean(y, d)
        f_c = _fft_peak(yd, d * dt)
    if f_c * span < _LS_MAX_PERIODS:  # the block-mean times only here (a pass over t)
        td = _block_mean(t, d)
        per_period = td.size / max(f_c * span, 1e-300)
        d2 = max(1, min(-(-td.size // _LS_POINTS), int(per_period / 16.0)))
        f_c = _ls_refine(_block_mean(td, d2), _block_mean(yd, d2), f_c, span)
    periods = f_c * span * n / (n - 1)
    if periods < MIN_PERIODS:
        raise CaptureError(
            f"the strongest line ({f_c:.6g} Hz) makes only {periods:.3g} periods in the record; "
            "a frequency estimate needs at least ~1 period: supply a longer record."
        )
    return f_c
