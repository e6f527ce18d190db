"""Sinusoidal-motion calibration of a low-frequency angular-acceleration rotary table (Feng et al. 2023).

Three measurement schemes of Feng et al. (2023) give the table's angular displacement θ(t):

- OSE: an optical shaft encoder's quadrature signals, demodulated into angle (§3, eqs. (3)–(8));
- LTS: a laser triangulation sensor on a reflector at radius R, θ = arctan(D/R) (§5, eq. (15));
- FOG: a rate gyro whose output is fitted directly and integrated analytically (§4, eqs. (9)–(14)).

Each cuts n whole motion periods bounded by 2n+1 reversing moments (§3.3), fits the fundamental and
its harmonics by the IEEE 1057 multi-harmonic sine fit with the frequency refined, and reports the
amplitude, frequency, angular-acceleration amplitude, THD (eq. (1)) and, given the set values, their
errors and the angular position error (eq. (2)).

References
----------
Feng R., Yan J., Wu Y., Yu N., Yin X. (2023). Methods for Comprehensive Calibration of a
Low-Frequency Angular Acceleration Rotary Table. Sensors 23, 4876. doi:10.3390/s23104876
IEEE Std 1057-2017, IEEE Standard for Digitizing Waveform Recorders, §4.1.3 (sine fitting).
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import numpy as np

from rotacal._threads import one_blas_thread
from rotacal.encoder import QuadratureCorrection, correct_quadrature, demodulate
from rotacal.errors import CaptureError, ConfigError
from rotacal.results import Result, with_warnings
from rotacal.signal import (
    SineFit,
    check_sampling,
    displacement_amplitudes_from_rate,
    estimate_frequency,
    fit_harmonics,
    fit_sine_3p,
    snr_db,
)
from rotacal.signal._values import check_magnitudes, check_setting
from rotacal.signal.clipping import check_clipping
from rotacal.table.motion_drift import (
    detrended_angle,
    drift_fields,
    drift_free_hysteresis,
    drift_note,
    drift_warnings,
    fit_motion,
    prefit_drift,
)
from rotacal.table.motion_lts_fog import (
    check_reach,
    extreme_reversals,
    fog_angle,
    fog_bias_note,
    lts_angle,
    model_zero_crossings,
)
from rotacal.table.motion_plausibility import motion_warnings
from rotacal.table.motion_uncertainty import (
    ReversalDetection,
    comparison_budgets,
    fit_dof,
    motion_budgets,
)
from rotacal.uncertainty import InstrumentSpecs, UncertaintyBudget, uncertainty_keys

__all__ = [
    "MotionResult",
    "SchemeComparison",
    "calibrate_encoder_motion",
    "calibrate_fog_motion",
    "calibrate_lts_motion",
    "compare_schemes",
    "extreme_reversals",
    "position_error",
]

#: Keys that appear in the JSON only when they apply (set values given, or the FOG scheme).
_OPTIONAL_KEYS = (
    "set_amplitude_deg",
    "set_frequency_hz",
    "amplitude_error_percent",
    "frequency_error_percent",
    "angular_acceleration_error_percent",
    "position_error_max_deg",
    "position_error_rms_deg",
    "snr_db",
    "drift_deg_s",
    "drift_deg_s_u",
    "rate_drift_deg_s2",
    "rate_drift_deg_s2_u",
)
_PLOT_POINTS = 20_000
#: Samples (evenly strided) for the Heydemann ellipse fit: parameter noise ~σ/√(2·10⁵), negligible.
_ELLIPSE_POINTS = 200_000


@dataclasses.dataclass(frozen=True)
class MotionResult(Result):
    """Result of a sinusoidal-motion calibration (JSON keys of INTERFACE.md, ``motion``)."""

    scheme: str
    amplitude_deg: float
    frequency_hz: float
    angular_acceleration_amplitude_deg_s2: float
    thd_percent: float
    harmonic_amplitudes_deg: np.ndarray
    reversal_times_s: np.ndarray
    periods_used: int
    analysis_start_s: float
    analysis_stop_s: float
    harmonics: int
    offset_deg: float
    residual_rms_deg: float
    # Standard uncertainties: the u of the budgets in ``_budgets`` (one number, one truth).
    amplitude_deg_u: float
    frequency_hz_u: float
    thd_percent_u: float
    samples_used: int
    notes: tuple[str, ...] = ()
    set_amplitude_deg: float | None = None
    set_frequency_hz: float | None = None
    amplitude_error_percent: float | None = None
    frequency_error_percent: float | None = None
    angular_acceleration_error_percent: float | None = None
    position_error_max_deg: float | None = None
    position_error_rms_deg: float | None = None
    snr_db: float | None = None
    # With drift=True (--drift): the fitted drift, see rotacal.table.motion_drift.drift_fields.
    drift_deg_s: float | None = None
    drift_deg_s_u: float | None = None
    rate_drift_deg_s2: float | None = None
    rate_drift_deg_s2_u: float | None = None
    # THD near zero (see rotacal.table.motion_uncertainty.thd_uncertainty), in %: the noise bias
    # of the plain THD (Monte Carlo) and the bias-corrected THD (noise power removed); the 95 %
    # interval for the true THD is the budget's (JSON ``thd_percent_interval``).
    thd_percent_bias: float = math.nan
    thd_percent_bias_corrected: float = math.nan
    # For figures and reports only (not in JSON): the fit, decimated samples, scheme details.
    _fit: SineFit | None = dataclasses.field(default=None, repr=False, compare=False)
    _plot: dict[str, Any] = dataclasses.field(default_factory=dict, repr=False, compare=False)
    # The uncertainty budget of every quantity, by its JSON key.
    _budgets: dict[str, UncertaintyBudget] = dataclasses.field(
        default_factory=dict, repr=False, compare=False
    )

    def to_dict(self) -> dict[str, Any]:
        """JSON of INTERFACE.md ``motion`` plus ``<name>_u``, ``<name>_U``, ``k``,
        ``coverage_probability`` and ``uncertainty_budgets`` for every quantity."""
        out = super().to_dict()
        for key in _OPTIONAL_KEYS:
            if out.get(key) is None:
                out.pop(key, None)
        out.update(uncertainty_keys(self._budgets) if self._budgets else {})
        return out


@dataclasses.dataclass(frozen=True)
class SchemeComparison(Result):
    """Two schemes on the same run, as one row of Feng et al. (2023) Table 1."""

    reference_scheme: str
    other_scheme: str
    thd_reference_percent: float
    thd_other_percent: float
    thd_difference_percent: float
    thd_difference_percent_u: float
    amplitude_difference_percent: float
    frequency_difference_percent: float
    snr_db: float | None
    _budgets: dict[str, UncertaintyBudget] = dataclasses.field(
        default_factory=dict, repr=False, compare=False
    )
    # For reports only (not in JSON): the two THDs' budgets (reference, other), by which a
    # report states each THD with its interval.
    _thd_budgets: tuple[UncertaintyBudget, UncertaintyBudget] | None = dataclasses.field(
        default=None, repr=False, compare=False
    )

    def to_dict(self) -> dict[str, Any]:
        """The row's JSON plus ``<name>_u``, ``<name>_U``, ``k`` of each difference."""
        out = super().to_dict()
        out.update(uncertainty_keys(self._budgets) if self._budgets else {})
        return out


