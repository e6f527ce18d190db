"""One huge LTS capture's sinusoidal-motion calibration, as tasks on Dask distributed.

:func:`calibrate_lts_motion_on_dask` gives what :func:`rotacal.table.calibrate_lts_motion_chunked`
gives for the same file (reversals to the sample, numbers to ≤ 1e-9 relative, tested), with the
passes split over a cluster's workers in blocks of ``chunk_rows`` rows, each task reading its own
rows (a shared file system; NPZ without compression, HDF5 or TDMS). θ = arctan(D/R) is
recomputed from D in every task. The single-process passes (:mod:`rotacal.table._stream_lts`)
become:

* **Checks** — one task reads the file through once, in order, with every check of the
  single-process path's first pass; it runs beside the other rounds, and its fault, if any, is
  the one reported (the first in file order). With ``drift`` its copies are needed first.
* **Drift prefit** (``drift``) — the straight line's running sums per block, added in block
  order; then the multi-harmonic fit with a linear term, its moments accumulated per task and
  merged in order as :mod:`rotacal.batch.capture_motion` merges the analysis fit's.
* **Trigger levels** — the 2 % and 98 % percentiles are exact order statistics: a round gives
  each block's smallest and largest value, then each narrowing pass of the rank search is a
  round whose blocks' tallies (counts below, histograms, the few values gathered) add up
  exactly.
* **Swings** — each block's runs between the Schmitt trigger's edges are found without the
  state carried in; the client joins them in block order carrying the trigger's state and the
  open swing's extremes (first occurrence), as one pass does.
* **Parabolas** — a round gives the samples of each reversal's window held by each block; the
  client fits each window's samples in order.
* **Fit** — the analysis fit and eq. (2) as the encoder's split runs them
  (:mod:`rotacal.batch.capture_motion`), on θ of the analysed samples.

References
----------
Feng R., Yan J., Wu Y., Yu N., Yin X. (2023). Sensors 23, 4876, §5, eqs. (1), (2), (15);
IEEE Std 1057-2017, §4.1.3.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import numpy as np

from rotacal._threads import one_blas_thread
from rotacal.batch._blocks import CaptureRows, Ticks, check_findings, check_task, open_capture
from rotacal.batch.capture_motion import _accumulate, _fit, _Split

if TYPE_CHECKING:
    from distributed import Client, Future

    from rotacal.io.read_options import ReadOptions
    from rotacal.signal import SineFit
    from rotacal.table._stream_checks import Checked
    from rotacal.table._stream_lts import SwingRuns, Tally
    from rotacal.table.motion import MotionResult
    from rotacal.uncertainty import InstrumentSpecs

__all__ = ["calibrate_lts_motion_on_dask"]

#: Rows of a block, the unit of work of a task: the single-process path's chunk.
CHUNK_ROWS = 2_000_000

_SIGNAL = "displacement_mm"


@dataclasses.dataclass(frozen=True)
class _Line:
    """θ less a straight line of ``slope`` (deg/s) through ``t_mid`` (s): the drift prefit."""

    slope: float
    t_mid: float


@dataclasses.dataclass(frozen=True)
class _Trigger:
    """What the trigger sees: θ = arctan(D/R) (R in mm) less ``trend``·(t − ``t0``) (deg/s, s)."""

    radius_mm: float
    trend: float
    t0: float

    def block(self, source: CaptureRows, a: int, b: int) -> tuple[np.ndarray, ...]:
        """t (s), θ (deg) and what the trigger sees (deg) of rows a … b − 1."""
        from rotacal.table._stream_lts import trigger_piece

        return trigger_piece(source.read(a, b), self.radius_mm, self.trend, self.t0)


def _range_task(source: CaptureRows, a: int, b: int, trig: _Trigger) -> tuple[float, float]:
    """The smallest and largest value the trigger sees in the block (deg)."""
    xt = trig.block(source, a, b)[2]
    return float(np.min(xt)), float(np.max(xt))


def _tally_task(
    source: CaptureRows,
    a: int,
    b: int,
    trig: _Trigger,
    keys: list[tuple[float, float]],
    gather: dict[tuple[float, float], bool],
) -> Tally:
    """The block's part of a pass of the rank search (:func:`~rotacal.table._stream_lts.tally`)."""
    from rotacal.table._stream_lts import tally

    return tally([trig.block(source, a, b)[2]], keys, gather)


