"""Rate from angle or counter readings: the readings reduced to the pulse times of virtual marks.

The pulse-timing pipeline (:func:`~rotacal.table.rate.calibrate_rate`, Kokuyama et al. 2015)
takes the times at which equally spaced marks of a scale pass a head. An angle readout (or an
up/down counter, unwrapped by :mod:`rotacal.signal.counter`) gives the angle θ at sample times
instead; this module turns it into the times at which θ crosses the marks ``k·360/M`` (M =
``pulses_per_rev``), so that every rate output — mean rate, bias, stability, s(φ), and the rate
over angle windows — works on it unchanged.

Crossing times, streaming with the last sample carried: the running maximum of ±θ (the turning
direction is the one with the longer travel) is interpolated linearly between the two samples
that bracket each mark (first passage). Marks are counted from the first reading.

Error bound of the interpolation. Between two samples Δt apart, linear interpolation of a θ
with |θ''| ≤ α misses θ by at most α·Δt²/8, so a crossing time is off by at most
``δt ≤ α·Δt²/(8·ω)`` at the local rate ω (a noise-free, unquantised angle). A readout quantised
to q (a counter: q = 360/N) places each crossing where the true angle is the mark plus an error
within a width of q (truncation: [0, q); rounding: [−q/2, q/2)), a time error within a width
``q/ω``; the rate over L marks (Δφ = L·360/M) is then off by at most ``2·(α·Δt²/8 + q)/Δφ``
relative. Where those errors fall depends on the sampling's phase against the marks: when the
sampling is commensurate with the rotation they repeat every revolution, and no Type A estimate
from the crossing times (the timing jitter, the spread of the revolutions) sees them. So the
resolution enters every uncertainty of the result as a Type B input (JCGM 100:2008 F.2.2.1
and §4.3.7: each end of a rate's window within a width q, so its angle within ±q, rectangular,
u = q/√3; see :func:`rotacal.table.rate_budgets._resolution_input`), named "readout
resolution" in the budgets.
Noise σ on θ moves a first passage by about σ/ω (in the Type A jitter).
:func:`crossing_error_bound_s` states the interpolation bound; the test checks the crossings of
a twin against the true angle's.

The table must turn one way: a fall of θ below its running maximum by more than
:data:`BACKWARD_MARKS` mark spacings (and 0.1°) is refused (the table turned back; a rate over
windows of rotation is not defined there).

References
----------
Kokuyama W., Watanabe T., Nozato H., Ota A. (2015/2016), angular velocity calibration system with
a self-calibratable rotary encoder (seed 004), §3–§5 (rate from pulse timing);
linear-interpolation error bound: e.g. Atkinson, An Introduction to Numerical Analysis (1989),
§3.2, eq. (3.2.11) with n = 1.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Iterator, Mapping
from typing import Any

import numpy as np

from rotacal.errors import CaptureError, ConfigError
from rotacal.results import with_warnings
from rotacal.signal.readings import CleanReadings, ReadingChunks, counter_register

__all__ = [
    "BACKWARD_MARKS",
    "MarkCrossings",
    "MarkTimes",
    "calibrate_rate_from_angle",
    "calibrate_rate_from_counts",
    "calibrate_rate_from_marks",
    "crossing_error_bound_s",
    "mark_times_from_chunks",
    "readout_quantum",
]

#: A fall below the running maximum by more than this many mark spacings is a reversal.
BACKWARD_MARKS = 5
_BACKWARD_MIN_DEG = 0.1
#: Readings looked at, and quanta a sample the table may step, to find an angle readout's quantum.
_QUANTUM_READINGS = 1 << 16
_MAX_STEP_QUANTA = 256


def readout_quantum(angle_deg: np.ndarray) -> float | None:
    """The quantum q (deg) of a quantised angle readout from its first readings, or None.

    A turning table steps several quanta a sample, so the smallest step between its distinct
    readings may be a multiple of q (:func:`~rotacal.table.motion_angle.angle_quantum` then finds
    none, or that multiple). q is the largest ``smallest step / k`` (k = 1 … 256) of which every
    reading's offset from the least is a whole multiple, to 10⁻³·q; None when no k fits (a
    continuous readout, or one stepping more than 256 quanta a sample).
    """
    a = np.unique(np.asarray(angle_deg[:_QUANTUM_READINGS], dtype=np.float64))
    if a.size < 3:
        return None
    smallest = float(np.min(np.diff(a)))
    offset = a - a[0]
    for k in range(1, _MAX_STEP_QUANTA + 1):
        n = offset * (k / smallest)
        if float(np.max(np.abs(n - np.rint(n)))) <= 1e-3:
            return smallest / k
    return None


def crossing_error_bound_s(
    max_acceleration_deg_s2: float, sample_interval_s: float, rate_deg_s: float
) -> float:
    """Bound (s) of a linearly interpolated crossing time: α·Δt²/(8·|ω|) (module docstring)."""
    return abs(max_acceleration_deg_s2) * sample_interval_s**2 / (8.0 * abs(rate_deg_s))


class _Direction:
    """First-passage crossings of one direction (x = ±θ), carried from chunk to chunk."""

    def __init__(self, spacing: float) -> None:
        self.spacing = spacing
        self.last: tuple[float, float] | None = None  # (t, running max)
        self.times: list[np.ndarray] = []
        self.back = 0.0  # largest fall below the running maximum (deg)

    def feed(self, t: np.ndarray, x: np.ndarray) -> None:
        if self.last is None:
            self.last = (float(t[0]), float(x[0]))
        t_prev, cm_prev = self.last
        cm = np.maximum.accumulate(x)
        np.maximum(cm, cm_prev, out=cm)
        self.back = max(self.back, float(np.max(cm - x)))
        k = np.floor(cm * (1.0 / self.spacing)).astype(np.int64)
        k_prev = math.floor(cm_prev * (1.0 / self.spacing))
        crossed = np.diff(k, prepend=k_prev)
        at = np.flatnonzero(crossed)  # samples that passed one mark or more
        if at.size:
            many = crossed[at]
            interval = np.repeat(at, many)
            first = np.repeat(np.cumsum(many) - many, many)
            k_before = np.where(at > 0, k[at - 1], k_prev)
            mark = (
                np.repeat(k_before, many) + 1 + (np.arange(interval.size) - first)
            ) * self.spacing
            t_lo = np.where(interval > 0, t[interval - 1], t_prev)
            c_lo = np.where(interval > 0, cm[interval - 1], cm_prev)
            c_hi, t_hi = cm[interval], t[interval]
            self.times.append(t_lo + (mark - c_lo) / (c_hi - c_lo) * (t_hi - t_lo))
        self.last = (float(t[-1]), float(cm[-1]))

    def count(self) -> int:
        return sum(a.size for a in self.times)


@dataclasses.dataclass(frozen=True)
class MarkTimes:
    """What :func:`mark_times_from_chunks` found.

    Attributes
    ----------
    times : array, s — the crossing times of the marks, in order.
    direction : +1 or −1 — the way the table turned.
    notes : list of str — for the rate result.
    faults : DaqFaults — the DAQ's gaps, duplicated times and repeated rows.
    resolution_deg : float or None — the readout's quantum (a count: 360/N; an angle readout:
        :func:`readout_quantum` of the first chunk; None: continuous).
    """

    times: np.ndarray
    direction: int
    notes: list[str]
    faults: Any
    resolution_deg: float | None


@dataclasses.dataclass
class MarkCrossings:
    """Times at which θ crosses the marks ``k·360/M`` from its first reading, chunk by chunk.

    Both directions are followed; :meth:`result` keeps the one the table turned (more marks).
    """

    marks_per_rev: int
    _origin: float | None = dataclasses.field(default=None, init=False, repr=False)

    def __post_init__(self) -> None:
        if isinstance(self.marks_per_rev, bool) or int(self.marks_per_rev) != self.marks_per_rev:
            raise ConfigError(f"--pulses-per-rev must be a whole number, got {self.marks_per_rev}")
        if self.marks_per_rev < 1:
            raise ConfigError(f"--pulses-per-rev must be at least 1, got {self.marks_per_rev}")
        spacing = 360.0 / float(self.marks_per_rev)
        self._up = _Direction(spacing)
        self._down = _Direction(spacing)

    def feed(self, t: np.ndarray, angle_deg: np.ndarray) -> None:
        """The next samples: times (s) and angles (deg)."""
        if t.size == 0:
            return
        if self._origin is None:
            self._origin = float(angle_deg[0])
        x = np.asarray(angle_deg, dtype=np.float64) - self._origin
        self._up.feed(t, x)
        self._down.feed(t, -x)

    def result(self) -> tuple[np.ndarray, int]:
        """(crossing times in s, +1 or −1 for the direction turned)."""
        way = self._up if self._up.count() >= self._down.count() else self._down
        spacing = way.spacing
        limit = max(BACKWARD_MARKS * spacing, _BACKWARD_MIN_DEG)
        if way.back > limit:
            raise CaptureError(
                f"the angle turns back by {way.back:.4g}° (more than {limit:.3g}°): a rate over "
                "marks needs the table turning one way; cut the record where it reverses"
            )
        times = np.concatenate(way.times) if way.times else np.empty(0)
        return times, 1 if way is self._up else -1


def mark_times_from_chunks(
    chunks: ReadingChunks,
    *,
    pulses_per_rev: int,
    counts_per_rev: float | None = None,
    counter_bits: int | None = None,
    signed: bool | None = None,
) -> MarkTimes:
    """One streaming pass over the cleaned readings (:class:`~rotacal.signal.readings.CleanReadings`:
    DAQ faults, a counter unwrapped) to the crossing times of the marks.

    Parameters
    ----------
    chunks : callable — each call a fresh pass of ``(time_s, reading)`` chunks (s; deg or counts).
    pulses_per_rev : int — M, virtual marks per revolution.
    counts_per_rev : float, optional — N; given: the readings are counts (else angles in deg).
    counter_bits, signed : the register (:func:`~rotacal.signal.readings.counter_register`: one
        more pass when something is to be inferred from the readings' range).

    Returns
    -------
    MarkTimes
    """
    if counts_per_rev is not None:
        if not (math.isfinite(counts_per_rev) and counts_per_rev > 0):
            raise ConfigError(f"--counts-per-rev must be positive, got {counts_per_rev}")
        counter_bits, signed = counter_register(chunks(), counter_bits, signed)
    clean = CleanReadings(chunks, counts_per_rev, counter_bits, signed)
    marks = MarkCrossings(int(pulses_per_rev))
    quantum: float | None = None if counts_per_rev is None else 360.0 / counts_per_rev
    for off, t, x in clean():
        if off == 0 and counts_per_rev is None:
            quantum = readout_quantum(x)
        marks.feed(t, x)
    assert clean.faults is not None
    times, direction = marks.result()
    notes = [
        f"pulse times: the angle's crossings of {pulses_per_rev} marks per revolution "
        f"({360.0 / pulses_per_rev:.6g}° apart), linearly interpolated between samples"
    ]
    if clean.register is not None:
        bits, is_signed = clean.register
        notes.append(
            f"count unwrapped in a {bits}-bit {'signed' if is_signed else 'unsigned'} register"
        )
    if direction < 0:
        notes.append("the table turns backwards: the rate is stated as its magnitude")
    return MarkTimes(times, direction, notes, clean.faults, quantum)


def calibrate_rate_from_marks(marks: MarkTimes, *, allow_gaps: bool = False, **rate_kw: Any) -> Any:
    """:func:`~rotacal.table.rate.calibrate_rate` of the crossing times of
    :func:`mark_times_from_chunks` (its notes, the resolution's bound and the DAQ faults added
    to the result).

    ``rate_kw``: the other arguments of ``calibrate_rate`` (``pulses_per_rev`` = M, ``average``,
    ``set_rate_deg_s`` in deg/s, ``specs``, …); ``compensate`` defaults to False (one virtual
    head: nothing to compensate). More than 1 % faulty samples is refused unless ``allow_gaps``.
    """
    from rotacal.table.rate import calibrate_rate

    times, notes = marks.times, list(marks.notes)
    marks.faults.check(allow_gaps)
    if times.size < 3:
        raise CaptureError(
            f"the angle crosses only {times.size} mark(s) of {rate_kw['pulses_per_rev']} per "
            "revolution: record longer, or raise --pulses-per-rev"
        )
    rate_kw.setdefault("compensate", False)
    # a continuous readout: 0 (virtual marks, no quantum)
    result = calibrate_rate([times], readout_resolution_deg=marks.resolution_deg or 0.0, **rate_kw)
    if marks.resolution_deg is not None:
        notes.append(_resolution_note(marks.resolution_deg, times, rate_kw))
    result = dataclasses.replace(result, notes=[*result.notes, *notes])
    return with_warnings(result, marks.faults.warnings())


def _resolution_note(q: float, times: np.ndarray, rate_kw: Mapping[str, Any]) -> str:
    """The readout resolution's bound on a crossing time and on a rate point (module docstring)."""
    spacing = 360.0 / float(rate_kw["pulses_per_rev"])
    omega = spacing * (times.size - 1) / float(times[-1] - times[0])
    window = int(rate_kw.get("average", 10)) * spacing
    return (
        f"readout resolution {q:.6g}°: each crossing time within {q / omega:.3g} s "
        f"(q/ω at {omega:.6g} °/s), a rate point over {window:.6g}° within "
        f"{200.0 * q / window:.3g} % and the mean rate within "
        f"{200.0 * q / (omega * float(times[-1] - times[0])):.3g} % (bounds); in the budgets as "
        "the Type B input 'readout resolution', each rate's angle within ±q, rectangular "
        "(JCGM 100 F.2.2.1, §4.3.7); s(φ) holds it too, of the order of q/φ, not in its u"
    )


def _rate(
    chunks: ReadingChunks, allow_gaps: bool, reading: Mapping[str, Any], **rate_kw: Any
) -> Any:
    marks = mark_times_from_chunks(chunks, pulses_per_rev=rate_kw["pulses_per_rev"], **reading)
    return calibrate_rate_from_marks(marks, allow_gaps=allow_gaps, **rate_kw)


def _pieces(t: Any, y: Any, rows: int = 1 << 20) -> ReadingChunks:
    t = np.asarray(t)
    y = np.asarray(y)
    if t.ndim != 1 or t.shape != y.shape:
        raise CaptureError("time_s and the readings must be 1-D arrays of one length")

    def chunks() -> Iterator[tuple[np.ndarray, np.ndarray]]:
        for s in range(0, t.size, rows):
            yield t[s : s + rows], y[s : s + rows]

    return chunks


def calibrate_rate_from_angle(
    t: Any, angle_deg: Any, *, pulses_per_rev: int, allow_gaps: bool = False, **rate_kw: Any
) -> Any:
    """:func:`~rotacal.table.rate.calibrate_rate` of an angle readout (module docstring).

    Parameters
    ----------
    t : array, s; angle_deg : array, deg.
    pulses_per_rev : int — M, virtual marks per revolution the angle is timed at.
    allow_gaps : bool — analyse more than 1 % faulty samples anyway.
    **rate_kw : the other arguments of ``calibrate_rate`` (``average``, ``set_rate_deg_s``,
        ``specs``, …); ``compensate`` defaults to False (one virtual head: nothing to compensate).

    Returns
    -------
    RateResult — with the notes and warnings of the reduction.
    """
    return _rate(_pieces(t, angle_deg), allow_gaps, {}, pulses_per_rev=pulses_per_rev, **rate_kw)


def calibrate_rate_from_counts(
    t: Any,
    count: Any,
    *,
    counts_per_rev: float,
    pulses_per_rev: int,
    counter_bits: int | None = None,
    signed: bool | None = None,
    allow_gaps: bool = False,
    **rate_kw: Any,
) -> Any:
    """:func:`calibrate_rate_from_angle` of an up/down counter (θ = 360·count/N, unwrapped)."""
    reading = {"counts_per_rev": counts_per_rev, "counter_bits": counter_bits, "signed": signed}
    return _rate(_pieces(t, count), allow_gaps, reading, pulses_per_rev=pulses_per_rev, **rate_kw)
