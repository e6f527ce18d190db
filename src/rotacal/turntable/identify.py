"""Identify a turntable's geometric errors from orientation errors measured at many positions.

The inverse of the GyroWheel study's error model (seed 001, §3.2, eqs. (17)–(25)): given the
orientation error (Δψ, Δθ, Δγ) of the instrument measured at positions (φ1, φ2) — with an
autocollimator and a mirror cube, or a reference IMU — estimate the table's errors χ by
nonlinear least squares on the full model, the same rotation matrices :meth:`Turntable.orientation_error`
uses (``model="seed"``: the small-angle matrices multiplied as printed in eqs. (17)–(19);
``model="exact"``: proper rotations in Table 3's order).

**Fit.** Gauss–Newton from χ = 0 with steps restricted to the separable subspace (the truncated
SVD of the Jacobian, columns in rad/rad, central differences of the model): at each iteration
δ = V_r·Σ_r⁻¹·U_rᵀ·(y − f(χ)) over the top r singular directions, so the directions the data
cannot see stay at zero (a minimum-norm solution) instead of wandering. The rank r counts the
singular values of the first-order Jacobian (eq. (26)) above ``rcond``·σ_max; at the solution the
Jacobian of the full model is checked against the same tolerance (a warning when its second-order
terms would lift a further direction above it). The model is a polynomial of low degree in χ
(products of three error matrices), so it converges in two or three iterations.

**Uncertainty.** s² = Σ residual² / ν with ν = 3n − r degrees of freedom (one pooled variance for
the three components), and Cov(χ̂) = s²·(JᵀJ)⁺ with the pseudo-inverse truncated at rank r
(Jacobian at the solution); U = k·u with k the Student t quantile for ν at 95 % (GUM G.3).

**Separability.** To first order (eq. (26)) the orientation error of the GyroWheel study's table
depends only on φ2 and on five sums: Δφy1 + Δεy, Δαx1 + Δεx, Δαy2, Δαx2 and Δφz2 + Δαz1 (and
not on η at all: "the intersection error has no effect on the orientation error", after eq. (25)).
The full model sees the individual errors only through products of two errors, whose share of the
Jacobian is of order |χ| (≈10⁻⁴ for a table within its allocation) — below ``rcond`` = 10⁻³: such
directions are reported as inseparable rather than estimated with a u larger than the error
itself. The separable combinations are read from the row space of the first-order Jacobian (at
χ = 0, :meth:`Turntable.linear_coefficients`, where they are exact sums) in reduced row-echelon
form with the errors in χ order, so they come out as named sums; each is estimated as C·χ̂ with u from C·Cov·Cᵀ. An error is
identifiable alone when its unit vector lies in that row space. Parameters the positions cannot
separate are grouped (connected through the null space) and each group says what further
measurement would separate it (:func:`rotacal.turntable.identify_design.advice`).

References
----------
Seed 001 (``../shared/seeds/001_4a387eb674e238f2.txt``), §3.2, eqs. (17)–(26), Tables 2–3.
JCGM 100:2008 (GUM), §G.3–G.4 (t-factor for ν degrees of freedom).
Björck, Å., *Numerical Methods for Least Squares Problems*, SIAM 1996, §2.7 (truncated SVD,
numerical rank) and §9.2 (Gauss–Newton).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from typing import Any, cast

import numpy as np
from numpy.typing import ArrayLike

from rotacal.errors import CaptureError, ConfigError
from rotacal.results import Result
from rotacal.turntable.chain import COMPONENTS, SMALL_ANGLE_LIMIT_RAD, Model
from rotacal.turntable.geometry import Turntable
from rotacal.turntable.identify_design import (
    advice,
    compare_with_bounds,
    first_order_rows,
    groups_of,
    recommend,
    right_singular,
)

__all__ = ["ARCSEC", "TurntableIdentification", "identify_turntable", "model_and_jacobian"]

#: One arc second in radians.
ARCSEC = math.pi / (180.0 * 3600.0)
#: Relative step of the central differences (rad): the model is a cubic in χ, so the truncation
#: error is ~h² and the rounding error ~ε/h, both far below the rank tolerance.
_STEP_RAD = 1e-6
_MAX_ITERATIONS = 30
#: The measured angles' range (deg): one turn either way.
_ANGLE_LIMIT_DEG = 360.0
_COVERAGE = 0.95
#: The smallest rank tolerance: the first-order Jacobian's null directions are zero to ~1e-16.
_RCOND_MIN = 1e-9
#: Entries of a first-order row basis below this are zeros (they are exact 0, ±1, cos, sin).
_TINY = 1e-9


@dataclasses.dataclass(frozen=True)
class TurntableIdentification(Result):
    """A turntable's geometric errors identified from measured orientation errors.

    Attributes
    ----------
    errors_arcsec, errors_u_arcsec : dict
        Every error of the table (names as in :func:`orientation_error`) → estimate and standard
        uncertainty (arcsec); ``None`` for an error the positions cannot separate (see
        ``unidentifiable`` and ``combinations``) and for translations (not seen by orientation).
    unidentifiable : tuple of str
        The errors the data cannot estimate alone.
    combinations : tuple of dict
        The separable linear combinations: ``name`` (e.g. ``"phi_y1 + eps_y"``), ``coefficients``,
        ``value_arcsec``, ``u_arcsec``, ``U_arcsec``.
    inseparable : tuple of dict
        Groups of errors the positions cannot separate: ``names``, ``structural`` (no position of
        this chain separates them) and ``separate_by`` (what further measurement would).
    positions, rank, dof : int
        Number of positions n, separable combinations r, degrees of freedom ν = 3n − r.
    s_arcsec : float
        Residual standard deviation (arcsec), pooled over the three components.
    residual_rms_arcsec : dict
        Residual rms of each component (psi, theta, gamma), arcsec.
    residuals_arcsec : dict
        Residual of each component at each position (arcsec), in the capture's order.
    k, coverage_probability : float
        U = k·u, k the t quantile for ``dof``.
    singular_values_relative : list of float
        σ_i/σ_max of the Jacobian at the solution (rad/rad columns).
    rcond : float
        Numerical-rank tolerance on σ_i/σ_max.
    model : str
        ``"seed"`` or ``"exact"`` (:meth:`Turntable.orientation_error`).
    iterations : int
        Gauss–Newton iterations.
    table : str
        The table's name.
    next_positions_deg, design : list, dict
        Positions to measure next and the criterion (:mod:`rotacal.turntable.identify_design`).
    allocation : dict or None
        The estimates against an allocation's upper bounds (:func:`compare_with_bounds`).
    """

    errors_arcsec: dict[str, float | None]
    errors_u_arcsec: dict[str, float | None]
    unidentifiable: tuple[str, ...]
    combinations: tuple[dict[str, Any], ...]
    inseparable: tuple[dict[str, Any], ...]
    positions: int
    rank: int
    dof: int
    s_arcsec: float
    residual_rms_arcsec: dict[str, float]
    residuals_arcsec: dict[str, list[float]]
    k: float
    coverage_probability: float
    singular_values_relative: list[float]
    rcond: float
    model: str
    iterations: int
    table: str
    next_positions_deg: list[list[float]] = dataclasses.field(default_factory=list)
    design: dict[str, Any] = dataclasses.field(default_factory=dict)
    allocation: dict[str, Any] | None = None
    _plot: dict[str, Any] = dataclasses.field(default_factory=dict, repr=False)


# ------------------------------------------------------------------------------------ inputs
def _column(values: ArrayLike, name: str) -> np.ndarray:
    try:
        arr = np.asarray(values, dtype=float).reshape(-1)
    except (TypeError, ValueError):
        raise CaptureError(f"column {name!r} must hold numbers.") from None
    bad = np.flatnonzero(~np.isfinite(arr))
    if bad.size:
        raise CaptureError(
            f"column {name!r} has a non-finite value ({arr[bad[0]]}) at data row {bad[0] + 1}: "
            "remove or repair that position."
        )
    return arr


def _inputs(
    phi1_deg: ArrayLike,
    phi2_deg: ArrayLike,
    dpsi_arcsec: ArrayLike,
    dtheta_arcsec: ArrayLike,
    dgamma_arcsec: ArrayLike,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(φ1, φ2) in rad and y (n, 3) in rad, validated: finite, equal lengths, in range."""
    names = ("phi1_deg", "phi2_deg", "dpsi_arcsec", "dtheta_arcsec", "dgamma_arcsec")
    cols = [
        _column(v, n)
        for v, n in zip(
            (phi1_deg, phi2_deg, dpsi_arcsec, dtheta_arcsec, dgamma_arcsec), names, strict=True
        )
    ]
    n = cols[0].size
    for c, name in zip(cols, names, strict=True):
        if c.size != n:
            raise CaptureError(
                f"column {name!r} has {c.size} rows, phi1_deg has {n}: every column needs one "
                "value per position."
            )
    for c, name in zip(cols[:2], names[:2], strict=True):
        out = np.flatnonzero(np.abs(c) > _ANGLE_LIMIT_DEG)
        if out.size:
            raise CaptureError(
                f"column {name!r} data row {out[0] + 1}: {c[out[0]]:g}° is outside ±360°; give "
                "the turntable angle in degrees."
            )
    limit = SMALL_ANGLE_LIMIT_RAD / ARCSEC
    for c, name in zip(cols[2:], names[2:], strict=True):
        out = np.flatnonzero(np.abs(c) > limit)
        if out.size:
            raise CaptureError(
                f"column {name!r} data row {out[0] + 1}: {c[out[0]]:g} arcsec is beyond the small-angle "
                f"model's {limit:.0f} arcsec (0.1 rad); give orientation errors in arcsec."
            )
    y = np.stack([cols[2], cols[3], cols[4]], axis=-1) * ARCSEC
    return np.radians(cols[0]), np.radians(cols[1]), y


