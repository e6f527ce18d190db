"""One huge encoder capture's sinusoidal-motion calibration, as tasks on Dask distributed.

:func:`calibrate_encoder_motion_on_dask` gives what
:func:`rotacal.table.calibrate_encoder_motion_chunked` gives for the same file (reversals to the
sample, numbers to ≤ 1e-9 relative, tested), with the passes split over a cluster's workers in
blocks of ``chunk_rows`` rows, each task reading its own rows (a shared file system; NPZ without
compression, HDF5 or TDMS). The single-process passes (:mod:`rotacal.table.streaming`) become:

* **Checks** — one task reads the file through once, in order, with every check of the
  single-process path's first pass (state carried from row to row); it runs beside the other
  rounds, and its fault, if any, is the one reported (the first in file order).
* **Heydemann correction** — each block returns its points on the in-memory stride; the client
  fits them in order (the same points, the same fit).
* **Phase** — the unwrapped phase carries a whole number of cycles from block to block. A first
  round unwraps each block from zero cycles and returns its first wrapped phase and its end
  state; the client chains them into each block's entry state (integers: exact) — the state
  the single-process pass has at that row. A second round runs the pass with that state: the
  transitions (and the k they reach), extremes and copies of each block, which the client
  folds in block order into the reversal candidates (their open run carried as in one
  process) and the reversal plan.
* **Reversing windows** — a round reads the samples of eqs. (7)–(8) of each window, another
  the time stamp of each reversal.
* **Fit** — θ of the analysed samples is recomputed per block from its entry state. The
  multi-harmonic fit's block moments are accumulated per task on the single-process block
  grid (the first add, which sets the working offset, done by the client) and the moments of
  the tasks are merged in order (Σ over disjoint blocks). A span short enough is gathered and
  fitted as in memory. With set values, eq. (2)'s three-parameter fit is fed in the same round
  (with a drift term, in a round of its own on θ less the drift) and its errors are a last
  round: the largest of the blocks' largest, the sum of their sums of squares.

References
----------
Feng R., Yan J., Wu Y., Yu N., Yin X. (2023). Sensors 23, 4876, §3, eqs. (1)–(8);
IEEE Std 1057-2017, §4.1.3; Heydemann P. L. M. (1981). Appl. Opt. 20, 3382.
"""

from __future__ import annotations

import dataclasses
import itertools
import math
from collections.abc import Callable, Iterator
from typing import TYPE_CHECKING, Any

import numpy as np

from rotacal._threads import one_blas_thread
from rotacal.batch._blocks import (
    CaptureRows,
    Ticks,
    block_starts,
    check_findings,
    check_task,
    open_capture,
    task_round,
)

if TYPE_CHECKING:
    from distributed import Client, Future

    from rotacal.encoder import PhaseState, QuadratureCorrection
    from rotacal.io.read_options import ReadOptions
    from rotacal.signal import SineFit
    from rotacal.table._stream_checks import Checked
    from rotacal.table._stream_encoder import PhaseBlock
    from rotacal.table._stream_fit import Fed, PartMoments
    from rotacal.table.motion import MotionResult
    from rotacal.uncertainty import InstrumentSpecs

__all__ = ["calibrate_encoder_motion_on_dask"]

#: Rows of a block, the unit of work of a task: the single-process path's chunk.
CHUNK_ROWS = 2_000_000

_SIGNALS = ("a", "b")


def _signals(source: CaptureRows, a: int, b: int) -> dict[str, np.ndarray]:
    return dataclasses.replace(source, columns=_SIGNALS).read(a, b)


def _points_task(source: CaptureRows, a: int, b: int, stride: int) -> tuple[np.ndarray, np.ndarray]:
    """The block's points of the Heydemann fit (global indices on ``stride``)."""
    from rotacal.table._stream_encoder import strided_points

    cols = _signals(source, a, b)
    return strided_points(a, cols["a"], cols["b"], stride)


