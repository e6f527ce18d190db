"""TOML description of a turntable → :class:`rotacal.turntable.model.Turntable`.

The file lists the chain base → instrument (``[[chain]]``), the errors in χ order (``[errors]``),
the orientation requirement (``[requirement]``) and optional Monte Carlo and calibration settings.
Angles in the file are in ``units`` (default arcmin), translations in ``length_units`` (default
mm); the loaded :class:`Turntable` is in rad and m. Example (the GyroWheel study's table is packaged as
``rotacal/turntable/tables/seed001.toml``; :func:`seed_table` loads it)::

    name = "Two-axis turntable"
    units = "arcmin"             # rad, mrad, urad, deg, arcmin, arcsec
    length_units = "mm"          # m, mm, um

    [requirement]                # allowed |Δψ|, |Δθ|, |Δγ| in `units` …
    psi = 1.62
    theta = 1.62
    gamma = 1.62
    # … or instead: calibration_deg_h = 0.01 (derived from a multiposition calibration), with
    # derivation = "calibration-check" (default) | "earth-rate-only" (the GyroWheel study's eq. (16))

    [[chain]]                    # a rotary axis about its own y, turning by phi1
    axis = "y"
    angle = "phi1"
    rotations = { phi_y1 = "y", alpha_z1 = "z", alpha_x1 = "x" }   # in the order applied

    [[chain]]                    # a fixed link: orthogonality and intersection
    rotations = { eps_y = "y", eps_x = "x" }
    translations = { eta = "x" }

    [[chain]]
    axis = "z"
    angle = "phi2"
    rotations = { alpha_y2 = "y", phi_z2 = "z", alpha_x2 = "x" }

    [errors]                     # χ order; keys: lower (≥ 0, default 0), iso, label, weight (> 0)
    phi_y1 = { lower = 0.05, iso = "EBB", label = "Position error of outer axis" }
    # … every chain error exactly once (an ISO symbol generated from the chain is accepted as key)

    [monte_carlo]                # optional: runs (integer ≥ 1), seed (integer ≥ 0),
                                 # signs = "random" | "positive", stream = "philox" | "pcg64"
    [calibration]                # optional: latitude_deg, outer_steps, inner_steps, required_deg_h
                                 # (the calibration accuracy to check the allocated table against)
    [sensitivity]                # optional: how eq. (28)'s sensitivities are averaged
    step_deg = 45                # grid step (deg), dividing 360 (default 1; 8 for three angles)
    endpoint = true              # count 360° as well as 0° (default false)
    [allocation]                 # optional: where the constraint of eqs. (31)–(33) holds
    constraint_angles = "every"  # every angle (default), or a step in degrees dividing 360
                                 # (45: the paper's grid φ2 ∈ {0°, 45°, 90°})

``[requirement] derivation`` chooses how ``calibration_deg_h`` becomes the orientation requirement
(:mod:`rotacal.turntable.requirement`): ``"calibration-check"`` (default; the tables the allocation
admits keep the calibration within that accuracy) or ``"earth-rate-only"`` (the paper's eq. (16)).
``[allocation] constraint_angles`` chooses where the allocation's constraint holds: at every angle
(default) or only on a grid (45: the paper's, with which Table 4 comes out).

``[sensitivity]`` chooses the averaging of the sensitivities (eq. (28)) and so of the allocation
weights (1/sensitivity): every angle of the table on 0, step, … below 360° by default — the unbiased
mean over a turn, 2/π = 0.6366 for every |sin| and |cos| term — or up to 360° included with
``endpoint = true``. ``step_deg = 45, endpoint = true`` is the paper's averaging: it reproduces
Figure 8's 0.6476/0.5365 but counts 0° and 360° twice (the packaged table of the GyroWheel study uses it).

Angular values must be small angles: a requirement component or an angular lower bound above 0.1 rad
(5.7°) is refused — the small-angle error model (eqs. (17)–(19)) needs errors ≪ 1 rad, and such a
value is almost always given in the wrong units.

Every fault is one :class:`~rotacal.errors.ConfigError` sentence naming the file, the table and the
key or value at fault: a TOML syntax error (with its line), an unknown key or table (with the
nearest valid key), an unknown or duplicate error name, a chain error missing from ``[errors]`` or
vice versa, an axis letter other than x/y/z, a rotary axis without ``angle``, two axes with the same
angle name, a chain with no error, a negative lower bound or one above 0.1 rad, a non-positive,
unknown or too large (> 0.1 rad) requirement component, both requirement forms, unknown units,
a ``[monte_carlo]`` runs or seed that is not an integer (≥ 1, ≥ 0; booleans refused), a
``[sensitivity]`` step that does not divide 360° or an endpoint that is not true/false; and, so
that absurd numbers never reach the budget's arithmetic, any number beyond float64's working
range (magnitude above 1e100, or below 1e-100 but not 0), more than 10⁹ Monte Carlo runs, fewer
than 2 or more than 360 calibration steps per axis, or a sensitivity step whose grid exceeds 10⁷ points.

References
----------
Seed 001, §3.2 (Tables 2–3, eqs. (17)–(22)) and §4 (eqs. (16), (28), (29), Figure 8).
"""

