"""The plain names of rotacal's quantities: one glossary for reports, certificates and the docs.

A result's JSON keeps its keys (``angular_acceleration_amplitude_deg_s2``); a person reads
"angular-acceleration amplitude" in °/s². :data:`GLOSSARY` maps each key that a report or a
certificate shows to a :class:`Term`: its name in plain words, the unit it is stated in, a symbol
where the literature has one, and one sentence of meaning. The HTML reports, the PDF certificate
and the documentation's list of JSON keys all read it, so a quantity has one name everywhere.

Keys of array quantities name the array (``harmonic_amplitudes_deg``); a report adds the index.
"""

from __future__ import annotations

import dataclasses

__all__ = ["GLOSSARY", "Term", "term", "unit_of"]


@dataclasses.dataclass(frozen=True)
class Term:
    """How a quantity reads for a person.

    Attributes
    ----------
    name : str
        Plain words, starting lower-case unless a proper noun or an abbreviation starts it
        ("angular-acceleration amplitude", "THD").
    unit : str
        The unit the JSON value is in, as printed ("°/s²", "%", "arcsec"; empty: none).
    meaning : str
        One sentence: what the quantity is and, where it helps, how it is defined.
    symbol : str
        The symbol of the literature, where there is one ("A", "THD", "K").
    """

    name: str
    unit: str
    meaning: str
    symbol: str = ""


def _t(name: str, unit: str, meaning: str, symbol: str = "") -> Term:
    return Term(name=name, unit=unit, meaning=meaning, symbol=symbol)


