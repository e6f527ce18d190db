"""What a turntable is made of: its chain of links, its geometric errors and their names.

A :class:`Link` is a row of Table 3 of the GyroWheel study (a rotary axis or a fixed link, with its
error rotations and translations), an :class:`ErrorSpec` a row of Table 2 (an error's kind, lower
bound, ISO 230-1/-7 symbol). Here too: the units a description may use, the checks of a chain
(one name per angle and per error), the ISO symbols generated from a chain, and the checks of
values a user gives (finite numbers, small angles, shapes that broadcast) that
:class:`rotacal.turntable.geometry.Turntable` and the TOML loader share. The model itself is
described in :mod:`rotacal.turntable.model`.

References
----------
Seed 001 (``../shared/seeds/001_4a387eb674e238f2.txt``), §3.2, Tables 2–3, eq. (25).
ISO 230-1:2012 and ISO 230-7:2015 (symbols of the geometric errors of axes of rotation).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping, Sequence
from typing import Any, Literal

import numpy as np

from rotacal.errors import ConfigError

__all__ = [
    "ANGLE_UNITS",
    "ARCMIN_PER_RAD",
    "AXES",
    "COMPONENTS",
    "KINDS",
    "LENGTH_UNITS",
    "SEED_ERROR_NAMES",
    "SMALL_ANGLE_LIMIT_RAD",
    "ErrorSpec",
    "Link",
    "generated_aliases",
]

AXES = ("x", "y", "z")
#: Orientation error components, in this order everywhere: Δψ (about y), Δθ (about z), Δγ (about x).
COMPONENTS = ("psi", "theta", "gamma")
#: Kinds of error: rotation of a rotary axis about itself, about another axis, of a fixed link, and
#: any translation.
KINDS = ("position", "wobble", "squareness", "offset")
#: The GyroWheel study's χ (eq. (25)) followed by the intersection error η.
SEED_ERROR_NAMES = (
    "phi_y1",
    "phi_z2",
    "alpha_x1",
    "alpha_z1",
    "alpha_x2",
    "alpha_y2",
    "eps_x",
    "eps_y",
    "eta",
)
#: Radians per unit of the angular units a configuration may use.
ANGLE_UNITS: dict[str, float] = {
    "rad": 1.0,
    "mrad": 1e-3,
    "urad": 1e-6,
    "deg": math.pi / 180.0,
    "arcmin": math.pi / 10_800.0,
    "arcsec": math.pi / 648_000.0,
}
#: Arcminutes per radian (10 800/π): multiply radians by it to display arcmin.
ARCMIN_PER_RAD = 1.0 / ANGLE_UNITS["arcmin"]
#: Largest |angular error| (rad) the model accepts (requirements and lower bounds too): the
#: small-angle matrices of eqs. (17)–(19) are meant for errors ≪ 1 rad, and a value above this is
#: almost always degrees or arcmin given by mistake.
SMALL_ANGLE_LIMIT_RAD = 0.1
#: Metres per unit of the length units a configuration may use.
LENGTH_UNITS: dict[str, float] = {"m": 1.0, "mm": 1e-3, "um": 1e-6}

Model = Literal["seed", "exact"]

_AXIS_INDEX = {"x": 0, "y": 1, "z": 2}
_ISO_ROT = "ABC"
_ISO_LIN = "XYZ"
#: (row, column) of ΔR giving Δψ, Δθ, Δγ (eq. (24)).
_DR_ENTRIES = ((0, 2), (1, 0), (2, 1))
#: Index in v (x, y, z) of ΔR ≈ I + skew(v) giving Δψ, Δθ, Δγ.
_V_INDEX = (1, 2, 0)
#: The two indices a rotation about x, y, z mixes, in the cyclic order (i, j): R[i,i] = R[j,j] = c,
#: R[i,j] = −s, R[j,i] = s.
_PLANE = {0: (1, 2), 1: (2, 0), 2: (0, 1)}
_FAST_CHUNK = 16_384
#: Largest default sensitivity grid (points over all angles); the default step is coarsened (to a
#: whole-degree divisor of 360) for tables of three or more angles to stay below it.
_MAX_SENSITIVITY_POINTS = 150_000
#: Default averaging of the sensitivities (eq. (28)): a 1° step, periodic (0 ≤ φ < 360°).
_DEFAULT_SENSITIVITY_STEP_DEG = 1.0


# ------------------------------------------------------------------------------------ the chain
@dataclasses.dataclass(frozen=True)
class Link:
    """One element of the chain base → instrument (a row of Table 3 of the GyroWheel study).

    Attributes
    ----------
    axis : {"x", "y", "z"} or None
        The rotary axis the link turns about (its own axis), or None for a fixed link.
    angle : str or None
        The name of the rotation angle (rotary axes only), e.g. ``"phi1"``.
    rotations : tuple of (name, axis)
        Error rotations in the order they are applied (matters for ``model="exact"`` only).
    translations : tuple of (name, axis)
        Error translations (lengths), applied after the rotations.
    """

    axis: str | None
    angle: str | None
    rotations: tuple[tuple[str, str], ...] = ()
    translations: tuple[tuple[str, str], ...] = ()

    def __post_init__(self) -> None:
        if self.axis is not None and self.axis not in AXES:
            raise ConfigError(
                f"axis = {self.axis!r} is not an axis letter; use 'x', 'y' or 'z' "
                "(or no axis for a fixed link)."
            )
        if self.axis is not None and not (isinstance(self.angle, str) and self.angle):
            raise ConfigError(
                f"the rotary axis about {self.axis} has no angle; name its angle, e.g. angle = "
                '"phi1".'
            )
        if self.axis is None and self.angle is not None:
            raise ConfigError(
                f"a fixed link (no axis) cannot have an angle ({self.angle!r}): give it an axis "
                "or remove the angle."
            )
        for field in ("rotations", "translations"):
            pairs = getattr(self, field)
            if isinstance(pairs, Mapping):
                pairs = tuple(pairs.items())
            for name, ax in pairs:
                if ax not in AXES:
                    raise ConfigError(
                        f"{field} {name} = {ax!r} is not an axis letter; use 'x', 'y' or 'z'."
                    )
            pairs = tuple((str(n), str(a)) for n, a in pairs)
            for name, _ in pairs:
                if not name or any(ch.isspace() for ch in name):
                    raise ConfigError(f"error name {name!r} is empty or contains spaces.")
            object.__setattr__(self, field, pairs)


@dataclasses.dataclass(frozen=True)
class ErrorSpec:
    """One geometric error of the table (a row of Table 2 of the GyroWheel study).

    Attributes
    ----------
    name : str
        Canonical name (e.g. ``"phi_y1"``).
    kind : {"position", "wobble", "squareness", "offset"}
        Derived from where the error sits in the chain.
    lower : float
        Manufacturing lower bound LB (eq. (29)): rad for rotations, m for offsets; ≥ 0.
    iso : str or None
        ISO 230-1/-7 symbol (e.g. ``"EBB"``), accepted as an alias. A :class:`Turntable` fills it
        with the generated symbol when none is given and the generated one is unambiguous.
    label : str
        Human description (Table 2's wording for the GyroWheel study's table).
    weight : float or None
        Override of the allocation weight (default: 1/sensitivity, the GyroWheel study after eq. (33)).
    """

    name: str
    kind: str
    lower: float = 0.0
    iso: str | None = None
    label: str = ""
    weight: float | None = None

    def __post_init__(self) -> None:
        if self.kind not in KINDS:
            raise ConfigError(
                f"error {self.name!r} has kind {self.kind!r}: use one of {', '.join(KINDS)}."
            )
        if not (math.isfinite(self.lower) and self.lower >= 0.0):
            raise ConfigError(
                f"the lower bound of {self.name!r} is {self.lower!r}: lower bounds are "
                "magnitudes, give a finite value ≥ 0."
            )
        if self.weight is not None and not (math.isfinite(self.weight) and self.weight > 0.0):
            raise ConfigError(
                f"the weight of {self.name!r} is {self.weight!r}: give a finite value > 0."
            )


@dataclasses.dataclass(frozen=True)
class _LinkPlan:
    axis: int  # −1 for a fixed link
    angle: int  # index into angle_names, −1 for a fixed link
    rotations: tuple[tuple[int, int], ...]  # (index into angular_error_names, axis index)
    translations: tuple[tuple[int, int], ...]  # (index into offset names, axis index)


@dataclasses.dataclass(frozen=True)
class _Plan:
    links: tuple[_LinkPlan, ...]
    angle_names: tuple[str, ...]
    angular: tuple[str, ...]
    offsets: tuple[str, ...]
    aliases: dict[str, str]  # upper-case alias → canonical name
    kinds: dict[str, str]


def _chain_kinds(links: Sequence[Link]) -> dict[str, str]:
    kinds: dict[str, str] = {}
    for link in links:
        for name, ax in link.rotations:
            if link.axis is None:
                kinds[name] = "squareness"
            else:
                kinds[name] = "position" if ax == link.axis else "wobble"
        for name, _ in link.translations:
            kinds[name] = "offset"
    return kinds


def _check_chain(links: Sequence[Link]) -> tuple[str, ...]:
    """The chain's angle names, after checking that angles and errors each have one name.

    The one place for these checks (:class:`Turntable` and the TOML loader both call it): two
    rotary axes with the same angle, an error in two links (or twice in one), an error named like
    an angle, a chain with no error at all. Messages name the link by its position (1 = base).
    """
    angle_names: list[str] = []
    for link in links:
        if link.angle is not None:
            if link.angle in angle_names:
                raise ConfigError(
                    f"two rotary axes have the same angle name {link.angle!r}; give each axis its "
                    "own angle."
                )
            angle_names.append(link.angle)
    seen: set[str] = set()
    for k, link in enumerate(links):
        for name, _ in (*link.rotations, *link.translations):
            if name in seen:
                raise ConfigError(
                    f"[[chain]] link {k + 1}: error {name!r} appears twice in the chain; every "
                    "error belongs to one link, once."
                )
            if name in angle_names:
                raise ConfigError(
                    f"[[chain]] link {k + 1}: error {name!r} has the name of an angle; rename one "
                    "of them."
                )
            seen.add(name)
    if not seen:
        raise ConfigError(
            "the chain has no errors: give its links error rotations (rotations = { ... }) or "
            "translations and list them in [errors]."
        )
    return tuple(angle_names)


def _check_sensitivity_grid(step_deg: Any, endpoint: Any, where: str = "") -> tuple[float, bool]:
    """(step_deg, endpoint) of a sensitivity grid, checked: step > 0 dividing 360°, a bool."""
    ok = not isinstance(step_deg, (bool, np.bool_)) and isinstance(
        step_deg, (int, float, np.integer, np.floating)
    )
    step = float(step_deg) if ok else math.nan
    count = 360.0 / step if step > 0 and math.isfinite(step) else math.nan
    if not (math.isfinite(count) and abs(count - round(count)) < 1e-9 and count >= 1):
        raise ConfigError(
            f"{where}step_deg = {step_deg!r} must be a number of degrees > 0 that divides 360° "
            "into whole steps (e.g. 1, 5 or 45)."
        )
    if not isinstance(endpoint, (bool, np.bool_)):
        raise ConfigError(
            f"{where}endpoint = {endpoint!r} must be true or false (count 360° as well as 0°)."
        )
    return step, bool(endpoint)


def _short(value: Any) -> str:
    """A one-line, bounded repr of a user's value for a message."""
    text = " ".join(repr(value).split())
    return text if len(text) <= 40 else text[:37] + "..."


