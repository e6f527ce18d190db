"""The orientation requirement a turntable is allocated for, derived from a calibration accuracy.

A table description may state its orientation requirement (Iψ, Iθ, Iγ) or only the calibration
accuracy ωm of the multiposition drift test it serves (``[requirement] calibration_deg_h``). Two
derivations turn ωm into the requirement of the allocation (``[requirement] derivation`` in the
TOML, ``--requirement-derivation`` on ``rotacal turntable budget``):

``"calibration-check"`` (default)
    The tables the allocation admits must keep the calibration within ωm in the model of the
    budget's calibration check: every test position of the plan sees its own orientation error
    (eq. (23), full model; it varies with φ2 by eq. (26)), the drift coefficients are fitted with
    the nominal inputs and Δωx, Δωy follow (eqs. (8)–(14)). The requirement is the box of
    eqs. (15)–(16) (:func:`~rotacal.turntable.calibration.orientation_requirement`, largest volume
    for one orientation error at every position) times the factor s for which the worst table
    within the allocated bounds reaches ωm: the rate error is linear in the table's errors χ to
    ~10⁻⁴, so its worst case over the box |χ_i| ≤ UB_i at position p is Σ_i |∂Δω_p/∂χ_i|·UB_i
    (the same argument as Lemma 1), checked with the full model at that sign vertex of every
    position. A few allocations find s (the allocation is homogeneous in the requirement up to
    the lower bounds and second-order terms).

``"earth-rate-only"``
    The paper's reading of eq. (16): the orientation error changes only what the gyro reads of
    the Earth rate (``b2' − b2``; no gravity terms, no fit — method ``"earth-rate"`` of
    :mod:`rotacal.turntable.calibration`), equal limits on the three components. For ωm =
    0.01 °/h that is ωm/(√2·Ωe) = 0.02694° (eq. (16) prints 0.027°) when the plan has a position
    with the Earth rate at 45° between two gyro axes (the default plan at latitude 45.75° gives
    0.026938°). The drift fit, through the g-sensitive coefficients of Table 1 (tens of °/h/g),
    turns the same orientation error into rate errors several times larger: tables allocated
    this way fail the calibration check (seed table: 35 % of them on x, 50 % on y).

References
----------
Seed 001 (``../shared/seeds/001_4a387eb674e238f2.txt``): eqs. (7)–(16), (23), (26), (31)–(34),
Lemma 1, Table 1.
"""

from __future__ import annotations

import dataclasses
import itertools
import math
from collections.abc import Mapping
from typing import Any

import numpy as np

from rotacal.errors import ConfigError
from rotacal.turntable.allocation import Allocation, allocate
from rotacal.turntable.calibration import (
    OrientationRequirement,
    orientation_requirement,
    rate_error_vectors_from_rotation,
)
from rotacal.turntable.chain import COMPONENTS, SMALL_ANGLE_LIMIT_RAD
from rotacal.turntable.geometry import Turntable

__all__ = [
    "DEFAULT_DERIVATION",
    "DERIVATIONS",
    "DerivedRequirement",
    "calibration_response",
    "calibration_worst_case",
    "check_derivation",
    "derive_requirement",
]

#: How an orientation requirement is derived from a calibration accuracy (see the module).
DERIVATIONS = ("calibration-check", "earth-rate-only")
DEFAULT_DERIVATION = "calibration-check"

#: Step of the central differences of the calibration response (rad): the response is linear
#: to ~10⁻⁴ relative at 10⁻⁴ rad, so the O(h²) error is ~10⁻⁶ relative and rounding ~10⁻⁹.
_STEP_RAD = 1e-7
#: The scale is accepted when the worst table reaches between (1 − this)·ωm and ωm ...
_ACCEPT = 1e-3
#: ... and aimed this far below ωm, so that second-order terms rarely need another allocation.
_AIM = 1e-4
_MAX_ALLOCATIONS = 5
#: Up to this many errors the full model is evaluated at every sign vertex of the box (2¹⁰).
_MAX_VERTEX_ERRORS = 10


def check_derivation(value: Any, where: str) -> str:
    """``value`` as one of :data:`DERIVATIONS`; else one ConfigError line naming ``where``."""
    if value not in DERIVATIONS:
        raise ConfigError(
            f"{where} = {value!r} is unknown: use 'calibration-check' (tables built to the "
            "allocation keep the calibration within its accuracy) or 'earth-rate-only' (the GyroWheel study's "
            "eq. (16): the Earth-rate reading alone)."
        )
    return str(value)


def _check_plan(table: Turntable) -> None:
    axes = [link.axis for link in table.links if link.axis is not None]
    if axes != ["y", "z"]:
        raise ConfigError(
            "a calibration accuracy needs a table of the GyroWheel study's geometry (an outer axis about y, "
            "then an inner axis about z): the multiposition kinematics of eq. (3) assume it; "
            "state [requirement] psi, theta, gamma for this table instead."
        )


