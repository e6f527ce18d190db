"""The fit and position-error passes shared by the chunked motion calibrations (private).

Every scheme ends the same way once its reversals have cut n whole periods, samples
``first..last``: the IEEE 1057 multi-harmonic fit of the analysed signal with the frequency
refined (Feng et al. 2023, eq. (1); eq. (9) for the FOG's rate), and with set values the angular
position error of eq. (2) against the ideal sinusoid of a three-parameter fit at the set
frequency. A scheme hands over its segment as a callable that starts a fresh pass over it,
yielding ``(global index of the piece's first sample, t, y)``.

A segment of at most ``gather_max`` samples is gathered and fitted exactly as in memory
(:func:`~rotacal.table.motion_drift.fit_motion`; the result then equals the in-memory one to
the bit); a longer one is fed to :class:`~rotacal.signal.HarmonicFitAccumulator` (normal
equations accumulated over the chunks, the first 2¹⁶ samples as one piece so that its working
offset is the in-memory one), keeping decimated copies for the figures.

References
----------
Feng et al. (2023), Sensors 23:4876, eqs. (1), (2), (9); IEEE Std 1057-2017, §4.1.3.
"""

from __future__ import annotations

import copy
import dataclasses
import math
from collections.abc import Callable, Iterator
from typing import Any

import numpy as np

from rotacal.results import with_warnings
from rotacal.signal import HarmonicFitAccumulator, SineFit
from rotacal.signal._blocks_store import MomentStore
from rotacal.table.motion import MotionResult, _plot_stride
from rotacal.table.motion_drift import detrended_angle, explained_fit, fit_motion
from rotacal.uncertainty import InstrumentSpecs

#: A fresh pass over the analysed samples: ``(global index of the first sample, t, y)`` pieces.
Segment = Callable[[], Iterator[tuple[int, np.ndarray, np.ndarray]]]
#: An accumulator and the map of t it is fed (None: t itself).
Fed = tuple[HarmonicFitAccumulator, Callable[[np.ndarray], np.ndarray] | None]

#: Samples held back before the first ``HarmonicFitAccumulator.add`` (the in-memory fit takes its
#: working offset from the first 2¹⁶ samples; the same samples give the same offset here).
_FIRST_ADD_SAMPLES = 1 << 16


#: Long blocks for the accumulated fits: harmonic 2H of 1.25·f may turn by up to _BLOCK_PHASE rad
#: within a block, its exponential kept to _BLOCK_MOMENTS Taylor terms (5.5⁴⁰/40! < 1e-18). The
#: accumulator's own default (0.25 rad, 16 moments) holds 22 times more blocks, whose moments
#: are what grows with a long capture and what each step of the frequency refinement sums over
#: (per sample ~9 times the bytes of these).
_BLOCK_PHASE = 5.5
_BLOCK_MOMENTS = 40


def block_length(f0: float, harmonics: int, dt: float | None) -> int | None:
    """Samples a block of :func:`accumulator` (None: the accumulator's own plan)."""
    if dt is None or not dt > 0:
        return None
    w = 2.0 * math.pi * f0 * 1.25
    m = int(2.0 * _BLOCK_PHASE / (2 * harmonics * w * dt))
    return m if m >= 64 else None  # too few samples a block to gain: the accumulator's plan


def accumulator(f0: float, harmonics: int, dt: float | None = None) -> HarmonicFitAccumulator:
    """A :class:`~rotacal.signal.HarmonicFitAccumulator` for a fit at about ``f0`` (Hz) with
    ``harmonics``, of samples ``dt`` (s) apart: blocks as long as the Taylor series of its
    block moments allows with 40 moments (the same least-squares solution, fewer blocks)."""
    m = block_length(f0, harmonics, dt)
    if m is None:
        return HarmonicFitAccumulator(f0, harmonics=harmonics)
    return HarmonicFitAccumulator(
        f0, harmonics=harmonics, block_samples=m, n_moments=_BLOCK_MOMENTS
    )


@dataclasses.dataclass
class SegmentFit:
    """The analysis fit of samples ``first..last`` and what the result needs of the segment."""

    fit: SineFit
    t_used: np.ndarray  # the segment's t when gathered, else its first and last t
    y_used: np.ndarray | None  # the segment's y when gathered
    t_plot: np.ndarray  # every _plot_stride-th t of the segment
    residual_plot: np.ndarray  # y − model there
    samples: int

    @property
    def gathered(self) -> bool:
        return self.y_used is not None


