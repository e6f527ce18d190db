"""One huge fibre-optic gyro capture's sinusoidal-motion calibration, as tasks on Dask distributed.

:func:`calibrate_fog_motion_on_dask` gives what :func:`rotacal.table.calibrate_fog_motion_chunked`
gives for the same file (reversals to the sample, numbers to ≤ 1e-9 relative, tested), with the
passes split over a cluster's workers in blocks of ``chunk_rows`` rows, each task reading its own
rows (a shared file system; NPZ without compression, HDF5 or TDMS). The single-process passes
(:mod:`rotacal.table._stream_fog`) become:

* **Checks** — one task reads the file through once, in order, with every check of the
  single-process path's first pass; it runs beside the rounds below until the reversals are
  cut, and its fault, if any, is the one reported (the first in file order).
* **Start** — what that pass gives the fit: the first chunk's median time step and the start
  frequency of the first 2²⁰ samples or, when they hold fewer than 4 periods, of the strided
  copy (every stride-th row, the stride the pass ends with), read by tasks of their own.
* **Fit of the whole rate** (eqs. (9)–(10)) and, on n whole periods, the **analysis fit** — the
  multi-harmonic fit's block moments are accumulated per task on the single-process block grid
  (:func:`~rotacal.table._stream_fit.add_ranges`; the first add, which sets the working offset,
  in a task of its own) and merged in order (Σ over disjoint blocks). A span short enough is
  gathered and analysed as one process analyses it.
* **Zero crossings** of the fitted rate — each block's, with the pair across its start (the row
  before it read too).
* **Angle** — the rate less D0 integrated by the trapezoid rule: each block's angle is its own
  running sum plus a prefix, the angle at the last sample of the block before. A first round
  returns each block's last own sum; the client chains the prefixes (the same adds in the same
  order as one process). A second round returns each block's angle sum, the SNR's slice sums
  (§5), a decimated copy and, with set values, the moments of eq. (2)'s three-parameter fit;
  a last round eq. (2)'s errors: the largest of the blocks' largest, the sum of their sums of
  squares.

References
----------
Feng R., Yan J., Wu Y., Yu N., Yin X. (2023). Sensors 23, 4876, §4, eqs. (2), (9)–(14), §5;
IEEE Std 1057-2017, §4.1.3.
"""

from __future__ import annotations

import dataclasses
import itertools
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

    from rotacal.io.read_options import ReadOptions
    from rotacal.signal import SineFit
    from rotacal.table._stream_checks import Checked
    from rotacal.table._stream_fit import Fed, PartMoments
    from rotacal.table._stream_fog import Integrated
    from rotacal.table.motion import MotionResult
    from rotacal.uncertainty import InstrumentSpecs

__all__ = ["calibrate_fog_motion_on_dask"]

#: Rows of a block, the unit of work of a task: the single-process path's chunk.
CHUNK_ROWS = 2_000_000


def _start_task(source: CaptureRows, n: int, rows: int) -> tuple[float, float, bool]:
    """What the first pass gives the fit's start: the frequency (Hz) of the first 2²⁰ samples
    (whether that is the in-memory estimate's, or they hold ≥ 4 periods: else the strided copy
    decides) and the first chunk's median time step (s)."""
    from rotacal.signal._checks import TYPICAL_STEPS
    from rotacal.signal._freq import estimate_frequency_unchecked
    from rotacal.table._stream_checks import _COPY_SAMPLES

    cols = source.read(0, min(n, _COPY_SAMPLES))
    t, y = cols["time_s"], cols["rate_deg_s"]
    typical = float(np.median(np.diff(t[: min(rows, TYPICAL_STEPS + 1)])))
    f = estimate_frequency_unchecked(t, y)
    return f, typical, n <= _COPY_SAMPLES or f * float(t[-1] - t[0]) >= 4.0


def _strided_task(source: CaptureRows, a: int, b: int, stride: int) -> tuple[np.ndarray, ...]:
    """Rows a … b − 1 whose index is a multiple of ``stride``: t (s) and rate (deg/s)."""
    cols = source.read(a, b)
    s0 = (-a) % stride
    return cols["time_s"][s0::stride].copy(), cols["rate_deg_s"][s0::stride].copy()


