"""Instrument specifications a user states in a TOML file: the Type B inputs of every budget.

A lab knows things the capture cannot tell: the encoder's graduation accuracy, the LTS resolution
and the uncertainty of its radius, the DAQ timebase accuracy, the rate table's set-rate accuracy,
the latitude. Each is stated once, with its distribution, and every calibration that needs it
takes it into its budget::

    [timebase]
    relative_error = { distribution = "rectangular", half_width = 2e-6 }   # ±2 ppm crystal

    [encoder]
    graduation_error_arcsec = { distribution = "rectangular", half_width = 1.0 }

    [lts]
    radius_mm = { distribution = "normal", value = 150.0, u = 0.02 }
    resolution_um = { distribution = "rectangular", half_width = 0.05 }

Every entry is a distribution in the form of
:func:`rotacal.uncertainty.distributions.distribution_from_spec` (a value, and u or a half-width,
or U with k, or lower and upper; errors may leave out the value, which is then 0). Only the names
of :data:`KNOWN_SPECS` are accepted — a typo ends in one line that names it and lists the valid
names, rather than being silently ignored — and a value outside the plausible range of its entry
(a unit slip) ends in one line "… is implausible for …; check units".

Every calibration turns a stated specification into a budget input in one way:
:meth:`InstrumentSpecs.input` (or :func:`spec_input`, which also takes ``specs=None``): value =
the stated mean, u, ν, the distribution's text and ``"Type B, KEY, from FILE"``. A non-zero mean
of an error is a recognised systematic effect: the result is corrected for it (GUM §3.2.4), the
budget row keeps the stated value and u, and the budget says so with
:meth:`InstrumentSpecs.correction_note`. A budget without Type B inputs says so with
:func:`type_a_note` (:data:`TYPE_A_ONLY_NOTE` when no specification was stated at all).

References
----------
JCGM 100:2008 (GUM) §4.3 (Type B evaluation from specifications and certificates), §3.2.4
(correction for a recognised systematic effect); JCGM 101:2008 §6.4 (assigning distributions).
"""

from __future__ import annotations

import dataclasses
import difflib
import math
import sys
from collections.abc import Mapping, Sequence
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np

from rotacal.errors import ConfigError
from rotacal.uncertainty.distributions import Distribution, distribution_from_spec
from rotacal.uncertainty.gum import Input

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

__all__ = [
    "KNOWN_SPECS",
    "TYPE_A_ONLY_NOTE",
    "InstrumentSpecs",
    "corrected_note",
    "example_specs_toml",
    "load_specs",
    "spec_distribution",
    "spec_input",
    "type_a_note",
]

#: The note of a budget built without any instrument specification (one text for every family).
TYPE_A_ONLY_NOTE = "no instrument specification stated: Type A only."

#: Every specification rotacal's budgets use: ``"section.name"`` → (unit, what it is, who uses it).
KNOWN_SPECS: dict[str, tuple[str, str, str]] = {
    "timebase.relative_error": (
        "1",
        "fractional error of the DAQ timebase (a +1e-6 clock makes every time 1 ppm long)",
        "frequency, pulse-timing rate, every rate the capture's time stamps give",
    ),
    "encoder.graduation_error_arcsec": (
        "arcsec",
        "angle error of one encoder reading (graduation and interpolation)",
        "motion amplitude by the optical encoder (Feng et al. 2023)",
    ),
    "encoder.undetectable_harmonics_arcsec": (
        "arcsec",
        "rms of the scale deviation at the orders that are multiples of the number of heads",
        "self-calibrated deviation and compensated rate (Kokuyama et al. 2015)",
    ),
    "lts.resolution_um": (
        "µm",
        "resolution (quantisation) of the laser triangulation sensor's distance",
        "motion amplitude by the LTS (Feng et al. 2023)",
    ),
    "lts.radius_mm": (
        "mm",
        "lever arm R from the axis to the LTS spot (value and its uncertainty)",
        "motion amplitude by the LTS, θ = arctan(D/R) (Feng et al. 2023, eq. 15)",
    ),
    "fog.scale_factor_relative": (
        "1",
        "relative uncertainty of the FOG's scale factor",
        "motion amplitude by the FOG (Feng et al. 2023)",
    ),
    "table.set_rate_relative": (
        "1",
        "relative error of the rate table's set rate (its rate accuracy)",
        "gyro scale factor and 3-axis calibrations (robot-manipulator study 2023; Kokuyama et al. 2015)",
    ),
    "table.set_angle_arcsec": (
        "arcsec",
        "error of the table's angle positioning (rotations through a known angle)",
        "3-axis calibration from rotations (Ferraris)",
    ),
    "table.orientation_error_arcsec": (
        "arcsec",
        "orientation error of the instrument on the turntable, per component (GyroWheel study, eq. 7)",
        "multiposition drift coefficients (GyroWheel study)",
    ),
    "site.latitude_deg": (
        "°",
        "latitude of the laboratory (value and its uncertainty)",
        "multiposition drift coefficients (Earth rate and gravity, GyroWheel study, eq. 3)",
    ),
}