def _rate_vectors(
    table: Turntable, chi: np.ndarray, p1: np.ndarray, p2: np.ndarray, latitude_deg: float
) -> np.ndarray:
    """Δω_vec of both axes (°/h) for tables χ (k, n_err): shape (2, k, positions)."""
    names = table.angular_error_names
    errors = {n: chi[:, i, None] for i, n in enumerate(names)}
    delta_r = table.rotation_error([np.radians(p1), np.radians(p2)], errors)
    dwx, dwy = rate_error_vectors_from_rotation(
        delta_r, phi1_deg=p1, phi2_deg=p2, latitude_deg=latitude_deg
    )
    return np.stack([np.asarray(dwx), np.asarray(dwy)])


def calibration_response(
    table: Turntable, *, phi1_deg: np.ndarray, phi2_deg: np.ndarray, latitude_deg: float
) -> np.ndarray:
    """∂Δω/∂χ of the multiposition calibration at every test position (°/h per rad).

    Central differences (step 10⁻⁷ rad) of the calibration check's model: the orientation error of
    each position from the table's full model (eq. (23)), the rate-sensing error vectors of
    eqs. (8)–(13) (rotacal's reading, method ``"coefficients"``).

    Parameters
    ----------
    table : Turntable
        A table of the GyroWheel study's geometry.
    phi1_deg, phi2_deg : ndarray
        The plan's outer and inner angles (deg).
    latitude_deg : float
        Latitude (deg).

    Returns
    -------
    ndarray, shape (2, positions, angular errors)
        Axis x then y.

    References
    ----------
    Seed 001, eqs. (8)–(13), (23), (26).
    """
    n = len(table.angular_error_names)
    step = _STEP_RAD * np.eye(n)
    up = _rate_vectors(table, step, phi1_deg, phi2_deg, latitude_deg)
    down = _rate_vectors(table, -step, phi1_deg, phi2_deg, latitude_deg)
    return np.transpose((up - down) / (2.0 * _STEP_RAD), (0, 2, 1))


def calibration_worst_case(
    table: Turntable,
    upper_bounds_rad: Mapping[str, float | None],
    *,
    phi1_deg: np.ndarray,
    phi2_deg: np.ndarray,
    latitude_deg: float,
    response: np.ndarray | None = None,
) -> dict[str, Any]:
    """The worst calibration error of any table whose errors satisfy |χ_i| ≤ UB_i.

    Linear: at position p of axis a, max over the box of |Δω| is Σ_i |∂Δω_p/∂χ_i|·UB_i, reached at
    the sign vertex χ_i = sign(∂Δω_p/∂χ_i)·UB_i. Full model: the largest Δωx, Δωy of the
    calibration check's model over every sign vertex χ = ±UB (tables of up to 10 errors; else over
    the linear worst vertex of every position and axis). The response is linear in χ to ~10⁻⁴, so
    moving inward from a vertex loses more at first order than the second-order terms can gain:
    the vertices are the worst points of the box.

    Parameters
    ----------
    table : Turntable
        A table of the GyroWheel study's geometry.
    upper_bounds_rad : mapping
        UB_i (rad; ``None`` or absent: the error is zero).
    phi1_deg, phi2_deg, latitude_deg
        The plan (deg) and latitude (deg).
    response : ndarray, optional
        :func:`calibration_response` for this table and plan (computed when absent).

    Returns
    -------
    dict
        ``linear_deg_h`` and ``full_deg_h``: {"x", "y"} (°/h); ``worst_deg_h``: the larger of all
        four.

    References
    ----------
    Seed 001, eqs. (8)–(14), (23), Lemma 1.
    """
    m = (
        calibration_response(table, phi1_deg=phi1_deg, phi2_deg=phi2_deg, latitude_deg=latitude_deg)
        if response is None
        else response
    )
    ub = np.array([float(upper_bounds_rad.get(n) or 0.0) for n in table.angular_error_names])
    linear = np.max(np.abs(m) @ ub, axis=1)  # (2,)
    if ub.size <= _MAX_VERTEX_ERRORS:  # every vertex: the second-order terms may pick another
        signs = np.array(list(itertools.product((1.0, -1.0), repeat=ub.size)))
    else:  # the linear worst vertex of every position and axis
        signs = np.where(m >= 0.0, 1.0, -1.0).reshape(-1, ub.size)
    vertices = signs * ub
    full = np.max(np.abs(_rate_vectors(table, vertices, phi1_deg, phi2_deg, latitude_deg)), (1, 2))
    return {
        "linear_deg_h": {"x": float(linear[0]), "y": float(linear[1])},
        "full_deg_h": {"x": float(full[0]), "y": float(full[1])},
        "worst_deg_h": float(max(np.max(linear), np.max(full))),
    }


