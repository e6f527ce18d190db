"""The peak of a long vector with bounded memory: its candidate elements and their denoised values.

:func:`rotacal.uncertainty.summaries.mc_budget` needs, of the vector d, only its plain peak, the
candidate elements that can hold the true extreme (|d| ≥ max|d| − Δ, Δ independent of the data),
and the vector with its noise shrunk away (Wiener) at those elements. The Wiener gain of each
order is 1 − E|noise_q|²/S_q with S_q the data's power spectrum, here Welch's estimate: the
periodograms of windows of :data:`WINDOW` elements at half-window hops, averaged, then smoothed
over ±8 orders (Welch 1967; Wiener 1949). The gain is applied to the one window that holds a
candidate in its middle half (the filter's circular wrap stays at the window's far ends). A
vector no longer than a window is one window: the whole-vector filter of
:func:`~rotacal.uncertainty.summaries.denoised` exactly.

Over a stream: :class:`WelchSums` adds the windows' periodograms in a first pass (of the vector
about a provisional reference: d = a·d₀ + b changes only order 0 beyond a factor, kept apart);
:class:`PeakCollector` finds the candidates and filters their windows in a second pass, with a
rolling buffer of one window. Both give what the whole-array functions give, to rounding.

References
----------
P. D. Welch, "The use of fast Fourier transform for the estimation of power spectra: a method
based on time averaging over short, modified periodograms", IEEE Trans. Audio Electroacoust.
15 (1967) 70–73; N. Wiener, Extrapolation, Interpolation and Smoothing of Stationary Time Series
(1949); P. Bloomfield, Fourier Analysis of Time Series, 2nd ed. (2000) §8 (smoothed periodogram).
"""

from __future__ import annotations

import dataclasses

import numpy as np
from numpy.typing import NDArray

__all__ = [
    "WINDOW",
    "PeakCollector",
    "PeakInputs",
    "WelchSums",
    "denoised_at",
    "welch_gain",
    "window_of",
    "window_starts",
]

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

#: Elements per Welch window (and per local Wiener filter).
WINDOW = 1 << 16
#: Orders the periodogram is smoothed over, either side.
SMOOTH = 8


def window_length(n: int) -> int:
    """Elements per window for a vector of n: :data:`WINDOW`, or n when shorter."""
    return min(int(n), WINDOW)