#: Specifications that state a quantity (its value matters), not an error centred on zero.
_NEED_VALUE = frozenset({"lts.radius_mm", "site.latitude_deg"})

#: Plausible magnitude L of each error specification (its unit): |mean| ≤ L and the half-width of
#: the equivalent rectangular distribution √3·u ≤ L. Beyond it the number is almost surely in the
#: wrong unit (ppm written as a fraction ×10⁶, a percentage as a fraction, degrees as arcsec …).
_PLAUSIBLE: dict[str, float] = {
    "timebase.relative_error": 0.01,
    "encoder.graduation_error_arcsec": 3600.0,
    "encoder.undetectable_harmonics_arcsec": 3600.0,
    "lts.resolution_um": 1000.0,
    "fog.scale_factor_relative": 0.01,
    "table.set_rate_relative": 0.01,
    "table.set_angle_arcsec": 3600.0,
    "table.orientation_error_arcsec": 3600.0,
}
#: Largest plausible LTS lever arm (mm).
_RADIUS_MAX_MM = 10_000.0


def _check_plausible(key: str, dist: Distribution, where: str) -> None:
    """One line ``"… is implausible for KEY …; check units"`` when a stated value is out of range."""
    if np.ndim(dist.mean) != 0:
        return
    m, u = float(dist.mean), float(dist.std)
    if not (math.isfinite(u) and math.isfinite(u * u) and math.isfinite(m)):
        why = "too large (u² overflows)" if math.isfinite(u) else "not finite"
        raise ConfigError(
            f"{where}: the standard uncertainty u = {u:.3g} is {why}; "
            "state a finite value, u or half-width in the unit of the entry."
        )
    half = math.sqrt(3.0) * u
    unit = KNOWN_SPECS[key][0] if key in KNOWN_SPECS else ""
    unit = "" if unit == "1" else f" {unit}"
    if key in _PLAUSIBLE:
        lim = _PLAUSIBLE[key]
        if abs(m) > lim or half > lim:
            raise ConfigError(
                f"{where}: value {m:g}{unit} with half-width {half:.3g}{unit} (√3·u) is "
                f"implausible for {key} (|value| and half-width ≤ {lim:g}{unit} expected); "
                "check units."
            )
    elif key == "lts.radius_mm":
        if not 0.0 < m <= _RADIUS_MAX_MM or half >= m:
            raise ConfigError(
                f"{where}: radius {m:g} mm ± {half:.3g} mm (√3·u) is implausible for {key} "
                f"(0 < R ≤ {_RADIUS_MAX_MM:g} mm and √3·u < R expected); check units."
            )
    elif key == "site.latitude_deg" and not (-90.0 <= m - half and m + half <= 90.0):
        raise ConfigError(
            f"{where}: latitude {m:g}° ± {half:.3g}° (√3·u) is implausible for {key} (it must "
            "lie within ±90°); check units."
        )