def _plot_stride(n: int) -> int:
    return max(1, n // _PLOT_POINTS)


def _displacement_plot(
    t: np.ndarray, angle: np.ndarray, seg: slice, fit: SineFit
) -> dict[str, Any]:
    """Decimated copies for the figures: the whole record, and the fit's residual over ``seg``."""
    step = _plot_stride(t.size)
    t_seg = t[seg][:: _plot_stride(angle[seg].size)]
    a_seg = angle[seg][:: _plot_stride(angle[seg].size)]
    return {
        "t": t[::step],
        "angle_deg": angle[::step],
        "t_used": t_seg,
        "residual_deg": a_seg - fit.evaluate(t_seg),  # the model only where it is plotted: fast
        "unit": "deg",
    }


def _check_settings(harmonics: int, periods: int | None) -> None:
    if harmonics < 1:
        raise ConfigError(f"--harmonics must be at least 1, got {harmonics}")
    if periods is not None and periods < 1:
        raise ConfigError(f"--periods must be at least 1, got {periods}")


def _check_set_values(set_amplitude_deg: float | None, set_frequency_hz: float | None) -> None:
    """Both set values or neither; each finite, > 0 and within float64's working range."""
    if set_amplitude_deg is None and set_frequency_hz is None:
        return
    if set_amplitude_deg is None or set_frequency_hz is None:
        raise ConfigError("give both --set-amplitude-deg and --set-frequency-hz, or neither")
    check_setting("--set-amplitude-deg", set_amplitude_deg, unit="deg")
    check_setting("--set-frequency-hz", set_frequency_hz, unit="Hz")


def check_pair_shapes(t: np.ndarray, name: str, y: np.ndarray) -> None:
    """``time_s`` and the signal ``name``: 1-D, equally long, enough samples for a sine fit."""
    if t.ndim != 1 or y.ndim != 1:
        raise CaptureError(f"time_s and {name} must be 1-D arrays")
    if t.size != y.size:
        raise CaptureError(f"time_s has {t.size} samples but {name} has {y.size}")
    if t.size < 16:
        raise CaptureError(f"the capture has only {t.size} samples: too few for a sine fit")


def _check_samples(t: np.ndarray, name: str, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Shapes, NaN, time order and gaps of a one-signal capture; a constant signal is refused."""
    t = np.asarray(t, dtype=float)
    y = np.asarray(y, dtype=float)
    check_pair_shapes(t, name, y)
    bad = np.flatnonzero(~np.isfinite(y))
    if bad.size:
        raise CaptureError(f"column {name} has a non-finite value (NaN or inf) at sample {bad[0]}")
    check_magnitudes(name, y)
    check_sampling(t, "time_s")
    if np.ptp(y) == 0:
        raise CaptureError(f"column {name} is constant: the table does not move in this capture")
    return t, y


def position_error(
    t: np.ndarray,
    angle_deg: np.ndarray,
    set_amplitude_deg: float,
    set_frequency_hz: float,
) -> np.ndarray:
    """Angular position error against the ideal sinusoid of set amplitude and frequency.

    ``ap_err(t_i) = ap_meas(t_i) − ap_ideal(t_i)`` (Feng et al. 2023, eq. (2)). The ideal motion has the
    set amplitude and frequency; its phase and mean are not set by the table's settings (the DAQ's
    time origin is arbitrary), so rotacal takes them from an IEEE 1057 three-parameter fit at the set
    frequency — the ideal sinusoid that lies closest to the measurement.

    Parameters
    ----------
    t : array, s
    angle_deg : array, deg — the measured angular displacement ap_meas.
    set_amplitude_deg : float, deg
    set_frequency_hz : float, Hz

    Returns
    -------
    array, deg — ap_err at every sample.

    References
    ----------
    Feng et al. (2023), Sensors 23:4876, eq. (2); IEEE Std 1057-2017, §4.1.3.1 (three-parameter fit).
    """
    if not set_amplitude_deg > 0 or not set_frequency_hz > 0:
        raise ConfigError("set amplitude and set frequency must both be positive")
    fit3 = fit_sine_3p(t, angle_deg, set_frequency_hz)
    phase = float(fit3.phases_rad[0])
    ideal = fit3.offset + set_amplitude_deg * np.sin(
        2 * np.pi * set_frequency_hz * (t - fit3.t_ref_s) + phase
    )
    return np.asarray(angle_deg - ideal)


def _finish(
    *,
    scheme: str,
    fit: SineFit,
    displacement_amplitudes: np.ndarray,
    displacement_amplitudes_u: np.ndarray,
    offset_deg: float,
    residual_rms_deg: float,
    reversal_times: np.ndarray,
    periods: int,
    t_used: np.ndarray,
    angle_used: np.ndarray | None,
    set_amplitude_deg: float | None,
    set_frequency_hz: float | None,
    notes: list[str],
    snr: float | None,
    plot: dict[str, Any],
    detection: ReversalDetection,
    specs: InstrumentSpecs | None = None,
    radius_mm: float | None = None,
) -> MotionResult:
    _check_set_values(set_amplitude_deg, set_frequency_hz)
    note = drift_note(scheme, fit)
    if note is not None:
        notes = [*notes, note]
    unc = motion_budgets(
        scheme=scheme,  # type: ignore[arg-type]
        fit=fit,
        displacement_amplitudes=np.asarray(displacement_amplitudes, dtype=float),
        displacement_amplitudes_u=np.asarray(displacement_amplitudes_u, dtype=float),
        reversal_times_s=np.asarray(reversal_times, dtype=float),
        detection=detection,
        specs=specs,
        set_amplitude_deg=set_amplitude_deg,
        set_frequency_hz=set_frequency_hz,
        radius_mm=radius_mm,
    )
    budgets = unc.budgets
    # for the report's table of harmonics: each A_h's u (the fit's, Type A) and its ν
    plot["harmonic_amplitudes_u_deg"] = unc.amplitudes_u_deg
    plot["fit_dof"] = fit_dof(fit)
    # One truth: every reported value is its budget's (corrected for stated systematic effects).
    amp = budgets["amplitude_deg"].value
    freq = budgets["frequency_hz"].value
    extra: dict[str, Any] = {}
    if set_amplitude_deg is not None and set_frequency_hz is not None:
        extra.update(
            set_amplitude_deg=float(set_amplitude_deg),
            set_frequency_hz=float(set_frequency_hz),
            amplitude_error_percent=budgets["amplitude_error_percent"].value,
            frequency_error_percent=budgets["frequency_error_percent"].value,
            angular_acceleration_error_percent=budgets["angular_acceleration_error_percent"].value,
        )
        if angle_used is not None:
            t_true = t_used
            if unc.timebase_error != 0.0:  # eq. (2) in true time (the set frequency is true)
                t0 = float(detection.capture_start_s)
                t_true = t0 + (t_used - t0) / (1.0 + unc.timebase_error)
            if scheme != "fog":  # the FOG's angle is integrated from the rate less its trend
                angle_used = detrended_angle(fit, t_used, angle_used)
            err = position_error(t_true, angle_used, set_amplitude_deg, set_frequency_hz)
            extra.update(
                position_error_max_deg=float(np.max(np.abs(err))),
                position_error_rms_deg=float(np.sqrt(np.mean(err**2))),
            )
            step = _plot_stride(err.size)
            plot["position_error_deg"] = err[::step]
    result = MotionResult(
        scheme=scheme,
        amplitude_deg=amp,
        frequency_hz=freq,
        angular_acceleration_amplitude_deg_s2=budgets[
            "angular_acceleration_amplitude_deg_s2"
        ].value,
        thd_percent=unc.thd.plain,
        harmonic_amplitudes_deg=unc.amplitudes_deg,
        reversal_times_s=unc.reversal_times_s,
        periods_used=int(periods),
        analysis_start_s=float(t_used[0]),
        analysis_stop_s=float(t_used[-1]),
        harmonics=int(displacement_amplitudes.size),
        offset_deg=float(offset_deg),
        residual_rms_deg=float(residual_rms_deg),
        amplitude_deg_u=budgets["amplitude_deg"].u,
        frequency_hz_u=budgets["frequency_hz"].u,
        thd_percent_u=budgets["thd_percent"].u,
        samples_used=int(t_used.size),
        notes=tuple(notes),
        snr_db=snr,
        thd_percent_bias=unc.thd.bias,
        thd_percent_bias_corrected=unc.thd.bias_corrected,
        _fit=fit,
        _plot=plot,
        _budgets=budgets,
        **extra,
        **drift_fields(scheme, fit),
    )
    drift = drift_warnings(scheme, fit, budgets, t_used[-1] - t_used[0])
    # an unfitted drift is the lack of fit already named: no second line for it
    residual = None if drift else plot.get("residual_deg", plot.get("residual_deg_s"))
    plausibility = motion_warnings(
        scheme,
        amplitude_deg=amp,
        frequency_hz=freq,
        harmonics=int(displacement_amplitudes.size),
        fundamental=float(fit.amplitudes[0]),
        residual=None if residual is None else np.asarray(residual, dtype=float),
        residual_unit="deg/s" if "residual_deg_s" in plot else "deg",
        set_amplitude_deg=set_amplitude_deg,
        set_frequency_hz=set_frequency_hz,
    )
    return with_warnings(result, [*drift, *plausibility])


def _cut(
    reversal_idx: np.ndarray,
    periods: int | None,
    what: str,
    span_deg: float | None = None,
    net_deg: float | None = None,
) -> tuple[int, int, int]:
    """First and last sample of n whole periods bounded by 2n+1 reversals (Feng et al. 2023, §3.3)."""
    available = (reversal_idx.size - 1) // 2
    if available < 1:
        moved = f" (the angle spans {span_deg:.3g}°)" if span_deg is not None else ""
        if span_deg is not None and net_deg is not None and abs(net_deg) > 0.5 * span_deg:
            moved = f"{moved[:-1]} and ends {net_deg:+.3g}° from its start: the table drifts, "
            moved += "rerun with --drift)"
        raise CaptureError(
            f"found {reversal_idx.size} reversing moment(s) in the {what}{moved}: at least 3 are "
            "needed for one whole motion period — record longer, or check that the table moves"
        )
    n = available if periods is None else periods
    if n > available:
        raise CaptureError(
            f"--periods {periods} asks for more than the {available} whole period(s) the {what} holds"
        )
    return int(reversal_idx[0]), int(reversal_idx[2 * n]), n


@one_blas_thread
def calibrate_encoder_motion(
    t: np.ndarray,
    a: np.ndarray,
    b: np.ndarray,
    *,
    lines: int,
    harmonics: int = 10,
    periods: int | None = None,
    set_amplitude_deg: float | None = None,
    set_frequency_hz: float | None = None,
    correction: QuadratureCorrection | None = None,
    specs: InstrumentSpecs | None = None,
    allow_clipped: bool = False,
    drift: bool = False,
    hysteresis_subintervals: int | None = None,
) -> MotionResult:
    """Sinusoidal-motion calibration from an optical shaft encoder (the OSE scheme).

    Heydemann-corrected quadrature demodulation, 12 subintervals per signal period, reversing moments by
    the odd/even trend-change rule and their precise point (eqs. (3)–(8)), n whole periods cut between
    2n+1 reversals, then the IEEE 1057 multi-harmonic fit of the angular displacement and THD (eq. (1)).

    Parameters
    ----------
    t : array, s — sample times, increasing.
    a, b : array — quadrature signals, a ≈ cos φ, b ≈ sin φ, φ = 2π·lines·θ/360 (any unit, e.g. V).
    lines : int — encoder lines (signal periods) per revolution.
    harmonics : int — N_H, highest harmonic in the fit and the THD (default 10).
    periods : int, optional — whole motion periods to analyse (default: all the capture holds).
    set_amplitude_deg, set_frequency_hz : float, optional — the table's set values (deg, Hz).
    correction : QuadratureCorrection, optional — a known correction instead of fitting one.
    specs : InstrumentSpecs, optional — the lab's instrument specifications (Type B inputs:
        ``timebase.relative_error``, ``encoder.graduation_error_arcsec``); None: Type A only.
    allow_clipped : bool — analyse a capture whose a or b sits at the rails
        (:mod:`rotacal.signal.clipping`) anyway, naming the clipping in ``warnings``; by default
        it is refused with a CaptureError.
    drift : bool — fit a linear drift term beside the harmonics, ``drift_deg_s`` (deg/s; see
        :mod:`rotacal.table.motion_drift`); without it a drift that matters is in ``warnings``.
    hysteresis_subintervals : int, optional — the reversal rule's hysteresis (30° subintervals;
        :func:`~rotacal.encoder.find_reversals`; 1 or 2: the paper's odd/even rule alone). Its
        default with ``drift``: :func:`~rotacal.table.motion_drift.drift_free_hysteresis`.

    Returns
    -------
    MotionResult
        With the uncertainty budget of every quantity (:mod:`rotacal.table.motion_uncertainty`).

    References
    ----------
    Feng et al. (2023), Sensors 23:4876, §3 and eqs. (1)–(8); IEEE Std 1057-2017, §4.1.3;
    JCGM 100:2008 and JCGM 101:2008 (budgets).
    """
    _check_settings(harmonics, periods)
    if int(lines) != lines or lines < 1:
        raise ConfigError(f"--lines must be a positive whole number, got {lines}")
    # demodulate checks the samples (lengths, NaN, time order, clipping, quadrature).
    demod = demodulate(
        t,
        a,
        b,
        int(lines),
        correction=correction,
        hysteresis_subintervals=hysteresis_subintervals,
        max_points=_ELLIPSE_POINTS,
        allow_clipped=allow_clipped,
        hysteresis_from=drift_free_hysteresis() if drift else None,
    )
    t, a, b = demod.time_s, np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    span = demod.angle_max_deg - demod.angle_min_deg
    angle = demod.angle_deg
    net = None if drift else float(angle[-1] - angle[0])  # for the hint of _cut's error
    first, last, n = _cut(demod.reversals.indices, periods, "encoder capture", span, net)
    seg = slice(first, last + 1)
    f0 = n / (t[last] - t[first])
    fit = fit_motion(t[seg], angle[seg], f0, harmonics, drift)
    notes = [f"quadrature correction: {demod.correction.method}"]
    step = _plot_stride(t.size)
    plot = {
        **_displacement_plot(t, angle, seg, fit),
        "reversal_kinds": demod.reversals.kinds,
        "lissajous_raw": (a[::step], b[::step]),
        "lissajous_corrected": correct_quadrature(a[::step], b[::step], demod.correction),
        "correction": demod.correction,
    }
    detection = ReversalDetection(
        method="argmax",
        fit=fit,
        sample_interval_s=float(t[last] - t[first]) / max(last - first, 1),
        capture_start_s=float(t[0]),
    )
    result = _finish(
        scheme="encoder",
        fit=fit,
        displacement_amplitudes=fit.amplitudes,
        displacement_amplitudes_u=fit.amplitudes_u,
        offset_deg=fit.offset,
        residual_rms_deg=fit.residual_rms,
        reversal_times=demod.reversals.times_s,
        periods=n,
        t_used=t[seg],
        angle_used=angle[seg],
        set_amplitude_deg=set_amplitude_deg,
        set_frequency_hz=set_frequency_hz,
        notes=notes,
        snr=None,
        plot=plot,
        detection=detection,
        specs=specs,
    )
    return with_warnings(result, demod.warnings)


def check_lts_settings(harmonics: int, periods: int | None, radius_mm: float) -> None:
    """The LTS scheme's settings: harmonics, periods and a finite, positive R (mm)."""
    _check_settings(harmonics, periods)
    if not radius_mm > 0:
        raise ConfigError(f"--radius-mm must be positive, got {radius_mm}")
    check_setting("--radius-mm", radius_mm, unit="mm")