def _start(split: _Split) -> tuple[float, float]:
    """The start frequency (Hz) and the typical time step (s) that the check pass gives
    (:func:`~rotacal.table._stream_checks.start_frequency`), from reads of their own: the first
    2²⁰ samples, and when they hold too few periods every stride-th sample of the capture
    (the stride :class:`~rotacal.table._stream_checks.StridedCopy` ends with: the least power
    of two that keeps at most 2²¹ samples)."""
    from rotacal.signal._freq import estimate_frequency_unchecked
    from rotacal.table._stream_checks import _COPY_SAMPLES

    f, typical, enough = split.round(_start_task, [(split.source, split.n, split.rows)])[0]
    if enough:
        return f, typical
    stride = 1
    while -(-split.n // stride) > 2 * _COPY_SAMPLES:
        stride *= 2
    got = split.round(
        _strided_task, [(split.source, lo, hi, stride) for lo, hi in split.pieces(0, split.n - 1)]
    )
    t = np.concatenate([g[0] for g in got])
    y = np.concatenate([g[1] for g in got])
    return estimate_frequency_unchecked(t, y), typical


def _crossings_task(
    source: CaptureRows, a: int, b: int, fit: SineFit
) -> tuple[np.ndarray, np.ndarray]:
    """The fitted rate's zero crossings in block a … b − 1 and between the row before and a:
    their times (s) and (unclipped) sample indices."""
    from rotacal.table._stream_fog import chunk_crossings

    t = source.column("time_s", max(a - 1, 0), b)
    times: list[np.ndarray] = []
    indices: list[np.ndarray] = []
    if a == 0:
        chunk_crossings(fit, t, a, None, times, indices)
    else:
        chunk_crossings(fit, t[1:], a, float(t[0]), times, indices)
    return np.concatenate(times), np.concatenate(indices)


@dataclasses.dataclass(frozen=True)
class _Rows:
    """The analysed values of a capture's rows: its rate, or (``fit`` given) the angle integrated
    from the rate of samples ``first`` on (:func:`~rotacal.table._stream_fog.piece_angle`), each
    block's piece entering with its prefix (``prefixes``, by block number; zeros: each block's own
    running sum)."""

    source: CaptureRows
    rows: int
    first: int
    fit: SineFit | None = None
    prefixes: tuple[float, ...] = ()

    def values(self, lo: int, hi: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """t (s), the value (rate deg/s or angle deg) and the rate of rows lo … hi − 1."""
        from rotacal.table._stream_fog import piece_angle

        if self.fit is None:
            cols = self.source.read(lo, hi)
            return cols["time_s"], cols["rate_deg_s"], cols["rate_deg_s"]
        # the angle of a block's piece runs from the piece's start: read from there
        a = max(self.first, lo // self.rows * self.rows)
        back = 1 if a > self.first else 0
        cols = self.source.read(a - back, hi)
        t, w = cols["time_s"], cols["rate_deg_s"]
        cuts = [a, *range(a // self.rows * self.rows + self.rows, hi, self.rows), hi]
        angle = []
        for s, e in itertools.pairwise(cuts):
            i, j = s - a + back, e - a + back
            before = (float(t[i - 1]), float(w[i - 1])) if s > self.first else None
            prefix = self.prefixes[s // self.rows] if self.prefixes else 0.0
            angle.append(piece_angle(t[i:j], w[i:j], self.fit, before, prefix))
        k = lo - a + back
        return t[k:], np.concatenate(angle)[lo - a :], w[k:]


def _values_task(rows: _Rows, lo: int, hi: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    return rows.values(lo, hi)


def _end_task(rows: _Rows, lo: int, hi: int) -> float:
    """The last value of the block's piece lo … hi − 1 (its own running sum's, for the angle)."""
    return float(rows.values(lo, hi)[1][-1])


@dataclasses.dataclass
class _Block:
    """What a task gives of a block's piece: each add's moments, decimated t and value, its
    first and last t (s) and, with the sums, Σ value and the SNR's slice sums."""

    adds: list[list[PartMoments]]
    dec_t: np.ndarray
    dec_y: np.ndarray
    ends: tuple[float, float]
    total: float = 0.0
    snr: list[tuple[float, float]] = dataclasses.field(default_factory=list)


def _block_task(
    rows: _Rows,
    piece: tuple[int, int],
    templates: list[Fed],
    ranges: list[tuple[int, int]],
    step: int,
    sums: bool,
) -> _Block:
    """The block's piece lo … hi − 1: the moments of each add of ``ranges`` (they start in the
    piece; the last may run on) made to a planned part of each template
    (:func:`~rotacal.table._stream_fit.planned_part`, t through its map), the piece's decimated
    copies (every ``step``-th from ``rows.first``) and, if ``sums``, its angle sum and the SNR's
    slice sums."""
    from rotacal.table._stream_fit import decimate, moments_of, planned_part
    from rotacal.table._stream_fog import snr_sums

    lo, hi = piece
    t, y, w = rows.values(lo, max(hi, ranges[-1][1] if ranges else hi))
    adds = []
    for start, stop in ranges:
        t_add, y_add = t[start - lo : stop - lo], y[start - lo : stop - lo]
        parts = []
        for template, to_t in templates:
            part = planned_part(template)
            part.add(t_add if to_t is None else to_t(t_add), y_add)
            parts.append(moments_of(part))
        adds.append(parts)
    t, y, w = t[: hi - lo], y[: hi - lo], w[: hi - lo]
    out = _Block(
        adds,
        decimate(lo, rows.first, step, t),
        decimate(lo, rows.first, step, y),
        (float(t[0]), float(t[-1])),
    )
    if sums:
        assert rows.fit is not None
        out.total, out.snr = float(np.sum(y)), snr_sums(t, w, rows.fit)
    return out


def _error_task(rows: _Rows, lo: int, hi: int, error: tuple[Any, ...]) -> tuple[float, float, Any]:
    """Eq. (2) over the block's piece (:func:`~rotacal.table._stream_fit.piece_error`)."""
    from rotacal.table._stream_fit import piece_error

    t, y, _ = rows.values(lo, hi)
    return piece_error(lo, t, y, *error)


@dataclasses.dataclass
class _Split:
    """A capture split in blocks over a cluster: rounds of tasks over the pieces of a span."""

    client: Client
    source: CaptureRows
    n: int
    rows: int
    tick: Callable[[], None]

    def round(self, fn: Callable[..., Any], args: list[tuple[Any, ...]]) -> list[Any]:
        return task_round(self.client, fn, args, self.tick)

    def pieces(self, first: int, last: int) -> list[tuple[int, int]]:
        """Rows [lo, hi) of each block within samples first … last (the non-empty ones)."""
        ends = [*block_starts(self.n, self.rows), self.n]
        cut = [min(max(x, first), last + 1) for x in ends]
        return [(lo, hi) for lo, hi in itertools.pairwise(cut) if lo < hi]

    def accumulate(
        self,
        rows: _Rows,
        fed: list[Fed],
        block: int | None,
        last: int,
        sums: bool = False,
    ) -> tuple[list[_Block], tuple[list[np.ndarray], list[np.ndarray]], list[float]]:
        """Feed the values of samples rows.first … last to each accumulator with the adds one
        process's ``accumulate`` makes over the blocks
        (:func:`~rotacal.table._stream_fit.add_ranges`): the first (which sets the grid and the
        working offset) from a task of its own, the others in a task for the block they start
        in, their moments merged in order — the same sums in the same order as one process.
        Returns the blocks' results, the decimated t and values and the span's first and last
        t (s)."""
        from rotacal.table._stream_fit import add_ranges, merge_part, planned_part
        from rotacal.table.motion import _plot_stride

        first = rows.first
        step = _plot_stride(last + 1 - first)
        pieces = self.pieces(first, last)
        ranges = add_ranges(first, [hi - lo for lo, hi in pieces], block) if fed else []
        templates: list[Fed] = []
        if ranges:
            t, y, _ = self.round(_values_task, [(rows, *ranges[0])])[0]
            for acc, to_t in fed:
                acc.add(t if to_t is None else to_t(t), y)
            # the planned accumulators (their Vandermonde matrices: MB) sent to each worker once
            templates = self.client.scatter(
                [[(planned_part(acc), to_t) for acc, to_t in fed]], broadcast=True
            )[0]
        by_piece: dict[int, list[tuple[int, int]]] = {}
        starts = [lo for lo, _ in pieces]
        for r in ranges[1:]:
            by_piece.setdefault(int(np.searchsorted(starts, r[0], side="right")) - 1, []).append(r)
        args = [
            (rows, piece, templates, by_piece.get(k, []), step, sums)
            for k, piece in enumerate(pieces)
        ]
        blocks = self.round(_block_task, args)
        for b in blocks:
            for parts in b.adds:
                for (acc, _), part in zip(fed, parts, strict=True):
                    merge_part(acc, part)
        dec = ([b.dec_t for b in blocks], [b.dec_y for b in blocks])
        return blocks, dec, [blocks[0].ends[0], blocks[-1].ends[1]]


@one_blas_thread  # as one process: the client's fit sums in the same order
def calibrate_fog_motion_on_dask(
    path: str,
    *,
    client: Client,
    harmonics: int = 10,
    periods: int | None = None,
    set_amplitude_deg: float | None = None,
    set_frequency_hz: float | None = None,
    specs: InstrumentSpecs | None = None,
    allow_clipped: bool = False,
    drift: bool = False,
    mapping: dict[str, str] | None = None,
    group: str | None = None,
    read_options: ReadOptions | None = None,
    chunk_rows: int = CHUNK_ROWS,
    progress: Callable[[int], None] | None = None,
) -> MotionResult:
    """Sinusoidal-motion calibration of a fibre-optic gyro's rate (columns ``time_s`` in s,
    ``rate_deg_s`` in deg/s) computed by the workers of a Dask cluster (Feng et al. 2023, §4,
    eqs. (9)–(14); see the module for how the passes are split).

    Parameters
    ----------
    path : str
        The capture (NPZ saved without compression, HDF5 or TDMS), at a path every worker sees.
    client : distributed.Client
        The cluster's client.
    harmonics, periods, set_amplitude_deg, set_frequency_hz, specs, allow_clipped, drift
        As :func:`rotacal.table.calibrate_fog_motion_chunked` (harmonics N_H; set values in deg
        and Hz).
    mapping, group, read_options
        How to read the capture, as :func:`rotacal.io.read_capture`.
    chunk_rows : int
        Rows of a task's block. The result equals that of the single-process path read in
        chunks of as many rows (its default, 2·10⁶, is this one's): the fit's adds and the
        angle's prefixes follow the chunks.
    progress : callable, optional
        Called with the number of tasks done so far.

    Returns
    -------
    MotionResult
        As ``calibrate_fog_motion_chunked`` over the same file: reversals to the sample,
        numbers to ≤ 1e-9 relative.

    Raises
    ------
    CaptureError, ConfigError
        As the single-process path, with the same messages (the first fault in file order);
        ConfigError also for a capture that cannot be read from a given row on (CSV, a
        compressed NPZ member).

    References
    ----------
    Feng et al. (2023), Sensors 23:4876, §4, eqs. (2), (9)–(14), §5; IEEE Std 1057-2017, §4.1.3.
    """
    from rotacal.table._stream_source import FOG_COLUMNS
    from rotacal.table.motion import _check_set_values, _check_settings

    _check_settings(harmonics, periods)
    _check_set_values(set_amplitude_deg, set_frequency_hz)
    source, n = open_capture(
        path, FOG_COLUMNS, FOG_COLUMNS[1], chunk_rows, mapping, group, read_options
    )
    split = _Split(client, source, n, chunk_rows, Ticks(progress))
    name = FOG_COLUMNS[1]
    checked = client.submit(check_task, source, chunk_rows, {name: None}, name, pure=False)
    try:
        return _calibrate(
            split,
            checked,
            allow_clipped,
            (harmonics, drift),
            periods,
            (set_amplitude_deg, set_frequency_hz),
            specs,
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
    from rotacal.table._stream_checks import raise_signal_faults

    return check_findings(
        checked, n, path, allow_clipped, lambda found: raise_signal_faults(found, "rate_deg_s")
    )


def _calibrate(
    split: _Split,
    checked: Future,
    allow_clipped: bool,
    model: tuple[int, bool],
    periods: int | None,
    set_values: tuple[float | None, float | None],
    specs: InstrumentSpecs | None,
) -> MotionResult:
    """The rounds of :func:`calibrate_fog_motion_on_dask` (see the module), the check task
    running beside them until the reversals are cut."""
    from rotacal.table import _stream_fog as fog
    from rotacal.table._stream_fit import accumulator, block_length, true_time
    from rotacal.table.motion import _cut
    from rotacal.table.streaming import _GATHER_MAX_SAMPLES

    harmonics, drift = model
    n = split.n
    if n < 16 or split.rows < 2:  # the check's refusal, or a first chunk without a step
        found, _ = _checks(checked, n, split.source.path, allow_clipped)
        f_start, dt = fog.start_frequency_of(found), found.typical
    else:
        f_start, dt = _start(split)
    acc = accumulator(f_start, harmonics, dt)
    rate = _Rows(split.source, split.rows, 0)
    _, (dec_t, dec_w), _ = split.accumulate(
        rate, [(acc, None)], block_length(f_start, harmonics, dt), n - 1
    )
    first_fit = acc.fit(f_start, harmonics, True, max_iter=50, rtol=1e-12, drift=drift)
    found_x = split.round(
        _crossings_task, [(split.source, lo, hi, first_fit) for lo, hi in split.pieces(0, n - 1)]
    )
    rev_times = np.concatenate([x[0] for x in found_x])
    rev_idx = np.clip(np.concatenate([x[1] for x in found_x]), 0, n - 1)
    found, clipped = _checks(checked, n, split.source.path, allow_clipped)
    split.tick()
    first, last, n_periods = _cut(rev_idx, periods, "FOG capture")
    to_true = true_time(specs, float(found.first_t))
    f0 = first_fit.frequency_hz
    if last + 1 - first <= _GATHER_MAX_SAMPLES:  # gathered and analysed as in memory
        got = split.round(
            _values_task,
            [(dataclasses.replace(rate, first=first), *p) for p in split.pieces(first, last)],
        )

        def segment() -> Iterator[tuple[int, np.ndarray, np.ndarray]]:
            g0 = first
            for t, w, _ in got:
                yield g0, t, w
                g0 += t.size

        analysed = fog.analysed(
            segment, (first, last, _GATHER_MAX_SAMPLES), f0, model, set_values, to_true, dt
        )
    else:
        analysed = _analysed(split, first, last, f0, model, set_values, to_true, dt)
    return fog.fog_result(
        found,
        first_fit,
        (np.concatenate(dec_t), np.concatenate(dec_w)),
        (rev_times, n_periods),
        analysed,
        set_values,
        specs,
        clipped,
    )


def _analysed(
    split: _Split,
    first: int,
    last: int,
    f0: float,
    model: tuple[int, bool],
    set_values: tuple[float | None, float | None],
    to_true: Callable[[np.ndarray], np.ndarray] | None,
    dt: float | None,
) -> tuple[Any, Integrated, tuple[float, float, np.ndarray] | None]:
    """:func:`rotacal.table._stream_fog.analysed` of an accumulated span, in rounds of tasks."""
    from rotacal.table import _stream_fog as fog
    from rotacal.table._stream_fit import (
        accumulated_fit,
        accumulator,
        block_length,
        ideal_fit,
        position_error_of,
    )
    from rotacal.table.motion import _plot_stride

    harmonics, drift = model
    set_amplitude_deg, set_frequency_hz = set_values
    n_seg = last + 1 - first
    acc = accumulator(f0, harmonics, dt)
    rate = _Rows(split.source, split.rows, first)
    _, dec, ends = split.accumulate(rate, [(acc, None)], block_length(f0, harmonics, dt), last)
    seg = accumulated_fit(acc, f0, harmonics, drift, True, dec, ends, n_seg)
    # the angle: each piece's own last sum, the prefixes chained in order as one process adds
    pieces = split.pieces(first, last)
    own = _Rows(split.source, split.rows, first, seg.fit)
    prefixes = [0.0] * (split.n // split.rows + 1)
    prefix = 0.0
    for (lo, _), end in zip(
        pieces, split.round(_end_task, [(own, *p) for p in pieces]), strict=True
    ):
        prefixes[lo // split.rows] = prefix
        prefix = prefix + end
    angle = dataclasses.replace(own, prefixes=tuple(prefixes))
    fed: list[Fed] = []
    acc3 = None
    if set_amplitude_deg is not None and set_frequency_hz is not None:
        acc3 = accumulator(set_frequency_hz, 1, dt)
        fed.append((acc3, to_true))
    blocks, (_, dec_angle), _ = split.accumulate(angle, fed, None, last, sums=True)
    total = signal = noise = 0.0
    for b in blocks:  # in order, as one process adds them
        for sig, noi in b.snr:
            signal += sig
            noise += noi
        total += b.total
    integrated = fog.integrated(total, signal, noise, n_seg, np.concatenate(dec_angle))
    if acc3 is None or set_amplitude_deg is None or set_frequency_hz is None:
        return seg, integrated, None
    error = (
        ideal_fit(acc3, set_frequency_hz),
        set_amplitude_deg,
        set_frequency_hz,
        to_true,
        first,
        _plot_stride(n_seg),
    )
    parts = split.round(_error_task, [(angle, lo, hi, error) for lo, hi in pieces])
    return seg, integrated, position_error_of(parts, first, last)
