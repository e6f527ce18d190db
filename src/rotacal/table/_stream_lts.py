"""The LTS scheme's passes of the chunked calibration (Feng et al. 2023, §5, eq. (15)) (private).

After the checks (:mod:`rotacal.table._stream_checks`), θ = arctan(D/R) is recomputed from D in
every pass (one arctan per sample: cheaper than storing it). The reversing moments are those of
:func:`~rotacal.table.extreme_reversals`, found with the state carried across chunks:

- the Schmitt trigger's levels come from the exact 2 % and 98 % percentiles of what it sees
  (:func:`order_statistics`: histograms narrowing on the wanted ranks, then the few values left
  gathered; numpy's linear interpolation between the two order statistics, :func:`percentile`);
- with ``drift`` the trigger follows a drift fitted first to the whole capture
  (:func:`prefit_drift_chunked`, the streamed :func:`~rotacal.table.motion_drift.prefit_drift`);
- the trigger's state, and the running extremes of the open swing, are carried from chunk to
  chunk (:func:`swing_extremes`); the first and last swings follow the in-memory zigzag rule;
- the parabola of each extreme (:func:`~rotacal.table.motion.refine_extreme`) is fitted on the
  samples within ±2.5 half windows of it, gathered while the pass is inside that span only.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Iterable, Iterator

import numpy as np

from rotacal.signal import HarmonicFitAccumulator
from rotacal.table._stream_checks import Checked, start_frequency
from rotacal.table._stream_fit import Segment, accumulate, accumulator, block_length
from rotacal.table._stream_source import Passes
from rotacal.table.motion import _plot_stride
from rotacal.table.motion_lts_fog import lts_angle, refine_extreme, reversal_half_window

_SIGNAL = "displacement_mm"
#: Bins of each histogram of :func:`order_statistics`, and the most values it gathers per rank.
_BINS = 4096
_GATHER = 1 << 21


def angle_segment(passes: Passes, radius_mm: float, first: int, last: int) -> Segment:
    """θ (deg) of samples ``first..last``: ``(global index of the piece's first sample, t, θ)``."""

    def pieces() -> Iterator[tuple[int, np.ndarray, np.ndarray]]:
        for _, off, cols in passes.run(first, last + 1):
            s = max(first - off, 0)
            e = min(last + 1 - off, cols[_SIGNAL].size)
            yield off + s, cols["time_s"][s:e], lts_angle(cols[_SIGNAL][s:e], radius_mm)

    return pieces


def prefit_drift_chunked(passes: Passes, found: Checked, radius_mm: float, harmonics: int) -> float:
    """:func:`~rotacal.table.motion_drift.prefit_drift` of θ in two passes: the straight line's
    slope from running sums, then the multi-harmonic fit with the linear term (block moments)."""
    t_mid = mid_time(found)
    whole = angle_segment(passes, radius_mm, 0, found.n - 1)
    slope = line_slope([line_sums(t, x, t_mid) for _, t, x in whole()], found.n)
    f0 = drift_start_frequency(found, radius_mm, slope)
    acc = accumulator(f0, harmonics, found.typical)

    def less_line() -> Iterator[tuple[int, np.ndarray, np.ndarray]]:
        for g0, t, x in whole():
            yield g0, t, x - slope * (t - t_mid)

    accumulate([(acc, None)], less_line(), block_length(f0, harmonics, found.typical))
    return drift_of(acc, f0, harmonics, slope)


def mid_time(found: Checked) -> float:
    """The middle of the capture (s): the origin of the prefit's straight line."""
    return 0.5 * (float(found.first_t) + float(found.last_t))


def line_sums(t: np.ndarray, x: np.ndarray, t_mid: float) -> tuple[float, float, float, float]:
    """Σ τ, Σ τ², Σ x, Σ τ·x of a piece (τ = t − t_mid, s; x in deg)."""
    tau = t - t_mid
    return float(np.sum(tau)), float(tau @ tau), float(np.sum(x)), float(tau @ x)


def line_slope(sums: list[tuple[float, float, float, float]], n: int) -> float:
    """The least-squares slope (deg/s) of θ over t from the pieces' :func:`line_sums`, added in
    order."""
    s_tau = s_tau2 = s_x = s_taux = 0.0
    for a, b, c, d in sums:
        s_tau += a
        s_tau2 += b
        s_x += c
        s_taux += d
    # Σ τ·(x − x̄) = Σ τ·x − x̄·Σ τ
    return (s_taux - s_x / n * s_tau) / s_tau2


def drift_start_frequency(found: Checked, radius_mm: float, slope: float) -> float:
    """The start frequency (Hz) of the prefit: the first pass's copies of θ less the line."""
    t_mid = mid_time(found)
    assert found.first_samples is not None and found.strided is not None
    t1, d1 = found.first_samples
    ts, ds = found.strided.arrays()
    return start_frequency(
        (t1, lts_angle(d1, radius_mm) - slope * (t1 - t_mid)),
        (ts, lts_angle(ds, radius_mm) - slope * (ts - t_mid)),
        whole=found.strided.stride == 1 and ts.size == t1.size,
    )


def drift_of(acc: HarmonicFitAccumulator, f0: float, harmonics: int, slope: float) -> float:
    """The drift (deg/s): the line's slope plus the linear term of the fit of θ less the line."""
    fit = acc.fit(f0, harmonics, True, max_iter=50, rtol=1e-12, drift=True)
    assert fit.drift is not None
    return slope + fit.drift


def trigger_values(
    passes: Passes, radius_mm: float, trend: float, t0: float
) -> Callable[[], Iterator[tuple[int, np.ndarray, np.ndarray, np.ndarray]]]:
    """A fresh pass over ``(offset, t, θ, what the trigger sees)``: θ less ``trend``·(t − t₀)."""

    def pieces() -> Iterator[tuple[int, np.ndarray, np.ndarray, np.ndarray]]:
        for _, off, cols in passes.run():
            yield off, *trigger_piece(cols, radius_mm, trend, t0)

    return pieces


def trigger_piece(
    cols: dict[str, np.ndarray], radius_mm: float, trend: float, t0: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """t (s), θ (deg) and what the trigger sees (deg) of a piece's columns."""
    t = cols["time_s"]
    x = lts_angle(cols[_SIGNAL], radius_mm)
    return t, x, (x if trend == 0.0 else x - trend * (t - t0))


def value_range(values: Callable[[], Iterator[np.ndarray]]) -> tuple[float, float]:
    """Smallest and largest value of a stream (one pass)."""
    lo, hi = math.inf, -math.inf
    for v in values():
        lo = min(lo, float(np.min(v)))
        hi = max(hi, float(np.max(v)))
    return lo, hi


@dataclasses.dataclass
class _Rank:
    """The search for the k-th smallest value: it lies in [lo, hi]; ``below`` values are < lo."""

    k: int
    lo: float
    hi: float
    below: int = 0
    count: int = -1  # values in [lo, hi] by the last histogram (-1: not histogrammed yet)
    value: float | None = None


_Key = tuple[float, float]


@dataclasses.dataclass
class Tally:
    """One pass's count of some values per searched range ``(lo, hi)``: the values below it,
    the histogram of those inside (or, when ``gather``, the values themselves) and their
    smallest and largest. The tallies of consecutive pieces add up (:meth:`merge`)."""

    below: dict[_Key, int]
    hist: dict[_Key, np.ndarray]
    kept: dict[_Key, list[np.ndarray]]
    v_lo: dict[_Key, float]
    v_hi: dict[_Key, float]

    def merge(self, other: Tally) -> None:
        """Add ``other``'s counts (integers: exact, in any order)."""
        for key in self.below:
            self.below[key] += other.below[key]
            self.hist[key] += other.hist[key]
            self.kept[key].extend(other.kept[key])
            self.v_lo[key] = min(self.v_lo[key], other.v_lo[key])
            self.v_hi[key] = max(self.v_hi[key], other.v_hi[key])


def tally(chunks: Iterable[np.ndarray], keys: list[_Key], gather: dict[_Key, bool]) -> Tally:
    """The :class:`Tally` of the values of ``chunks`` for each range of ``keys``."""
    out = Tally(
        dict.fromkeys(keys, 0),
        {key: np.zeros(_BINS, dtype=np.int64) for key in keys},
        {key: [] for key in keys},
        dict.fromkeys(keys, math.inf),
        dict.fromkeys(keys, -math.inf),
    )
    for v in chunks:
        for key in keys:
            a, b = key
            out.below[key] += int(np.count_nonzero(v < a))
            inside = v[(v >= a) & (v <= b)]
            if inside.size == 0:
                continue
            out.v_lo[key] = min(out.v_lo[key], float(inside.min()))
            out.v_hi[key] = max(out.v_hi[key], float(inside.max()))
            if gather[key]:
                out.kept[key].append(inside)
            elif b > a:
                out.hist[key] += np.histogram(inside, bins=_BINS, range=(a, b))[0]
    return out


def order_statistics(
    values: Callable[[], Iterator[np.ndarray]], ranks: list[int], lo: float, hi: float
) -> list[float]:
    """The k-th smallest values (k 0-based) of a stream of values all within [lo, hi], exactly
    (:func:`search_ranks`, each pass a :func:`tally` of the stream)."""
    return search_ranks(lambda keys, gather: tally(values(), keys, gather), ranks, lo, hi)


def search_ranks(
    count: Callable[[list[_Key], dict[_Key, bool]], Tally],
    ranks: list[int],
    lo: float,
    hi: float,
) -> list[float]:
    """The k-th smallest values (k 0-based) of values all within [lo, hi], exactly; ``count``
    makes one pass's :class:`Tally` of all the values.

    Each pass histograms, per rank, the values in the rank's current range into 4096 bins and
    narrows the range to the bin holding the rank; once a range holds at most 2²¹ values they are
    gathered and sorted (a range whose values are all equal gives its value at once). For
    smoothly spread values two passes suffice up to ~10¹⁰ samples. The result does not depend
    on [lo, hi] as long as it holds every value.
    """
    todo = [_Rank(k, lo, hi) for k in ranks]
    while any(r.value is None for r in todo):
        live = [r for r in todo if r.value is None]
        keys = sorted({(r.lo, r.hi) for r in live})
        gather = {key: all(_gathering(r) for r in live if (r.lo, r.hi) == key) for key in keys}
        counted = count(keys, gather)
        for r in live:
            key = (r.lo, r.hi)
            r.below = counted.below[key]
            if counted.v_lo[key] == counted.v_hi[key]:  # every value left is the same one
                r.value = counted.v_lo[key]
            elif gather[key]:
                r.value = float(np.sort(np.concatenate(counted.kept[key]))[r.k - r.below])
            else:
                hist = counted.hist[key]
                cum = np.cumsum(hist)
                j = int(np.searchsorted(cum, r.k - r.below, side="right"))
                edges = np.histogram_bin_edges(np.empty(0), bins=_BINS, range=(r.lo, r.hi))
                r.below += int(cum[j - 1]) if j > 0 else 0
                r.lo, r.hi = float(edges[j]), float(edges[j + 1])
                r.count = int(hist[j])
    return [float(r.value) for r in todo if r.value is not None]


def _gathering(r: _Rank) -> bool:
    """A rank whose range holds few enough values to gather them (known after one histogram)."""
    return 0 <= r.count <= _GATHER


def percentile(n: int, q: float, order: Callable[[list[int]], list[float]]) -> float:
    """``np.percentile(x, q)`` (linear method) of n values from their order statistics."""
    return percentiles(n, [q], order)[0]


def percentiles(n: int, qs: list[float], order: Callable[[list[int]], list[float]]) -> list[float]:
    """``np.percentile(x, q)`` (linear method) of n values for each q of ``qs``, the order
    statistics they need asked of ``order`` at once (one search: its passes serve them all)."""
    plans = []
    for q in qs:
        virtual = (n - 1) * (q / 100.0)
        below = math.floor(virtual)
        plans.append((below, min(below + 1, n - 1), virtual - below))
    wanted = sorted({k for below, above, _ in plans for k in (below, above)})
    value = dict(zip(wanted, order(wanted), strict=True))
    out = []
    for below, above, gamma in plans:
        a, b = value[below], value[above]
        diff = b - a
        out.append(b - diff * (1 - gamma) if gamma >= 0.5 else a + diff * gamma)
    return out


@dataclasses.dataclass
class Extremes:
    """The kept extremes of the trigger's swings: global index, time (s), sign (+1 maximum)."""

    index: np.ndarray
    time: np.ndarray
    sign: np.ndarray
    plot_t: np.ndarray  # every _plot_stride(n)-th sample of the capture, for the figures
    plot_angle: np.ndarray


@dataclasses.dataclass
class SwingRuns:
    """A piece of the trigger's pass, computed without its entry state (:func:`swing_runs`):
    its runs of samples between the trigger's edges, with their extremes, for
    :class:`SwingFold` to join in order.

    ``decided`` is the first sample (in the piece) where the trigger decides (−1: none), with
    the state ``first_state`` there and ``last_state`` at the piece's end; a run starts there.
    Whether that start is an edge depends on the state carried in (the fold knows it); every
    other run start after the first is an edge closing a swing of sign ``closing[j]``.
    """

    off: int
    decided: int
    first_state: int
    last_state: int
    starts: np.ndarray
    closing: np.ndarray
    seg_max: np.ndarray
    seg_min: np.ndarray
    arg_max: np.ndarray  # global indices
    arg_min: np.ndarray
    t_max: np.ndarray
    t_min: np.ndarray
    x_first: float
    x_last: float
    plot_t: np.ndarray
    plot_x: np.ndarray


def swing_runs(
    off: int, t: np.ndarray, x: np.ndarray, xt: np.ndarray, mid: float, h: float, step: int
) -> SwingRuns:
    """The :class:`SwingRuns` of a piece starting at global index ``off``: t (s), θ (deg),
    what the Schmitt trigger sees ``xt`` (deg), its centre ``mid`` and half-width ``h`` (deg),
    ``step`` the figures' stride."""
    state = np.where(xt > mid + h, 1, np.where(xt < mid - h, -1, 0)).astype(np.int8)
    at = np.where(state != 0, np.arange(state.size), -1)
    np.maximum.accumulate(at, out=at)
    filled = np.where(at >= 0, state[np.maximum(at, 0)], 0).astype(np.int8)
    nonzero = np.flatnonzero(filled)
    decided = int(nonzero[0]) if nonzero.size else -1
    before = np.concatenate(([0], filled[:-1]))
    edges = np.flatnonzero((filled != before) & (before != 0))  # after `decided`: its own
    starts = np.concatenate(([0], [decided] if decided > 0 else [], edges)).astype(np.intp)
    closing = before[starts].astype(np.int8)  # 0 at the first run and at `decided`
    seg_max = np.maximum.reduceat(x, starts)
    seg_min = np.minimum.reduceat(x, starts)
    arg_max = _first_hits(x, starts, seg_max)
    arg_min = _first_hits(x, starts, seg_min)
    s0 = (-off) % step
    return SwingRuns(
        off,
        decided,
        int(filled[decided]) if decided >= 0 else 0,
        int(filled[-1]),
        starts,
        closing,
        seg_max,
        seg_min,
        off + arg_max,
        off + arg_min,
        np.array(t[arg_max]),
        np.array(t[arg_min]),
        float(x[0]),
        float(x[-1]),
        np.array(t[s0::step]),
        np.array(x[s0::step]),
    )


class SwingFold:
    """Joins the :class:`SwingRuns` of the pieces in order, carrying the trigger's state and
    the open swing's running maximum and minimum (first occurrence); :meth:`finish` gives the
    extremes of :func:`~rotacal.table.extreme_reversals`."""

    def __init__(self, n: int, h: float) -> None:
        self.n, self.h = n, h
        self.state = 0  # the trigger's state before the next piece (0: no decision yet)
        self.sign_first = 0
        self.x_first = self.x_last = math.nan
        self.open_max: list[float] = [-math.inf, -1, math.nan]
        self.open_min: list[float] = [math.inf, -1, math.nan]
        self.swings: list[tuple[int, int, float, float]] = []  # sign, index, time, extreme
        self.dec_t: list[np.ndarray] = []
        self.dec_x: list[np.ndarray] = []

    def _close(self, sign: int) -> None:
        best = self.open_max if sign > 0 else self.open_min
        self.swings.append((sign, int(best[1]), float(best[2]), sign * float(best[0])))
        self.open_max = [-math.inf, -1, math.nan]
        self.open_min = [math.inf, -1, math.nan]

    def add(self, r: SwingRuns) -> None:
        """The next piece."""
        if r.off == 0:
            self.x_first = r.x_first
        self.x_last = r.x_last
        self.dec_t.append(r.plot_t)
        self.dec_x.append(r.plot_x)
        if self.sign_first == 0 and r.decided >= 0:
            self.sign_first = r.first_state
        for j, start in enumerate(r.starts.tolist()):
            if start == r.decided:  # an edge only if the trigger entered in the other state
                if self.state != 0 and self.state != r.first_state:
                    self._close(self.state)
            elif j > 0:
                self._close(int(r.closing[j]))
            if r.seg_max[j] > self.open_max[0]:
                self.open_max = [float(r.seg_max[j]), int(r.arg_max[j]), float(r.t_max[j])]
            if r.seg_min[j] < self.open_min[0]:
                self.open_min = [float(r.seg_min[j]), int(r.arg_min[j]), float(r.t_min[j])]
        if r.decided >= 0:
            self.state = r.last_state

    def finish(self) -> Extremes:
        """The kept extremes (the first and last swings by the in-memory zigzag rule)."""
        plot_t, plot_x = np.concatenate(self.dec_t), np.concatenate(self.dec_x)
        if self.sign_first == 0:
            return Extremes(np.empty(0, np.intp), np.empty(0), np.empty(0, np.int8), plot_t, plot_x)
        self._close(self.state)
        swings = self.swings
        sign = np.array([s[0] for s in swings], dtype=np.int8)
        index = np.array([s[1] for s in swings], dtype=np.intp)
        times = np.array([s[2] for s in swings])
        best = np.array([s[3] for s in swings])
        h = self.h
        keep = np.ones(sign.size, dtype=bool)
        keep[0] = self.x_first * self.sign_first < best[0] - h and index[0] > 0
        keep[-1] = self.x_last * int(sign[-1]) < best[-1] - h and index[-1] < self.n - 1
        return Extremes(index[keep], times[keep], sign[keep], plot_t, plot_x)


def swing_extremes(
    pieces: Callable[[], Iterator[tuple[int, np.ndarray, np.ndarray, np.ndarray]]],
    n: int,
    mid: float,
    h: float,
) -> Extremes:
    """The extremes of :func:`~rotacal.table.extreme_reversals`, in one pass with the trigger's
    state and the open swing's running maximum and minimum carried (:class:`SwingFold`)."""
    step = _plot_stride(n)
    fold = SwingFold(n, h)
    for off, t, x, xt in pieces():
        fold.add(swing_runs(off, t, x, xt, mid, h, step))
    return fold.finish()


def _first_hits(x: np.ndarray, starts: np.ndarray, best: np.ndarray) -> np.ndarray:
    """Index (in x) of the first sample of each run ``starts[j]:starts[j+1]`` equal to best[j]."""
    lengths = np.diff(np.append(starts, x.size))
    run = np.repeat(np.arange(starts.size), lengths)
    hit = np.flatnonzero(x == best[run])
    return hit[np.unique(run[hit], return_index=True)[1]]


def reversal_windows(ext: Extremes, span_s: float) -> tuple[np.ndarray, np.ndarray, float]:
    """The first and last time (s) of each extreme's parabola window (±2.5 half windows) and
    the half window (s)."""
    half = reversal_half_window(ext.time, span_s)
    return ext.time - 2.5 * half, ext.time + 2.5 * half, half


def window_pieces(
    off: int, t: np.ndarray, x: np.ndarray, lo: np.ndarray, hi: np.ndarray, which: list[int]
) -> list[tuple[int, int, np.ndarray, np.ndarray]]:
    """``(window, global index of the first sample, t, θ)`` of the samples of a piece (global
    index ``off``) within each window ``which[i]`` (lo[i] ≤ t ≤ hi[i]), those that hold any."""
    # all windows at once: one binary search per bound
    starts = np.searchsorted(t, lo)
    stops = np.searchsorted(t, hi, side="right")
    return [
        (j, off + a, np.array(t[a:b]), np.array(x[a:b]))
        for j, a, b in zip(which, starts.tolist(), stops.tolist(), strict=True)
        if b > a
    ]


def refined_reversals(
    pieces: Callable[[], Iterator[tuple[int, np.ndarray, np.ndarray, np.ndarray]]],
    ext: Extremes,
    span_s: float,
    n: int,
) -> tuple[np.ndarray, np.ndarray]:
    """Reversing moments (s) and their sample index (``np.searchsorted(t, moment)``, clipped
    to the capture) from the extremes, each parabola on its window's samples (one pass)."""
    m = ext.index.size
    times, indices = np.empty(m), np.empty(m, dtype=np.intp)
    if m == 0:
        return times, indices
    lo, hi, half = reversal_windows(ext, span_s)
    nxt = 0
    active: dict[int, list[tuple[int, np.ndarray, np.ndarray]]] = {}
    for off, t, x, _ in pieces():
        while nxt < m and lo[nxt] <= t[-1]:
            active[nxt] = []
            nxt += 1
        open_now = list(active)
        for j, g0, t_w, x_w in window_pieces(off, t, x, lo[open_now], hi[open_now], open_now):
            active[j].append((g0, t_w, x_w))
        for j in open_now:
            if hi[j] < t[-1]:
                finish_window(j, active.pop(j), ext, half, times, indices)
    for j in list(active):
        finish_window(j, active.pop(j), ext, half, times, indices)
    return times, np.clip(indices, 0, n - 1)


def finish_window(
    j: int,
    parts: list[tuple[int, np.ndarray, np.ndarray]],
    ext: Extremes,
    half: float,
    times: np.ndarray,
    indices: np.ndarray,
) -> None:
    """The reversing moment (s) and sample index of window ``j`` from its pieces, in order."""
    times[j], indices[j] = window_moment(parts, float(ext.time[j]), int(ext.sign[j]), half)


def window_moment(
    parts: list[tuple[int, np.ndarray, np.ndarray]], t_ext: float, sign: int, half: float
) -> tuple[float, int]:
    """The reversing moment (s) of the extreme at ``t_ext`` (s; ``sign`` +1 a maximum) from its
    window's pieces ``(global index, t, θ)`` in order (:func:`~rotacal.table.refine_extreme`,
    half window ``half`` s), and its sample index."""
    t_w = np.concatenate([p[1] for p in parts])
    x_w = np.concatenate([p[2] for p in parts])
    moment = refine_extreme(t_w, x_w, t_ext, sign, half)
    return moment, parts[0][0] + int(np.searchsorted(t_w, moment))
