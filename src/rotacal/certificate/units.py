"""Units of reported results: as printed in the PDF, and in D-SI notation for the DCC.

The D-SI (Hutzschenreuter et al., "SmartCom Digital System of Units (D-SI) Guide", PTB 2020,
v2) writes units as LaTeX-like macros: ``\\degree\\per\\second``, ``\\percent``,
``\\hour\\tothe{0.5}``. The units rotacal's analyses report are a small fixed set; each maps to one
D-SI string, and a gyro's own output unit (``--output-unit``) combines with them. A unit outside
the set is refused with the list of those known, never guessed.
"""

from __future__ import annotations

from rotacal.errors import ConfigError

__all__ = [
    "CONVERTED_UNITS",
    "OUTPUT_UNITS",
    "RESULT_UNITS",
    "dsi_unit",
    "factor_to_printed",
    "printed_unit",
]

#: Units of the analyses' results (the ``unit`` of their uncertainty budgets) → D-SI.
RESULT_UNITS: dict[str, str] = {
    "°": r"\degree",
    "deg": r"\degree",
    "arcsec": r"\arcsecond",
    "″": r"\arcsecond",
    "Hz": r"\hertz",
    "s": r"\second",
    "%": r"\percent",
    "%FS": r"\percent",
    "°/s": r"\degree\per\second",
    "deg/s": r"\degree\per\second",
    "°/s²": r"\degree\per\second\tothe{2}",
    "°/h": r"\degree\per\hour",
    "deg/h": r"\degree\per\hour",
    "°/√h": r"\degree\per\hour\tothe{0.5}",
    "°/h/√h": r"\degree\per\hour\tothe{1.5}",
    "°/h²": r"\degree\per\hour\tothe{2}",
    "m/s²": r"\metre\per\second\tothe{2}",
    "°/h/(m/s²)": r"\degree\per\hour\per\metre\second\tothe{2}",
    "°/h/(m/s²)²": r"\degree\per\hour\per\metre\tothe{2}\second\tothe{4}",
}

#: Units without a D-SI form, stated in SI instead: unit → (printed unit, factor to it). The
#: g-sensitivity of a gyro is stated per m/s² (1 g = 9.806 65 m/s², the standard acceleration of
#: gravity, CGPM 1901); the certificate says so.
STANDARD_GRAVITY = 9.80665
CONVERTED_UNITS: dict[str, tuple[str, float]] = {
    "deg/h/g": ("°/h/(m/s²)", 1.0 / STANDARD_GRAVITY),
    "deg/h/g^2": ("°/h/(m/s²)²", 1.0 / STANDARD_GRAVITY**2),
}

#: Units some analyses write with "deg", printed with the degree sign like the rest.
_DEGREE_SIGN = {"deg": "°", "deg/s": "°/s", "deg/h": "°/h", "deg/s/(°/s)": "", "m/s^2": "m/s²"}

#: A gyro's output units (``--output-unit``) that a certificate can state → D-SI. Counts of an
#: A/D converter or a digital output (LSB) are numbers: ``\\one``.
OUTPUT_UNITS: dict[str, str] = {
    "V": r"\volt",
    "mV": r"\milli\volt",
    "µV": r"\micro\volt",
    "A": r"\ampere",
    "mA": r"\milli\ampere",
    "Hz": r"\hertz",
    "LSB": r"\one",
    "count": r"\one",
    "counts": r"\one",
    "digit": r"\one",
    "°/s": r"\degree\per\second",
    "deg/s": r"\degree\per\second",
    "rad/s": r"\radian\per\second",
    # an accelerometer's output (gyro accelerometer)
    "m/s²": r"\metre\per\second\tothe{2}",
    "m/s^2": r"\metre\per\second\tothe{2}",
}
#: A result per unit of input, as the analyses write it → the input's D-SI, for an output unit
#: divided by it: a gyro's "V/(°/s)", an accelerometer's "LSB/(m/s²)".
_PER_INPUT = {"(°/s)": r"\second\per\degree", "(m/s²)": r"\second\tothe{2}\per\metre"}

#: How the analyses name a gyro's output unit when the user did not give it.
UNSTATED_OUTPUT = "output unit"


def printed_unit(unit: str, output_unit: str = "") -> str:
    """``unit`` of a result with the gyro's output unit put in for ``"output unit"``.

    ``"output unit/(°/s)"`` with ``output_unit = "V"`` → ``"V/(°/s)"``; a digital gyro's
    ``"°/s/(°/s)"`` becomes ``""`` (a pure number). Units without the placeholder come back as
    they are.
    """
    if output_unit:
        unit = unit.replace(UNSTATED_OUTPUT, output_unit)
    if unit in ("°/s/(°/s)", "deg/s/(°/s)", "m/s^2/(m/s²)", "m/s²/(m/s²)"):
        return ""  # a gyro that reads in °/s, an accelerometer in m/s²: a pure number
    if unit in CONVERTED_UNITS:
        return CONVERTED_UNITS[unit][0]
    return _DEGREE_SIGN.get(unit, unit)


def dsi_unit(unit: str, output_unit: str = "") -> str:
    """The D-SI notation of a result's ``unit`` (after :func:`printed_unit`).

    Raises
    ------
    ConfigError
        When the unit is the unstated ``"output unit"`` (the certificate must name it:
        ``--output-unit``) or not one a certificate can state.
    """
    if UNSTATED_OUTPUT in unit and not output_unit:
        raise ConfigError(
            "the gyro's output unit is not stated: give the measurement the option "
            'output-unit (e.g. output-unit = "V"; known: ' + ", ".join(OUTPUT_UNITS) + ")"
        )
    shown = printed_unit(unit, output_unit)
    if shown == "":
        return r"\one"
    if shown in RESULT_UNITS:
        return RESULT_UNITS[shown]
    if output_unit:
        out = _output_dsi(output_unit)
        if shown == output_unit:
            return out
        for per, dsi in _PER_INPUT.items():
            if shown == f"{output_unit}/{per}":
                # V/(°/s) = V·s/°; a count per °/s is s/°
                return (out if out != r"\one" else "") + dsi
    raise ConfigError(
        f"the unit {shown!r} cannot be stated in a certificate (D-SI); known: "
        + ", ".join(RESULT_UNITS)
    )


def _output_dsi(output_unit: str) -> str:
    try:
        return OUTPUT_UNITS[output_unit]
    except KeyError:
        raise ConfigError(
            f"the output unit {output_unit!r} cannot be stated in a certificate (D-SI); use one of "
            + ", ".join(OUTPUT_UNITS)
        ) from None


def factor_to_printed(unit: str, output_unit: str = "") -> float:
    """The factor that takes a value in ``unit`` to :func:`printed_unit` (1 but for
    :data:`CONVERTED_UNITS`)."""
    if output_unit:
        unit = unit.replace(UNSTATED_OUTPUT, output_unit)
    return CONVERTED_UNITS[unit][1] if unit in CONVERTED_UNITS else 1.0