from __future__ import annotations

import difflib
import math
import os
import sys
from collections.abc import Mapping
from importlib import resources
from pathlib import Path
from typing import Any

from rotacal.errors import ConfigError
from rotacal.signal._values import LARGEST, SMALLEST
from rotacal.turntable.chain import (
    ANGLE_UNITS,
    COMPONENTS,
    LENGTH_UNITS,
    ErrorSpec,
    Link,
    _chain_kinds,
    _check_chain,
    generated_aliases,
)
from rotacal.turntable.geometry import Turntable
from rotacal.turntable.stream import STREAMS

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

__all__ = [
    "ALLOCATION_KEYS",
    "CALIBRATION_KEYS",
    "MONTE_CARLO_KEYS",
    "SEED_TABLE_RESOURCE",
    "SENSITIVITY_KEYS",
    "load_turntable",
    "parse_turntable",
    "seed_table",
    "seed_table_toml",
]

#: The packaged description of the GyroWheel study's table, inside ``rotacal.turntable``.
SEED_TABLE_RESOURCE = ("tables", "seed001.toml")
_TOP_KEYS = (
    "name",
    "units",
    "length_units",
    "requirement",
    "chain",
    "errors",
    "monte_carlo",
    "calibration",
    "sensitivity",
    "allocation",
)
_LINK_KEYS = ("axis", "angle", "rotations", "translations")
_ERROR_KEYS = ("lower", "iso", "label", "weight")
_REQUIREMENT_KEYS = (*COMPONENTS, "calibration_deg_h", "derivation")
#: Keys of ``[monte_carlo]`` (defaults applied by the consumers: 1 000 000, 2026, "random",
#: "philox").
MONTE_CARLO_KEYS = ("runs", "seed", "signs", "stream")
#: Keys of ``[calibration]`` (defaults applied by the consumers: 45.75, 8, 8).
CALIBRATION_KEYS = ("latitude_deg", "outer_steps", "inner_steps", "required_deg_h")
#: Keys of ``[sensitivity]`` (defaults: a 1° step without the endpoint, see
#: ``Turntable.sensitivity_grid``).
SENSITIVITY_KEYS = ("step_deg", "endpoint")
#: Keys of ``[allocation]`` (default: the constraint at every angle).
ALLOCATION_KEYS = ("constraint_angles",)
_SIGNS = ("random", "positive")
#: Most Monte Carlo draws a file may ask for: 10⁹ take minutes at ≥ 10⁷ draws/s; more is a typo.
MAX_RUNS = 1_000_000_000
#: Most points of the sensitivity grid (about 1 µs each): a finer step changes nothing.
MAX_GRID_POINTS = 10_000_000


