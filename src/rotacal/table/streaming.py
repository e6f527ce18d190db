"""Out-of-core sinusoidal-motion calibration (Feng et al. 2023): the OSE, LTS and FOG schemes.

:func:`calibrate_encoder_motion_chunked`, :func:`calibrate_lts_motion_chunked` and
:func:`calibrate_fog_motion_chunked` give the same :class:`~rotacal.table.MotionResult` as
:func:`~rotacal.table.calibrate_encoder_motion`, :func:`~rotacal.table.calibrate_lts_motion` and
:func:`~rotacal.table.calibrate_fog_motion` (reversals to the sample, numbers to ≤ 1e-9
relative) while reading the capture chunk by chunk, so memory is set by the chunk size, not by
the capture's length. The capture is read in passes, each a fresh call of ``chunks()``
(:mod:`rotacal.table._stream_source`):

1. checks with state carried across chunks (:mod:`rotacal.table._stream_checks`): lengths,
   NaN/inf, magnitudes, time order across chunks, gaps, samples at the rails, each signal's range;
2. the scheme's own passes up to its reversing moments — the encoder's Heydemann correction,
   phase with the cycle count carried and reversals (:mod:`rotacal.table._stream_encoder`); the
   LTS's trigger levels, swings and parabolas (:mod:`rotacal.table._stream_lts`); the FOG's fit of
   the whole rate and its zero crossings (:mod:`rotacal.table._stream_fog`);
3. the fit of the n whole periods between 2n+1 reversals, normal equations accumulated over
   chunks (:class:`~rotacal.signal.HarmonicFitAccumulator`; a span of at most
   ``_GATHER_MAX_SAMPLES`` is gathered and fitted as in memory), and with set values the angular
   position error of eq. (2) (:mod:`rotacal.table._stream_fit`); the FOG's integrated angle, SNR
   and its own eq. (2) on the way.

The OSE passes' per-chunk work are functions of :mod:`rotacal.table._stream_encoder` and
:mod:`rotacal.table._stream_fit` that a Dask task calls as well
(:mod:`rotacal.batch.capture_motion`: the same calibration split over a cluster's workers).

Passes after the first stop reading after the last sample they need, and the reader's checks
(NPZ CRC-32, NaN/inf) run on the first pass only. What grows with the capture is only per-event:
the encoder's reversal candidates (the transitions are planned chunk by chunk), the reversal
windows and the decimated copies (≈ 20 000 points each); the block moments of the fit (42 numbers a
block of hundreds to thousands of samples) move to a temporary file past 8 MB: memory is flat.

References
----------
Feng R., Yan J., Wu Y., Yu N., Yin X. (2023). Methods for Comprehensive Calibration of a
Low-Frequency Angular Acceleration Rotary Table. Sensors 23, 4876, §3–§5, eqs. (1)–(15).
IEEE Std 1057-2017, §4.1.3 (sine fitting).
"""

from __future__ import annotations

import math
import os
from collections.abc import Callable, Iterator, Mapping

import numpy as np

from rotacal._threads import one_blas_thread
from rotacal.encoder import QuadratureCorrection, correct_quadrature
from rotacal.errors import ConfigError
from rotacal.table import _stream_encoder as enc
from rotacal.table import _stream_fog as fog
from rotacal.table import _stream_lts as lts
from rotacal.table._stream_checks import (
    Checked,
    check_pass,
    raise_encoder_faults,
    raise_signal_faults,
)
from rotacal.table._stream_fit import (
    Segment,
    SegmentFit,
    accumulator,
    detrended,
    fit_segment,
    position_error_pass,
    true_time,
    with_segment,
)
from rotacal.table._stream_source import (
    ENCODER_COLUMNS,
    FOG_COLUMNS,
    LTS_COLUMNS,
    ChunkSource,
    Passes,
    chunks_from_file,
)
from rotacal.table.motion import (
    MotionResult,
    _check_set_values,
    _check_settings,
    _cut,
    _finish,
    check_lts_settings,
)
from rotacal.table.motion_drift import drift_free_hysteresis
from rotacal.table.motion_lts_fog import (
    TRIGGER_PERCENTILES,
    check_reach,
    lts_angle,
    trigger_levels,
)
from rotacal.table.motion_uncertainty import ReversalDetection
from rotacal.uncertainty import InstrumentSpecs