def _two_angles(table: Turntable) -> None:
    if len(table.angle_names) != 2:
        raise ConfigError(
            f"{table.source or table.name}: identification reads two angles (phi1_deg, "
            f"phi2_deg); this table has {len(table.angle_names)} "
            f"({', '.join(table.angle_names)})."
        )


# ------------------------------------------------------------------------------------ model
def model_and_jacobian(
    table: Turntable, phi1: np.ndarray, phi2: np.ndarray, chi: np.ndarray, model: str
) -> tuple[np.ndarray, np.ndarray]:
    """f(χ) (n, 3) and its Jacobian ∂f/∂χ (3n, p), rows position-major (ψ, θ, γ per position).

    Central differences of :meth:`Turntable.orientation_error` (rad, errors in χ order), all
    2p + 1 evaluations in one broadcast call.
    """
    p = chi.size
    shifts = np.zeros((2 * p + 1, p))
    shifts[1 : p + 1] = np.eye(p) * _STEP_RAD
    shifts[p + 1 :] = -np.eye(p) * _STEP_RAD
    values = table.orientation_error(
        [phi1, phi2], (chi + shifts)[:, None, :], model=cast(Model, model)
    )
    jac = (values[1 : p + 1] - values[p + 1 :]) / (2.0 * _STEP_RAD)  # (p, n, 3)
    return values[0], jac.reshape(p, -1).T