@dataclasses.dataclass(frozen=True)
class DerivedRequirement:
    """An orientation requirement derived from a calibration accuracy, and its allocation.

    ``requirement_rad`` is what the allocation was made for; ``box`` the requirement of
    eqs. (15)–(16) by rotacal's reading (drawn in the report); ``scale`` the factor on the box
    (``"calibration-check"``; ``None`` for ``"earth-rate-only"``); ``earth_rate`` the equal limit of
    the Earth-rate reading (``"earth-rate-only"``, else ``None``); ``worst`` the
    :func:`calibration_worst_case` of the allocation; ``allocations`` how many were made.
    """

    derivation: str
    required_deg_h: float
    requirement_rad: dict[str, float]
    box: OrientationRequirement
    earth_rate: OrientationRequirement | None
    scale: float | None
    allocation: Allocation
    worst: dict[str, Any]
    allocations: int

    def to_dict(self) -> dict[str, Any]:
        """The JSON of the derivation (without the allocation, which the budget reports)."""
        out: dict[str, Any] = {
            "derivation": self.derivation,
            "required_deg_h": self.required_deg_h,
            "requirement_deg": {c: math.degrees(v) for c, v in self.requirement_rad.items()},
            "allocations": self.allocations,
            "worst_table_rate_error_deg_h": self.worst,
        }
        if self.scale is not None:
            out["scale_of_box"] = self.scale
            out["box_deg"] = dict(self.box.limits_deg)
        if self.earth_rate is not None:
            out["earth_rate_equal_limit_deg"] = self.earth_rate.equal_limit_deg
        return out


def derive_requirement(
    table: Turntable,
    required_deg_h: float,
    derivation: str = DEFAULT_DERIVATION,
    *,
    phi1_deg: np.ndarray,
    phi2_deg: np.ndarray,
    latitude_deg: float,
    constraint_step_deg: float | None = None,
) -> DerivedRequirement:
    """The orientation requirement for a calibration accuracy ωm, and the allocation made for it.

    See the module docstring for the two derivations.

    Parameters
    ----------
    table : Turntable
        A table of the GyroWheel study's geometry (outer axis about y, inner about z).
    required_deg_h : float
        Calibration accuracy ωm (°/h, > 0).
    derivation : {"calibration-check", "earth-rate-only"}
        How the requirement follows from ωm.
    phi1_deg, phi2_deg : ndarray
        The multiposition plan (deg).
    latitude_deg : float
        Latitude (deg).
    constraint_step_deg : float, optional
        Passed to :func:`~rotacal.turntable.allocation.allocate`.

    Returns
    -------
    DerivedRequirement

    Raises
    ------
    ConfigError
        An unknown derivation, a table not of the GyroWheel study's geometry, a non-positive ωm, lower bounds
        that leave no allocation for the derived requirement.

    References
    ----------
    Seed 001, eqs. (7)–(16), (23), (26), (31)–(34), Lemma 1.
    """
    derivation = check_derivation(derivation, "the requirement derivation")
    _check_plan(table)
    p1, p2, lat = phi1_deg, phi2_deg, latitude_deg
    box = orientation_requirement(required_deg_h, phi1_deg=p1, phi2_deg=p2, latitude_deg=lat)
    wm = box.required_deg_h
    response = calibration_response(table, phi1_deg=p1, phi2_deg=p2, latitude_deg=lat)

    def allocated(req: dict[str, float]) -> tuple[Allocation, dict[str, Any]]:
        alloc = allocate(table, req, constraint_step_deg=constraint_step_deg)
        worst = calibration_worst_case(
            table,
            alloc.upper_bounds_rad,
            phi1_deg=p1,
            phi2_deg=p2,
            latitude_deg=lat,
            response=response,
        )
        return alloc, worst

    if derivation == "earth-rate-only":
        earth = orientation_requirement(
            wm, phi1_deg=p1, phi2_deg=p2, latitude_deg=lat, method="earth-rate"
        )
        req = dict.fromkeys(COMPONENTS, earth.equal_limit_rad)
        alloc, worst = allocated(req)
        return DerivedRequirement(derivation, wm, req, box, earth, None, alloc, worst, 1)

    shape = np.array([box.limits_rad[c] for c in COMPONENTS])
    scale, best, count = 1.0, None, 0
    while count < _MAX_ALLOCATIONS:
        count += 1
        req = dict(zip(COMPONENTS, np.minimum(scale * shape, SMALL_ANGLE_LIMIT_RAD), strict=True))
        alloc, worst = allocated({c: float(v) for c, v in req.items()})
        if worst["worst_deg_h"] <= wm:
            best = (scale, req, alloc, worst)
            if worst["worst_deg_h"] >= wm * (1.0 - _ACCEPT):
                break
        scale *= wm / worst["worst_deg_h"] * (1.0 - _AIM)
    if best is None:
        raise ConfigError(
            f"no allocation keeps the calibration within {wm:g} °/h: even the tightest tried "
            f"leaves {worst['worst_deg_h']:.4g} °/h; lower the [errors] lower bounds or relax "
            "calibration_deg_h."
        )
    scale, req, alloc, worst = best
    return DerivedRequirement(
        derivation,
        wm,
        {c: float(v) for c, v in req.items()},
        box,
        None,
        float(scale),
        alloc,
        worst,
        count,
    )