@one_blas_thread
def calibrate_lts_motion(
    t: np.ndarray,
    displacement_mm: np.ndarray,
    *,
    radius_mm: float,
    harmonics: int = 10,
    periods: int | None = None,
    set_amplitude_deg: float | None = None,
    set_frequency_hz: float | None = None,
    specs: InstrumentSpecs | None = None,
    allow_clipped: bool = False,
    drift: bool = False,
) -> MotionResult:
    """Sinusoidal-motion calibration from a laser triangulation sensor (the LTS scheme).

    θ_i = arctan(D_i / R) (eq. (15)); reversing moments by extreme values; n whole periods between
    2n+1 reversals; IEEE 1057 multi-harmonic fit of θ and THD (eq. (1)).

    Parameters
    ----------
    t : array, s.
    displacement_mm : array, mm — the LTS reading D of the reflector at radius R.
    radius_mm : float, mm — R, distance from the laser spot to the table's axis.
    harmonics, periods, set_amplitude_deg, set_frequency_hz : as `calibrate_encoder_motion`.
    specs : InstrumentSpecs, optional — Type B inputs (``timebase.relative_error``,
        ``lts.radius_mm`` — its value must be ``radius_mm`` —, ``lts.resolution_um``).
    allow_clipped : bool — analyse a displacement at the sensor's rails anyway (named in
        ``warnings``); refused by default (:mod:`rotacal.signal.clipping`).
    drift : bool — as `calibrate_encoder_motion`; the reversals' trigger then follows the drift
        of a first fit of the whole capture (:func:`extreme_reversals`).

    References
    ----------
    Feng et al. (2023), Sensors 23:4876, §5, eqs. (1), (2), (15); IEEE Std 1057-2017, §4.1.3;
    JCGM 100:2008 and JCGM 101:2008 (budgets).
    """
    check_lts_settings(harmonics, periods, radius_mm)
    t, d = _check_samples(t, "displacement_mm", displacement_mm)
    clipped = check_clipping({"displacement_mm": d}, allow_clipped=allow_clipped)
    check_reach(float(np.max(np.abs(d))), radius_mm)
    angle = lts_angle(d, radius_mm)
    result = displacement_motion(
        t, angle, harmonics=harmonics, periods=periods, drift=drift, what="LTS capture",
        notes=[f"θ = arctan(D/R), R = {radius_mm:g} mm"],
        set_values=(set_amplitude_deg, set_frequency_hz), specs=specs, radius_mm=float(radius_mm),
    )  # fmt: skip
    return with_warnings(result, clipped)


