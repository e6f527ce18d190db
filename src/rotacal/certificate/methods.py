"""The method of each measurement command as a certificate states it (ISO/IEC 17025:2017
§7.8.2.1 f: identification of the method used), with the publications it follows."""

from __future__ import annotations

from rotacal.references import REFERENCES, cite

__all__ = ["METHODS", "method_of"]

_MOTION = (
    "Sinusoidal-motion calibration: the angular displacement is fitted by the IEEE Std 1057 "
    "multi-harmonic sine fit over whole periods between reversing moments; amplitude, frequency, "
    "angular-acceleration amplitude and total harmonic distortion follow ({feng2023}, eqs. (1)–(2); "
    "{ieee1057})."
)

#: command → (the method in one or two sentences, with ``{key}`` citations; the references).
METHODS: dict[str, tuple[str, tuple[str, ...]]] = {
    "motion encoder": (
        _MOTION + " The angle is demodulated from the optical encoder's quadrature signals with "
        "Heydemann's correction ({feng2023}, eqs. (3)–(8); {heydemann1981}).",
        ("feng2023", "ieee1057", "heydemann1981", "gum"),
    ),
    "motion lts": (
        _MOTION + " The angle is θ = arctan(D/R) from the laser triangulation sensor's "
        "displacement D at radius R ({feng2023}, eq. (15)).",
        ("feng2023", "ieee1057", "gum"),
    ),
    "motion fog": (
        "Sinusoidal-motion calibration from the rate measured by a fibre-optic gyro: a "
        "multi-harmonic fit of the rate gives the displacement's harmonics and the THD, and the "
        "signal-to-noise ratio ({feng2023}, eqs. (9)–(14); {ieee1057}).",
        ("feng2023", "ieee1057", "gum"),
    ),
    "selfcal": (
        "Self-calibration of the scale of an angle encoder by the equal-division-averaged "
        "method with several reading heads; harmonics of the scale deviation whose order is a "
        "multiple of the number of heads cannot be detected ({kokuyama2015}).",
        ("kokuyama2015", "gum"),
    ),
    "rate": (
        "Angular velocity from the timing of the encoder's pulses over whole revolutions, its "
        "deviation and root Allan variance over angle ({kokuyama2015}). With window angles "
        "(--window-deg): the rate-table acceptance figures of consecutive, non-overlapping "
        "windows of W degrees, each window's mean rate Θ/Δt from the elapsed time through a known "
        "angle ({kokuyama2015}, §5): rate accuracy 100·(ω̄ − Ω)/Ω against the set rate Ω, rate "
        "stability 100·s(ω_i)/ω̄ and its peak 100·max|ω_i − ω̄|/ω̄ per window size; k from Student's t for the N − 1 degrees of "
        "freedom of N windows.",
        ("kokuyama2015", "gum"),
    ),
    "position": (
        "Positioning accuracy of a rotary axis against a reference (reference encoder, or "
        "autocollimator and polygon): the deviations at each target position, runs in both "
        "directions, give the systematic deviation E, repeatability R, reversal value B and "
        "accuracy A of {iso230_2} (clauses 2–3); the error curve's harmonics by least squares; "
        "U = k·u with k = t₉₅(ν_eff), the readings' scatter at each position counted with n − 1 "
        "degrees of freedom (Welch–Satterthwaite).",
        ("iso230_2", "gum"),
    ),
    "turntable identify": (
        "Geometric errors of a two-axis turntable identified from orientation errors measured "
        "at many (φ₁, φ₂) positions: least squares on the full nonlinear error model of "
        "{gyrowheel} (§3.2, eqs. (17)–(25)), uncertainties from the residuals (Student's k); "
        "parameters the positions cannot separate are reported as their separable sums "
        "(first-order Jacobian, eq. (26)) and not as values.",
        ("gyrowheel", "gum"),
    ),
    "motion angle": (
        _MOTION + " The angle is read as logged (angle_deg) or from a counter's count, its "
        "register wrap unwrapped and the DAQ's lost or doubled samples found from the time "
        "stamps; the reversing moments are the angle's extremes ({feng2023}, §3.3, §5), and the "
        "readout's resolution enters as a Type B input.",
        ("feng2023", "ieee1057", "gum"),
    ),
    "gyro scale-factor": (
        "Scale factor and bias by a least-squares line through the gyro's mean outputs at the "
        "set rates of the table; nonlinearity as the largest deviation from that line in percent "
        "of full scale ({kokuyama2015}, §4; {ieee1431}).",
        ("kokuyama2015", "ieee1431", "gum"),
    ),
    "gyro triad": (
        "Scale factors, misalignment and bias of a three-axis gyro: u = K·ω + b by least squares "
        "over rotations at several rates about each axis, with outlier rejection (the modified "
        "six-position method, {robot2023}, eqs. (4), (5), (7)).",
        ("robot2023", "gum"),
    ),
    "gyro rotations": (
        "Scale factors, misalignment and bias of a three-axis gyro from rotations through a "
        "known angle about each axis and static positions ({ferraris1995}).",
        ("ferraris1995", "gum"),
    ),
    "gyro multiposition": (
        "Drift coefficients of a gyro by least squares over turntable positions, with the Earth's "
        "rate and gravity at each position ({gyrowheel}, eqs. (1)–(6)).",
        ("gyrowheel", "gum"),
    ),
    "allan": (
        "Overlapping Allan deviation of the gyro's output at rest; its noise terms (quantization, "
        "angle random walk, bias instability, rate random walk, rate ramp) by a weighted "
        "least-squares fit of all five terms of {ieee952}, Annex C, Table C.1, to the whole "
        "curve, weighted by the covariance of its points.",
        ("ieee952", "gum"),
    ),
    "gyro frequency-response": (
        "Dynamic calibration on a sinusoidal table: the table's angle and the gyro's rate are "
        "sine-fitted at each frequency ({ieee1057}, §4.1.3; {feng2023}, eqs. (9)–(13)), giving "
        "amplitude ratio and phase; a second-order model (natural frequency, damping ratio, "
        "−3 dB bandwidth) is fitted across the frequencies by weighted least squares.",
        ("ieee1057", "feng2023", "gum"),
    ),
    "gyro resolution": (
        "Threshold and resolution of a gyro from a small-step test: the smallest input step "
        "whose output change reaches 50 % of the change the scale factor expects (the "
        "definitions of {ieee528}; the test of {ieee1431}); the value is the middle of the "
        "bracketing steps, its u that of a rectangular distribution over them (k = 1.65, "
        "p = 95 %).",
        ("ieee528", "ieee1431", "gum"),
    ),
    "gyro accelerometer": (
        "Scale factors, misalignment and bias of an accelerometer triad from six static "
        "positions, each axis up and down, against local gravity ({ferraris1995}, "
        "eqs. (19)–(23)).",
        ("ferraris1995", "gum"),
    ),
}


def method_of(command: str) -> tuple[str, tuple[str, ...]]:
    """The method sentence of ``command`` with its citations filled in, and the full entries of
    the publications it cites (authors (year). Title. Venue.), the GUM last."""
    sentence, keys = METHODS[command]
    text = sentence.format(**{key: cite(key) for key in REFERENCES})
    return text, tuple(REFERENCES[key].full() for key in keys)
