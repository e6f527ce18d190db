"""The plateaus of a continuous log read in chunks: the detection of :mod:`rotacal.gyro.plateaus`
as passes over the capture with carried state, so that memory is set by the chunk, not the log.

:func:`find_plateaus_chunked` makes the decisions of :func:`rotacal.gyro.plateaus.find_plateaus`
(which is this function over one chunk) on a capture fed as chunks. Each pass is a fresh call of
``chunks(columns)`` and reads only the columns it needs:

A. ``time_s``, ``rate_deg_s``: the log's checks (finite, strictly increasing time, the previous
   chunk's last time carried), the sampling interval (median step of the first 2·10⁶ rows), the
   strided first differences of the robust noise estimate (the previous chunk's last rate
   carried), a strided copy for the figure.
B. ``rate_deg_s``: the filtered derivative from the cumulative sum continued across chunks
   (``np.cumsum`` is a sequential scan: the carried sum gives the same values to the bit), with
   the last 2h sums carried; the steady runs, each with its sum of rates (the band's centre).
C. ``rate_deg_s``: each run's edges moved to where the rate enters its band (the 2h rows before
   the chunk carried: an edge moves by 2h rows at most), and the count, mean and M₂ of every
   refined run and the sums of the rows between them (Chan, Golub & LeVeque 1983, eq. 2.1), from
   which the merge of neighbouring runs is decided without the rows.
D. ``output`` (when it is given): the block means of the DUT's settling (blocks of h/10 rows,
   the open block carried to the next chunk, a plateau's settling read and its blocks dropped as
   soon as they are all in), a strided copy for the figure.
E. ``time_s``, ``rate_deg_s`` [, ``temperature_c``]: each plateau's span after settling: times of
   its ends, mean, M₂, the means of its first and last thirds (its drift), its mean temperature.

The statistics of a span come from per-chunk two-pass means and M₂ merged pairwise, so a chunk
boundary moves them by rounding only (≤ 1e-12 relative; over one chunk they are NumPy's own
``mean``/``std`` of the span). Memory: the chunk, 2h rows, a few numbers per run, the settling's
block means of one plateau (at most ``SETTLE_BLOCKS``) and 2·10⁶ differences.

References
----------
Basseville M., Nikiforov I. V. (1993), *Detection of Abrupt Changes*, §2.1 (the detector);
Chan T. F., Golub G. H., LeVeque R. J. (1983), Am. Stat. 37(3):242–247, eq. (2.1).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator, Mapping, Sequence
from typing import Any

import numpy as np

from rotacal.errors import CaptureError, ConfigError
from rotacal.gyro.plateaus import (
    _NOISE_SAMPLES,
    _NOISY_FACTOR,
    _Z,
    DEFAULT_PLATEAU_WINDOW_S,
    Plateau,
    PlateauSearch,
    _drift_limit,
    _positive,
    _settling_of,
)
from rotacal.gyro.scale_factor_points import DEFAULT_RATE_TOLERANCE_DEG_S
from rotacal.gyro.scale_factor_stream import _CHANGED
from rotacal.gyro.scale_factor_stream import _Reader as _Passes

__all__ = ["LogChunks", "find_plateaus_chunked", "log_chunks"]

#: ``chunks(columns)`` starts a fresh pass over the log and yields mappings of 1-D arrays of the
#: named columns (``time_s`` in s, ``rate_deg_s`` in °/s, ``output``, ``temperature_c`` in °C),
#: the same rows on every call.
LogChunks = Callable[[Sequence[str]], Iterator[Mapping[str, np.ndarray]]]

#: Rows kept for the log's figure (evenly strided).
FIGURE_ROWS = 20_000
#: Blocks of a plateau's start that its settling is read from (8 bytes each): 2·10⁸ rows at
#: 1 kHz (55 h), 2·10⁷ at 100 Hz; a DUT settles in seconds, and memory stays bounded.
SETTLE_BLOCKS = 2_000_000


def log_chunks(*columns: np.ndarray | None, chunk_rows: int | None = None) -> LogChunks:
    """A chunk source over arrays in memory: ``time_s``, ``rate_deg_s``, then ``output`` and
    ``temperature_c`` when given (None: absent); ``chunk_rows`` rows a chunk (None: one chunk)."""
    names = ("time_s", "rate_deg_s", "output", "temperature_c")
    arrays = {
        k: np.asarray(v, dtype=float).reshape(-1)
        for k, v in zip(names, columns, strict=False)
        if v is not None
    }
    if chunk_rows is not None and (
        isinstance(chunk_rows, bool) or not isinstance(chunk_rows, int) or chunk_rows < 1
    ):
        raise ConfigError(f"chunk_rows must be a whole number ≥ 1, not {chunk_rows!r}")

    def chunks(wanted: Sequence[str]) -> Iterator[dict[str, np.ndarray]]:
        n = max(a.size for a in arrays.values())
        step = n if chunk_rows is None else chunk_rows
        for s in range(0, max(n, 1), max(step, 1)):
            yield {k: arrays[k][s : s + step] for k in wanted}

    return chunks


class _Tail:
    """The last ``keep`` rows before the current chunk, joined to it: window[i] is row
    ``start + i``."""

    def __init__(self, keep: int) -> None:
        self.keep = keep
        self.buf = np.empty(0)
        self.start = 0

    def window(self, offset: int, x: np.ndarray) -> np.ndarray:
        win = np.concatenate([self.buf, x]) if self.buf.size else x
        self.start = offset - self.buf.size
        self.buf = win[-self.keep :].copy() if self.keep else np.empty(0)
        return win


def _stats(x: np.ndarray) -> tuple[int, float, float]:
    """(count, mean, M₂) of a span's rows (two-pass, as ``np.mean``/``np.std``)."""
    if x.size == 0:
        return 0, 0.0, 0.0
    m = float(np.mean(x))
    return x.size, m, float(np.sum((x - m) ** 2))