def _swing_task(
    source: CaptureRows, a: int, b: int, trig: _Trigger, mid: float, h: float, step: int
) -> tuple[SwingRuns, float, float]:
    """The block's runs between the trigger's edges, and its first and last time (s)."""
    from rotacal.table._stream_lts import swing_runs

    t, x, xt = trig.block(source, a, b)
    return swing_runs(a, t, x, xt, mid, h, step), float(t[0]), float(t[-1])


def _window_task(
    source: CaptureRows,
    a: int,
    b: int,
    trig: _Trigger,
    windows: _Windows,
    edges: tuple[bool, bool],
) -> tuple[list[tuple[int, float, int]], list[tuple[int, int, np.ndarray, np.ndarray]]]:
    """The reversing moment (s) and sample index of each window of ``windows`` the block holds
    whole; the block's samples of the others (cut by its start or end, unless ``edges`` says
    that is the capture's first or last row)."""
    from rotacal.table._stream_lts import window_moment, window_pieces

    t, x, _ = trig.block(source, a, b)
    done, cut = [], []
    for piece in window_pieces(a, t, x, windows.lo, windows.hi, windows.which):
        j, g0, t_w, _ = piece
        i = windows.which.index(j)
        whole = (g0 > a or edges[0]) and (g0 + t_w.size < b or edges[1])
        if whole:
            done.append(
                (j, *window_moment([piece[1:]], windows.t_ext[i], windows.sign[i], windows.half))
            )
        else:
            cut.append(piece)
    return done, cut


@dataclasses.dataclass(frozen=True)
class _Windows:
    """Reversal windows ``which``: their first and last times (s), their extreme's time (s) and
    sign, and the half window (s)."""

    which: list[int]
    lo: np.ndarray
    hi: np.ndarray
    t_ext: list[float]
    sign: list[int]
    half: float


def _line_task(
    source: CaptureRows, a: int, b: int, trig: _Trigger, t_mid: float
) -> tuple[float, float, float, float]:
    """The block's sums of the prefit's straight line (:func:`~rotacal.table._stream_lts.line_sums`)."""
    from rotacal.table._stream_lts import line_sums

    t, x, _ = trig.block(source, a, b)
    return line_sums(t, x, t_mid)


@dataclasses.dataclass(frozen=True)
class _LtsSpan:
    """Rows ``lo`` … ``hi − 1`` whose θ a task of the fit computes (the encoder's ``_Span``)."""

    source: CaptureRows
    radius_mm: float
    lo: int
    hi: int

    def theta(self, detrend: SineFit | _Line | None) -> tuple[np.ndarray, np.ndarray]:
        """t (s) and θ (deg) of the rows, less ``detrend``'s drift or line if given."""
        from rotacal.table.motion_drift import detrended_angle

        t, x, _ = _Trigger(self.radius_mm, 0.0, 0.0).block(self.source, self.lo, self.hi)
        if detrend is None:
            return t, x
        if isinstance(detrend, _Line):
            return t, x - detrend.slope * (t - detrend.t_mid)
        return t, detrended_angle(detrend, t, x)


@dataclasses.dataclass
class _LtsSplit(_Split):
    """The encoder's split with LTS spans (no phase state: θ of a row is its own)."""

    radius_mm: float = 1.0

    def span(self, j: int, lo: int, hi: int, jit: bool) -> Any:
        return _LtsSpan(self.source, self.radius_mm, lo, hi)

    def blocks(self) -> list[tuple[int, int]]:
        return [(a, min(self.n, a + self.rows)) for a in self.starts]

    def each_block(self, fn: Callable[..., Any], trig: _Trigger, *extra: Any) -> list[Any]:
        """``fn(source, a, b, trig, *extra)`` of every block, in block order."""
        return self.round(fn, [(self.source, a, b, trig, *extra) for a, b in self.blocks()])


