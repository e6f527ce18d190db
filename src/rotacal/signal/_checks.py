"""Input checks shared by the sine fits (private)."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from rotacal.errors import CaptureError, ConfigError
from rotacal.signal._values import check_time_span

_EPS = float(np.finfo(np.float64).eps)
_GRID_CHUNK = 1 << 16


def as_samples(name: str, values: Any) -> np.ndarray:
    """Return ``values`` as a 1-D float64 array (no copy when it already is one)."""
    arr = np.asarray(values, dtype=np.float64)
    if arr.ndim != 1:
        raise CaptureError(
            f"{name} must be a one-dimensional array of samples; got an array of shape {arr.shape}."
        )
    return arr


def as_pair(t: Any, y: Any) -> tuple[np.ndarray, np.ndarray]:
    """Return ``t`` and ``y`` as 1-D float64 arrays of the same length."""
    ta = as_samples("t", t)
    ya = as_samples("y", y)
    if ta.shape != ya.shape:
        raise CaptureError(
            f"t and y must have the same length; got {ta.size} time stamps and {ya.size} samples."
        )
    return ta, ya


def check_finite(name: str, values: np.ndarray) -> None:
    """Raise CaptureError naming the first NaN/inf sample of ``values``."""
    # a finite sum of squares proves every value finite (a NaN or inf would carry into it; its
    # terms cannot cancel) in one BLAS pass without a temporary (vdot: ~4x faster than
    # np.add.reduce); only when it is not (or overflows) are the values looked at
    if values.dtype.kind == "f":
        with np.errstate(over="ignore", invalid="ignore"):
            if math.isfinite(float(np.vdot(values, values))):
                return
    if not np.isfinite(values).all():
        i = int(np.flatnonzero(~np.isfinite(values))[0])
        raise CaptureError(
            f"{name} contains NaN or inf (first at index {i}: {values[i]!r}); remove or "
            "interpolate those samples before fitting."
        )


def check_increasing(t: np.ndarray, *, previous: float | None = None) -> None:
    """Raise CaptureError unless ``t`` is finite and strictly increasing (after ``previous``)."""
    check_finite("t", t)
    if previous is not None and t.size and not t[0] > previous:
        raise CaptureError(
            f"time t must increase across chunks: this chunk starts at t = {t[0]!r} s, not after "
            f"the previous chunk's last time {previous!r} s; feed the chunks in time order."
        )
    if t.size > 1:
        bad = np.flatnonzero(~(np.diff(t) > 0))
        if bad.size:
            i = int(bad[0])
            raise CaptureError(
                f"time t must increase strictly: t[{i + 1}] = {t[i + 1]!r} s is not after "
                f"t[{i}] = {t[i]!r} s; sort the samples and drop duplicated time stamps."
            )


#: A time step longer than this many median steps is a gap (lost samples).
MAX_GAP = 3.0
#: The typical step is the median of the first this-many steps (a full median of 10⁸ is slow).
TYPICAL_STEPS = 100_000


def check_sampling(t: np.ndarray, name: str = "time_s", *, max_gap: float = MAX_GAP) -> None:
    """Raise CaptureError unless ``t`` is finite, strictly increasing, free of gaps and resolved.

    A gap — a step longer than ``max_gap`` times the median step — means lost samples (a DAQ
    dropout, a spliced file): phase unwrapping, reversal counting and the FFT start of the fits
    all assume the record is continuous, so a gap would give a silently wrong result. Jitter of
    the time stamps is fine. Time stamps beyond float64's working range, or so large that float64
    resolves them to more than 1 % of a sample interval (1e12 s sampled at 2 kHz), are refused
    too (:func:`rotacal.signal._values.check_time_span`).

    Parameters
    ----------
    t : array, s — sample times.
    name : str — the column's name, for the message.
    max_gap : float — the largest accepted step, in median steps.
    """
    t = np.asarray(t, dtype=np.float64)
    typical = _typical_if_steps_in_bounds(t, max_gap) if t.size > TYPICAL_STEPS else None
    if typical is not None:
        check_time_span(name, float(t[0]), float(t[-1]), typical)
        return
    # a fault somewhere (or a short record): the passes below find the first one and name it
    with np.errstate(over="ignore", invalid="ignore"):
        finite = math.isfinite(float(np.sum(t)))  # one cheap pass; search only if it fails
    if not finite:
        bad = np.flatnonzero(~np.isfinite(t))
        if bad.size:
            raise CaptureError(f"column '{name}' has a NaN or inf at sample {int(bad[0])}.")
    if t.size < 2:
        return
    steps = np.diff(t)
    bad = np.flatnonzero(~(steps > 0))
    if bad.size:
        i = int(bad[0])
        raise order_error(name, i + 1, float(t[i]), float(t[i + 1]))
    typical = _typical_step(t)
    gaps = np.flatnonzero(steps > max_gap * typical)
    if gaps.size:
        i = int(gaps[0])
        raise gap_error(name, i + 1, float(steps[i]), typical)
    check_time_span(name, float(t[0]), float(t[-1]), typical)


def _typical_step(t: np.ndarray) -> float:
    """The median of the first TYPICAL_STEPS steps of ``t`` (s)."""
    return float(np.median(np.diff(t[: TYPICAL_STEPS + 1])))


def _typical_if_steps_in_bounds(t: np.ndarray, max_gap: float) -> float | None:
    """The typical step (s) when every step of ``t`` is in (0, max_gap·typical], else None: one
    pass in cache-sized blocks, without the full-size arrays of steps and masks (~5 passes over
    2·10⁷ samples → 1). NaN/inf anywhere make a step NaN or inf and the answer None, as does any
    fault: then :func:`check_sampling`'s full passes find and name it (the same messages)."""
    if not math.isfinite(float(t[0])):
        return None
    typical = _typical_step(t)
    limit = max_gap * typical
    if not (typical > 0 and math.isfinite(limit)):
        return None
    steps = np.empty(min(t.size - 1, _GRID_CHUNK))
    with np.errstate(invalid="ignore", over="ignore"):
        for lo in range(0, t.size - 1, _GRID_CHUNK):
            hi = min(t.size - 1, lo + _GRID_CHUNK)
            block = steps[: hi - lo]
            np.subtract(t[lo + 1 : hi + 1], t[lo:hi], out=block)
            # NaN fails both comparisons: `not (x > 0)` rather than `x <= 0`
            if not (block.min() > 0.0 and block.max() <= limit):
                return None
    return typical


