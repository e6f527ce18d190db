"""``motion angle`` on a capture read in chunks: the in-memory calibration's steps, memory flat.

:func:`calibrate_angle_motion_chunked` takes the steps of
:func:`~rotacal.table.motion_angle.calibrate_angle_motion` in passes over the capture, each pass
a fresh :class:`~rotacal.signal.readings.CleanReadings` pass of the readings with the DAQ's
repeated rows and duplicated times dropped and a counter unwrapped (the last reading carried
from chunk to chunk), numbered as the cleaned record. The LTS scheme's streamed passes (:mod:`rotacal.table._stream_lts`) then
run on it unchanged — they take (offset, t, θ) pieces: the exact 2–98 % percentiles of the
trigger (order statistics), the swings' extremes with the trigger's state carried, the parabola
of each extreme on its window — and the accumulated multi-harmonic fit with the position error
(:mod:`rotacal.table._stream_fit`). The result equals the in-memory one (reversals to the
sample, numbers to the accumulated fit's ≤ 1e-9 relative; tested).

References
----------
Feng et al. (2023), Sensors 23:4876, eqs. (1), (2), §3.3, §5; IEEE Std 1057-2017 §4.1.3.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Iterator

import numpy as np

from rotacal._threads import one_blas_thread
from rotacal.errors import CaptureError, ConfigError
from rotacal.results import with_warnings
from rotacal.signal._values import check_magnitudes, check_time_span
from rotacal.signal.daq_faults import DaqFaults
from rotacal.signal.readings import CleanReadings, ReadingChunks, counter_register
from rotacal.table import _stream_lts as lts
from rotacal.table._stream_checks import StridedCopy, start_frequency
from rotacal.table._stream_fit import accumulate, accumulator, block_length, true_time
from rotacal.table.motion import MotionResult, _check_set_values, _check_settings, _cut
from rotacal.table.motion_angle import (
    _ANGLE_HINT,
    _LTS_HINT,
    READ_DIRECTLY,
    angle_quantum,
    with_resolution,
)
from rotacal.table.motion_lts_fog import TRIGGER_PERCENTILES, trigger_levels
from rotacal.table.streaming import _fit_and_error, displacement_result
from rotacal.uncertainty import InstrumentSpecs

__all__ = ["calibrate_angle_motion_chunked"]

_FIRST = 1 << 20  # samples kept for the start frequency (as the LTS check pass keeps)


@dataclasses.dataclass
class _Stats:
    """What the first pass found of the cleaned record."""

    n: int = 0
    lo: float = math.inf
    hi: float = -math.inf
    first_t: float = math.nan
    last_t: float = math.nan
    first_x: float = math.nan
    last_x: float = math.nan
    quantum: float | None = None
    faults: DaqFaults | None = None
    first: tuple[np.ndarray, np.ndarray] | None = None
    strided: StridedCopy = dataclasses.field(default_factory=StridedCopy)


def _first_pass(clean: CleanReadings, angle: bool) -> _Stats:
    s = _Stats()
    held_t: list[np.ndarray] = []
    held_x: list[np.ndarray] = []
    for off, t, x in clean():
        if s.n == 0:
            s.first_t, s.first_x = float(t[0]), float(x[0])
            if angle:
                s.quantum = angle_quantum(x)
        s.lo, s.hi = min(s.lo, float(x.min())), max(s.hi, float(x.max()))
        s.last_t, s.last_x = float(t[-1]), float(x[-1])
        if off < _FIRST:
            held_t.append(t[: _FIRST - off].copy())
            held_x.append(x[: _FIRST - off].copy())
        s.strided.add(off, t, x)
        s.n = off + t.size
    s.faults = clean.faults
    if s.n < 16:
        raise CaptureError(f"the capture has only {s.n} samples: too few for a sine fit")
    s.first = (np.concatenate(held_t), np.concatenate(held_x))
    return s


def _prefit_drift(clean: CleanReadings, s: _Stats, harmonics: int, dt: float) -> float:
    """:func:`~rotacal.table.motion_drift.prefit_drift` streamed (as the LTS scheme's)."""
    t_mid = 0.5 * (s.first_t + s.last_t)
    slope = lts.line_slope([lts.line_sums(t, x, t_mid) for _, t, x in clean()], s.n)
    assert s.first is not None
    ts, xs = s.strided.arrays()
    f0 = start_frequency(
        (s.first[0], s.first[1] - slope * (s.first[0] - t_mid)),
        (ts, xs - slope * (ts - t_mid)),
        whole=s.strided.stride == 1 and ts.size == s.first[0].size,
    )
    acc = accumulator(f0, harmonics, dt)

    def less_line() -> Iterator[tuple[int, np.ndarray, np.ndarray]]:
        for g0, t, x in clean():
            yield g0, t, x - slope * (t - t_mid)

    accumulate([(acc, None)], less_line(), block_length(f0, harmonics, dt))
    return lts.drift_of(acc, f0, harmonics, slope)


@one_blas_thread
def calibrate_angle_motion_chunked(
    chunks: ReadingChunks,
    *,
    counts_per_rev: float | None = None,
    counter_bits: int | None = None,
    signed: bool | None = None,
    resolution_deg: float | None = None,
    harmonics: int = 10,
    periods: int | None = None,
    set_amplitude_deg: float | None = None,
    set_frequency_hz: float | None = None,
    specs: InstrumentSpecs | None = None,
    allow_clipped: bool = False,
    drift: bool = False,
    allow_gaps: bool = False,
) -> MotionResult:
    """:func:`~rotacal.table.motion_angle.calibrate_angle_motion` (or, with ``counts_per_rev``,
    ``calibrate_count_motion``) of a capture read in chunks, in passes (module docstring).

    Parameters
    ----------
    chunks : callable — ``chunks()`` starts a fresh pass and yields ``(time_s, reading)`` array
        pairs in record order (s; deg or counts); every call gives the same record.
    counts_per_rev : float, optional — N: the readings are counts (θ = 360·count/N).
    counter_bits, signed : the register; without ``counter_bits`` one extra pass finds the
        readings' range and :func:`~rotacal.signal.counter.infer_register` rules.
    resolution_deg, harmonics, periods, set_amplitude_deg, set_frequency_hz, specs, allow_clipped, drift, allow_gaps : as ``calibrate_angle_motion``.
    """
    del allow_clipped  # an angle readout has no rails
    _check_settings(harmonics, periods)
    _check_set_values(set_amplitude_deg, set_frequency_hz)
    inferred = counter_bits is None
    if counts_per_rev is not None:
        if not (math.isfinite(counts_per_rev) and counts_per_rev > 0):
            raise ConfigError(f"--counts-per-rev must be positive, got {counts_per_rev}")
        counter_bits, signed = counter_register(chunks(), counter_bits, signed)
    clean = CleanReadings(chunks, counts_per_rev, counter_bits, signed)
    s = _first_pass(clean, counts_per_rev is None)
    assert s.faults is not None
    s.faults.check(allow_gaps)
    dt = s.faults.typical_step_s
    check_time_span("time_s", s.first_t, s.last_t, dt)
    check_magnitudes("angle_deg", np.array([s.lo, s.hi]))
    if not s.hi > s.lo:
        raise CaptureError("column angle_deg is constant: the table does not move in this capture")
    t0 = s.first_t
    trend = _prefit_drift(clean, s, harmonics, dt) if drift else 0.0

    def pieces() -> Iterator[tuple[int, np.ndarray, np.ndarray, np.ndarray]]:
        for off, t, x in clean():
            yield off, t, x, (x if trend == 0.0 else x - trend * (t - t0))

    def seen() -> Iterator[np.ndarray]:
        for *_, xt in pieces():
            yield xt

    lo_x, hi_x = (s.lo, s.hi) if trend == 0.0 else lts.value_range(seen)
    p_lo, p_hi = lts.percentiles(
        s.n, list(TRIGGER_PERCENTILES), lambda r: lts.order_statistics(seen, r, lo_x, hi_x)
    )
    mid, h = trigger_levels(p_lo, p_hi, None)
    ext = lts.swing_extremes(pieces, s.n, mid, h)
    rev_times, rev_idx = lts.refined_reversals(pieces, ext, s.last_t - t0, s.n)
    net = None if drift else s.last_x - s.first_x
    first, last, n_periods = _cut(rev_idx, periods, "angle capture", s.hi - s.lo, net)
    f0 = n_periods / (rev_times[2 * n_periods] - rev_times[0])

    def segment() -> Iterator[tuple[int, np.ndarray, np.ndarray]]:
        for off, t, x in clean():
            if off > last:
                return
            a, b = max(first - off, 0), min(last + 1 - off, t.size)
            if b > a:
                yield off + a, t[a:b], x[a:b]

    seg, error = _fit_and_error(
        segment, first, last, f0, harmonics, drift, set_amplitude_deg, set_frequency_hz,
        true_time(specs, t0), dt,
    )  # fmt: skip
    result = displacement_result(
        ext, seg, error, (first, last, rev_times, n_periods, t0), [READ_DIRECTLY],
        (set_amplitude_deg, set_frequency_hz), specs, (),
    )  # fmt: skip
    result = dataclasses.replace(
        result,
        scheme="angle",
        warnings=tuple(w.replace(_LTS_HINT, _ANGLE_HINT) for w in result.warnings),
    )
    q, what = resolution_deg, "stated"
    if counts_per_rev is not None:
        q, what = 360.0 / float(counts_per_rev), f"1 count of {counts_per_rev:g}/rev"
    elif q is None and s.quantum is not None:
        q, what = s.quantum, "quantum of the readings"
    if q is not None:
        result = with_resolution(result, float(q), what)
    if counts_per_rev is not None:
        kind = "signed" if signed else "unsigned"
        given = "inferred from the readings" if inferred else "given"
        note = f"count unwrapped in a {counter_bits}-bit {kind} register ({given})"
        result = dataclasses.replace(result, notes=(*result.notes, note))
    return with_warnings(result, s.faults.warnings())
