"""Noise terms of a gyro from a rate record read in chunks (bounded memory; IEEE Std 952 Annex C).

:func:`gyro_noise_chunks` is :func:`rotacal.gyro.noise.gyro_noise` for a record too long to hold:
it takes the chunks of the rate column (and of its time column) in order, checks each as the
in-memory path checks the whole — NaN/inf and out-of-range samples, a constant record, time
stamps that are not increasing, have a gap or are not at a constant rate, clipping (the rails
found with carried state, :class:`~rotacal.signal.clipping.RailDetector`) — and feeds the rate to
:class:`~rotacal.signal.allan_stream.ChunkedAdev`. The sampling rate of a time column is its mean
step, known once the column has been read: the same number the in-memory path takes. The noise
terms, their budgets and warnings come from the deviation as in memory
(:func:`~rotacal.gyro.noise.noise_of_deviation`), so the result equals ``gyro_noise`` of the whole
record at the same τ grid to ≤ 1e-9 relative (tested). The τ grid is octave or decade: every τ,
or the log grid, needs the whole record.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable, Mapping
from typing import Any

import numpy as np

from rotacal.errors import CaptureError
from rotacal.gyro.noise import GyroNoise, _check_fs_hz, _constant_rate, noise_of_deviation
from rotacal.signal._checks import MAX_GAP, TYPICAL_STEPS, gap_error, order_error
from rotacal.signal._values import check_time_span
from rotacal.signal.allan_stream import DEFAULT_HISTORY, ChunkedAdev
from rotacal.signal.clipping import RailDetector, check_clipping
from rotacal.uncertainty.specs import InstrumentSpecs

__all__ = ["NoiseChecks", "gyro_noise_chunks"]


class _TimeSteps:
    """The checks of :func:`rotacal.signal.check_sampling` and the constant-rate test of the
    in-memory path on a time column fed in chunks: order and gaps are refused as soon as seen
    (sample numbers from the start), the span and the rate at the end."""

    def __init__(self, name: str = "time_s") -> None:
        self.name = name
        self.count = 0
        self.first = math.nan
        self.last = math.nan
        self.typical: float | None = None  # median of the first TYPICAL_STEPS steps
        self.min_step = math.inf
        self.max_step = -math.inf

    def add(self, t: np.ndarray) -> None:
        if not t.size:
            return
        joined = t if self.count == 0 else np.concatenate(([self.last], t))
        base = self.count - (self.count > 0)  # sample number of joined[0]
        steps = np.diff(joined)
        if steps.size:
            bad = np.flatnonzero(~(steps > 0))
            if bad.size:
                i = int(bad[0])
                raise order_error(self.name, base + i + 1, float(joined[i]), float(joined[i + 1]))
            if self.typical is None:
                self.typical = float(np.median(steps[:TYPICAL_STEPS]))
            gaps = np.flatnonzero(steps > MAX_GAP * self.typical)
            if gaps.size:
                i = int(gaps[0])
                raise gap_error(self.name, base + i + 1, float(steps[i]), self.typical)
            self.min_step = min(self.min_step, float(steps.min()))
            self.max_step = max(self.max_step, float(steps.max()))
        if self.count == 0:
            self.first = float(t[0])
        self.last = float(t[-1])
        self.count += t.size

    def resume(self, start: int, previous: float, typical: float) -> None:
        """Start at row ``start`` (> 0) after the time stamp ``previous`` (s), with the typical
        step the rows before set: the state a single pass has there, but for the extreme steps
        (those of this block and of the step into it) and the first time stamp."""
        self.count, self.last, self.typical = start, previous, typical

    def merge(self, later: _TimeSteps) -> None:
        """Fold in the checks of the rows that follow (made with :meth:`resume` at this one's
        end): the state of one pass over both."""
        if self.count == 0:
            self.first, self.typical = later.first, later.typical
        self.count, self.last = later.count, later.last
        self.min_step = min(self.min_step, later.min_step)
        self.max_step = max(self.max_step, later.max_step)

    def rate(self, n: int, fs_hz: float | None) -> float:
        """The sampling rate (Hz), as the in-memory path computes it."""
        if self.count != n:
            raise CaptureError(
                f"{self.name} has {self.count} values, the rate column {n}; they must match."
            )
        if n < 2:
            raise CaptureError(f"the record holds {n} sample(s): too short for an Allan deviation.")
        assert self.typical is not None
        check_time_span(self.name, self.first, self.last, self.typical)
        return _constant_rate(self.first, self.last, n, self.min_step, self.max_step, fs_hz)


class NoiseChecks:
    """What :func:`gyro_noise_chunks` checks of the chunks besides the deviation itself: the time
    column (order, gaps, constant rate; the sampling rate), and the rails of clipping, with
    carried state. ``add(chunk)`` in row order, then ``finish(n)`` with the rate samples seen.
    """

    def __init__(self, column: str, fs_hz: float | None) -> None:
        _check_fs_hz(fs_hz)
        self.column, self.fs_hz = column, fs_hz
        self.times: _TimeSteps | None = None
        self.rails = RailDetector(column)

    @classmethod
    def block(
        cls,
        column: str,
        fs_hz: float | None,
        *,
        rows: int,
        start: int,
        previous: float | None = None,
        typical: float | None = None,
    ) -> NoiseChecks:
        """The checks of one block of a record split over several processes: rows ``start`` on
        of a column of ``rows`` rows; with a time column, ``previous`` is the time stamp before
        the block (s; none for the first) and ``typical`` the typical step (s) the first block
        sets. Blocks merge in row order (:meth:`merge`) into the checks of one pass."""
        checks = cls(column, fs_hz)
        checks.rails = RailDetector(column, rows, start=start)
        if previous is not None and typical is not None:
            checks.times = _TimeSteps()
            checks.times.resume(start, previous, typical)
        return checks

    def merge(self, later: NoiseChecks) -> None:
        """Fold in the checks of the block that follows (see :meth:`block`)."""
        if self.times is not None and later.times is not None:
            self.times.merge(later.times)
        self.rails.merge(later.rails)

    def add(self, chunk: Mapping[str, Any]) -> np.ndarray:
        """Check the next rows (``column`` and ``time_s`` when given); the rate as float64."""
        rate = np.asarray(chunk[self.column], dtype=np.float64)
        t = chunk.get("time_s")
        if self.times is None and t is not None:
            self.times = _TimeSteps()
        if self.times is not None:
            if t is None or np.shape(t) != rate.shape:
                raise CaptureError(
                    f"time_s and {self.column} must come in chunks of equal lengths; got "
                    f"{None if t is None else np.shape(t)} and {rate.shape}."
                )
            self.times.add(np.asarray(t, dtype=np.float64))
        self.rails.add(rate)
        return rate

    def finish(self, n: int, allow_clipped: bool) -> tuple[float, tuple[str, ...]]:
        """The sampling rate (Hz) and the clipping warnings, once ``n`` rate samples were fed."""
        if self.times is not None:
            fs = self.times.rate(n, self.fs_hz)
        elif self.fs_hz is None:
            raise CaptureError("give the sampling rate (fs_hz, --fs-hz) or a time_s column.")
        else:
            fs = float(self.fs_hz)
        clipped = check_clipping({self.column: self.rails.result()}, allow_clipped=allow_clipped)
        return fs, tuple(clipped)


def gyro_noise_chunks(
    chunks: Iterable[Mapping[str, Any]],
    *,
    column: str = "rate_deg_s",
    fs_hz: float | None = None,
    unit: str = "deg/s",
    taus: str = "octave",
    specs: InstrumentSpecs | None = None,
    allow_clipped: bool = False,
    history: int = DEFAULT_HISTORY,
    progress: Callable[[int], None] | None = None,
) -> GyroNoise:
    """Overlapping Allan deviation and IEEE 952 noise terms of a rate record read in chunks.

    Parameters
    ----------
    chunks : iterable of mappings
        Consecutive row ranges of the capture: ``column`` (rate, in ``unit``) and, unless
        ``fs_hz`` is given, ``time_s`` (s), of equal lengths (e.g. from
        :func:`rotacal.io.iter_capture_chunks`).
    column : str
        The rate column's name (also for messages).
    fs_hz : float, Hz, optional
        Sampling rate; when a ``time_s`` column comes too, it must agree (0.1 %).
    unit, specs, allow_clipped
        As :func:`rotacal.gyro.noise.gyro_noise`.
    taus : "octave" or "decade"
        The τ grid (every τ and the log grid need the whole record).
    history : int
        Phase values carried between chunks (see :class:`~rotacal.signal.allan_stream.ChunkedAdev`).
    progress : callable, optional
        Called with the samples done so far (2·N in all: the reading pass, then the long τ).

    Returns
    -------
    GyroNoise
        As ``gyro_noise(whole, taus=taus)`` to ≤ 1e-9 relative.

    Raises
    ------
    CaptureError, ConfigError
        As :func:`rotacal.gyro.noise.gyro_noise` (the same checks, the same messages).

    References
    ----------
    IEEE Std 952-1997, Annex C; NIST SP 1065 (Riley 2008), eq. (11) and §5.3.
    """
    checks = NoiseChecks(column, fs_hz)
    with ChunkedAdev(taus=taus, history=history, column=column, progress=progress) as acc:
        for chunk in chunks:
            acc.add(checks.add(chunk))
        fs, clipped = checks.finish(acc.n_samples, allow_clipped)
        adev = acc.result(fs=fs)
    return noise_of_deviation(adev, unit=unit, column=column, specs=specs, warnings=clipped)
