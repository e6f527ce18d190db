"""Statistics of capture columns fed in chunks, with carried state (whole-array NumPy per chunk).

:class:`ColumnStats` keeps what :class:`~rotacal.inspect.result.ColumnSummary` reports of one
column; :class:`TimeStats` the sampling of the time column (interval, jitter, gaps). Feeding a
column whole or in any chunking gives the same numbers, except the mean interval and jitter,
whose sums may differ in the last bits.
"""

from __future__ import annotations

import math

import numpy as np

from rotacal.signal._checks import MAX_GAP, TYPICAL_STEPS
from rotacal.signal.clipping import RailDetector

from .result import ColumnSummary, Gap

#: Gaps listed one by one in a result (every one is counted).
MAX_LISTED_GAPS = 100


class ColumnStats:
    """Samples, range, NaN/inf, repeats, smallest step, monotony and rails of one column.

    Parameters
    ----------
    name : str — the column's name (for the clipping detector's messages).
    """

    def __init__(self, name: str) -> None:
        self.name = name
        self.samples = 0
        self.nan = 0
        self.inf = 0
        self.first_nonfinite: int | None = None
        self.lo = math.inf
        self.hi = -math.inf
        self.repeated = 0
        self.smallest_step = math.inf
        self.increasing = True
        self.integral = True  # every finite value a whole number (a counter, raw ADC counts)
        self.last = math.nan  # the previous chunk's last sample
        self.rails = RailDetector(name)

    def add(self, values: np.ndarray) -> None:
        """Feed the next samples (1-D float64, in row order)."""
        x = values
        if x.size == 0:
            return
        finite = np.isfinite(x)
        n_finite = int(np.count_nonzero(finite))
        if n_finite < x.size:
            n_nan = int(np.count_nonzero(np.isnan(x)))
            self.nan += n_nan
            self.inf += x.size - n_finite - n_nan
            if self.first_nonfinite is None:
                self.first_nonfinite = self.samples + int(np.argmin(finite))
            self.increasing = False
        if n_finite:
            xf = x if n_finite == x.size else x[finite]
            self.lo = min(self.lo, float(xf.min()))
            self.hi = max(self.hi, float(xf.max()))
            if self.integral:
                self.integral = bool(np.all(xf == np.trunc(xf)))
        # steps between consecutive samples, the first one from the previous chunk's last
        steps = np.diff(x, prepend=self.last)
        self.repeated += int(np.count_nonzero(steps == 0.0))
        size = np.abs(steps)  # NaN steps fail "> 0" and are left out
        self.smallest_step = min(
            self.smallest_step, float(np.min(size, where=size > 0.0, initial=math.inf))
        )
        if self.increasing:
            rising = steps[1:] > 0.0 if self.samples == 0 else steps > 0.0
            self.increasing = bool(rising.all())
        self.rails.add(x)
        self.samples += x.size
        self.last = float(x[-1])

    def summary(self) -> ColumnSummary:
        clip = self.rails.result()
        finite = self.lo <= self.hi
        return ColumnSummary(
            samples=self.samples,
            min=self.lo if finite else None,
            max=self.hi if finite else None,
            nan=self.nan,
            inf=self.inf,
            repeated_fraction=self.repeated / self.samples if self.samples else 0.0,
            clipped_fraction=clip.share if clip is not None else 0.0,
            smallest_step=self.smallest_step if math.isfinite(self.smallest_step) else None,
            increasing=self.increasing and self.samples > 1,
            first_nonfinite_row=self.first_nonfinite,
        )

    def clipping_note(self) -> str | None:
        """The clipping detector's description of the rails, when there are any."""
        clip = self.rails.result()
        return None if clip is None else clip.describe()


class TimeStats:
    """Sampling of a time column (s) fed in chunks: usual interval, jitter, gaps, backward steps.

    The usual interval is the median of the first :data:`TYPICAL_STEPS` forward steps; a step
    longer than :data:`MAX_GAP` of them is a gap (the rule of every analysis,
    :func:`rotacal.signal._checks.check_sampling`). The mean interval and its standard deviation
    (the jitter) are taken over the other forward steps, as sums of deviations from the usual
    interval (no cancellation for long records).
    """

    def __init__(self) -> None:
        self.rows = 0
        self.first = math.nan
        self.last = math.nan  # the last finite time stamp so far
        self.typical: float | None = None
        self.count = 0
        self.sum_d = 0.0
        self.sum_d2 = 0.0
        self.backward = 0
        self.first_backward: int | None = None
        self.gaps: list[tuple[float, float]] = []
        self.gap_count = 0

    def add(self, t: np.ndarray) -> None:
        """Feed the next time stamps (1-D float64, s)."""
        base = self.rows
        self.rows += t.size
        finite = np.isfinite(t)
        all_finite = bool(finite.all())
        tf = t if all_finite else t[finite]
        if tf.size == 0:
            return
        if math.isnan(self.first):
            self.first = float(tf[0])
            tf_prev, skip = tf, 1  # step k ends at finite sample k + 1
        else:
            tf_prev, skip = np.concatenate(([self.last], tf)), 0
        steps = np.diff(tf_prev)
        self.last = float(tf[-1])
        if steps.size == 0:
            return
        back = steps <= 0.0
        if back.any():
            if self.first_backward is None:
                k = int(np.argmax(back)) + skip  # index among the finite samples of the chunk
                self.first_backward = base + (k if all_finite else int(np.flatnonzero(finite)[k]))
            self.backward += int(np.count_nonzero(back))
        forward = steps[~back]
        if self.typical is None:
            if forward.size == 0:
                return
            self.typical = float(np.median(forward[:TYPICAL_STEPS]))
        is_gap = steps > MAX_GAP * self.typical
        if is_gap.any():
            where = np.flatnonzero(is_gap)
            self.gap_count += where.size
            room = MAX_LISTED_GAPS - len(self.gaps)
            for i in where[:room]:
                self.gaps.append((float(tf_prev[i]), float(tf_prev[i + 1])))
        usual = steps[~back & ~is_gap] - self.typical
        self.count += usual.size
        self.sum_d += float(usual.sum())
        self.sum_d2 += float(np.dot(usual, usual))

    @property
    def interval(self) -> float | None:
        """Mean usual interval (s)."""
        if self.typical is None or self.count == 0:
            return None
        return self.typical + self.sum_d / self.count

    @property
    def jitter(self) -> float | None:
        """Standard deviation of the usual intervals (s; population form, divided by N)."""
        if self.typical is None or self.count == 0:
            return None
        mean = self.sum_d / self.count
        return math.sqrt(max(self.sum_d2 / self.count - mean * mean, 0.0))

    @property
    def duration(self) -> float | None:
        return None if math.isnan(self.first) else self.last - self.first

    def gap_list(self) -> tuple[Gap, ...]:
        interval = self.interval
        return tuple(
            Gap(
                start_s=a,
                end_s=b,
                missing_samples=max(round((b - a) / interval) - 1, 0) if interval else 0,
            )
            for a, b in self.gaps
        )
