"""Constant-rate calibration of a rotary table from encoder pulse timing (seed 004, §5).

The table turns at a set angular velocity; the encoder's pulse times give the angle at every
pulse. From them: the mean rate over whole revolutions (where the scale's deviation cancels
exactly), its bias against the set rate, the rate over time by the time-difference method with and
without compensation by the self-calibrated deviation (rms and peak deviation in % of rate), and the
relative root Allan variance of angular velocity as a function of rotation angle, s(φ).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from rotacal.encoder.pulses import (
    check_pulse_times,
    check_pulses_per_rev,
    head_columns,
    pair_heads,
    pulse_angle_deg,
    pulse_rate,
    whole_revolution_rate,
)
from rotacal.encoder.selfcal import SelfCalibration, check_period, head_shifts, self_calibrate
from rotacal.errors import CaptureError, ConfigError
from rotacal.results import Result

__all__ = ["RateResult", "align_deviation", "allan_versus_angle", "calibrate_rate"]

FloatArray = NDArray[np.float64]

#: Allan points per decade of rotation angle.
ALLAN_POINTS_PER_DECADE = 12
#: Below this correlation a deviation curve is not trusted to match a capture.
MIN_ALIGNMENT_CORRELATION = 0.7
#: A single head's phase-correlation peak must stand this many robust spreads above the rest
#: (the largest of m Gaussian values stands about 4.5 spreads out for m ~ 10⁴).
_SINGLE_HEAD_SIGNIFICANCE = 10.0


@dataclasses.dataclass(frozen=True)
class RateResult(Result):
    """Constant-rate calibration of a table (INTERFACE.md ``rate``).

    Attributes
    ----------
    mean_rate_deg_s : float, deg/s
        Mean angular velocity over the whole revolutions of the record (the scale's deviation
        cancels over a revolution); over the whole record by a straight-line fit when shorter.
    rate_deviation_rms_percent, rate_deviation_peak_percent : float, %
        rms and peak of the averaged rate about the mean, in % of the mean rate, compensated by
        the self-calibrated deviation when one was applied.
    rate_deviation_rms_percent_uncompensated, rate_deviation_peak_percent_uncompensated : float, %
        The same with the nominal pitch (no compensation).
    allan_angle_deg, allan_tau_s : list of float
        Rotation angles φ (deg) and the corresponding τ = φ/ω_m (s).
    allan_relative : list of float
        s(φ) = σ(φ/ω_m)/ω_m (dimensionless), compensated when a deviation was applied.
    allan_relative_uncompensated : list of float
    set_rate_deg_s, rate_bias_deg_s, rate_bias_percent : float or None
        Set rate and mean − set (deg/s and % of the set rate), when a set rate is given.
    head : str
        ``"head_k"`` or ``"all heads"`` (the head-averaged times).
    average : int
        Pulse intervals per averaged rate point.
    revolutions : int
        Whole revolutions in the record used for the mean rate.
    mean_rate_window_s : list of float, s
        [start, stop] of the time over which the mean rate is taken.
    duration_s : float, s
    compensated : bool
    deviation_shift_pulses : int or None
        Deviation index of the head's first pulse (how the curve was aligned with the capture).
    alignment_correlation : float or None
        Correlation of the capture's own angle error with the deviation when it had to be
        aligned by correlation (None when the deviation came from the same capture).
    notes : list of str
    """

    mean_rate_deg_s: float
    rate_deviation_rms_percent: float
    rate_deviation_peak_percent: float
    rate_deviation_rms_percent_uncompensated: float
    rate_deviation_peak_percent_uncompensated: float
    allan_angle_deg: list[float]
    allan_tau_s: list[float]
    allan_relative: list[float]
    allan_relative_uncompensated: list[float]
    set_rate_deg_s: float | None
    rate_bias_deg_s: float | None
    rate_bias_percent: float | None
    head: str
    average: int
    revolutions: int
    mean_rate_window_s: list[float]
    duration_s: float
    compensated: bool
    deviation_shift_pulses: int | None
    alignment_correlation: float | None
    notes: list[str]
    _time_s: FloatArray = dataclasses.field(repr=False)
    _rate_deg_s: FloatArray = dataclasses.field(repr=False)
    _rate_uncompensated_deg_s: FloatArray = dataclasses.field(repr=False)
    _selfcal: SelfCalibration | None = dataclasses.field(repr=False, default=None)

    @property
    def time_s(self) -> FloatArray:
        """Time (s) of each averaged rate point."""
        return self._time_s

    @property
    def rate_deg_s(self) -> FloatArray:
        """Averaged rate (deg/s), compensated when a deviation was applied."""
        return self._rate_deg_s

    @property
    def rate_uncompensated_deg_s(self) -> FloatArray:
        """Averaged rate (deg/s) with the nominal pitch."""
        return self._rate_uncompensated_deg_s

    @property
    def selfcal(self) -> SelfCalibration | None:
        """The self-calibration made from this capture, when one was made."""
        return self._selfcal


def allan_versus_angle(
    times_s: ArrayLike,
    angle_deg: ArrayLike,
    *,
    mean_rate_deg_s: float,
    angles_deg: ArrayLike | None = None,
    pitch_deg: float | None = None,
) -> tuple[FloatArray, FloatArray]:
    """Relative root Allan variance of angular velocity versus rotation angle, s(φ).

    With angles θ_i at pulse times t_i, the rate over k pulses is ω_i = (θ_{i+k} − θ_i)/(t_{i+k}
    − t_i), the Allan variance σ²(τ) = ½⟨(ω_{i+k} − ω_i)²⟩ (overlapping, averaged over every i)
    and s(φ) = √σ²(φ/ω_m)/ω_m. The seed samples the angle at equal times; here it is sampled at
    equal angles (the pulses), so φ = k·Δθ is exact and τ = φ/ω_m as the seed converts it.

    Parameters
    ----------
    times_s : array_like, s
        Pulse times.
    angle_deg : array_like, deg
        Angle at each pulse (compensated or nominal).
    mean_rate_deg_s : float, deg/s
        ω_m.
    angles_deg : array_like, deg, optional
        Rotation angles φ to evaluate (rounded to whole pulses); default: 12 per decade from
        one pitch to a third of the record.
    pitch_deg : float, deg, optional
        Nominal pitch Δθ (default: the mean angle step).

    Returns
    -------
    phi_deg : ndarray, deg
    s : ndarray
        Relative root Allan variance (dimensionless).

    References
    ----------
    Kokuyama et al. (seed 004), §5 "Evaluation using root Allan variance": ω_i = (θ_{i+k} −
    θ_i)/(kΔt), σ²(τ) = ½⟨(ω_{i+k} − ω_i)²⟩, τ = φ/ω_m, s(φ) = √σ²(φ/ω_m)/ω_m; Figure 10.
    """
    t = np.asarray(times_s, dtype=np.float64)
    a = np.asarray(angle_deg, dtype=np.float64)
    n = t.size
    pitch = float(pitch_deg) if pitch_deg is not None else float((a[-1] - a[0]) / (n - 1))
    kmax = (n - 1) // 3
    if kmax < 1:
        raise CaptureError(f"{n} pulses are too few for an Allan variance; record more.")
    if angles_deg is None:
        decades = max(math.log10(kmax), 0.0)
        grid = np.rint(np.logspace(0.0, decades, int(decades * ALLAN_POINTS_PER_DECADE) + 1))
        # one revolution, where the scale's deviation cancels (the seed's Figure 10 dip)
        whole = np.rint(360.0 / pitch)
        extra = [whole] if whole <= kmax else []
        ks = np.unique(np.concatenate((grid, extra))).astype(np.int64)
    else:
        req = np.atleast_1d(np.asarray(angles_deg, dtype=np.float64))
        if not np.all(np.isfinite(req)) or np.any(req <= 0):
            raise ConfigError("Allan angles must be finite and > 0 deg.")
        ks = np.unique(np.maximum(1, np.rint(req / pitch)).astype(np.int64))
        too_long = ks[ks > kmax]
        if too_long.size:
            raise ConfigError(
                f"an Allan angle of {too_long[0] * pitch:.6g} deg needs more than a third of the "
                f"record ({kmax * pitch:.6g} deg); drop it or record longer."
            )
    s = np.empty(ks.size)
    for idx, k in enumerate(ks):  # one whole-array pass per angle
        omega = (a[k:] - a[:-k]) / (t[k:] - t[:-k])
        d = omega[k:] - omega[:-k]
        s[idx] = math.sqrt(0.5 * float(np.mean(d * d))) / abs(mean_rate_deg_s)
    return np.asarray(ks * pitch, dtype=np.float64), s


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
    count = np.arange(revs * m)
    t = times_s[: revs * m]
    slope, icpt = np.polyfit(t - t[0], count * (360.0 / m), 1)
    err = (count * (360.0 / m) - (icpt + slope * (t - t[0]))) * 3600.0
    folded = -err.reshape(revs, m).mean(axis=0)
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
    if shifts is not None:
        try:
            shifts = [int(x) for x in shifts]
        except (TypeError, ValueError):
            raise ConfigError(
                "the self-calibration's 'head_line_shifts' must be integers."
            ) from None
    return _Deviation(values, fingerprint, str(rotation), shifts)


def calibrate_rate(
    heads: Sequence[ArrayLike] | Mapping[str, ArrayLike],
    *,
    pulses_per_rev: int,
    selfcal: SelfCalibration | Mapping[str, Any] | ArrayLike | None = None,
    head: int | str = 0,
    average: int = 10,
    set_rate_deg_s: float | None = None,
    allan_angles_deg: ArrayLike | None = None,
    compensate: bool = True,
) -> RateResult:
    """Angular velocity of a table from pulse timing: mean, bias, stability and s(φ).

    Parameters
    ----------
    heads : sequence of array_like, or mapping with ``head_0`` …, s
        Pulse times of every head (head 0 first); one head is enough without self-calibration.
    pulses_per_rev : int
        m, pulses per revolution.
    selfcal : SelfCalibration, its JSON dict, an array of m deviations (arcsec), or None
        The scale deviation used to compensate the angle. None with ≥ 2 heads and a whole
        revolution: self-calibrate this capture (as the seed does); with one head: no compensation.
        A curve from another capture is aligned to this one by correlation.
    head : int or "all"
        The head whose pulses give the rate (default 0, the reference, as in the seed's Figure 9)
        or ``"all"`` for the head-averaged times (the average cancels every detectable order of
        the deviation, so compensation changes nothing there).
    average : int
        Pulse intervals averaged per rate point (the seed: 10).
    set_rate_deg_s : float, deg/s, optional
        The commanded rate, for the bias.
    allan_angles_deg : array_like, deg, optional
        Angles φ for s(φ) (default 12 per decade).
    compensate : bool
        Set False to skip compensation (results then equal the uncompensated ones).

    Returns
    -------
    RateResult

    Raises
    ------
    CaptureError, ConfigError
        Bad pulse trains, an unknown head, a deviation curve for another m or one that cannot be
        aligned with this capture.

    References
    ----------
    Kokuyama et al. (seed 004), §5: time-difference rate with 10-point averaging, Figure 9 (rate
    compensated with the extracted deviation, bias and fluctuation in % of rate), the relative root
    Allan variance s(φ) of Figure 10.
    """
    m = check_pulses_per_rev(pulses_per_rev)
    if isinstance(heads, Mapping):
        trains = head_columns(heads)
    else:
        trains = [np.asarray(h, dtype=np.float64) for h in heads]
    if not trains:
        raise CaptureError("no pulse trains given; the capture needs head_0 (and more heads).")
    names = [f"head_{i}" for i in range(len(trains))]
    trains = [check_pulse_times(t, name) for t, name in zip(trains, names, strict=True)]
    n = len(trains)
    if set_rate_deg_s is not None:
        if not math.isfinite(float(set_rate_deg_s)) or float(set_rate_deg_s) == 0:
            raise ConfigError(
                f"set_rate_deg_s must be finite and non-zero, got {set_rate_deg_s!r}."
            )
    use_all = isinstance(head, str) and head == "all"
    k = 0
    if not use_all:
        if isinstance(head, str) and head.startswith("head_"):
            head = head[5:]
        try:
            k = int(head)
        except (TypeError, ValueError):
            raise ConfigError(f"head must be a head number or 'all', got {head!r}.") from None
        if not 0 <= k < n:
            raise ConfigError(f"head {k} does not exist; the capture has head_0 … head_{n - 1}.")
    notes: list[str] = []

    made: SelfCalibration | None = None
    deviation: FloatArray | None = None
    shift: int | None = None
    correlation: float | None = None
    if compensate and not use_all:
        if selfcal is None and n >= 2:
            try:
                made = self_calibrate(trains, pulses_per_rev=m)
            except CaptureError as e:
                raise CaptureError(
                    f"{e} (the rate is compensated with a self-calibration of this capture; "
                    "give one with --selfcal, or use --no-compensation)"
                ) from None
            selfcal = made
            notes.append(
                f"compensated with the deviation self-calibrated from this capture "
                f"({made.heads} heads, {made.revolutions_used} revolutions)."
            )
        if selfcal is None:
            notes.append("one head and no self-calibration given: the rate is not compensated.")
        else:
            dev = _as_deviation(selfcal, m)
            deviation = dev.values
            here = (float(trains[0][0]), float(trains[0][-1]), int(trains[0].size))
            same = dev.fingerprint is not None and (
                math.isclose(dev.fingerprint[0], here[0], abs_tol=1e-12)
                and math.isclose(dev.fingerprint[1], here[1], abs_tol=1e-12)
                and dev.fingerprint[2] == here[2]
            )
            shift = 0  # deviation index of head 0's first pulse
            if not same:
                shift, correlation = align_deviation(trains, deviation, m)
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
            if k != 0:
                # head k's first pulse sees the line s_k ahead of the head-0 pulse it pairs with
                pairing = pair_heads(trains, names)
                shifts = dev.shifts or list(head_shifts(n, m, dev.rotation))
                if len(shifts) != n:
                    raise ConfigError(
                        f"the self-calibration is of {len(shifts)} heads, the capture has {n}."
                    )
                shift = (shift + shifts[k] - int(pairing.index_offsets[k])) % m
    elif use_all:
        notes.append(
            "rate from the head-averaged pulse times: the average cancels every detectable order "
            "of the scale deviation, so there is nothing to compensate."
        )

    if use_all:
        if n < 2:
            raise ConfigError("head='all' needs at least 2 heads; the capture has one.")
        pairing = pair_heads(trains, names)
        times = pairing.mean_times_s
        notes.extend(pairing.notes)
        label = "all heads"
    else:
        times = trains[k]
        label = f"head_{k}"
    count = np.arange(times.size)
    angle_nom = pulse_angle_deg(count, m)
    angle = (
        pulse_angle_deg(count, m, deviation, line_offset=shift or 0)
        if deviation is not None
        else angle_nom
    )

    if n == 1 and times.size > m:
        # one head: nothing else checks m; its angle error must repeat once per revolution
        t_rel = times - times[0]
        err = angle_nom - np.polyval(np.polyfit(t_rel, angle_nom, 1), t_rel)
        if not check_period(-err, m, coarse=False):
            notes.append(
                f"one head: {m} pulses per revolution cannot be confirmed from the data's own "
                "period (too short a record, or too weak a graduation pattern); a wrong count "
                "scales the rate."
            )
    mean_rate, revs = whole_revolution_rate(times, m)
    window = [float(times[0]), float(times[revs * m] if revs else times[-1])]
    if mean_rate is None:
        mean_rate = float(np.polyfit(times - times[0], angle, 1)[0])
        notes.append(
            f"less than one whole revolution ({times.size} pulses of {m}): the mean rate is a "
            "straight-line fit of the compensated angle, not exact over revolutions."
        )

    t_avg, rate = pulse_rate(times, angle, average=average)
    _, rate_nom = pulse_rate(times, angle_nom, average=average)
    dev_pct = 100.0 * (rate - mean_rate) / mean_rate
    dev_nom_pct = 100.0 * (rate_nom - mean_rate) / mean_rate

    phi, s = allan_versus_angle(
        times, angle, mean_rate_deg_s=mean_rate, angles_deg=allan_angles_deg, pitch_deg=360.0 / m
    )
    if deviation is not None:
        _, s_nom = allan_versus_angle(
            times, angle_nom, mean_rate_deg_s=mean_rate, angles_deg=phi, pitch_deg=360.0 / m
        )
    else:
        s_nom = s
    bias = bias_pct = None
    if set_rate_deg_s is not None:
        set_rate = abs(float(set_rate_deg_s))
        if float(set_rate_deg_s) < 0:
            notes.append(
                "pulse times carry no sense of rotation: the mean rate is a magnitude and is "
                f"compared with |set rate| = {set_rate:g} °/s."
            )
        bias = mean_rate - set_rate
        bias_pct = 100.0 * bias / set_rate
    return RateResult(
        mean_rate_deg_s=float(mean_rate),
        rate_deviation_rms_percent=float(np.sqrt(np.mean(dev_pct**2))),
        rate_deviation_peak_percent=float(np.max(np.abs(dev_pct))),
        rate_deviation_rms_percent_uncompensated=float(np.sqrt(np.mean(dev_nom_pct**2))),
        rate_deviation_peak_percent_uncompensated=float(np.max(np.abs(dev_nom_pct))),
        allan_angle_deg=[float(x) for x in phi],
        allan_tau_s=[float(x / abs(mean_rate)) for x in phi],
        allan_relative=[float(x) for x in s],
        allan_relative_uncompensated=[float(x) for x in s_nom],
        set_rate_deg_s=None if set_rate_deg_s is None else float(set_rate_deg_s),
        rate_bias_deg_s=bias,
        rate_bias_percent=bias_pct,
        head=label,
        average=int(average),
        revolutions=int(revs),
        mean_rate_window_s=window,
        duration_s=float(times[-1] - times[0]),
        compensated=deviation is not None,
        deviation_shift_pulses=shift,
        alignment_correlation=correlation,
        notes=notes,
        _time_s=t_avg,
        _rate_deg_s=rate,
        _rate_uncompensated_deg_s=rate_nom,
        _selfcal=made,
    )
