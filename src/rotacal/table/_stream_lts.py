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
from collections.abc import Callable, Iterator

import numpy as np

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
    t_mid = 0.5 * (float(found.first_t) + float(found.last_t))
    s_tau = s_tau2 = s_x = s_taux = 0.0
    whole = angle_segment(passes, radius_mm, 0, found.n - 1)
    for _, t, x in whole():
        tau = t - t_mid
        s_tau += float(np.sum(tau))
        s_tau2 += float(tau @ tau)
        s_x += float(np.sum(x))
        s_taux += float(tau @ x)
    # Σ τ·(x − x̄) = Σ τ·x − x̄·Σ τ
    slope = (s_taux - s_x / found.n * s_tau) / s_tau2
    assert found.first_samples is not None and found.strided is not None
    t1, d1 = found.first_samples
    ts, ds = found.strided.arrays()
    f0 = start_frequency(
        (t1, lts_angle(d1, radius_mm) - slope * (t1 - t_mid)),
        (ts, lts_angle(ds, radius_mm) - slope * (ts - t_mid)),
        whole=found.strided.stride == 1 and ts.size == t1.size,
    )
    acc = accumulator(f0, harmonics, found.typical)

    def less_line() -> Iterator[tuple[int, np.ndarray, np.ndarray]]:
        for g0, t, x in whole():
            yield g0, t, x - slope * (t - t_mid)

    accumulate([(acc, None)], less_line(), block_length(f0, harmonics, found.typical))
    fit = acc.fit(f0, harmonics, True, max_iter=50, rtol=1e-12, drift=True)
    assert fit.drift is not None
    return slope + fit.drift


def trigger_values(
    passes: Passes, radius_mm: float, trend: float, t0: float
) -> Callable[[], Iterator[tuple[int, np.ndarray, np.ndarray, np.ndarray]]]:
    """A fresh pass over ``(offset, t, θ, what the trigger sees)``: θ less ``trend``·(t − t₀)."""

    def pieces() -> Iterator[tuple[int, np.ndarray, np.ndarray, np.ndarray]]:
        for _, off, cols in passes.run():
            t = cols["time_s"]
            x = lts_angle(cols[_SIGNAL], radius_mm)
            yield off, t, x, (x if trend == 0.0 else x - trend * (t - t0))

    return pieces


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


def order_statistics(
    values: Callable[[], Iterator[np.ndarray]], ranks: list[int], lo: float, hi: float
) -> list[float]:
    """The k-th smallest values (k 0-based) of a stream of values all within [lo, hi], exactly.

    Each pass histograms, per rank, the values in the rank's current range into 4096 bins and
    narrows the range to the bin holding the rank; once a range holds at most 2²¹ values they are
    gathered and sorted (a range whose values are all equal gives its value at once). For
    smoothly spread values two passes suffice up to ~10¹⁰ samples.
    """
    todo = [_Rank(k, lo, hi) for k in ranks]
    while any(r.value is None for r in todo):
        live = [r for r in todo if r.value is None]
        keys = sorted({(r.lo, r.hi) for r in live})
        gather = {key: all(_gathering(r) for r in live if (r.lo, r.hi) == key) for key in keys}
        below = dict.fromkeys(keys, 0)
        hist = {key: np.zeros(_BINS, dtype=np.int64) for key in keys}
        kept: dict[tuple[float, float], list[np.ndarray]] = {key: [] for key in keys}
        v_lo = dict.fromkeys(keys, math.inf)
        v_hi = dict.fromkeys(keys, -math.inf)
        for v in values():
            for key in keys:
                a, b = key
                below[key] += int(np.count_nonzero(v < a))
                inside = v[(v >= a) & (v <= b)]
                if inside.size == 0:
                    continue
                v_lo[key] = min(v_lo[key], float(inside.min()))
                v_hi[key] = max(v_hi[key], float(inside.max()))
                if gather[key]:
                    kept[key].append(inside)
                elif b > a:
                    hist[key] += np.histogram(inside, bins=_BINS, range=(a, b))[0]
        for r in live:
            key = (r.lo, r.hi)
            r.below = below[key]
            if v_lo[key] == v_hi[key]:  # every value left is the same one
                r.value = v_lo[key]
            elif gather[key]:
                r.value = float(np.sort(np.concatenate(kept[key]))[r.k - r.below])
            else:
                counts = hist[key]
                cum = np.cumsum(counts)
                j = int(np.searchsorted(cum, r.k - r.below, side="right"))
                edges = np.histogram_bin_edges(np.empty(0), bins=_BINS, range=(r.lo, r.hi))
                r.below += int(cum[j - 1]) if j > 0 else 0
                r.lo, r.hi = float(edges[j]), float(edges[j + 1])
                r.count = int(counts[j])
    return [float(r.value) for r in todo if r.value is not None]


