"""The deviation curve a rate is compensated with: read from a self-calibration (its result, its
JSON or a bare array) and placed on a capture by correlation (Kokuyama et al. 2015, §3)."""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
from numpy.typing import NDArray

from rotacal.encoder.selfcal import (
    SelfCalibration,
    self_calibrate,
)
from rotacal.errors import CaptureError, ConfigError
from rotacal.signal._values import LARGEST
from rotacal.table.rate_plausibility import TrendSums

__all__ = ["FoldSums", "align_deviation"]

FloatArray = NDArray[np.float64]

#: Below this correlation a deviation curve is not trusted to match a capture.
MIN_ALIGNMENT_CORRELATION = 0.7
#: A single head's phase-correlation peak must stand this many robust spreads above the rest
#: (the largest of m Gaussian values stands about 4.5 spreads out for m ~ 10⁴).
_SINGLE_HEAD_SIGNIFICANCE = 10.0


def _circular_match(observed: FloatArray, deviation: FloatArray) -> tuple[int, float]:
    """Shift L maximising Σ_j observed[j]·deviation[(j + L) mod m], and the correlation there."""
    m = deviation.size
    o = observed - observed.mean()
    d = deviation - deviation.mean()
    corr = np.fft.irfft(np.conj(np.fft.rfft(o)) * np.fft.rfft(d), m)
    shift = int(np.argmax(corr))
    norm = float(np.sqrt(np.sum(o**2) * np.sum(d**2)))
    return shift, float(corr[shift] / norm) if norm > 0 else 0.0


def align_deviation(
    heads: Sequence[FloatArray], deviation_arcsec: FloatArray, pulses_per_rev: int
) -> tuple[int, float]:
    """Find the deviation index of head 0's first pulse in a capture, by correlation.

    With two or more heads the capture is self-calibrated and its own curve matched to the given
    one: both are free of the table's rate fluctuation. With one head, the head's angle error
    against a straight line in time, folded over the revolutions, is matched instead, without
    the first order: a once-per-revolution rate fluctuation of the table (common: cogging, an
    unbalanced load) looks exactly like eccentricity to a single head.

    Parameters
    ----------
    heads : sequence of ndarray, s
        Checked pulse trains of the capture, head 0 first.
    deviation_arcsec : ndarray, shape (m,), arcsec
        The deviation curve to place.
    pulses_per_rev : int

    Returns
    -------
    shift : int
        Deviation index of head 0's pulse 0.
    correlation : float
        With several heads, the normalised correlation of the two curves at that shift (1 = the
        same shape); with one head, 0.07 × the phase-correlation peak's height in robust spreads
        (so that the same 0.7 threshold means a peak ten spreads out).
    """
    m = pulses_per_rev
    if len(heads) >= 2:
        own = self_calibrate(heads, pulses_per_rev=m)
        return _circular_match(own.deviation_arcsec, deviation_arcsec)
    times_s = heads[0]
    revs = (times_s.size - 1) // m
    if revs < 1:
        raise CaptureError(
            "aligning a deviation curve from another capture needs at least one whole revolution "
            f"of the head ({m} pulses); this one has {times_s.size}."
        )
    fold = FoldSums(times_s.size, m)
    fold.update(times_s)
    return _phase_shift(fold.folded(), deviation_arcsec, m)