__all__ = [
    "ChunkSource",
    "calibrate_encoder_motion_chunked",
    "calibrate_fog_motion_chunked",
    "calibrate_lts_motion_chunked",
    "encoder_chunks_from_file",
    "fog_chunks_from_file",
    "lts_chunks_from_file",
]


#: Analysed spans up to this many samples are gathered and fitted exactly as in memory (16 MB).
_GATHER_MAX_SAMPLES = 1_000_000
_TWO_PI = 2.0 * math.pi


@one_blas_thread
def calibrate_encoder_motion_chunked(
    chunks: ChunkSource,
    *,
    lines: int,
    harmonics: int = 10,
    periods: int | None = None,
    set_amplitude_deg: float | None = None,
    set_frequency_hz: float | None = None,
    correction: QuadratureCorrection | None = None,
    progress: Callable[[int], None] | None = None,
    specs: InstrumentSpecs | None = None,
    allow_clipped: bool = False,
    drift: bool = False,
    hysteresis_subintervals: int | None = None,
) -> MotionResult:
    """Sinusoidal-motion calibration from an encoder capture read in chunks (flat memory).

    The same calibration as :func:`~rotacal.table.calibrate_encoder_motion` — Heydemann-corrected
    quadrature demodulation, 12 subintervals per signal period, reversing moments by the odd/even
    trend-change rule and their precise point (eqs. (3)–(8)), n whole periods between 2n+1
    reversals, the IEEE 1057 multi-harmonic fit and THD (eq. (1)), and with set values the
    angular position error (eq. (2)) — and the same result (reversals to the sample, numbers to
    rounding), computed in five or six passes over the capture so that memory is bounded by the
    chunk size (see the module docstring).

    Parameters
    ----------
    chunks : callable
        ``chunks()`` starts a fresh pass over the capture and returns an iterator of mappings
        holding the 1-D arrays ``time_s`` (s), ``a`` and ``b`` (signal unit, e.g. V) of one chunk
        each, in time order; every call must give the same chunks. See
        :func:`encoder_chunks_from_file`.
    lines : int
        Encoder lines (signal periods) per revolution.
    harmonics : int
        N_H, highest harmonic in the fit and the THD (default 10).
    periods : int, optional
        Whole motion periods to analyse (default: all the capture holds).
    set_amplitude_deg, set_frequency_hz : float, optional
        The table's set values (deg, Hz).
    correction : QuadratureCorrection, optional
        A known correction instead of fitting one (skips that pass).
    progress : callable, optional
        Called after each chunk with the number of samples processed so far, summed over the
        passes (at most 7·N for a capture of N samples; passes 4–7 read only what they need).
    specs : InstrumentSpecs, optional
        The lab's instrument specifications (Type B inputs of the budgets, as in memory).
    allow_clipped : bool
        Analyse a capture whose a or b sits at the rails anyway (named in ``warnings``); refused
        by default. Pass 1 judges every sample (:class:`~rotacal.signal.RailDetector`, state
        carried across chunks): the same finding, and message, as in memory.
    drift : bool
        Fit a linear drift term beside the harmonics (``drift_deg_s``), as in memory; with set
        values this costs one more pass (the three-parameter fit of eq. (2) on θ less the drift).
    hysteresis_subintervals : int, optional
        The reversal rule's hysteresis (subintervals), as in memory.

    Returns
    -------
    MotionResult

    Raises
    ------
    CaptureError
        The one-line errors of the in-memory path, with sample indices counted from the start of
        the capture (NaN/inf, time not increasing — also across chunks —, clipping, signals not in
        quadrature, too few reversals), and chunks that are not mappings of equal-length 1-D
        ``time_s``, ``a``, ``b`` or that change from one pass to the next.
    ConfigError
        Bad ``lines``, ``harmonics``, ``periods`` or set values.

    References
    ----------
    Feng et al. (2023), Sensors 23:4876, §3 and eqs. (1)–(8); IEEE Std 1057-2017, §4.1.3;
    Heydemann 1981, Appl. Opt. 20:3382 (signal correction); JCGM 100:2008, JCGM 101:2008
    (budgets, :mod:`rotacal.table.motion_uncertainty`).
    """
    check_encoder_settings(lines, harmonics, periods, set_amplitude_deg, set_frequency_hz)
    passes = Passes(chunks, progress)
    scale = 360.0 / (_TWO_PI * float(lines))

    found = check_pass(passes, {"a": "b", "b": "a"})
    raise_encoder_faults(found, enc.MIN_SAMPLES)
    clipped = found.clipping(allow_clipped)
    n = found.n
    corr = correction if correction is not None else enc.correction_pass(passes, n)
    demod = enc.phase_pass_chunked(
        passes,
        n,
        corr,
        scale,
        hysteresis_subintervals,
        drift_free_hysteresis() if drift else None,
    )
    rev_idx, rev_times = enc.reversals_pass(passes, n, corr, demod.plan)
    first, last, n_periods = _cut(
        rev_idx, periods, "encoder capture", demod.span_deg, None if drift else demod.net_deg
    )
    f0 = n_periods / (rev_times[2 * n_periods] - rev_times[0])
    segment = enc.segment(passes, demod.states, corr, scale, first, last)
    t0 = float(found.first_t)
    seg, error = _fit_and_error(
        segment,
        first,
        last,
        f0,
        harmonics,
        drift,
        set_amplitude_deg,
        set_frequency_hz,
        true_time(specs, t0),
        found.typical,
    )
    return encoder_result(
        demod,
        corr,
        seg,
        error,
        (first, last, rev_times, n_periods, t0),
        set_amplitude_deg,
        set_frequency_hz,
        specs,
        clipped,
    )