def _gathering(r: _Rank) -> bool:
    """A rank whose range holds few enough values to gather them (known after one histogram)."""
    return 0 <= r.count <= _GATHER


def percentile(n: int, q: float, order: Callable[[list[int]], list[float]]) -> float:
    """``np.percentile(x, q)`` (linear method) of n values from their order statistics."""
    virtual = (n - 1) * (q / 100.0)
    below = math.floor(virtual)
    above = min(below + 1, n - 1)
    a, b = order([below, above]) if above != below else order([below]) * 2
    gamma = virtual - below
    diff = b - a
    return b - diff * (1 - gamma) if gamma >= 0.5 else a + diff * gamma


@dataclasses.dataclass
class Extremes:
    """The kept extremes of the trigger's swings: global index, time (s), sign (+1 maximum)."""

    index: np.ndarray
    time: np.ndarray
    sign: np.ndarray
    plot_t: np.ndarray  # every _plot_stride(n)-th sample of the capture, for the figures
    plot_angle: np.ndarray


def swing_extremes(
    pieces: Callable[[], Iterator[tuple[int, np.ndarray, np.ndarray, np.ndarray]]],
    n: int,
    mid: float,
    h: float,
) -> Extremes:
    """The extremes of :func:`~rotacal.table.extreme_reversals`, in one pass with the trigger's
    state and the open swing's running maximum and minimum (first occurrence) carried."""
    step = _plot_stride(n)
    state_before = 0  # the trigger's state before this chunk (0: no decision yet)
    # the open swing: its running max and min of θ, with their index and time
    open_max = [-math.inf, -1, math.nan]
    open_min = [math.inf, -1, math.nan]
    sign_first = 0
    x_first = x_last = math.nan
    swings: list[tuple[int, int, float, float]] = []  # sign, index, time, signed extreme
    dec_t: list[np.ndarray] = []
    dec_x: list[np.ndarray] = []

    def close(sign: int) -> None:
        best = open_max if sign > 0 else open_min
        swings.append((sign, int(best[1]), float(best[2]), sign * float(best[0])))
        open_max[:] = [-math.inf, -1, math.nan]
        open_min[:] = [math.inf, -1, math.nan]

    for off, t, x, xt in pieces():
        if off == 0:
            x_first = float(x[0])
        x_last = float(x[-1])
        s0 = (-off) % step
        dec_t.append(np.array(t[s0::step]))
        dec_x.append(np.array(x[s0::step]))
        state = np.where(xt > mid + h, 1, np.where(xt < mid - h, -1, 0)).astype(np.int8)
        at = np.where(state != 0, np.arange(state.size), -1)
        np.maximum.accumulate(at, out=at)
        filled = np.where(at >= 0, state[np.maximum(at, 0)], state_before).astype(np.int8)
        before = np.concatenate(([state_before], filled[:-1]))
        edges = np.flatnonzero((filled != before) & (before != 0))
        if sign_first == 0:
            decided = np.flatnonzero(filled)
            if decided.size:
                sign_first = int(filled[decided[0]])
        starts = np.concatenate(([0], edges))
        seg_max = np.maximum.reduceat(x, starts)
        seg_min = np.minimum.reduceat(x, starts)
        arg_max = _first_hits(x, starts, seg_max)
        arg_min = _first_hits(x, starts, seg_min)
        for j in range(starts.size):
            if j > 0:  # an edge: the swing before it ends with the state it had
                close(int(before[starts[j]]))
            if seg_max[j] > open_max[0]:
                open_max[:] = [float(seg_max[j]), off + int(arg_max[j]), float(t[arg_max[j]])]
            if seg_min[j] < open_min[0]:
                open_min[:] = [float(seg_min[j]), off + int(arg_min[j]), float(t[arg_min[j]])]
        state_before = int(filled[-1])
    plot_t, plot_x = np.concatenate(dec_t), np.concatenate(dec_x)
    if sign_first == 0:
        return Extremes(np.empty(0, np.intp), np.empty(0), np.empty(0, np.int8), plot_t, plot_x)
    close(state_before)
    sign = np.array([s[0] for s in swings], dtype=np.int8)
    index = np.array([s[1] for s in swings], dtype=np.intp)
    times = np.array([s[2] for s in swings])
    best = np.array([s[3] for s in swings])
    # the first and last swings are cut by the record's ends (extreme_reversals' zigzag rule)
    keep = np.ones(sign.size, dtype=bool)
    keep[0] = x_first * sign_first < best[0] - h and index[0] > 0
    keep[-1] = x_last * int(sign[-1]) < best[-1] - h and index[-1] < n - 1
    return Extremes(index[keep], times[keep], sign[keep], plot_t, plot_x)


