"""Gyro scale factor and nonlinearity from a long log read in chunks (Kokuyama et al. 2015, §4).

:func:`calibrate_scale_factor_chunked` gives the same :class:`ScaleFactorResult` as
:func:`~rotacal.gyro.scale_factor.calibrate_scale_factor` while reading the capture chunk by
chunk, so memory is set by the chunk size and the number of rate points, not by the log's length.
Each pass is a fresh call of ``chunks(columns)``:

1. ``rate_deg_s`` alone: the rate points. Single linkage with a tolerance only ever merges groups
   as rows are added, and a new rate joins a group exactly when it lies within the tolerance of
   the group's span, so each group is carried as its (lowest, highest) set rate and its row
   count; merging the chunks' groups makes the same decisions, on the same differences of the
   same values, as sorting the whole column. Non-finite and out-of-range rates are counted.
2. ``rate_deg_s`` and ``output``: every per-sample quantity of the analysis, accumulated per
   rate point with carried state —

   * the point statistics: count, mean and sum of squared deviations merged chunk by chunk
     (Chan, Golub & LeVeque 1983: each chunk's two-pass mean and M2, then the pairwise update
     M2 = M2_a + M2_b + δ²·n_a·n_b/n), numerically safe at 10⁹ samples;
   * the set rates' means (lowest rate plus the summed excess, as in memory);
   * non-finite outputs (count, first rows), magnitudes, whether the output copies the rate;
   * samples at the rails: the column's :class:`~rotacal.signal.RailDetector` (its state carried
     across chunks) and, per point, the two largest and two smallest distinct values with their
     counts and the number of distinct values (capped at 7: the grouped rule asks ≥ 6 levels and
     a median ≥ 4) — the grouped and rest rules of :func:`~rotacal.signal.find_clipping` decided
     on those;
   * the output quantum on the very samples :func:`output_quantum` takes (every ⌈n/50 000⌉-th
     finite sample of each point, n from pass 1; a third pass when outputs left out by
     ``nan_policy="omit"`` change n);
   * the resolution's noise: the means of consecutive blocks of N samples per point (the open
     block carried to the next chunk, its sum taken less the point's first sample as in memory),
     their mean and M2 merged as above.

Nothing is approximated: the result equals the in-memory one to rounding (checked to 1e-9
relative in ``tests/gyro/test_scale_factor_stream.py``). Memory holds the chunk, a few arrays per
rate point and the quantum's samples (≤ 50 000 per point, 8 bytes each).

References
----------
Kokuyama W., Watanabe T., Nozato H., Ota A., "Development of angular velocity calibration facility
using self-calibratable rotary encoder", §4. Chan T. F., Golub G. H., LeVeque R. J. (1983),
"Algorithms for computing the sample variance: analysis and recommendations", Am. Stat. 37(3),
242–247, eq. (2.1) (pairwise update of mean and M2).
"""

from __future__ import annotations

from collections.abc import Callable, Iterator, Mapping, Sequence
from typing import Any

import numpy as np

from rotacal.errors import CaptureError, ConfigError
from rotacal.gyro.resolution import check_blocks_fit
from rotacal.gyro.scale_factor import (
    _COPY_WHY,
    _bad_rates,
    _check_options,
    _empty_point,
    _finish,
    _nonfinite_outputs,
    _Options,
    _refuse_flat_output,
    _refuse_one_rate,
)
from rotacal.gyro.scale_factor_points import (
    _QUANTUM_SAMPLES,
    _SHOW_ROWS,
    PointData,
    _grid_step,
)
from rotacal.gyro.scale_factor_result import ScaleFactorResult
from rotacal.signal._values import LARGEST, SMALLEST, check_magnitudes
from rotacal.signal.clipping import (
    _GROUP_MIN,
    _GROUP_NOISY_LEVELS,
    _GROUP_PILE_FRACTION,
    _GROUP_PILE_RATIO,
    _GROUP_RESOLVED_LEVELS,
    Clipping,
    RailDetector,
    check_clipping,
)

__all__ = ["ScaleFactorChunks", "calibrate_scale_factor_chunked", "scale_factor_chunks"]

#: ``chunks(columns)`` starts a fresh pass over the capture and yields mappings of 1-D arrays of
#: the named columns (``rate_deg_s`` in °/s, ``output`` in output units), the same on every call.
ScaleFactorChunks = Callable[[Sequence[str]], Iterator[Mapping[str, np.ndarray]]]