class _Reader:
    """Helpers that turn TOML values into checked Python values, naming the source on faults."""

    def __init__(self, source: str) -> None:
        self.source = source

    def fail(self, message: str) -> ConfigError:
        return ConfigError(f"{self.source}: {message}")

    def keys(self, table: Mapping[str, Any], allowed: tuple[str, ...], where: str) -> None:
        for key in table:
            if key not in allowed:
                near = difflib.get_close_matches(str(key), allowed, n=1)
                hint = f" (did you mean {near[0]!r}?)" if near else ""
                raise self.fail(
                    f"{where} has an unknown key {key!r}{hint}; valid keys: {', '.join(allowed)}."
                )

    def table(self, value: Any, where: str) -> Mapping[str, Any]:
        if not isinstance(value, Mapping):
            raise self.fail(f"{where} must be a table, got {value!r}.")
        return value

    def string(self, value: Any, where: str) -> str:
        if not isinstance(value, str) or not value.strip():
            raise self.fail(f"{where} must be a non-empty string, got {value!r}.")
        return value

    def number(self, value: Any, where: str) -> float:
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise self.fail(f"{where} must be a number, got {value!r}.")
        if not math.isfinite(value):
            raise self.fail(f"{where} must be finite, got {value!r}.")
        if abs(value) > LARGEST or 0 < abs(value) < SMALLEST:
            raise self.fail(
                f"{where} = {value:g} is beyond what float64 arithmetic of the budget carries "
                f"(magnitudes from {SMALLEST:g} to {LARGEST:g}, or 0); check the value and its unit."
            )
        return float(value)

    def integer(self, value: Any, where: str, minimum: int, maximum: int | None = None) -> int:
        if isinstance(value, bool) or not isinstance(value, int) or value < minimum:
            raise self.fail(f"{where} must be an integer ≥ {minimum}, got {value!r}.")
        if maximum is not None and value > maximum:
            raise self.fail(f"{where} must be an integer ≤ {maximum:_}, got {value:_}.")
        return int(value)

    def units(self, value: Any, where: str, table: Mapping[str, float]) -> str:
        if value not in table:
            raise self.fail(f"{where} = {value!r} is unknown: use one of {', '.join(table)}.")
        return str(value)


def _check_grid_size(reader: _Reader, step_deg: Any, links: tuple[Link, ...]) -> None:
    """Refuse a [sensitivity] step so fine that the averaging grid exceeds MAX_GRID_POINTS."""
    step = reader.number(step_deg, "[sensitivity] step_deg")
    angles = sum(1 for link in links if link.angle is not None)
    if step > 0 and (360.0 / step) ** angles > MAX_GRID_POINTS:
        raise reader.fail(
            f"[sensitivity] step_deg = {step:g} makes a grid of {(360.0 / step) ** angles:.3g} "
            f"points over {angles} angles (at most {MAX_GRID_POINTS:.0e}: about 10 s); choose a "
            "coarser step such as 1 or 45."
        )


def _link(reader: _Reader, entry: Any, k: int) -> Link:
    where = f"[[chain]] link {k + 1}"
    entry = reader.table(entry, where)
    reader.keys(entry, _LINK_KEYS, where)
    axis = entry.get("axis")
    angle = entry.get("angle")
    if angle is not None:
        angle = reader.string(angle, f"{where} angle")
    pairs: dict[str, tuple[tuple[str, Any], ...]] = {}
    for field in ("rotations", "translations"):
        table = reader.table(entry.get(field, {}), f"{where} {field}")
        pairs[field] = tuple((str(n), a) for n, a in table.items())
    try:  # Link checks the axis letters and the angle (one place)
        return Link(axis, angle, pairs["rotations"], pairs["translations"])
    except ConfigError as exc:
        raise reader.fail(f"{where}: {exc}") from None