def decimate(g0: int, first: int, step: int, x: np.ndarray) -> np.ndarray:
    """Samples of ``x`` (first global index ``g0``) whose index − first is a multiple of step."""
    return np.array(x[(first - g0) % step :: step])


def fit_segment(
    segment: Segment,
    first: int,
    last: int,
    f0: float,
    harmonics: int,
    drift: bool,
    *,
    gather_max: int,
    rate: bool = False,
    beside: list[Fed] | None = None,
    dt: float | None = None,
) -> SegmentFit:
    """The fit of :func:`~rotacal.table.motion_drift.fit_motion` (start frequency ``f0``, Hz)
    on the segment, in one pass. ``beside``: further accumulators fed the same pieces in the
    same pass when the segment is not gathered (eq. (2)'s three-parameter fit); ``dt``: the
    sample interval (s), for the blocks of :func:`accumulator`."""
    n_seg = last + 1 - first
    step = _plot_stride(n_seg)
    if n_seg <= gather_max:
        pieces = [(np.array(t), np.array(y)) for _, t, y in segment()]
        t_seg = np.concatenate([p[0] for p in pieces])
        y_seg = np.concatenate([p[1] for p in pieces])
        del pieces
        fit = fit_motion(t_seg, y_seg, f0, harmonics, drift, rate=rate)
        t_plot = t_seg[::step]
        return SegmentFit(fit, t_seg, y_seg, t_plot, y_seg[::step] - fit.evaluate(t_plot), n_seg)
    acc = accumulator(f0, harmonics, dt)
    dec_t: list[np.ndarray] = []
    dec_y: list[np.ndarray] = []
    ends: list[float] = []

    def tap() -> Iterator[tuple[int, np.ndarray, np.ndarray]]:
        """The segment's pieces, keeping decimated copies and the end times on the way."""
        for g0, t_piece, y_piece in segment():
            dec_t.append(decimate(g0, first, step, t_piece))
            dec_y.append(decimate(g0, first, step, y_piece))
            ends[:] = [ends[0] if ends else float(t_piece[0]), float(t_piece[-1])]
            yield g0, t_piece, y_piece

    accumulate([(acc, None), *(beside or [])], tap(), block_length(f0, harmonics, dt))
    return accumulated_fit(acc, f0, harmonics, drift, rate, (dec_t, dec_y), ends, n_seg)


def accumulated_fit(
    acc: HarmonicFitAccumulator,
    f0: float,
    harmonics: int,
    drift: bool,
    rate: bool,
    dec: tuple[list[np.ndarray], list[np.ndarray]],
    ends: list[float],
    n_seg: int,
) -> SegmentFit:
    """The fit of :func:`fit_segment` from its accumulator fed the whole segment, the segment's
    decimated copies (t, y) and its first and last t (s)."""
    fit = explained_fit(
        lambda with_term: acc.fit(
            f0, harmonics, True, max_iter=50, rtol=1e-12, drift=with_term, drift_check=not with_term
        ),
        drift,
        rate,
    )
    t_plot = np.concatenate(dec[0])
    return SegmentFit(
        fit, np.array(ends), None, t_plot, np.concatenate(dec[1]) - fit.evaluate(t_plot), n_seg
    )