#: Every quantity a report or certificate names, by its JSON key.
GLOSSARY: dict[str, Term] = {
    # --- sinusoidal motion (Feng et al. 2023) ---
    "amplitude_deg": _t(
        "amplitude of the angular displacement",
        "°",
        "Amplitude of the fundamental of the fitted angular displacement.",
        "A",
    ),
    "frequency_hz": _t("frequency", "Hz", "Frequency of the fundamental of the motion.", "f"),
    "angular_acceleration_amplitude_deg_s2": _t(
        "angular-acceleration amplitude",
        "°/s²",
        "Amplitude of the angular acceleration of the fundamental, A·(2πf)².",
        "α",
    ),
    "thd_percent": _t(
        "total harmonic distortion",
        "%",
        "Root-sum-square of the harmonic amplitudes 2…N of the angular displacement over the "
        "fundamental's (IEEE Std 1057 sine fitting; Feng et al. 2023, eq. 1).",
        "THD",
    ),
    "harmonic_amplitudes_deg": _t(
        "harmonic amplitudes", "°", "Amplitude of each harmonic h = 1…N of the displacement."
    ),
    "reversal_times_s": _t(
        "reversing moments",
        "s",
        "Times at which the table's motion reverses (Feng et al. 2023, eqs. 7–8).",
    ),
    "periods_used": _t("periods analysed", "", "Whole periods of motion the fit uses."),
    "amplitude_error_percent": _t(
        "amplitude error", "%", "Measured amplitude against the set amplitude."
    ),
    "frequency_error_percent": _t(
        "frequency error", "%", "Measured frequency against the set frequency."
    ),
    "angular_acceleration_error_percent": _t(
        "angular-acceleration amplitude error",
        "%",
        "Measured angular-acceleration amplitude against the one of the set motion.",
    ),
    "position_error_max_deg": _t(
        "angular position error, largest",
        "°",
        "Largest |measured − ideal| displacement over the analysed periods "
        "(Feng et al. 2023, eq. 2).",
    ),
    "position_error_rms_deg": _t(
        "angular position error, rms",
        "°",
        "Root-mean-square of measured − ideal displacement (Feng et al. 2023, eq. 2).",
    ),
    "snr_db": _t(
        "signal-to-noise ratio",
        "dB",
        "Power of the fitted rate signal without its constant term over the residual's.",
        "SNR",
    ),
    "residual_rms_deg": _t(
        "fit residual, rms", "°", "Root-mean-square of measurement minus the harmonic fit."
    ),
    "drift_deg_s": _t("drift", "°/s", "Linear drift of the displacement fitted beside the motion."),
    "rate_drift_deg_s2": _t("rate drift", "°/s²", "Linear drift of the rate (FOG scheme)."),
    "thd_difference_percent": _t(
        "THD difference of two schemes",
        "pp",
        "THD by the combined scheme minus THD by the FOG, in percentage points.",
    ),
    "amplitude_difference_percent": _t(
        "amplitude difference of two schemes", "%", "Relative difference of the two amplitudes."
    ),
    "frequency_difference_percent": _t(
        "frequency difference of two schemes", "%", "Relative difference of the two frequencies."
    ),
    "thd_percent_bias": _t(
        "noise bias of the THD",
        "pp",
        "How far noise pushes the plain THD up at the bias-corrected THD (Monte Carlo).",
    ),
    "thd_percent_bias_corrected": _t(
        "THD, bias-corrected",
        "%",
        "The THD with the noise power of the fitted harmonics removed.",
    ),
    "thd_reference_percent": _t(
        "THD by the combined scheme", "%", "THD of the run by the encoder or the LTS."
    ),
    "thd_other_percent": _t("THD by the FOG", "%", "THD of the same run by the fibre-optic gyro."),
    "set_amplitude_deg": _t(
        "set amplitude", "°", "Amplitude the table was set to; the reference of the errors."
    ),
    "set_frequency_hz": _t(
        "set frequency", "Hz", "Frequency the table was set to; the reference of the errors."
    ),
    "samples_used": _t("samples analysed", "", "Samples in the whole periods the fit uses."),
    "harmonics": _t("harmonics fitted", "", "Number N of harmonics of the multi-harmonic fit."),
    "offset_deg": _t("mean displacement", "°", "Constant term of the fitted displacement."),
    "analysis_start_s": _t("start of the analysed span", "s", "First reversing moment used."),
    "analysis_stop_s": _t("end of the analysed span", "s", "Last reversing moment used."),
    # --- angular-velocity standard (Kokuyama et al. 2015) ---
    "deviation_arcsec": _t(
        "scale deviation",
        "arcsec",
        "Angle deviation of the encoder's graduation at each pulse of head 0, zero mean.",
    ),
    "deviation_pp_arcsec": _t(
        "scale deviation, peak-to-peak", "arcsec", "Largest minus smallest scale deviation."
    ),
    "deviation_rms_arcsec": _t("scale deviation, rms", "arcsec", "Rms of the scale deviation."),
    "mean_rate_deg_s": _t("mean rate", "°/s", "Angular velocity averaged over whole revolutions."),
    "rate_bias_deg_s": _t("rate bias", "°/s", "Mean rate minus the set rate."),
    "rate_bias_percent": _t("rate bias", "%", "Mean rate against the set rate, relative."),
    "rate_deviation_rms_percent": _t(
        "rate fluctuation, rms", "%", "Rms of the rate's deviation from its mean, relative."
    ),
    "rate_deviation_peak_percent": _t(
        "rate fluctuation, largest", "%", "Largest |deviation| of the rate from its mean, relative."
    ),
    "allan_angle_deg": _t(
        "rotation angles of the Allan analysis",
        "°",
        "Angles φ over which the rate's root Allan variance s(φ) is evaluated.",
        "φ",
    ),
    "allan_relative": _t(
        "relative root Allan variance",
        "",
        "Root Allan variance of the rate over the angle φ, relative to the mean rate "
        "(Kokuyama et al. 2015, §5).",
        "s(φ)",
    ),
    # --- gyroscopes ---
    "scale_factor": _t(
        "scale factor",
        "output units per °/s",
        "Slope of the least-squares line of the gyro's output against the table's rate.",
        "S",
    ),
    "bias": _t("bias", "output units", "Output at zero rate (intercept of the line).", "B"),
    "nonlinearity_percent_fs": _t(
        "nonlinearity",
        "% FS",
        "Largest deviation from the line over the full-scale output, 100·max|δ|/(|S|·FS).",
    ),
    "full_scale_deg_s": _t("full scale", "°/s", "Full-scale rate of the nonlinearity.", "FS"),
    "scale_misalignment": _t(
        "scale and misalignment matrix",
        "",
        "K in u = K·ω + b: the diagonal holds the scale factors, the off-diagonal terms the "
        "cross-axis sensitivities.",
        "K",
    ),
    "residual_rms": _t(
        "fit residual, rms", "output units", "Rms of the outputs minus the calibrated model."
    ),
    "drift_coefficients": _t(
        "drift coefficients",
        "°/h, °/h/g, °/h/g²",
        "The gyro's g-independent, g-sensitive and g²-sensitive drift terms.",
        "D",
    ),
    "arw_deg_rt_h": _t(
        "angle random walk",
        "°/√h",
        "White rate noise, read off the Allan deviation's −½ slope at τ = 1 s (IEEE Std 952).",
        "N",
    ),
    "bias_instability_deg_h": _t(
        "bias instability",
        "°/h",
        "Flicker floor of the Allan deviation divided by 0.664 (IEEE Std 952).",
        "B",
    ),
    "rrw_deg_h_rt_h": _t(
        "rate random walk",
        "°/h/√h",
        "Random walk of the rate, read off the Allan deviation's +½ slope (IEEE Std 952).",
        "K",
    ),
    "rate_ramp_deg_h2": _t(
        "rate ramp", "°/h²", "Steady change of the rate, off the Allan deviation's +1 slope.", "R"
    ),
    "quantization_deg": _t(
        "quantization noise", "°", "Angle quantization, off the Allan deviation's −1 slope.", "Q"
    ),
    # --- encoder self-calibration, gyro triad, rate standard (Kokuyama et al. 2015; Ferraris
    # et al. 1995) ---
    "head_offsets_arcsec": _t(
        "head placement errors",
        "arcsec",
        "Each read head's position against its nominal i·360/n, modulo one pitch; head 0 is the "
        "reference.",
    ),
    "repeatability_rms_arcsec": _t(
        "repeatability, rms",
        "arcsec",
        "Rms of each revolution's deviation curve minus the mean curve.",
    ),
    "repeatability_pp_arcsec": _t(
        "repeatability, peak-to-peak",
        "arcsec",
        "Largest peak-to-peak of a revolution's curve minus the mean curve.",
    ),
    "closure_residual_rms_arcsec": _t(
        "closure residual, rms",
        "arcsec",
        "Rms of what the fitted deviation leaves unexplained in the head differences.",
    ),
    "revolutions_used": _t("revolutions averaged", "", "Whole revolutions the curve averages."),
    "harmonic_amplitudes_arcsec": _t(
        "harmonic amplitudes of the scale deviation",
        "arcsec",
        "Amplitude of each Fourier order (per revolution) of the scale deviation.",
    ),
    "timing_jitter_s": _t(
        "timing noise of the pulses", "s", "Type A noise of one pulse time, from the pulse times."
    ),
    "scale_factors": _t(
        "scale factor |K_i|",
        "output units per °/s",
        "Length of row i of K: the sensitivity of gyro i along its own sensitive axis.",
        "|K_i|",
    ),
    "misalignment_deg": _t(
        "misalignment",
        "°",
        "Angle between gyro i's sensitive axis (row i of K) and its nominal axis.",
        "θ_i",
    ),
    "fit_residual_rms": _t(
        "fit residual, rms", "output units", "Rms of u − (K·ω + b) per output over its kept rows."
    ),
    "residual_rms_before": _t(
        "residual before calibration, rms",
        "°/s",
        "Rms of the raw outputs at face value minus the reference rates.",
    ),
    "outliers_rejected": _t(
        "rows with a rejected output", "", "Rows with at least one output rejected as anomalous."
    ),
    # --- turntable error budget (the GyroWheel study; ISO 230-7 symbols in brackets) ---
    "phi_y1": _t(
        "position error of the outer axis",
        "′",
        "Angle by which the outer axis turns away from its commanded angle (ISO 230-7 EBB).",
        "Δφy1",
    ),
    "phi_z2": _t(
        "position error of the inner axis",
        "′",
        "Angle by which the inner axis turns away from its commanded angle (ISO 230-7 ECC).",
        "Δφz2",
    ),
    "alpha_x1": _t(
        "wobble of the outer axis about x",
        "′",
        "Tilt of the outer axis about the x axis as it turns (ISO 230-7 EAB).",
        "Δαx1",
    ),
    "alpha_z1": _t(
        "wobble of the outer axis about z",
        "′",
        "Tilt of the outer axis about the z axis as it turns (ISO 230-7 ECB).",
        "Δαz1",
    ),
    "alpha_x2": _t(
        "wobble of the inner axis about x",
        "′",
        "Tilt of the inner axis about the x axis as it turns (ISO 230-7 EAC).",
        "Δαx2",
    ),
    "alpha_y2": _t(
        "wobble of the inner axis about y",
        "′",
        "Tilt of the inner axis about the y axis as it turns (ISO 230-7 EBC).",
        "Δαy2",
    ),
    "eps_x": _t(
        "perpendicularity error of the axes about x",
        "′",
        "Departure of the inner axis from perpendicular to the outer axis, about x (ISO 230-7 "
        "EA0C).",
        "Δεx",
    ),
    "eps_y": _t(
        "perpendicularity error of the axes about y",
        "′",
        "Departure of the inner axis from perpendicular to the outer axis, about y (ISO 230-7 "
        "EB0C).",
        "Δεy",
    ),
    "eta": _t(
        "intersection error of the axes",
        "mm",
        "Distance by which the two axes miss each other; it moves the instrument but does not "
        "turn it (ISO 230-7 EX0C).",
        "Δη",
    ),
    "requirement_arcmin": _t(
        "orientation requirement",
        "′",
        "Largest orientation error Δψ, Δθ, Δγ the instrument on the table may have.",
        "I",
    ),
    "sensitivities": _t(
        "averaged sensitivity",
        "rad/rad",
        "Mean over the table's angles of |∂Δ/∂χ|, how much an error source moves one orientation "
        "component.",
        "C",
    ),
    "lower_bounds_arcmin": _t(
        "lower bound", "′", "Smallest error manufacturing can achieve for an error source.", "LB"
    ),
    "upper_bounds_arcmin": _t(
        "allocated upper bound",
        "′",
        "Tolerance allocated to an error source so that the orientation stays within the "
        "requirement.",
        "UB",
    ),
    "errors_arcsec": _t(
        "identified geometric error",
        "″",
        "A turntable error estimated from orientation errors measured at many positions; empty "
        "for an error the positions cannot separate from others (see the combinations).",
        "χ",
    ),
    "unidentifiable": _t(
        "errors not separable alone",
        "",
        "The table's errors that orientation errors at these positions see only in sums with "
        "others (or, for a translation, not at all).",
    ),
    "max_abs_arcmin": _t(
        "largest orientation error among the tables drawn",
        "′",
        "Largest |Δψ|, |Δθ|, |Δγ| over the Monte Carlo draws; it grows with the number of draws.",
    ),
    "fraction_outside": _t(
        "fraction of tables outside the orientation requirement",
        "",
        "Share of the tables drawn within their tolerances (at random angles) whose orientation "
        "error exceeds the requirement on some component.",
    ),
    "quantile_abs_arcmin": _t(
        "orientation error 99.9 % of tables stay within",
        "′",
        "The 99.9 % quantile of |Δψ|, |Δθ|, |Δγ| over tables built within their tolerances, at "
        "random angles.",
    ),
    "quantile_abs_interval_arcmin": _t(
        "coverage interval of the orientation error 99.9 % of tables stay within",
        "′",
        "95 % distribution-free interval of the 99.9 % quantile, from the order statistics of the "
        "draws (David and Nagaraja 2003, §7.1).",
    ),
    "fraction_outside_interval": _t(
        "coverage interval of the fraction of tables outside the requirement",
        "",
        "95 % exact binomial interval (Clopper and Pearson 1934).",
    ),
    "p95_rate_error_interval_deg_h": _t(
        "coverage interval of the rate-sensing error 95 % of calibrations stay within",
        "°/h",
        "95 % distribution-free interval of the 95th percentile, from the order statistics.",
    ),
    "fraction_above_required_interval": _t(
        "coverage interval of the fraction of calibrations above the required accuracy",
        "",
        "95 % exact binomial interval (Clopper and Pearson 1934).",
    ),
    "p95_rate_error_deg_h": _t(
        "rate-sensing error 95 % of calibrations stay within",
        "°/h",
        "95th percentile of the drift calibration's rate error Δω over tables drawn within the "
        "allocation.",
        "Δω",
    ),
    "max_rate_error_deg_h": _t(
        "largest rate-sensing error among the tables drawn",
        "°/h",
        "Largest Δω of the drift calibration over the tables drawn.",
        "Δω",
    ),
    "fraction_above_required": _t(
        "fraction of calibrations above the required accuracy",
        "",
        "Share of the tables drawn on which the drift calibration's rate error exceeds ωm.",
    ),
}


def term(key: str) -> Term:
    """The :class:`Term` of a JSON key (a trailing ``_u``/``_U`` names the same quantity).

    Raises
    ------
    KeyError
        When the glossary has no entry: every quantity a report shows must have one (the tests
        render every report and look for keys that reach the reader).
    """
    base = key[:-2] if key.endswith(("_u", "_U")) else key
    return GLOSSARY[base]


def unit_of(key: str) -> str:
    """The unit of a JSON key's value, as printed."""
    return term(key).unit