def _float_array(value: Any, what: str, unit: str) -> np.ndarray:
    """``value`` as a float array; a non-number or non-finite value is one ConfigError line."""
    try:
        if value is None:
            raise TypeError
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise ConfigError(
            f"{what} = {_short(value)} is not a number: give {unit} as a float or an array of "
            "floats."
        ) from None
    if not np.all(np.isfinite(arr)):
        raise ConfigError(f"{what} has non-finite values (nan or inf): give finite {unit}.")
    return arr


def _check_small(arr: np.ndarray, what: str) -> None:
    """Refuse |angular error| > SMALL_ANGLE_LIMIT_RAD (one line naming it and saying radians)."""
    if arr.size and (big := float(np.max(np.abs(arr)))) > SMALL_ANGLE_LIMIT_RAD:
        raise ConfigError(
            f"{what} = {big:.6g} rad ({math.degrees(big):.4g}°) is beyond "
            f"{SMALL_ANGLE_LIMIT_RAD:g} rad: angular errors are in radians and the small-angle "
            "model of eqs. (17)–(19) needs them ≪ 1 rad; convert degrees or arcmin to radians."
        )


def _broadcast(named: Sequence[tuple[str, tuple[int, ...]]]) -> tuple[int, ...]:
    """np.broadcast_shapes of named shapes; a mismatch is one ConfigError naming the culprit."""
    try:
        return np.broadcast_shapes(*(shape for _, shape in named))
    except ValueError:
        pass
    acc: tuple[int, ...] = ()
    owners: list[str] = []
    for label, shape in named:
        try:
            acc = np.broadcast_shapes(acc, shape)
        except ValueError:
            with_ = ", ".join(owners[:2]) + (", …" if len(owners) > 2 else "")
            raise ConfigError(
                f"{label} has shape {shape}, which does not broadcast with the shape {acc} of "
                f"{with_}: give shapes that broadcast (e.g. errors of shape (k, 1) against angles "
                "of shape (m,))."
            ) from None
        if shape:
            owners.append(label)
    return acc  # pragma: no cover - the first call raised, so some pair fails