def check_encoder_settings(
    lines: int,
    harmonics: int,
    periods: int | None,
    set_amplitude_deg: float | None,
    set_frequency_hz: float | None,
) -> None:
    """The OSE calibration's refusals of its settings (ConfigError), as in memory."""
    _check_settings(harmonics, periods)
    if int(lines) != lines or lines < 1:
        raise ConfigError(f"--lines must be a positive whole number, got {lines}")
    _check_set_values(set_amplitude_deg, set_frequency_hz)


def encoder_result(
    demod: enc.Demod,
    corr: QuadratureCorrection,
    seg: SegmentFit,
    error: tuple[float, float, np.ndarray] | None,
    cut: tuple[int, int, np.ndarray, int, float],
    set_amplitude_deg: float | None,
    set_frequency_hz: float | None,
    specs: InstrumentSpecs | None,
    clipped: tuple[str, ...],
) -> MotionResult:
    """The OSE result from the passes' findings: the phase pass's ``demod``, the correction,
    the fit and position error of the analysed samples, and ``cut`` = (first, last, reversal
    times (s), whole periods, capture start (s))."""
    first, last, rev_times, n_periods, t0 = cut
    plot = {
        "t": demod.plot_t,
        "angle_deg": demod.plot_angle,
        "t_used": seg.t_plot,
        "residual_deg": seg.residual_plot,
        "reversal_kinds": demod.plan.kinds,
        "lissajous_raw": (demod.plot_a, demod.plot_b),
        "lissajous_corrected": correct_quadrature(demod.plot_a, demod.plot_b, corr),
        "correction": corr,
        "unit": "deg",
    }
    detection = ReversalDetection(
        method="argmax",
        fit=seg.fit,
        sample_interval_s=_sample_interval(seg, first, last),
        capture_start_s=t0,
    )
    result = _finish_angle(
        "encoder",
        seg,
        detection,
        rev_times,
        n_periods,
        plot,
        [f"quadrature correction: {corr.method}"],
        set_amplitude_deg,
        set_frequency_hz,
        specs,
    )
    return with_segment(result, seg, error, clipped)


def _finish_angle(
    scheme: str,
    seg: SegmentFit,
    detection: ReversalDetection,
    rev_times: np.ndarray,
    n_periods: int,
    plot: dict[str, object],
    notes: list[str],
    set_amplitude_deg: float | None,
    set_frequency_hz: float | None,
    specs: InstrumentSpecs | None,
    radius_mm: float | None = None,
) -> MotionResult:
    """``_finish`` of a scheme that fits the angle itself (OSE, LTS): the fit's amplitudes,
    offset and residual are the displacement's."""
    return _finish(
        scheme=scheme,
        fit=seg.fit,
        displacement_amplitudes=seg.fit.amplitudes,
        displacement_amplitudes_u=seg.fit.amplitudes_u,
        offset_deg=seg.fit.offset,
        residual_rms_deg=seg.fit.residual_rms,
        reversal_times=rev_times,
        periods=n_periods,
        t_used=seg.t_used,
        angle_used=seg.y_used,
        set_amplitude_deg=set_amplitude_deg,
        set_frequency_hz=set_frequency_hz,
        notes=notes,
        snr=None,
        plot=plot,
        detection=detection,
        specs=specs,
        radius_mm=radius_mm,
    )


