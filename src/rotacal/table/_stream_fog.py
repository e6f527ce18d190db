"""The FOG scheme's passes of the chunked calibration (Feng et al. 2023, §4, eqs. (9)–(14)) (private).

After the checks (:mod:`rotacal.table._stream_checks`):

- the multi-harmonic fit of the whole capture's rate (eqs. (9)–(10)), its normal equations
  accumulated over the chunks, from a start frequency of the first samples or a strided copy;
- the zero crossings of that fitted rate (the reversing moments), each between two samples of
  one chunk or across a boundary (the last sample of the chunk before carried);
- after the analysis fit of n whole periods (:mod:`rotacal.table._stream_fit`), the angle
  integrated from the measured rate less D0 by the trapezoid rule — each chunk's own running
  sum plus a prefix, the angle at the chunk before's last sample (the in-memory cumsum's steps;
  rounding differs by the prefix's one add, ~1e-16 relative, and a chunk's angle needs only its
  prefix: :mod:`rotacal.batch.capture_fog` splits it so) —, its mean, the SNR's sums (Feng et
  al. 2023, §5), decimated copies, and eq. (2)'s three-parameter fit accumulated beside.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Iterator

import numpy as np

from rotacal.signal import SineFit, displacement_amplitudes_from_rate
from rotacal.signal._result import harmonic_series
from rotacal.table._stream_checks import Checked, start_frequency
from rotacal.table._stream_fit import (
    Fed,
    Segment,
    SegmentFit,
    accumulate,
    accumulator,
    block_length,
    decimate,
    fit_segment,
    position_error_pass,
    with_segment,
)
from rotacal.table._stream_source import Passes
from rotacal.table.motion import MotionResult, _finish, _plot_stride
from rotacal.table.motion_lts_fog import (
    fog_angle,
    fog_angle_steps,
    fog_bias_note,
    model_zero_crossings,
)
from rotacal.table.motion_uncertainty import ReversalDetection
from rotacal.uncertainty import InstrumentSpecs

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
        chunk_crossings(fit, t, off, t_before, times, indices)
        t_before = float(t[-1])
    return np.concatenate(times), np.clip(np.concatenate(indices), 0, n - 1)


def chunk_crossings(
    fit: SineFit,
    t: np.ndarray,
    off: int,
    t_before: float | None,
    times: list[np.ndarray],
    indices: list[np.ndarray],
) -> None:
    """The zero crossings of the fitted rate among the chunk's times ``t`` (s; first global
    index ``off``) and between ``t_before`` (the chunk before's last time, None for the first
    chunk) and ``t[0]``, appended to ``times`` and (unclipped sample indices) ``indices``."""
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


def piece_angle(
    t: np.ndarray,
    w: np.ndarray,
    fit: SineFit,
    before: tuple[float, float] | None,
    prefix: float,
) -> np.ndarray:
    """The angle (deg) of one piece of the segment: ``prefix`` (the angle at the piece before's
    last sample) plus the running sum of the trapezoid steps of the rate less the fitted D0 (or
    D0 + D1·τ) from that sample (``before``: its t, rate; None for the segment's first piece,
    whose angle starts at 0). The prefix is added to the piece's own running sum, so that a
    piece's angle needs only the prefix (Σ of the pieces' last local sums, in order) and not the
    pieces before."""
    if before is None:
        local = np.concatenate(([0.0], np.cumsum(fog_angle_steps(t, w, fit))))
    else:
        t_b, w_b = before
        local = np.cumsum(
            fog_angle_steps(np.concatenate(([t_b], t)), np.concatenate(([w_b], w)), fit)
        )
    return prefix + local


def _integrated(
    segment: Segment, fit: SineFit
) -> Iterator[tuple[int, np.ndarray, np.ndarray, np.ndarray]]:
    """``(g0, t, rate, angle)``: the angle (deg) integrated from the segment's rate less the
    fitted D0 (or D0 + D1·τ) by the trapezoid rule from 0 at its first sample, not centred
    (:func:`piece_angle`, the prefix carried from piece to piece)."""
    before: tuple[float, float] | None = None  # t, rate of the last sample
    prefix = 0.0
    for g0, t, w in segment():
        angle = piece_angle(t, w, fit, before, prefix)
        before = (float(t[-1]), float(w[-1]))
        prefix = float(angle[-1])
        yield g0, t, w, angle


def snr_sums(t: np.ndarray, w: np.ndarray, fit: SineFit) -> list[tuple[float, float]]:
    """The SNR's signal and noise sums (deg²/s², :func:`~rotacal.signal.snr_db`) of each slice
    of the rate ``w`` at ``t`` (s): the fitted AC part's squares and the residual's."""
    w_rad = 2.0 * math.pi * fit.frequency_hz
    out = []
    for s in range(0, t.size, _SLICE):
        ts, ws = t[s : s + _SLICE], w[s : s + _SLICE]
        ac = harmonic_series(w_rad * (ts - fit.t_ref_s), fit.cos_coefs, fit.sin_coefs, 0.0)
        r = ws - fit.offset - ac
        if fit.drift is not None:
            r -= fit.drift * (ts - fit.t_ref_s)
        out.append((float(ac @ ac), float(r @ r)))
    return out


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

    def with_snr() -> Iterator[tuple[int, np.ndarray, np.ndarray]]:
        nonlocal total, signal, noise
        for g0, t, w, angle in _integrated(segment, fit):
            for sig, noi in snr_sums(t, w, fit):
                signal += sig
                noise += noi
            total += float(np.sum(angle))
            dec.append(decimate(g0, first, step, angle))
            yield g0, t, angle

    if beside:
        accumulate(beside, with_snr())
    else:
        for _ in with_snr():
            pass
    return integrated(total, signal, noise, n_seg, np.concatenate(dec))


def integrated(
    total: float, signal: float, noise: float, n_seg: int, dec: np.ndarray
) -> Integrated:
    """:class:`Integrated` from the angle's sum (deg), the SNR's sums, the samples and the
    decimated angle."""
    mean = total / n_seg
    snr = math.inf if noise == 0.0 else 10.0 * math.log10(signal / noise)
    return Integrated(mean, (total - n_seg * mean) / n_seg, snr, dec - mean)


def start_frequency_of(found: Checked) -> float:
    """The FOG fit's start frequency (Hz) from the first pass's first samples, else its strided
    copy of the rate (:func:`start_frequency`)."""
    assert found.first_samples is not None and found.strided is not None
    strided = found.strided.arrays()
    return start_frequency(
        found.first_samples,
        strided,
        whole=found.strided.stride == 1 and strided[0].size == found.first_samples[0].size,
    )


def analysed(
    rates: Segment,
    span: tuple[int, int, int],
    f0: float,
    model: tuple[int, bool],
    set_values: tuple[float | None, float | None],
    to_true: Callable[[np.ndarray], np.ndarray] | None,
    dt: float | None,
) -> tuple[SegmentFit, Integrated, tuple[float, float, np.ndarray] | None]:
    """The FOG's analysis fit of the rate of samples first … last (``span``: first, last and the
    most samples gathered; ``model``: harmonics, drift; start frequency ``f0``, Hz), the
    integrated angle and, with set values (deg, Hz) and the segment not gathered, eq. (2)'s
    position error."""
    first, last, gather_max = span
    harmonics, drift = model
    set_amplitude_deg, set_frequency_hz = set_values
    seg = fit_segment(
        rates, first, last, f0, harmonics, drift, gather_max=gather_max, rate=True, dt=dt
    )
    fit = seg.fit
    acc3 = None
    if set_amplitude_deg is not None and set_frequency_hz is not None and not seg.gathered:
        acc3 = accumulator(set_frequency_hz, 1, dt)
    angle = integrate(rates, fit, first, last, [] if acc3 is None else [(acc3, to_true)])
    error = None
    if acc3 is not None and set_amplitude_deg is not None and set_frequency_hz is not None:
        # eq. (2) on the angle not centred: the fit's offset takes the mean, err is the same
        error = position_error_pass(
            angle_segment(rates, fit),
            first,
            last,
            set_amplitude_deg,
            set_frequency_hz,
            acc3=acc3,
            to_true=to_true,
        )
    return seg, angle, error


def fog_result(
    found: Checked,
    first_fit: SineFit,
    plot_rate: tuple[np.ndarray, np.ndarray],
    reversals: tuple[np.ndarray, int],
    analysed: tuple[SegmentFit, Integrated, tuple[float, float, np.ndarray] | None],
    set_values: tuple[float | None, float | None],
    specs: InstrumentSpecs | None,
    clipped: tuple[str, ...],
) -> MotionResult:
    """The FOG calibration's result from the passes' findings: the first pass's, the whole
    rate's fit and its decimated copy (t in s, rate in deg/s), the reversing moments (s) and the
    periods analysed, :func:`analysed`'s fit, angle and position error."""
    seg, angle, error = analysed
    rev_times, n_periods = reversals
    set_amplitude_deg, set_frequency_hz = set_values
    fit = seg.fit
    n, t0 = found.n, float(found.first_t)
    # gathered: the in-memory angle, whose position error _finish then takes
    angle_used = None if seg.y_used is None else fog_angle(seg.t_used, seg.y_used, fit)
    plot = {
        "t": plot_rate[0],
        "rate_deg_s": plot_rate[1],
        "t_used": seg.t_plot,
        "residual_deg_s": seg.residual_plot,
        "angle_deg_integrated": angle.angle_plot,
        "unit": "deg/s",
    }
    detection = ReversalDetection(
        method="rate_zero",
        fit=first_fit,
        sample_interval_s=float(found.last_t - found.first_t) / max(n - 1, 1),
        capture_start_s=t0,
    )
    result = _finish(
        scheme="fog",
        fit=fit,
        displacement_amplitudes=displacement_amplitudes_from_rate(fit.amplitudes, fit.frequency_hz),
        displacement_amplitudes_u=displacement_amplitudes_from_rate(
            fit.amplitudes_u, fit.frequency_hz
        ),
        offset_deg=float(np.mean(angle_used)) if angle_used is not None else angle.centred_mean_deg,
        residual_rms_deg=float(fit.residual_rms / (2.0 * math.pi * fit.frequency_hz)),
        reversal_times=rev_times,
        periods=n_periods,
        t_used=seg.t_used,
        angle_used=angle_used,
        set_amplitude_deg=set_amplitude_deg,
        set_frequency_hz=set_frequency_hz,
        notes=[fog_bias_note(fit)],
        snr=angle.snr_db,
        plot=plot,
        detection=detection,
        specs=specs,
    )
    return with_segment(result, seg, error, clipped)
