"""Units of reported results: as printed in the PDF, and in D-SI notation for the DCC.

The D-SI (Hutzschenreuter et al., "SmartCom Digital System of Units (D-SI) Guide", PTB 2020,
v2) writes units as LaTeX-like macros: ``\\degree\\per\\second``, ``\\percent``,
``\\hour\\tothe{0.5}``. The units rotacal's analyses report are a small fixed set; each maps to one
D-SI string, and a gyro's own output unit (``--output-unit``) combines with them. A unit outside
the set is refused with the list of those known, never guessed.
"""

from __future__ import annotations

from rotacal.errors import ConfigError

__all__ = ["OUTPUT_UNITS", "RESULT_UNITS", "dsi_unit", "printed_unit"]

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
}

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
}

#: How the analyses name a gyro's output unit when the user did not give it.
UNSTATED_OUTPUT = "output unit"


def printed_unit(unit: str, output_unit: str = "") -> str:
    """``unit`` of a result with the gyro's output unit put in for ``"output unit"``.

    ``"output unit/(°/s)"`` with ``output_unit = "V"`` → ``"V/(°/s)"``; a digital gyro's
    ``"°/s/(°/s)"`` becomes ``""`` (a pure number). Units without the placeholder come back as
    they are.
    """
    if UNSTATED_OUTPUT not in unit or not output_unit:
        return unit
    if unit == f"{UNSTATED_OUTPUT}/(°/s)" and output_unit in ("°/s", "deg/s"):
        return ""
    return unit.replace(UNSTATED_OUTPUT, output_unit)


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
        if shown == f"{output_unit}/(°/s)":
            # V/(°/s) = V·s/°; a count per °/s is s/°
            return (out if out != r"\one" else "") + r"\second\per\degree"
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