def _sample_interval(seg: SegmentFit, first: int, last: int) -> float:
    """The mean sample interval (s) of the analysed span, as in memory."""
    return float(seg.t_used[-1] - seg.t_used[0]) / max(last - first, 1)


def _fit_and_error(
    segment: Segment,
    first: int,
    last: int,
    f0: float,
    harmonics: int,
    drift: bool,
    set_amplitude_deg: float | None,
    set_frequency_hz: float | None,
    to_true: Callable[[np.ndarray], np.ndarray] | None,
    dt: float | None,
) -> tuple[SegmentFit, tuple[float, float, np.ndarray] | None]:
    """The analysis fit of an angle segment (OSE, LTS) and, when it was not gathered and set
    values are given, the position error of eq. (2) on θ less any fitted drift: without a drift
    term eq. (2)'s three-parameter fit is accumulated in the fit's pass, with one in a pass of
    its own (it needs the drift)."""
    with_set = set_amplitude_deg is not None and set_frequency_hz is not None
    acc3 = None
    beside = []
    if set_frequency_hz is not None and with_set and not drift:
        acc3 = accumulator(set_frequency_hz, 1, dt)
        beside.append((acc3, to_true))
    seg = fit_segment(
        segment,
        first,
        last,
        f0,
        harmonics,
        drift,
        gather_max=_GATHER_MAX_SAMPLES,
        beside=beside,
        dt=dt,
    )
    if seg.gathered or set_amplitude_deg is None or set_frequency_hz is None:
        return seg, None
    error = position_error_pass(
        detrended(segment, seg.fit),
        first,
        last,
        set_amplitude_deg,
        set_frequency_hz,
        acc3=acc3,
        to_true=to_true,
        dt=dt,
    )
    return seg, error


@one_blas_thread
def calibrate_lts_motion_chunked(
    chunks: ChunkSource,
    *,
    radius_mm: float,
    harmonics: int = 10,
    periods: int | None = None,
    set_amplitude_deg: float | None = None,
    set_frequency_hz: float | None = None,
    progress: Callable[[int], None] | None = None,
    specs: InstrumentSpecs | None = None,
    allow_clipped: bool = False,
    drift: bool = False,
) -> MotionResult:
    """Sinusoidal-motion calibration from a laser triangulation sensor's capture read in chunks.

    The same calibration as :func:`~rotacal.table.calibrate_lts_motion` — θ = arctan(D/R)
    (eq. (15)), reversing moments by extreme values (Schmitt trigger on the 2–98 % range, a
    parabola through ±1/20 of a period at each extreme), n whole periods between 2n+1 reversals,
    the IEEE 1057 multi-harmonic fit and THD (eq. (1)), with set values the angular position
    error (eq. (2)) — and the same result (reversals to the sample, numbers to ≤ 1e-9 relative),
    computed in passes over the capture so that memory is bounded by the chunk size
    (:mod:`rotacal.table._stream_lts`).

    Parameters
    ----------
    chunks : callable
        ``chunks()`` starts a fresh pass over the capture and returns an iterator of mappings
        holding the 1-D arrays ``time_s`` (s) and ``displacement_mm`` (mm) of one chunk each, in
        time order; every call must give the same chunks. See :func:`lts_chunks_from_file`.
    radius_mm : float
        R, mm: from the laser spot to the table's axis.
    harmonics, periods, set_amplitude_deg, set_frequency_hz, specs, allow_clipped, drift
        As :func:`~rotacal.table.calibrate_lts_motion` (harmonics N_H; set values in deg, Hz).
    progress : callable, optional
        Called after each chunk with the number of samples processed so far, summed over the
        passes (about 7·N for a capture of N samples, 10·N with ``drift``).

    Returns
    -------
    MotionResult

    Raises
    ------
    CaptureError
        The errors of the in-memory path (too few samples, NaN/inf, time not increasing — also
        across chunks —, gaps, clipping, a constant signal, |D| > R, too few reversals), with
        sample indices counted from the start of the capture, and chunks that are not mappings
        of equal-length 1-D ``time_s``, ``displacement_mm`` or that change from pass to pass.
    ConfigError
        Bad ``radius_mm``, ``harmonics``, ``periods`` or set values.

    References
    ----------
    Feng et al. (2023), Sensors 23:4876, §5, eqs. (1), (2), (15); IEEE Std 1057-2017, §4.1.3;
    JCGM 100:2008 and JCGM 101:2008 (budgets).
    """
    check_lts_run(harmonics, periods, radius_mm, set_amplitude_deg, set_frequency_hz)
    passes = Passes(chunks, progress, LTS_COLUMNS, "lts_chunks_from_file(path)")
    found = check_pass(passes, {LTS_COLUMNS[1]: None}, keep=LTS_COLUMNS[1] if drift else None)
    clipped = lts_faults(found, radius_mm, allow_clipped)
    n = found.n
    t0 = float(found.first_t)
    trend = lts.prefit_drift_chunked(passes, found, radius_mm, harmonics) if drift else 0.0
    pieces = lts.trigger_values(passes, radius_mm, trend, t0)

    def trigger_seen() -> Iterator[np.ndarray]:
        for *_, xt in pieces():
            yield xt

    if trend == 0.0:  # θ itself: its range from D's, arctan being increasing
        lo_x, hi_x = lts_span(found, radius_mm)[:2]
    else:
        lo_x, hi_x = lts.value_range(trigger_seen)

    def order(ranks: list[int]) -> list[float]:
        return lts.order_statistics(trigger_seen, ranks, lo_x, hi_x)

    q_lo, q_hi = TRIGGER_PERCENTILES
    p_lo, p_hi = lts.percentiles(n, [q_lo, q_hi], order)
    mid, h = trigger_levels(p_lo, p_hi, None)
    ext = lts.swing_extremes(pieces, n, mid, h)
    rev_times, rev_idx = lts.refined_reversals(pieces, ext, float(found.last_t) - t0, n)
    first, last, n_periods = lts_cut(found, radius_mm, drift, rev_idx, periods)
    f0 = n_periods / (rev_times[2 * n_periods] - rev_times[0])
    seg, error = _fit_and_error(
        lts.angle_segment(passes, radius_mm, first, last),
        first,
        last,
        f0,
        harmonics,
        drift,
        set_amplitude_deg,
        set_frequency_hz,
        true_time(specs, t0),
        found.typical,
    )
    return lts_result(
        ext,
        seg,
        error,
        (first, last, rev_times, n_periods, t0),
        radius_mm,
        set_amplitude_deg,
        set_frequency_hz,
        specs,
        clipped,
    )


