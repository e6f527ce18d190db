"""The first pass of every chunked motion calibration: the capture's checks, state carried (private).

:func:`check_pass` reads the capture once and gathers, with the state carried from chunk to
chunk, what the in-memory paths check on the whole arrays: the sample count, NaN/inf (count and
first row), magnitudes beyond float64's working range, time order (also across chunks), gaps,
the time span, samples at the rails (:class:`~rotacal.signal.RailDetector`), and each signal's
range, first and last value. Two functions then raise the in-memory path's error, in its order
and with its words: :func:`raise_encoder_faults` (those of :func:`~rotacal.encoder.demodulate`)
and :func:`raise_signal_faults` (those of the LTS and FOG schemes). :class:`StridedCopy` keeps a
bounded, evenly strided copy of a signal for the frequency's start value.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import numpy as np

from rotacal.errors import CaptureError
from rotacal.signal._checks import MAX_GAP, TYPICAL_STEPS, gap_error
from rotacal.signal._freq import estimate_frequency_unchecked
from rotacal.signal._values import (
    LARGEST,
    SMALLEST,
    check_magnitudes,
    check_time_span,
    in_working_range,
)
from rotacal.signal.clipping import RailDetector, check_clipping
from rotacal.table._stream_source import Passes

#: Samples kept at the start of a capture, and at most twice that many evenly strided over it,
#: for the frequency's start value (:func:`start_frequency`).
_COPY_SAMPLES = 1 << 20


class StridedCopy:
    """Every ``stride``-th sample of a capture fed in chunks (global indices 0, stride, …), the
    stride doubled whenever more than ``2·limit`` are held: at most ``2·limit`` samples."""

    def __init__(self, limit: int = _COPY_SAMPLES) -> None:
        self.stride = 1
        self._limit = limit
        self._t: list[np.ndarray] = []
        self._y: list[np.ndarray] = []
        self._count = 0

    def add(self, offset: int, t: np.ndarray, y: np.ndarray) -> None:
        """The chunk ``t, y`` whose first sample has the global index ``offset``."""
        s0 = (-offset) % self.stride
        self._t.append(np.array(t[s0 :: self.stride]))
        self._y.append(np.array(y[s0 :: self.stride]))
        self._count += self._t[-1].size
        while self._count > 2 * self._limit:
            # the kept samples sit at 0, stride, 2·stride, …: every other one is on the new grid
            t_all, y_all = self.arrays()
            self._t, self._y = [t_all[::2].copy()], [y_all[::2].copy()]
            self._count = self._t[0].size
            self.stride *= 2

    def arrays(self) -> tuple[np.ndarray, np.ndarray]:
        """The samples kept, ``(t, y)``."""
        return np.concatenate(self._t), np.concatenate(self._y)


def start_frequency(
    first: tuple[np.ndarray, np.ndarray], strided: tuple[np.ndarray, np.ndarray], whole: bool
) -> float:
    """Start value (Hz) of a fit's frequency (FFT + single-sine refinement, as
    :func:`~rotacal.signal.estimate_frequency`): from ``first``, the first 2²⁰ samples, when they
    are the whole capture (``whole``: the in-memory estimate) or hold at least 4 periods, else
    from ``strided``, the strided copy of the whole capture (:class:`StridedCopy`)."""
    f = estimate_frequency_unchecked(*first)
    if whole or f * float(first[0][-1] - first[0][0]) >= 4.0:
        return f
    return estimate_frequency_unchecked(*strided)


@dataclasses.dataclass
class Checked:
    """What the check pass found (see the module docstring)."""

    n: int
    counts: dict[str, int]
    first_bad: dict[str, int]
    too_large: CaptureError | None
    peak: dict[str, float]
    order: tuple[int, Any, Any] | None
    gap: tuple[int, float, float] | None
    typical: float | None
    first_t: Any
    last_t: Any
    rails: dict[str, RailDetector]
    low: dict[str, float]
    high: dict[str, float]
    first_value: dict[str, float]
    last_value: dict[str, float]
    first_samples: tuple[np.ndarray, np.ndarray] | None = None
    strided: StridedCopy | None = None

    def clipping(self, allow_clipped: bool) -> tuple[str, ...]:
        """The clipping verdict of :func:`~rotacal.signal.clipping.check_clipping`."""
        found = {name: det.result() for name, det in self.rails.items()}
        return check_clipping(found, allow_clipped=allow_clipped)


def check_pass(
    passes: Passes,
    companions: dict[str, str | None],
    *,
    keep: str | None = None,
) -> Checked:
    """Pass 1: read every chunk once and gather the facts of :class:`Checked`.

    ``companions``: each signal column → its quadrature companion for the rail detector (the
    encoder's a and b), or None. ``keep``: a signal of which the first 2²⁰ samples and a strided
    copy are kept (:func:`start_frequency`).
    """
    time_name = passes.columns[0]
    names = (*companions, time_name)
    rails = {name: RailDetector(name) for name in companions}
    counts = dict.fromkeys(names, 0)
    first_bad = dict.fromkeys(names, -1)
    order: tuple[int, Any, Any] | None = None
    first_t: Any = None
    last_t: Any = None
    typical: float | None = None  # the median time step of the first chunk
    gap: tuple[int, float, float] | None = None
    lengths: list[int] = []
    n = 0
    # magnitudes, as the in-memory check_magnitudes: the first value beyond the working range,
    # and each signal's largest |value| (inf once a chunk passes the one-pass test)
    too_large: CaptureError | None = None
    peak = dict.fromkeys(companions, 0.0)
    low = dict.fromkeys(companions, math.inf)
    high = dict.fromkeys(companions, -math.inf)
    first_value = dict.fromkeys(companions, math.nan)
    last_value = dict.fromkeys(companions, math.nan)
    first_t_parts: list[np.ndarray] = []
    first_y_parts: list[np.ndarray] = []
    n_first = 0
    strided = StridedCopy() if keep is not None else None
    for _, off, cols in passes.run():
        size = cols[time_name].size
        lengths.append(size)
        for name in names:
            x = cols[name]
            if name != time_name and in_working_range(x):
                peak[name] = math.inf
                _extend_range(name, x, low, high, first_value, last_value, off)
                continue
            with np.errstate(over="ignore", invalid="ignore"):
                total = float(np.sum(x))
            if not math.isfinite(total):
                bad = np.flatnonzero(~np.isfinite(x))
                if bad.size:
                    counts[name] += int(bad.size)
                    if first_bad[name] < 0:
                        first_bad[name] = off + int(bad[0])
                    continue
            if name != time_name and x.size:
                chunk_peak = float(np.max(np.abs(x)))
                peak[name] = max(peak[name], chunk_peak)
                _extend_range(name, x, low, high, first_value, last_value, off)
                if chunk_peak > LARGEST and too_large is None:
                    try:
                        check_magnitudes(
                            name, x, what=_WHAT.get(name, "a sensor signal"), offset=off
                        )
                    except CaptureError as exc:
                        too_large = exc
        t = cols[time_name]
        if order is None:
            if last_t is not None and t[0] - last_t <= 0:
                order = (off, last_t, t[0])
            else:
                steps = np.flatnonzero(np.diff(t) <= 0)
                if steps.size:
                    i = int(steps[0])
                    order = (off + i + 1, t[i], t[i + 1])
        if typical is None and t.size > 1:
            typical = float(np.median(np.diff(t[: TYPICAL_STEPS + 1])))
        if gap is None and typical is not None:
            joined = t if last_t is None else np.concatenate(([last_t], t))
            steps = np.diff(joined)
            g = np.flatnonzero(steps > MAX_GAP * typical)
            if g.size:
                gap = (off + int(g[0]) + (1 if last_t is None else 0), float(steps[g[0]]), typical)
        if first_t is None and t.size:
            first_t = t[0]
        last_t = t[-1]
        n += size
        for name, companion in companions.items():
            rails[name].add(cols[name], None if companion is None else cols[companion])
        if keep is not None and strided is not None:
            strided.add(off, t, cols[keep])
            if n_first < _COPY_SAMPLES:
                take = min(size, _COPY_SAMPLES - n_first)
                first_t_parts.append(np.array(t[:take]))
                first_y_parts.append(np.array(cols[keep][:take]))
                n_first += take
    passes.lengths = lengths
    first = None
    if keep is not None and first_t_parts:
        first = (np.concatenate(first_t_parts), np.concatenate(first_y_parts))
    return Checked(
        n=n,
        counts=counts,
        first_bad=first_bad,
        too_large=too_large,
        peak=peak,
        order=order,
        gap=gap,
        typical=typical,
        first_t=first_t,
        last_t=last_t,
        rails=rails,
        low=low,
        high=high,
        first_value=first_value,
        last_value=last_value,
        first_samples=first,
        strided=strided,
    )


_WHAT = {"a": "an encoder signal", "b": "an encoder signal"}


def _extend_range(
    name: str,
    x: np.ndarray,
    low: dict[str, float],
    high: dict[str, float],
    first_value: dict[str, float],
    last_value: dict[str, float],
    offset: int,
) -> None:
    """Each signal's range and its first and last value (finite chunks only)."""
    if x.size == 0:
        return
    low[name] = min(low[name], float(np.min(x)))
    high[name] = max(high[name], float(np.max(x)))
    if offset == 0:
        first_value[name] = float(x[0])
    last_value[name] = float(x[-1])


def raise_encoder_faults(found: Checked, min_samples: int) -> None:
    """The in-memory encoder path's errors (:func:`~rotacal.encoder.demodulate`), in its order."""
    n = found.n
    if n < min_samples:
        raise CaptureError(f"column 'a' has {n} samples; at least {min_samples} are needed.")
    for name in ("a", "b", "time_s"):
        if found.counts[name]:
            raise CaptureError(
                f"column '{name}' has {found.counts[name]} non-finite values (NaN or inf), the "
                f"first at sample {found.first_bad[name]}; remove or interpolate them before "
                "demodulating."
            )
    if found.too_large is not None:
        raise found.too_large
    for name in ("a", "b"):
        if 0.0 < found.peak[name] < SMALLEST:
            check_magnitudes(name, np.array([found.peak[name]]), what="an encoder signal")
    _raise_time_faults(found)


def raise_signal_faults(found: Checked, name: str) -> None:
    """The in-memory LTS and FOG paths' errors (one signal ``name``), in their order."""
    n = found.n
    if n < 16:
        raise CaptureError(f"the capture has only {n} samples: too few for a sine fit")
    if found.counts[name]:
        raise CaptureError(
            f"column {name} has a non-finite value (NaN or inf) at sample {found.first_bad[name]}"
        )
    if found.too_large is not None:
        raise found.too_large
    if 0.0 < found.peak[name] < SMALLEST:
        check_magnitudes(name, np.array([found.peak[name]]))
    if found.counts["time_s"]:
        raise CaptureError(
            f"column 'time_s' has a NaN or inf at sample {found.first_bad['time_s']}."
        )
    _raise_time_faults(found)
    if found.low[name] == found.high[name]:
        raise CaptureError(f"column {name} is constant: the table does not move in this capture")


def _raise_time_faults(found: Checked) -> None:
    if found.order is not None:
        row, before, after = found.order
        raise CaptureError(
            f"column 'time_s' is not strictly increasing at sample {row} "
            f"({float(before):.9g} s then {float(after):.9g} s); sort or fix the time stamps."
        )
    if found.gap is not None:
        raise gap_error("time_s", *found.gap)
    if found.typical is not None:
        check_time_span("time_s", float(found.first_t), float(found.last_t), found.typical)
