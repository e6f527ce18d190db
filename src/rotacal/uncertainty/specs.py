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
or U with k; errors may leave out the value, which is then 0). Only the names of :data:`KNOWN_SPECS` are accepted — a typo ends in one line that
names it and lists the valid names, rather than being silently ignored.

References
----------
JCGM 100:2008 (GUM) §4.3 (Type B evaluation from specifications and certificates); JCGM 101:2008
§6.4 (assigning distributions).
"""

from __future__ import annotations

import dataclasses
import difflib
import sys
from collections.abc import Mapping
from importlib import resources
from pathlib import Path
from typing import Any

from rotacal.errors import ConfigError
from rotacal.uncertainty.distributions import Distribution, distribution_from_spec

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

__all__ = ["KNOWN_SPECS", "InstrumentSpecs", "example_specs_toml", "load_specs"]

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
        "motion amplitude by the optical encoder (seed 000)",
    ),
    "encoder.undetectable_harmonics_arcsec": (
        "arcsec",
        "rms of the scale deviation at the orders that are multiples of the number of heads",
        "self-calibrated deviation and compensated rate (seed 004)",
    ),
    "lts.resolution_um": (
        "µm",
        "resolution (quantisation) of the laser triangulation sensor's distance",
        "motion amplitude by the LTS (seed 000)",
    ),
    "lts.radius_mm": (
        "mm",
        "lever arm R from the axis to the LTS spot (value and its uncertainty)",
        "motion amplitude by the LTS, θ = arctan(D/R) (seed 000, eq. 15)",
    ),
    "fog.scale_factor_relative": (
        "1",
        "relative uncertainty of the FOG's scale factor",
        "motion amplitude by the FOG (seed 000)",
    ),
    "table.set_rate_relative": (
        "1",
        "relative error of the rate table's set rate (its rate accuracy)",
        "gyro scale factor and 3-axis calibrations (seeds 003, 004)",
    ),
    "table.set_angle_arcsec": (
        "arcsec",
        "error of the table's angle positioning (rotations through a known angle)",
        "3-axis calibration from rotations (Ferraris)",
    ),
    "table.orientation_error_arcsec": (
        "arcsec",
        "orientation error of the instrument on the turntable, per component (seed 001 eq. 7)",
        "multiposition drift coefficients (seed 001)",
    ),
    "site.latitude_deg": (
        "°",
        "latitude of the laboratory (value and its uncertainty)",
        "multiposition drift coefficients (Earth rate and gravity, seed 001 eq. 3)",
    ),
}


#: Specifications that state a quantity (its value matters), not an error centred on zero.
_NEED_VALUE = frozenset({"lts.radius_mm", "site.latitude_deg"})


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

    def describe(self, key: str) -> str:
        """``"lts.radius_mm (mm) = normal …, from lab.toml"`` — the origin text of a budget row."""
        dist = self.get(key)
        unit = KNOWN_SPECS[key][0]
        what = dist.describe() if dist is not None else "not stated"
        return f"{key} ({unit}): {what}, from {self.source}"


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
        closest valid name), a malformed distribution (unknown distribution, negative u, …).

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
            if "value" not in spec and key not in _NEED_VALUE:
                spec = {**spec, "value": 0.0}  # an error specification: centred on zero
            entries[key] = distribution_from_spec(spec, where=f"{where}: [{section}] {name}")
    return InstrumentSpecs(entries=entries, source=where)


def example_specs_toml() -> str:
    """A commented specifications file with every known entry (example values, not defaults)."""
    return (
        resources.files("rotacal.uncertainty")
        .joinpath("templates", "specs_example.toml")
        .read_text(encoding="utf-8")
    )
