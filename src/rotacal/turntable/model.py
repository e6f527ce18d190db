"""Geometric error model of a multi-axis turntable by homogeneous transforms (GyroWheel study, §3).

A turntable is a chain of links from the base (frame F0) to the instrument (the last frame). A
link is either a **rotary axis** — turning by its angle φ about its own x, y or z — or a **fixed
link** that carries the orthogonality (squareness) and intersection (offset) errors between two
axes. Each link also carries small error rotations, listed in order, and error translations. The
two-axis table of the GyroWheel study (Tables 2–3) is the chain::

    0T1 = Ry(φ1) · E(Δαx1, Δφy1, Δαz1)          outer axis about y: position error Δφy1, wobbles
    1T2 = E(Δεx, Δεy, 0) · Trans(Δη, 0, 0)      orthogonality Δεx, Δεy and intersection Δη
    2T3 = Rz(φ2) · E(Δαx2, Δαy2, Δφz2)          inner axis about z: position error Δφz2, wobbles
    3T4 = I                                     the gyro sits on the inner frame

with the active rotations Ry, Rz printed in eqs. (17), (19) and the small-angle error matrix
E(ex, ey, ez) = [[1, −ez, ey], [ez, 1, −ex], [−ey, ex, 1]] = I + skew(e). The actual transform is
T_t = Π iT(i+1) (eq. (22)), the ideal one T_d the product of the perfect rotations (eq. (21)); the
orientation error is ΔR = R_dᵀ·R_t (eq. (23)) and its components (eq. (24)), always in the order
:data:`COMPONENTS`:

    Δψ = ΔR[0, 2]  (about the instrument's y),  Δθ = ΔR[1, 0]  (about z),  Δγ = ΔR[2, 1]  (about x),

so that ΔR ≈ I + skew(v) with v = (Δγ, Δψ, Δθ).

Two models of a link's error rotations:

- ``model="seed"`` (default): one small-angle matrix E per link, with every error of the link
  summed about its axis, multiplied exactly as printed in eqs. (17)–(19) (E is not orthogonal);
- ``model="exact"``: each error is a proper rotation (``scipy.spatial.transform.Rotation``),
  applied in the order the link lists them — Table 3's order for the GyroWheel study's table (e.g. φ1 about y, then
  Δφy1 about y, Δαz1 about z, Δαx1 about x). It equals the GyroWheel study's model to first order.

Translations are applied after the link's rotations (eq. (18): E·Trans; Table 3's wording puts the
translation first — the difference is an origin shift of order Δη·Δε and none in orientation).
Translations never change the orientation: "the intersection error has no effect on the
orientation error" (GyroWheel study, after eq. (25)).

ΔR is computed by the recursion D ← A_kᵀ·D·A_k·E_k over the links (A_k the link's perfect
rotation, E_k its error matrix), which equals R_dᵀR_t because A_kᵀA_k = I. It starts from D = I
and skips the conjugation while D is still exactly the identity, so the outer axis of the GyroWheel study's table
table, R_y(φ1), cancels exactly (to the last bit), as it does in eq. (26). The first-order
expansion, ΔR ≈ I + Σ_k skew(S_kᵀ e_k) with S_k the product of the perfect rotations after link k,
gives the generalised eq. (26) (:meth:`Turntable.linear_coefficients`) and the sensitivities of
eq. (28) (:meth:`Turntable.sensitivities`).

Names: the GyroWheel study's error vector χ (eq. (25)) is ``phi_y1, phi_z2, alpha_x1, alpha_z1, alpha_x2,
alpha_y2, eps_x, eps_y`` plus the translation ``eta``. Every error may also be named by its
ISO 230-1 / ISO 230-7 symbol: the one stated in the table (``iso``) or, when unambiguous, a
generated one — a rotary axis about x/y/z has letter A/B/C; its position error is E{L}{L} (EBB),
its wobble about another axis M is E{M}{L} (EAB, ECB), its offsets E{X|Y|Z}{L}; a fixed link's
rotation about M before the axis with letter L is E{M}0{L} (EA0C, EB0C), its translation E{X}0{L}
(EX0C). Aliases are matched case-insensitively; canonical names exactly.

Units: radians for every angle and angular error, metres for translations (the TOML loader,
:mod:`rotacal.turntable.config`, converts from the file's units).

References
----------
Seed 001 (``../shared/seeds/001_4a387eb674e238f2.txt``): GyroWheel calibration tests — error
analysis and turntable error allocation, §3.2, eqs. (17)–(27), Tables 2–3; §4.1, eq. (28), Figure 8.
ISO 230-1:2012 and ISO 230-7:2015 (symbols of the geometric errors of axes of rotation).
"""

from __future__ import annotations

import dataclasses
import functools
import math
from collections.abc import Mapping, Sequence
from typing import Any, Literal, cast

import numpy as np
from numpy.typing import ArrayLike

from rotacal.errors import ConfigError
from rotacal.turntable.fast import chain_arrays, compiled_kernel, numba_enabled

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
    "Turntable",
    "generated_aliases",
    "load_turntable",
    "orientation_error",
    "seed_table",
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