def window_starts(n: int) -> IntArray:
    """First element of every window: j·L/2, the last one ending at the vector's end."""
    size = window_length(n)
    if n <= size:
        return np.zeros(1, dtype=np.int64)
    hop = size // 2
    last = -(-(n - size) // hop)
    return np.minimum(np.arange(last + 1, dtype=np.int64) * hop, n - size)


def window_of(pos: IntArray, n: int) -> IntArray:
    """The window whose middle half holds each element (the first and last take the ends)."""
    size = window_length(n)
    p = np.asarray(pos, dtype=np.int64)
    if n <= size:
        return np.zeros(p.size, dtype=np.int64)
    hop = size // 2
    last = window_starts(n).size - 1
    return np.clip((p - size // 4) // hop, 0, last)


@dataclasses.dataclass
class WelchSums:
    """Σ of the windows' periodograms |rfft|² of a vector fed in order, windows of
    :func:`window_starts` (order 0 also as Σ X(0) and Σ X(0)², for :meth:`power`'s affine map)."""

    n: int
    size: int = 0
    power_sum: FloatArray = dataclasses.field(default_factory=lambda: np.zeros(0))
    dc_sum: float = 0.0
    dc_sq: float = 0.0
    count: int = 0
    _buffer: FloatArray = dataclasses.field(default_factory=lambda: np.zeros(0))
    _buffer_start: int = 0
    _next: int = 0  # index of the next window to take

    def __post_init__(self) -> None:
        self.size = window_length(self.n)
        self.power_sum = np.zeros(self.size // 2 + 1)
        self._starts = window_starts(self.n)

    def update(self, d: FloatArray) -> None:
        """Add the next elements of the vector."""
        buf = np.concatenate((self._buffer, d))
        end = self._buffer_start + buf.size
        while self._next < self._starts.size and self._starts[self._next] + self.size <= end:
            s = int(self._starts[self._next]) - self._buffer_start
            spec = np.fft.rfft(buf[s : s + self.size])
            self.power_sum += spec.real**2 + spec.imag**2
            self.dc_sum += float(spec[0].real)
            self.dc_sq += float(spec[0].real) ** 2
            self.count += 1
            self._next += 1
        keep = int(self._starts[self._next]) if self._next < self._starts.size else end
        keep = max(keep - self._buffer_start, 0)
        self._buffer = buf[keep:].copy()
        self._buffer_start += keep

    def power(self, scale: float = 1.0, shift: float = 0.0) -> FloatArray:
        """The Welch average of the periodograms of scale·d + shift."""
        p = scale * scale * self.power_sum
        p[0] = (
            scale * scale * self.dc_sq
            + 2.0 * scale * shift * self.size * self.dc_sum
            + self.count * (shift * self.size) ** 2
        )
        return np.asarray(p / max(self.count, 1), dtype=np.float64)


def welch_gain(
    power: FloatArray, noise_periodogram: FloatArray, smooth: int = SMOOTH
) -> FloatArray:
    """Wiener gain per order, max(0, 1 − E|noise_q|²/S_q), S_q the power smoothed over ±smooth
    orders (mirrored at the ends); order 0 (the mean) kept."""
    kernel = np.ones(2 * smooth + 1)
    padded = np.concatenate((power[smooth:0:-1], power, power[-2 : -smooth - 2 : -1]))
    s = np.convolve(padded, kernel, mode="valid") / kernel.size
    with np.errstate(divide="ignore", invalid="ignore"):
        gain = np.where(s > 0, np.clip(1.0 - noise_periodogram / s, 0.0, 1.0), 0.0)
    gain[0] = 1.0
    return np.asarray(gain, dtype=np.float64)


def _filter_window(values: FloatArray, gains: list[FloatArray]) -> list[FloatArray]:
    spec = np.fft.rfft(values)
    return [np.fft.irfft(spec * g, values.size) for g in gains]


def denoised_at(d: FloatArray, pos: IntArray, gains: list[FloatArray]) -> list[FloatArray]:
    """The vector filtered by each gain, at the elements ``pos`` (each from its own window)."""
    n = d.size
    starts = window_starts(n)
    size = window_length(n)
    which = window_of(pos, n)
    out = [np.empty(pos.size) for _ in gains]
    for j in np.unique(which).tolist():
        sel = np.flatnonzero(which == j)
        s = int(starts[j])
        for o, f in zip(out, _filter_window(d[s : s + size], gains), strict=True):
            o[sel] = f[pos[sel] - s]
    return out


@dataclasses.dataclass(frozen=True)
class PeakInputs:
    """What the peak's budget needs of the vector (see the module docstring)."""

    n: int
    plain: float
    pos: IntArray
    base: FloatArray
    denoised: list[FloatArray]


class PeakCollector:
    """Second pass over a vector of n elements: the candidates |d| ≥ ``floor`` and the
    vector filtered by each gain at them, with a rolling buffer of one window."""

    def __init__(self, n: int, floor: float, gains: list[FloatArray]) -> None:
        self.n, self.floor, self.gains = int(n), float(floor), gains
        self.size = window_length(n)
        self._starts = window_starts(n)
        self._buffer = np.zeros(0)
        self._buffer_start = 0
        self._pending: list[tuple[int, IntArray]] = []  # window, candidates in it
        self._pos: list[IntArray] = []
        self._base: list[FloatArray] = []
        self._den: list[list[FloatArray]] = [[] for _ in gains]
        self.plain = 0.0

    def update(self, d: FloatArray) -> None:
        """Add the next elements of the vector."""
        start = self._buffer_start + self._buffer.size
        a = np.abs(d)
        if a.size:
            self.plain = max(self.plain, float(a.max()))
        hit = np.flatnonzero(a >= self.floor)
        buf = np.concatenate((self._buffer, d))
        if hit.size:
            pos = hit.astype(np.int64) + start
            which = window_of(pos, self.n)
            for j in np.unique(which).tolist():
                self._pending.append((j, pos[which == j]))
        end = self._buffer_start + buf.size
        while self._pending and self._starts[self._pending[0][0]] + self.size <= end:
            j, pos = self._pending.pop(0)
            s = int(self._starts[j]) - self._buffer_start
            values = buf[s : s + self.size]
            self._pos.append(pos)
            self._base.append(values[pos - int(self._starts[j])])
            for store, f in zip(self._den, _filter_window(values, self.gains), strict=True):
                store.append(f[pos - int(self._starts[j])])
        # keep what a window not yet complete may still need
        need = end - self.size
        if self._pending:
            need = min(need, int(self._starts[self._pending[0][0]]))
        keep = max(need - self._buffer_start, 0)
        self._buffer = buf[keep:].copy()
        self._buffer_start += keep

    def result(self) -> PeakInputs:
        """The candidates (sorted), their values and denoised values, and the plain peak."""
        if self._pending:
            raise RuntimeError("the vector ended before its last window; feed all n elements.")

        def cat(parts: list[FloatArray] | list[IntArray], dtype: type) -> NDArray:
            return np.concatenate(parts).astype(dtype) if parts else np.zeros(0, dtype=dtype)

        pos = cat(self._pos, np.int64)
        order = np.argsort(pos, kind="stable")
        return PeakInputs(
            self.n,
            self.plain,
            pos[order],
            cat(self._base, np.float64)[order],
            [cat(store, np.float64)[order] for store in self._den],
        )
