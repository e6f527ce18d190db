"""Constant-rate calibration of a rotary table from encoder pulse timing (Kokuyama et al. 2015, §5).

The table turns at a set angular velocity; the encoder's pulse times give the angle at every
pulse. From them: the mean rate over whole revolutions (where the scale's deviation cancels
exactly), its bias against the set rate, the rate over time by the time-difference method with and
without compensation by the self-calibrated deviation (rms and peak deviation in % of rate), and the
relative root Allan variance of angular velocity as a function of rotation angle, s(φ).

Uncertainty (GUM, JCGM 100; Monte Carlo, JCGM 101). The mean rate is the mean over the stated
window of whole revolutions: 360·R over the time of R revolutions of one line. Its inputs are the
timing jitter of the window's two end pulses (Type A, estimated from the pulse times themselves:
the same line one and two revolutions later, where the graduation cancels exactly), the DAQ
timebase (Type B, ``timebase.relative_error``: rate ∝ 1/time) and the graduation — zero, because
the window starts and ends on the same line, and m pitches are exactly 360°. The bias against the
set rate is a property of the table, not of one record: it adds the table's wander, the spread of
the single-revolution rates (Type A); both budgets are validated by the same Monte Carlo (JCGM 101
§8). The rms and peak of the rate deviation are rms/max-type: noise raises them, so their budgets
(:mod:`rotacal.uncertainty.summaries`) state the plain value, the bias of the noise whose level
the capture gives (never of a bound or a specification), and a 95 % interval for the true value.
Each s(φ) point has the χ² uncertainty of its equivalent degrees of freedom (Greenhall & Riley
2003).
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
from rotacal.encoder.selfcal import (
    UNDETECTABLE_SPEC,
    DeviationNoise,
    SelfCalibration,
    check_period,
    head_shifts,
    noise_gain,
    self_calibrate,
    undetectable_input,
    undetectable_orders,
)
from rotacal.errors import CaptureError, ConfigError
from rotacal.results import Result
from rotacal.signal._values import LARGEST, check_setting
from rotacal.signal.allan import adev_confidence_interval, edf_overlapping_adev
from rotacal.table.rate_plausibility import rate_warnings
from rotacal.uncertainty import (
    Constant,
    Input,
    InstrumentSpecs,
    UncertaintyBudget,
    linear_fit_uncertainty,
    monte_carlo,
    propagate,
    uncertainty_keys,
    validate_gum,
)
from rotacal.uncertainty.distributions import Distribution, Normal, StudentT
from rotacal.uncertainty.specs import (
    TYPE_A_ONLY_NOTE,
    corrected_note,
    spec_distribution,
    spec_input,
)
from rotacal.uncertainty.summaries import (
    COVERAGE,
    CirculantError,
    CovarianceCorrection,
    ErrorProcess,
    FilteredWhite,
    Summary,
    drop_large_dof_notes,
    mc_budget,
    rms_budget,
)

__all__ = [
    "RateResult",
    "align_deviation",
    "allan_uncertainty",
    "allan_versus_angle",
    "calibrate_rate",
    "timing_jitter",
]

FloatArray = NDArray[np.float64]

#: Allan points per decade of rotation angle.
ALLAN_POINTS_PER_DECADE = 12
#: Below this correlation a deviation curve is not trusted to match a capture.
MIN_ALIGNMENT_CORRELATION = 0.7
#: A single head's phase-correlation peak must stand this many robust spreads above the rest
#: (the largest of m Gaussian values stands about 4.5 spreads out for m ~ 10⁴).
_SINGLE_HEAD_SIGNIFICANCE = 10.0
#: Difference filters of the timing-jitter estimate: across revolutions (the same line, so the
#: graduation cancels) and along the pulses (removes the table's slow rate changes).
_REV_FILTER = np.array([1.0, -2.0, 1.0])
_PULSE_FILTER = np.array([1.0, -3.0, 3.0, -1.0])
#: Trials of the Monte Carlo that validates the mean rate's GUM budget (JCGM 101 §8).
_VALIDATION_TRIALS = 200_000
_TIMEBASE = "timebase.relative_error"
_GRADUATION = "encoder.graduation_error_arcsec"


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
    timing_jitter_s, timing_jitter_dof : float or None
        Standard deviation (s) of the timing noise of the pulses used, estimated from them (see
        :func:`timing_jitter`), and its degrees of freedom.
    timebase_correction : float
        The stated mean fractional timebase error δ̂ the rates were corrected for (rate·(1 + δ̂));
        0 when none was stated.
    rate_deviation_rms_percent_bias, rate_deviation_peak_percent_bias : float or None, %
        How much the noise whose level the capture gives (the timing jitter with two or more
        whole revolutions, the self-calibration's noise) raises the plain rms and peak; None
        when there is none (e.g. fewer than two revolutions: the jitter estimate is then only an
        upper bound, and a bound or a specification is never subtracted).
    rate_deviation_rms_percent_bias_corrected, rate_deviation_peak_percent_bias_corrected : float
        or None, %
        The plain values less that bias. The 95 % interval for the true value is the JSON
        ``rate_deviation_rms_percent_interval`` / ``rate_deviation_peak_percent_interval``.
    allan_relative_u, allan_relative_U : list of float
        Standard and expanded (p = 95 %) uncertainty of each s(φ) from its equivalent degrees
        of freedom; U is half the width of the χ² interval, so k = U/u differs per point.
    allan_relative_edf : list of float
        Equivalent degrees of freedom of each σ²(φ/ω_m) (Greenhall & Riley 2003).
    allan_relative_interval : list of [float, float]
        The 95 % χ² interval of each s(φ).
    allan_noise_alpha : list of int
        Power-law noise type α assumed for each edf (2 white PM … −2 random-walk FM), from the
        local slope of s(φ).
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

    ``to_dict()`` adds ``<name>_u``/``<name>_U`` for ``mean_rate_deg_s``, ``rate_bias_deg_s``,
    ``rate_bias_percent`` (with a set rate), ``rate_deviation_rms_percent`` and
    ``rate_deviation_peak_percent`` (with ``<name>_interval``: u the standard deviation of the
    summary's error, U half the interval's width), ``k`` (per quantity; a list for
    ``allan_relative``), ``coverage_probability`` and ``uncertainty_budgets``.
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
    timing_jitter_s: float | None = None
    timing_jitter_dof: float | None = None
    timebase_correction: float = 0.0
    rate_deviation_rms_percent_bias: float | None = None
    rate_deviation_rms_percent_bias_corrected: float | None = None
    rate_deviation_peak_percent_bias: float | None = None
    rate_deviation_peak_percent_bias_corrected: float | None = None
    allan_relative_u: list[float] = dataclasses.field(default_factory=list)
    allan_relative_U: list[float] = dataclasses.field(default_factory=list)
    allan_relative_edf: list[float] = dataclasses.field(default_factory=list)
    allan_relative_interval: list[list[float]] = dataclasses.field(default_factory=list)
    allan_noise_alpha: list[int] = dataclasses.field(default_factory=list)
    _budgets: dict[str, UncertaintyBudget] = dataclasses.field(repr=False, default_factory=dict)

    def to_dict(self) -> dict[str, Any]:
        out = super().to_dict()
        out.update(uncertainty_keys(self._budgets))
        out["k"]["allan_relative"] = [
            big / u if u > 0 else None
            for big, u in zip(self.allan_relative_U, self.allan_relative_u, strict=True)
        ]
        return out

    @property
    def budgets(self) -> dict[str, UncertaintyBudget]:
        """Uncertainty budgets by JSON key."""
        return dict(self._budgets)

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
    equal angles (the pulses), so φ = k·Δθ is exact and τ = φ/ω_m as Kokuyama et al. (2015) convert it.

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
    Kokuyama et al. (2015), §5 "Evaluation using root Allan variance": ω_i = (θ_{i+k} −
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
        # one revolution, where the scale's deviation cancels (Kokuyama et al.'s Figure 10 dip)
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


def _rho(h: FloatArray) -> FloatArray:
    """Autocorrelation of white noise filtered by ``h``, lags −(r−1) … r−1."""
    r = np.correlate(h, h, mode="full")
    return r / r[h.size - 1]


def _dof_of_mean_square(n: int, lags: NDArray[np.int64], rho: FloatArray) -> float:
    """Degrees of freedom 2·E²/Var of the mean of n squared Gaussian values whose correlation is
    ``rho`` at ``lags``: n²/Σ_ℓ (n − |ℓ|)·ρ(ℓ)² (only pairs within the series count)."""
    weight = np.maximum(n - np.abs(lags), 0).astype(np.float64)
    return float(n) ** 2 / float(np.sum(weight * rho**2))


def timing_jitter(times_s: ArrayLike, pulses_per_rev: int) -> tuple[float, float, bool]:
    """Standard deviation of the white timing noise of a pulse train, from the train itself.

    With two whole revolutions and a few pulses to spare, the same line one and two revolutions
    later gives D_j = t_{j+2m} − 2t_{j+m} + t_j, in which the scale's graduation error cancels
    exactly (m pitches are 360° from any line) and the mean rate drops out; a third difference
    along the pulses, E_j = D_{j+3} − 3D_{j+2} + 3D_{j+1} − D_j, then suppresses the table's
    slow rate changes by (2π·f/f_pulse)³. White timing noise of variance σ_t² gives
    E[E_j²] = Σh²·σ_t² with Σh² = 6·20 = 120. Shorter trains use the third difference along the
    pulses alone, which also holds the graduation error (an upper bound, flagged by the third
    return value).

    Parameters
    ----------
    times_s : array_like, s
        Pulse times of one head (or the head-averaged times of a set of heads).
    pulses_per_rev : int
        m.

    Returns
    -------
    sigma_t : float, s
        Estimated standard deviation of the timing noise of one pulse time.
    dof : float
        Its degrees of freedom, n²/Σ_ℓ (n − |ℓ|)·ρ(ℓ)² for n differences with autocorrelation ρ
        (the filtered values are correlated; Bartlett 1946) — only the pairs inside the series
        count, which matters when it is shorter than the lag 2m of the same-line difference.
    graduation_free : bool
        True when the graduation cancelled (two revolutions available).

    Raises
    ------
    CaptureError
        Fewer than 8 pulses.

    References
    ----------
    JCGM 100:2008 (GUM) §4.2 (Type A evaluation); Kokuyama et al. (2015) §3, the head output
    s_i(k) = kΔθ + 360i/n + a_i(k), a(k) periodic in k with period m, and §5 ("nearly-white
    electronic noise in the encoder output signals"); M. S. Bartlett, "On the theoretical
    specification of sampling properties of autocorrelated time series", J. R. Stat. Soc. Suppl.
    8 (1946) — the variance of a variance estimate from correlated values.
    """
    t = np.asarray(times_s, dtype=np.float64)
    m = check_pulses_per_rev(pulses_per_rev)
    h = _PULSE_FILTER
    if t.size >= 2 * m + 2 * h.size:
        d = t[2 * m :] - 2.0 * t[m:-m] + t[: -2 * m]
        e = np.convolve(d, h[::-1], mode="valid")
        norm = float(np.sum(_REV_FILTER**2) * np.sum(h**2))
        # the same-line difference correlates values m and 2m apart, the pulse filter 1 … 3
        lag_r = (np.arange(_REV_FILTER.size * 2 - 1) - (_REV_FILTER.size - 1)) * m
        lag_p = np.arange(h.size * 2 - 1) - (h.size - 1)
        lags = (lag_r[:, None] + lag_p[None, :]).ravel()
        rho = np.outer(_rho(_REV_FILTER), _rho(h)).ravel()
        dof = _dof_of_mean_square(e.size, lags, rho)
        exact = True
    elif t.size >= 2 * h.size:
        e = np.convolve(t, h[::-1], mode="valid")
        norm = float(np.sum(h**2))
        dof = _dof_of_mean_square(e.size, np.arange(h.size * 2 - 1) - (h.size - 1), _rho(h))
        exact = False
    else:
        raise CaptureError(
            f"{t.size} pulses are too few to estimate the timing noise; record more."
        )
    sigma = math.sqrt(float(np.mean(e * e)) / norm)
    return sigma, dof, exact


def _noise_alpha(phi: FloatArray, s: FloatArray) -> NDArray[np.int64]:
    """Power-law noise type of each s(φ) point from the local log-log slope μ of s(φ)."""
    if phi.size < 2:
        return np.full(phi.size, 2, dtype=np.int64)
    with np.errstate(divide="ignore"):
        mu = np.gradient(np.log(np.maximum(s, 1e-300)), np.log(phi))
    # σ ∝ τ^μ: μ = −1 white (or flicker) PM, −½ white FM, 0 flicker FM, +½ random-walk FM.
    # White PM (the pulses' electronic noise, Kokuyama et al. 2015, §5) only in the leading run of the φ⁻¹
    # slope: a steep fall further out is the 360° dip of the graduation or a fluctuation's
    # notch, over which the FM types' smaller edf is the cautious choice.
    alpha = np.select([mu <= -0.25, mu <= 0.25], [0, -1], -2).astype(np.int64)
    steep = mu <= -0.75
    lead = int(np.argmin(steep)) if not steep.all() else steep.size
    alpha[:lead] = 2
    return alpha


def allan_uncertainty(
    s: ArrayLike, angles_deg: ArrayLike, pitch_deg: float, pulses: int
) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray, FloatArray, NDArray[np.int64]]:
    """Uncertainty of each relative root Allan variance s(φ) from its equivalent dof.

    The angle is sampled at the pulses (equal angles), so the pulse times play the part of the
    phase and φ = k·Δθ the part of τ = m·τ₀: σ²(φ) is the overlapping Allan variance of cluster
    size k over N pulses. Its edf (Greenhall & Riley 2003) depends on the noise type, taken from
    the local slope of s(φ). ν·ŝ²/s² ~ χ²(ν), so u(ŝ) = ŝ/√(2ν) and the 95 % interval is
    [ŝ·√(ν/χ²₀.₉₇₅), ŝ·√(ν/χ²₀.₀₂₅)].

    Parameters
    ----------
    s : array_like
        s(φ) (dimensionless).
    angles_deg : array_like, deg
        φ of each point (whole pulses).
    pitch_deg : float, deg
        Δθ.
    pulses : int
        N, the pulses the variance was computed from.

    Returns
    -------
    u, U, edf, low, high : ndarray
        Standard uncertainty, U (half the width of the 95 % interval), edf, and the interval.
    alpha : ndarray of int
        The noise type assumed at each point.

    References
    ----------
    C. A. Greenhall and W. J. Riley, "Uncertainty of stability variances based on finite
    differences", Proc. 35th PTTI (2003); NIST SP 1065 (Riley 2008) §5.3; Kokuyama et al.
    (2015) §5, s(φ) = √σ²(φ/ω_m)/ω_m.
    """
    sv = np.asarray(s, dtype=np.float64)
    phi = np.asarray(angles_deg, dtype=np.float64)
    ks = np.maximum(1, np.rint(phi / pitch_deg)).astype(np.int64)
    alpha = _noise_alpha(phi, sv)
    edf = np.empty(sv.size)
    for a in np.unique(alpha):  # one whole-array call per noise type
        sel = alpha == a
        edf[sel] = edf_overlapping_adev(int(pulses), ks[sel], int(a))
    u = sv / np.sqrt(2.0 * edf)
    low, high = adev_confidence_interval(sv, edf, COVERAGE)
    return u, 0.5 * (high - low), edf, low, high, alpha


def _with_notes(
    b: UncertaintyBudget, notes: Sequence[str], method: str | None = None
) -> UncertaintyBudget:
    return dataclasses.replace(b, notes=(*b.notes, *notes), method=method or b.method)


def _validated(
    gum: Any,
    model: Any,
    dists: Mapping[str, Distribution],
    names: Sequence[str],
    unit: str,
    notes: Sequence[str],
) -> dict[str, UncertaintyBudget]:
    """The GUM budgets of ``names`` (the outputs of ``gum``), each validated by one Monte Carlo
    of the same model (JCGM 101 §8); where the GUM interval fails, U is half the Monte Carlo
    probabilistically symmetric 95 % interval (method "Monte Carlo")."""
    mc = monte_carlo(model, dists, trials=_VALIDATION_TRIALS, p=COVERAGE)
    results = mc if isinstance(mc, Mapping) else {names[0]: mc}
    checks = [validate_gum(gum, results[name], j=j, shortest=False) for j, name in enumerate(names)]
    # one decision for all outputs of the model (e.g. a bias in deg/s and in %): the same inputs
    # must not give a validated GUM U for one and a Monte Carlo U for the other
    passed = all(c["passed"] for c in checks)
    out: dict[str, UncertaintyBudget] = {}
    for j, name in enumerate(names):
        budget = drop_large_dof_notes(gum.budget(j))
        res, check = results[name], checks[j]
        unit_j = budget.unit or unit
        if passed:
            out[name] = _with_notes(
                budget,
                [
                    *notes,
                    f"the GUM interval agrees with a Monte Carlo of {res.trials} trials within "
                    f"the numerical tolerance {check['delta']:.2g} {unit_j} (JCGM 101 §8).",
                ],
                "GUM, validated by Monte Carlo",
            )
            continue
        lo, hi = res.interval_symmetric
        big_u = 0.5 * (hi - lo)
        worst = max(max(c["d_low"], c["d_high"]) / c["delta"] for c in checks)
        out[name] = dataclasses.replace(
            budget,
            U=big_u,
            k=big_u / budget.u if budget.u > 0 else budget.k,
            dof_eff=math.inf,
            method="Monte Carlo",
            notes=(
                *(n for n in budget.notes if "truncated to" not in n),
                *notes,
                f"the GUM interval ±{budget.U:.3g} {unit_j} is not validated by a Monte Carlo of "
                f"{res.trials} trials (an end is off by {worst:.2g} times the numerical "
                "tolerance, JCGM 101 §8; a rectangular or a t input with few degrees of freedom "
                f"dominates): U is half the Monte Carlo 95 % interval [{lo:.10g}, {hi:.10g}] "
                f"{unit_j}.",
            ),
        )
    return out


def _mean_rate_budgets(
    times: FloatArray,
    angle: FloatArray,
    m: int,
    revs: int,
    set_rate: float | None,
    specs: InstrumentSpecs | None,
    jitter: tuple[float, float, bool],
) -> dict[str, UncertaintyBudget]:
    """GUM budgets of the mean rate and of the bias against the set rate, both validated by a
    Monte Carlo of their own model (JCGM 101 §8) — the same inputs give the same U.

    References
    ----------
    JCGM 100:2008 (GUM) §3.2.4 (correction for a stated systematic effect), §4.2–4.3, §5.1
    eq. (10), G.4 (Welch–Satterthwaite); JCGM 101:2008 §6.4.9 (a Type A input with ν degrees of
    freedom as a scaled t), §8 (validation of the GUM uncertainty framework); Kokuyama et al.
    (2015) §3, §5.
    """
    sigma_t, sigma_dof, graduation_free = jitter
    tb = spec_input(specs, _TIMEBASE, name="timebase relative error", unit="")
    inputs: list[Input] = []
    dists: dict[str, Distribution] = {}
    notes: list[str] = []
    if revs >= 1:
        span = float(times[revs * m] - times[0])
        inputs.append(
            Input(
                name="pulse timing jitter at the window's two ends",
                value=0.0,
                u=math.sqrt(2.0) * sigma_t,
                dof=sigma_dof,
                distribution="normal",
                unit="s",
                source=(
                    f"Type A, σ_t = {sigma_t:.3g} s per pulse from the pulse times "
                    + (
                        "(the same line one and two revolutions later)"
                        if graduation_free
                        else "(along the pulses: includes the graduation, an upper bound)"
                    )
                ),
                description="normal, √2·σ_t",
            )
        )
        inputs.append(
            Input(
                name="graduation error over whole revolutions",
                value=0.0,
                u=0.0,
                distribution="constant",
                unit="arcsec",
                source=(
                    "exact: the window starts and ends on the same line, and m pitches make "
                    "exactly 360° whatever the scale's deviation"
                ),
                description="exact (0)",
            )
        )
        turns = 360.0 * revs

        def rate(*x: Any) -> Any:  # x = (end-pulse timing error e, graduation g[, δ])
            return (turns + x[1] / 3600.0) / (span - x[0]) * (1.0 + (x[2] if len(x) > 2 else 0.0))

        def grad(*x: float) -> list[float]:  # exact ∂ω/∂(e, g[, δ])
            f = 1.0 + (x[2] if len(x) > 2 else 0.0)
            a, t = turns + x[1] / 3600.0, span - x[0]
            return [a / t**2 * f, f / (3600.0 * t), *([a / t] if len(x) > 2 else [])]

        dists["e"] = Normal(0.0, math.sqrt(2.0) * sigma_t)
        dists["g"] = Constant(0.0)
    else:
        fit = linear_fit_uncertainty(times - times[0], angle)
        inputs.append(
            Input(
                name="straight-line fit of the angle over time",
                value=fit.slope,
                u=fit.u_slope,
                dof=float(fit.dof),
                distribution="normal",
                unit="deg/s",
                source=f"Type A, slope of {fit.n} pulses (residuals taken as independent)",
            )
        )
        notes.append(
            "less than one revolution: the graduation error the compensation leaves is not "
            "averaged out, and its correlated residuals make the fit's u a lower bound."
        )

        def rate(*x: Any) -> Any:  # x = (fitted slope[, δ])
            return x[0] * (1.0 + (x[1] if len(x) > 1 else 0.0))

        def grad(*x: float) -> list[float]:  # exact ∂ω/∂(slope[, δ])
            return [1.0 + (x[1] if len(x) > 1 else 0.0), *([x[0]] if len(x) > 1 else [])]

        dists["e"] = Normal(fit.slope, fit.u_slope)
    dist_tb = spec_distribution(specs, _TIMEBASE)
    if tb is not None and dist_tb is not None:
        inputs.append(tb)
        dists["d"] = dist_tb
        if tb.value != 0.0:
            notes.append(corrected_note(_TIMEBASE, tb.value, "", specs.source if specs else ""))
    elif specs is None:
        notes.append(TYPE_A_ONLY_NOTE)
    else:
        notes.append(
            f"{_TIMEBASE} not stated: the timebase error is not in the budget; rate ∝ 1/time, so "
            "a timebase of ±a makes the rate ∓a (relative)."
        )

    gum = propagate(
        rate,
        inputs,
        jacobian=grad,
        p=COVERAGE,
        names_out=["mean_rate_deg_s"],
        units_out=["deg/s"],
    )
    budgets = _validated(
        gum,
        lambda **kw: rate(*(kw[k] for k in dists)),
        dists,
        ["mean_rate_deg_s"],
        "deg/s",
        notes,
    )
    if set_rate is None:
        return budgets

    # the bias is the table's: its mean rate at this setting, not only in this record
    per_rev = 360.0 / np.diff(times[: revs * m + 1 : m]) if revs >= 1 else np.zeros(0)
    wander: list[Input] = []
    bias_notes: list[str] = []
    bias_dists = dict(dists)
    if per_rev.size >= 2:
        s_w = float(np.std(per_rev, ddof=1)) / math.sqrt(per_rev.size)
        wander.append(
            Input(
                name="table rate wander between revolutions",
                value=0.0,
                u=s_w,
                dof=float(per_rev.size - 1),
                distribution="normal",
                unit="deg/s",
                source=f"Type A, s/√R of {per_rev.size} single-revolution rates",
            )
        )
        bias_dists["w"] = StudentT(0.0, s_w, float(per_rev.size - 1))
        bias_notes.append(
            "the wander is the spread of the single-revolution rates (it also holds their "
            "timing jitter); it makes the bias a statement about the table at this setting, "
            "not only about this record; in the Monte Carlo it is a scaled t with ν = R − 1 "
            "(JCGM 101 §6.4.9)."
        )
    else:
        bias_notes.append(
            "fewer than two whole revolutions: the table's rate wander between records cannot be "
            "estimated, so the bias budget holds only this record's measurement."
        )
    n_in = len(inputs)
    names = ["rate_bias_deg_s", "rate_bias_percent"]

    def bias(*x: Any) -> Any:
        y = rate(*x[:n_in]) + (x[n_in] if len(x) > n_in else 0.0) - set_rate
        return np.array([y, 100.0 * y / set_rate])

    def bias_grad(*x: float) -> np.ndarray:
        g = np.array([*grad(*x[:n_in]), *([1.0] if len(x) > n_in else [])])
        return np.vstack([g, 100.0 * g / set_rate])

    def bias_mc(**kw: Any) -> dict[str, Any]:
        y = rate(*(kw[k] for k in dists)) + kw.get("w", 0.0) - set_rate
        return {names[0]: y, names[1]: 100.0 * y / set_rate}

    gb = propagate(
        bias,
        [*inputs, *wander],
        jacobian=bias_grad,
        p=COVERAGE,
        names_out=names,
        units_out=["deg/s", "%"],
    )
    extra = [*notes, *bias_notes, f"set rate {set_rate:.10g} deg/s taken as exact (the reference)."]
    budgets.update(_validated(gb, bias_mc, bias_dists, names, "deg/s", extra))
    return budgets


def _point_errors(autocov_lines: FloatArray, m: int, average: int, scale: float) -> FloatArray:
    """Autocovariance, over the rate points, of the error a curve on the scale lines gives them.

    Rate point i averages ``average`` pulse intervals from boundary line L_i = (i·A + L₀) mod m,
    so an angle error ξ(L) (arcsec) moves it by scale·(ξ(L_i + A) − ξ(L_i))/3600 (%). Along the
    points this is stationary with period P = m/gcd(A, m): c_η(k) = (scale/3600)²·[2c(kA) −
    c(kA + A) − c(kA − A)] (indices of c mod m), k = 0 … P − 1.
    """
    a = int(average)
    period = m // math.gcd(a, m)
    k = np.arange(period)
    c = autocov_lines
    lag = (k * a) % m
    eta = 2.0 * c[lag] - c[(lag + a) % m] - c[(lag - a) % m]
    return np.asarray((scale / 3600.0) ** 2 * eta, dtype=np.float64)


def _deviation_sources(
    *,
    m: int,
    heads: int,
    use_all: bool,
    compensated: bool,
    selfcal: Any,
    specs: InstrumentSpecs | None,
    average: int,
    omega: float,
    jitter: tuple[float, float, bool],
    own: tuple[list[int], int, int, float] | None = None,
) -> tuple[list[ErrorProcess], list[str]]:
    """The errors of the rate points (% of rate): the timing jitter at each point's two ends,
    and the scale-curve errors the angle still holds (the self-calibration's noise, the orders
    it cannot see, an uncompensated graduation), each in its role.

    ``own`` = (head line shifts, rate head, revolutions of the self-calibration, share of the
    rate's pulses inside them) when the curve was self-calibrated from this capture: the rate
    head's timing noise is then also in the curve (:func:`rotacal.encoder.selfcal.noise_gain`),
    and the two partly cancel — a covariance correction of −2·Cov(curve error, the head's angle
    noise) per line."""
    sigma_t, sigma_dof, graduation_free = jitter
    scale = 100.0 / (average * 360.0 / m)  # % of rate per degree of boundary angle error
    out: list[ErrorProcess] = []
    notes: list[str] = []
    out.append(
        FilteredWhite(
            Input(
                name="pulse timing jitter",
                value=0.0,
                u=sigma_t,
                dof=sigma_dof,
                distribution="normal",
                unit="s",
                source="Type A, from the pulse times (see timing_jitter)"
                + ("" if graduation_free else "; an upper bound that holds the graduation too"),
            ),
            "noise" if graduation_free else "bound",
            level="timing jitter",
            taps=np.array([-1.0, 1.0]) * scale * abs(omega),
            sigma=sigma_t,
        )
    )

    def curve(inp: Input, autocov: FloatArray, role: Any) -> CirculantError:
        return CirculantError(inp, role, autocov=_point_errors(autocov, m, average, scale))

    und, und_note = undetectable_input(specs)
    grad = spec_input(specs, _GRADUATION, name="graduation error (not compensated)", unit="arcsec")
    if compensated:
        noise: DeviationNoise | None = None
        dof_sc = math.inf
        if isinstance(selfcal, SelfCalibration):
            noise = selfcal._noise
            pb = selfcal.point_budget
            if noise is not None and pb is not None and pb.rows:
                dof_sc = pb.rows[0].dof  # the revolutions' spread (Type A) alone
            if noise is None:
                notes.append(
                    "the self-calibration has no uncertainty from its data (one revolution): its "
                    "noise is not in the budgets."
                )
        elif isinstance(selfcal, Mapping) and selfcal.get("deviation_arcsec_u") is not None:
            try:
                u_pts = np.asarray(selfcal["deviation_arcsec_u"], dtype=np.float64)
            except (TypeError, ValueError):
                raise ConfigError(
                    "the self-calibration's 'deviation_arcsec_u' must be a list of numbers."
                ) from None
            if u_pts.shape != (m,) or not np.all(np.isfinite(u_pts)) or np.any(u_pts < 0):
                raise ConfigError(
                    f"the self-calibration's 'deviation_arcsec_u' must hold {m} finite values ≥ 0."
                )
            noise = DeviationNoise.white(m, float(np.sqrt(np.mean(u_pts**2))))
            notes.append(
                "the deviation's uncertainty comes from its JSON (one u per line): taken as white "
                "noise of that size (it may already hold the undetectable orders)."
            )
        else:
            notes.append(
                "the deviation was given without its uncertainty: its noise is not in the budgets."
            )
        if noise is not None:
            inp = Input(
                name="noise of the self-calibrated deviation",
                value=0.0,
                u=noise.point_u,
                dof=dof_sc,
                distribution="normal",
                unit="arcsec",
                source="Type A, the self-calibration's budget (per line)",
                description="normal, with the curve's spectrum",
            )
            out.append(curve(inp, noise.autocov(), "noise"))
            if own is not None and own[2] >= 2:
                shifts, head, revs, share = own
                kappa = noise_gain(shifts, m, head)
                s2 = (abs(omega) * sigma_t * 3600.0) ** 2  # the head's angle noise, arcsec²
                cross = np.fft.irfft(kappa.real, m) * (s2 / revs)  # Cov(curve(L), noise(L − ℓ))
                out.append(
                    CovarianceCorrection(
                        Input(
                            name="correlation of the rate head's timing noise with the curve",
                            value=0.0,
                            u=0.0,
                            unit="arcsec",
                            source=(
                                f"the curve was self-calibrated from this capture over {revs} "
                                "revolutions, so it holds this head's own timing noise "
                                f"(gain {float(np.mean(kappa.real[kappa.real != 0])):.3g} per "
                                "order, averaged over the revolutions)"
                            ),
                        ),
                        "noise",
                        level="timing jitter",
                        autocov=_point_errors(-2.0 * share * cross, m, average, scale),
                    )
                )
    if (compensated or use_all) and und is not None:
        n_sc = heads
        if isinstance(selfcal, SelfCalibration):
            n_sc = selfcal.heads
        elif isinstance(selfcal, Mapping) and isinstance(selfcal.get("heads"), int):
            n_sc = int(selfcal["heads"])
        mask = np.zeros(m // 2 + 1, dtype=bool)
        if n_sc >= 2:
            mask[undetectable_orders(n_sc, m)] = True
        model = DeviationNoise(m, np.zeros(m // 2 + 1), mask, und.u)
        out.append(curve(und, model.autocov(undetectable=True), "bound"))
        if und_note:
            notes.append(und_note)
        notes.append(
            f"{UNDETECTABLE_SPEC} is taken as a random curve, white across the undetectable "
            "orders (the cautious choice for a rate: a smooth n-th harmonic of the same rms moves "
            "it far less)."
        )
    elif compensated or use_all:
        notes.append(
            "the orders that are multiples of the number of heads stay in the rate (no "
            f"self-calibration sees them) and are not in its uncertainty; state {UNDETECTABLE_SPEC}."
        )
    if not compensated and not use_all:
        if grad is not None:
            out.append(curve(grad, DeviationNoise.white(m, grad.u).autocov(), "bound"))
            if grad.value != 0.0:
                notes.append(
                    f"the stated mean {grad.value:g} arcsec of {_GRADUATION} is a common offset "
                    "of every reading: a rate takes angle differences, so the correction for it "
                    "is exactly 0 (GUM §3.2.4); its u stays in the budget."
                )
        else:
            notes.append(
                "the rate is not compensated: the scale's graduation error is in it but not in its "
                f"uncertainty; compensate, or state {_GRADUATION}."
            )
    return out, notes


def _rate_deviation_budgets(
    dev_pct: FloatArray,
    sources: list[ErrorProcess],
    notes: list[str],
    specs: InstrumentSpecs | None,
) -> dict[str, Summary]:
    """Budgets of the rms (closed form) and the peak (Monte Carlo) of the rate deviation.

    A rate point averages A pulse intervals, so an angle error ξ_j at pulse j (deg: the angle's
    error minus ω times the time's error) moves it by (ξ_end − ξ_start)/(A·Δθ) relative: only the
    errors at the block boundaries count.

    References
    ----------
    JCGM 101:2008 §7 (Monte Carlo); Kokuyama et al. (2015) §5 (the time-difference rate,
    10-point averaging); :mod:`rotacal.uncertainty.summaries`.
    """
    extra = [
        *notes,
        "the measurand is the table's rate deviation in this record, so the table's own "
        "fluctuation is the value, not an error; a timebase error scales every rate and the mean "
        "alike and leaves a relative deviation unchanged.",
    ]
    if specs is None:
        extra.append(TYPE_A_ONLY_NOTE)
    return {
        "rate_deviation_rms_percent": rms_budget(
            "rate_deviation_rms_percent", "%", dev_pct, sources, notes=extra
        ),
        "rate_deviation_peak_percent": mc_budget(
            "rate_deviation_peak_percent", "%", dev_pct, sources, statistic="peak", notes=extra
        ),
    }


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
    specs: InstrumentSpecs | None = None,
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
        revolution: self-calibrate this capture (as Kokuyama et al. (2015) do); with one head: no compensation.
        A curve from another capture is aligned to this one by correlation.
    head : int or "all"
        The head whose pulses give the rate (default 0, the reference, as in Kokuyama et al.'s Figure 9)
        or ``"all"`` for the head-averaged times (the average cancels every detectable order of
        the deviation, so compensation changes nothing there).
    average : int
        Pulse intervals averaged per rate point (Kokuyama et al. (2015): 10).
    set_rate_deg_s : float, deg/s, optional
        The commanded rate, for the bias.
    allan_angles_deg : array_like, deg, optional
        Angles φ for s(φ) (default 12 per decade).
    compensate : bool
        Set False to skip compensation (results then equal the uncompensated ones).
    specs : InstrumentSpecs, optional
        The lab's instrument specifications (Type B inputs). Used: ``timebase.relative_error``
        (mean rate and bias; a stated mean error δ̂ corrects the rates by (1 + δ̂), GUM §3.2.4),
        ``encoder.undetectable_harmonics_arcsec`` (what the compensation cannot remove),
        ``encoder.graduation_error_arcsec`` (an uncompensated rate; its mean is a common offset
        that cancels in every rate). None: Type A only. A specification is never subtracted from
        the rate deviation: it widens its interval only.

    Returns
    -------
    RateResult
        With uncertainty budgets of the mean rate, the bias, the rms and peak rate deviation
        (plain value, bias of the noise of known level, 95 % interval for the true value) and
        the uncertainty of every s(φ).

    Raises
    ------
    CaptureError, ConfigError
        Bad pulse trains, an unknown head, a deviation curve for another m or one that cannot be
        aligned with this capture.

    References
    ----------
    Kokuyama et al. (2015), §5: time-difference rate with 10-point averaging, Figure 9 (rate
    compensated with the extracted deviation, bias and fluctuation in % of rate), the relative root
    Allan variance s(φ) of Figure 10. JCGM 100:2008 (GUM), JCGM 101:2008 (the budgets); Greenhall
    & Riley 2003 (edf of s(φ)).
    """
    m = check_pulses_per_rev(pulses_per_rev)
    if specs is not None and not isinstance(specs, InstrumentSpecs):
        raise ConfigError(
            f"specs must be the InstrumentSpecs of load_specs(...), got {type(specs).__name__}."
        )
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
        check_setting("--set-rate-deg-s", set_rate_deg_s, positive=False, unit="deg/s")
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
    own_revs: int | None = None  # revolutions of a curve self-calibrated from this capture
    own_shifts: list[int] | None = None
    deviation: FloatArray | None = None
    shift: int | None = None
    correlation: float | None = None
    if compensate and not use_all:
        if selfcal is None and n >= 2:
            try:
                made = self_calibrate(trains, pulses_per_rev=m, specs=specs)
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
            if same and dev.shifts is not None and len(dev.shifts) == n:
                own_shifts = dev.shifts
                if isinstance(selfcal, SelfCalibration):
                    own_revs = selfcal.revolutions_used
                elif isinstance(selfcal, Mapping):
                    own_revs = _json_number(selfcal, "revolutions_used", int)
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
    jitter = timing_jitter(times, m)
    if not jitter[2]:
        notes.append(
            "fewer than two whole revolutions: the timing jitter is estimated along the pulses "
            "and holds the graduation error too (an upper bound)."
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
    set_rate: float | None = None
    if set_rate_deg_s is not None:
        set_rate = abs(float(set_rate_deg_s))
        if float(set_rate_deg_s) < 0:
            notes.append(
                "pulse times carry no sense of rotation: the mean rate is a magnitude and is "
                f"compared with |set rate| = {set_rate:g} °/s."
            )

    # ---- uncertainty
    correction = specs.mean(_TIMEBASE) if specs is not None else 0.0
    if correction != 0.0:
        notes.append(
            f"{specs.correction_note(_TIMEBASE) if specs is not None else ''} Every rate is "
            f"multiplied by 1 + δ̂ = {1 + correction:.10g}."
        )
    raw_rate = mean_rate  # in the DAQ's seconds, as the rate points
    budgets = _mean_rate_budgets(times, angle, m, revs, set_rate, specs, jitter)
    mean_rate = budgets["mean_rate_deg_s"].value  # one truth: the field is the budget's value
    bias = bias_pct = None
    if set_rate is not None:
        bias = budgets["rate_bias_deg_s"].value
        bias_pct = budgets["rate_bias_percent"].value
    sources, source_notes = _deviation_sources(
        m=m,
        heads=n,
        use_all=use_all,
        compensated=deviation is not None,
        selfcal=selfcal,
        specs=specs,
        average=int(average),
        omega=raw_rate,
        jitter=jitter,
        own=(
            None
            if own_shifts is None or own_revs is None or use_all
            else (own_shifts, k, own_revs, min(1.0, own_revs * m / max(times.size - 1, 1)))
        ),
    )
    dev_sum = _rate_deviation_budgets(dev_pct, sources, source_notes, specs)
    budgets.update({key: sm.budget for key, sm in dev_sum.items()})
    rms_sum = dev_sum["rate_deviation_rms_percent"]
    peak_sum = dev_sum["rate_deviation_peak_percent"]
    a_u, a_big_u, a_edf, a_lo, a_hi, a_alpha = allan_uncertainty(s, phi, 360.0 / m, times.size)
    factor = 1.0 + correction
    rate = rate * factor
    rate_nom = rate_nom * factor
    return RateResult(
        mean_rate_deg_s=float(mean_rate),
        rate_deviation_rms_percent=rms_sum.budget.value,  # one truth: the budgets' values
        rate_deviation_peak_percent=peak_sum.budget.value,
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
        timing_jitter_s=jitter[0],
        timing_jitter_dof=jitter[1],
        timebase_correction=correction,
        rate_deviation_rms_percent_bias=rms_sum.bias,
        rate_deviation_rms_percent_bias_corrected=rms_sum.bias_corrected,
        rate_deviation_peak_percent_bias=peak_sum.bias,
        rate_deviation_peak_percent_bias_corrected=peak_sum.bias_corrected,
        allan_relative_u=[float(x) for x in a_u],
        allan_relative_U=[float(x) for x in a_big_u],
        allan_relative_edf=[float(x) for x in a_edf],
        allan_relative_interval=[[float(lo), float(hi)] for lo, hi in zip(a_lo, a_hi, strict=True)],
        allan_noise_alpha=[int(x) for x in a_alpha],
        _budgets=budgets,
        warnings=tuple(
            rate_warnings(
                mean_rate_deg_s=float(mean_rate),
                set_rate_deg_s=set_rate,
                time_s=t_avg,
                deviation_percent=dev_pct,
            )
        ),
    )