def parse_turntable(
    data: Mapping[str, Any], *, source: str = "turntable TOML text", name: str | None = None
) -> Turntable:
    """A :class:`Turntable` from the parsed TOML (a dict), checking every key and value.

    Parameters
    ----------
    data : mapping
        The parsed document (e.g. ``tomllib.loads(text)``).
    source : str
        How to name the document in messages (the file's path).
    name : str, optional
        The table's name when the document has none.

    Returns
    -------
    Turntable
        Angles and bounds in rad, translations in m.

    Raises
    ------
    ConfigError
        One sentence naming the source, table and key or value at fault.

    References
    ----------
    Seed 001, Tables 2–3 (the chain), eqs. (16), (29) (requirement, lower bounds).
    """
    rd = _Reader(source)
    rd.keys(data, _TOP_KEYS, "the top level")
    title = rd.string(data.get("name", name or "turntable"), "name")
    units = rd.units(data.get("units", "arcmin"), "units", ANGLE_UNITS)
    length_units = rd.units(data.get("length_units", "mm"), "length_units", LENGTH_UNITS)
    to_rad, to_m = ANGLE_UNITS[units], LENGTH_UNITS[length_units]

    chain = data.get("chain")
    if not isinstance(chain, list) or not chain:
        raise rd.fail(
            "there is no [[chain]]: list the links base → instrument as [[chain]] tables."
        )
    links = tuple(_link(rd, entry, k) for k, entry in enumerate(chain))
    try:  # the chain's own checks live in the model (one place), before [errors] is read
        _check_chain(links)
    except ConfigError as exc:
        raise rd.fail(str(exc)) from None
    kinds = _chain_kinds(links)
    generated = generated_aliases(links)

    errors_table = rd.table(data.get("errors", {}), "[errors]")
    specs: list[ErrorSpec] = []
    given: dict[str, str] = {}
    for key, entry in errors_table.items():
        canonical = key if key in kinds else generated.get(str(key).upper())
        if canonical is None:
            symbols = f" (or the ISO symbols {', '.join(sorted(generated))})" if generated else ""
            raise rd.fail(
                f"[errors] names {key!r}, which is no error of the chain; valid names: "
                f"{', '.join(kinds)}{symbols}."
            )
        if canonical in given:
            raise rd.fail(
                f"[errors] lists {canonical!r} twice (as {given[canonical]!r} and {key!r}); "
                "list it once."
            )
        given[canonical] = str(key)
        where = f"[errors] {key}"
        entry = rd.table(entry, where)
        rd.keys(entry, _ERROR_KEYS, where)
        kind = kinds[canonical]
        factor, unit = (to_m, length_units) if kind == "offset" else (to_rad, units)
        lower = rd.number(entry.get("lower", 0.0), f"{where} lower")
        if lower < 0:
            raise rd.fail(
                f"{where}: lower = {lower:g} {unit} is negative; lower bounds are magnitudes (≥ 0)."
            )
        weight = entry.get("weight")
        if weight is not None:
            weight = rd.number(weight, f"{where} weight")
            if weight <= 0:
                raise rd.fail(f"{where}: weight = {weight:g} must be > 0.")
        iso = entry.get("iso")
        if iso is not None:
            iso = rd.string(iso, f"{where} iso")
        label = rd.string(entry["label"], f"{where} label") if "label" in entry else ""
        specs.append(
            ErrorSpec(
                name=canonical,
                kind=kind,
                lower=lower * factor,
                iso=iso,
                label=label,
                weight=weight,
            )
        )

    requirement: dict[str, float] | None = None
    calibration_deg_h: float | None = None
    if "requirement" in data:
        req = rd.table(data["requirement"], "[requirement]")
        for key in req:
            if key not in _REQUIREMENT_KEYS:
                near = difflib.get_close_matches(str(key), _REQUIREMENT_KEYS, n=1)
                hint = f" (did you mean {near[0]!r}?)" if near else ""
                raise rd.fail(
                    f"[requirement] has an unknown component {key!r}{hint}; use "
                    f"{', '.join(COMPONENTS)} (in {units}) or calibration_deg_h (and derivation)."
                )
        stated = [c for c in COMPONENTS if c in req]
        if stated and "calibration_deg_h" in req:
            raise rd.fail(
                "[requirement] gives both the orientation limits and calibration_deg_h; keep one "
                "of the two forms."
            )
        if "calibration_deg_h" in req:
            calibration_deg_h = rd.number(
                req["calibration_deg_h"], "[requirement] calibration_deg_h"
            )
            if calibration_deg_h <= 0:
                raise rd.fail(
                    f"[requirement] calibration_deg_h = {calibration_deg_h:g} must be > 0 (°/h)."
                )
        else:
            missing = [c for c in COMPONENTS if c not in req]
            if missing:
                raise rd.fail(
                    f"[requirement] lacks {missing[0]!r}; give psi, theta and gamma (in {units}) "
                    "or calibration_deg_h."
                )
            requirement = {}
            for c in COMPONENTS:
                value = rd.number(req[c], f"[requirement] {c}")
                if value <= 0:
                    raise rd.fail(
                        f"[requirement] {c} = {value:g} {units} must be > 0 (an allowed |error|)."
                    )
                requirement[c] = value * to_rad

    settings: dict[str, Any] = {}
    if "monte_carlo" in data:
        mc = rd.table(data["monte_carlo"], "[monte_carlo]")
        rd.keys(mc, MONTE_CARLO_KEYS, "[monte_carlo]")
        checked: dict[str, Any] = {}
        if "runs" in mc:
            checked["runs"] = rd.integer(mc["runs"], "[monte_carlo] runs", 1, MAX_RUNS)
        if "seed" in mc:
            checked["seed"] = rd.integer(mc["seed"], "[monte_carlo] seed", 0)
        if "signs" in mc:
            if mc["signs"] not in _SIGNS:
                raise rd.fail(
                    f"[monte_carlo] signs = {mc['signs']!r} is unknown; use 'random' or 'positive'."
                )
            checked["signs"] = str(mc["signs"])
        if "stream" in mc:
            if mc["stream"] not in STREAMS:
                raise rd.fail(
                    f"[monte_carlo] stream = {mc['stream']!r} is unknown; use 'philox' (the "
                    "default) or 'pcg64' (the stream of earlier versions)."
                )
            checked["stream"] = str(mc["stream"])
        settings["monte_carlo"] = checked
    if "calibration" in data:
        cal = rd.table(data["calibration"], "[calibration]")
        rd.keys(cal, CALIBRATION_KEYS, "[calibration]")
        checked = {}
        if "latitude_deg" in cal:
            lat = rd.number(cal["latitude_deg"], "[calibration] latitude_deg")
            if abs(lat) > 90:
                raise rd.fail(f"[calibration] latitude_deg = {lat:g} must be within ±90°.")
            checked["latitude_deg"] = lat
        for key in ("outer_steps", "inner_steps"):
            if key in cal:
                # one step would hold that axis still: its coefficients cannot be separated
                checked[key] = rd.integer(cal[key], f"[calibration] {key}", 2, 360)
        if "required_deg_h" in cal:
            accuracy = rd.number(cal["required_deg_h"], "[calibration] required_deg_h")
            if accuracy <= 0:
                raise rd.fail(f"[calibration] required_deg_h = {accuracy:g} must be > 0 (°/h).")
            checked["required_deg_h"] = accuracy
        settings["calibration"] = checked
    if "sensitivity" in data:
        sens = rd.table(data["sensitivity"], "[sensitivity]")
        rd.keys(sens, SENSITIVITY_KEYS, "[sensitivity]")
        settings["sensitivity"] = dict(sens)  # values checked by Turntable (sensitivity_grid)
        if "step_deg" in sens:
            _check_grid_size(rd, sens["step_deg"], links)
    settings.update(_allocation_options(rd, data))

    try:
        return Turntable(
            name=title,
            links=links,
            errors=tuple(specs),
            requirement=requirement,
            calibration_requirement_deg_h=calibration_deg_h,
            settings=settings,
            units=units,
            length_units=length_units,
            source=source,
        )
    except ConfigError as exc:
        raise rd.fail(str(exc)) from None