def _rref(rows: np.ndarray) -> np.ndarray:
    """Reduced row-echelon form of a row basis (r, p), pivots in column order; tiny → 0."""
    a = np.array(rows, dtype=float)
    r = 0
    for col in range(a.shape[1]):
        if r == a.shape[0]:
            break
        pivot = r + int(np.argmax(np.abs(a[r:, col])))
        if abs(a[pivot, col]) < 1e-6:
            continue
        a[[r, pivot]] = a[[pivot, r]]
        a[r] /= a[r, col]
        for i in range(a.shape[0]):
            if i != r:
                a[i] -= a[i, col] * a[r]
        r += 1
    a[np.abs(a) < _TINY] = 0.0
    return a[:r]


def _combination_name(coefficients: Mapping[str, float]) -> str:
    text = ""
    for name, c in coefficients.items():
        sign = "−" if c < 0 else "+"
        mag = abs(c)
        term = name if abs(mag - 1.0) < 1e-9 else f"{mag:.4g}·{name}"
        text += f"{'−' if c < 0 else ''}{term}" if not text else f" {sign} {term}"
    return text


def _fit(
    table: Turntable,
    phi1: np.ndarray,
    phi2: np.ndarray,
    y: np.ndarray,
    model: str,
    rank: int,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, int]:
    """Gauss–Newton on the top-``rank`` right singular directions of the Jacobian at each
    iterate (a truncated-SVD step): (χ̂, f(χ̂), J(χ̂), iterations)."""
    chi = np.zeros(len(table.angular_error_names))
    target = y.reshape(-1)
    iterations = 0
    while iterations < _MAX_ITERATIONS:
        iterations += 1
        f, jac = model_and_jacobian(table, phi1, phi2, chi, model)
        u, s, vt = np.linalg.svd(jac, full_matrices=False)
        step = vt[:rank].T @ ((u[:, :rank].T @ (target - f.reshape(-1))) / s[:rank])
        chi = chi + step
        if np.max(np.abs(chi)) > SMALL_ANGLE_LIMIT_RAD:
            raise CaptureError(
                "the fit leaves the small-angle model (an error beyond 0.1 rad): the orientation "
                "errors are not in arcsec, or the table's chain is not the one measured."
            )
        if np.max(np.abs(step)) <= 1e-10 * max(float(np.max(np.abs(chi))), ARCSEC):
            break
    f, jac = model_and_jacobian(table, phi1, phi2, chi, model)
    return chi, f, jac, iterations