def check_lts_run(
    harmonics: int,
    periods: int | None,
    radius_mm: float,
    set_amplitude_deg: float | None,
    set_frequency_hz: float | None,
) -> None:
    """The settings checks of the LTS calibration (ConfigError)."""
    check_lts_settings(harmonics, periods, radius_mm)
    _check_set_values(set_amplitude_deg, set_frequency_hz)


def lts_faults(found: Checked, radius_mm: float, allow_clipped: bool) -> tuple[str, ...]:
    """The first pass's faults of an LTS capture raised in the in-memory order (the signal's,
    clipping, |D| > R); the clipping warnings."""
    name = LTS_COLUMNS[1]
    raise_signal_faults(found, name)
    clipped = found.clipping(allow_clipped)
    check_reach(max(abs(found.low[name]), abs(found.high[name])), radius_mm)
    return clipped


def lts_span(found: Checked, radius_mm: float) -> tuple[float, float, float]:
    """The smallest and largest θ (deg), arctan being increasing, and θ's net change from the
    first to the last sample (deg)."""
    name = LTS_COLUMNS[1]

    def angle_of(value: float) -> float:
        return float(lts_angle(np.array([value]), radius_mm)[0])

    net = angle_of(found.last_value[name]) - angle_of(found.first_value[name])
    return angle_of(found.low[name]), angle_of(found.high[name]), net


def lts_cut(
    found: Checked, radius_mm: float, drift: bool, rev_idx: np.ndarray, periods: int | None
) -> tuple[int, int, int]:
    """The analysed span's first and last sample and its number of periods (``_cut``)."""
    low, high, net = lts_span(found, radius_mm)
    return _cut(rev_idx, periods, "LTS capture", high - low, None if drift else net)