#: More rate points than this are not a rate-table test (a measured rate, not the set rate).
MAX_RATE_POINTS = 1_000_000
#: Distinct values counted per point: enough to decide the grouped clipping rule exactly.
_LEVELS_CAP = 7
_RATE = "rate_deg_s"
_OUTPUT = "output"
_CHANGED = (
    "the capture changed between the passes over it (a different number of rows): analyse a file "
    "that is not being written to"
)


# --------------------------------------------------------------------------------------------
# pass 1: the rate points
# --------------------------------------------------------------------------------------------
class _FirstRows:
    """How many rows were flagged, and the first ``_SHOW_ROWS`` of them (for the messages)."""

    def __init__(self) -> None:
        self.count = 0
        self.first: list[int] = []

    def add(self, flagged: np.ndarray, offset: int) -> None:
        idx = np.flatnonzero(flagged)
        if idx.size:
            self.count += int(idx.size)
            room = _SHOW_ROWS - len(self.first)
            self.first += [offset + int(i) for i in idx[: max(room, 0)]]


class _Magnitudes:
    """:func:`check_magnitudes` over a column fed in chunks: the same message, naming the largest
    magnitude's sample (rows counted from the start)."""

    def __init__(self, name: str, what: str) -> None:
        self.name, self.what = name, what
        self.largest = 0.0
        self.value = 0.0
        self.row = 0

    def add(self, x: np.ndarray, offset: int) -> None:
        if x.size == 0:
            return
        with np.errstate(over="ignore"):
            i = int(np.argmax(np.abs(x)))
        if abs(float(x[i])) > self.largest:
            self.largest, self.value, self.row = abs(float(x[i])), float(x[i]), offset + i

    def finish(self) -> None:
        """The whole column's tests: a magnitude beyond LARGEST, or all below SMALLEST."""
        if self.largest > LARGEST:
            check_magnitudes(self.name, np.array([self.value]), what=self.what, offset=self.row)
        if 0.0 < self.largest < SMALLEST:
            check_magnitudes(self.name, np.array([self.largest]), what=self.what)