def _allocation_options(rd: _Reader, data: Mapping[str, Any]) -> dict[str, Any]:
    """``[requirement] derivation`` and ``[allocation]``, checked: the budget's two choices."""
    from rotacal.turntable.allocation import check_constraint_angles
    from rotacal.turntable.requirement import check_derivation

    out: dict[str, Any] = {}
    req = data.get("requirement")
    if isinstance(req, Mapping) and "derivation" in req:
        if "calibration_deg_h" not in req:
            raise rd.fail(
                "[requirement] derivation applies to calibration_deg_h only; remove it or give "
                "calibration_deg_h instead of psi, theta, gamma."
            )
        try:
            out["requirement"] = {
                "derivation": check_derivation(req["derivation"], "[requirement] derivation")
            }
        except ConfigError as exc:
            raise rd.fail(str(exc)) from None
    if "allocation" in data:
        alloc = rd.table(data["allocation"], "[allocation]")
        rd.keys(alloc, ALLOCATION_KEYS, "[allocation]")
        checked: dict[str, Any] = {}
        if "constraint_angles" in alloc:
            try:
                step = check_constraint_angles(
                    alloc["constraint_angles"], "[allocation] constraint_angles"
                )
            except ConfigError as exc:
                raise rd.fail(str(exc)) from None
            checked["constraint_angles"] = "every" if step is None else step
        out["allocation"] = checked
    return out


