"""Angle and angular velocity from the time stamps of encoder pulse edges (Kokuyama et al. 2015).

A multi-head encoder capture holds, per read head, the time (s) of every successive pulse edge
(INTERFACE.md: columns ``head_0`` … ``head_{n-1}``, head 0 the reference). Between two pulses the
scale has turned by one pitch Δθ = 360/m (plus the scale's deviation), so the angle is a count and
the angular velocity a pitch over a time difference — Kokuyama et al.'s time-difference method (§5).

This module checks pulse trains (finite, strictly increasing, no missing or extra pulse), pairs
the heads at the same instant (never by pulse index: heads start at different times), builds the
head-averaged time axis, and turns pulse times into angle and rate. The self-calibration itself is
in :mod:`rotacal.encoder.selfcal`.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from rotacal.columns import HEAD_NAME as _HEAD_NAME
from rotacal.errors import CaptureError, ConfigError
from rotacal.signal._checks import TYPICAL_STEPS
from rotacal.signal._values import check_time_span

__all__ = [
    "HeadPairing",
    "check_heads_not_copies",
    "check_pulse_times",
    "check_pulses_per_rev",
    "head_columns",
    "pair_heads",
    "pulse_angle_deg",
    "pulse_rate",
    "whole_revolution_rate",
]

FloatArray = NDArray[np.float64]

#: An interval this many local pulse periods long (or longer) means missing pulses.
MISSING_PULSE_RATIO = 1.5
#: An interval this short (in local pulse periods) means a spurious extra edge: an edge anywhere
#: inside an interval leaves a piece of at most half a period (plus the rate's wander).
EXTRA_PULSE_RATIO = 0.75
#: Intervals per block when estimating the local pulse period (robust to slow rate changes).
_PERIOD_BLOCK = 64
#: Pulse intervals :func:`pulse_rate` turns into rate points at a time.
_RATE_CHUNK = 1 << 18


def check_pulses_per_rev(pulses_per_rev: Any) -> int:
    """Return ``pulses_per_rev`` as an int ≥ 2 or raise ConfigError."""
    if isinstance(pulses_per_rev, bool) or not isinstance(pulses_per_rev, int | np.integer):
        if isinstance(pulses_per_rev, float) and pulses_per_rev.is_integer():
            pulses_per_rev = int(pulses_per_rev)
        else:
            raise ConfigError(
                f"pulses_per_rev must be a whole number of pulses per revolution, "
                f"got {pulses_per_rev!r}."
            )
    m = int(pulses_per_rev)
    if m < 2:
        raise ConfigError(f"pulses_per_rev must be at least 2, got {m}.")
    return m


def head_columns(columns: Mapping[str, ArrayLike]) -> list[FloatArray]:
    """The pulse trains ``head_0`` … ``head_{n-1}`` of a capture, in head order.

    Parameters
    ----------
    columns : mapping of str to array
        Capture columns; those named ``head_<k>`` are taken, others ignored.

    Returns
    -------
    list of ndarray
        One float64 array of pulse times (s) per head, head 0 first.

    Raises
    ------
    CaptureError
        No ``head_*`` column, or the heads are not numbered 0 … n−1 without a hole.
    """
    found: dict[int, ArrayLike] = {}
    for name, values in columns.items():
        match = _HEAD_NAME.match(name)
        if match:
            found[int(match.group(1))] = values
    if not found:
        raise CaptureError(
            "the capture has no head_0 … head_{n-1} columns of pulse times; name them so or map "
            "them with --column OLD=head_0."
        )
    missing = [k for k in range(max(found) + 1) if k not in found]
    if missing:
        raise CaptureError(
            f"the heads must be numbered head_0 … head_{max(found)} without a hole; "
            f"head_{missing[0]} is missing."
        )
    return [np.asarray(found[k], dtype=np.float64) for k in range(len(found))]


def block_medians(dt: FloatArray) -> FloatArray:
    """Medians of consecutive blocks of _PERIOD_BLOCK intervals (``dt.size`` a multiple of it).

    ``np.median`` row by row, by the same arithmetic (the mean of the two middle values of each
    sorted row: the same bits), from a sort of the short rows, several times faster than the
    partition np.median does.
    """
    rows = np.sort(dt.reshape(-1, _PERIOD_BLOCK), axis=1)
    half = _PERIOD_BLOCK // 2
    return np.asarray((rows[:, half - 1] + rows[:, half]) / 2.0)


def _local_period(dt: FloatArray) -> FloatArray:
    """Robust local pulse period at every interval: block medians, linearly interpolated."""
    n = dt.size
    if n <= 2 * _PERIOD_BLOCK:
        return np.full(n, float(np.median(dt)))
    size = _PERIOD_BLOCK
    nb = n // size
    medians = block_medians(dt[: nb * size])
    centres = (np.arange(nb) + 0.5) * size
    # np.interp(arange(n), centres, medians) by rows: the centres are evenly spaced, so the
    # intervals between them are whole rows of `size` intervals (the same operations, the
    # same bits, without a binary search per interval)
    slope = (medians[1:] - medians[:-1]) / (centres[1:] - centres[:-1])
    half = size // 2
    out = np.empty(n)
    out[:half] = medians[0]
    inner = out[half : half + (nb - 1) * size].reshape(nb - 1, size)
    np.multiply(slope[:, None], np.arange(size, dtype=np.float64)[None, :], out=inner)
    inner += medians[:-1, None]
    out[half + (nb - 1) * size :] = medians[-1]
    return out


def check_pulse_times(t: ArrayLike, name: str = "head_0", *, first_index: int = 0) -> FloatArray:
    """Check one head's pulse times and return them as float64.

    A pulse train must be finite and strictly increasing, and every interval must be one pulse
    period: an interval ≥ 1.5 local periods means missing pulses (a dropout, a dirty scale), one
    ≤ 0.75 periods a spurious edge (noise, a bouncing comparator). Either would shift the line
    count of every later pulse, so they are refused rather than repaired silently.

    Parameters
    ----------
    t : array_like, s
        Pulse edge times of one head.
    name : str
        The column name, for messages.
    first_index : int
        Pulse number of ``t[0]`` in the whole train (a chunk of a stream), for messages.

    Returns
    -------
    ndarray, s

    Raises
    ------
    CaptureError
        NaN/inf, fewer than 3 pulses, non-increasing times, missing or extra pulses.
    """
    t = np.asarray(t, dtype=np.float64)
    if t.ndim != 1:
        raise CaptureError(f"column '{name}' must be 1-D pulse times, got shape {t.shape}.")
    bad = np.flatnonzero(~np.isfinite(t))
    if bad.size:
        raise CaptureError(
            f"column '{name}' has a NaN or inf at pulse {int(bad[0]) + first_index}."
        )
    if t.size < 3:
        raise CaptureError(f"column '{name}' has {t.size} pulse(s); a pulse train needs more.")
    dt = np.diff(t)
    bad = np.flatnonzero(~(dt > 0))
    if bad.size:
        i = int(bad[0])
        raise CaptureError(
            f"column '{name}' is not strictly increasing at pulse {i + 1 + first_index} "
            f"({t[i]:.9g} s then {t[i + 1]:.9g} s); pulse times must be sorted and distinct."
        )
    typical = float(np.median(dt[:TYPICAL_STEPS]))
    check_time_span(name, float(t[0]), float(t[-1]), typical, "pulse interval")
    ratio = _local_period(dt)
    np.divide(dt, ratio, out=ratio)  # in place: one record-long array less at the peak
    refuse_bad_intervals(name, ratio, t, first=first_index)
    return t


def refuse_bad_intervals(name: str, ratio: FloatArray, t: FloatArray, first: int = 0) -> None:
    """Refuse missing pulses (an interval ≥ MISSING_PULSE_RATIO local periods) or an extra edge
    (≤ EXTRA_PULSE_RATIO); ``ratio``: intervals over their local period, ``t``: the pulse times
    (s) around them, ``first``: the index of ``t[0]`` in the train (for messages)."""
    long_ = np.flatnonzero(ratio >= MISSING_PULSE_RATIO)
    if long_.size:
        i = int(long_[0])
        lost = max(1, round(float(ratio[i])) - 1)
        more = f" (and {long_.size - 1} more gaps)" if long_.size > 1 else ""
        raise CaptureError(
            f"column '{name}': about {lost} pulse(s) missing after pulse {first + i} at "
            f"t = {t[i]:.9g} s (an interval of {ratio[i]:.2f} pulse periods){more}; every pulse "
            "is needed to count the lines — cut the capture before the gap or re-record."
        )
    short = np.flatnonzero(ratio <= EXTRA_PULSE_RATIO)
    if short.size:
        i = int(short[0])
        raise CaptureError(
            f"column '{name}': an extra pulse edge at t = {t[i + 1]:.9g} s (an interval of "
            f"{ratio[i]:.2f} pulse periods); check the comparator or remove spurious edges."
        )


@dataclasses.dataclass(frozen=True)
class HeadPairing:
    """Every head paired with head 0 at the same instant.

    For head-0 pulse ``j`` (``first ≤ j < stop``, indices into head 0's pulse train) the pulse of
    head i that occurs nearest in time is ``j + index_offsets[i]``. The offsets are fixed over the
    capture (a head never "slips" a line), so the pairing does not flip when a head sits half a
    pitch away from a line.

    Attributes
    ----------
    index_offsets : ndarray of int, shape (n,)
        Pulse-index offset of each head against head 0 (0 for head 0).
    first, stop : int
        Head-0 pulse range covered by every head.
    delays_s : ndarray, shape (n, stop − first), s
        ``t_i[j + offset_i] − t_0[j]`` for the covered range (row 0 is zero).
    mean_times_s : ndarray, shape (stop − first,), s
        The head-averaged time of each paired set of pulses.
    notes : tuple of str
        What had to be left out (heads that start late or stop early).
    """

    index_offsets: NDArray[np.int64]
    first: int
    stop: int
    delays_s: FloatArray
    mean_times_s: FloatArray
    notes: tuple[str, ...] = ()

    @property
    def heads(self) -> int:
        return int(self.index_offsets.size)

    @property
    def pulses(self) -> int:
        return self.stop - self.first


def _sorted_search(times: FloatArray, queries: FloatArray) -> NDArray[np.int64]:
    """``np.searchsorted(times, queries)`` for increasing queries, in linear time.

    Two heads' pulses advance together, so query j's insertion point is nearly always the first
    one's plus j; that guess is kept where it satisfies times[k − 1] < query ≤ times[k] (the
    definition of the left insertion point) and searched for only elsewhere. Binary searches
    of every query cost O(log N) cache misses each, which grew faster than the record.
    """
    if queries.size == 0:
        return np.zeros(0, dtype=np.int64)
    first = int(np.searchsorted(times, queries[0]))
    k = np.arange(first, first + queries.size, dtype=np.int64)
    inside = k <= times.size
    kk = np.minimum(k, times.size)
    above = np.ones(queries.size, dtype=bool)  # times[k − 1] < query (vacuous at k = 0)
    above[kk > 0] = times[kk[kk > 0] - 1] < queries[kk > 0]
    below = np.ones(queries.size, dtype=bool)  # query ≤ times[k] (vacuous at k = N)
    below[kk < times.size] = queries[kk < times.size] <= times[kk[kk < times.size]]
    wrong = np.flatnonzero(~(inside & above & below))
    if wrong.size:
        k[wrong] = np.searchsorted(times, queries[wrong])
    return k


def _mode(values: NDArray[np.int64]) -> int:
    """The most frequent value (the smallest of equally frequent ones), as ``np.unique`` with
    ``return_counts`` finds it, by counting (linear time) when the values span a short range."""
    lo, hi = int(values.min()), int(values.max())
    if hi - lo <= 4 * values.size:
        return lo + int(np.argmax(np.bincount(values - lo)))
    found, counts = np.unique(values, return_counts=True)
    return int(found[np.argmax(counts)])


def pair_heads(heads: Sequence[FloatArray], names: Sequence[str] | None = None) -> HeadPairing:
    """Pair every head's pulses with head 0's by time (Kokuyama et al. 2015, §3: heads output simultaneously).

    Parameters
    ----------
    heads : sequence of ndarray, s
        Checked pulse trains (see :func:`check_pulse_times`), head 0 first.
    names : sequence of str, optional
        Column names for messages (default ``head_<i>``).

    Returns
    -------
    HeadPairing

    Raises
    ------
    CaptureError
        A head that never overlaps head 0 in time, or whose pulses cannot be paired with head 0's
        one to one (a different pulse rate: a different scale, or a miscounted head).
    """
    names = list(names) if names is not None else [f"head_{i}" for i in range(len(heads))]
    t0 = heads[0]
    period = float(np.median(np.diff(t0)))
    offsets = np.zeros(len(heads), dtype=np.int64)
    lo, hi = 0, t0.size
    for i in range(1, len(heads)):
        ti = heads[i]
        if ti[-1] < t0[0] or ti[0] > t0[-1]:
            raise CaptureError(
                f"column '{names[i]}' ({ti[0]:.6g}–{ti[-1]:.6g} s) does not overlap head_0 "
                f"({t0[0]:.6g}–{t0[-1]:.6g} s) in time; the heads must be recorded together."
            )
        # nearest pulse of head i for every head-0 pulse inside head i's record
        inside = np.flatnonzero((t0 >= ti[0]) & (t0 <= ti[-1]))
        k = np.clip(_sorted_search(ti, t0[inside]), 1, ti.size - 1)
        nearer_left = (t0[inside] - ti[k - 1]) < (ti[k] - t0[inside])
        k = k - nearer_left.astype(np.int64)
        offsets[i] = _mode(k - inside)
        lo = max(lo, -int(offsets[i]))
        hi = min(hi, ti.size - int(offsets[i]))
    if hi - lo < 2:
        raise CaptureError(
            "the heads overlap for fewer than 2 pulses of head_0; record all heads together."
        )
    j = np.arange(lo, hi)
    delays = np.empty((len(heads), j.size))
    for i, ti in enumerate(heads):
        delays[i] = ti[j + offsets[i]] - t0[j]
    worst = np.abs(delays).max(axis=1)
    bad = np.flatnonzero(worst > 0.75 * period)
    if bad.size:
        i = int(bad[0])
        jj = int(j[np.argmax(np.abs(delays[i]))])
        raise CaptureError(
            f"column '{names[i]}' drifts against head_0: near t = {t0[jj]:.9g} s its paired pulse is "
            f"{worst[i] / period:.2f} pulse periods away, so it has a different number of pulses "
            "per revolution or lost/extra pulses; every head must read the same scale."
        )
    spans = [(float(ti[0]), float(ti[-1]), ti.size) for ti in heads]
    notes = pairing_notes(names, spans, offsets, lo, hi)
    mean_times = t0[j] + delays.mean(axis=0)
    return HeadPairing(
        index_offsets=offsets,
        first=lo,
        stop=hi,
        delays_s=delays,
        mean_times_s=mean_times,
        notes=tuple(notes),
    )


def pairing_notes(
    names: Sequence[str],
    spans: Sequence[tuple[float, float, int]],
    offsets: NDArray[np.int64],
    lo: int,
    hi: int,
) -> list[str]:
    """What a pairing leaves out: heads (``spans``: first and last time, s, and pulse count of
    each) that start after head 0 or stop before it; ``lo``/``hi``: the paired head-0 range."""
    notes: list[str] = []
    size0 = spans[0][2]
    for i, (first, last, size) in enumerate(spans):
        if i and (-int(offsets[i]) == lo and lo > 0):
            notes.append(
                f"{names[i]} starts {lo} pulses after head_0 (at {first:.6g} s); the pulses of "
                "head_0 before it are not used for comparing heads."
            )
        if size - int(offsets[i]) == hi and hi < size0:
            notes.append(
                f"{names[i]} stops {size0 - hi} pulses before head_0 (at {last:.6g} s); the "
                "pulses of head_0 after it are not used for comparing heads."
            )
    return notes


def check_heads_not_copies(heads: Sequence[FloatArray], names: Sequence[str] | None = None) -> None:
    """Refuse a head whose pulse times are head 0's, shifted by one constant (to rounding).

    Heads at different places on the scale see different lines' errors and their own timing
    jitter, so their pulse times never differ from head 0's by an exact constant: such a column
    is head 0's data written twice, and a self-calibration from it would report a perfect scale.

    Parameters
    ----------
    heads : sequence of ndarray, s — checked pulse trains (:func:`check_pulse_times`), head 0 first.
    names : sequence of str, optional — column names for messages (default ``head_<i>``).

    Raises
    ------
    CaptureError
        Naming the head that copies head 0 and the time shift.
    """
    names = list(names) if names is not None else [f"head_{i}" for i in range(len(heads))]
    t0 = heads[0]
    for i in range(1, len(heads)):
        n = min(t0.size, heads[i].size)
        shift = heads[i][:n] - t0[:n]
        rounding = 8.0 * np.spacing(max(abs(float(t0[n - 1])), abs(float(heads[i][n - 1]))))
        if float(np.ptp(shift)) <= rounding:
            raise CaptureError(
                f"column '{names[i]}' is a copy of head_0 (every pulse time head_0's shifted by "
                f"{float(shift[0]):.6g} s): heads that are copies carry no information about the "
                "scale; check that each column holds its own head's pulse times."
            )


def pulse_angle_deg(
    count: ArrayLike,
    pulses_per_rev: int,
    deviation_arcsec: ArrayLike | None = None,
    *,
    line_offset: int = 0,
) -> FloatArray:
    """Angle (deg) at pulse numbers ``count`` of one head, optionally compensated.

    Uncompensated, pulse ``k`` is at ``k·360/m``. With the scale's deviation (INTERFACE.md
    ``selfcal`` convention: index 0 is the line head 0 saw at its first pulse) the true rotation
    from the head's pulse 0 is ``k·360/m + (d[(k + L) mod m] − d[L mod m])/3600``, where
    ``L = line_offset`` is the deviation index of the head's pulse 0.

    Parameters
    ----------
    count : array_like of int
        Pulse numbers from the head's first pulse.
    pulses_per_rev : int
        m, pulses per revolution.
    deviation_arcsec : array_like, shape (m,), arcsec, optional
        Self-calibrated deviation of the scale.
    line_offset : int
        Deviation index of the head's first pulse.

    Returns
    -------
    ndarray, deg

    References
    ----------
    Kokuyama W., Watanabe T., Nozato H., Ota A., "Development of angular velocity calibration
    facility using self-calibratable rotary encoder", §3, s_i(k) = kΔθ + 360i/n + a_i(k).
    """
    k = np.asarray(count, dtype=np.int64)
    angle = np.asarray(k * (360.0 / pulses_per_rev), dtype=np.float64)
    if deviation_arcsec is None:
        return angle
    d = np.asarray(deviation_arcsec, dtype=np.float64)
    if d.shape != (pulses_per_rev,):
        raise ConfigError(
            f"the deviation has {d.size} values but pulses_per_rev is {pulses_per_rev}; they must "
            "match (was the self-calibration made with another --pulses-per-rev?)."
        )
    idx = (k + line_offset) % pulses_per_rev
    return np.asarray(angle + (d[idx] - d[line_offset % pulses_per_rev]) / 3600.0)


def pulse_rate(
    times_s: ArrayLike,
    angle_deg: ArrayLike,
    *,
    average: int = 1,
) -> tuple[FloatArray, FloatArray]:
    """Angular velocity by the time-difference method, averaged over ``average`` intervals.

    The rate between two successive pulses is their angle difference over their time difference;
    ``average`` consecutive rates are then averaged (Kokuyama et al. (2015) average 10 to suppress electric
    noise), in non-overlapping blocks.

    Parameters
    ----------
    times_s : array_like, s
        Pulse times of one head (or the head-averaged times).
    angle_deg : array_like, deg
        Angle at each pulse (from :func:`pulse_angle_deg`).
    average : int
        Intervals per averaged rate point (≥ 1).

    Returns
    -------
    time_s : ndarray, s
        Mean time of each block of intervals (the centre of each interval, averaged).
    rate_deg_s : ndarray, deg/s

    References
    ----------
    Kokuyama et al. (2015), §5: "Taking time difference between adjacent two pulses, angular
    velocity between the two pulses is obtained. Then … 10 straight points of data are averaged."
    """
    t = np.asarray(times_s, dtype=np.float64)
    a = np.asarray(angle_deg, dtype=np.float64)
    if isinstance(average, bool) or not isinstance(average, int | np.integer) or average < 1:
        raise ConfigError(f"average must be a whole number of intervals ≥ 1, got {average!r}.")
    size = int(average)
    intervals = max(t.size - 1, 0)
    if a.shape != t.shape:
        raise ConfigError(f"{a.size} angles for {t.size} pulse times; give one angle per pulse.")
    blocks = intervals // size
    if blocks < 1:
        raise CaptureError(
            f"{intervals} pulse intervals cannot make one average of {average}; lower --average."
        )
    # the same arithmetic per block as on the whole record (the same bits), a few thousand
    # blocks at a time: no record-long temporaries
    time_s, rate_deg_s = np.empty(blocks), np.empty(blocks)
    step = max(1, _RATE_CHUNK // size)
    for b0 in range(0, blocks, step):
        b1 = min(b0 + step, blocks)
        tt, aa = t[b0 * size : b1 * size + 1], a[b0 * size : b1 * size + 1]
        dt = np.diff(tt)
        rate_deg_s[b0:b1] = (np.diff(aa) / dt).reshape(b1 - b0, size).mean(axis=1)
        time_s[b0:b1] = (tt[:-1] + 0.5 * dt).reshape(b1 - b0, size).mean(axis=1)
    return time_s, rate_deg_s


def whole_revolution_rate(
    times_s: FloatArray, pulses_per_rev: int
) -> tuple[float, int] | tuple[None, int]:
    """Mean rate (deg/s) over the whole revolutions of a pulse train, and their number.

    Over a whole revolution the scale's deviation cancels exactly (m pitches are 360°), so the
    mean rate needs no calibration: 360·R over the time of R revolutions.
    """
    revs = (times_s.size - 1) // pulses_per_rev
    if revs < 1:
        return None, 0
    span = float(times_s[revs * pulses_per_rev] - times_s[0])
    return 360.0 * revs / span, revs
