"""The turntable: a chain with its errors checked, and its orientation error by 3×3 matrices.

:class:`Turntable` validates a chain against its errors and requirement, resolves names and
aliases, checks the angles and errors a caller gives, and evaluates ΔR = R_dᵀ·R_t (eq. (23)) and
the homogeneous transforms of eqs. (17)–(22) with whole-array matrix products. Its first-order
model (eqs. (26)–(28)) is in :mod:`rotacal.turntable.linear`, the Monte Carlo's path in
:mod:`rotacal.turntable.fast`; :mod:`rotacal.turntable.model` describes the model.

References
----------
Seed 001 (``../shared/seeds/001_4a387eb674e238f2.txt``), §3.2, eqs. (17)–(25), Tables 2–3.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping, Sequence
from typing import Any, cast

import numpy as np
from numpy.typing import ArrayLike

from rotacal.errors import ConfigError
from rotacal.turntable.chain import (
    _AXIS_INDEX,
    _DEFAULT_SENSITIVITY_STEP_DEG,
    _DR_ENTRIES,
    _MAX_SENSITIVITY_POINTS,
    ANGLE_UNITS,
    COMPONENTS,
    LENGTH_UNITS,
    SMALL_ANGLE_LIMIT_RAD,
    ErrorSpec,
    Link,
    Model,
    _alias_map,
    _broadcast,
    _chain_kinds,
    _check_chain,
    _check_sensitivity_grid,
    _check_small,
    _default_label,
    _float_array,
    _LinkPlan,
    _Plan,
    _short,
)
from rotacal.turntable.fast import _FastPath
from rotacal.turntable.linear import _FirstOrder
from rotacal.turntable.matrices import (
    _exact_matrix,
    _rotation_matrix,
    _small_angle_matrix,
)

__all__ = ["Turntable"]


@dataclasses.dataclass(frozen=True)
class Turntable(_FirstOrder, _FastPath):
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