def generated_aliases(links: Sequence[Link]) -> dict[str, str]:
    """ISO 230-1/-7 symbols generated from the chain, only those that name one error.

    A rotary axis about x/y/z has letter A/B/C; its position error is E{L}{L}, its wobble about M
    is E{M}{L}, its translation along X/Y/Z is E{X|Y|Z}{L}; a fixed link's rotation about M before
    the next rotary axis (letter L) is E{M}0{L}, its translation E{X|Y|Z}0{L} (no symbol for a
    fixed link with no rotary axis after it). A symbol two errors would share is not generated.

    Parameters
    ----------
    links : sequence of Link
        The chain, base → instrument.

    Returns
    -------
    dict
        Upper-case symbol → canonical error name.

    References
    ----------
    ISO 230-1:2012 §3 and ISO 230-7:2015 §3 (error motions and location errors of rotary axes).
    """
    candidates: dict[str, set[str]] = {}
    for k, link in enumerate(links):
        if link.axis is not None:
            letter = _ISO_ROT[_AXIS_INDEX[link.axis]]
            infix = ""
        else:
            nxt = next((lk.axis for lk in links[k + 1 :] if lk.axis is not None), None)
            if nxt is None:
                continue
            letter = _ISO_ROT[_AXIS_INDEX[nxt]]
            infix = "0"
        for name, ax in link.rotations:
            sym = f"E{_ISO_ROT[_AXIS_INDEX[ax]]}{infix}{letter}"
            candidates.setdefault(sym, set()).add(name)
        for name, ax in link.translations:
            sym = f"E{_ISO_LIN[_AXIS_INDEX[ax]]}{infix}{letter}"
            candidates.setdefault(sym, set()).add(name)
    return {sym: next(iter(names)) for sym, names in candidates.items() if len(names) == 1}