def _cycles_task(
    source: CaptureRows, a: int, b: int, corr: QuadratureCorrection, jit: bool
) -> tuple[float, PhaseState]:
    """The block's first wrapped phase (rad) and its state at the end, unwrapped from zero
    cycles."""
    from rotacal.encoder._kernel import phase_pass

    cols = _signals(source, a, b)
    run = phase_pass(cols["a"], cols["b"], corr, jit=jit)
    return float(run.phase_rad[0]), run.state


def _entry_states(ends: list[tuple[float, PhaseState]]) -> list[PhaseState | None]:
    """The phase state at each block's start (None for the first) from :func:`_cycles_task`'s
    results: a block's cycle count is its own plus those carried in — the previous block's
    at its end and the step between its last and this block's first wrapped phase (the rule
    of :func:`~rotacal.encoder.unwrapped_phase`)."""
    from rotacal.encoder import PhaseState

    states: list[PhaseState | None] = [None]
    before: PhaseState | None = None
    for first_wrapped, end in ends[:-1]:
        carried = 0
        if before is not None:
            d0 = first_wrapped - before.last_wrapped_rad
            carried = before.cycles + int(d0 < -math.pi) - int(d0 > math.pi)
        before = PhaseState(end.last_wrapped_rad, end.cycles + carried)
        states.append(before)
    return states


def _phase_task(
    source: CaptureRows,
    a: int,
    b: int,
    corr: QuadratureCorrection,
    scale: float,
    state: PhaseState | None,
    jit: bool,
    n: int,
    with_rule: bool,
) -> PhaseBlock:
    """The single-process phase pass over the block, entering with its state."""
    from rotacal.table._stream_encoder import phase_block

    return phase_block(source.read(a, b), a, corr, scale, state, None, jit, n, with_rule)


def _chp_task(
    source: CaptureRows, corr: QuadratureCorrection, windows: list[tuple[int, int, int]]
) -> list[tuple[int, int]]:
    """Chp (eqs. (7)–(8)) of each window ``(w, lo, hi)``: the samples lo … hi it reads."""
    from rotacal.encoder import correct_quadrature, reversal_point_in_window

    found = []
    for w, lo, hi in windows:
        cols = _signals(source, lo, hi + 1)
        u, v = correct_quadrature(cols["a"], cols["b"], corr)
        found.append((w, lo + reversal_point_in_window(u, v)))
    return found


def _times_task(source: CaptureRows, indices: list[int]) -> np.ndarray:
    """The time stamps (s) of the rows ``indices`` (ascending, within a block)."""
    t = source.column("time_s", indices[0], indices[-1] + 1)
    return t[np.asarray(indices) - indices[0]]


@dataclasses.dataclass(frozen=True)
class _Span:
    """Rows ``lo`` … ``hi − 1`` of the capture whose θ a task computes, unwrapped from the
    start ``a`` ≤ lo of their block with the block's entry ``state`` (the same θ as the
    single-process pass, which runs from the chunk's start)."""

    source: CaptureRows
    corr: QuadratureCorrection
    scale: float  # deg of θ per rad of signal phase
    state: PhaseState | None
    jit: bool
    a: int
    lo: int
    hi: int

    def theta(self, detrend: SineFit | None) -> tuple[np.ndarray, np.ndarray]:
        """t (s) and θ (deg) of the rows, less ``detrend``'s drift if given."""
        from rotacal.table._stream_encoder import chunk_theta
        from rotacal.table.motion_drift import detrended_angle

        cols = self.source.read(self.a, self.hi)
        theta = chunk_theta(cols, self.corr, self.state, self.scale, self.jit)[self.lo - self.a :]
        t = np.array(cols["time_s"][self.lo - self.a :])
        return t, theta if detrend is None else detrended_angle(detrend, t, theta)


def _theta_task(span: _Span, detrend: SineFit | None) -> tuple[np.ndarray, np.ndarray]:
    return span.theta(detrend)