def _merge_spans(
    lo: np.ndarray, hi: np.ndarray, rows: np.ndarray, tol: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Groups (lowest, highest set rate, rows) of a single linkage at ``tol``, merged: sorted by
    their lowest rate, a group starts where its lowest rate exceeds every earlier highest by more
    than ``tol`` (on sorted values that is np.diff(rates) > tol, the test in memory)."""
    order = np.argsort(lo, kind="stable")
    lo, hi, rows = lo[order], hi[order], rows[order]
    reach = np.maximum.accumulate(hi)
    new = np.empty(lo.size, dtype=bool)
    new[:1] = True
    new[1:] = lo[1:] - reach[:-1] > tol
    starts = np.flatnonzero(new)
    return lo[starts], np.maximum.reduceat(hi, starts), np.add.reduceat(rows, starts)


class _RatePoints:
    """Pass 1: the rate points of ``rate_deg_s`` fed in chunks."""

    def __init__(self, tol: float, start: int = 0) -> None:
        self.tol = tol
        self.lo = np.empty(0)
        self.hi = np.empty(0)
        self.rows = np.empty(0, dtype=np.int64)
        self.n = start  # rows fed, counted from the log's first (``start``: a block's first row)
        self.bad = _FirstRows()
        self.magnitudes = _Magnitudes(_RATE, "a set rate")

    def add(self, rate: np.ndarray) -> None:
        if (
            rate.size > 1
            and not self.bad.count
            and rate[0] == rate[-1]
            and np.isfinite(rate[0])
            and not np.any(rate != rate[0])
        ):
            # one set rate (a plateau's slice of a continuous log): its first row makes the same
            # groups as all of them, the others only add to its group's count
            n = self.n + rate.size
            self.add(rate[:1])
            self.n = n
            self.rows[np.searchsorted(self.lo, rate[0], side="right") - 1] += rate.size - 1
            return
        offset, self.n = self.n, self.n + rate.size
        finite = np.isfinite(rate)
        if not finite.all():
            self.bad.add(~finite, offset)
        if self.bad.count:
            return  # refused at the end, with the count of all of them
        self.magnitudes.add(rate, offset)
        if self.lo.size:
            # a rate within a group's span joins that group and links no other (they lie more
            # than the tolerance beyond its ends): only the rates outside every span are sorted
            g = np.searchsorted(self.lo, rate, side="right") - 1
            inside = (g >= 0) & (rate <= self.hi[np.maximum(g, 0)])
            self.rows += np.bincount(g[inside], minlength=self.lo.size)
            rate = rate[~inside]
            if rate.size == 0:
                return
        rs = np.sort(rate)
        new = np.empty(rs.size, dtype=bool)
        new[:1] = True
        new[1:] = np.diff(rs) > self.tol
        starts = np.flatnonzero(new)
        ends = np.r_[starts[1:], rs.size]
        self.lo, self.hi, self.rows = _merge_spans(
            np.r_[self.lo, rs[starts]],
            np.r_[self.hi, rs[ends - 1]],
            np.r_[self.rows, ends - starts],
            self.tol,
        )
        self.check_count()

    def check_count(self) -> None:
        """Refuse a column of more rate points than a rate-table test holds."""
        if self.lo.size > MAX_RATE_POINTS:
            raise CaptureError(
                f"column rate_deg_s holds more than {MAX_RATE_POINTS} rate points (set rates more "
                f"than {self.tol:g} °/s apart): it must hold the table's set rate on each row, not "
                "a measured rate."
            )

    def finish(self) -> None:
        if self.n == 0:
            raise CaptureError("the capture has no rows: it needs rate_deg_s and output samples.")
        if self.bad.count:
            raise CaptureError(_bad_rates(self.bad.count, np.array(self.bad.first)))
        self.magnitudes.finish()


# --------------------------------------------------------------------------------------------
# pass 2: everything per sample, per rate point
# --------------------------------------------------------------------------------------------
def _by_point(
    gid: np.ndarray, y: np.ndarray, seen: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """A chunk's finite samples sorted by rate point (stable: row order within a point): points,
    samples, segment starts and sizes, and each sample's index among its point's finite samples
    since the start (``seen``: how many each point had before this chunk)."""
    if gid.size and gid[0] == gid[-1] and np.all(gid == gid[0]):
        # one rate point (a plateau's slice of a continuous log): already in order, no sort
        gs, ys, starts = gid, y, np.zeros(1, dtype=np.intp)
        return gs, ys, starts, np.array([gs.size]), np.arange(gs.size) + seen[gs[0]]
    order = np.argsort(gid, kind="stable")
    gs, ys = gid[order], y[order]
    starts = np.flatnonzero(np.r_[True, gs[1:] != gs[:-1]])
    sizes = np.diff(np.r_[starts, gs.size])
    within = np.arange(gs.size) - np.repeat(starts - seen[gs[starts]], sizes)
    return gs, ys, starts, sizes, within


def _chan_merge(
    n: np.ndarray, mean: np.ndarray, m2: np.ndarray, g: np.ndarray, nb: Any, mb: Any, m2b: Any
) -> None:
    """Merge the (count, mean, M2) of new samples into those of groups ``g`` (Chan et al. 1983)."""
    na = n[g].astype(float)
    total = na + nb
    delta = mb - mean[g]
    mean[g] += delta * (nb / total)
    m2[g] += m2b + delta * delta * (na * (nb / total))
    n[g] += nb.astype(n.dtype) if isinstance(nb, np.ndarray) else nb


def _segments_top2(v: np.ndarray, starts: np.ndarray) -> tuple[np.ndarray, ...]:
    """Per segment of ``v``: the largest value, its count, the next distinct value inward and its
    count (−inf and 0 when there is none)."""
    sizes = np.diff(np.r_[starts, v.size])
    top = np.maximum.reduceat(v, starts)
    at = v == np.repeat(top, sizes)
    k_top = np.add.reduceat(at, starts)
    second = np.maximum.reduceat(np.where(at, -np.inf, v), starts)
    k_second = np.add.reduceat(v == np.repeat(second, sizes), starts)
    return top, k_top.astype(np.int64), second, k_second.astype(np.int64)


class _Top2:
    """Per rate point: the two largest distinct values (as sign·output) and their counts."""

    def __init__(self, ng: int, sign: float) -> None:
        self.sign = sign
        self.top = np.full(ng, -np.inf)
        self.k_top = np.zeros(ng, dtype=np.int64)
        self.second = np.full(ng, -np.inf)
        self.k_second = np.zeros(ng, dtype=np.int64)

    def add(self, g: np.ndarray, ys: np.ndarray, starts: np.ndarray) -> None:
        self.fold(g, *_segments_top2(self.sign * ys, starts))

    def fold(
        self, g: np.ndarray, t_b: np.ndarray, k_b: np.ndarray, s_b: np.ndarray, ks_b: np.ndarray
    ) -> None:
        """Fold other samples' two largest values (as sign·output) and counts into points g."""
        t_a, k_a, s_a, ks_a = self.top[g], self.k_top[g], self.second[g], self.k_second[g]
        top = np.maximum(t_a, t_b)
        k_top = np.where(t_a == top, k_a, 0) + np.where(t_b == top, k_b, 0)
        # the next value inward: each side's top when it is below the new top, else its second
        c_a, kc_a = np.where(t_a == top, s_a, t_a), np.where(t_a == top, ks_a, k_a)
        c_b, kc_b = np.where(t_b == top, s_b, t_b), np.where(t_b == top, ks_b, k_b)
        second = np.maximum(c_a, c_b)
        k_second = np.where(c_a == second, kc_a, 0) + np.where(c_b == second, kc_b, 0)
        k_second = np.where(np.isfinite(second), k_second, 0)
        self.top[g], self.k_top[g], self.second[g], self.k_second[g] = top, k_top, second, k_second


class _Levels:
    """Per rate point: its distinct output values, up to ``_LEVELS_CAP`` of them."""

    def __init__(self, ng: int) -> None:
        self.known = np.full((ng, _LEVELS_CAP), np.nan)
        self.count = np.zeros(ng, dtype=np.int64)

    def add(self, gs: np.ndarray, ys: np.ndarray, starts: np.ndarray) -> None:
        """``ys`` sorted by point ``gs`` (segments from ``starts``). A noisy point shows its
        levels in its first samples: the first 64, then 4096, then all samples of each point
        still open are searched for values not yet counted."""
        sizes = np.diff(np.r_[starts, gs.size])
        seg_g = gs[starts]
        for window in (64, 4096, gs.size):
            open_ = self.count[seg_g] < _LEVELS_CAP
            if not open_.any():
                return
            take = np.minimum(sizes[open_], window)
            rows = np.repeat(starts[open_], take) + (
                np.arange(int(take.sum())) - np.repeat(np.cumsum(take) - take, take)
            )
            g, v = gs[rows], ys[rows]
            fresh = ~np.any(v[:, None] == self.known[g], axis=1)
            g, v = g[fresh], v[fresh]
            if g.size == 0:
                continue
            order = np.lexsort((v, g))
            g, v = g[order], v[order]
            new = np.r_[True, (g[1:] != g[:-1]) | (v[1:] != v[:-1])]
            g, v = g[new], v[new]  # distinct (point, value) pairs, by point
            first = np.flatnonzero(np.r_[True, g[1:] != g[:-1]])
            slot = (
                self.count[g] + np.arange(g.size) - np.repeat(first, np.diff(np.r_[first, g.size]))
            )
            keep = slot < _LEVELS_CAP
            self.known[g[keep], slot[keep]] = v[keep]
            self.count += np.bincount(g[keep], minlength=self.count.size)


class _Blocks:
    """Per rate point: the means of consecutive blocks of ``block`` finite samples (less the
    point's first sample), their count, mean and M2; the open block is carried."""

    def __init__(self, ng: int, block: int, seen: np.ndarray | None = None) -> None:
        self.block = block
        self.carry_sum = np.zeros(ng)
        self.carry_n = np.zeros(ng, dtype=np.int64)
        self.n = np.zeros(ng)
        self.mean = np.zeros(ng)
        self.m2 = np.zeros(ng)
        # one block of the log (``seen``: each point's samples before it): the block open at its
        # start holds seen % block samples whose sum it cannot know; the samples that complete
        # it are summed apart (``head_sum``) for the rows before to finish (``pending`` until then)
        self.entry_n = np.zeros(ng, dtype=np.int64) if seen is None else seen % block
        self.carry_n += self.entry_n
        self.pending = self.entry_n > 0
        self.head_sum = np.zeros(ng)

    def add(self, gs: np.ndarray, v: np.ndarray, within: np.ndarray) -> None:
        """``v``: finite samples less their point's shift, sorted by point (stable); ``within``:
        each one's index among its point's finite samples since the start."""
        k = within // self.block
        cut = np.flatnonzero(np.r_[True, (gs[1:] != gs[:-1]) | (k[1:] != k[:-1])])
        sums = np.add.reduceat(v, cut)
        sizes = np.diff(np.r_[cut, v.size])
        bg = gs[cut]
        # a block that continues the carried one (its first sample is not a block's first)
        cont = within[cut] % self.block != 0
        sums[cont] += self.carry_sum[bg[cont]]
        sizes[cont] += self.carry_n[bg[cont]]
        self.carry_n[bg[cont]] = 0
        self.carry_sum[bg[cont]] = 0.0
        full = sizes == self.block
        part = ~full  # at most one per point: its last block, carried on
        self.carry_sum[bg[part]] = sums[part]
        self.carry_n[bg[part]] = sizes[part]
        head = full & cont & self.pending[bg]  # completes the block open at the start
        if head.any():
            self.head_sum[bg[head]] = sums[head]
            self.pending[bg[head]] = False
            full &= ~head
        if not full.any():
            return
        means, fg = sums[full] / self.block, bg[full]
        ng = self.n.size
        nb = np.bincount(fg, minlength=ng).astype(float)
        has = np.flatnonzero(nb)
        mb = np.bincount(fg, weights=means, minlength=ng)[has] / nb[has]
        centre = np.zeros(ng)
        centre[has] = mb
        dev = means - centre[fg]
        m2b = np.bincount(fg, weights=dev * dev, minlength=ng)[has]
        _chan_merge(self.n, self.mean, self.m2, has, nb[has], mb, m2b)

    def noise(self) -> np.ndarray:
        """σ_B of each point (output units), NaN below two blocks (as :func:`_block_noise`)."""
        with np.errstate(invalid="ignore", divide="ignore"):
            return np.where(self.n > 1, np.sqrt(self.m2 / np.maximum(self.n - 1, 1)), np.nan)


class _PointSums:
    """Pass 2: everything the analysis needs of the samples, per rate point (module docstring)."""

    def __init__(
        self,
        points: _RatePoints,
        opts: _Options,
        *,
        start: int | None = None,
        seen: np.ndarray | None = None,
    ) -> None:
        """``start`` and ``seen``: the sums of one block of the log, from row ``start`` on,
        each point having ``seen`` samples before it (see :mod:`rotacal.gyro.scale_factor_merge`;
        a log read through the reader, whose samples are all finite)."""
        ng = points.lo.size
        self.lo, self.rows = points.lo, points.rows
        self.stride = np.maximum(-(-self.rows // _QUANTUM_SAMPLES), 1)
        self.n_rows = 0 if start is None else start
        self.rate_excess = np.zeros(ng)
        self.n = np.zeros(ng, dtype=np.int64)
        self.mean = np.zeros(ng)  # of the samples less ``shift``
        self.m2 = np.zeros(ng)
        self.shift = np.zeros(ng)
        self.bad = _FirstRows()
        self.magnitudes = _Magnitudes(_OUTPUT, "a gyro output")
        self.abs_max = 0.0
        self.copy = self.negative = True
        self.rails = RailDetector(
            _OUTPUT, None if start is None else int(self.rows.sum()), start=start
        )
        self.highs, self.lows = _Top2(ng, 1.0), _Top2(ng, -1.0)
        self.levels = _Levels(ng)
        self.blocks = _Blocks(ng, opts.noise.block, seen)
        # finite samples of each point before the chunk: the statistics' counts, or for a block
        # of the log those before the block plus its own (its statistics start from zero)
        self.seen = self.n if seen is None else seen.astype(np.int64)
        self.kept: list[tuple[np.ndarray, ...]] = []

    def group_of(self, rate: np.ndarray) -> np.ndarray:
        if rate.size > 1 and rate[0] == rate[-1] and not np.any(rate != rate[0]):
            return np.full(rate.size, np.searchsorted(self.lo, rate[0], side="right") - 1)
        return np.searchsorted(self.lo, rate, side="right") - 1

    def add(self, rate: np.ndarray, y: np.ndarray) -> None:
        offset, self.n_rows = self.n_rows, self.n_rows + y.size
        gid = self.group_of(rate)
        self.rate_excess += np.bincount(gid, weights=rate - self.lo[gid], minlength=self.lo.size)
        self.copy = self.copy and np.array_equal(rate, y)
        self.negative = self.negative and np.array_equal(rate, -y)
        self.rails.add(y)
        ok = np.isfinite(y)
        if ok.all():
            self.magnitudes.add(y, offset)
        else:
            self.bad.add(~ok, offset)
            self.magnitudes.add(np.where(ok, y, 0.0), offset)
            y, gid = y[ok], gid[ok]
        if y.size == 0 or self.magnitudes.largest > LARGEST:
            return  # nothing, or refused at the end of the pass: no overflowing arithmetic
        self.abs_max = max(self.abs_max, float(np.max(np.abs(y))))
        gs, ys, starts, sizes, within = _by_point(gid, y, self.seen)
        seg_g = gs[starts]
        fresh = self.n[seg_g] == 0
        # each point's first finite sample (of the block: the merge moves it to the log's)
        self.shift[seg_g[fresh]] = ys[starts[fresh]]
        d = ys - np.repeat(self.shift[seg_g], sizes)  # as in memory: the digits of the noise
        # point statistics: this chunk's two-pass mean and M2, merged
        seg_mean = np.add.reduceat(d, starts) / sizes
        dev = d - np.repeat(seg_mean, sizes)
        seg_m2 = np.add.reduceat(dev * dev, starts)
        _chan_merge(self.n, self.mean, self.m2, seg_g, sizes, seg_mean, seg_m2)
        if self.seen is not self.n:
            self.seen[seg_g] += sizes
        self.highs.add(seg_g, ys, starts)
        self.lows.add(seg_g, ys, starts)
        self.levels.add(gs, ys, starts)
        if self.blocks.block > 1:  # blocks of one sample: the point statistics themselves
            self.blocks.add(gs, d, within)
        keep = within % self.stride[gs] == 0
        self.kept.append((gs[keep], ys[keep]))

    def quantum(self) -> float | None:
        """:func:`output_quantum` on the kept samples (the same ones it takes)."""
        if not self.kept:
            return None
        g = np.concatenate([k[0] for k in self.kept])
        y = np.concatenate([k[1] for k in self.kept])
        return None if y.size < 2 else _grid_step(y, g)

    def clipping(self, rates: np.ndarray, allow_clipped: bool) -> tuple[str, ...]:
        """:func:`~rotacal.signal.check_clipping` with the rate points as groups and the points
        at zero rate as rest, decided on the carried statistics."""
        rails = []
        rest = rates == 0
        for rail, ok in self.rails.extremes():
            side = self.highs if rail.side == "maximum" else self.lows
            value = side.sign * rail.value
            if np.any(side.top[rest] == value):
                continue  # where the sensor rests, not a rail
            grouped = self._grouped_rail(side, value)
            if ok if grouped is None else grouped:
                rails.append(rail)
        clip = Clipping(_OUTPUT, int(self.n.sum()), tuple(rails)) if rails else None
        return check_clipping({_OUTPUT: clip}, allow_clipped=allow_clipped)

    def _grouped_rail(self, side: _Top2, value: float) -> bool | None:
        """The grouped rule of :func:`rotacal.signal.clipping._grouped_rail` from the points'
        extremes, counts and (capped) numbers of distinct values."""
        verdict: bool | None = None
        sizes, levels = self.n, self.levels.count
        for g in np.flatnonzero(side.top == value):
            size = int(sizes[g])
            if size < _GROUP_MIN:
                continue
            verdict = False
            k_ext = int(side.k_top[g])
            if k_ext == size:
                others = levels[(np.arange(sizes.size) != g) & (sizes >= _GROUP_MIN)]
                if others.size and float(np.median(others)) >= _GROUP_NOISY_LEVELS:
                    return True  # flat at the extreme while the other points show their noise
                continue
            if k_ext < max(_GROUP_MIN, _GROUP_PILE_FRACTION * size):
                continue
            if levels[g] < _GROUP_RESOLVED_LEVELS:
                continue  # too coarse for the point's noise to show its shape
            if k_ext > _GROUP_PILE_RATIO * int(side.k_second[g]):
                return True
        return verdict


def _quantum_samples_again(reader: _Reader, sums: _PointSums) -> list[tuple[np.ndarray, ...]]:
    """Pass 3: every ⌈n/50 000⌉-th finite sample of each point, n its finite samples."""
    stride = np.maximum(-(-sums.n // _QUANTUM_SAMPLES), 1)
    seen = np.zeros_like(sums.n)
    kept: list[tuple[np.ndarray, ...]] = []
    for _, (rate, y) in reader.run((_RATE, _OUTPUT)):
        ok = np.isfinite(y)
        gs, ys, starts, sizes, within = _by_point(sums.group_of(rate)[ok], y[ok], seen)
        seen[gs[starts]] += sizes
        keep = within % stride[gs] == 0
        kept.append((gs[keep], ys[keep]))
    return kept


# --------------------------------------------------------------------------------------------
# the method
# --------------------------------------------------------------------------------------------
class _Reader:
    """Fresh passes over the chunk source, each checked for the same row count (also the
    continuous log's, :mod:`rotacal.gyro.plateaus_stream`; ``example`` names the function that
    makes a chunk source, for the message when ``chunks`` is not callable)."""

    def __init__(
        self,
        chunks: Callable[[Sequence[str]], Iterator[Mapping[str, np.ndarray]]],
        progress: Callable[[int], None] | None,
        example: str = "scale_factor_chunks(rate, output)",
    ) -> None:
        if not callable(chunks):
            raise ConfigError(
                "chunks must be a callable that starts a fresh pass over the capture each time it "
                f"is called with the columns it needs (e.g. {example}), not "
                f"a {type(chunks).__name__}"
            )
        self.chunks, self.progress = chunks, progress
        self.done = 0
        self.rows: int | None = None

    def run(self, columns: Sequence[str]) -> Iterator[tuple[int, list[np.ndarray]]]:
        """(row of the chunk's first sample, its columns as float64) for each chunk."""
        offset = 0
        it = iter(self.chunks(tuple(columns)))
        try:
            for raw in it:
                cols = [np.asarray(raw[c], dtype=np.float64).reshape(-1) for c in columns]
                other = next((j for j, c in enumerate(cols) if c.size != cols[0].size), None)
                if other is not None:
                    raise CaptureError(
                        f"column {columns[0]} has {cols[0].size} rows but column "
                        f"{columns[other]} has {cols[other].size} in the chunk from row {offset}: "
                        "they must have one row per sample."
                    )
                if cols[0].size == 0:
                    continue
                yield offset, cols
                offset += cols[0].size
                self.done += cols[0].size
                if self.progress is not None:
                    self.progress(self.done)
        finally:
            close = getattr(it, "close", None)
            if close is not None:
                close()
        if self.rows is not None and offset != self.rows:
            raise CaptureError(_CHANGED)
        self.rows = offset


def calibrate_scale_factor_chunked(
    chunks: ScaleFactorChunks,
    *,
    progress: Callable[[int], None] | None = None,
    **options: Any,
) -> ScaleFactorResult:
    """Scale factor, bias and nonlinearity of a gyro from a rate-table log read in chunks.

    The method, checks and result of :func:`~rotacal.gyro.scale_factor.calibrate_scale_factor`
    (Kokuyama et al. 2015, §4: point means, the unweighted least-squares line V = S·Ω + V0,
    NL = 100·max|δ|/(|S|·FS) %FS, budgets, requirement), in two passes over the capture (three
    when ``nan_policy="omit"`` leaves outputs out) with the per-sample state carried from chunk to
    chunk (see the module docstring), so that memory stays flat whatever the log's length.

    Parameters
    ----------
    chunks : callable
        ``chunks(columns)`` starts a fresh pass and yields mappings holding the 1-D arrays of the
        named columns, ``rate_deg_s`` (set rate, °/s) and ``output`` (output units), one chunk
        each, in row order; every call gives the same rows (:func:`scale_factor_chunks`, or
        the CLI's file reader).
    progress : callable, optional
        Called after each chunk with the rows read so far, summed over the passes (2·N, or 3·N).
    **options
        The keywords of :func:`~rotacal.gyro.scale_factor.calibrate_scale_factor`
        (``full_scale_deg_s`` in °/s, ``requirement``, ``rate_tolerance_deg_s`` in °/s,
        ``nan_policy``, ``output_unit``, ``specs``, ``mc_trials``, ``sample_rate_hz`` and
        ``bandwidth_hz`` in Hz, ``allow_clipped``), with the same defaults.

    Returns
    -------
    ScaleFactorResult
        Equal to the in-memory result to rounding (≤ 1e-9 relative).

    Raises
    ------
    ConfigError
        An option that is not one of those, or a bad value (as in memory).

    References
    ----------
    Kokuyama et al. (2015), §4; IEEE Std 952-1997, Annex C; Chan, Golub & LeVeque (1983), eq. 2.1.
    """
    opts = _check_options(**options)
    reader = _Reader(chunks, progress)
    points = _RatePoints(opts.tol)
    for _, (rate,) in reader.run((_RATE,)):
        points.add(rate)
    check_points(points, opts)
    sums = _PointSums(points, opts)
    for _, (rate, y) in reader.run((_RATE, _OUTPUT)):
        sums.add(rate, y)
    return result_of_sums(points, sums, opts, reader)


def check_points(points: _RatePoints, opts: _Options) -> None:
    """The refusals once the rate points are known (pass 1 ended): no rows, non-finite or
    absurd set rates, a single rate, blocks of the bandwidth longer than every point."""
    points.finish()
    _refuse_one_rate(points.lo)
    check_blocks_fit(opts.noise, points.rows)  # refused before reading the outputs


def result_of_sums(
    points: _RatePoints, sums: _PointSums, opts: _Options, reader: _Reader
) -> ScaleFactorResult:
    """The result from pass 2's sums, with its refusals in the order of the in-memory path
    (``reader`` for the passes a refusal or left-out outputs need)."""
    rates = points.lo + sums.rate_excess / points.rows
    if sums.magnitudes.largest > LARGEST:  # the statistics were not accumulated
        sums.magnitudes.finish()
    empty = np.flatnonzero(sums.n == 0)
    if empty.size:
        g = int(empty[0])
        first = _FirstRows()
        for offset, (rate,) in reader.run((_RATE,)):
            if len(first.first) < _SHOW_ROWS:
                first.add(sums.group_of(rate) == g, offset)
        raise CaptureError(_empty_point(rates[g], np.array(first.first), int(points.rows[g])))
    notes = _nonfinite_outputs(sums.bad.count, np.array(sums.bad.first), opts.nan_policy)
    sums.magnitudes.finish()
    if sums.copy or sums.negative:
        label = "an identical copy" if sums.copy else "the negative"
        raise CaptureError(f"column 'output' is {label} of column 'rate_deg_s': {_COPY_WHY}.")
    with np.errstate(invalid="ignore", divide="ignore"):
        std = np.where(sums.n > 1, np.sqrt(sums.m2 / np.maximum(sums.n - 1, 1)), np.nan)
    _refuse_flat_output(sums.shift + sums.mean, opts.unit)
    clipped = sums.clipping(rates, opts.allow_clipped)
    if sums.bad.count:  # outputs left out: the quantum's stride counts finite samples only
        sums.kept = _quantum_samples_again(reader, sums)
    check_blocks_fit(opts.noise, sums.n)
    data = PointData(
        rates=rates,
        spread=points.hi - points.lo,
        counts=sums.n.copy(),
        means=sums.shift + sums.mean,
        std=std,
        quantum=sums.quantum(),
        noise=std if opts.noise.block == 1 else sums.blocks.noise(),
        output_abs_max=sums.abs_max,
        clipped=clipped,
        notes=tuple(notes),
    )
    return _finish(data, opts)


def scale_factor_chunks(
    rate_deg_s: np.ndarray, output: np.ndarray, *, chunk_rows: int = 1_000_000
) -> ScaleFactorChunks:
    """A chunk source over two arrays already in memory (tests, memory maps, other readers).

    Parameters
    ----------
    rate_deg_s, output : array
        Set rate (°/s) and DUT output (output units) of each row; equal lengths.
    chunk_rows : int
        Rows per chunk (≥ 1).
    """
    if isinstance(chunk_rows, bool) or not isinstance(chunk_rows, int | np.integer):
        raise ConfigError(f"chunk_rows must be a whole number of rows, not {chunk_rows!r}")
    if chunk_rows < 1:
        raise ConfigError(f"chunk_rows must be at least 1, not {chunk_rows}")
    columns = {_RATE: np.asarray(rate_deg_s).reshape(-1), _OUTPUT: np.asarray(output).reshape(-1)}
    if columns[_RATE].size != columns[_OUTPUT].size:
        raise CaptureError(
            f"column rate_deg_s has {columns[_RATE].size} rows but column output has "
            f"{columns[_OUTPUT].size}: they must have one row per sample."
        )
    rows = int(chunk_rows)

    def chunks(names: Sequence[str]) -> Iterator[dict[str, np.ndarray]]:
        for start in range(0, columns[_RATE].size, rows):
            yield {c: columns[c][start : start + rows] for c in names}

    return chunks