@dataclasses.dataclass(frozen=True)
class InstrumentSpecs:
    """The instrument specifications of one lab set-up, by ``"section.name"``.

    ``source`` names where they came from (a file name) for messages and reports.
    """

    entries: Mapping[str, Distribution]
    source: str = "specifications"

    def get(self, key: str) -> Distribution | None:
        """The stated distribution of ``key`` (one of :data:`KNOWN_SPECS`), or None."""
        if key not in KNOWN_SPECS:
            raise ConfigError(f"{key!r} is not a known specification; valid: {_valid()}.")
        return self.entries.get(key)

    def mean(self, key: str) -> float:
        """The stated mean of ``key`` (its unit, :data:`KNOWN_SPECS`); 0.0 when not stated.

        A non-zero mean of an error specification is a recognised systematic effect: the result
        is corrected for it (JCGM 100:2008 §3.2.4) and its u stays in the budget.
        """
        dist = self.get(key)
        return 0.0 if dist is None else float(dist.mean)

    def input(
        self, key: str, *, name: str, unit: str | None = None, scale: float = 1.0
    ) -> Input | None:
        """The budget input of the stated specification ``key``, or None when it is not stated.

        The one place where a specification becomes an input quantity of a budget (every family
        uses it): value = the stated mean, u = the distribution's standard deviation, ν its dof
        (JCGM 101 §6.4), the distribution's description, and ``"Type B, KEY, from FILE"`` as its
        origin. A non-zero value is a systematic effect the caller corrects the result for (JCGM
        100 §3.2.4; say so with :meth:`correction_note`).

        Parameters
        ----------
        key : str
            Name of the specification (one of :data:`KNOWN_SPECS`).
        name : str
            Name of the input in the budget (e.g. ``"timebase error ε_t"``).
        unit : str, optional
            Unit shown in the budget; default the specification's unit (:data:`KNOWN_SPECS`),
            with ``"1"`` shown as ``""``.
        scale : float, optional
            Factor from the specification's unit to ``unit`` (e.g. π/648000 for arcsec → rad);
            value and u are multiplied by it. Default 1.

        Returns
        -------
        Input or None

        References
        ----------
        JCGM 100:2008 (GUM) §4.3 (Type B evaluation), §3.2.4 (correction for a recognised
        systematic effect); JCGM 101:2008 §6.4 (expectation and standard deviation).
        """
        dist = self.get(key)
        if dist is None:
            return None
        own = KNOWN_SPECS[key][0]
        shown = own if unit is None else unit
        f = float(scale)
        text = str(dist.describe())
        if f != 1.0 and own != "1":
            text = f"{text} {own}"  # the description stays in the specification's own unit
        return Input(
            name=name,
            value=f * float(dist.mean),
            u=abs(f) * float(dist.std),
            dof=float(dist.dof),
            distribution=str(dist.name),
            unit="" if shown == "1" else shown,
            source=f"Type B, {key}, from {self.source}",
            description=text,
        )

    def correction_note(self, key: str, *, unit: str | None = None) -> str | None:
        """The budget note of a result corrected for the stated mean of ``key``, or None when that
        mean is 0 or ``key`` is not stated (see :func:`corrected_note`)."""
        m = self.mean(key)
        if m == 0.0:
            return None
        return corrected_note(key, m, KNOWN_SPECS[key][0] if unit is None else unit, self.source)

    def describe(self, key: str) -> str:
        """``"lts.radius_mm (mm) = normal …, from lab.toml"`` — the origin text of a budget row."""
        dist = self.get(key)
        unit = KNOWN_SPECS[key][0]
        what = dist.describe() if dist is not None else "not stated"
        return f"{key} ({unit}): {what}, from {self.source}"


def corrected_note(key: str, mean: float, unit: str = "", source: str = "") -> str:
    """The standard note of a result corrected for a stated non-zero mean (GUM §3.2.4).

    ``"corrected for the stated mean of timebase.relative_error = 1.2e-06 (GUM §3.2.4, from
    lab.toml); its u stays in the budget."``
    """
    shown = f" {unit}" if unit and unit != "1" else ""
    origin = f", from {source}" if source else ""
    return (
        f"corrected for the stated mean of {key} = {mean:g}{shown} (GUM §3.2.4{origin}); its u "
        "stays in the budget."
    )


def spec_distribution(specs: InstrumentSpecs | None, key: str) -> Distribution | None:
    """The stated distribution of ``key`` (a name of :data:`KNOWN_SPECS`), or None — also when
    ``specs`` is None. For a Monte Carlo input; a GUM budget takes :func:`spec_input`."""
    return None if specs is None else specs.get(key)