def displacement_motion(
    t: np.ndarray,
    angle: np.ndarray,
    *,
    harmonics: int,
    periods: int | None,
    drift: bool,
    what: str,
    notes: list[str],
    set_values: tuple[float | None, float | None],
    specs: InstrumentSpecs | None,
    radius_mm: float | None = None,
) -> MotionResult:
    """The calibration of a checked displacement θ (deg) read directly, in memory: reversing
    moments by extreme values, n whole periods between 2n + 1 reversals, the IEEE 1057 fit and
    the LTS scheme's budgets (Feng et al. (2023), §5, eqs. (1), (2)). ``what`` names the capture
    in a refusal; ``set_values`` are the set amplitude (deg) and frequency (Hz); an LTS gives its
    ``radius_mm``, an angle readout none."""
    trend = prefit_drift(t, angle, harmonics) if drift else 0.0
    rev_times = extreme_reversals(t, angle, drift=trend)
    rev_idx = np.searchsorted(t, rev_times).clip(0, t.size - 1)
    net = None if drift else float(angle[-1] - angle[0])
    first, last, n = _cut(rev_idx, periods, what, float(np.ptp(angle)), net)
    seg = slice(first, last + 1)
    f0 = n / (rev_times[2 * n] - rev_times[0])
    fit = fit_motion(t[seg], angle[seg], f0, harmonics, drift)
    detection = ReversalDetection(
        method="parabola",
        fit=fit,
        sample_interval_s=float(t[last] - t[first]) / max(last - first, 1),
        capture_start_s=float(t[0]),
        half_window_s=1.0 / (20.0 * fit.frequency_hz),  # extreme_reversals: ±period/20
    )
    return _finish(
        scheme="lts",
        fit=fit,
        displacement_amplitudes=fit.amplitudes,
        displacement_amplitudes_u=fit.amplitudes_u,
        offset_deg=fit.offset,
        residual_rms_deg=fit.residual_rms,
        reversal_times=rev_times,
        periods=n,
        t_used=t[seg],
        angle_used=angle[seg],
        set_amplitude_deg=set_values[0],
        set_frequency_hz=set_values[1],
        notes=notes,
        snr=None,
        plot=_displacement_plot(t, angle, seg, fit),
        detection=detection,
        specs=specs,
        radius_mm=radius_mm,
    )