def _alias_map(
    links: tuple[Link, ...], errors: tuple[ErrorSpec, ...], angle_names: list[str]
) -> tuple[dict[str, str], dict[str, str]]:
    """Accepted symbols (upper case → name) and the generated symbol of each error that has one.

    Explicit ``iso`` symbols come first and must each name one error (not another error's or an
    angle's name); generated symbols are added when unambiguous and not already taken.
    """
    taken = {n.upper(): n for n in (*(e.name for e in errors), *angle_names)}
    aliases: dict[str, str] = {}
    for e in errors:
        if e.iso is None:
            continue
        sym = str(e.iso).strip().upper()
        if not sym:
            raise ConfigError(f"the ISO symbol of {e.name!r} is empty: give one or omit it.")
        other = aliases.get(sym, taken.get(sym, e.name))
        if other != e.name:
            raise ConfigError(
                f"ISO symbol {e.iso!r} of {e.name!r} is already the name or symbol of "
                f"{other!r}: symbols must name one error."
            )
        aliases[sym] = e.name
    by_name: dict[str, str] = {}
    for sym, name in generated_aliases(links).items():
        if sym in aliases or (sym in taken and taken[sym] != name):
            continue
        aliases[sym] = name
        by_name.setdefault(name, sym)
    return aliases, by_name


def _default_label(kind: str, link: Link, ax: str, next_angle: str | None) -> str:
    if kind == "position":
        return f"Position error of the axis turning by {link.angle}"
    if kind == "wobble":
        return f"Wobble error of the axis turning by {link.angle}, about {ax}"
    if kind == "squareness":
        where = f" before the axis turning by {next_angle}" if next_angle else ""
        return f"Orthogonality (squareness) error about {ax}{where}"
    where = f" of the axis turning by {link.angle}" if link.angle else ""
    if not where and next_angle:
        where = f" before the axis turning by {next_angle}"
    return f"Offset along {ax}{where}"