# -------------------------------------------------------------------------------- the turntable
@dataclasses.dataclass(frozen=True)
class Turntable:
    """A turntable's chain of links, its geometric errors and its requirement (GyroWheel study, §3–4).

    Build it from a TOML description with :func:`load_turntable`, or :func:`seed_table` for the
    two-axis table of the GyroWheel study. Constructing it validates the chain against ``errors``: every
    chain error appears in ``errors`` exactly once and vice versa, names are unique, angle names
    are unique. Missing ISO symbols in ``errors`` are filled with the generated ones (see the
    module docstring); an empty label is filled with a description from the chain.

    Attributes
    ----------
    name : str
    links : tuple of Link
        Base → instrument.
    errors : tuple of ErrorSpec
        In χ order (the configuration's ``[errors]`` order).
    requirement : dict or None
        Allowed |Δψ|, |Δθ|, |Δγ| (rad), keys :data:`COMPONENTS`.
    calibration_requirement_deg_h : float or None
        Required calibration accuracy (°/h) to derive the requirement from (eqs. (7)–(16)).
    settings : dict
        The ``[monte_carlo]``, ``[calibration]`` and ``[sensitivity]`` tables as given (validated,
        no defaults added); ``settings["sensitivity"]`` (``step_deg``, ``endpoint``) chooses the
        averaging of :meth:`sensitivities` (see :attr:`sensitivity_grid`).
    units : str
        Display units of angles (a key of :data:`ANGLE_UNITS`).
    length_units : str
        Display units of translations (a key of :data:`LENGTH_UNITS`).
    source : str
        Where the description came from (the TOML file's path, ``"turntable TOML text"``,
        ``"packaged seed001.toml"``; empty when built in code): messages about the table start
        with it. Not part of equality.

    Requirements and lower bounds of angular errors above :data:`SMALL_ANGLE_LIMIT_RAD` (0.1 rad)
    are refused: the small-angle model of eqs. (17)–(19) needs errors ≪ 1 rad.
    """

    name: str
    links: tuple[Link, ...]
    errors: tuple[ErrorSpec, ...]
    requirement: dict[str, float] | None = None
    calibration_requirement_deg_h: float | None = None
    settings: dict[str, Any] = dataclasses.field(default_factory=dict)
    units: str = "arcmin"
    length_units: str = "mm"
    source: str = dataclasses.field(default="", compare=False)

    # ------------------------------------------------------------------------- validation
    def __post_init__(self) -> None:
        links = tuple(self.links)
        errors = tuple(self.errors)
        object.__setattr__(self, "links", links)
        if not links:
            raise ConfigError("the chain is empty: give at least one [[chain]] link.")
        if self.units not in ANGLE_UNITS:
            raise ConfigError(
                f"units {self.units!r} is unknown: use one of {', '.join(ANGLE_UNITS)}."
            )
        if self.length_units not in LENGTH_UNITS:
            raise ConfigError(
                f"length_units {self.length_units!r} is unknown: use one of "
                f"{', '.join(LENGTH_UNITS)}."
            )
        angle_names = list(_check_chain(links))
        chain_names = [n for lk in links for n, _ in (*lk.rotations, *lk.translations)]
        spec_names = [e.name for e in errors]
        seen: set[str] = set()
        for name in spec_names:
            if name in seen:
                raise ConfigError(f"error {name!r} is listed twice in [errors]: list it once.")
            seen.add(name)
        for name in chain_names:
            if name not in seen:
                raise ConfigError(
                    f"chain error {name!r} is missing from [errors]: add it there (in χ order)."
                )
        for name in spec_names:
            if name not in chain_names:
                raise ConfigError(
                    f"[errors] lists {name!r}, which no [[chain]] link has: add it to a link or "
                    f"remove it (chain errors: {', '.join(chain_names)})."
                )
        kinds = _chain_kinds(links)
        for e in errors:
            if e.kind != kinds[e.name]:
                raise ConfigError(
                    f"error {e.name!r} has kind {e.kind!r} but sits in the chain as a "
                    f"{kinds[e.name]} error: fix its kind."
                )
            if e.kind != "offset" and e.lower > SMALL_ANGLE_LIMIT_RAD:
                raise ConfigError(
                    f"[errors] {e.name}: lower = {self._in_units(e.lower)} is "
                    f"{math.degrees(e.lower):.3g}°: the small-angle error model needs errors ≪ 1 "
                    "rad; check units."
                )
        self._check_requirement()
        self._check_settings()

        aliases, by_name = _alias_map(links, errors, angle_names)
        next_angle: dict[str, str | None] = {}
        for k, link in enumerate(links):
            nxt = next((lk.angle for lk in links[k + 1 :] if lk.axis is not None), None)
            for name, _ in (*link.rotations, *link.translations):
                next_angle[name] = nxt
        where = {n: (lk, ax) for lk in links for n, ax in (*lk.rotations, *lk.translations)}
        filled = []
        for e in errors:
            changes: dict[str, Any] = {}
            if e.iso is None and e.name in by_name:
                changes["iso"] = by_name[e.name]
            if not e.label:
                lk, ax = where[e.name]
                changes["label"] = _default_label(e.kind, lk, ax, next_angle[e.name])
            filled.append(dataclasses.replace(e, **changes) if changes else e)
        object.__setattr__(self, "errors", tuple(filled))

        index_ang = {n: i for i, n in enumerate(e.name for e in filled if e.kind != "offset")}
        index_off = {n: i for i, n in enumerate(e.name for e in filled if e.kind == "offset")}
        plans = []
        for link in links:
            plans.append(
                _LinkPlan(
                    axis=-1 if link.axis is None else _AXIS_INDEX[link.axis],
                    angle=-1 if link.angle is None else angle_names.index(link.angle),
                    rotations=tuple((index_ang[n], _AXIS_INDEX[a]) for n, a in link.rotations),
                    translations=tuple(
                        (index_off[n], _AXIS_INDEX[a]) for n, a in link.translations
                    ),
                )
            )
        object.__setattr__(
            self,
            "_plan",
            _Plan(
                links=tuple(plans),
                angle_names=tuple(angle_names),
                angular=tuple(index_ang),
                offsets=tuple(index_off),
                aliases=aliases,
                kinds=kinds,
            ),
        )

    def _check_requirement(self) -> None:
        if self.requirement is not None and self.calibration_requirement_deg_h is not None:
            raise ConfigError(
                "both an orientation requirement and calibration_deg_h are given: keep one."
            )
        if self.requirement is not None:
            req = dict(self.requirement)
            for key in req:
                if key not in COMPONENTS:
                    raise ConfigError(
                        f"requirement component {key!r} is unknown: use {', '.join(COMPONENTS)}."
                    )
            missing = [key for key in COMPONENTS if key not in req]
            if missing:
                raise ConfigError(
                    f"the requirement lacks {missing[0]!r}: give all of {', '.join(COMPONENTS)}."
                )
            for key in COMPONENTS:
                value = req[key]
                if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
                    raise ConfigError(f"requirement {key} = {value!r} must be a finite value > 0.")
                if value > SMALL_ANGLE_LIMIT_RAD:
                    raise ConfigError(
                        f"[requirement] {key} = {self._in_units(value)} is "
                        f"{math.degrees(value):.3g}°: the small-angle error model needs errors ≪ "
                        "1 rad; check units."
                    )
            object.__setattr__(self, "requirement", {k: float(req[k]) for k in COMPONENTS})
        cal = self.calibration_requirement_deg_h
        if cal is not None and not (math.isfinite(cal) and cal > 0):
            raise ConfigError(f"calibration_deg_h = {cal!r} must be a finite value > 0 (°/h).")

    def _in_units(self, value_rad: float) -> str:
        """An angle (rad) in the table's display units, e.g. ``"1200 arcmin"``."""
        return f"{value_rad / ANGLE_UNITS[self.units]:.6g} {self.units}"

    def _check_settings(self) -> None:
        settings = dict(self.settings)
        if "sensitivity" in settings:
            given = settings["sensitivity"]
            if not isinstance(given, Mapping):
                raise ConfigError(f"[sensitivity] must be a table, got {_short(given)}.")
            unknown = [str(k) for k in given if k not in ("step_deg", "endpoint")]
            if unknown:
                raise ConfigError(
                    f"[sensitivity] has an unknown key {unknown[0]!r}; valid keys: step_deg, "
                    "endpoint."
                )
            step, end = _check_sensitivity_grid(
                given.get("step_deg", _DEFAULT_SENSITIVITY_STEP_DEG),
                given.get("endpoint", False),
                "[sensitivity] ",
            )
            checked: dict[str, Any] = {}
            if "step_deg" in given:
                checked["step_deg"] = step
            if "endpoint" in given:
                checked["endpoint"] = end
            settings["sensitivity"] = checked
        object.__setattr__(self, "settings", settings)

    @property
    def sensitivity_grid(self) -> tuple[float, bool]:
        """The averaging of :meth:`sensitivities` (and so of the allocation's weights).

        ``(step_deg, endpoint)``: every angle of the table takes the values 0, step, … up to 360°
        — with 360° itself when ``endpoint`` is True (the paper's grid, which counts 0° and 360°
        twice), without it otherwise (the unbiased mean over a turn). The table's
        ``[sensitivity]`` settings choose it; the default is a 1° step without the endpoint,
        coarsened for tables of three or more angles to the finest whole-degree divisor of 360
        whose grid stays ≤ 1.5·10⁵ points (8° for three angles).

        Returns
        -------
        tuple of (float, bool)
            Step (deg) and whether 360° is included.

        References
        ----------
        Seed 001, eq. (28) and Figure 8.
        """
        given = self.settings.get("sensitivity", {})
        step = given.get("step_deg")
        if step is None:
            n = max(len(self._p.angle_names), 1)
            divisors = [d for d in range(1, 361) if 360 % d == 0]
            step = float(
                next(
                    d
                    for d in divisors
                    if d >= _DEFAULT_SENSITIVITY_STEP_DEG
                    and (360 // d) ** n <= _MAX_SENSITIVITY_POINTS
                )
            )
        return float(step), bool(given.get("endpoint", False))

    @property
    def _p(self) -> _Plan:
        return cast(_Plan, self.__dict__["_plan"])

    # ---------------------------------------------------------------------------- names
    @property
    def error_names(self) -> tuple[str, ...]:
        """Canonical error names in χ order (translations included)."""
        return tuple(e.name for e in self.errors)

    @property
    def angular_error_names(self) -> tuple[str, ...]:
        """Names of the errors that rotate (all but the offsets), in χ order: the columns of
        :meth:`error_array`, :meth:`linear_coefficients` and :meth:`sensitivities`."""
        return self._p.angular

    @property
    def offset_names(self) -> tuple[str, ...]:
        """Names of the translation errors, in χ order."""
        return self._p.offsets

    @property
    def angle_names(self) -> tuple[str, ...]:
        """Names of the rotation angles, in chain order (base → instrument)."""
        return self._p.angle_names

    @property
    def aliases(self) -> dict[str, str]:
        """Every accepted ISO symbol (upper case) → canonical name."""
        return dict(self._p.aliases)

    def error(self, name: str) -> ErrorSpec:
        """The :class:`ErrorSpec` of ``name`` (canonical or alias)."""
        canonical = self.resolve(name)
        return next(e for e in self.errors if e.name == canonical)

    def resolve(self, name: str) -> str:
        """Canonical name of an error given by its name or an ISO 230-1/-7 alias.

        Raises
        ------
        ConfigError
            If the name is unknown (the message lists the valid names).
        """
        if name in self._p.kinds:
            return name
        canonical = self._p.aliases.get(str(name).strip().upper())
        if canonical is not None:
            return canonical
        symbols = ", ".join(sorted(self._p.aliases))
        raise ConfigError(
            f"unknown error name {name!r}: valid names are {', '.join(self.error_names)}"
            + (f" (or their ISO symbols {symbols})." if symbols else ".")
        )

    # ------------------------------------------------------------------------ inputs
    def _angles(self, angles: Sequence[ArrayLike] | Mapping[str, ArrayLike]) -> list[np.ndarray]:
        names = self._p.angle_names
        if isinstance(angles, Mapping):
            for key in angles:
                if key not in names:
                    raise ConfigError(
                        f"unknown angle {key!r}: this table's angles are {', '.join(names)}."
                    )
            missing = [n for n in names if n not in angles]
            if missing:
                raise ConfigError(
                    f"angle {missing[0]!r} is missing: give every angle of {', '.join(names)}."
                )
            values = [angles[n] for n in names]
        else:
            values = list(angles)
            if len(values) != len(names):
                raise ConfigError(
                    f"{len(values)} angle(s) given, this table has {len(names)} "
                    f"({', '.join(names)}): give them in chain order or as a mapping by name."
                )
        return [
            _float_array(value, f"angle {name!r}", "radians")
            for name, value in zip(names, values, strict=True)
        ]

    def _error_values(
        self, errors: Mapping[str, ArrayLike] | ArrayLike | None
    ) -> tuple[list[np.ndarray | None], list[np.ndarray | None]]:
        """Angular and offset error values (None = zero), names resolved."""
        ang: list[np.ndarray | None] = [None] * len(self._p.angular)
        off: list[np.ndarray | None] = [None] * len(self._p.offsets)
        if errors is None:
            return ang, off
        if not isinstance(errors, Mapping):
            arr = _float_array(errors, "the error array", "radians (metres for translations)")
            n_ang, n_all = len(ang), len(self.errors)
            if arr.ndim == 0 or arr.shape[-1] not in (n_ang, n_all):
                raise ConfigError(
                    f"an error array needs a last axis of {n_ang} (angular errors "
                    f"{', '.join(self._p.angular)}) or {n_all} (all errors in χ order), got "
                    f"shape {arr.shape}; or pass a mapping by name."
                )
            order = self._p.angular if arr.shape[-1] == n_ang else self.error_names
            columns = {n: arr[..., i] for i, n in enumerate(order)}
            for name in self._p.angular:
                _check_small(columns[name], f"error {name!r} (column of the error array)")
            return (
                [columns[n] for n in self._p.angular],
                [columns.get(n) for n in self._p.offsets],
            )
        index_ang = {n: i for i, n in enumerate(self._p.angular)}
        index_off = {n: i for i, n in enumerate(self._p.offsets)}
        given: dict[str, str] = {}
        for key, value in errors.items():
            name = self.resolve(key)
            if name in given:
                raise ConfigError(
                    f"error {name!r} is given twice (as {given[name]!r} and {key!r}): give it once."
                )
            given[name] = key
            if name in index_ang:
                arr = _float_array(value, f"error {key!r}", "radians")
                _check_small(arr, f"error {key!r}")
                ang[index_ang[name]] = arr
            else:
                off[index_off[name]] = _float_array(value, f"error {key!r}", "metres")
        return ang, off

    def error_array(self, errors: Mapping[str, ArrayLike]) -> np.ndarray:
        """The angular errors as one array in χ order (missing names are zero).

        Parameters
        ----------
        errors : mapping
            Error name (canonical or ISO alias) → value (rad; arrays broadcast). Translations are
            accepted and left out.

        Returns
        -------
        ndarray, shape (..., n_angular)
            rad; columns :attr:`angular_error_names`.
        """
        ang, _ = self._error_values(errors)
        shape = _broadcast(
            [
                (f"error {n!r}", a.shape)
                for n, a in zip(self._p.angular, ang, strict=True)
                if a is not None
            ]
        )
        out = np.zeros((*shape, len(ang)))
        for i, a in enumerate(ang):
            if a is not None:
                out[..., i] = a
        return out

    # ------------------------------------------------------------------------ matrices
    def _link_errors(self, ang: list[np.ndarray | None], model: str) -> list[np.ndarray | None]:
        """Each link's error rotation matrix (..., 3, 3), or None when it is exactly I."""
        if model not in ("seed", "exact"):
            raise ConfigError(f"model {model!r} is unknown: use 'seed' or 'exact'.")
        mats: list[np.ndarray | None] = []
        for plan in self._p.links:
            present = [(v, a) for i, a in plan.rotations if (v := ang[i]) is not None]
            if not present:
                mats.append(None)
                continue
            if model == "seed":
                mats.append(_small_angle_matrix(present))
            else:
                mats.append(_exact_matrix(present))
        return mats

    def _batch_shape(
        self, phis: list[np.ndarray], ang: list[np.ndarray | None], off: list[np.ndarray | None]
    ) -> tuple[int, ...]:
        p = self._p
        named = [(f"angle {n!r}", a.shape) for n, a in zip(p.angle_names, phis, strict=True)]
        named += [
            (f"error {n!r}", a.shape) for n, a in zip(p.angular, ang, strict=False) if a is not None
        ]
        named += [
            (f"error {n!r}", a.shape) for n, a in zip(p.offsets, off, strict=False) if a is not None
        ]
        return _broadcast(named) if named else ()

    def rotation_error(
        self,
        angles: Sequence[ArrayLike] | Mapping[str, ArrayLike],
        errors: Mapping[str, ArrayLike] | ArrayLike | None,
        *,
        model: Model = "seed",
    ) -> np.ndarray:
        """Orientation error matrix ΔR = R_dᵀ·R_t of the instrument (GyroWheel study, eq. (23)).

        Parameters
        ----------
        angles : sequence (chain order) or mapping by name of array_like
            Rotation angles (rad); broadcast together and with the errors.
        errors : mapping or array_like
            Error name (canonical or ISO alias) → value (rad for rotations, m for translations;
            missing = 0; arrays broadcast, e.g. shape (k, 1) against angles of shape (m,)), or an
            array whose last axis is the angular errors (or all errors) in χ order.
        model : {"seed", "exact"}
            Small-angle matrices as printed (eqs. (17)–(19)) or proper rotations in the link's
            order (Table 3).

        Returns
        -------
        ndarray, shape (..., 3, 3)
            ΔR (dimensionless); orthogonal for ``model="exact"``.

        Raises
        ------
        ConfigError
            An unknown error or angle name; a value that is not a finite number; an angular error
            beyond 0.1 rad (:data:`SMALL_ANGLE_LIMIT_RAD`: radians are expected); shapes that do
            not broadcast. One line naming the error or angle.

        References
        ----------
        Seed 001, eqs. (17)–(23), Table 3.
        """
        phis = self._angles(angles)
        ang, off = self._error_values(errors)
        batch = self._batch_shape(phis, ang, off)
        if model == "exact":
            return self._rotation_error_exact(phis, ang, batch)
        mats = self._link_errors(ang, model)
        d: np.ndarray | None = None
        for plan, e in zip(self._p.links, mats, strict=True):
            if plan.axis >= 0 and d is not None:
                a = _rotation_matrix(plan.axis, phis[plan.angle])
                d = np.swapaxes(a, -1, -2) @ d @ a
            if e is not None:
                d = e if d is None else d @ e
        if d is None:
            d = np.eye(3)
        return np.array(np.broadcast_to(d, (*batch, 3, 3)))

    def _rotation_error_exact(
        self, phis: list[np.ndarray], ang: list[np.ndarray | None], batch: tuple[int, ...]
    ) -> np.ndarray:
        """ΔR of the exact model, composed as quaternions (one conversion to a matrix at the end,
        so ΔR is orthogonal to a few ulp)."""
        from scipy.spatial.transform import Rotation

        size = math.prod(batch)

        def elementary(axis: int, value: np.ndarray) -> Rotation:
            rotvec = np.zeros((size, 3))
            rotvec[:, axis] = np.broadcast_to(value, batch).reshape(-1)
            return Rotation.from_rotvec(rotvec)

        d: Rotation | None = None
        for plan in self._p.links:
            if plan.axis >= 0 and d is not None:
                a = elementary(plan.axis, phis[plan.angle])
                d = a.inv() * d * a
            for i, axis in plan.rotations:
                value = ang[i]
                if value is not None:
                    r = elementary(axis, value)
                    d = r if d is None else d * r
        if d is None:
            return np.array(np.broadcast_to(np.eye(3), (*batch, 3, 3)))
        return np.asarray(d.as_matrix()).reshape(*batch, 3, 3)

    def orientation_error(
        self,
        angles: Sequence[ArrayLike] | Mapping[str, ArrayLike],
        errors: Mapping[str, ArrayLike] | ArrayLike | None,
        *,
        model: Model = "seed",
    ) -> np.ndarray:
        """Orientation error (Δψ, Δθ, Δγ) of the instrument (GyroWheel study, eqs. (23)–(25)).

        Parameters
        ----------
        angles, errors, model
            As for :meth:`rotation_error` (rad; translations in m).

        Returns
        -------
        ndarray, shape (..., 3)
            (Δψ, Δθ, Δγ) = (ΔR[0,2], ΔR[1,0], ΔR[2,1]) in rad (:data:`COMPONENTS`).

        References
        ----------
        Seed 001, eqs. (17)–(25).
        """
        dr = self.rotation_error(angles, errors, model=model)
        return np.stack([dr[..., i, j] for i, j in _DR_ENTRIES], axis=-1)

    def transform(
        self,
        angles: Sequence[ArrayLike] | Mapping[str, ArrayLike],
        errors: Mapping[str, ArrayLike] | ArrayLike | None,
        *,
        model: Model = "seed",
    ) -> np.ndarray:
        """Actual homogeneous transform T_t = Π iT(i+1), base → instrument (GyroWheel study, eq. (22)).

        Each link is [A·E, A·E·t; 0, 1]: its perfect rotation A (eqs. (17), (19)), its error
        rotation E, then its translation t (eq. (18): E·Trans).

        Parameters
        ----------
        angles, errors, model
            As for :meth:`rotation_error` (rad; translations in m).

        Returns
        -------
        ndarray, shape (..., 4, 4)
            T_t; rotation part dimensionless, translation column in m.

        References
        ----------
        Seed 001, eqs. (17)–(22).
        """
        phis = self._angles(angles)
        ang, off = self._error_values(errors)
        batch = self._batch_shape(phis, ang, off)
        mats = self._link_errors(ang, model)
        t = np.zeros((*batch, 4, 4))
        t[..., :, :] = np.eye(4)
        for plan, e in zip(self._p.links, mats, strict=True):
            link = np.zeros((*batch, 4, 4))
            rot: np.ndarray = np.eye(3)
            if plan.axis >= 0:
                rot = _rotation_matrix(plan.axis, phis[plan.angle])
            if e is not None:
                rot = rot @ e
            link[..., :3, :3] = rot
            link[..., 3, 3] = 1.0
            shift = [(v, a) for i, a in plan.translations if (v := off[i]) is not None]
            if shift:
                vec = np.zeros((*np.broadcast_shapes(*(v.shape for v, _ in shift)), 3))
                for v, a in shift:
                    vec[..., a] += v
                link[..., :3, 3] = (rot @ vec[..., None])[..., 0]
            t = t @ link
        return t

    def ideal_transform(self, angles: Sequence[ArrayLike] | Mapping[str, ArrayLike]) -> np.ndarray:
        """Ideal homogeneous transform T_d, the product of the perfect rotations (eq. (21)).

        Parameters
        ----------
        angles : sequence or mapping of array_like
            Rotation angles (rad).

        Returns
        -------
        ndarray, shape (..., 4, 4)

        References
        ----------
        Seed 001, eq. (21).
        """
        return self.transform(angles, None)

    def linear_coefficients(
        self, angles: Sequence[ArrayLike] | Mapping[str, ArrayLike]
    ) -> np.ndarray:
        """First-order coefficients ∂(Δψ, Δθ, Δγ)/∂χ_i at χ = 0: the generalised eq. (26).

        ΔR ≈ I + Σ_k skew(S_kᵀ·e_k) with S_k the product of the perfect rotations after link k, so
        an error of link k about its axis a contributes row a of S_k (the same for both models).
        For the GyroWheel study's table this is eq. (26): e.g. ∂Δψ/∂Δφy1 = cos φ2, ∂Δγ/∂Δφy1 = sin φ2.

        Parameters
        ----------
        angles : sequence or mapping of array_like
            Rotation angles (rad), broadcast together.

        Returns
        -------
        ndarray, shape (..., 3, n_angular)
            rad/rad; rows :data:`COMPONENTS`, columns :attr:`angular_error_names`.

        References
        ----------
        Seed 001, eqs. (26)–(28).
        """
        phis = self._angles(angles)
        batch = self._batch_shape(phis, [], [])  # no errors: names the angle at fault
        n = len(self._p.angular)
        out = np.zeros((*batch, 3, n))
        suffix: np.ndarray = np.eye(3)
        for plan in reversed(self._p.links):
            for i, a in plan.rotations:
                row = suffix[..., a, :]  # (..., 3): v = S_kᵀ·unit_a
                for c, vi in enumerate(_V_INDEX):
                    out[..., c, i] = row[..., vi]
            if plan.axis >= 0:
                suffix = _rotation_matrix(plan.axis, phis[plan.angle]) @ suffix
        return out

    def point_coefficients(self, angles: np.ndarray) -> np.ndarray:
        """:meth:`linear_coefficients` at one point, for a search that asks for tens of thousands.

        The same products in the same order (each rotation matrix of shape (1, 3, 3) and the
        suffix multiplied by NumPy, as there, so the same bits), without the checks of the angles
        and with the entries gathered as Python floats — NumPy's per-call cost on 3×3 arrays was
        most of a point's time.

        Parameters
        ----------
        angles : ndarray, shape (n_angles,)
            Rotation angles (rad, finite; trusted: not checked), in :attr:`angle_names` order.

        Returns
        -------
        ndarray, shape (3, n_angular)
            rad/rad; rows :data:`COMPONENTS`, columns :attr:`angular_error_names`.

        References
        ----------
        Seed 001, eqs. (26)–(28).
        """
        out = [[0.0] * len(self._p.angular) for _ in range(3)]
        suffix: np.ndarray = np.eye(3)
        for plan in reversed(self._p.links):
            if plan.rotations:
                rows = suffix.reshape(3, 3).tolist()
                for i, a in plan.rotations:
                    for c, vi in enumerate(_V_INDEX):
                        out[c][i] = rows[a][vi]
            if plan.axis >= 0:
                suffix = _point_rotation(plan.axis, angles[plan.angle : plan.angle + 1]) @ suffix
        return np.array(out)

    def sensitivities(
        self, *, step_deg: float | None = None, endpoint: bool | None = None
    ) -> np.ndarray:
        """Mean |∂(Δψ, Δθ, Δγ)/∂χ_i| at χ = 0 over the rotation angles (GyroWheel study, eq. (28)).

        The seed says only that the sensitivities "vary with the rotation angles" and that their
        average values are given (Figure 8). rotacal averages |coefficient| over a grid of every
        angle of the table: 0, step, … below 360° (``endpoint=False``, the default: the unbiased
        mean over a turn, 2/π = 0.6366 for every |sin| and |cos| term at a 1° step), or 0, step,
        …, 360° (``endpoint=True``). The paper's grid is ``step_deg=45, endpoint=True`` (9 points
        per angle, 0° and 360° both counted): for the GyroWheel study's table it gives exactly Figure 8's
        0.6476 (mean |cos φ2|) and 0.5365 (mean |sin φ2|) — the counted-twice 0°/360° points are
        where |cos| = 1 and |sin| = 0, hence the unequal pair. Without arguments the table's own
        choice is used (:attr:`sensitivity_grid`, its ``[sensitivity]`` settings).

        Figure 8 also prints 0.6481/0.5372 for some of the same terms and small values
        0.0021–0.0059 where the linear model has 0. rotacal finds these consistent with central
        finite-difference partials of the full model (eqs. (17)–(25)) at a non-zero nominal error,
        averaged over the paper's grid: at every error ≈ 3·10⁻³ rad the full model gives
        0.6483/0.5375 and insensitive pairs between 0.0018 and 0.0052 (the paper states no nominal
        error; rotacal takes the partials at χ = 0).

        Parameters
        ----------
        step_deg : float, optional
            Grid step (deg); 360/step must be an integer. Default: the table's
            (:attr:`sensitivity_grid`).
        endpoint : bool, optional
            Include 360° as well as 0°. Default: the table's.

        Returns
        -------
        ndarray, shape (3, n_angular)
            rad/rad; rows :data:`COMPONENTS`, columns :attr:`angular_error_names`.

        Raises
        ------
        ConfigError
            A step that is not > 0 or does not divide 360°; an endpoint that is not a bool.

        References
        ----------
        Seed 001, eq. (28) and Figure 8.
        """
        table_step, table_end = self.sensitivity_grid
        step, end = _check_sensitivity_grid(
            table_step if step_deg is None else step_deg,
            table_end if endpoint is None else endpoint,
        )
        count = round(360.0 / step)
        degrees = np.linspace(0.0, 360.0, count + 1) if end else np.arange(count) * (360.0 / count)
        grid = np.radians(degrees)
        n_angles = len(self._p.angle_names)
        if n_angles == 0:
            return np.abs(self.linear_coefficients([]))
        total = np.zeros((3, len(self._p.angular)))
        rest = np.meshgrid(*([grid] * (n_angles - 1)), indexing="ij") if n_angles > 1 else []
        for first in grid:  # a loop over the outermost angle's grid keeps memory flat
            coef = self.linear_coefficients([np.full(1, first), *(g.ravel() for g in rest)])
            total += np.abs(coef).sum(axis=0)
        return total / grid.size**n_angles

    # ------------------------------------------------------------------------ fast path
    def fast_orientation_error(self, angles: np.ndarray, chi: np.ndarray) -> np.ndarray:
        """(Δψ, Δθ, Δγ) of many draws at once, the Monte Carlo path (seed model, eqs. (17)–(24)).

        The same recursion as :meth:`rotation_error` with ``model="seed"``, written as whole-array
        element-wise products of 3×3 matrices kept as nine arrays, in cache-sized chunks; constant
        zeros and ones of each link are skipped. Orientation only: translations cannot change it.
        Inputs are trusted (finite; checked for shape only).

        Parameters
        ----------
        angles : ndarray, shape (N, n_angles)
            Rotation angles (rad), columns :attr:`angle_names`.
        chi : ndarray, shape (N, n_angular)
            Angular errors (rad), columns :attr:`angular_error_names`.

        Returns
        -------
        ndarray, shape (N, 3)
            (Δψ, Δθ, Δγ) in rad.

        References
        ----------
        Seed 001, eqs. (17)–(24).
        """
        angles = np.asarray(angles, dtype=float)
        chi = np.asarray(chi, dtype=float)
        n_angles, n_ang = len(self._p.angle_names), len(self._p.angular)
        if angles.ndim != 2 or angles.shape[1] != n_angles:
            raise ConfigError(
                f"angles must have shape (N, {n_angles}) (columns {', '.join(self.angle_names)}), "
                f"got {angles.shape}."
            )
        if chi.ndim != 2 or chi.shape[1] != n_ang or chi.shape[0] != angles.shape[0]:
            raise ConfigError(
                f"chi must have shape ({angles.shape[0]}, {n_ang}) (columns "
                f"{', '.join(self.angular_error_names)}), got {chi.shape}."
            )
        n = angles.shape[0]
        needs_angle = self._fast_angles()
        if n == 1:
            # One point (the worst case's local search asks for thousands, one at a time): the
            # kernel written out as straight-line code (:func:`_one_point_kernel`) on Python
            # floats, without NumPy's per-operation overhead on 1-element arrays — the same IEEE
            # operations in the same order; cos and sin still by NumPy.
            trig1 = {
                k: (float(np.cos(angles[:, k])[0]), float(np.sin(angles[:, k])[0]))
                for k in needs_angle
            }
            kernel = _one_point_kernel(self._p.links, needs_angle, n_ang)
            return np.array([kernel(trig1, [float(v) for v in chi[0]])], dtype=float)
        out = np.empty((n, 3))
        if numba_enabled():
            compiled_kernel()(
                np.ascontiguousarray(angles),
                np.ascontiguousarray(chi),
                *_chain_arrays(self._p.links),
                out,
            )
            return out
        # the kernel's operations as straight-line code on whole chunks (no per-entry checks)
        kernel = _one_point_kernel(self._p.links, needs_angle, n_ang)
        for start in range(0, n, _FAST_CHUNK):
            stop = min(n, start + _FAST_CHUNK)
            a_t = angles[start:stop].T
            c_t = np.ascontiguousarray(chi[start:stop].T)
            trig = {
                k: (np.cos(a_t[k]), np.sin(a_t[k])) for k in needs_angle
            }  # only angles that do not cancel
            psi, theta, gamma = kernel(trig, c_t)
            out[start:stop, 0] = psi
            out[start:stop, 1] = theta
            out[start:stop, 2] = gamma
        return out

    def fast_angle_trig(self, angles: np.ndarray) -> dict[int, tuple[np.ndarray, np.ndarray]]:
        """cos and sin of the angles :meth:`fast_orientation_error_at` needs, by angle index.

        Parameters
        ----------
        angles : ndarray, shape (N, n_angles)
            Rotation angles (rad), columns :attr:`angle_names`.

        Returns
        -------
        dict
            Angle index → (cos, sin), each of shape (N,); slices of them serve any run of rows.
        """
        angles = np.asarray(angles, dtype=float)
        return {k: (np.cos(angles[:, k]), np.sin(angles[:, k])) for k in self._fast_angles()}

    def fast_orientation_error_at(
        self, trig: dict[int, tuple[np.ndarray, np.ndarray]], chi: np.ndarray, n: int
    ) -> np.ndarray:
        """(Δψ, Δθ, Δγ) of one error vector at n angle points: :meth:`fast_orientation_error`
        for many angles and the same χ, as a search over the vertices of an error box asks.

        The same operations on the same values (each χ_i a 0-d array that broadcasts, so no entry
        is taken for a constant), hence the same numbers, without gathering a row of χ and the
        angles' cos and sin for every point again.

        Parameters
        ----------
        trig : dict
            Of the n points, from :meth:`fast_angle_trig` (or slices of its arrays).
        chi : ndarray, shape (n_angular,)
            Angular errors (rad), columns :attr:`angular_error_names`.
        n : int
            Number of angle points.

        Returns
        -------
        ndarray, shape (n, 3)
            (Δψ, Δθ, Δγ) in rad.

        References
        ----------
        Seed 001, eqs. (17)–(24).
        """
        entries = [np.asarray(float(v)) for v in np.asarray(chi, dtype=float)]
        out = np.empty((n, 3))
        out[:, 0], out[:, 1], out[:, 2] = _fast_kernel(self._p.links, trig, entries)  # type: ignore[arg-type]
        return out

    def _fast_angles(self) -> tuple[int, ...]:
        """Angles whose rotation conjugates a non-identity D (the others cancel exactly)."""
        needed = []
        seen_error = False
        for plan in self._p.links:
            if plan.axis >= 0 and seen_error:
                needed.append(plan.angle)
            if plan.rotations:
                seen_error = True
        return tuple(needed)


# ---------------------------------------------------------------------------- matrix helpers
def _rotation_matrix(axis: int, phi: np.ndarray) -> np.ndarray:
    """Active rotation about x/y/z by φ (rad), as Ry, Rz of eqs. (17), (19): (..., 3, 3)."""
    c, s = np.cos(phi), np.sin(phi)
    out = np.zeros((*np.shape(phi), 3, 3))
    i, j = _PLANE[axis]
    out[..., axis, axis] = 1.0
    out[..., i, i] = c
    out[..., j, j] = c
    out[..., i, j] = -s
    out[..., j, i] = s
    return out


def _point_rotation(axis: int, phi: np.ndarray) -> np.ndarray:
    """:func:`_rotation_matrix` of one angle (φ of shape (1,), rad): the same entries, shape
    (1, 3, 3), built from Python floats (a few µs less per call)."""
    c, s = float(np.cos(phi)[0]), float(np.sin(phi)[0])
    m = [[0.0] * 3 for _ in range(3)]
    i, j = _PLANE[axis]
    m[axis][axis] = 1.0
    m[i][i] = m[j][j] = c
    m[i][j], m[j][i] = -s, s
    return np.array([m])


def _small_angle_matrix(present: list[tuple[np.ndarray, int]]) -> np.ndarray:
    """E(ex, ey, ez) = I + skew(e) of eqs. (17)–(19), errors about the same axis summed."""
    shape = np.broadcast_shapes(*(v.shape for v, _ in present))
    e = np.zeros((*shape, 3))
    for v, a in present:
        e[..., a] += v
    out = np.zeros((*shape, 3, 3))
    out[..., 0, 0] = out[..., 1, 1] = out[..., 2, 2] = 1.0
    out[..., 0, 1] = -e[..., 2]
    out[..., 0, 2] = e[..., 1]
    out[..., 1, 0] = e[..., 2]
    out[..., 1, 2] = -e[..., 0]
    out[..., 2, 0] = -e[..., 1]
    out[..., 2, 1] = e[..., 0]
    return out


def _exact_matrix(present: list[tuple[np.ndarray, int]]) -> np.ndarray:
    """Product of proper elementary rotations in the listed order (scipy Rotation)."""
    from scipy.spatial.transform import Rotation

    shape = np.broadcast_shapes(*(v.shape for v, _ in present))
    size = int(np.prod(shape)) if shape else 1
    total = None
    for v, a in present:
        rotvec = np.zeros((size, 3))
        rotvec[:, a] = np.broadcast_to(v, shape).reshape(-1)
        r = Rotation.from_rotvec(rotvec)
        total = r if total is None else total * r  # total·r: r applied in the moved frame
    assert total is not None
    return np.asarray(total.as_matrix()).reshape(*shape, 3, 3)


_Entry = Any  # float (an exact constant) or ndarray


def _is_const(x: _Entry, value: float) -> bool:
    return isinstance(x, float) and x == value


def _add(a: _Entry, b: _Entry) -> _Entry:
    if _is_const(a, 0.0):
        return b
    if _is_const(b, 0.0):
        return a
    return a + b


def _sub(a: _Entry, b: _Entry) -> _Entry:
    if _is_const(b, 0.0):
        return a
    if _is_const(a, 0.0):
        return -b
    return a - b


def _mul(a: _Entry, b: _Entry) -> _Entry:
    if _is_const(a, 0.0) or _is_const(b, 0.0):
        return 0.0
    if _is_const(a, 1.0):
        return b
    if _is_const(b, 1.0):
        return a
    return a * b


class _Symbol:
    """An entry of :func:`_fast_kernel` as the name of a local variable of generated code: each
    operation on it appends one assignment to ``lines`` (see :func:`_one_point_kernel`)."""

    __slots__ = ("lines", "name")

    def __init__(self, name: str, lines: list[str]) -> None:
        self.name, self.lines = name, lines

    def _new(self, expression: str) -> _Symbol:
        name = f"t{len(self.lines)}"
        self.lines.append(f"    {name} = {expression}")
        return _Symbol(name, self.lines)

    @staticmethod
    def _text(x: Any) -> str:
        return x.name if isinstance(x, _Symbol) else repr(float(x))

    def __add__(self, other: Any) -> _Symbol:
        return self._new(f"{self.name} + {self._text(other)}")

    def __radd__(self, other: Any) -> _Symbol:
        return self._new(f"{self._text(other)} + {self.name}")

    def __sub__(self, other: Any) -> _Symbol:
        return self._new(f"{self.name} - {self._text(other)}")

    def __rsub__(self, other: Any) -> _Symbol:
        return self._new(f"{self._text(other)} - {self.name}")

    def __mul__(self, other: Any) -> _Symbol:
        return self._new(f"{self.name} * {self._text(other)}")

    def __rmul__(self, other: Any) -> _Symbol:
        return self._new(f"{self._text(other)} * {self.name}")

    def __neg__(self) -> _Symbol:
        return self._new(f"-{self.name}")


@functools.lru_cache(maxsize=32)
def _chain_arrays(links: tuple[_LinkPlan, ...]) -> tuple[np.ndarray, ...]:
    """:func:`rotacal.turntable.fast.chain_arrays` of a chain, made once per chain."""
    return chain_arrays(links)


@functools.lru_cache(maxsize=32)
def _one_point_kernel(links: tuple[_LinkPlan, ...], angles: tuple[int, ...], n_angular: int) -> Any:
    """:func:`_fast_kernel` for one chain, generated once as a straight-line Python function
    ``f(trig, chi) -> (Δψ, Δθ, Δγ)``: the kernel run on :class:`_Symbol` entries records every
    operation it does (the constant zeros and ones of the chain skipped as the kernel skips
    them), in its order, so that on floats the function computes exactly what the kernel does
    on arrays."""
    lines: list[str] = []
    trig = {k: (_Symbol(f"c{k}", lines), _Symbol(f"s{k}", lines)) for k in angles}
    chi = [_Symbol(f"x{i}", lines) for i in range(n_angular)]
    result = _fast_kernel(links, trig, chi)  # type: ignore[arg-type]
    head = [f"    c{k}, s{k} = trig[{k}]" for k in angles]
    head += [f"    x{i} = chi[{i}]" for i in range(n_angular)]
    values = ", ".join(_Symbol._text(v) for v in result)
    source = "\n".join(["def kernel(trig, chi):", *head, *lines, f"    return ({values})"])
    namespace: dict[str, Any] = {}
    exec(compile(source, "<rotacal.turntable.model one-point kernel>", "exec"), namespace)
    return namespace["kernel"]


def _fast_kernel(
    links: tuple[_LinkPlan, ...], trig: dict[int, tuple[np.ndarray, np.ndarray]], chi: np.ndarray
) -> tuple[_Entry, _Entry, _Entry]:
    """ΔR[0,2], ΔR[1,0], ΔR[2,1] by D ← Aᵀ·D·A·E with D as nine entries (row-major)."""
    d: list[_Entry] | None = None
    # the last link with errors needs only the three entries of eq. (24) when no rotation follows
    last = len(links) - 1
    while last >= 0 and not links[last].rotations:
        last -= 1
    if any(plan.axis >= 0 for plan in links[last + 1 :]):
        last = -1
    for k, plan in enumerate(links):
        if plan.axis >= 0 and d is not None:
            c, s = trig[plan.angle]
            i, j = _PLANE[plan.axis]
            m = list(d)
            for r in range(3):  # M = D·A: columns i, j mix
                di, dj = d[3 * r + i], d[3 * r + j]
                m[3 * r + i] = _add(_mul(di, c), _mul(dj, s))
                m[3 * r + j] = _sub(_mul(dj, c), _mul(di, s))
            d = list(m)
            for col in range(3):  # Aᵀ·M: rows i, j mix
                mi, mj = m[3 * i + col], m[3 * j + col]
                d[3 * i + col] = _add(_mul(mi, c), _mul(mj, s))
                d[3 * j + col] = _sub(_mul(mj, c), _mul(mi, s))
        if not plan.rotations:
            continue
        e: list[_Entry] = [0.0, 0.0, 0.0]
        for idx, a in plan.rotations:
            e[a] = _add(e[a], chi[idx])
        ex, ey, ez = e
        if d is None:
            d = [1.0, _sub(0.0, ez), ey, ez, 1.0, _sub(0.0, ex), _sub(0.0, ey), ex, 1.0]
            continue
        # D·(I + skew(e)): (D·K)[r] = (D[r,1]ez − D[r,2]ey, D[r,2]ex − D[r,0]ez, D[r,0]ey − D[r,1]ex)
        rows = (
            ((0, 2), (1, 0), (2, 1))
            if k == last
            else tuple((r, c) for r in range(3) for c in range(3))
        )
        new = list(d)
        for r, col in rows:
            d0, d1, d2 = d[3 * r], d[3 * r + 1], d[3 * r + 2]
            if col == 0:
                inc = _sub(_mul(d1, ez), _mul(d2, ey))
            elif col == 1:
                inc = _sub(_mul(d2, ex), _mul(d0, ez))
            else:
                inc = _sub(_mul(d0, ey), _mul(d1, ex))
            new[3 * r + col] = _add(d[3 * r + col], inc)
        d = new
    if d is None:
        return 0.0, 0.0, 0.0
    return d[2], d[3], d[7]


# ------------------------------------------------------------------------------ module level
def load_turntable(
    path_or_text: Any = None, *, text: str | None = None, name: str | None = None
) -> Turntable:
    """A turntable from its TOML description (:func:`rotacal.turntable.config.load_turntable`).

    Parameters
    ----------
    path_or_text : str or path-like, optional
        The TOML file; a ``str`` containing a line break is the TOML text itself.
    text : str, optional
        The TOML text (give either this or ``path_or_text``).
    name : str, optional
        The table's name when the document has none (default: the file's stem).

    Returns
    -------
    Turntable
        Angles, angular errors, lower bounds and requirement in rad (converted from the file's
        ``units``, default arcmin); translations in m (from ``length_units``, default mm).

    Raises
    ------
    ConfigError
        One line naming the file (or "turntable TOML text"), the table and key at fault.

    References
    ----------
    Seed 001, §3.2, Tables 2–3 and eqs. (17)–(22) (the chain); eqs. (16), (29) (requirement,
    lower bounds).
    """
    from rotacal.turntable.config import load_turntable as _load

    return _load(path_or_text, text=text, name=name)


def seed_table() -> Turntable:
    """The two-axis turntable of the GyroWheel study, from the packaged ``tables/seed001.toml``.

    Outer axis about y (φ1), a fixed link (orthogonality, intersection), inner axis about z (φ2);
    errors in the χ order of eq. (25), then η. See :func:`rotacal.turntable.config.seed_table`.

    Returns
    -------
    Turntable
        Requirement 0.027° = 1.62 arcmin per component (eq. (16)), in rad; lower bounds 0.05
        arcmin (rad) for every angular error and 0 m for η — rotacal's stated choice, the paper
        gives none; the paper's sensitivity averaging (``sensitivity_grid`` = (45.0, True)).

    References
    ----------
    Seed 001, Tables 2–3, eqs. (16)–(22), Figure 8.
    """
    from rotacal.turntable.config import seed_table as _seed

    return _seed()


@functools.lru_cache(maxsize=1)
def _seed_cached() -> Turntable:
    return seed_table()


def orientation_error(
    phi1: ArrayLike, phi2: ArrayLike, errors: Mapping[str, ArrayLike]
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Orientation error (Δψ, Δθ, Δγ) of the GyroWheel study's two-axis table (eqs. (17)–(24)).

    Parameters
    ----------
    phi1, phi2 : array_like
        Outer (about y) and inner (about z) rotation angles (rad); broadcast.
    errors : mapping
        ``phi_y1, phi_z2, alpha_x1, alpha_z1, alpha_x2, alpha_y2, eps_x, eps_y`` (rad) and ``eta``
        (m) — or their ISO symbols — to values; missing names are zero; arrays broadcast with the
        angles (e.g. values of shape (k, 1) and angles of shape (m,) give (k, m)).

    Returns
    -------
    dpsi, dtheta, dgamma : ndarray
        rad, each of the broadcast shape.

    Raises
    ------
    ConfigError
        An unknown name, a value that is not a finite number, an angular error beyond 0.1 rad
        (radians are expected), shapes that do not broadcast: one line naming the error or angle.

    References
    ----------
    Seed 001, eqs. (17)–(24), Tables 2–3.
    """
    out = _seed_cached().orientation_error([phi1, phi2], errors)
    return out[..., 0], out[..., 1], out[..., 2]
