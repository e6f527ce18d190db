"""The FOG scheme's passes of the chunked calibration (Feng et al. 2023, §4, eqs. (9)–(14)) (private).

After the checks (:mod:`rotacal.table._stream_checks`):

- the multi-harmonic fit of the whole capture's rate (eqs. (9)–(10)), its normal equations
  accumulated over the chunks, from a start frequency of the first samples or a strided copy;
- the zero crossings of that fitted rate (the reversing moments), each between two samples of
  one chunk or across a boundary (the last sample of the chunk before carried);
- after the analysis fit of n whole periods (:mod:`rotacal.table._stream_fit`), the angle
  integrated from the measured rate less D0 by the trapezoid rule with the running sum carried
  (the same sums in the same order as in memory), its mean, the SNR's sums (Feng et al. 2023,
  §5), decimated copies, and eq. (2)'s three-parameter fit accumulated beside.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Iterator

import numpy as np

from rotacal.signal import SineFit
from rotacal.signal._result import harmonic_series
from rotacal.table._stream_fit import (
    Fed,
    Segment,
    accumulate,
    accumulator,
    block_length,
    decimate,
)
from rotacal.table._stream_source import Passes
from rotacal.table.motion import _plot_stride
from rotacal.table.motion_lts_fog import fog_angle_steps, model_zero_crossings

_SIGNAL = "rate_deg_s"
#: Samples a model evaluation works on at once: its ten or so work arrays stay in the cache and
#: do not grow with the chunk (2·10⁶ samples made them 160 MB).
_SLICE = 1 << 16


def rate_segment(passes: Passes, first: int, last: int) -> Segment:
    """The rate of samples ``first..last``: ``(global index of the piece's first sample, t, ω)``."""

    def pieces() -> Iterator[tuple[int, np.ndarray, np.ndarray]]:
        for _, off, cols in passes.run(first, last + 1):
            s = max(first - off, 0)
            e = min(last + 1 - off, cols[_SIGNAL].size)
            yield off + s, cols["time_s"][s:e], cols[_SIGNAL][s:e]

    return pieces


def whole_fit(
    passes: Passes, n: int, f_start: float, harmonics: int, drift: bool, dt: float | None
) -> tuple[SineFit, np.ndarray, np.ndarray]:
    """The fit of the whole capture's rate (as :func:`~rotacal.signal.fit_harmonics` from
    ``f_start``, Hz; samples ``dt`` s apart) and every _plot_stride(n)-th sample (t, rate) for the figures."""
    acc = accumulator(f_start, harmonics, dt)
    step = _plot_stride(n)
    dec_t: list[np.ndarray] = []
    dec_w: list[np.ndarray] = []
    whole = rate_segment(passes, 0, n - 1)

    def tap() -> Iterator[tuple[int, np.ndarray, np.ndarray]]:
        for g0, t, w in whole():
            dec_t.append(decimate(g0, 0, step, t))
            dec_w.append(decimate(g0, 0, step, w))
            yield g0, t, w

    accumulate([(acc, None)], tap(), block_length(f_start, harmonics, dt))
    fit = acc.fit(f_start, harmonics, True, max_iter=50, rtol=1e-12, drift=drift)
    return fit, np.concatenate(dec_t), np.concatenate(dec_w)


def zero_crossings(passes: Passes, fit: SineFit, n: int) -> tuple[np.ndarray, np.ndarray]:
    """Times (s) of :func:`~rotacal.table.motion.model_zero_crossings` over the whole capture and
    their sample index (``np.searchsorted(t, time)``, clipped to the capture), in one pass."""
    times: list[np.ndarray] = []
    indices: list[np.ndarray] = []
    t_before: float | None = None
    for _, off, cols in passes.run():
        t = cols["time_s"]
        # the pair across the boundary: the chunk before's last sample leads this one
        local = t if t_before is None else np.concatenate(([t_before], t))
        start = off if t_before is None else off - 1
        # slices sharing their last sample with the next: every pair of samples in one slice
        for s in range(0, max(local.size - 1, 1), _SLICE):
            part = local[s : s + _SLICE + 1]
            moments, _ = model_zero_crossings(fit, part)
            times.append(moments)
            # the first sample at or after each moment, counted in this chunk (the one after the
            # chunk's last sample when the moment lies beyond it, by rounding only)
            indices.append(start + s + np.searchsorted(part, moments))
        t_before = float(t[-1])
    return np.concatenate(times), np.clip(np.concatenate(indices), 0, n - 1)


def _integrated(
    segment: Segment, fit: SineFit
) -> Iterator[tuple[int, np.ndarray, np.ndarray, np.ndarray]]:
    """``(g0, t, rate, angle)``: the angle (deg) integrated from the segment's rate less the
    fitted D0 (or D0 + D1·τ) by the trapezoid rule from 0 at its first sample, not centred."""
    before: tuple[float, float, float] | None = None  # t, rate, angle of the last sample
    for g0, t, w in segment():
        if before is None:
            angle = np.concatenate(([0.0], np.cumsum(fog_angle_steps(t, w, fit))))
        else:
            t_b, w_b, a_b = before
            steps = fog_angle_steps(np.concatenate(([t_b], t)), np.concatenate(([w_b], w)), fit)
            # the running sum carried as the first term: the in-memory cumsum's own order
            angle = np.cumsum(np.concatenate(([a_b], steps)))[1:]
        before = (float(t[-1]), float(w[-1]), float(angle[-1]))
        yield g0, t, w, angle


def angle_segment(segment: Segment, fit: SineFit) -> Segment:
    """The angle of :func:`_integrated` as a segment: ``(g0, t, angle)``."""

    def pieces() -> Iterator[tuple[int, np.ndarray, np.ndarray]]:
        for g0, t, _, angle in _integrated(segment, fit):
            yield g0, t, angle

    return pieces


@dataclasses.dataclass
class Integrated:
    """What the angle pass gives: the mean angle (deg), the SNR (dB), decimated copies."""

    mean_deg: float
    centred_mean_deg: float  # the mean of angle − mean_deg (rounding only)
    snr_db: float
    angle_plot: np.ndarray  # every _plot_stride-th sample of the centred angle


def integrate(
    segment: Segment,
    fit: SineFit,
    first: int,
    last: int,
    beside: list[Fed],
) -> Integrated:
    """One pass over the segment: the angle, its mean, the SNR's signal and noise sums (as
    :func:`~rotacal.signal.snr_db`) and a decimated copy; ``beside`` accumulators are fed
    ``(t, angle)`` (eq. (2)'s three-parameter fit)."""
    n_seg = last + 1 - first
    step = _plot_stride(n_seg)
    total = 0.0
    signal = noise = 0.0
    dec: list[np.ndarray] = []
    w_rad = 2.0 * math.pi * fit.frequency_hz

    def with_snr() -> Iterator[tuple[int, np.ndarray, np.ndarray]]:
        nonlocal total, signal, noise
        for g0, t, w, angle in _integrated(segment, fit):
            for s in range(0, t.size, _SLICE):
                ts, ws = t[s : s + _SLICE], w[s : s + _SLICE]
                ac = harmonic_series(w_rad * (ts - fit.t_ref_s), fit.cos_coefs, fit.sin_coefs, 0.0)
                r = ws - fit.offset - ac
                if fit.drift is not None:
                    r -= fit.drift * (ts - fit.t_ref_s)
                signal += float(ac @ ac)
                noise += float(r @ r)
            total += float(np.sum(angle))
            dec.append(decimate(g0, first, step, angle))
            yield g0, t, angle

    if beside:
        accumulate(beside, with_snr())
    else:
        for _ in with_snr():
            pass
    mean = total / n_seg
    snr = math.inf if noise == 0.0 else 10.0 * math.log10(signal / noise)
    return Integrated(mean, (total - n_seg * mean) / n_seg, snr, np.concatenate(dec) - mean)