def lts_result(
    ext: lts.Extremes,
    seg: SegmentFit,
    error: tuple[float, float, np.ndarray] | None,
    cut: tuple[int, int, np.ndarray, int, float],
    radius_mm: float,
    set_amplitude_deg: float | None,
    set_frequency_hz: float | None,
    specs: InstrumentSpecs | None,
    clipped: tuple[str, ...],
) -> MotionResult:
    """The LTS calibration's result from its passes: ``cut`` is (first, last, reversal times
    (s), periods, the capture's first time (s))."""
    return displacement_result(
        ext,
        seg,
        error,
        cut,
        [f"θ = arctan(D/R), R = {radius_mm:g} mm"],
        (set_amplitude_deg, set_frequency_hz),
        specs,
        clipped,
        radius_mm=float(radius_mm),
    )


def displacement_result(
    ext: lts.Extremes,
    seg: SegmentFit,
    error: tuple[float, float, np.ndarray] | None,
    cut: tuple[int, int, np.ndarray, int, float],
    notes: list[str],
    set_values: tuple[float | None, float | None],
    specs: InstrumentSpecs | None,
    clipped: tuple[str, ...],
    *,
    radius_mm: float | None = None,
) -> MotionResult:
    """The result of a streamed calibration whose reading is the displacement θ itself (the LTS
    scheme's budgets; an LTS also gives ``radius_mm``, an angle readout none): ``cut`` is
    (first, last, reversal times (s), periods, the capture's first time (s)); ``set_values``
    the set amplitude (deg) and frequency (Hz)."""
    first, last, rev_times, n_periods, t0 = cut
    plot = {
        "t": ext.plot_t,
        "angle_deg": ext.plot_angle,
        "t_used": seg.t_plot,
        "residual_deg": seg.residual_plot,
        "unit": "deg",
    }
    detection = ReversalDetection(
        method="parabola",
        fit=seg.fit,
        sample_interval_s=_sample_interval(seg, first, last),
        capture_start_s=t0,
        half_window_s=1.0 / (20.0 * seg.fit.frequency_hz),  # extreme_reversals: ±period/20
    )
    result = _finish_angle(
        "lts", seg, detection, rev_times, n_periods, plot, notes, *set_values, specs, radius_mm
    )
    return with_segment(result, seg, error, clipped)


@one_blas_thread
def calibrate_fog_motion_chunked(
    chunks: ChunkSource,
    *,
    harmonics: int = 10,
    periods: int | None = None,
    set_amplitude_deg: float | None = None,
    set_frequency_hz: float | None = None,
    progress: Callable[[int], None] | None = None,
    specs: InstrumentSpecs | None = None,
    allow_clipped: bool = False,
    drift: bool = False,
) -> MotionResult:
    """Sinusoidal-motion calibration from a fibre-optic gyro's rate read in chunks.

    The same calibration as :func:`~rotacal.table.calibrate_fog_motion` — the rate fitted
    directly with its harmonics (eqs. (9)–(10)), the reversing moments at the zero crossings of
    the fitted rate, the fit repeated on n whole periods, the displacement harmonics and THD
    by analytic integration (eqs. (11)–(14)), the SNR (§5) and with set values the position error
    of eq. (2) on the rate less D0 integrated by the trapezoid rule — and the same result
    (numbers to ≤ 1e-9 relative), computed in passes over the capture so that memory is bounded
    by the chunk size (:mod:`rotacal.table._stream_fog`). The frequency's start value comes from
    the first 2²⁰ samples when they hold ≥ 4 periods, else from an evenly strided copy of the
    whole capture (≤ 2²¹ samples).

    Parameters
    ----------
    chunks : callable
        ``chunks()`` starts a fresh pass over the capture and returns an iterator of mappings
        holding the 1-D arrays ``time_s`` (s) and ``rate_deg_s`` (deg/s) of one chunk each, in
        time order; every call must give the same chunks. See :func:`fog_chunks_from_file`.
    harmonics, periods, set_amplitude_deg, set_frequency_hz, specs, allow_clipped, drift
        As :func:`~rotacal.table.calibrate_fog_motion` (harmonics N_H; set values in deg, Hz).
    progress : callable, optional
        Called after each chunk with the number of samples processed so far, summed over the
        passes (at most 6·N for a capture of N samples).

    Returns
    -------
    MotionResult

    Raises
    ------
    CaptureError
        The errors of the in-memory path (too few samples, NaN/inf, time not increasing — also
        across chunks —, gaps, clipping, a constant signal, too few reversals, a fit that does
        not converge), with sample indices counted from the start of the capture, and chunks
        that are not mappings of equal-length 1-D ``time_s``, ``rate_deg_s`` or that change.
    ConfigError
        Bad ``harmonics``, ``periods`` or set values.

    References
    ----------
    Feng et al. (2023), Sensors 23:4876, §4, eqs. (9)–(14), §5 (SNR); IEEE Std 1057-2017,
    §4.1.3; JCGM 100:2008 and JCGM 101:2008 (budgets).
    """
    _check_settings(harmonics, periods)
    _check_set_values(set_amplitude_deg, set_frequency_hz)
    passes = Passes(chunks, progress, FOG_COLUMNS, "fog_chunks_from_file(path)")
    name = FOG_COLUMNS[1]
    found = check_pass(passes, {name: None}, keep=name)
    raise_signal_faults(found, name)
    clipped = found.clipping(allow_clipped)
    n = found.n
    f_start = fog.start_frequency_of(found)
    first_fit, plot_t, plot_w = fog.whole_fit(passes, n, f_start, harmonics, drift, found.typical)
    rev_times, rev_idx = fog.zero_crossings(passes, first_fit, n)
    first, last, n_periods = _cut(rev_idx, periods, "FOG capture")
    seg, angle, error = fog.analysed(
        fog.rate_segment(passes, first, last),
        (first, last, _GATHER_MAX_SAMPLES),
        first_fit.frequency_hz,
        (harmonics, drift),
        (set_amplitude_deg, set_frequency_hz),
        true_time(specs, float(found.first_t)),
        found.typical,
    )
    return fog.fog_result(
        found,
        first_fit,
        (plot_t, plot_w),
        (rev_times, n_periods),
        (seg, angle, error),
        (set_amplitude_deg, set_frequency_hz),
        specs,
        clipped,
    )