@one_blas_thread  # as one process: the client's fits sum in the same order
def calibrate_lts_motion_on_dask(
    path: str,
    *,
    client: Client,
    radius_mm: float,
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
    """Sinusoidal-motion calibration of an LTS capture (columns ``time_s``, ``displacement_mm``)
    computed by the workers of a Dask cluster (see the module for how the passes are split).

    Parameters
    ----------
    path : str
        The capture (NPZ saved without compression, HDF5 or TDMS), at a path every worker sees.
    client : distributed.Client
        The cluster's client.
    radius_mm : float
        R, mm: from the laser spot to the table's axis.
    harmonics, periods, set_amplitude_deg, set_frequency_hz, specs, allow_clipped, drift
        As :func:`rotacal.table.calibrate_lts_motion_chunked` (set values in deg and Hz).
    mapping, group, read_options
        How to read the capture, as :func:`rotacal.io.read_capture`.
    chunk_rows : int
        Rows of a task's block. The result equals that of the single-process path read in
        chunks of as many rows (its default, 2·10⁶, is this one's): the fit's adds, and so its
        sums, follow the chunks.
    progress : callable, optional
        Called with the number of tasks done so far.

    Returns
    -------
    MotionResult
        As ``calibrate_lts_motion_chunked`` over the same file: reversals to the sample,
        numbers to ≤ 1e-9 relative.

    Raises
    ------
    CaptureError, ConfigError
        As the single-process path, with the same messages (the first fault in file order);
        ConfigError also for a capture that cannot be read from a given row on (CSV, a
        compressed NPZ member).

    References
    ----------
    Feng et al. (2023), Sensors 23:4876, §5, eqs. (1), (2), (15); IEEE Std 1057-2017, §4.1.3.
    """
    from rotacal.table._stream_source import LTS_COLUMNS
    from rotacal.table.streaming import check_lts_run

    check_lts_run(harmonics, periods, radius_mm, set_amplitude_deg, set_frequency_hz)
    source, n = open_capture(path, LTS_COLUMNS, _SIGNAL, chunk_rows, mapping, group, read_options)
    split = _LtsSplit(client, source, n, chunk_rows, Ticks(progress), radius_mm=float(radius_mm))
    checked = client.submit(
        check_task, source, chunk_rows, {_SIGNAL: None}, _SIGNAL if drift else None, pure=False
    )
    checks = _Checks(checked, n, str(path), float(radius_mm), allow_clipped, split.tick)
    try:
        return _calibrate(
            split,
            checks,
            harmonics,
            periods,
            (set_amplitude_deg, set_frequency_hz),
            specs,
            drift,
        )
    except Exception:
        checks()  # the fault the single-process path finds first, if the file has one
        raise


@dataclasses.dataclass
class _Checks:
    """The check task's findings, its faults raised as one process raises them (once)."""

    checked: Future
    n: int
    path: str
    radius_mm: float
    allow_clipped: bool
    tick: Callable[[], None]
    got: tuple[Checked, tuple[str, ...]] | None = None

    def __call__(self) -> tuple[Checked, tuple[str, ...]]:
        """The findings and the clipping warnings."""
        from rotacal.table.streaming import lts_faults

        if self.got is None:
            found, clipped = check_findings(
                self.checked,
                self.n,
                self.path,
                self.allow_clipped,
                lambda found: lts_faults(found, self.radius_mm, self.allow_clipped),
            )
            self.tick()
            self.got = found, clipped
        return self.got


def _calibrate(
    split: _LtsSplit,
    checks: _Checks,
    harmonics: int,
    periods: int | None,
    set_values: tuple[float | None, float | None],
    specs: InstrumentSpecs | None,
    drift: bool,
) -> MotionResult:
    """The rounds of :func:`calibrate_lts_motion_on_dask` (see the module)."""
    from rotacal.table import _stream_lts as lts
    from rotacal.table.motion import _plot_stride
    from rotacal.table.motion_lts_fog import TRIGGER_PERCENTILES, trigger_levels
    from rotacal.table.streaming import lts_cut, lts_result

    n = split.n
    if n < 16 or drift:  # too short for any round; or the prefit needs the first pass's copies
        found, _ = checks()
        trig = _Trigger(split.radius_mm, _drift(split, found, harmonics), float(found.first_t))
    else:
        trig = _Trigger(split.radius_mm, 0.0, 0.0)
    ranges = split.each_block(_range_task, trig)
    lo_x, hi_x = min(r[0] for r in ranges), max(r[1] for r in ranges)

    def count(keys: list[tuple[float, float]], gather: dict[tuple[float, float], bool]) -> Tally:
        first, *rest = split.each_block(_tally_task, trig, keys, gather)
        for part in rest:
            first.merge(part)
        return first

    def order(ranks: list[int]) -> list[float]:
        return lts.search_ranks(count, ranks, lo_x, hi_x)

    q_lo, q_hi = TRIGGER_PERCENTILES
    p_lo, p_hi = lts.percentiles(n, [q_lo, q_hi], order)
    mid, h = trigger_levels(p_lo, p_hi, None)
    found, clipped = checks()
    fold = lts.SwingFold(n, h)
    bounds = []
    for runs, t_a, t_b in split.each_block(_swing_task, trig, mid, h, _plot_stride(n)):
        fold.add(runs)
        bounds.append((t_a, t_b))
    ext = fold.finish()
    t0 = float(found.first_t)
    rev_times, rev_idx = _refine(split, trig, ext, float(found.last_t) - t0, bounds)
    first, last, n_periods = lts_cut(found, split.radius_mm, drift, rev_idx, periods)
    f0 = n_periods / (rev_times[2 * n_periods] - rev_times[0])
    seg, error = _fit(
        split, first, last, f0, harmonics, drift, set_values, specs, t0, found.typical
    )
    return lts_result(
        ext,
        seg,
        error,
        (first, last, rev_times, n_periods, t0),
        split.radius_mm,
        *set_values,
        specs,
        clipped,
    )


def _drift(split: _LtsSplit, found: Checked, harmonics: int) -> float:
    """The drift prefit (:func:`~rotacal.table._stream_lts.prefit_drift_chunked`) in rounds."""
    from rotacal.table import _stream_lts as lts
    from rotacal.table._stream_fit import accumulator, block_length

    t_mid = lts.mid_time(found)
    sums = split.each_block(_line_task, _Trigger(split.radius_mm, 0.0, 0.0), t_mid)
    slope = lts.line_slope(sums, found.n)
    f0 = lts.drift_start_frequency(found, split.radius_mm, slope)
    acc = accumulator(f0, harmonics, found.typical)
    block = block_length(f0, harmonics, found.typical)
    _accumulate(split, [(acc, None)], block, 0, found.n - 1, _Line(slope, t_mid))  # type: ignore[arg-type]
    return lts.drift_of(acc, f0, harmonics, slope)


def _refine(
    split: _LtsSplit,
    trig: _Trigger,
    ext: Any,
    span_s: float,
    bounds: list[tuple[float, float]],
) -> tuple[np.ndarray, np.ndarray]:
    """Reversing moments (s) and sample indices (clipped to the capture): the samples of each
    window from the blocks whose time span meets it, in block order, then each parabola."""
    from rotacal.table._stream_lts import finish_window, reversal_windows

    times, indices = np.empty(ext.index.size), np.empty(ext.index.size, dtype=np.intp)
    if ext.index.size == 0:
        return times, indices
    lo, hi, half = reversal_windows(ext, span_s)
    args = []
    blocks = split.blocks()
    for k, ((a, b), (t_a, t_b)) in enumerate(zip(blocks, bounds, strict=True)):
        which = np.flatnonzero((lo <= t_b) & (hi >= t_a)).tolist()
        if which:
            windows = _Windows(
                which,
                lo[which],
                hi[which],
                ext.time[which].tolist(),
                ext.sign[which].tolist(),
                half,
            )
            args.append((split.source, a, b, trig, windows, (k == 0, k == len(blocks) - 1)))
    parts: dict[int, list[tuple[int, np.ndarray, np.ndarray]]] = {}
    for done, cut in split.round(_window_task, args):
        for j, moment, index in done:
            times[j], indices[j] = moment, index
        for j, g0, t_w, x_w in cut:
            parts.setdefault(j, []).append((g0, t_w, x_w))
    for j, pieces in parts.items():  # the windows cut by a block boundary
        finish_window(j, pieces, ext, half, times, indices)
    return times, np.clip(indices, 0, split.n - 1)
