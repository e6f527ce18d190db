"""The pulse-timing rate of one huge capture (``rotacal rate``), as tasks on Dask distributed.

:func:`calibrate_rate_on_dask` gives what :func:`rotacal.table.rate_file.calibrate_rate_file`
gives for the same head (≤ 1e-9 relative, tested), with both passes of
:mod:`rotacal.table.rate_stream` split into blocks of ``chunk_rows`` pulses, each read by a
worker on its own (a shared file system; NPZ without compression, HDF5 or TDMS):

* **First round** — a task per block [a, b) checks its pulse times with the pulse before them
  (the checks and the messages of the single-process path, which checks the same chunks: with
  the same ``chunk_rows`` the same first fault in file order; one more task reads the column
  through in order for its stored checksum), and sums what starts in it: the
  timing jitter's filtered values (the 2m + 3 pulses after b read too), the terms of s(φ) that
  lie wholly inside it (their heads and tails kept), its rate points with the three before them
  (the rms statistics' lagged sums), the Welch windows that start in it (the points after it
  read too), the trend's centred sums, the times of whole revolutions and the first pulses.
  The provisional reference (the first rate point) is computed by the client up front.
* **The client** merges the blocks in order (:meth:`~rotacal.table.rate_stream.PassOne.merge`):
  the terms of s(φ) across each boundary from the carried tails and the next block's first
  decimated pulses (fewer than 2·k/d each, at every stride d), sums added exactly or in
  Chan's pairwise update; then the mean rate, the budgets' inputs and the Wiener gains.
* **Second round** — a task per block finds the peak's candidates among its rate points about
  the mean rate and filters the window that holds each (the windows' points around the block
  read when there are candidates).

The pass that places a deviation from another capture (folded sums per line and a line's
centred sums, :class:`~rotacal.table.rate_alignment.FoldSums`) is a round of its own, each
block checked as above; a capture's own self-calibration (several heads, none given) is made by
the client as on one machine.
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Iterator, Mapping
from os import PathLike
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from rotacal.batch._blocks import CaptureRows, Ticks, block_starts, task_round
from rotacal.errors import CaptureError, ConfigError

if TYPE_CHECKING:
    from distributed import Client

    from rotacal.encoder.selfcal import SelfCalibration
    from rotacal.table.rate import RateResult
    from rotacal.table.rate_alignment import FoldSums
    from rotacal.table.rate_stream import PassOne, RatePasses, RatePlan
    from rotacal.uncertainty import InstrumentSpecs
    from rotacal.uncertainty.summaries import ErrorProcess, PeakInputs

__all__ = ["calibrate_rate_on_dask"]

FloatArray = NDArray[np.float64]


def _points(
    t: FloatArray, plan: RatePlan, p0: int, *, nominal: bool = True
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """The rate points from p0 on (each from pulses p·A … (p + 1)·A, ``t`` their times in s,
    from pulse p0·A on) as the single-process path computes them: times (s), compensated and
    (``nominal``) uncompensated rates (deg/s)."""
    rp = plan.rate_points(nominal=nominal)
    rp.seen = p0 * plan.average
    nom, ang = rp.angles(t)
    return rp.push(t, ang, nom)


def _check_block(t: FloatArray, first: int, a: int, b: int, name: str) -> None:
    """Check pulses [a, b) with the pulse before them (``t``: the pulses from ``first`` on), as
    the single-process path checks a chunk: the same pulses, the same messages."""
    from rotacal.encoder.pulses import check_pulse_times

    lead = max(a - 1, 0)
    if b - lead >= 3:
        check_pulse_times(t[lead - first : b - first], name, first_index=lead)


def _fold_task(
    source: CaptureRows, n: int, m: int, t01: tuple[float, float], a: int, b: int
) -> FoldSums:
    """The alignment's folded sums over pulses [a, b) (``t01``: the train's first two pulse
    times, s), the pulses checked first."""
    from rotacal.table.rate_alignment import FoldSums

    lead = max(a - 1, 0)
    t = source.column(source.columns[0], lead, b)
    _check_block(t, lead, a, b, source.columns[0])
    fold = FoldSums.starting_at(n, m, a, *t01)
    fold.update(t[a - lead :])
    return fold


def _read_through(source: CaptureRows, rows: int) -> int:
    """Read the column through once, in order, as the single-process path reads it: a stored
    checksum (an NPZ member's CRC-32) covers the whole column and is checked at its end. The
    rows read."""
    name, n = source.columns[0], 0
    for part in source.chunks([name], rows):
        n += part[name].size
    return n


class _Integrity:
    """The whole column read through once by one task beside the first round over it (the
    single-process path checks the stored checksum at the end of its first pass)."""

    def __init__(
        self, client: Client, source: CaptureRows, rows: int, tick: Callable[[], None]
    ) -> None:
        self.client, self.source, self.rows, self.tick = client, source, rows, tick
        self.future: Any = None
        self.settled = False

    def start(self) -> None:
        """Submit the task (once)."""
        if self.future is None:
            self.future = self.client.submit(_read_through, self.source, self.rows, pure=False)

    def settle(self, pulses: int) -> None:
        """After a round without a fault: the task's error, if any (a damaged file)."""
        if self.settled or self.future is None:
            return
        read = self.future.result()
        self.tick()
        self.settled = True
        if read != pulses:
            raise CaptureError(
                f"{self.source.path}: {read} pulses were read, {pulses} declared; the file changed"
            )


def _dask_fold(
    pulses: int,
    m: int,
    *,
    client: Client,
    source: CaptureRows,
    chunk_rows: int,
    tick: Callable[[], None],
    integrity: _Integrity,
) -> FoldSums:
    """The alignment's pass (:class:`~rotacal.table.rate_alignment.FoldSums`) as a round of
    tasks, merged in block order."""
    from rotacal.table.rate_alignment import FoldSums

    fold = FoldSums(pulses, m)
    head = source.column(source.columns[0], 0, min(pulses, 2))
    if head.size < 2:  # nothing to split; the rate's checks refuse the train
        fold.update(head)
        return fold
    t01 = (float(head[0]), float(head[1]))
    blocks = [(a, min(pulses, a + chunk_rows)) for a in block_starts(pulses, chunk_rows)]
    integrity.start()
    for part in task_round(
        client, _fold_task, [(source, pulses, m, t01, a, b) for a, b in blocks], tick
    ):
        fold.merge(part)
    integrity.settle(pulses)
    return fold


def _first_task(
    source: CaptureRows, plan: RatePlan, ref: float, a: int, b: int
) -> tuple[PassOne, tuple[dict[int, Any], dict[int, Any] | None]] | None:
    """What the first pass gathers over pulses [a, b), as :meth:`PassOne.merge` takes it
    (None when the rows it reads past the block cannot be read)."""
    from rotacal.table.rate_allan_sums import AllanSums
    from rotacal.table.rate_stream import PassOne
    from rotacal.uncertainty.summaries_peak import WelchSums, window_length, window_starts
    from rotacal.uncertainty.summaries_rms import MAX_LAG

    n, m, avg, name = plan.n, plan.m, plan.average, source.columns[0]
    one = PassOne.empty(plan)
    # the rate points p·A in [a, b), the MAX_LAG − 1 before them, and the Welch windows that
    # start among them (with the points up to their ends)
    p0, p1 = -(-a // avg), min(plan.points, -(-b // avg))
    starts, size = window_starts(plan.points), window_length(plan.points)
    windows = np.flatnonzero((starts >= p0) & (starts < p1))
    q0 = max(0, p0 - (MAX_LAG - 1))
    q1 = max(p1, int(starts[windows[-1]]) + size) if windows.size else p1
    lead = max(a - 1, 0)
    r0, r1 = min(lead, q0 * avg), max(min(n, b + one.jitter.span), q1 * avg + 1)
    mine = source.column(name, lead, b)
    _check_block(mine, lead, a, b, name)
    try:  # the rows around the block are checked by the blocks they belong to
        t = np.concatenate((source.column(name, r0, lead), mine, source.column(name, b, r1)))
    except (CaptureError, ConfigError):
        return None  # a fault in another block's rows: that block reports it, in file order
    rp = plan.rate_points()
    rp.seen = r0
    nom_all, ang_all = rp.angles(t)  # once for the block and the rate points around it
    own, nom, ang = (x[a - r0 : b - r0] for x in (t, nom_all, ang_all))
    if a == 0:
        one.first_t = float(own[0])
    if b == n:
        one.last_t = float(own[-1])
    if a < plan.prefix_pulses:
        one.prefix_t.append(own[: plan.prefix_pulses - a].copy())
        one.prefix_a.append(nom[: plan.prefix_pulses - a].copy())
    if plan.revs >= 1:
        first = (-a) % m
        keep = np.arange(a + first, b, m) <= plan.revs * m
        one.rev_times.append(own[first::m][keep].copy())
        if a <= plan.revs * m < b:
            one.end_t = float(own[plan.revs * m - a])
    else:
        one.short_t.append(own.copy())
        one.short_a.append(ang.copy())
    one.jitter.update(t[a - r0 : min(n, b + one.jitter.span) - r0])  # terms starting in [a, b)
    ks, strides = plan.ks.tolist(), plan.strides
    one.allan = AllanSums.starting_at(ks, strides, a, jit=plan.compiled)
    heads = one.allan.heads(own, ang)
    one.allan.update(own, ang)
    heads_nom = None
    if one.allan_nom is not None:
        one.allan_nom = AllanSums.starting_at(ks, strides, a, jit=plan.compiled)
        heads_nom = one.allan_nom.heads(own, nom)
        one.allan_nom.update(own, nom)
    if p1 > p0:
        span = slice(q0 * avg - r0, q1 * avg + 1 - r0)
        t_avg, rate, rate_nom = plan.rate_points().push(t[span], ang_all[span], nom_all[span])
        d = 100.0 * (rate - ref) / ref
        d0 = d[p0 - q0 : p1 - q0]
        stats = one.stats
        stats.n, stats.tail = p0, d[: p0 - q0]
        stats.update(d0)
        if windows.size:
            s = int(starts[windows[0]])
            one.welch = WelchSums(plan.points, _buffer_start=s, _next=int(windows[0]))
            one.welch.update(d[s - q0 :])
        one.trend.update(t_avg[p0 - q0 : p1 - q0], d0)
        dn = d0
        if plan.deviation is not None:
            dn = 100.0 * (rate_nom[p0 - q0 : p1 - q0] - ref) / ref
        one.add_extremes(d0, dn)
    return one, (heads, heads_nom)


def _second_task(
    source: CaptureRows,
    plan: RatePlan,
    mean_rate: float,
    floor: float,
    gains: list[FloatArray],
    a: int,
    b: int,
) -> tuple[float, NDArray[np.int64], FloatArray, list[FloatArray]]:
    """The second pass over the rate points p·A in [a, b): their largest |d| about the mean rate
    (%), the candidates |d| ≥ ``floor``, their values and their values filtered by each gain
    in the window whose middle holds them (:class:`~rotacal.uncertainty.summaries_peak.
    PeakCollector`'s arithmetic)."""
    from rotacal.uncertainty.summaries_peak import (
        denoised_at,
        window_length,
        window_of,
        window_starts,
    )

    avg, points = plan.average, plan.points
    p0, p1 = -(-a // avg), min(points, -(-b // avg))
    if p1 <= p0:
        return 0.0, np.zeros(0, dtype=np.int64), np.zeros(0), [np.zeros(0) for _ in gains]

    def deviation(q0: int, q1: int) -> FloatArray:
        t = source.column(source.columns[0], q0 * avg, q1 * avg + 1)
        _, rate, _ = _points(t, plan, q0, nominal=False)
        return np.asarray(100.0 * (rate - mean_rate) / mean_rate, dtype=np.float64)

    d, q0 = deviation(p0, p1), p0
    mine = np.abs(d)
    pos = np.flatnonzero(mine >= floor).astype(np.int64) + p0
    base = d[pos - q0]
    den = [np.empty(pos.size) for _ in gains]
    which = window_of(pos, points)
    starts, size = window_starts(points), window_length(points)
    if pos.size:  # the candidates are few: their windows' points around the block only then
        lo, hi = int(starts[which[0]]), int(starts[which[-1]]) + size
        if lo < p0 or hi > p1:
            d, q0 = deviation(lo, hi), lo
    for j in np.unique(which).tolist():
        sel = np.flatnonzero(which == j)
        s = int(starts[j])
        values = d[s - q0 : s - q0 + size]
        for out, filtered in zip(den, denoised_at(values, pos[sel] - s, gains), strict=True):
            out[sel] = filtered
    return float(mine.max()), pos, base, den


def _dask_passes(
    chunks: Callable[[], Iterator[FloatArray]],
    pulses: int,
    *,
    client: Client,
    source: CaptureRows,
    chunk_rows: int,
    tick: Callable[[], None],
    integrity: _Integrity,
    sources_for: Callable[[float, tuple[float, float, bool]], list[ErrorProcess]],
    keep_series: bool = False,
    progress: Callable[[int], None] | None = None,
    **settings: Any,
) -> RatePasses:
    """:func:`rotacal.table.rate_stream.rate_passes` with both passes as rounds of tasks
    (``chunks`` is not read: each task reads its own block)."""
    from rotacal.table.rate_stream import PassOne, finish_passes, rate_plan
    from rotacal.uncertainty.summaries import PeakInputs

    if keep_series:
        raise ConfigError("the rate points of a capture split over workers are not kept")
    plan = rate_plan(pulses, **settings)
    head = source.column(source.columns[0], 0, plan.average + 1)
    _, first, _ = _points(head, plan, 0)
    ref = float(first[0])  # the provisional reference: the first rate point
    starts = block_starts(plan.n, chunk_rows)
    blocks = [(a, min(plan.n, a + chunk_rows)) for a in starts]
    one = PassOne.empty(plan)
    one.ref = ref
    integrity.start()
    for part in task_round(
        client, _first_task, [(source, plan, ref, a, b) for a, b in blocks], tick
    ):
        if part is None:  # the block whose rows those are raised first: never reached
            raise CaptureError(f"{source.path}: rows of the capture could not be read again")
        one.merge(*part)
    integrity.settle(plan.n)

    def second(mean_rate: float, floor: float, gains: list[FloatArray]) -> PeakInputs:
        parts = task_round(
            client,
            _second_task,
            [(source, plan, mean_rate, floor, gains, a, b) for a, b in blocks],
            tick,
        )
        return PeakInputs(
            plan.points,
            max(p[0] for p in parts),
            np.concatenate([p[1] for p in parts]),
            np.concatenate([p[2] for p in parts]),
            [np.concatenate([p[3][i] for p in parts]) for i in range(len(gains))],
        )

    return finish_passes(plan, one, sources_for, second)


def calibrate_rate_on_dask(
    path: str | PathLike[str],
    *,
    client: Client,
    pulses_per_rev: int,
    selfcal: SelfCalibration | Mapping[str, Any] | ArrayLike | None = None,
    head: int | str = 0,
    average: int = 10,
    set_rate_deg_s: float | None = None,
    allan_angles_deg: ArrayLike | None = None,
    compensate: bool = True,
    specs: InstrumentSpecs | None = None,
    mapping: Any = None,
    group: str | None = None,
    read_options: Any = None,
    chunk_rows: int | None = None,
    progress: Callable[[int], None] | None = None,
) -> RateResult:
    """:func:`rotacal.table.rate_file.calibrate_rate_file` of one head of a capture, its two
    passes split over the workers of a Dask cluster (see the module for how).

    Parameters
    ----------
    path : str
        The capture (NPZ saved without compression, HDF5 or TDMS), at a path every worker sees.
    client : distributed.Client
        The cluster's client.
    pulses_per_rev, selfcal, head, average, set_rate_deg_s, allan_angles_deg, compensate, specs
        As :func:`~rotacal.table.rate_file.calibrate_rate_file` (m pulses per revolution,
        ``average`` intervals per rate point, the set rate in deg/s, s(φ) angles in deg).
    mapping, group, read_options
        How to read the capture, as :func:`rotacal.io.read_capture`.
    chunk_rows : int, optional
        Pulses of a task's block [default: the single-process path's chunk,
        :data:`rotacal.table.rate_file.CHUNK_PULSES`, which checks the same chunks].
    progress : callable, optional
        Called with the number of tasks done so far (the passes the client makes itself, the
        alignment and the self-calibration, are not counted).

    Returns
    -------
    RateResult
        As ``calibrate_rate_file`` over the same file to ≤ 1e-9 relative.

    Raises
    ------
    CaptureError, ConfigError
        As the single-process path, with the same messages; ConfigError also for a capture that
        cannot be read from a given row on (CSV, a compressed NPZ member).

    References
    ----------
    Kokuyama et al. (2015) §5; see :func:`rotacal.table.rate.calibrate_rate`.
    """
    from rotacal.table.rate_file import CHUNK_PULSES, HeadPasses, calibrate_rate_file

    rows = CHUNK_PULSES if chunk_rows is None else int(chunk_rows)
    if rows < 1:
        raise ConfigError(f"chunk_rows must be positive, got {chunk_rows}")
    tick = Ticks(progress)

    def split(column: str) -> dict[str, Any]:
        """How a pass over the column is split: the client, the rows, the blocks' size, the
        read-through of the column (shared by the passes: the first one waits for it)."""
        rows_of = CaptureRows(str(path), (column,), mapping, group, read_options)
        if column not in checks:
            checks[column] = _Integrity(client, rows_of, rows, tick)
        return {
            "client": client,
            "source": rows_of,
            "chunk_rows": rows,
            "tick": tick,
            "integrity": checks[column],
        }

    checks: dict[str, _Integrity] = {}
    return calibrate_rate_file(
        path,
        pulses_per_rev=pulses_per_rev,
        selfcal=selfcal,
        head=head,
        average=average,
        set_rate_deg_s=set_rate_deg_s,
        allan_angles_deg=allan_angles_deg,
        compensate=compensate,
        specs=specs,
        mapping=mapping,
        group=group,
        read_options=read_options,
        chunk_rows=rows,
        passes_for=lambda column: HeadPasses(
            fold=functools.partial(_dask_fold, **split(column)),
            rate=functools.partial(_dask_passes, **split(column)),
        ),
    )