@one_blas_thread
def calibrate_fog_motion(
    t: np.ndarray,
    rate_deg_s: np.ndarray,
    *,
    harmonics: int = 10,
    periods: int | None = None,
    set_amplitude_deg: float | None = None,
    set_frequency_hz: float | None = None,
    specs: InstrumentSpecs | None = None,
    allow_clipped: bool = False,
    drift: bool = False,
) -> MotionResult:
    """Sinusoidal-motion calibration from a fibre-optic gyro's rate (the FOG scheme).

    The rate is sine-fitted directly, θ̇(t) = D0 + Σ A'_h sin(2π h f t + φ_h) (eqs. (9)–(10)), and
    integrated analytically: the displacement harmonics are A'_h/(2π h f) (eqs. (11)–(13)), which
    give THD_θ (eq. (14)). No noise filter and no numerical integration: the fit's robustness does
    both jobs, as Feng et al. (2023) intend. The reversing moments are the zero crossings of the fitted rate;
    n whole periods are cut between 2n+1 of them and the fit is repeated on that span. The SNR is the
    fitted signal without its constant term over the residual, in dB (seed §5). The position error
    (eq. (2)) uses the measured rate minus the fitted D0, integrated by the trapezoid rule.

    Parameters
    ----------
    t : array, s.
    rate_deg_s : array, deg/s.
    harmonics, periods, set_amplitude_deg, set_frequency_hz : as `calibrate_encoder_motion`.
    specs : InstrumentSpecs, optional — Type B inputs (``timebase.relative_error``,
        ``fog.scale_factor_relative``).
    allow_clipped : bool — analyse a rate at the gyro's rails anyway (named in ``warnings``);
        refused by default (:mod:`rotacal.signal.clipping`).
    drift : bool — fit the rate as ``D0 + D1·(t − t_ref) + harmonics`` and report D0 (a steady
        table drift plus the gyro's bias, which D0 takes anyway) as ``drift_deg_s`` and D1 as
        ``rate_drift_deg_s2`` (:mod:`rotacal.table.motion_drift`).

    References
    ----------
    Feng et al. (2023), Sensors 23:4876, §4, eqs. (9)–(14), §5 (SNR); IEEE Std 1057-2017, §4.1.3;
    JCGM 100:2008 and JCGM 101:2008 (budgets).
    """
    _check_settings(harmonics, periods)
    t, w = _check_samples(t, "rate_deg_s", rate_deg_s)
    clipped = check_clipping({"rate_deg_s": w}, allow_clipped=allow_clipped)
    f_start = estimate_frequency(t, w)
    first_fit = fit_harmonics(t, w, frequency_hz=f_start, harmonics=harmonics, drift=drift)
    rev_times = model_zero_crossings(first_fit, t)[0]
    rev_idx = np.searchsorted(t, rev_times).clip(0, t.size - 1)
    first, last, n = _cut(rev_idx, periods, "FOG capture")
    seg = slice(first, last + 1)
    fit = fit_motion(t[seg], w[seg], first_fit.frequency_hz, harmonics, drift, rate=True)
    disp = displacement_amplitudes_from_rate(fit.amplitudes, fit.frequency_hz)
    disp_u = displacement_amplitudes_from_rate(fit.amplitudes_u, fit.frequency_hz)
    tt, ww = t[seg], w[seg]
    angle = fog_angle(tt, ww, fit)
    snr = snr_db(ww, fit, tt)
    step = _plot_stride(t.size)
    seg_step = _plot_stride(tt.size)
    plot = {
        "t": t[::step],
        "rate_deg_s": w[::step],
        "t_used": tt[::seg_step],
        "residual_deg_s": ww[::seg_step] - fit.evaluate(tt[::seg_step]),
        "angle_deg_integrated": angle[::seg_step],
        "unit": "deg/s",
    }
    detection = ReversalDetection(
        method="rate_zero",
        fit=first_fit,
        sample_interval_s=float(t[-1] - t[0]) / max(t.size - 1, 1),
        capture_start_s=float(t[0]),
    )
    result = _finish(
        scheme="fog",
        fit=fit,
        displacement_amplitudes=disp,
        displacement_amplitudes_u=disp_u,
        offset_deg=float(np.mean(angle)),
        residual_rms_deg=float(fit.residual_rms / (2 * math.pi * fit.frequency_hz)),
        reversal_times=rev_times,
        periods=n,
        t_used=tt,
        angle_used=angle,
        set_amplitude_deg=set_amplitude_deg,
        set_frequency_hz=set_frequency_hz,
        notes=[fog_bias_note(fit)],
        snr=float(snr),
        plot=plot,
        detection=detection,
        specs=specs,
    )
    return with_warnings(result, clipped)