def _chan(a: tuple[int, float, float], b: tuple[int, float, float]) -> tuple[int, float, float]:
    """(count, mean, M₂) of two sets of rows together (Chan, Golub & LeVeque 1983, eq. 2.1)."""
    na, ma, qa = a
    nb, mb, qb = b
    if nb == 0:
        return a
    if na == 0:
        return b
    n = na + nb
    d = mb - ma
    return n, ma + d * (nb / n), qa + qb + d * d * (na * (nb / n))


# --------------------------------------------------------------------------------------------
# pass A: checks, sampling interval, noise
# --------------------------------------------------------------------------------------------
class _Scan:
    """Pass A over (time_s, rate_deg_s): the refusals of a log, dt, the noise differences."""

    def __init__(self, n: int, first_rows: int, noise_samples: int) -> None:
        self.n = n
        self.stride = max(1, (n - 1) // noise_samples)
        self.fig = max(1, n // FIGURE_ROWS)
        self.first_rows = first_rows
        self.t_first: list[np.ndarray] = []
        self.diffs: list[np.ndarray] = []
        self.fig_t: list[np.ndarray] = []
        self.fig_r: list[np.ndarray] = []
        self.bad = {"time_s": [0, -1, 0.0], "rate_deg_s": [0, -1, 0.0]}
        self.back = [0, -1, 0.0, 0.0]  # count, row, time, time before
        self.last_t = self.last_r = math.nan

    def add(self, offset: int, t: np.ndarray, r: np.ndarray) -> None:
        for name, x in (("time_s", t), ("rate_deg_s", r)):
            bad = np.flatnonzero(~np.isfinite(x))
            if bad.size:
                rec = self.bad[name]
                if rec[1] < 0:
                    rec[1], rec[2] = offset + int(bad[0]), float(x[bad[0]])
                rec[0] += bad.size
        tt = np.r_[self.last_t, t] if offset else t
        back = np.flatnonzero(np.diff(tt) <= 0)
        if back.size:
            k = int(back[0])
            if self.back[1] < 0:
                self.back[1:] = [offset + k + (0 if offset else 1), tt[k + 1], tt[k]]
            self.back[0] += back.size
        if offset < self.first_rows:
            self.t_first.append(t[: self.first_rows - offset])
        # strided differences r[i+1] − r[i], i ≡ 0 (mod stride), the last rate carried
        rr = np.r_[self.last_r, r] if offset else r
        base = offset - 1 if offset else 0  # row of rr[0]
        first = -(-base // self.stride) * self.stride
        idx = np.arange(first - base, rr.size - 1, self.stride)
        self.diffs.append(rr[idx + 1] - rr[idx])
        sel = slice(-(-offset // self.fig) * self.fig - offset, None, self.fig)
        self.fig_t.append(t[sel].copy())
        self.fig_r.append(r[sel].copy())
        self.last_t, self.last_r = float(t[-1]), float(r[-1])

    def refuse(self) -> None:
        """The log's refusals, in the order of the whole-array checks."""
        for name, (count, row, value) in self.bad.items():
            if count:
                raise CaptureError(
                    f"column {name} holds {value} at row {row} (0-based, {count} such): "
                    "every row of a continuous log needs a finite time and table rate"
                )
        count, row, after, before = self.back
        if count:
            raise CaptureError(
                f"column time_s does not increase at row {row} (0-based): {after!r} s after "
                f"{before!r} s ({count} such rows); a continuous log needs strictly increasing time"
            )

    def dt(self) -> float:
        return float(np.median(np.diff(np.concatenate(self.t_first))))

    def noise(self) -> float:
        """σ of the table rate's white noise (°/s): 1.4826·MAD of its first differences over √2."""
        d = np.concatenate(self.diffs)
        med = np.median(d)
        return float(1.4826 * np.median(np.abs(d - med)) / math.sqrt(2.0))


# --------------------------------------------------------------------------------------------
# pass B: the steady runs
# --------------------------------------------------------------------------------------------
class _Runs:
    """Pass B: boundaries k (between rows k − 1 and k) are changes when |D[k]| > thr; rows after
    a change are unsteady (rows before h follow boundary h, rows after n − h boundary n − h);
    the runs of steady rows, each with the sum of its rates."""

    def __init__(self, n: int, h: int, thr: float) -> None:
        self.n, self.h, self.thr = n, h, thr
        self.c = np.zeros(1)  # cumulative sums C[k] for k ≥ c0
        self.c0 = 0
        self.r0 = math.nan
        self.rows = np.empty(0)  # rates of rows ≥ next_row not yet flagged
        self.next_row = 0
        self.last_change = True
        self.open: list[Any] | None = None  # [start, sum] of the run being read
        self.runs: list[tuple[int, int, float]] = []

    def add(self, offset: int, r: np.ndarray) -> None:
        n, h = self.n, self.h
        if offset == 0:
            self.r0 = float(r[0])
        # C continued from its last value (the same sequential scan as over the whole column)
        more = np.cumsum(np.r_[self.c[-1], r - self.r0])[1:]
        self.c = np.concatenate([self.c, more])
        self.rows = np.concatenate([self.rows, r])
        end = offset + r.size  # rows known: [.., end)
        k0 = max(h, self.next_row)
        k1 = min(n - h + 1, end - h + 1)
        if k1 <= k0 and end < n:
            return
        if k1 > k0:
            c, c0 = self.c, self.c0
            d = c[k0 + h - c0 : k1 + h - c0] - c[k0 - c0 : k1 - c0]
            d -= c[k0 - c0 : k1 - c0]
            d += c[k0 - h - c0 : k1 - h - c0]
            change = np.abs(d) > self.thr * h
            self.last_change = bool(change[-1])
        else:
            change = np.zeros(0, dtype=bool)
        flags = [change]
        if self.next_row == 0:
            flags.insert(0, np.full(h, change[0]))
        stop = k1 if k1 > k0 else self.next_row
        if end == n:  # the last h − 1 rows follow boundary n − h
            flags.append(np.full(n - stop, self.last_change))
            stop = n
        unsteady = np.concatenate(flags)
        self._runs(unsteady, stop, end == n)
        # keep C from the next boundary's left end on, the rates from the next unflagged row
        keep = max(0, min(stop, n - h + 1) - h) - self.c0
        self.c, self.c0 = self.c[keep:], self.c0 + keep
        self.rows = self.rows[stop - self.next_row :]
        self.next_row = stop

    def _runs(self, unsteady: np.ndarray, stop: int, last: bool) -> None:
        first = self.next_row
        x = self.rows[: stop - first]
        prev = np.r_[not (self.open is not None), unsteady]
        edges = np.flatnonzero(np.diff(prev.view(np.int8)))  # positions where the flag flips
        pos = 0
        for e in edges:
            if self.open is None:  # a run starts
                self.open = [first + int(e), 0.0]
            else:  # it stops
                self.open[1] += float(np.sum(x[max(self.open[0] - first, 0) : int(e)]))
                self.runs.append((self.open[0], first + int(e), self.open[1]))
                self.open = None
            pos = int(e)
        if self.open is not None:
            self.open[1] += float(np.sum(x[max(self.open[0] - first, pos) :]))
            if last:
                self.runs.append((self.open[0], self.n, self.open[1]))
                self.open = None


def steady_runs(passes: _Passes, n: int, h: int, thr: float) -> list[tuple[int, int, float]]:
    runs = _Runs(n, h, thr)
    for offset, (r,) in passes.run(("rate_deg_s",)):
        runs.add(offset, r)
    return runs.runs


# --------------------------------------------------------------------------------------------
# pass C: the edges refined; pass D: the statistics of the runs and of the rows between them
# --------------------------------------------------------------------------------------------
def refine_edges(
    passes: _Passes, runs: list[tuple[int, int, float]], n: int, band: float, reach: int
) -> np.ndarray:
    """Each run's edges moved out to where the rate enters its band around the run's mean (at
    most ``reach`` rows, never into the neighbouring run): [start, stop) of each."""
    k = len(runs)
    a = np.array([x[0] for x in runs], dtype=np.int64)
    b = np.array([x[1] for x in runs], dtype=np.int64)
    mean = [x[2] / (x[1] - x[0]) for x in runs]
    out = np.column_stack([a, b]).astype(np.int64)
    # events in row order: run i's start (needs rows up to a_i), its stop (up to hi_i ≤ a_i+1)
    hi = np.minimum(np.r_[a[1:], n], b + reach)
    need = np.column_stack([a, hi]).reshape(-1)
    tail = _Tail(reach)
    e = 0
    for offset, (r,) in passes.run(("rate_deg_s",)):
        end = offset + r.size
        win = tail.window(offset, r)
        w0 = tail.start
        while e < 2 * k and (need[e] <= end or end == n):
            i, after = divmod(e, 2)
            if not after:
                lo = max(int(out[i - 1, 1]) if i else 0, int(a[i]) - reach)
                far = np.flatnonzero(np.abs(win[lo - w0 : int(a[i]) - w0] - mean[i]) > band)
                out[i, 0] = lo + (int(far[-1]) + 1 if far.size else 0)
            else:
                seg = win[int(b[i]) - w0 : int(hi[i]) - w0]
                far = np.flatnonzero(np.abs(seg - mean[i]) > band)
                out[i, 1] = int(b[i]) + (int(far[0]) if far.size else seg.size)
            e += 1
    return out


def span_stats(
    passes: _Passes, spans: np.ndarray, names: Sequence[str] = ("rate_deg_s",)
) -> list[list[tuple[int, float, float]]]:
    """(count, mean, M₂) over each [start, stop) of ``spans`` (sorted, not overlapping) of each
    named column, merged over the chunks (Chan et al. 1983, eq. 2.1)."""
    out = [[(0, 0.0, 0.0)] * len(spans) for _ in names]
    if not len(spans):
        return out
    starts, stops = spans[:, 0], spans[:, 1]
    for offset, cols in passes.run(tuple(names)):
        end = offset + cols[0].size
        first = int(np.searchsorted(stops, offset, side="right"))
        last = int(np.searchsorted(starts, end, side="left"))
        for i in range(first, last):
            s, t = max(int(starts[i]), offset) - offset, min(int(stops[i]), end) - offset
            if t > s:
                for j, x in enumerate(cols):
                    out[j][i] = _chan(out[j][i], _stats(x[s:t]))
    return out


def merge_runs(runs: np.ndarray, passes: _Passes, z: float, sigma: float, tol: float) -> np.ndarray:
    """Join neighbouring runs whose means, and the mean of the rows between them, agree within
    the change threshold taken with the noisier of σ and the runs' own standard deviations (an
    outlier cannot split a plateau; a plateau noisier than the log is not cut in pieces but
    stays one, to be judged whole). Pass D: the statistics of the runs and the gaps between."""
    edges = runs.reshape(-1)
    spans = np.column_stack([edges[:-1], edges[1:]])  # run 0, gap 0, run 1, gap 1, …
    (stats,) = span_stats(passes, spans)
    merged: list[list[int]] = []
    last: tuple[int, float, float] = (0, 0.0, 0.0)
    for i, (a, b) in enumerate(runs):
        st = stats[2 * i]
        mean, sd = st[1], math.sqrt(st[2] / st[0])
        if merged:
            last_sd = math.sqrt(last[2] / last[0])
            spread = z * max(sigma, sd, last_sd)
            n_last = merged[-1][1] - merged[-1][0]
            same = abs(mean - last[1]) <= spread * math.sqrt(1.0 / (b - a) + 1.0 / n_last) + tol
            gap = stats[2 * i - 1]
            if same and gap[0]:
                limit = spread * math.sqrt(1.0 / gap[0] + 1.0 / n_last) + tol
                same = abs(gap[1] - last[1]) <= limit
            if same:
                merged[-1][1] = int(b)
                last = _chan(_chan(last, gap), st)
                continue
        merged.append([int(a), int(b)])
        last = st
    return np.asarray(merged, dtype=np.int64).reshape(-1, 2)


# --------------------------------------------------------------------------------------------
# pass D: the DUT's settling read from the output
# --------------------------------------------------------------------------------------------
def settling_rows(
    passes: _Passes, runs: np.ndarray, m: int, fig: int
) -> tuple[list[int], np.ndarray]:
    """The DUT's settling (rows) in each run, from the means of consecutive blocks of ``m``
    output rows from the run's start (whole blocks, at most ``SETTLE_BLOCKS`` of them; the open
    block carried to the next chunk; a run's blocks dropped once its settling is read), and every
    ``fig``-th output row."""
    rows = [0] * len(runs)
    blocks: dict[int, list[np.ndarray]] = {}
    carry: dict[int, np.ndarray] = {}
    stops = np.minimum(
        runs[:, 0] + (runs[:, 1] - runs[:, 0]) // m * m, runs[:, 0] + SETTLE_BLOCKS * m
    )
    figure: list[np.ndarray] = []
    for offset, (y,) in passes.run(("output",)):
        end = offset + y.size
        figure.append(y[-(-offset // fig) * fig - offset :: fig].copy())
        first = int(np.searchsorted(runs[:, 1], offset, side="right"))
        last = int(np.searchsorted(runs[:, 0], end, side="left"))
        for i in range(first, last):
            s, t = max(int(runs[i, 0]), offset), min(int(stops[i]), end)
            if t > s:
                x = np.concatenate([carry.pop(i, np.empty(0)), y[s - offset : t - offset]])
                whole = x.size // m * m
                if whole:
                    blocks.setdefault(i, []).append(x[:whole].reshape(-1, m).mean(axis=1))
                carry[i] = x[whole:].copy()
            if stops[i] <= end and i in carry:  # the run's blocks are all in: read its settling
                carry.pop(i)
                got = blocks.pop(i, [])
                rows[i] = _settling_of(np.concatenate(got) if got else np.empty(0), m)
    return rows, np.concatenate(figure)


# --------------------------------------------------------------------------------------------
# pass E: each plateau after settling
# --------------------------------------------------------------------------------------------
class _Spans:
    """Pass E: per span [a, b): the times of its ends, (count, mean, M₂) of the rate, the means
    of its first and last thirds of ``thirds`` rows each, and the temperature's finite sum and
    count."""

    def __init__(self, spans: np.ndarray, temperature: bool) -> None:
        self.spans = spans
        k = (spans[:, 1] - spans[:, 0]) // 3
        self.thirds = [np.c_[spans[:, 0], spans[:, 0] + k], np.c_[spans[:, 1] - k, spans[:, 1]]]
        self.rows = np.c_[spans[:, 0], spans[:, 1] - 1].reshape(-1)
        self.times = np.full(self.rows.size, math.nan)
        ns = len(spans)
        self.stats: list[tuple[int, float, float]] = [(0, 0.0, 0.0)] * ns
        self.third_stats = [[(0, 0.0, 0.0)] * ns, [(0, 0.0, 0.0)] * ns]
        self.temp = np.zeros((ns, 2)) if temperature else None

    def names(self) -> tuple[str, ...]:
        return ("time_s", "rate_deg_s") + (("temperature_c",) if self.temp is not None else ())

    def add(self, offset: int, cols: list[np.ndarray]) -> None:
        t, r = cols[0], cols[1]
        end = offset + t.size
        here = (self.rows >= offset) & (self.rows < end)
        self.times[here] = t[self.rows[here] - offset]
        for spans, out in (
            (self.spans, self.stats),
            *zip(self.thirds, self.third_stats, strict=True),
        ):
            for i, s, u in _parts(spans, offset, end):
                out[i] = _chan(out[i], _stats(r[s:u]))
        if self.temp is not None:
            for i, s, u in _parts(self.spans, offset, end):
                x = cols[2][s:u]
                self.temp[i] += (float(np.nansum(x)), int(np.count_nonzero(~np.isnan(x))))


def _parts(spans: np.ndarray, offset: int, end: int) -> Iterator[tuple[int, int, int]]:
    """(span, first, stop) of the parts of sorted ``spans`` inside rows [offset, end), as
    positions in the chunk."""
    if not len(spans):
        return
    order = np.argsort(spans[:, 0], kind="stable")
    for i in order:
        s, u = max(int(spans[i, 0]), offset), min(int(spans[i, 1]), end)
        if u > s:
            yield int(i), s - offset, u - offset


# --------------------------------------------------------------------------------------------
# the method
# --------------------------------------------------------------------------------------------
def find_plateaus_chunked(
    chunks: LogChunks,
    *,
    rows: int | None = None,
    output: bool = True,
    temperature: bool = False,
    settle_s: float | None = None,
    window_s: float | None = None,
    min_plateau_s: float | None = None,
    rate_tolerance_deg_s: float = DEFAULT_RATE_TOLERANCE_DEG_S,
    progress: Callable[[int], None] | None = None,
) -> PlateauSearch:
    """The plateaus of a continuous rate-table log read in chunks (filtered-derivative change
    detection, Basseville & Nikiforov 1993, §2.1; the method of :mod:`rotacal.gyro.plateaus`).

    Parameters
    ----------
    chunks : callable
        ``chunks(columns)`` starts a fresh pass and yields mappings holding the 1-D arrays of the
        named columns — ``time_s`` (s), ``rate_deg_s`` (°/s), ``output`` (output units),
        ``temperature_c`` (°C) — in row order, the same rows every call (:func:`log_chunks`).
    rows : int or None
        The log's number of rows when known (a file's metadata); None: one more pass counts them.
    output : bool
        Whether the source has ``output`` (the default settling is read from it).
    temperature : bool
        Whether the source has ``temperature_c`` (each used plateau's mean is kept).
    settle_s, window_s, min_plateau_s, rate_tolerance_deg_s
        As :func:`rotacal.gyro.plateaus.find_plateaus` (s, s, s, °/s).
    progress : callable, optional
        Called after each chunk with the rows read so far, summed over the passes.

    Returns
    -------
    PlateauSearch
        The result of :func:`rotacal.gyro.plateaus.find_plateaus` on the whole columns (to
        rounding of the spans' means and deviations), with a strided copy of the log.

    Raises
    ------
    CaptureError
        As :func:`~rotacal.gyro.plateaus.find_plateaus`; columns of unequal lengths in a chunk; a
        capture that changes between passes.

    References
    ----------
    Basseville & Nikiforov (1993), §2.1; Chan, Golub & LeVeque (1983), eq. (2.1).
    """
    passes = _Passes(chunks, progress, example="log_chunks(time, rate, output)")
    if rows is None:
        for _ in passes.run(("rate_deg_s",)):
            pass
        rows = passes.rows
    n = int(rows or 0)
    if n < 4:
        raise CaptureError(f"the log has {n} rows: too few to find plateaus in")
    scan = _Scan(n, _NOISE_SAMPLES, _NOISE_SAMPLES)
    for offset, (t, r) in passes.run(("time_s", "rate_deg_s")):
        scan.add(offset, t, r)
    if passes.rows != n:
        raise CaptureError(_CHANGED)
    scan.refuse()
    window = _positive("window_s", window_s, DEFAULT_PLATEAU_WINDOW_S)
    dt = scan.dt()
    h = max(3, round(window / dt))
    t_last = scan.last_t
    t_first = float(scan.t_first[0][0])
    if 2 * h >= n:
        raise CaptureError(
            f"the log spans {n} rows ({t_last - t_first:.6g} s): too short to find plateaus in "
            f"with a window of {h} rows ({h * dt:.3g} s)"
        )
    min_s = _positive("min_plateau_s", min_plateau_s, 5.0 * h * dt)
    tol = _positive("rate_tolerance_deg_s", rate_tolerance_deg_s, DEFAULT_RATE_TOLERANCE_DEG_S)
    sigma = scan.noise()
    thr = _Z * sigma * math.sqrt(2.0 / h) + tol
    found = steady_runs(passes, n, h, thr)
    runs = np.zeros((0, 2), dtype=np.int64)
    if found:
        edges = refine_edges(passes, found, n, _Z * sigma + tol, 2 * h)
        runs = merge_runs(edges, passes, _Z, sigma, tol)
    # a steady run shorter than the window is no plateau (a ramp's turning point, a sine's crest)
    runs = runs[runs[:, 1] - runs[:, 0] >= h]
    min_rows = max(10, math.ceil(min_s / dt - 1e-9))
    if not np.any(runs[:, 1] - runs[:, 0] >= min_rows):
        raise CaptureError(
            f"the table rate never settles: no span of {min_rows} rows ({min_rows * dt:.3g} s, "
            f"min_plateau_s) holds a steady rate (noise σ = {sigma:.3g} °/s); a continuous log "
            "must hold each rate for a while"
        )
    fig_y = np.full(sum(x.size for x in scan.fig_t), math.nan)
    m = max(1, h // 10)  # blocks of a tenth of the window: they follow a ringing DUT
    settling: list[int] = []
    if output:
        settling, fig_y = settling_rows(passes, runs, m, scan.fig)
    if settle_s is not None:
        settle, source = _positive("settle_s", settle_s, 0.0), "given"
        settle_rows = math.ceil(settle / dt - 1e-9)
    else:
        settle_rows = max([h, *settling])
        settle, source = round(settle_rows * dt, 9), ("output" if output else "window")
    a2 = np.minimum(runs[:, 0] + settle_rows, runs[:, 1])
    spans = np.column_stack([np.where(runs[:, 1] - a2 >= 1, a2, runs[:, 0]), runs[:, 1]])
    measured = _Spans(spans, temperature)
    for offset, cols in passes.run(measured.names()):
        measured.add(offset, cols)
    search = _judge(runs, a2, measured, sigma, tol, min_rows, dt, settle)
    return PlateauSearch(
        **search,
        settle_s=settle,
        settle_source=source,
        window_s=h * dt,
        rate_noise_deg_s=sigma,
        threshold_deg_s=thr,
        _log=(np.concatenate(scan.fig_t), np.concatenate(scan.fig_r), fig_y),
    )


def _judge(
    runs: np.ndarray,
    a2: np.ndarray,
    measured: _Spans,
    sigma: float,
    tol: float,
    min_rows: int,
    dt: float,
    settle: float,
) -> dict[str, Any]:
    """Used and rejected plateaus: too short after settling, too noisy, or drifting."""
    stds = [
        math.sqrt(st[2] / st[0]) if b - a > 1 else math.nan
        for (a, b), st in zip(np.c_[a2, runs[:, 1]], measured.stats, strict=True)
    ]
    typical = float(np.nanmedian(stds)) if np.isfinite(stds).any() else 0.0
    used: list[Plateau] = []
    rejected: list[Plateau] = []
    rows: list[tuple[int, int]] = []
    temps: list[float] = []
    for i, ((a, b), sd) in enumerate(zip(runs, stds, strict=True)):
        a, b, start = int(a), int(b), int(a2[i])
        count, mean, m2 = measured.stats[i]
        values = (
            float(measured.times[2 * i]),
            float(measured.times[2 * i + 1]),
            mean,
            count,
            math.sqrt(m2 / count) if count > 1 else 0.0,
        )
        first, last = measured.third_stats[0][i], measured.third_stats[1][i]
        drift = abs(last[1] - first[1]) if first[0] else 0.0
        if b - start < min_rows:
            why = (
                f"too short: {b - start} rows ({(b - start) * dt:.3g} s) after settling "
                f"{settle:.3g} s, fewer than {min_rows} ({min_rows * dt:.3g} s)"
            )
        elif sd > _NOISY_FACTOR * typical + tol:
            why = (
                f"too noisy: table rate σ = {sd:.3g} °/s, above {_NOISY_FACTOR:g}× the plateaus' "
                f"median {typical:.3g} °/s (+ {tol:g} °/s)"
            )
        elif drift > (limit := _drift_limit(b - start, sigma, sd, tol)):
            why = (
                f"not steady: the table rate drifts by {drift:.3g} °/s from its first to its "
                f"last third, more than {limit:.3g} °/s ({_Z:g} standard errors)"
            )
        else:
            used.append(Plateau(*values))
            rows.append((start, b))
            if measured.temp is not None:
                total, finite = measured.temp[i]
                temps.append(float(total / finite) if finite else math.nan)
            continue
        rejected.append(Plateau(*values, reason=why))
    warnings = tuple(
        f"plateau {p.start_s:.6g}–{p.end_s:.6g} s at {p.rate_deg_s:+.6g} °/s rejected, {p.reason}"
        for p in rejected
    )
    distinct = np.unique(np.round(np.array([p.rate_deg_s for p in used]) / max(tol, 1e-12)))
    if distinct.size < 2:
        found = "no plateau" if not used else f"one plateau rate ({used[0].rate_deg_s:+.6g} °/s)"
        extra = f" ({len(rejected)} rejected: {rejected[0].reason})" if rejected else ""
        raise CaptureError(
            f"the log holds {found} usable for a scale factor{extra}: it needs plateaus at two "
            "rates at least; check the rate_deg_s column, --settle-s and the log's length"
        )
    return {
        "plateaus": tuple(used),
        "rejected": tuple(rejected),
        "_rows": np.asarray(rows, dtype=np.int64).reshape(-1, 2),
        "_temperature_c": tuple(temps) if measured.temp is not None else None,
        "warnings": warnings,
    }
