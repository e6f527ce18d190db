"""Multiposition calibration of a gyro's drift coefficients with Earth rate and gravity (GyroWheel study).

The gyro sits on a two-axis turntable (outer angle φ1, inner angle φ2; initial orientation of its
axes north-west-up). At each position the Earth rate and gravity components in the gyro frame are
known from eq. (3) at the latitude λ. The rate-sensing model (eq. (1)) of the x axis,

    ω_x = k_y·i_y − DF − Dx·ax − Dy·ay − Dz·az − Dxx·ax² − Dzz·az² − Dxy·ax·ay,

gives one linear equation per position in the seven drift coefficients; stacked (eqs. (2), (4),
(5)) it is ``b1 − b2 = A·β`` with ``b1`` the torquer outputs k·i in rate units, ``b2`` the Earth
rate components and A the gravity terms, solved by least squares (eq. (6)). The y axis uses
``DF, Dx, Dy, Dz, Dyy, Dzz, Dyx`` with the columns 1, ax, ay, az, ay², az², ax·ay. Units: deg/h,
deg/h/g, deg/h/g² (gravity components in g).

Each coefficient gets an uncertainty budget (GUM): the least-squares covariance s²·(AᵀA)⁻¹
(Type A, ν = N − 7), the latitude ``site.latitude_deg`` (the Earth-rate components of eq. (3)
depend on it) and the turntable's orientation error ``table.orientation_error_arcsec`` (Δψ, Δθ,
Δγ of eq. (7), acting on the Earth-rate and gravity components by eq. (8)); their sensitivities
come from differentiating the least-squares solution (eqs. (9)–(11)) — see
:func:`drift_sensitivities`.

Not every set of positions identifies the seven coefficients: with φ1 and φ2 both multiples of 90°
the column ax·ay is zero everywhere, and with inner angles only at odd multiples of 45° ax² = ay²
makes 1, ax² and az² collinear. :func:`check_multiposition_plan` says which coefficients a plan
leaves unidentifiable; :func:`multiposition_plan` makes plans that identify all of them. The model
(eq. (3), A, the sensitivities) is :mod:`rotacal.gyro.multiposition_model`, the plans
:mod:`rotacal.gyro.multiposition_plan`; this module fits a capture and states its budgets.

References
----------
Seed 001 (GyroWheel calibration tests: error analysis and turntable error allocation), §2.1,
eqs. (1)–(6) and Table 1; §2.2, eqs. (7)–(11). JCGM 100:2008 (GUM) §5.1, G.4.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import numpy as np

from rotacal.errors import CaptureError, ConfigError
from rotacal.gyro.multiposition_model import (
    _ARCSEC,
    _NAMES,
    _ORIENTATION,
    _UNITS,
    COVERAGE_PROBABILITY,
    EARTH_RATE_DEG_H,
    _angles,
    _axis,
    _check_columns,
    _latitude,
    _rows,
    _solve_with_sensitivities,
    coefficient_names,
    coefficient_units,
    drift_design_matrix,
    drift_sensitivities,
    earth_rate_and_gravity,
)
from rotacal.gyro.multiposition_plan import (
    MultipositionPlan,
    _plan_core,
    check_multiposition_plan,
    multiposition_plan,
)
from rotacal.gyro.plausibility import multiposition_warnings
from rotacal.results import Result
from rotacal.signal.clipping import check_clipping
from rotacal.uncertainty.budget import UncertaintyBudget
from rotacal.uncertainty.gum import Input, propagate
from rotacal.uncertainty.specs import TYPE_A_ONLY_NOTE, InstrumentSpecs, spec_distribution

__all__ = [
    "EARTH_RATE_DEG_H",
    "MultipositionPlan",
    "MultipositionResult",
    "calibrate_multiposition",
    "check_multiposition_plan",
    "coefficient_names",
    "coefficient_units",
    "drift_design_matrix",
    "drift_sensitivities",
    "earth_rate_and_gravity",
    "multiposition_plan",
]


@dataclasses.dataclass(frozen=True)
class MultipositionResult(Result):
    """Drift coefficients by multiposition least squares (JSON keys of INTERFACE.md,
    ``gyro multiposition``).

    ``drift_coefficients`` and ``drift_coefficients_u`` map the seven names of the axis to values
    and standard uncertainties in deg/h, deg/h/g and deg/h/g² (see ``drift_coefficient_units``);
    each u is that of the coefficient's budget in ``_budgets`` (key
    ``"drift_coefficients.<name>"``). ``residuals_deg_h`` holds one residual per row of the
    capture. The JSON adds ``drift_coefficients_U`` ({name: U}), ``k``
    ({"drift_coefficients": {name: k}}), ``coverage_probability`` and ``uncertainty_budgets``
    ({"drift_coefficients": {name: budget}}).
    """

    axis: str
    drift_coefficients: dict[str, float]
    drift_coefficients_u: dict[str, float]
    drift_coefficient_units: dict[str, str]
    latitude_deg: float
    earth_rate_deg_h: float
    rows: int
    positions: int
    dof: int
    rank: int
    condition_number: float
    residual_rms_deg_h: float
    residual_std_deg_h: float
    residuals_deg_h: np.ndarray
    notes: tuple[str, ...] = ()
    _covariance: np.ndarray | None = dataclasses.field(default=None, repr=False, compare=False)
    _plot: dict[str, Any] = dataclasses.field(default_factory=dict, repr=False, compare=False)
    _budgets: dict[str, UncertaintyBudget] = dataclasses.field(
        default_factory=dict, repr=False, compare=False
    )

    def to_dict(self) -> dict[str, Any]:
        """INTERFACE.md ``gyro multiposition`` keys plus the expanded uncertainties and budgets."""
        out = super().to_dict()
        names = list(self.drift_coefficients)
        found = {n: self._budgets.get(f"drift_coefficients.{n}") for n in names}
        out["drift_coefficients_U"] = {
            n: (None if b is None else float(b.U)) for n, b in found.items()
        }
        out["k"] = {
            "drift_coefficients": {n: (None if b is None else float(b.k)) for n, b in found.items()}
        }
        out["coverage_probability"] = COVERAGE_PROBABILITY if self._budgets else None
        out["uncertainty_budgets"] = {
            "drift_coefficients": {
                n: (None if b is None else b.to_dict()) for n, b in found.items()
            }
        }
        return out


def calibrate_multiposition(
    phi1_deg: np.ndarray,
    phi2_deg: np.ndarray,
    output_deg_h: np.ndarray,
    *,
    axis: str = "x",
    latitude_deg: float | None = None,
    earth_rate_deg_h: float = EARTH_RATE_DEG_H,
    specs: InstrumentSpecs | None = None,
    allow_clipped: bool = False,
) -> MultipositionResult:
    """Drift coefficients of one gyro axis from its outputs at several turntable positions, each
    with its uncertainty budget.

    Forms ``b1 − b2 = A·β`` (eq. (5)) with b1 the outputs k·i (deg/h), b2 the Earth-rate component
    of the axis at each row's position (eq. (3)) and A the gravity terms (eq. (4)), and solves it by
    least squares (eq. (6), here through a QR factorisation of A rather than the normal equations). The
    standard uncertainties are √diag(s²·(AᵀA)⁻¹) with s² = Σr²/(N − 7), the residual variance: they
    assume white, equal noise on every reading. Repeated readings of a position are rows of their
    own.

    Parameters
    ----------
    phi1_deg, phi2_deg : array
        Outer and inner turntable angles of each row (deg).
    output_deg_h : array
        The axis's torquer output in rate units, k·i (deg/h).
    axis : {"x", "y"}
        x: ``DF, Dx, Dy, Dz, Dxx, Dzz, Dxy``; y: ``DF, Dx, Dy, Dz, Dyy, Dzz, Dyx``.
    latitude_deg : float
        Latitude of the laboratory (deg, −90…90). May be left out when ``specs`` states
        ``site.latitude_deg``; when both are given they must agree.
    earth_rate_deg_h : float
        Earth rate Ωe (°/h); default the sidereal 15.041067 °/h.
    specs : InstrumentSpecs, optional
        The lab's instrument specifications. Used: ``site.latitude_deg`` (value and u, deg) and
        ``table.orientation_error_arcsec`` (one distribution for each of Δψ, Δθ, Δγ, arcsec;
        a stated mean is corrected for by eq. (8)); others do not apply. None: Type A only.
    allow_clipped : bool
        Fit an output with readings at the rails (:mod:`rotacal.signal.clipping`) anyway
        (``--allow-clipped``); ``warnings`` name the clipping. Refused by default.

    Returns
    -------
    MultipositionResult
        Coefficients (deg/h, deg/h/g, deg/h/g²) with standard uncertainties, the condition number
        and rank of A, residuals (deg/h), and one uncertainty budget per coefficient.

    Notes
    -----
    Budget of each coefficient β_j (GUM law of propagation, k = t_0.975(ν_eff)):
    the least-squares fit, u = s·√[(AᵀA)⁻¹]_jj with ν = N − 7 (Type A; white, equal noise on
    every reading); the latitude, sensitivity ∂β_j/∂λ; the orientation error, one row per
    component Δψ, Δθ, Δγ (taken as the same at every position: a mounting error of the gyro on
    the table, as the GyroWheel study's §2.2 analyses it), sensitivities ∂β_j/∂Δ from
    :func:`drift_sensitivities`. The inputs are independent.

    Raises
    ------
    CaptureError
        Non-finite values (naming the rows), values beyond float64's working range (angles beyond
        ±1e9°), a constant output, a column that copies another (or its negative), fewer than 7
        distinct positions, positions that leave coefficients unidentifiable (naming them, and
        an axis that never turns), or an output at its rails.
    ConfigError
        Latitude outside ±90°, missing, or contradicting ``site.latitude_deg``; an unknown axis.

    References
    ----------
    Seed 001, §2.1, eqs. (1)–(6); §2.2, eqs. (7)–(11) (orientation error). JCGM 100:2008 (GUM)
    §4.2 (Type A), §4.3 (Type B), §5.1 (law of propagation), G.4 (ν_eff, k).
    """
    ax_ = _axis(axis)
    lat_spec = spec_distribution(specs, "site.latitude_deg")
    orient_spec = spec_distribution(specs, "table.orientation_error_arcsec")
    if latitude_deg is None:
        if lat_spec is None:
            raise ConfigError(
                "give the latitude: latitude_deg (--latitude-deg, deg) or site.latitude_deg in the "
                "instrument specifications."
            )
        lat = _latitude(lat_spec.mean)
    else:
        lat = _latitude(latitude_deg)
        if lat_spec is not None and abs(float(lat_spec.mean) - lat) > 1e-9:
            where = specs.source if specs is not None else "the specifications"
            raise ConfigError(
                f"latitude_deg = {lat:g}° contradicts site.latitude_deg = {float(lat_spec.mean):g}° "
                f"in {where}: give one latitude."
            )
    try:
        we = float(earth_rate_deg_h)
    except (TypeError, ValueError):
        raise ConfigError(f"earth_rate_deg_h must be a number, got {earth_rate_deg_h!r}.") from None
    if not math.isfinite(we) or we < 0:
        raise ConfigError(
            f"earth_rate_deg_h must be a finite number ≥ 0, got {earth_rate_deg_h!r}."
        )
    y = np.asarray(output_deg_h, dtype=float).reshape(-1)
    p1, p2 = _angles(phi1_deg, phi2_deg, CaptureError)
    if y.size != p1.size:
        raise CaptureError(
            f"column output_deg_h has {y.size} rows but phi1_deg has {p1.size}: give one output per "
            "pair of angles."
        )
    bad = np.flatnonzero(~np.isfinite(y))
    if bad.size:
        raise CaptureError(
            f"column output_deg_h has {bad.size} non-finite value(s) (NaN or inf) at rows "
            f"{_rows(bad)} (counted from 0): remove those rows or re-measure those positions."
        )
    _check_columns(p1, p2, y)
    plan, _, first, pos_of_row = _plan_core(p1, p2, ax_, CaptureError, "the capture")
    clipped = check_clipping({"output_deg_h": y}, allow_clipped=allow_clipped, groups=pos_of_row)
    names = _NAMES[ax_]
    w, g = earth_rate_and_gravity(p1, p2, lat, earth_rate_deg_h=we)
    d0 = float(orient_spec.mean) if orient_spec is not None else 0.0
    # Eq. (6) (eq. (11) with a stated mean orientation error) through A = QR, no normal
    # equations: β = R⁻¹·Qᵀ(b1 − b2), (AᵀA)⁻¹ = R⁻¹R⁻ᵀ; and ∂β/∂(λ, Δψ, Δθ, Δγ).
    beta, jac, resid, a, cov_unit = _solve_with_sensitivities(
        p1, p2, y, w, g, ax_, lat, we, (d0 * _ARCSEC,) * 3
    )
    n, p = a.shape
    dof = n - p
    notes: list[str] = [
        f"Earth rate {we:.8g} °/h (sidereal), latitude {lat:g}°; gravity components in g, "
        "positions by the GyroWheel study's eq. (3) (gyro axes north-west-up at φ1 = φ2 = 0)."
    ]
    if d0 != 0.0:
        notes.append(
            f"corrected for the stated mean orientation error Δψ = Δθ = Δγ = {d0:g} arcsec "
            "(GyroWheel study, eqs. (7)–(11))."
        )
    if dof > 0:
        s2 = float(resid @ resid) / dof
        cov = s2 * cov_unit
        u = np.sqrt(np.diag(cov))
        s_std = math.sqrt(s2)
    else:
        cov = np.full_like(cov_unit, np.nan)
        u = np.full(p, np.nan)
        s_std = math.nan
        notes.append(
            "as many readings as coefficients: the fit is exact and gives no uncertainty; repeat "
            "positions or add more."
        )
    if plan.condition_number > 100:
        notes.append(
            f"the design is poorly conditioned (condition number {plan.condition_number:.3g}): "
            "small errors in the outputs are strongly amplified; prefer both axes in 45° steps (8 × 8 positions)."
        )
    budgets: dict[str, UncertaintyBudget] = {}
    if dof > 0:
        budgets = _drift_budgets(
            names,
            ax_,
            beta,
            u,
            jac,
            dof,
            s_std,
            specs,
        )
        u = np.array([budgets[f"drift_coefficients.{nm}"].u for nm in names])
    cnt = np.bincount(pos_of_row, minlength=first.size)
    pos_mean = np.bincount(pos_of_row, weights=resid, minlength=first.size) / cnt
    plot = {
        "phi1_deg": p1[first],
        "phi2_deg": p2[first],
        "readings": cnt,
        "mean_residual_deg_h": pos_mean,
        "row_position": pos_of_row,
    }
    return MultipositionResult(
        axis=ax_,
        drift_coefficients=dict(zip(names, (float(v) for v in beta), strict=True)),
        drift_coefficients_u=dict(zip(names, (float(v) for v in u), strict=True)),
        drift_coefficient_units=coefficient_units(ax_),
        latitude_deg=lat,
        earth_rate_deg_h=we,
        rows=int(n),
        positions=int(first.size),
        dof=int(dof),
        rank=plan.rank,
        condition_number=plan.condition_number,
        residual_rms_deg_h=float(np.sqrt(np.mean(resid * resid))),
        residual_std_deg_h=s_std,
        residuals_deg_h=resid,
        notes=tuple(notes),
        _covariance=cov,
        _plot=plot,
        _budgets=budgets,
        warnings=(
            *clipped,
            *multiposition_warnings(resid, pos_of_row, p),
        ),
    )


def _drift_budgets(
    names: tuple[str, ...],
    axis: str,
    beta: np.ndarray,
    u_fit: np.ndarray,
    jac: np.ndarray,
    dof: int,
    s_std: float,
    specs: InstrumentSpecs | None,
) -> dict[str, UncertaintyBudget]:
    """One GUM budget per drift coefficient (see :func:`calibrate_multiposition`, Notes)."""
    units = dict(zip(names, _UNITS, strict=True))
    extra: list[tuple[Input, int]] = []  # (input, column of jac)
    notes: list[str] = []
    if specs is None:
        notes.append(TYPE_A_ONLY_NOTE)
    else:
        lat_in = specs.input("site.latitude_deg", name="latitude λ", unit="deg")
        if lat_in is not None:
            extra.append((lat_in, 0))
        else:
            notes.append("site.latitude_deg not stated: the latitude is taken as exact.")
        if specs.get("table.orientation_error_arcsec") is not None:
            for col, (_, label) in enumerate(_ORIENTATION, start=1):
                o_in = specs.input("table.orientation_error_arcsec", name=label)
                assert o_in is not None
                extra.append((o_in, col))
            # a stated mean Δ̄ enters eq. (11) (GUM §3.2.4); its u stays in the rows
            if (fix := specs.correction_note("table.orientation_error_arcsec")) is not None:
                notes.append(fix)
            notes.append(
                "the orientation error is taken as the same at every position (a mounting "
                "error, the GyroWheel study's §2.2); a part that changes from position to position shows in "
                "the residuals (Type A)."
            )
        else:
            notes.append("table.orientation_error_arcsec not stated: the orientation is exact.")
    budgets: dict[str, UncertaintyBudget] = {}
    for j, name in enumerate(names):
        fit = Input(
            name="least-squares fit, s·√[(AᵀA)⁻¹]_jj",
            value=float(beta[j]),
            u=float(u_fit[j]),
            dof=float(dof),
            distribution="normal",
            unit=units[name],
            source=f"Type A, s = {s_std:.3g} deg/h, ν = {dof}",
            description="normal",
        )
        inputs = [fit, *(item for item, _ in extra)]
        c = np.array([1.0, *(float(jac[j, col]) for _, col in extra)])
        x0 = np.array([inp.value for inp in inputs])

        def model(*x: float, _c: np.ndarray = c, _x0: np.ndarray = x0) -> float:
            # β_j = β_fit,j + Σ_i ∂β_j/∂x_i·(x_i − x_i0): linear in every input
            return float(x[0] + _c[1:] @ (np.asarray(x[1:]) - _x0[1:]))

        res = propagate(
            model,
            inputs,
            jacobian=lambda *x, _c=c: _c.reshape(1, -1),
            p=COVERAGE_PROBABILITY,
            names_out=[f"{name} ({axis} axis)"],
            units_out=[units[name]],
        )
        b = res.budget(0)
        budgets[f"drift_coefficients.{name}"] = dataclasses.replace(b, notes=(*b.notes, *notes))
    return budgets
