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
        "deviation and root Allan variance over angle ({kokuyama2015}).",
        ("kokuyama2015", "gum"),
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
        "Overlapping Allan deviation of the gyro's output at rest and its noise terms (angle "
        "random walk, bias instability, rate random walk) read off the curve ({ieee952}, Annex C).",
        ("ieee952", "gum"),
    ),
}


def method_of(command: str) -> tuple[str, tuple[str, ...]]:
    """The method sentence of ``command`` with its citations filled in, and the full entries of
    the publications it cites (authors (year). Title. Venue.), the GUM last."""
    sentence, keys = METHODS[command]
    text = sentence.format(**{key: cite(key) for key in REFERENCES})
    return text, tuple(REFERENCES[key].full() for key in keys)