def order_error(name: str, sample: int, before: float, after: float) -> CaptureError:
    """The one message for time stamps that do not increase (in-memory and chunked paths)."""
    return CaptureError(
        f"column '{name}' is not strictly increasing at sample {sample} "
        f"({before:.9g} s then {after:.9g} s); sort or fix the time stamps."
    )


def gap_error(name: str, sample: int, step: float, typical: float) -> CaptureError:
    """The one message for a gap in the time stamps (shared by the in-memory and chunked paths)."""
    return CaptureError(
        f"column '{name}' has a gap of {step:.6g} s before sample {sample} (the usual step is "
        f"{typical:.3g} s): samples are missing; analyse the parts on either side separately."
    )


def grid_tolerance(dt: float, t_first: float, t_last: float) -> float:
    """How far (s) a time stamp may sit from the ideal uniform grid and still count as on it."""
    return max(1e-10 * abs(dt), 64.0 * _EPS * max(abs(t_first), abs(t_last)))


def max_grid_deviation(t: np.ndarray, t0: float, dt: float, g0: int) -> float:
    """Largest |t_i − (t0 + (g0 + i)·dt)| in seconds (NaN if ``t`` holds NaN).

    Works chunk-wise in cache-sized pieces without full-size temporaries.
    """
    n = t.size
    if n == 0:
        return 0.0
    step = min(n, _GRID_CHUNK)
    base = np.arange(step, dtype=np.float64) * dt
    buf = np.empty(step)
    worst = 0.0
    for s in range(0, n, step):
        e = min(n, s + step)
        d = np.subtract(t[s:e], base[: e - s], out=buf[: e - s])
        off = t0 + (g0 + s) * dt
        hi = float(d.max()) - off
        lo = float(d.min()) - off
        dev = max(hi, -lo)
        if not math.isfinite(dev):
            return math.nan
        worst = max(worst, dev)
    return worst


def uniform_step(t: np.ndarray) -> float | None:
    """Return the sampling interval (s) if ``t`` lies on a uniform increasing grid, else None."""
    n = t.size
    if n < 2:
        return None
    dt = (float(t[-1]) - float(t[0])) / (n - 1)
    if not (math.isfinite(dt) and dt > 0):
        return None
    dev = max_grid_deviation(t, float(t[0]), dt, 0)
    if math.isfinite(dev) and dev <= grid_tolerance(dt, float(t[0]), float(t[-1])):
        return dt
    return None


def check_harmonics(harmonics: Any) -> int:
    """Validate the number of harmonics (an integer ≥ 1)."""
    if isinstance(harmonics, bool) or not isinstance(harmonics, (int, np.integer)):
        raise ConfigError(f"harmonics must be an integer ≥ 1; got {harmonics!r}.")
    if harmonics < 1:
        raise ConfigError(f"harmonics must be ≥ 1 (1 = the fundamental only); got {harmonics}.")
    return int(harmonics)


def check_frequency(frequency_hz: Any) -> float:
    """Validate a frequency in Hz (finite, > 0)."""
    try:
        f = float(frequency_hz)
    except (TypeError, ValueError):
        raise ConfigError(
            f"frequency_hz must be a positive number; got {frequency_hz!r}."
        ) from None
    if not (math.isfinite(f) and f > 0):
        raise ConfigError(f"frequency_hz must be a finite positive number in Hz; got {f!r}.")
    return f


def check_record(n: int, span_s: float, frequency_hz: float, harmonics: int, n_params: int) -> None:
    """Raise if the record is too short or too coarsely sampled for the requested fit."""
    if n < n_params + 1:
        raise CaptureError(
            f"the record holds {n} samples, fewer than the {n_params + 1} needed to fit "
            f"{n_params} parameters ({harmonics} harmonics) and estimate the residual; supply a "
            "longer record or fewer harmonics."
        )
    periods = frequency_hz * span_s * n / (n - 1)
    if periods < MIN_PERIODS:
        raise CaptureError(
            f"the record spans only {periods:.3g} periods of {frequency_hz:.6g} Hz; a sine fit "
            f"needs at least ~1 full period ({MIN_PERIODS} accepted): supply a longer record."
        )
    fs_mean = (n - 1) / span_s
    if harmonics * frequency_hz >= 0.5 * fs_mean:
        raise ConfigError(
            f"harmonic {harmonics} of {frequency_hz:.6g} Hz lies at or above the Nyquist "
            f"frequency {0.5 * fs_mean:.6g} Hz of the mean sampling rate; lower harmonics."
        )


MIN_PERIODS = 0.9