def load_turntable(
    path_or_text: str | os.PathLike[str] | None = None,
    *,
    text: str | None = None,
    name: str | None = None,
) -> Turntable:
    """Load a turntable description (TOML) from a file or from a string.

    Parameters
    ----------
    path_or_text : str or path-like, optional
        The TOML file. A ``str`` that contains a line break is taken as the TOML text itself
        (convenient in tests); a ``Path`` is always a file.
    text : str, optional
        The TOML text (explicit form; give either this or ``path_or_text``).
    name : str, optional
        The table's name when the document has no ``name`` (default: the file's stem).

    Returns
    -------
    Turntable
        Angles and bounds in rad, translations in m.

    Raises
    ------
    ConfigError
        One sentence naming the file (or "turntable TOML text") and what to fix; a TOML syntax
        error names its line and column.

    References
    ----------
    Seed 001, Tables 2–3 and eqs. (16)–(22).
    """
    if text is not None and path_or_text is not None:
        raise ConfigError("give either a path or text=, not both.")
    source = "turntable TOML text"
    if text is None:
        if path_or_text is None:
            raise ConfigError("no turntable description given: pass a TOML file path or text=.")
        if isinstance(path_or_text, str) and "\n" in path_or_text:
            text = path_or_text
        else:
            path = Path(path_or_text)
            source = str(path)
            if not path.is_file():
                raise ConfigError(f"turntable configuration {path} does not exist: check the path.")
            try:
                text = path.read_text(encoding="utf-8")
            except (OSError, UnicodeDecodeError) as exc:
                raise ConfigError(f"{path}: cannot be read as UTF-8 text ({exc}).") from None
            name = name or path.stem
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"{source}: TOML syntax error: {exc}; fix it there.") from None
    return parse_turntable(data, source=source, name=name)


def seed_table() -> Turntable:
    """The two-axis turntable of the GyroWheel study, loaded from the packaged ``tables/seed001.toml``.

    Chain and error names of Tables 2–3 (χ order of eq. (25), then η), labels as in Table 2,
    requirement 1.62 arcmin = 0.027° per component (eq. (16)); lower bounds are rotacal's stated
    choice (0.05 arcmin for every angular error, 0 mm for η): the paper gives none. Its
    ``[sensitivity]`` table keeps the paper's averaging (45° grid, 360° included), which
    reproduces Figure 8's 0.6476/0.5365.

    Returns
    -------
    Turntable

    References
    ----------
    Seed 001, Tables 2–3, eqs. (16)–(22).
    """
    text = seed_table_toml()
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:  # pragma: no cover - packaged file
        raise ConfigError(f"packaged seed001.toml: TOML syntax error: {exc}.") from None
    return parse_turntable(data, source="packaged seed001.toml")


def seed_table_toml() -> str:
    """The text of the packaged ``tables/seed001.toml``: a commented starting point for a table."""
    ref = resources.files("rotacal.turntable")
    for part in SEED_TABLE_RESOURCE:
        ref = ref.joinpath(part)
    return ref.read_text(encoding="utf-8")