class FoldSums:
    """The angle error of one head against a straight line in time, folded over its whole
    revolutions (arcsec, sign of a deviation), summed over a stream of its n pulse times: the
    line's normal equations (centred, merged chunk by chunk) and, per line, the sums over the
    revolutions of its time and of its angle less a provisional line (the first interval's
    rate): small numbers, so that any chunking gives the same folded curve to rounding."""

    def __init__(self, n: int, pulses_per_rev: int) -> None:
        self.m = int(pulses_per_rev)
        self.revs = (int(n) - 1) // self.m
        self.used = self.revs * self.m
        self.seen = 0
        self.t0 = math.nan
        self.last = math.nan
        self._rate0 = math.nan
        self._x_sums = np.zeros(self.m)
        self._y_sums = np.zeros(self.m)
        self._fit = TrendSums()

    def _fold(self, sums: FloatArray, values: FloatArray) -> None:
        pad = np.concatenate((np.zeros(self.seen % self.m), values))  # whole turns of the lines
        full = np.zeros(-(-pad.size // self.m) * self.m)
        full[: pad.size] = pad
        sums += full.reshape(-1, self.m).sum(axis=0)

    def update(self, t: FloatArray) -> None:
        """Add the next pulse times (s)."""
        if t.size == 0:
            return
        if self.seen == 0:
            self.t0 = float(t[0])
        if math.isnan(self._rate0) and self.seen + t.size >= 2:
            t1 = float(t[1 - self.seen])
            self._rate0 = (360.0 / self.m) / (t1 - self.t0)
        self.last = float(t[-1])
        take = t[: max(self.used - self.seen, 0)]
        if take.size:
            count = np.arange(self.seen, self.seen + take.size)
            x = take - self.t0
            y = count * (360.0 / self.m) - self._rate0 * x  # the angle less the provisional line
            self._fit.update(x, y)
            self._fold(self._x_sums, x)
            self._fold(self._y_sums, y)
        self.seen += t.size

    @classmethod
    def starting_at(cls, n: int, pulses_per_rev: int, first: int, t0: float, t1: float) -> FoldSums:
        """The sums of a block of the train that starts at pulse ``first``, fed its pulses
        (``t0``, ``t1``: the train's first two pulse times, s); :meth:`merge` adds it."""
        out = cls(n, pulses_per_rev)
        out.seen, out.t0 = int(first), float(t0)
        out._rate0 = (360.0 / out.m) / (float(t1) - out.t0)
        return out

    def merge(self, block: FoldSums) -> None:
        """Add the sums of the block of pulses that follows those seen."""
        if self.seen == 0:
            self.t0, self._rate0 = block.t0, block._rate0
        self._x_sums += block._x_sums
        self._y_sums += block._y_sums
        self._fit.merge(block._fit)
        self.last, self.seen = block.last, block.seen

    def folded(self) -> FloatArray:
        """−(mean over the revolutions of count·Δθ − line(t)), arcsec, line by line."""
        fit = self._fit
        slope = fit.ctd / fit.ctt
        icpt = fit.mean_d - slope * fit.mean_t
        mean_err = (self._y_sums - slope * self._x_sums) / self.revs - icpt
        return np.asarray(-mean_err * 3600.0, dtype=np.float64)


def _phase_shift(folded: FloatArray, deviation_arcsec: FloatArray, m: int) -> tuple[int, float]:
    """Shift of ``deviation_arcsec`` that matches a single head's folded angle error, by phase
    correlation without the first order, and its significance on the correlation's scale."""
    # Phase correlation: every order weighs the same, so the many orders carried by the
    # graduation errors outvote the few where the table's rate fluctuation sits.
    cross = np.conj(np.fft.rfft(folded)) * np.fft.rfft(deviation_arcsec)
    cross[:2] = 0.0
    mag = np.abs(cross)
    cross = np.where(mag > 0, cross / np.where(mag > 0, mag, 1.0), 0.0)
    phat = np.fft.irfft(cross, m)
    shift = int(np.argmax(phat))
    spread = 1.4826 * float(np.median(np.abs(phat - np.median(phat))))
    significance = (float(phat[shift]) - float(np.median(phat))) / spread if spread > 0 else 0.0
    # on the scale of the correlation threshold: 0.7 when the peak stands 10 spreads out
    return shift, MIN_ALIGNMENT_CORRELATION * significance / _SINGLE_HEAD_SIGNIFICANCE


@dataclasses.dataclass(frozen=True)
class _Deviation:
    """A deviation curve to compensate with, and what identifies the capture it indexes."""

    values: FloatArray
    fingerprint: tuple[float, float, int] | None  # head 0's first and last time, pulse count
    rotation: str
    shifts: list[int] | None


def _json_number(d: Mapping[str, Any], key: str, kind: type) -> Any:
    value = d.get(key)
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise ConfigError(f"the self-calibration's '{key}' must be a number, got {value!r}.")
    if not math.isfinite(value) or abs(value) > LARGEST:
        raise ConfigError(
            f"the self-calibration's '{key}' = {value!r} is not a usable number (not finite, or "
            "beyond float64's working range); redo the self-calibration (--selfcal)."
        )
    if kind is int and float(value) != int(value):
        raise ConfigError(f"the self-calibration's '{key}' must be a whole number, got {value!r}.")
    return kind(value)


def _as_deviation(selfcal: Any, m: int) -> _Deviation:
    """The deviation from a SelfCalibration, its JSON dict, or a bare array of m values."""
    fingerprint: tuple[float, float, int] | None = None
    rotation, shifts, pprev = "forward", None, m
    if isinstance(selfcal, SelfCalibration):
        raw: Any = selfcal.deviation_arcsec
        fingerprint = (selfcal.first_pulse_time_s, selfcal.last_pulse_time_s, selfcal.head0_pulses)
        rotation, shifts, pprev = selfcal.rotation, selfcal.head_line_shifts, selfcal.pulses_per_rev
    elif isinstance(selfcal, Mapping):
        if "deviation_arcsec" not in selfcal:
            raise ConfigError("the self-calibration has no 'deviation_arcsec' (a selfcal JSON?).")
        raw = selfcal["deviation_arcsec"]
        first = _json_number(selfcal, "first_pulse_time_s", float)
        last = _json_number(selfcal, "last_pulse_time_s", float)
        count = _json_number(selfcal, "head0_pulses", int)
        if first is not None and last is not None and count is not None:
            fingerprint = (first, last, count)
        pprev = _json_number(selfcal, "pulses_per_rev", int) or m
        rotation = selfcal.get("rotation", "forward")
        if rotation not in ("forward", "reverse"):
            raise ConfigError(
                f"the self-calibration's 'rotation' must be 'forward' or 'reverse', got {rotation!r}."
            )
        shifts = selfcal.get("head_line_shifts")
    else:
        raw = selfcal
    try:
        values = np.asarray(raw, dtype=np.float64)
    except (TypeError, ValueError):
        raise ConfigError("the deviation must be a list of numbers (arcsec).") from None
    if values.ndim != 1:
        raise ConfigError(f"the deviation must be one list of m values, got shape {values.shape}.")
    if pprev != m or values.size != m:
        given = pprev if pprev != m else values.size
        raise ConfigError(
            f"the self-calibration is for {given} pulses per revolution, the capture is analysed "
            f"with {m}; use a self-calibration of the same encoder and --pulses-per-rev."
        )
    if not np.all(np.isfinite(values)):
        raise ConfigError("the deviation holds a NaN or null; redo the self-calibration.")
    if values.size and float(np.max(np.abs(values))) > LARGEST:
        i = int(np.argmax(np.abs(values)))
        raise ConfigError(
            f"the deviation holds {values[i]:.6g} arcsec at entry {i}: not a scale deviation "
            "(beyond float64's working range); redo the self-calibration (--selfcal)."
        )
    if shifts is not None:
        try:
            shifts = [int(x) for x in shifts]
        except (TypeError, ValueError):
            raise ConfigError(
                "the self-calibration's 'head_line_shifts' must be integers."
            ) from None
    return _Deviation(values, fingerprint, str(rotation), shifts)


def same_capture(dev: _Deviation, here: tuple[float, float, int]) -> bool:
    """Whether a deviation's fingerprint (head 0's first and last time, pulse count) is this
    capture's ``here``: then it indexes the capture as it is, no alignment."""
    fp = dev.fingerprint
    return fp is not None and (
        math.isclose(fp[0], here[0], abs_tol=1e-12)
        and math.isclose(fp[1], here[1], abs_tol=1e-12)
        and fp[2] == here[2]
    )


def own_revolutions(selfcal: Any) -> int | None:
    """Revolutions a self-calibration (its result or JSON) was made from, when it says."""
    if isinstance(selfcal, SelfCalibration):
        return selfcal.revolutions_used
    if isinstance(selfcal, Mapping):
        return _json_number(selfcal, "revolutions_used", int)
    return None


def accept_alignment(shift: int, correlation: float, notes: list[str]) -> None:
    """Refuse an alignment below :data:`MIN_ALIGNMENT_CORRELATION`, else note it."""
    if correlation < MIN_ALIGNMENT_CORRELATION:
        raise CaptureError(
            f"the deviation curve does not match this capture (best correlation "
            f"{correlation:.2f} < {MIN_ALIGNMENT_CORRELATION}): self-calibrate this "
            "capture, or give a self-calibration of the same encoder."
        )
    notes.append(
        f"the deviation comes from another capture; aligned by correlation "
        f"(head_0 starts at its index {shift}, correlation {correlation:.3f})."
    )