def encoder_chunks_from_file(
    path: str | os.PathLike[str],
    *,
    mapping: Mapping[str, str] | None = None,
    group: str | None = None,
    chunk_rows: int = 2_000_000,
) -> ChunkSource:
    """A chunk source for :func:`calibrate_encoder_motion_chunked` reading an encoder capture file.

    Each call of the returned function streams ``time_s``, ``a`` and ``b`` from the file with
    :func:`rotacal.io.iter_capture_chunks` (CSV, NPZ, HDF5, TDMS; uncompressed NPZ members and
    contiguous HDF5 datasets are memory-mapped, and the pages of each chunk are handed back to
    the system once the next chunk is asked for, so the process's memory stays flat).

    Parameters
    ----------
    path : str or path-like
        The capture file.
    mapping : mapping, optional
        File column name -> canonical name (``--column OLD=NEW``).
    group : str, optional
        HDF5 or TDMS group holding the columns.
    chunk_rows : int
        Rows per chunk (default 2·10⁶: ≈ 48 MB of float64 columns, ≈ 0.5 GB of work arrays).

    Returns
    -------
    callable
        ``chunks()`` → iterator of ``{"time_s": ..., "a": ..., "b": ...}`` (s, signal unit).

    Raises
    ------
    ConfigError
        ``chunk_rows`` not a whole number ≥ 1. File errors are raised by the first pass.
    """
    return chunks_from_file(
        path, ENCODER_COLUMNS, mapping=mapping, group=group, chunk_rows=chunk_rows
    )


def lts_chunks_from_file(
    path: str | os.PathLike[str],
    *,
    mapping: Mapping[str, str] | None = None,
    group: str | None = None,
    chunk_rows: int = 2_000_000,
) -> ChunkSource:
    """A chunk source for :func:`calibrate_lts_motion_chunked`: ``time_s`` (s) and
    ``displacement_mm`` (mm) streamed from a capture file, as :func:`encoder_chunks_from_file`."""
    return chunks_from_file(path, LTS_COLUMNS, mapping=mapping, group=group, chunk_rows=chunk_rows)


def fog_chunks_from_file(
    path: str | os.PathLike[str],
    *,
    mapping: Mapping[str, str] | None = None,
    group: str | None = None,
    chunk_rows: int = 2_000_000,
) -> ChunkSource:
    """A chunk source for :func:`calibrate_fog_motion_chunked`: ``time_s`` (s) and
    ``rate_deg_s`` (deg/s) streamed from a capture file, as :func:`encoder_chunks_from_file`."""
    return chunks_from_file(path, FOG_COLUMNS, mapping=mapping, group=group, chunk_rows=chunk_rows)