def _fit_task(
    span: _Span,
    detrend: SineFit | None,
    templates: list[Fed],
    ranges: list[tuple[int, int]],
    first: int,
    step: int,
) -> tuple[list[list[PartMoments]], np.ndarray, np.ndarray, float]:
    """Each add of ``ranges`` (they tile the span) made to a planned part of each template
    (:func:`~rotacal.table._stream_fit.planned_part`, t through its map): the moments of
    each add's parts, the decimated t and θ of the span and its last t (s)."""
    from rotacal.table._stream_fit import decimate, moments_of, planned_part

    t, y = span.theta(detrend)
    lo = span.lo
    adds = []
    for start, stop in ranges:
        t_add, y_add = t[start - lo : stop - lo], y[start - lo : stop - lo]
        parts = []
        for template, to_t in templates:
            part = planned_part(template)
            part.add(t_add if to_t is None else to_t(t_add), y_add)
            parts.append(moments_of(part))
        adds.append(parts)
    return adds, decimate(lo, first, step, t), decimate(lo, first, step, y), float(t[-1])


def _error_task(
    span: _Span, detrend: SineFit | None, error: tuple[Any, ...]
) -> tuple[float, float, np.ndarray]:
    """Eq. (2) over the span (:func:`~rotacal.table._stream_fit.piece_error`)."""
    from rotacal.table._stream_fit import piece_error

    t, y = span.theta(detrend)
    return piece_error(span.lo, t, y, *error)


@dataclasses.dataclass
class _Split:
    """A capture split in blocks over a cluster, once the phase state at each block's start is
    known: rounds of tasks over the rows of an analysed span."""

    client: Client
    source: CaptureRows
    n: int
    rows: int
    tick: Callable[[], None]
    corr: QuadratureCorrection | None = None
    scale: float = 1.0
    states: list[PhaseState | None] = dataclasses.field(default_factory=list)

    @property
    def starts(self) -> list[int]:
        return block_starts(self.n, self.rows)

    def round(self, fn: Callable[..., Any], args: list[tuple[Any, ...]]) -> list[Any]:
        return task_round(self.client, fn, args, self.tick)

    def span(self, j: int, lo: int, hi: int, jit: bool) -> _Span:
        """Rows lo … hi − 1, read from the start of block j (≤ lo)."""
        assert self.corr is not None
        a = j * self.rows
        return _Span(self.source, self.corr, self.scale, self.states[j], jit, a, lo, hi)

    def spans(self, cuts: Callable[[int], int], jit: bool) -> list[_Span]:
        """Rows [cuts(a_j), cuts(a_{j+1})) of each block j (the non-empty ones)."""
        ends = [*self.starts, self.n]
        out = []
        for j, a in enumerate(ends[:-1]):
            lo, hi = cuts(a), cuts(ends[j + 1])
            if lo < hi:
                out.append(self.span(j, lo, hi, jit))
        return out


def _clip(first: int, last: int) -> Callable[[int], int]:
    return lambda x: min(max(x, first), last + 1)