def _first_hits(x: np.ndarray, starts: np.ndarray, best: np.ndarray) -> np.ndarray:
    """Index (in x) of the first sample of each run ``starts[j]:starts[j+1]`` equal to best[j]."""
    lengths = np.diff(np.append(starts, x.size))
    run = np.repeat(np.arange(starts.size), lengths)
    hit = np.flatnonzero(x == best[run])
    return hit[np.unique(run[hit], return_index=True)[1]]


def refined_reversals(
    pieces: Callable[[], Iterator[tuple[int, np.ndarray, np.ndarray, np.ndarray]]],
    ext: Extremes,
    span_s: float,
    n: int,
) -> tuple[np.ndarray, np.ndarray]:
    """Reversing moments (s) and their sample index (``np.searchsorted(t, moment)``, clipped
    to the capture) from the extremes, each parabola on its window's samples (one pass)."""
    m = ext.index.size
    times = np.empty(m)
    indices = np.empty(m, dtype=np.intp)
    if m == 0:
        return times, indices
    half = reversal_half_window(ext.time, span_s)
    lo = ext.time - 2.5 * half
    hi = ext.time + 2.5 * half
    nxt = 0
    active: dict[int, list[tuple[int, np.ndarray, np.ndarray]]] = {}
    for off, t, x, _ in pieces():
        while nxt < m and lo[nxt] <= t[-1]:
            active[nxt] = []
            nxt += 1
        open_now = np.fromiter(active, dtype=np.intp, count=len(active))
        # all windows at once: one binary search per bound and chunk
        starts = np.searchsorted(t, lo[open_now])
        stops = np.searchsorted(t, hi[open_now], side="right")
        for j, a, b in zip(open_now.tolist(), starts.tolist(), stops.tolist(), strict=True):
            if b > a:
                active[j].append((off + a, np.array(t[a:b]), np.array(x[a:b])))
            if hi[j] < t[-1]:
                _finish_window(j, active.pop(j), ext, half, times, indices)
    for j in list(active):
        _finish_window(j, active.pop(j), ext, half, times, indices)
    return times, np.clip(indices, 0, n - 1)


def _finish_window(
    j: int,
    parts: list[tuple[int, np.ndarray, np.ndarray]],
    ext: Extremes,
    half: float,
    times: np.ndarray,
    indices: np.ndarray,
) -> None:
    t_w = np.concatenate([p[1] for p in parts])
    x_w = np.concatenate([p[2] for p in parts])
    moment = refine_extreme(t_w, x_w, float(ext.time[j]), int(ext.sign[j]), half)
    times[j] = moment
    indices[j] = parts[0][0] + int(np.searchsorted(t_w, moment))