def compare_schemes(reference: MotionResult, other: MotionResult) -> SchemeComparison:
    """Compare two schemes that measured the same run, as a row of Feng et al. (2023) Table 1.

    Every difference is ``reference − other``: THD in percentage points (Feng et al.'s "Difference
    Value of THD": the combined OSE/LTS scheme minus the FOG), amplitude and frequency in % of the
    reference's value. Each difference has a budget (:func:`~rotacal.table.motion_uncertainty.
    comparison_budgets`) from the two results' budgets; ``thd_difference_percent_u`` is its u.

    References
    ----------
    Feng et al. (2023), Sensors 23:4876, §5, Table 1; JCGM 100:2008 (GUM) eq. (10).
    """
    if not reference._budgets or not other._budgets:
        raise ConfigError(
            "compare_schemes needs two results of rotacal's motion calibrations (with budgets)"
        )
    budgets = comparison_budgets(
        reference._budgets,
        other._budgets,
        reference_scheme=reference.scheme,
        other_scheme=other.scheme,
    )
    return SchemeComparison(
        reference_scheme=reference.scheme,
        other_scheme=other.scheme,
        thd_reference_percent=reference.thd_percent,
        thd_other_percent=other.thd_percent,
        thd_difference_percent=reference.thd_percent - other.thd_percent,
        thd_difference_percent_u=budgets["thd_difference_percent"].u,
        amplitude_difference_percent=100
        * (reference.amplitude_deg - other.amplitude_deg)
        / reference.amplitude_deg,
        frequency_difference_percent=100
        * (reference.frequency_hz - other.frequency_hz)
        / reference.frequency_hz,
        snr_db=other.snr_db if other.snr_db is not None else reference.snr_db,
        _budgets=budgets,
        _thd_budgets=(reference._budgets["thd_percent"], other._budgets["thd_percent"]),
    )