def _accumulate(
    split: _Split,
    fed: list[Fed],
    block: int | None,
    first: int,
    last: int,
    detrend: SineFit | None,
) -> tuple[tuple[list[np.ndarray], list[np.ndarray]], list[float]]:
    """Feed θ of samples first … last to each accumulator with the adds one process's
    ``accumulate`` makes over the blocks (:func:`~rotacal.table._stream_fit.add_ranges`): the
    first (which sets the accumulator's grid and working offset) here, the others in tasks by
    the block they start in, each add's moments merged in order — the same sums in the same
    order as one process. Returns the decimated t and θ and the segment's first and last t."""
    from rotacal.table._stream_fit import add_ranges, merge_part, planned_part
    from rotacal.table.motion import _plot_stride

    n_seg = last + 1 - first
    jit = _use_numba(n_seg)
    step = _plot_stride(n_seg)
    cuts = _clip(first, last)
    bounds = [*split.starts, split.n]
    sizes = [cuts(b) - cuts(a) for a, b in itertools.pairwise(bounds)]
    ranges = add_ranges(first, [size for size in sizes if size], block)
    (start, stop), rest = ranges[0], ranges[1:]
    t, y = split.round(_theta_task, [(split.span(start // split.rows, start, stop, jit), detrend)])[
        0
    ]
    for acc, to_t in fed:
        acc.add(t if to_t is None else to_t(t), y)
    dec: tuple[list[np.ndarray], list[np.ndarray]] = ([t[::step]], [y[::step]])
    ends = [float(t[0]), float(t[-1])]
    by_block: dict[int, list[tuple[int, int]]] = {}
    for r in rest:
        by_block.setdefault(r[0] // split.rows, []).append(r)
    # the planned accumulators (their Vandermonde matrices: MB) sent to each worker once
    templates = split.client.scatter(
        [[(planned_part(acc), to_t) for acc, to_t in fed]], broadcast=True
    )[0]
    args = [
        (split.span(k, rs[0][0], rs[-1][1], jit), detrend, templates, rs, first, step)
        for k, rs in by_block.items()
    ]
    for adds, dec_t, dec_y, t_end in split.round(_fit_task, args):
        for parts in adds:
            for (acc, _), part in zip(fed, parts, strict=True):
                merge_part(acc, part)
        dec[0].append(dec_t)
        dec[1].append(dec_y)
        ends[1] = t_end
    return dec, ends


def _use_numba(n: int) -> bool:
    from rotacal._jit import use_numba

    return use_numba(n)


@one_blas_thread  # as one process: the client's fit sums in the same order
def calibrate_encoder_motion_on_dask(
    path: str,
    *,
    client: Client,
    lines: int,
    harmonics: int = 10,
    periods: int | None = None,
    set_amplitude_deg: float | None = None,
    set_frequency_hz: float | None = None,
    correction: QuadratureCorrection | None = None,
    specs: InstrumentSpecs | None = None,
    allow_clipped: bool = False,
    drift: bool = False,
    hysteresis_subintervals: int | None = None,
    mapping: dict[str, str] | None = None,
    group: str | None = None,
    read_options: ReadOptions | None = None,
    chunk_rows: int = CHUNK_ROWS,
    progress: Callable[[int], None] | None = None,
) -> MotionResult:
    """Sinusoidal-motion calibration of an encoder capture (columns ``time_s``, ``a``, ``b``)
    computed by the workers of a Dask cluster (see the module for how the passes are split).

    Parameters
    ----------
    path : str
        The capture (NPZ saved without compression, HDF5 or TDMS), at a path every worker sees.
    client : distributed.Client
        The cluster's client.
    lines, harmonics, periods, set_amplitude_deg, set_frequency_hz
        As :func:`rotacal.table.calibrate_encoder_motion_chunked` (lines per revolution; set
        values in deg and Hz).
    correction, specs, allow_clipped, drift, hysteresis_subintervals
        As :func:`rotacal.table.calibrate_encoder_motion_chunked` (hysteresis in 30°
        subintervals).
    mapping, group, read_options
        How to read the capture, as :func:`rotacal.io.read_capture`.
    chunk_rows : int
        Rows of a task's block. The result equals that of the single-process path read in
        chunks of as many rows (its default, 2·10⁶, is this one's): the fit's adds, and so its
        sums, follow the chunks (another chunking changes the residual's rounding, ~1e-7 of
        the uncertainties).
    progress : callable, optional
        Called with the number of tasks done so far.

    Returns
    -------
    MotionResult
        As ``calibrate_encoder_motion_chunked`` over the same file: reversals to the sample,
        numbers to ≤ 1e-9 relative.

    Raises
    ------
    CaptureError, ConfigError
        As the single-process path, with the same messages (the first fault in file order);
        ConfigError also for a capture that cannot be read from a given row on (CSV, a
        compressed NPZ member).

    References
    ----------
    Feng et al. (2023), Sensors 23:4876, §3 and eqs. (1)–(8); IEEE Std 1057-2017, §4.1.3;
    Heydemann 1981, Appl. Opt. 20:3382.
    """
    from rotacal.table._stream_source import ENCODER_COLUMNS
    from rotacal.table.streaming import check_encoder_settings

    check_encoder_settings(lines, harmonics, periods, set_amplitude_deg, set_frequency_hz)
    source, n = open_capture(path, ENCODER_COLUMNS, "a", chunk_rows, mapping, group, read_options)
    split = _Split(client, source, n, chunk_rows, Ticks(progress))
    checked = client.submit(check_task, source, chunk_rows, {"a": "b", "b": "a"}, pure=False)
    try:
        return _calibrate(
            split,
            checked,
            lines,
            harmonics,
            periods,
            (set_amplitude_deg, set_frequency_hz),
            correction,
            specs,
            allow_clipped,
            drift,
            hysteresis_subintervals,
        )
    except Exception:
        # the fault the single-process path finds first, if the file has one
        _checks(checked, n, str(path), allow_clipped)
        raise


def _checks(
    checked: Future, n: int, path: str, allow_clipped: bool
) -> tuple[Checked, tuple[str, ...]]:
    """The check task's findings, its faults raised as one process raises them, and the
    clipping warnings."""
    from rotacal.table._stream_checks import raise_encoder_faults
    from rotacal.table._stream_encoder import MIN_SAMPLES

    return check_findings(
        checked, n, path, allow_clipped, lambda found: raise_encoder_faults(found, MIN_SAMPLES)
    )


def _calibrate(
    split: _Split,
    checked: Future,
    lines: int,
    harmonics: int,
    periods: int | None,
    set_values: tuple[float | None, float | None],
    correction: QuadratureCorrection | None,
    specs: InstrumentSpecs | None,
    allow_clipped: bool,
    drift: bool,
    hysteresis_subintervals: int | None,
) -> MotionResult:
    """The rounds of :func:`calibrate_encoder_motion_on_dask` (see the module)."""
    from rotacal.table import _stream_encoder as enc
    from rotacal.table.motion import _cut
    from rotacal.table.motion_drift import drift_free_hysteresis
    from rotacal.table.streaming import encoder_result

    source, n, starts = split.source, split.n, split.starts
    blocks = [(a, min(n, a + split.rows)) for a in starts]
    if n < enc.MIN_SAMPLES:
        _checks(checked, n, source.path, allow_clipped)
    split.scale = 360.0 / (2.0 * math.pi * float(lines))
    corr = correction
    if corr is None:
        stride = enc.correction_stride(n)
        points = split.round(_points_task, [(source, a, b, stride) for a, b in blocks])
        corr = enc.correction_of_points(points)
    split.corr = corr
    jit = _use_numba(n)
    ends = split.round(_cycles_task, [(source, a, b, corr, jit) for a, b in blocks])
    split.states = _entry_states(ends)
    rule = drift_free_hysteresis() if drift else None
    fold = enc.PhaseFold()
    phase_args = [
        (source, a, b, corr, split.scale, state, jit, n, rule is not None)
        for (a, b), state in zip(blocks, split.states, strict=True)
    ]
    for block in split.round(_phase_task, phase_args):
        fold.add(block)
    demod = fold.finish(split.states, split.scale, hysteresis_subintervals, rule, stacklevel=4)
    found, clipped = _checks(checked, n, source.path, allow_clipped)
    split.tick()
    rev_idx, rev_times = _reversals(split, demod.plan)
    first, last, n_periods = _cut(
        rev_idx, periods, "encoder capture", demod.span_deg, None if drift else demod.net_deg
    )
    f0 = n_periods / (rev_times[2 * n_periods] - rev_times[0])
    t0 = float(found.first_t)
    seg, error = _fit(
        split, first, last, f0, harmonics, drift, set_values, specs, t0, found.typical
    )
    return encoder_result(
        demod,
        corr,
        seg,
        error,
        (first, last, rev_times, n_periods, t0),
        *set_values,
        specs,
        clipped,
    )


def _reversals(split: _Split, plan: Any) -> tuple[np.ndarray, np.ndarray]:
    """The index and time (s) of each reversal: Chp of every window wider than one sample in a
    round of tasks (grouped by the block a window starts in), then the time stamps."""
    from rotacal.table._stream_encoder import reversal_index, window_bounds

    lo, hi, chp = window_bounds(plan, split.n)
    by_block: dict[int, list[tuple[int, int, int]]] = {}
    for w in np.flatnonzero(hi > lo).tolist():
        by_block.setdefault(int(lo[w]) // split.rows, []).append((w, int(lo[w]), int(hi[w])))
    for found in split.round(
        _chp_task, [(split.source, split.corr, ws) for ws in by_block.values()]
    ):
        for w, point in found:
            chp[w] = point
    indices = np.array(
        [reversal_index(plan, chp, r) for r in range(plan.pairs.shape[0])], dtype=np.intp
    )
    times = np.empty(indices.size, dtype=np.float64)
    groups: dict[int, list[int]] = {}
    for r in np.argsort(indices, kind="stable").tolist():
        groups.setdefault(int(indices[r]) // split.rows, []).append(r)
    stamps = split.round(
        _times_task, [(split.source, [int(indices[r]) for r in rs]) for rs in groups.values()]
    )
    for rs, got in zip(groups.values(), stamps, strict=True):
        times[rs] = got
    return indices, times


def _fit(
    split: _Split,
    first: int,
    last: int,
    f0: float,
    harmonics: int,
    drift: bool,
    set_values: tuple[float | None, float | None],
    specs: InstrumentSpecs | None,
    t0: float,
    dt: float | None,
) -> tuple[Any, tuple[float, float, np.ndarray] | None]:
    """The analysis fit of samples first … last and, with set values, the position error of
    eq. (2), as :func:`rotacal.table.streaming._fit_and_error` gives them."""
    from rotacal.table._stream_fit import (
        accumulated_fit,
        accumulator,
        block_length,
        ideal_fit,
        position_error_of,
    )
    from rotacal.table.motion import _plot_stride
    from rotacal.table.streaming import _GATHER_MAX_SAMPLES, _fit_and_error, true_time

    set_amplitude_deg, set_frequency_hz = set_values
    n_seg = last + 1 - first
    jit = _use_numba(n_seg)
    to_true = true_time(specs, t0)
    if n_seg <= _GATHER_MAX_SAMPLES:  # gathered and fitted as in memory
        pieces = split.round(
            _theta_task, [(span, None) for span in split.spans(_clip(first, last), jit)]
        )

        def segment() -> Iterator[tuple[int, np.ndarray, np.ndarray]]:
            g0 = first
            for t, y in pieces:
                yield g0, t, y
                g0 += t.size

        return _fit_and_error(segment, first, last, f0, harmonics, drift, *set_values, to_true, dt)
    acc = accumulator(f0, harmonics, dt)
    fed: list[Fed] = [(acc, None)]
    acc3 = None
    if set_amplitude_deg is not None and set_frequency_hz is not None and not drift:
        acc3 = accumulator(set_frequency_hz, 1, dt)
        fed.append((acc3, to_true))
    dec, ends = _accumulate(split, fed, block_length(f0, harmonics, dt), first, last, None)
    seg = accumulated_fit(acc, f0, harmonics, drift, False, dec, ends, n_seg)
    if set_amplitude_deg is None or set_frequency_hz is None:
        return seg, None
    if acc3 is None:  # eq. (2) on θ less the fitted drift: its own round
        acc3 = accumulator(set_frequency_hz, 1, dt)
        _accumulate(
            split, [(acc3, to_true)], block_length(set_frequency_hz, 1, dt), first, last, seg.fit
        )
    error = (
        ideal_fit(acc3, set_frequency_hz),
        set_amplitude_deg,
        set_frequency_hz,
        to_true,
        first,
        _plot_stride(n_seg),
    )
    args = [(span, seg.fit, error) for span in split.spans(_clip(first, last), jit)]
    return seg, position_error_of(split.round(_error_task, args), first, last)