def spec_input(
    specs: InstrumentSpecs | None,
    key: str,
    *,
    name: str,
    unit: str | None = None,
    scale: float = 1.0,
) -> Input | None:
    """:meth:`InstrumentSpecs.input` that also takes ``specs = None`` (then None)."""
    return None if specs is None else specs.input(key, name=name, unit=unit, scale=scale)


def type_a_note(specs: InstrumentSpecs | None, applicable: Sequence[str]) -> str | None:
    """The note of a budget without Type B inputs, or None when one of ``applicable`` is stated.

    ``specs`` None → :data:`TYPE_A_ONLY_NOTE`; specifications stated but none of ``applicable``
    (names of :data:`KNOWN_SPECS`) → ``"no applicable instrument specification stated (… in
    FILE): Type A only."``.
    """
    if specs is None:
        return TYPE_A_ONLY_NOTE
    if any(specs.get(k) is not None for k in applicable):
        return None
    return (
        f"no applicable instrument specification stated ({', '.join(applicable)} in "
        f"{specs.source}): Type A only."
    )


def _valid() -> str:
    return ", ".join(KNOWN_SPECS)


def load_specs(source: str | Path | Mapping[str, Any]) -> InstrumentSpecs:
    """Read instrument specifications from a TOML file (or TOML text, or a parsed mapping).

    Parameters
    ----------
    source : str, Path or mapping
        A path to a TOML file; TOML text (a string with a line break); or the parsed tables.

    Returns
    -------
    InstrumentSpecs

    Raises
    ------
    ConfigError
        One line naming the file and the fault: TOML syntax, an unknown section or name (with the
        closest valid name), a malformed distribution (unknown distribution, negative u, t with
        dof ≤ 2, lower > upper, a u that is not finite, …), a value outside the plausible range of
        the entry ("… is implausible for …; check units": relative errors within ±0.01, angles
        within ±3600″, LTS resolution ≤ 1000 µm, 0 < radius ≤ 10 m, latitude within ±90°).

    References
    ----------
    JCGM 100:2008 (GUM) §4.3; JCGM 101:2008 §6.4.
    """
    if isinstance(source, Mapping):
        data: Mapping[str, Any] = source
        where = "specifications"
    else:
        text_given = isinstance(source, str) and "\n" in source
        where = "specifications text" if text_given else Path(source).name
        text = str(source) if text_given else Path(source).read_text(encoding="utf-8")
        try:
            data = tomllib.loads(text)
        except tomllib.TOMLDecodeError as exc:
            raise ConfigError(f"{where}: TOML syntax error: {exc}.") from None
    entries: dict[str, Distribution] = {}
    for section, table in data.items():
        if not isinstance(table, Mapping):
            raise ConfigError(
                f"{where}: {section!r} must be a table [{section}] of specifications; valid "
                f"names: {_valid()}."
            )
        for name, spec in table.items():
            key = f"{section}.{name}"
            if key not in KNOWN_SPECS:
                close = difflib.get_close_matches(key, KNOWN_SPECS, n=1)
                hint = f" (did you mean {close[0]}?)" if close else ""
                raise ConfigError(
                    f"{where}: [{section}] {name} is not a known specification{hint}; valid: "
                    f"{_valid()}."
                )
            if not isinstance(spec, Mapping):
                raise ConfigError(
                    f"{where}: [{section}] {name} must be a distribution such as "
                    '{ distribution = "rectangular", half_width = 1.0 }.'
                )
            stated = any(k in spec for k in ("value", "lower", "upper"))
            if not stated and key not in _NEED_VALUE:
                spec = {**spec, "value": 0.0}  # an error specification: centred on zero
            entry = f"{where}: [{section}] {name}"
            entries[key] = distribution_from_spec(spec, where=entry)
            _check_plausible(key, entries[key], entry)
    return InstrumentSpecs(entries=entries, source=where)


def example_specs_toml() -> str:
    """A commented specifications file with every known entry (example values, not defaults)."""
    return (
        resources.files("rotacal.uncertainty")
        .joinpath("templates", "specs_example.toml")
        .read_text(encoding="utf-8")
    )