def first_add_samples(block: int | None) -> int:
    """Samples of :func:`accumulate`'s first add: at least 2¹⁶, whole blocks of ``block``."""
    m = block or 1
    return -(-_FIRST_ADD_SAMPLES // m) * m


def planned_part(acc: HarmonicFitAccumulator) -> HarmonicFitAccumulator:
    """An empty accumulator on the time grid, block plan and working offset of ``acc`` (which
    has had its first add): a part of the record is added to it elsewhere (a Dask task) and
    merged back with :func:`merge_part`. Reads the accumulator's private state: the two
    functions are its merge."""
    part = copy.copy(acc)
    part._store = MomentStore(acc._k + 2)
    part._records = []
    part._n = 0
    part._sum_y2 = 0.0
    part._t_first = math.nan
    part._t_last = None
    return part


@dataclasses.dataclass
class PartMoments:
    """What a planned part (:func:`planned_part`) holds once fed: its block moments' records
    (the samples less the working offset, for an accumulator of one-sample blocks), its Σ(y −
    y0)², its number of samples and last t (s) — without the plan's matrices (MB)."""

    records: list[Any]
    sum_y2: float
    n: int
    t_last: float | None


def moments_of(part: HarmonicFitAccumulator) -> PartMoments:
    """The moments of a fed planned part, to send back to the accumulator it was planned on."""
    records = list(part._records) if part._explicit else list(part._store.records())
    return PartMoments(records, part._sum_y2, part._n, part._t_last)


def merge_part(acc: HarmonicFitAccumulator, part: PartMoments) -> None:
    """Add the moments of a part (:func:`planned_part` fed the samples that follow those of
    ``acc``, :func:`moments_of`) to ``acc``: moments add (the same blocks, and with the same
    adds the same sums in the same order, as one accumulator fed both)."""
    if part.n == 0:
        return
    if acc._explicit:
        acc._records.extend(part.records)
    else:
        for record in part.records:
            acc._store.append(*record)
    acc._sum_y2 += part.sum_y2
    acc._n += part.n
    acc._t_last = part.t_last


def accumulate(
    accs: list[Fed], pieces: Iterator[tuple[int, np.ndarray, np.ndarray]], block: int | None = None
) -> None:
    """Feed the pieces to each accumulator (t through its map), the first 2¹⁶ samples as one
    piece (the in-memory fit takes its working offset from them).

    ``block``: the first accumulator's block length (:func:`block_length`); each add then ends
    on a block boundary (the rest carried to the next), so that no block is split between two
    adds and the accumulator's merge needs no second copy of its moments to sum the halves.
    """

    def add(t_piece: np.ndarray, y_piece: np.ndarray) -> None:
        for acc, to_t in accs:
            acc.add(t_piece if to_t is None else to_t(t_piece), y_piece)

    m = block or 1
    first = first_add_samples(block)
    carry_t: list[np.ndarray] = []
    carry_y: list[np.ndarray] = []
    n_carry = 0
    started = False
    for _, t_piece, y_piece in pieces:
        want = first if not started else m
        if n_carry + t_piece.size < want:
            carry_t.append(np.array(t_piece))
            carry_y.append(np.array(y_piece))
            n_carry += t_piece.size
            continue
        i = 0
        if n_carry or not started:  # complete the first add, or the block the last one began
            i = want - n_carry
            add(np.concatenate([*carry_t, t_piece[:i]]), np.concatenate([*carry_y, y_piece[:i]]))
            started = True
        cut = i + (t_piece.size - i) // m * m
        if cut > i:
            add(t_piece[i:cut], y_piece[i:cut])
        carry_t, carry_y = [np.array(t_piece[cut:])], [np.array(y_piece[cut:])]
        n_carry = t_piece.size - cut
    if n_carry:
        add(np.concatenate(carry_t), np.concatenate(carry_y))


def add_ranges(first: int, sizes: list[int], block: int | None) -> list[tuple[int, int]]:
    """The samples ``[start, stop)`` (global indices) of each add :func:`accumulate` makes when
    fed pieces of ``sizes`` samples from sample ``first`` on: the same adds (same blocks, same
    sums in the same order) can then be made elsewhere and merged (:func:`merge_part`). It
    follows :func:`accumulate` step by step (tested: the split calibration equals it)."""
    m = block or 1
    head = first_add_samples(block)
    out: list[tuple[int, int]] = []
    pos = carry_start = first
    n_carry = 0
    started = False
    for size in sizes:
        want = head if not started else m
        if n_carry + size < want:
            n_carry += size
            pos += size
            continue
        i = 0
        if n_carry or not started:
            i = want - n_carry
            out.append((carry_start, pos + i))
            started = True
        cut = i + (size - i) // m * m
        if cut > i:
            out.append((pos + i, pos + cut))
        carry_start, n_carry = pos + cut, size - cut
        pos += size
    if n_carry:
        out.append((carry_start, carry_start + n_carry))
    return out


def detrended(segment: Segment, fit: SineFit) -> Segment:
    """The segment with y less the fitted drift (:func:`~rotacal.table.motion_drift.detrended_angle`)."""

    def pieces() -> Iterator[tuple[int, np.ndarray, np.ndarray]]:
        for g0, t_piece, y_piece in segment():
            yield g0, t_piece, detrended_angle(fit, t_piece, y_piece)

    return pieces


def true_time(
    specs: InstrumentSpecs | None, capture_start_s: float
) -> Callable[[np.ndarray], np.ndarray] | None:
    """The map of capture time to true time for eq. (2) when the timebase has a stated mean
    fractional error e₀ (``t₀ + (t − t₀)/(1 + e₀)``, as in memory), else None."""
    e0 = 0.0 if specs is None else float(specs.mean("timebase.relative_error"))
    if e0 == 0.0:
        return None
    return lambda t: capture_start_s + (t - capture_start_s) / (1.0 + e0)


def position_error_pass(
    segment: Segment,
    first: int,
    last: int,
    set_amplitude_deg: float,
    set_frequency_hz: float,
    *,
    acc3: HarmonicFitAccumulator | None = None,
    to_true: Callable[[np.ndarray], np.ndarray] | None = None,
    dt: float | None = None,
) -> tuple[float, float, np.ndarray]:
    """Eq. (2) against the ideal sinusoid of :func:`~rotacal.table.position_error`: its maximum
    and rms (deg) and a decimated copy. ``acc3``: the three-parameter fit's accumulator, already
    fed the segment (t through ``to_true``); None: fed in a pass of its own first."""
    if acc3 is None:
        acc3 = accumulator(set_frequency_hz, 1, dt)
        accumulate([(acc3, to_true)], segment(), block_length(set_frequency_hz, 1, dt))
    fit3 = ideal_fit(acc3, set_frequency_hz)
    step = _plot_stride(last + 1 - first)
    parts = [
        piece_error(
            g0, t_piece, y_piece, fit3, set_amplitude_deg, set_frequency_hz, to_true, first, step
        )
        for g0, t_piece, y_piece in segment()
    ]
    return position_error_of(parts, first, last)


def ideal_fit(acc3: HarmonicFitAccumulator, set_frequency_hz: float) -> SineFit:
    """The three-parameter fit at the set frequency (Hz) whose sinusoid eq. (2) compares with."""
    return acc3.fit(set_frequency_hz, 1, False, max_iter=1, rtol=1e-12)


def piece_error(
    g0: int,
    t_piece: np.ndarray,
    y_piece: np.ndarray,
    fit3: SineFit,
    set_amplitude_deg: float,
    set_frequency_hz: float,
    to_true: Callable[[np.ndarray], np.ndarray] | None,
    first: int,
    step: int,
) -> tuple[float, float, np.ndarray]:
    """Eq. (2) on one piece of the segment (first global index ``g0``; t in s, θ in deg)
    against the ideal sinusoid of the three-parameter fit ``fit3``: the largest |error|, the
    sum of its squares (deg²) and its decimated copy."""
    t_true = t_piece if to_true is None else to_true(t_piece)
    ideal = fit3.offset + set_amplitude_deg * np.sin(
        2 * np.pi * set_frequency_hz * (t_true - fit3.t_ref_s) + float(fit3.phases_rad[0])
    )
    err = y_piece - ideal
    return float(np.max(np.abs(err))), float(err @ err), decimate(g0, first, step, err)


def position_error_of(
    parts: list[tuple[float, float, np.ndarray]], first: int, last: int
) -> tuple[float, float, np.ndarray]:
    """The maximum and rms (deg) of eq. (2) and its decimated copy, from the pieces'
    :func:`piece_error` in segment order."""
    worst = max((p[0] for p in parts), default=0.0)
    total = sum(p[1] for p in parts)  # in order, as one process adds them
    return worst, math.sqrt(total / (last + 1 - first)), np.concatenate([p[2] for p in parts])


def with_segment(
    result: MotionResult,
    seg: SegmentFit,
    error: tuple[float, float, np.ndarray] | None,
    warnings: tuple[str, ...],
) -> MotionResult:
    """The result of ``_finish`` with what it could not see of an accumulated segment: the
    samples used and the position error (from :func:`position_error_pass`)."""
    if not seg.gathered:
        extra: dict[str, Any] = {"samples_used": seg.samples}
        if error is not None:
            worst, rms, err_dec = error
            result._plot["position_error_deg"] = err_dec
            extra.update(position_error_max_deg=worst, position_error_rms_deg=rms)
        result = dataclasses.replace(result, **extra)
    return with_warnings(result, warnings)
