"""The partial sums of a long gyro log's blocks, merged in row order into those of one pass.

:func:`rotacal.gyro.scale_factor_stream.calibrate_scale_factor_chunked` carries its state from
chunk to chunk. Split over processes (:mod:`rotacal.batch.capture_scale_factor`), each block of
rows is summed from a state that does not depend on the rows before it, and the blocks are
merged here, in row order, into the state one pass reaches:

* **Pass 1** (:class:`_RatePoints` of each block, from the block's first row): the groups of set
  rates merge as the chunks' groups do in one pass (the union of spans by single linkage, the
  same decisions on the same values); rows, refused rates and the largest magnitude add up.
* **Between the passes**: each block's groups lie inside one merged group each, so the samples
  of every rate point before each block (``seen``) are sums of the blocks' group sizes. A block
  of pass 2 starts from them: each sample's index within its point, hence the quantum's samples
  and the boundaries of the resolution's blocks, are the log's.
* **Pass 2** (:class:`_PointSums` of each block): counts, means and M2 merge pairwise (Chan et
  al. 1983, eq. 2.1), each block's mean moved from its own first sample to the log's (the
  means are kept less a point's first sample, for their digits); the two largest and smallest
  values with their counts and the distinct levels (capped) merge as sets; the rails merge
  with :meth:`rotacal.signal.RailDetector.merge`; the block open at a block's start is completed
  with the sum the rows before carried (the block held the rest apart, ``head_sum``), and its
  mean merged before the block's own.

The result equals one pass's to rounding (tested to 1e-9 relative against it); a log read from
a file holds finite samples only (the readers refuse NaN and inf).

References
----------
Chan T. F., Golub G. H., LeVeque R. J. (1983), "Algorithms for computing the sample variance:
analysis and recommendations", Am. Stat. 37(3), 242–247, eq. (2.1).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from rotacal.gyro.scale_factor_points import _SHOW_ROWS
from rotacal.gyro.scale_factor_stream import (
    _LEVELS_CAP,
    _Blocks,
    _chan_merge,
    _FirstRows,
    _Levels,
    _Magnitudes,
    _merge_spans,
    _PointSums,
    _RatePoints,
    _Top2,
)

__all__ = ["merge_point_sums", "merge_rate_points", "points_seen"]


def _merge_rows(a: _FirstRows, b: _FirstRows) -> None:
    a.count += b.count
    a.first = (a.first + b.first)[:_SHOW_ROWS]


def _merge_magnitudes(a: _Magnitudes, b: _Magnitudes) -> None:
    if b.largest > a.largest:  # a tie keeps the earlier sample, as one pass does
        a.largest, a.value, a.row = b.largest, b.value, b.row


def merge_rate_points(parts: Sequence[_RatePoints]) -> _RatePoints:
    """Pass 1 of the blocks (in row order), merged into that of one pass over the log (a new
    one: the blocks' own groups are still needed, by :func:`points_seen`)."""
    total = _RatePoints(parts[0].tol)
    for later in parts:
        total.n = later.n
        _merge_rows(total.bad, later.bad)
        _merge_magnitudes(total.magnitudes, later.magnitudes)
        if total.bad.count:
            continue  # refused at the end with the count of all of them, as in one pass
        total.lo, total.hi, total.rows = _merge_spans(
            np.r_[total.lo, later.lo],
            np.r_[total.hi, later.hi],
            np.r_[total.rows, later.rows],
            total.tol,
        )
        total.check_count()
    return total


def points_seen(parts: Sequence[_RatePoints], points: _RatePoints) -> list[np.ndarray]:
    """The samples of each rate point of ``points`` before each block of ``parts``."""
    ng = points.lo.size
    seen, out = np.zeros(ng, dtype=np.int64), []
    for part in parts:
        out.append(seen.copy())
        group = np.searchsorted(points.lo, part.lo, side="right") - 1
        seen += np.bincount(group, weights=part.rows, minlength=ng).astype(np.int64)
    return out


def _merge_levels(a: _Levels, b: _Levels) -> None:
    """The distinct values of both (each point's first ``_LEVELS_CAP``; a capped count stays)."""
    both = np.sort(np.concatenate([a.known, b.known], axis=1), axis=1)  # NaN (empty) last
    distinct = ~np.isnan(both)
    distinct[:, 1:] &= both[:, 1:] != both[:, :-1]
    rank = np.cumsum(distinct, axis=1) - 1
    rows, cols = np.nonzero(distinct & (rank < _LEVELS_CAP))
    a.known[:] = np.nan
    a.known[rows, rank[rows, cols]] = both[rows, cols]
    a.count = np.minimum(distinct.sum(axis=1), _LEVELS_CAP)


def _merge_top2(a: _Top2, b: _Top2) -> None:
    g = np.flatnonzero(b.k_top > 0)
    a.fold(g, b.top[g], b.k_top[g], b.second[g], b.k_second[g])


def _merge_blocks(a: _Blocks, b: _Blocks, corr: np.ndarray) -> None:
    """The resolution's blocks: the one open at b's start completed with a's carried sum, then
    b's complete blocks; ``corr`` moves b's sums to a's first samples (per point)."""
    size = a.block
    entered = b.entry_n > 0
    done = entered & ~b.pending  # b completed the block open at its start
    g = np.flatnonzero(done)
    if g.size:
        full = a.carry_sum[g] + b.head_sum[g] + (size - b.entry_n[g]) * corr[g]
        _chan_merge(a.n, a.mean, a.m2, g, np.ones(g.size), full / size, np.zeros(g.size))
    own = b.carry_sum + (b.carry_n - np.where(entered & b.pending, b.entry_n, 0)) * corr
    a.carry_sum = np.where(entered & b.pending, a.carry_sum + own, own)
    a.carry_n = b.carry_n.copy()
    g = np.flatnonzero(b.n > 0)
    _chan_merge(a.n, a.mean, a.m2, g, b.n[g], b.mean[g] + corr[g], b.m2[g])


def _fold_sums(a: _PointSums, b: _PointSums) -> None:
    """Pass 2 of the block ``b`` folded into ``a``, the sums of the rows before it."""
    before, has = a.n > 0, b.n > 0
    corr = np.where(before & has, b.shift - a.shift, 0.0)  # b's first samples → the log's
    first = has & ~before
    a.shift[first] = b.shift[first]
    g = np.flatnonzero(has)
    _chan_merge(a.n, a.mean, a.m2, g, b.n[g], b.mean[g] + corr[g], b.m2[g])
    a.rate_excess += b.rate_excess
    a.n_rows = b.n_rows
    a.copy, a.negative = a.copy and b.copy, a.negative and b.negative
    a.rails.merge(b.rails)
    _merge_rows(a.bad, b.bad)
    _merge_magnitudes(a.magnitudes, b.magnitudes)
    a.abs_max = max(a.abs_max, b.abs_max)
    _merge_top2(a.highs, b.highs)
    _merge_top2(a.lows, b.lows)
    _merge_levels(a.levels, b.levels)
    if a.blocks.block > 1:
        _merge_blocks(a.blocks, b.blocks, corr)
    a.kept += b.kept


def merge_point_sums(parts: Sequence[_PointSums]) -> _PointSums:
    """Pass 2 of the blocks (in row order, each made with its ``start`` and ``seen``), merged
    into that of one pass over the log (into the first block's, which it changes)."""
    total = parts[0]
    for later in parts[1:]:
        _fold_sums(total, later)
    return total
