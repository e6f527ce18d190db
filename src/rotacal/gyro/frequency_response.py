"""Dynamic calibration of a gyro on a sinusoidal table: amplitude ratio and phase per frequency.

Each capture holds one frequency: the table's angle θ (from its encoder's quadrature signals,
demodulated as in Feng et al. 2023 §3, or an ``angle_deg`` column) and the DUT's rate, sampled
together (``time_s``). Both are sine-fitted (IEEE Std 1057-2017 §4.1.3, as Feng et al. 2023 fit
the table's motion, eqs. (9)–(13)): θ with its frequency refined, the DUT rate at that frequency.
The reference rate is the derivative of the fitted angle's fundamental, amplitude 2πf·A_θ and
phase φ_θ + 90°. Per capture:

* ``amplitude_ratio`` = A_rate / (2πf·A_θ), in dB 20·log10 of it;
* ``phase_deg`` = φ_rate − (φ_θ + 90°): the DUT's rate against the reference rate, negative when
  the DUT lags; unwrapped across the captures in frequency order, starting within ±180° at the
  lowest frequency.

Uncertainties (GUM, JCGM 100:2008, first-order propagation, §5.1.2): the amplitude ratio's from
the relative uncertainties of A_rate, A_θ and f (the fits' covariances scaled by their residual
variance, white noise assumed; the fits' phases refer to the middle of the record, where they are
uncorrelated with f to first order, so f's uncertainty does not enter the phase); the phase's from
u(φ_rate) and u(φ_θ), and a Type B input for the **time skew** between the reference and DUT
channels: a capture states one ``time_s`` for both, but a multiplexing DAQ converts its channels
one after another within a sample interval Δt, so unless the skew bound is given
(``channel_skew_s``, 0 for simultaneous sampling) it is taken as rectangular within ±Δt (GUM
§4.3.7), u = Δt/√3, contributing 360·f·u degrees. The skew is common to every capture: in the
model fit it is a fully correlated input (:mod:`rotacal.gyro.frequency_model`). A stated timebase
error (``specs``: ``timebase.relative_error``) corrects the frequencies and the ratios and is
propagated likewise (:func:`calibrate_frequency_response`).

References
----------
IEEE Std 1057-2017, §4.1.3 (sine fits); Feng et al. 2023, Sensors 23:4876, §3 and eqs. (9)–(13);
JCGM 100:2008 (GUM); IEEE Std 952 and IEEE Std 1431-2004 (a gyro's frequency response, one of
their test procedures).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from rotacal.errors import CaptureError, ConfigError
from rotacal.gyro.frequency_model import CommonInput, SecondOrderFit, fit_second_order
from rotacal.results import Result
from rotacal.uncertainty.quantiles import norm_ppf, t_ppf
from rotacal.uncertainty.specs import InstrumentSpecs

__all__ = [
    "FrequencyPoint",
    "FrequencyResponse",
    "calibrate_frequency_response",
    "response_at_frequency",
]

#: The DUT rate is refused as not sinusoidal above this THD (%) of its fit.
MAX_THD_PERCENT = 10.0
#: Repeated frequencies: two captures whose fitted frequencies differ by less than this share.
SAME_FREQUENCY_RELATIVE = 1e-3
#: The DUT's fundamental must stand this many standard uncertainties above zero.
MIN_AMPLITUDE_SIGMAS = 5.0
#: Coverage probability of the expanded uncertainties (``*_U``, the summary and the report).
COVERAGE_PROBABILITY = 0.95
_DB = 20.0 / math.log(10.0)


@dataclasses.dataclass(frozen=True)
class FrequencyPoint(Result):
    """One capture's amplitude ratio and phase (see the module docstring).

    Attributes
    ----------
    frequency_hz, frequency_hz_u : the table's fitted frequency and its u (Hz).
    amplitude_ratio, amplitude_ratio_u : DUT rate / reference rate (-), u (-).
    phase_deg, phase_deg_u : DUT rate against reference rate (deg, in (−180, 180]), u with the
        skew (deg).
    phase_deg_u_fit : u of the phase from the fits only (deg), the weight in the model fit.
    reference_amplitude_deg : A_θ (deg).
    reference_rate_amplitude_deg_s : 2πf·A_θ (deg/s).
    dut_amplitude_deg_s : A_rate (deg/s).
    dut_thd_percent : THD of the DUT rate's fit (%), Feng et al. 2023 eq. (1).
    reference_rate_thd_percent : THD of the table's rate (%), from θ's harmonics h·A_h (eq. (14)
        read backwards); the DUT is refused when its THD exceeds this by more than
        ``max_thd_percent`` (root-sum-square).
    dut_snr_db : 20·log10 of the DUT's fundamental rms over its residual rms (dB).
    channel_skew_s : the skew bound used (s), rectangular half-width.
    harmonics : harmonics fitted to θ and to the rate.
    samples : samples in the capture.
    """

    frequency_hz: float
    frequency_hz_u: float
    amplitude_ratio: float
    amplitude_ratio_u: float
    phase_deg: float
    phase_deg_u: float
    phase_deg_u_fit: float
    reference_amplitude_deg: float
    reference_rate_amplitude_deg_s: float
    dut_amplitude_deg_s: float
    dut_thd_percent: float
    reference_rate_thd_percent: float
    dut_snr_db: float
    channel_skew_s: float
    harmonics: int
    samples: int
    _time_s: np.ndarray = dataclasses.field(repr=False)
    _dut_residual_deg_s: np.ndarray = dataclasses.field(repr=False)


def _as_column(name: str, values: Any) -> np.ndarray:
    x = np.asarray(values, dtype=np.float64)
    if x.ndim != 1:
        raise CaptureError(f"column {name!r} must be one-dimensional, got shape {x.shape}")
    return x


def _reference_angle(
    t: np.ndarray,
    n: int,
    angle_deg: Any,
    a: Any,
    b: Any,
    lines: int | None,
    allow_clipped: bool,
) -> tuple[np.ndarray, tuple[str, ...]]:
    """θ (deg) of the table: the encoder's signals demodulated (given with ``lines``), else the
    angle column."""
    encoder = a is not None and b is not None and lines is not None
    if angle_deg is not None and not encoder:
        theta = _as_column("angle_deg", angle_deg)
        if theta.size != n:
            raise CaptureError(
                f"the reference angle_deg has {theta.size} samples and the DUT's rate_deg_s "
                f"{n}: reference and DUT must have the same length (sampled together)"
            )
        return theta, ()
    if a is None or b is None:
        raise CaptureError(
            "no reference: the capture needs angle_deg, or the encoder's a and b with --lines"
        )
    if lines is None:
        raise ConfigError("the reference is an encoder's a and b: give its --lines")
    aa, bb = _as_column("a", a), _as_column("b", b)
    if aa.size != n or bb.size != n:
        raise CaptureError(
            f"the reference a, b have {aa.size}, {bb.size} samples and the DUT's rate_deg_s "
            f"{n}: reference and DUT must have the same length (sampled together)"
        )
    from rotacal.encoder import demodulate

    demod = demodulate(t, aa, bb, lines, allow_clipped=allow_clipped)
    return demod.angle_deg, tuple(demod.warnings)


def _fitted_harmonics(harmonics: int, f0: float, fs: float) -> int:
    """``harmonics``, lowered so that the highest stays below the Nyquist frequency."""
    below = max(1, math.ceil(0.5 * fs / f0) - 1)
    return max(1, min(int(harmonics), below))


def _wrap_deg(x: float) -> float:
    """x (deg) in (−180, 180]."""
    y = math.remainder(x, 360.0)
    return 180.0 if y == -180.0 else y


def response_at_frequency(
    time_s: Any,
    rate_deg_s: Any,
    *,
    angle_deg: Any = None,
    a: Any = None,
    b: Any = None,
    lines: int | None = None,
    harmonics: int = 5,
    channel_skew_s: float | None = None,
    max_thd_percent: float = MAX_THD_PERCENT,
    allow_clipped: bool = False,
) -> FrequencyPoint:
    """Amplitude ratio and phase of the DUT's rate against the table's at one frequency.

    Parameters
    ----------
    time_s : array_like — sample times (s), strictly increasing, shared by every column.
    rate_deg_s : array_like — the DUT's rate (deg/s).
    angle_deg : array_like, optional — the table's angle θ (deg), the reference; or
    a, b, lines : the encoder's quadrature signals (signal units) and its lines per revolution (-),
        the reference when all three are given.
    harmonics : int — harmonics fitted to θ and to the rate (lowered below Nyquist).
    channel_skew_s : float, optional — bound of the time skew between reference and DUT (s),
        rectangular; None: one mean sample interval (module docstring).
    max_thd_percent : float — the DUT rate is refused as not sinusoidal when its THD exceeds the
        table rate's by more than this (%, root-sum-square).
    allow_clipped : bool — analyse clipped signals anyway (named in ``warnings``).

    Returns
    -------
    FrequencyPoint

    Raises
    ------
    CaptureError
        Different lengths, no reference, a DUT rate that is not sinusoidal (THD above
        ``max_thd_percent``, residual above the sine, no fundamental), bad sampling, clipping.

    References
    ----------
    IEEE Std 1057-2017 §4.1.3; Feng et al. 2023, Sensors 23:4876, eqs. (1), (9)–(13); JCGM 100:2008.
    """
    from rotacal.signal import (
        ClippedSignalError,
        check_sampling,
        estimate_frequency,
        find_clipping,
        fit_harmonics,
        thd_percent,
    )

    t = _as_column("time_s", time_s)
    rate = _as_column("rate_deg_s", rate_deg_s)
    if rate.size != t.size:
        raise CaptureError(
            f"rate_deg_s has {rate.size} samples and time_s {t.size}: they must be sampled together"
        )
    if t.size < 16:
        raise CaptureError(f"the capture holds {t.size} samples: too short for a sine fit")
    check_sampling(t, "time_s")
    if channel_skew_s is not None and not (math.isfinite(channel_skew_s) and channel_skew_s >= 0):
        raise ConfigError(f"channel_skew_s must be a time ≥ 0 s, got {channel_skew_s!r}")
    theta, warnings = _reference_angle(t, rate.size, angle_deg, a, b, lines, allow_clipped)
    if not np.all(np.isfinite(rate)):
        raise CaptureError(
            f"rate_deg_s holds a non-finite value at row {np.argmin(np.isfinite(rate))}"
        )
    clip = find_clipping(rate, "rate_deg_s")
    if clip is not None:
        if not allow_clipped:
            raise ClippedSignalError(clip.refusal(), (clip,))
        warnings = (*warnings, clip.warning())
    fs = (t.size - 1) / float(t[-1] - t[0])
    f0 = estimate_frequency(t, theta)
    nh = _fitted_harmonics(harmonics, f0, fs)
    ref = fit_harmonics(t, theta, f0, harmonics=nh)
    f = ref.frequency_hz
    dut = fit_harmonics(t, rate, f, harmonics=nh, refine_frequency=False)
    a_dut, u_dut = float(dut.amplitudes[0]), float(dut.amplitudes_u[0])
    if not a_dut > MIN_AMPLITUDE_SIGMAS * u_dut:
        raise CaptureError(
            f"the DUT's rate shows no sine at the table's {f:.6g} Hz (amplitude {a_dut:.3g} ± "
            f"{u_dut:.2g} deg/s): is rate_deg_s the gyro on this table?"
        )
    thd = thd_percent(dut.amplitudes) if nh > 1 else 0.0
    # the table's own distortion reaches the DUT too: judge only what the DUT adds to it
    h = np.arange(1, nh + 1)
    thd_ref = thd_percent(h * ref.amplitudes) if nh > 1 else 0.0
    excess = math.sqrt(max(thd * thd - thd_ref * thd_ref, 0.0))
    if excess > max_thd_percent:
        raise CaptureError(
            f"the DUT's rate is not sinusoidal at {f:.6g} Hz: THD {thd:.3g} % where the "
            f"table's rate has {thd_ref:.3g} %, {excess:.3g} % beyond it (above "
            f"{max_thd_percent:g} %); a response ratio of a distorted output is not defined"
        )
    if dut.residual_rms > a_dut / math.sqrt(2.0):
        raise CaptureError(
            f"the DUT's rate is not sinusoidal at {f:.6g} Hz: its residual ({dut.residual_rms:.3g}"
            f" deg/s rms) exceeds the sine ({a_dut / math.sqrt(2.0):.3g} deg/s rms)"
        )
    w = 2.0 * math.pi * f
    a_ref = float(ref.amplitudes[0])
    ratio = a_dut / (w * a_ref)
    rel = math.hypot(u_dut / a_dut, float(ref.amplitudes_u[0]) / a_ref, ref.frequency_u_hz / f)
    phase = _wrap_deg(math.degrees(float(dut.phases_rad[0]) - float(ref.phases_rad[0])) - 90.0)
    assert dut.phases_u_rad is not None and ref.phases_u_rad is not None
    u_fit = math.degrees(math.hypot(float(dut.phases_u_rad[0]), float(ref.phases_u_rad[0])))
    skew = 1.0 / fs if channel_skew_s is None else float(channel_skew_s)
    u_skew = 360.0 * f * skew / math.sqrt(3.0)
    snr = (
        20.0 * math.log10(a_dut / math.sqrt(2.0) / dut.residual_rms)
        if dut.residual_rms > 0
        else math.inf
    )
    return FrequencyPoint(
        frequency_hz=f,
        frequency_hz_u=ref.frequency_u_hz,
        amplitude_ratio=ratio,
        amplitude_ratio_u=ratio * rel,
        phase_deg=phase,
        phase_deg_u=math.hypot(u_fit, u_skew),
        phase_deg_u_fit=u_fit,
        reference_amplitude_deg=a_ref,
        reference_rate_amplitude_deg_s=w * a_ref,
        dut_amplitude_deg_s=a_dut,
        dut_thd_percent=thd,
        reference_rate_thd_percent=thd_ref,
        dut_snr_db=snr,
        channel_skew_s=skew,
        harmonics=nh,
        samples=int(t.size),
        _time_s=t,
        _dut_residual_deg_s=rate - dut.evaluate(t),
        warnings=warnings,
    )


@dataclasses.dataclass(frozen=True)
class FrequencyResponse(Result):
    """A gyro's frequency response on a sinusoidal table (INTERFACE.md, ``gyro frequency-response``).

    The lists hold one value per capture, in the order the captures were given; ``phase_deg`` is
    unwrapped across them in frequency order. ``k`` holds the coverage factor of each point's
    list (``amplitude_ratio``, ``phase_deg``: the normal 1.96 of their many degrees of freedom) and
    of each model parameter (1.96, or Student's t for the fit's ν when the Birge ratio scaled the
    covariance), for ``coverage_probability``; ``*_U`` = k·u of the model's parameters. The model is H(s) = ωn²/(s² + 2ζωn·s + ωn²)
    (× e^(−sτ) with ``delay``), see :mod:`rotacal.gyro.frequency_model`.
    """

    frequency_hz: list[float]
    frequency_hz_u: list[float]
    amplitude_ratio: list[float]
    amplitude_ratio_u: list[float]
    amplitude_ratio_db: list[float]
    amplitude_ratio_db_u: list[float]
    phase_deg: list[float]
    phase_deg_u: list[float]
    natural_frequency_hz: float
    natural_frequency_hz_u: float
    damping_ratio: float
    damping_ratio_u: float
    bandwidth_hz: float
    bandwidth_hz_u: float
    delay_s: float | None
    delay_s_u: float | None
    model: str
    correlation_natural_frequency_damping: float
    chi_squared: float
    degrees_of_freedom: int
    dut_thd_percent: list[float]
    reference_rate_thd_percent: list[float]
    dut_snr_db: list[float]
    reference_amplitude_deg: list[float]
    channel_skew_s: list[float]
    captures: list[str]
    coverage_probability: float
    k: dict[str, float]
    natural_frequency_hz_U: float
    damping_ratio_U: float
    bandwidth_hz_U: float
    _points: tuple[FrequencyPoint, ...] = dataclasses.field(repr=False)
    _fit: SecondOrderFit = dataclasses.field(repr=False)


def _unwrapped(phases: np.ndarray, order: np.ndarray) -> np.ndarray:
    """Phases (deg) made continuous along increasing frequency (each within 180° of the last)."""
    out = phases.copy()
    out[order] = np.degrees(np.unwrap(np.radians(phases[order])))
    return out


def calibrate_frequency_response(
    captures: Sequence[Mapping[str, Any]],
    *,
    names: Sequence[str] | None = None,
    lines: int | None = None,
    harmonics: int = 5,
    channel_skew_s: float | None = None,
    delay: bool = False,
    max_thd_percent: float = MAX_THD_PERCENT,
    allow_clipped: bool = False,
    specs: InstrumentSpecs | None = None,
) -> FrequencyResponse:
    """Amplitude ratio and phase at each capture's frequency, and the second-order model fitted.

    Parameters
    ----------
    captures : sequence of mappings — each with ``time_s`` (s), ``rate_deg_s`` (deg/s) and the
        reference: ``angle_deg`` (deg), or ``a`` and ``b`` (signal units) with ``lines``.
    names : sequence of str, optional — a name per capture, for messages and ``captures``.
    lines : int, optional — encoder lines per revolution (-).
    harmonics, channel_skew_s, max_thd_percent, allow_clipped : see :func:`response_at_frequency`.
    delay : bool — fit a pure delay τ with the second-order model.
    specs : InstrumentSpecs, optional — Type B inputs: ``timebase.relative_error`` e (its mean
        corrects every frequency, f·(1 + e), and ratio, R/(1 + e): the table's rate comes from
        the stamped times, the DUT's does not; its u enters both and, fully correlated, the
        model's parameters; the phases do not depend on it, both channels sharing one clock).

    Returns
    -------
    FrequencyResponse

    Raises
    ------
    CaptureError
        A capture refused (:func:`response_at_frequency`, named), fewer frequencies than model
        parameters, two captures at the same frequency, a DUT in antiphase, points that do not
        determine the model.
    """
    names = [f"capture {i + 1}" for i in range(len(captures))] if names is None else list(names)
    if len(names) != len(captures):
        raise ConfigError(f"{len(names)} names for {len(captures)} captures")
    n_par = 3 if delay else 2
    if len(captures) < n_par:
        raise CaptureError(
            f"{len(captures)} capture{'s' if len(captures) != 1 else ''} (frequencies) for a "
            f"model of {n_par} parameters: give captures at {n_par} or more frequencies"
        )
    points = []
    for name, cap in zip(names, captures, strict=True):
        missing = [c for c in ("time_s", "rate_deg_s") if c not in cap]
        if missing:
            raise CaptureError(f"{name}: no column {missing[0]!r} (the DUT's rate and its times)")
        try:
            points.append(
                response_at_frequency(
                    cap["time_s"],
                    cap["rate_deg_s"],
                    angle_deg=cap.get("angle_deg"),
                    a=cap.get("a"),
                    b=cap.get("b"),
                    lines=lines,
                    harmonics=harmonics,
                    channel_skew_s=channel_skew_s,
                    max_thd_percent=max_thd_percent,
                    allow_clipped=allow_clipped,
                )
            )
        except CaptureError as e:
            raise type(e)(f"{name}: {e}") from None
    e0 = 0.0 if specs is None else float(specs.mean("timebase.relative_error"))
    dist = None if specs is None else specs.get("timebase.relative_error")
    u_e = 0.0 if dist is None else float(dist.std)
    # a clock e fast stamps every interval (1 + e) long: the true frequency is f·(1 + e), the
    # table's true rate 2πf(1 + e)·A_θ, so the ratio is R/(1 + e); the phase does not move (both
    # channels are sampled at the same instants)
    f = np.array([p.frequency_hz for p in points]) * (1.0 + e0)
    f_u = np.hypot(np.array([p.frequency_hz_u for p in points]) * (1.0 + e0), f * u_e)
    order = np.argsort(f, kind="stable")
    close = np.flatnonzero(np.diff(f[order]) <= SAME_FREQUENCY_RELATIVE * f[order][1:])
    if close.size:
        i, j = sorted((int(order[close[0]]), int(order[close[0] + 1])))
        raise CaptureError(
            f"{names[i]} and {names[j]} are at the same frequency ({f[i]:.6g} and {f[j]:.6g} "
            "Hz): each capture must be one distinct frequency"
        )
    phase = _unwrapped(np.array([p.phase_deg for p in points]), order)
    if abs(phase[order[0]]) > 90.0:
        raise CaptureError(
            f"the DUT's rate is in antiphase with the table's at the lowest frequency "
            f"({phase[order[0]]:.1f}° at {f[order[0]]:.6g} Hz): its sensitive axis points "
            "against the encoder's positive direction; negate rate_deg_s (CLI: --dut-sign -1)"
        )
    ratio = np.array([p.amplitude_ratio for p in points]) / (1.0 + e0)
    ratio_u_fit = np.array([p.amplitude_ratio_u for p in points]) / (1.0 + e0)
    ratio_u = np.hypot(ratio_u_fit, ratio * u_e)
    skews = {p.channel_skew_s for p in points}
    none = np.zeros(f.size)
    common = [CommonInput("channel skew", none, -360.0 * f, max(skews) / math.sqrt(3.0))]
    if u_e > 0:
        # the frequencies scale with (1 + e): fn with them, τ against them
        common.append(CommonInput("timebase", -ratio, none, u_e, np.array([1.0, 0.0, -1.0])))
    fit = fit_second_order(
        f,
        ratio,
        ratio_u_fit,
        phase,
        np.array([p.phase_deg_u_fit for p in points]),
        delay=delay,
        common=common,
    )
    warnings = [w for p in points for w in p.warnings]
    if fit.lack_of_fit:
        warnings.append(
            f"the second-order model does not fit the points (χ² = {fit.chi_squared:.3g} for "
            f"{fit.degrees_of_freedom} degrees of freedom): its uncertainties are scaled by "
            f"χ²/ν = {fit.birge_ratio:.3g}"
            + ("" if delay else "; a digital gyro's delay may be missing (--delay)")
        )
    if fit.bandwidth_hz > f.max():
        warnings.append(
            f"the bandwidth {fit.bandwidth_hz:.4g} Hz lies above the highest frequency measured "
            f"({f.max():.4g} Hz): it is the model's extrapolation"
        )
    if len(skews) > 1:
        warnings.append(
            "the captures have different sampling rates; the largest skew bound was taken as "
            "common to all in the model fit"
        )
    cov = fit.covariance
    corr = float(cov[0, 1] / math.sqrt(cov[0, 0] * cov[1, 1]))
    k_point = norm_ppf(0.5 + COVERAGE_PROBABILITY / 2.0)
    k_model = (
        t_ppf(0.5 + COVERAGE_PROBABILITY / 2.0, fit.degrees_of_freedom)
        if fit.birge_ratio > 1.0
        else k_point
    )
    model = "H(s) = ωn²/(s² + 2ζωn·s + ωn²)" + (" · exp(−s·τ)" if delay else "")
    return FrequencyResponse(
        frequency_hz=f.tolist(),
        frequency_hz_u=f_u.tolist(),
        amplitude_ratio=ratio.tolist(),
        amplitude_ratio_u=ratio_u.tolist(),
        amplitude_ratio_db=(20.0 * np.log10(ratio)).tolist(),
        amplitude_ratio_db_u=(_DB * ratio_u / ratio).tolist(),
        phase_deg=phase.tolist(),
        phase_deg_u=[p.phase_deg_u for p in points],
        natural_frequency_hz=fit.natural_frequency_hz,
        natural_frequency_hz_u=fit.natural_frequency_hz_u,
        damping_ratio=fit.damping_ratio,
        damping_ratio_u=fit.damping_ratio_u,
        bandwidth_hz=fit.bandwidth_hz,
        bandwidth_hz_u=fit.bandwidth_hz_u,
        delay_s=fit.delay_s,
        delay_s_u=fit.delay_s_u,
        model=model,
        correlation_natural_frequency_damping=corr,
        chi_squared=fit.chi_squared,
        degrees_of_freedom=fit.degrees_of_freedom,
        dut_thd_percent=[p.dut_thd_percent for p in points],
        reference_rate_thd_percent=[p.reference_rate_thd_percent for p in points],
        dut_snr_db=[p.dut_snr_db for p in points],
        reference_amplitude_deg=[p.reference_amplitude_deg for p in points],
        channel_skew_s=[p.channel_skew_s for p in points],
        captures=list(names),
        coverage_probability=COVERAGE_PROBABILITY,
        k={
            "amplitude_ratio": k_point,
            "phase_deg": k_point,
            **dict.fromkeys(("natural_frequency_hz", "damping_ratio", "bandwidth_hz"), k_model),
            **({"delay_s": k_model} if delay else {}),
        },
        natural_frequency_hz_U=k_model * fit.natural_frequency_hz_u,
        damping_ratio_U=k_model * fit.damping_ratio_u,
        bandwidth_hz_U=k_model * fit.bandwidth_hz_u,
        _points=tuple(points),
        _fit=fit,
        warnings=tuple(dict.fromkeys(warnings)),
    )