def identify_turntable(
    phi1_deg: ArrayLike,
    phi2_deg: ArrayLike,
    dpsi_arcsec: ArrayLike,
    dtheta_arcsec: ArrayLike,
    dgamma_arcsec: ArrayLike,
    *,
    table: Turntable | None = None,
    model: str = "seed",
    rcond: float = 1e-3,
    bounds_arcsec: Mapping[str, float | None] | None = None,
    bounds_source: str = "",
    next_positions: int = 6,
    design_step_deg: float = 30.0,
) -> TurntableIdentification:
    """The geometric errors of a turntable from its orientation errors at n positions.

    Nonlinear least squares on the full model of the GyroWheel study, eqs. (17)–(25) (see the
    module docstring for the fit, the uncertainty and the separability analysis).

    Parameters
    ----------
    phi1_deg, phi2_deg : array_like, shape (n,)
        Outer and inner axis angles of each position (deg, within ±360°).
    dpsi_arcsec, dtheta_arcsec, dgamma_arcsec : array_like, shape (n,)
        Measured orientation error about the instrument's y, z and x axes (arcsec, eq. (24)).
    table : Turntable, optional
        The chain (two rotary axes); default :func:`seed_table`.
    model : {"seed", "exact"}
        The forward model's error matrices (:meth:`Turntable.orientation_error`).
    rcond : float
        Directions of the Jacobian with σ_i < rcond·σ_max are inseparable (10⁻⁹ ≤ rcond < 1).
    bounds_arcsec : mapping, optional
        Upper bounds of an allocation (arcsec; ``None`` for no bound) to compare with.
    bounds_source : str
        Where the bounds came from (named in the comparison).
    next_positions : int
        How many positions to recommend (0: none).
    design_step_deg : float
        Step of the (φ1, φ2) candidate grid of the recommendation (deg, dividing 360).

    Returns
    -------
    TurntableIdentification

    Raises
    ------
    CaptureError
        A non-finite value, an angle beyond ±360°, an orientation error beyond 0.1 rad, columns
        of unequal length, too few positions for ν ≥ 1 (one line naming the column and row).
    ConfigError
        A table that does not have two rotary axes; a bad ``model``, ``rcond`` or design option.

    References
    ----------
    Seed 001, eqs. (17)–(26); GUM §G.3.
    """
    from rotacal.turntable.model import _seed_cached
    from rotacal.uncertainty.quantiles import t_ppf

    if model not in ("seed", "exact"):
        raise ConfigError(f"model {model!r} is unknown: use 'seed' or 'exact'.")
    if not (isinstance(rcond, (int, float)) and _RCOND_MIN <= float(rcond) < 1.0):
        raise ConfigError(
            f"rcond must be a number from {_RCOND_MIN:g} to below 1 (default 1e-3), got {rcond!r}: "
            "below it, rounding noise of the Jacobian would count as a separable direction."
        )
    table = _seed_cached() if table is None else table
    _two_angles(table)
    phi1, phi2, y = _inputs(phi1_deg, phi2_deg, dpsi_arcsec, dtheta_arcsec, dgamma_arcsec)
    n = phi1.size
    if n < 2:
        raise CaptureError(
            f"{n} position{'s' if n != 1 else ''}: identification needs at least 2 (each gives "
            "3 readings; the table has up to 5 separable combinations)."
        )
    names = table.angular_error_names
    # the rank from the first-order Jacobian (exact 0, ±1, sines and cosines), checked at the
    # solution below: the full model adds products of errors, O(|χ|) of the Jacobian
    sv0, vt0 = right_singular(first_order_rows(table, phi1, phi2))
    rank = int(np.sum(sv0 > rcond * sv0[0])) if sv0[0] > 0 else 0
    chi, f, jac, iterations = _fit(table, phi1, phi2, y, model, rank)
    dof = 3 * n - rank
    if dof < 1:
        raise CaptureError(
            f"{n} positions give {3 * n} readings for {rank} separable combinations: no degree "
            f"of freedom is left for the uncertainty; measure at least {rank // 3 + 1} positions."
        )
    resid = y - f
    s2 = float(np.sum(resid**2)) / dof
    _, sv, vt = np.linalg.svd(jac, full_matrices=False)
    cov = s2 * (vt[:rank].T / sv[:rank] ** 2) @ vt[:rank]
    second_order = sv.size > rank and sv[rank] > rcond * sv[0]

    # separable combinations from the first-order row space (exact sums at χ = 0)
    rows = _rref(vt0[:rank])
    k = t_ppf(0.5 + _COVERAGE / 2.0, dof)
    combos = []
    for row in rows:
        coefficients = {names[i]: round(float(row[i]), 12) for i in np.flatnonzero(row)}
        u = math.sqrt(max(float(row @ cov @ row), 0.0)) / ARCSEC
        combos.append(
            {
                "name": _combination_name(coefficients),
                "coefficients": coefficients,
                "value_arcsec": float(row @ chi) / ARCSEC,
                "u_arcsec": u,
                "U_arcsec": k * u,
            }
        )
    basis = vt0[:rank]
    alone = [
        np.linalg.norm(np.eye(chi.size)[i] - basis.T @ basis[:, i]) < 1e-6 for i in range(chi.size)
    ]
    errors: dict[str, float | None] = {}
    errors_u: dict[str, float | None] = {}
    for i, name in enumerate(names):
        errors[name] = float(chi[i]) / ARCSEC if alone[i] else None
        errors_u[name] = math.sqrt(max(float(cov[i, i]), 0.0)) / ARCSEC if alone[i] else None
    for name in table.offset_names:
        errors[name] = errors_u[name] = None
    unidentifiable = tuple(n_ for n_ in table.error_names if errors[n_] is None)

    null = vt0[rank:].T
    groups = [[names[i] for i in g] for g in groups_of(null)]
    inseparable = advice(table, groups, design_step_deg)
    next_deg, design = recommend(table, phi1, phi2, next_positions, design_step_deg)
    rms = {c: float(np.sqrt(np.mean(resid[:, j] ** 2))) / ARCSEC for j, c in enumerate(COMPONENTS)}
    warnings = _warnings(dof, rms)
    if second_order:
        warnings.append(
            f"at the solution the full model's second-order terms separate a further direction "
            f"(σ/σmax = {sv[rank] / sv[0]:.2g} > rcond {rcond:g}): the errors are large for the "
            "small-angle model; that direction is still reported as inseparable."
        )
    allocation = None
    if bounds_arcsec is not None:
        allocation = compare_with_bounds(combos, bounds_arcsec, k, bounds_source, table)
    return TurntableIdentification(
        errors_arcsec=errors,
        errors_u_arcsec=errors_u,
        unidentifiable=unidentifiable,
        combinations=tuple(combos),
        inseparable=tuple(inseparable),
        positions=n,
        rank=rank,
        dof=dof,
        s_arcsec=math.sqrt(s2) / ARCSEC,
        residual_rms_arcsec=rms,
        residuals_arcsec={c: list(resid[:, j] / ARCSEC) for j, c in enumerate(COMPONENTS)},
        k=k,
        coverage_probability=_COVERAGE,
        singular_values_relative=[float(v / sv[0]) for v in sv],
        rcond=float(rcond),
        model=model,
        iterations=iterations,
        table=table.name,
        next_positions_deg=next_deg,
        design=design,
        allocation=allocation,
        warnings=tuple(warnings),
        _plot={"phi1_deg": np.degrees(phi1), "phi2_deg": np.degrees(phi2)},
    )


def _warnings(dof: int, rms: Mapping[str, float]) -> list[str]:
    out = []
    if dof < 5:
        out.append(
            f"only {dof} degree{'s' if dof != 1 else ''} of freedom: s is poorly known and k is "
            "large; measure more positions."
        )
    values = [v for v in rms.values() if v > 0]
    if len(values) == 3 and max(values) > 3.0 * min(values):
        text = ", ".join(f"{c} {v:.3g}" for c, v in rms.items())
        out.append(
            f"the residual rms differs between the components ({text} arcsec): the pooled s "
            "assumes equal noise on Δψ, Δθ and Δγ; u is then too small for the noisiest."
        )
    return out
