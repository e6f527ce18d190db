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
leaves unidentifiable; :func:`multiposition_plan` makes plans that identify all of them.

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
from scipy.linalg import solve_triangular

from rotacal.errors import CaptureError, ConfigError
from rotacal.gyro.plausibility import multiposition_warnings
from rotacal.results import Result
from rotacal.signal._values import check_magnitudes, check_not_constant, check_not_copies
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

#: Sidereal rotation rate of the Earth, 7.292115·10⁻⁵ rad/s, in °/h.
EARTH_RATE_DEG_H = 15.041067

_NAMES = {
    "x": ("DF", "Dx", "Dy", "Dz", "Dxx", "Dzz", "Dxy"),
    "y": ("DF", "Dx", "Dy", "Dz", "Dyy", "Dzz", "Dyx"),
}
_COLUMNS = {
    "x": ("1", "ax", "ay", "az", "ax²", "az²", "ax·ay"),
    "y": ("1", "ax", "ay", "az", "ay²", "az²", "ax·ay"),
}
_UNITS = ("deg/h", "deg/h/g", "deg/h/g", "deg/h/g", "deg/h/g^2", "deg/h/g^2", "deg/h/g^2")
#: Relative singular-value threshold below which a direction of β is not identified.
_RANK_RTOL = 1e-9
#: Angles equal to this (deg, modulo 360) are the same position (for per-position residuals).
_POSITION_DECIMALS = 6
#: Coverage probability of the expanded uncertainties.
COVERAGE_PROBABILITY = 0.95
#: One arcsecond in radians.
_ARCSEC = math.pi / (180.0 * 3600.0)
#: Budget row names of the orientation-error components (GyroWheel study, eq. (7)).
_ORIENTATION = (
    ("Δψ", "orientation error Δψ about y (eq. 7)"),
    ("Δθ", "orientation error Δθ about z (eq. 7)"),
    ("Δγ", "orientation error Δγ about x (eq. 7)"),
)


def _axis(axis: Any) -> str:
    if axis not in _NAMES:
        raise ConfigError(f"axis must be 'x' or 'y', got {axis!r}.")
    return str(axis)


def coefficient_names(axis: str = "x") -> tuple[str, ...]:
    """Names of the seven drift coefficients of ``axis`` in the order of β (GyroWheel study, eq. (4))."""
    return _NAMES[_axis(axis)]


def coefficient_units(axis: str = "x") -> dict[str, str]:
    """Unit of each drift coefficient of ``axis``: deg/h, deg/h/g or deg/h/g^2."""
    return dict(zip(_NAMES[_axis(axis)], _UNITS, strict=True))


def _latitude(latitude_deg: Any) -> float:
    try:
        lat = float(latitude_deg)
    except (TypeError, ValueError):
        raise ConfigError(
            f"latitude_deg must be a number in degrees, got {latitude_deg!r}."
        ) from None
    if not math.isfinite(lat) or abs(lat) > 90.0:
        raise ConfigError(f"latitude_deg must be between −90 and +90°, got {latitude_deg!r}.")
    return lat


#: Largest |position| accepted (deg): float64 resolves it to 1e-7° (a 2e-9 rad error in sin/cos,
#: nothing against the GyroWheel study's 0.01 °/h); beyond it a column holds something other than angles.
MAX_POSITION_DEG = 1e9


def _check_columns(p1: np.ndarray, p2: np.ndarray, y: np.ndarray) -> None:
    """Positions and outputs within float64's working range, a varying output, no copies.

    An axis that never turns is the plan's business (:func:`_plan_core` names the column).
    """
    for name, v in (("phi1_deg", p1), ("phi2_deg", p2)):
        check_magnitudes(name, v, what="a table angle", largest=MAX_POSITION_DEG)
    check_magnitudes("output_deg_h", y, what="a gyro output")
    check_not_constant(
        "output_deg_h",
        y,
        "a gyro's output changes with the Earth rate and gravity from one position to the next",
    )
    check_not_copies(
        {"phi1_deg": p1, "phi2_deg": p2, "output_deg_h": y},
        "each column must hold its own axis's angles or the gyro's output",
    )


def _angles(phi1_deg: Any, phi2_deg: Any, error: type[Exception]) -> tuple[np.ndarray, np.ndarray]:
    p1 = np.asarray(phi1_deg, dtype=float).reshape(-1)
    p2 = np.asarray(phi2_deg, dtype=float).reshape(-1)
    if p1.size != p2.size:
        raise error(
            f"column phi1_deg has {p1.size} rows but phi2_deg has {p2.size}: give one pair of "
            "angles per row."
        )
    for name, v in (("phi1_deg", p1), ("phi2_deg", p2)):
        bad = np.flatnonzero(~np.isfinite(v))
        if bad.size:
            raise error(
                f"column {name} has {bad.size} non-finite value(s) (NaN or inf) at rows "
                f"{_rows(bad)} (counted from 0): every row needs both turntable angles."
            )
    return p1, p2


def _rows(idx: np.ndarray) -> str:
    shown = ", ".join(str(int(i)) for i in idx[:8])
    return shown + (f" and {idx.size - 8} more" if idx.size > 8 else "")


def earth_rate_and_gravity(
    phi1_deg: np.ndarray,
    phi2_deg: np.ndarray,
    latitude_deg: float,
    *,
    earth_rate_deg_h: float = EARTH_RATE_DEG_H,
) -> tuple[np.ndarray, np.ndarray]:
    """Earth-rate and gravity components in the gyro frame at each turntable position.

    Seed 001, eq. (3), with the gyro's axes north-west-up at φ1 = φ2 = 0:
    ``ax = −sin φ1·cos φ2``, ``ay = sin φ1·sin φ2``, ``az = cos φ1``,
    ``ωx = Ωe·cos φ2·(cos φ1·cos λ − sin φ1·sin λ)``,
    ``ωy = Ωe·sin φ2·(−cos φ1·cos λ + sin φ1·sin λ)``,
    ``ωz = Ωe·(sin φ1·cos λ + cos φ1·sin λ)``.

    Parameters
    ----------
    phi1_deg, phi2_deg : array
        Outer and inner turntable angles (deg).
    latitude_deg : float
        Latitude λ (deg, −90…90).
    earth_rate_deg_h : float
        Ωe (°/h); default the sidereal rate 15.041067 °/h.

    Returns
    -------
    (omega_deg_h, gravity_g) : (ndarray, ndarray)
        Each of shape (n, 3): (ωx, ωy, ωz) in °/h and (ax, ay, az) in g.

    References
    ----------
    Seed 001, §2.1, eq. (3).
    """
    p1, p2 = _angles(phi1_deg, phi2_deg, ConfigError)
    lam = math.radians(_latitude(latitude_deg))
    we = float(earth_rate_deg_h)
    r1, r2 = np.radians(p1), np.radians(p2)
    s1, c1, s2, c2 = np.sin(r1), np.cos(r1), np.sin(r2), np.cos(r2)
    sl, cl = math.sin(lam), math.cos(lam)
    a = np.column_stack([-s1 * c2, s1 * s2, c1])
    w = we * np.column_stack(
        [c2 * (c1 * cl - s1 * sl), s2 * (-c1 * cl + s1 * sl), s1 * cl + c1 * sl]
    )
    return w, a


def drift_design_matrix(
    phi1_deg: np.ndarray, phi2_deg: np.ndarray, *, axis: str = "x"
) -> np.ndarray:
    """The regression matrix A of the GyroWheel study, eq. (4): rows (1, ax, ay, az, a₁², az², ax·ay).

    Parameters
    ----------
    phi1_deg, phi2_deg : array
        Outer and inner turntable angles (deg).
    axis : {"x", "y"}
        a₁ = ax for the x axis, ay for the y axis.

    Returns
    -------
    ndarray, shape (n, 7)
        Columns in g⁰, g¹ (three), g² (three).

    References
    ----------
    Seed 001, eqs. (2)–(4).
    """
    ax_ = _axis(axis)
    _, a = earth_rate_and_gravity(phi1_deg, phi2_deg, 0.0)
    return _design(a, ax_)


def _design(a: np.ndarray, axis: str) -> np.ndarray:
    """Rows (1, ax, ay, az, a₁², az², ax·ay) of eq. (4) from gravity components (n, 3) in g."""
    gx, gy, gz = a[:, 0], a[:, 1], a[:, 2]
    sq = gx * gx if axis == "x" else gy * gy
    return np.column_stack([np.ones_like(gx), gx, gy, gz, sq, gz * gz, gx * gy])


def _design_derivative(a: np.ndarray, da: np.ndarray, axis: str) -> np.ndarray:
    """dA for a change da (n, 3) of the gravity components: the derivative of :func:`_design`."""
    gx, gy, gz = a[:, 0], a[:, 1], a[:, 2]
    dx, dy, dz = da[:, 0], da[:, 1], da[:, 2]
    dsq = 2.0 * gx * dx if axis == "x" else 2.0 * gy * dy
    return np.column_stack([np.zeros_like(gx), dx, dy, dz, dsq, 2.0 * gz * dz, dx * gy + gx * dy])


def _orientation_generators() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """∂ΔR/∂Δψ, ∂ΔR/∂Δθ, ∂ΔR/∂Δγ of the GyroWheel study's eq. (7) (ΔR = I + Δψ·Eψ + Δθ·Eθ + Δγ·Eγ)."""
    e_psi = np.array([[0.0, 0.0, 1.0], [0.0, 0.0, 0.0], [-1.0, 0.0, 0.0]])
    e_theta = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 0.0]])
    e_gamma = np.array([[0.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])
    return e_psi, e_theta, e_gamma


def _delta_r(dpsi: float, dtheta: float, dgamma: float) -> np.ndarray:
    """ΔR of the GyroWheel study's eq. (7) for small rotations Δψ (about y), Δθ (about z), Δγ (about x), rad."""
    e_psi, e_theta, e_gamma = _orientation_generators()
    return np.eye(3) + dpsi * e_psi + dtheta * e_theta + dgamma * e_gamma


def _earth_rate_dlat(
    phi1_deg: np.ndarray, phi2_deg: np.ndarray, latitude_deg: float, earth_rate_deg_h: float
) -> np.ndarray:
    """∂ω/∂λ of eq. (3) (n, 3) in °/h per degree of latitude."""
    r1, r2 = np.radians(phi1_deg), np.radians(phi2_deg)
    s1, c1, s2, c2 = np.sin(r1), np.cos(r1), np.sin(r2), np.cos(r2)
    lam = math.radians(latitude_deg)
    sl, cl = math.sin(lam), math.cos(lam)
    d = earth_rate_deg_h * np.column_stack(
        [c2 * (-c1 * sl - s1 * cl), s2 * (c1 * sl + s1 * cl), -s1 * sl + c1 * cl]
    )
    return d * (math.pi / 180.0)


def drift_sensitivities(
    phi1_deg: np.ndarray,
    phi2_deg: np.ndarray,
    output_deg_h: np.ndarray,
    *,
    axis: str = "x",
    latitude_deg: float,
    earth_rate_deg_h: float = EARTH_RATE_DEG_H,
    orientation_error_arcsec: tuple[float, float, float] = (0.0, 0.0, 0.0),
) -> tuple[np.ndarray, np.ndarray]:
    """Drift coefficients and their sensitivities to the latitude and the orientation error.

    With the orientation error ΔR of eq. (7) the Earth-rate and gravity components are
    ``ω′ = ω·ΔR``, ``a′ = a·ΔR`` (eq. (8), row vectors), the regression is ``b1 − b2′ = A′β``
    (eqs. (9)–(10)) and β = (A′ᵀA′)⁻¹A′ᵀ(b1 − b2′) (eq. (11)). Differentiating the normal
    equations ``A′ᵀA′β = A′ᵀb`` (b = b1 − b2′) gives, for any input p of A′ or b2′,

        ∂β/∂p = (A′ᵀA′)⁻¹·[(∂A′/∂p)ᵀ·r − A′ᵀ·(∂A′/∂p)·β − A′ᵀ·∂b2′/∂p],   r = b − A′β,

    exact to first order (ΔR is linear in the angles, so ∂a′/∂Δψ = a·∂ΔR/∂Δψ everywhere).

    Parameters
    ----------
    phi1_deg, phi2_deg : array
        Outer and inner turntable angles of each row (deg).
    output_deg_h : array
        The axis's torquer output in rate units, k·i (deg/h).
    axis : {"x", "y"}
        The gyro axis.
    latitude_deg : float
        Latitude λ (deg).
    earth_rate_deg_h : float
        Ωe (°/h).
    orientation_error_arcsec : (Δψ, Δθ, Δγ)
        The orientation error at which β and the derivatives are evaluated (arcsec; rotations
        about the gyro's y, z and x axes, the GyroWheel study's eq. (7)). Default: none.

    Returns
    -------
    (beta, jacobian) : (ndarray (7,), ndarray (7, 4))
        β in deg/h, deg/h/g, deg/h/g² (order of :func:`coefficient_names`); the columns of the
        Jacobian are ∂β/∂λ (per degree) and ∂β/∂Δψ, ∂β/∂Δθ, ∂β/∂Δγ (per arcsec).

    References
    ----------
    Seed 001, §2.1 eqs. (3)–(6) and §2.2 eqs. (7)–(11); JCGM 100:2008 (GUM) §5.1.3 (sensitivity
    coefficients as partial derivatives of the measurement model).
    """
    ax_ = _axis(axis)
    lat = _latitude(latitude_deg)
    p1, p2 = _angles(phi1_deg, phi2_deg, ConfigError)
    y = np.asarray(output_deg_h, dtype=float).reshape(-1)
    if y.size != p1.size:
        raise CaptureError(
            f"column output_deg_h has {y.size} rows but phi1_deg has {p1.size}: give one output per "
            "pair of angles."
        )
    try:
        dpsi, dtheta, dgamma = (float(v) * _ARCSEC for v in orientation_error_arcsec)
    except (TypeError, ValueError):
        raise ConfigError(
            "orientation_error_arcsec must be three numbers (Δψ, Δθ, Δγ) in arcsec, got "
            f"{orientation_error_arcsec!r}."
        ) from None
    w, a = earth_rate_and_gravity(p1, p2, lat, earth_rate_deg_h=earth_rate_deg_h)
    beta, jac, *_ = _solve_with_sensitivities(
        p1, p2, y, w, a, ax_, lat, float(earth_rate_deg_h), (dpsi, dtheta, dgamma)
    )
    return beta, jac


def _solve_with_sensitivities(
    p1: np.ndarray,
    p2: np.ndarray,
    y: np.ndarray,
    w: np.ndarray,
    a: np.ndarray,
    axis: str,
    lat: float,
    we: float,
    delta_rad: tuple[float, float, float],
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """β, ∂β/∂(λ°, Δψ″, Δθ″, Δγ″), the residuals, A′ and (A′ᵀA′)⁻¹ (eqs. (8)–(11))."""
    k = 0 if axis == "x" else 1
    dr = _delta_r(*delta_rad)
    wp, ap = w @ dr, a @ dr  # eq. (8), row vectors
    design = _design(ap, axis)
    q, r = np.linalg.qr(design)
    beta = solve_triangular(r, q.T @ (y - wp[:, k]))
    resid = y - wp[:, k] - design @ beta
    r_inv = solve_triangular(r, np.eye(r.shape[0]))
    cov_unit = r_inv @ r_inv.T
    dw_lat = _earth_rate_dlat(p1, p2, lat, we) @ dr
    cols = [-(cov_unit @ (design.T @ dw_lat[:, k]))]  # A′ does not depend on λ; ∂b = −∂ω
    for gen in _orientation_generators():
        da = _design_derivative(ap, a @ gen, axis)
        dw = (w @ gen)[:, k]
        cols.append(cov_unit @ (da.T @ resid - design.T @ (da @ beta) - design.T @ dw))
    jac = np.column_stack(cols)
    jac[:, 1:] *= _ARCSEC
    # zero what is zero by the symmetry of the plan (round-off of ~1e-18 of the column's scale)
    scale = np.max(np.abs(jac), axis=0, keepdims=True)
    jac[np.abs(jac) <= 1e-12 * scale] = 0.0
    return beta, jac, resid, design, cov_unit


@dataclasses.dataclass(frozen=True)
class MultipositionPlan(Result):
    """A set of turntable positions and how well it identifies the drift coefficients.

    ``condition_number`` is that of A (its columns are dimensionless gravity terms);
    ``u_factors`` are √diag((AᵀA)⁻¹): a coefficient's standard uncertainty per unit noise of one
    reading (deg/h per deg/h), for one reading per position.
    """

    axis: str
    phi1_deg: np.ndarray
    phi2_deg: np.ndarray
    positions: int
    rank: int
    condition_number: float
    u_factors: dict[str, float]
    identifiable: bool
    unidentifiable: tuple[str, ...]


def _distinct_positions(p1: np.ndarray, p2: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Index of the first row of each distinct position (angles mod 360°, to 10⁻⁶°) and the
    position of each row, numbered in the order the positions first appear."""
    scale = 10.0**_POSITION_DECIMALS
    full = round(360.0 * scale)
    k1 = np.round(np.mod(p1, 360.0) * scale).astype(np.int64) % full
    k2 = np.round(np.mod(p2, 360.0) * scale).astype(np.int64) % full
    _, first, inverse = np.unique(k1 * full + k2, return_index=True, return_inverse=True)
    order = np.argsort(first)  # positions in the order they first appear
    rank_of = np.empty_like(order)
    rank_of[order] = np.arange(order.size)
    return first[order], rank_of[np.asarray(inverse).reshape(-1)]


def _analyse(
    a: np.ndarray, names: tuple[str, ...]
) -> tuple[int, float, tuple[str, ...], list[str]]:
    """Rank, condition number, unidentifiable coefficients and a reason for each fault."""
    # A = QR: R (7 × 7) has A's singular values and right singular vectors, at a fraction of
    # the cost of an SVD of the tall A.
    sv, vt = np.linalg.svd(np.linalg.qr(a, mode="r"), full_matrices=False)[1:]
    tol = _RANK_RTOL * sv[0] if sv.size else 0.0
    rank = int(np.count_nonzero(sv > tol))
    cond = float(sv[0] / sv[-1]) if sv[-1] > tol else math.inf
    if rank == len(names):
        return rank, cond, (), []
    null = vt[rank:]  # rows spanning the null space of A
    weight = np.sqrt(np.sum(null * null, axis=0))
    bad = tuple(n for n, wgt in zip(names, weight, strict=True) if wgt > 1e-6)
    reasons = []
    col_norm = np.sqrt(np.sum(a * a, axis=0))
    zero = [names[j] for j in range(len(names)) if col_norm[j] <= 1e-9 * max(col_norm.max(), 1.0)]
    if zero:
        reasons.append(
            f"the column{'s' if len(zero) > 1 else ''} of {', '.join(zero)} "
            f"{'are' if len(zero) > 1 else 'is'} zero at every position"
        )
    rest = [n for n in bad if n not in zero]
    if rest:
        reasons.append(f"only a combination of {', '.join(rest)} is determined")
    return rank, cond, bad, reasons


def check_multiposition_plan(
    phi1_deg: np.ndarray, phi2_deg: np.ndarray, *, axis: str = "x"
) -> MultipositionPlan:
    """Check that a plan of turntable positions identifies every drift coefficient.

    Parameters
    ----------
    phi1_deg, phi2_deg : array
        Outer and inner angles of the planned positions (deg).
    axis : {"x", "y"}
        The gyro axis the plan is for.

    Returns
    -------
    MultipositionPlan
        Rank 7, the condition number of A and the uncertainty factors.

    Raises
    ------
    ConfigError
        Fewer than 7 distinct positions, non-finite angles, or a plan that leaves coefficients
        unidentifiable (named in the message, with the reason).

    References
    ----------
    Seed 001, eqs. (4)–(6): β is unique only when AᵀA is invertible (rank A = 7).
    """
    return _plan(phi1_deg, phi2_deg, axis, ConfigError, "the plan")


def _plan(
    phi1_deg: Any, phi2_deg: Any, axis: str, error: type[Exception], what: str
) -> MultipositionPlan:
    return _plan_core(phi1_deg, phi2_deg, axis, error, what)[0]


def _plan_core(
    phi1_deg: Any, phi2_deg: Any, axis: str, error: type[Exception], what: str
) -> tuple[MultipositionPlan, np.ndarray, np.ndarray, np.ndarray]:
    """The plan's checks; also A, the first row of each position and each row's position."""
    ax_ = _axis(axis)
    names = _NAMES[ax_]
    p1, p2 = _angles(phi1_deg, phi2_deg, error)
    first, pos_of_row = _distinct_positions(p1, p2)
    if first.size < len(names):
        raise error(
            f"{what} has {first.size} distinct turntable position(s): the {len(names)} drift "
            f"coefficients of the {ax_} axis need at least {len(names)}: turn both axes in 45° steps (8 × 8 positions)."
        )
    a = drift_design_matrix(p1, p2, axis=ax_)
    rank, cond, bad, reasons = _analyse(a, names)
    if bad:
        held = [(n, v) for n, v in (("phi1_deg", p1), ("phi2_deg", p2)) if np.ptp(v) == 0]
        reasons = [*(f"{n} is {float(v[0]):g}° in every row" for n, v in held), *reasons]
        raise error(
            f"{what} leaves {', '.join(bad)} of the {ax_} axis unidentifiable ({'; '.join(reasons)}; "
            f"rank {rank} of {len(names)}): add or change positions: both axes in 45° steps "
            "(8 × 8 positions) identify all seven."
        )
    a1 = a[first]
    u = np.sqrt(np.diag(np.linalg.inv(a1.T @ a1)))
    plan = MultipositionPlan(
        axis=ax_,
        phi1_deg=p1,
        phi2_deg=p2,
        positions=int(first.size),
        rank=rank,
        condition_number=cond,
        u_factors=dict(zip(names, (float(v) for v in u), strict=True)),
        identifiable=True,
        unidentifiable=(),
    )
    return plan, a, first, pos_of_row


def multiposition_plan(
    *,
    outer_steps: int = 8,
    inner_steps: int = 8,
    outer_offset_deg: float = 0.0,
    inner_offset_deg: float = 0.0,
    axis: str = "x",
) -> MultipositionPlan:
    """A full-factorial plan: φ1 every 360°/outer_steps, φ2 every 360°/inner_steps.

    The default, both axes every 45° (64 positions), identifies all seven coefficients of either
    axis with a condition number of A of 6.9 (the smallest a uniform grid gives: the columns 1,
    a₁² and az² are correlated by geometry). Coarser grids can fail: 90° steps make ax·ay vanish;
    four inner angles at 45° + k·90° make a₁² and az² collinear with 1. Those raise ConfigError.

    Parameters
    ----------
    outer_steps, inner_steps : int
        Number of equally spaced outer and inner angles (≥ 1).
    outer_offset_deg, inner_offset_deg : float
        Angle of the first position on each axis (deg).
    axis : {"x", "y"}
        The gyro axis to check the plan for.

    Returns
    -------
    MultipositionPlan
        Angles in the order outer-major (the inner axis steps fastest), rank and conditioning.

    References
    ----------
    Seed 001, §2.1 (multiposition tests on a two-axis turntable, eqs. (2)–(6)).
    """
    steps = []
    for name, v in (("outer_steps", outer_steps), ("inner_steps", inner_steps)):
        if isinstance(v, bool) or not float(v).is_integer() or not 1 <= int(v) <= 360:
            raise ConfigError(f"{name} must be an integer from 1 to 360, got {v!r}.")
        steps.append(int(v))
    offs = []
    for name, off in (
        ("outer_offset_deg", outer_offset_deg),
        ("inner_offset_deg", inner_offset_deg),
    ):
        try:
            f = float(off)
        except (TypeError, ValueError):
            raise ConfigError(f"{name} must be a number of degrees, got {off!r}.") from None
        if not math.isfinite(f):
            raise ConfigError(f"{name} must be finite, got {off!r}.")
        offs.append(f)
    outer = offs[0] + np.arange(steps[0]) * (360.0 / steps[0])
    inner = offs[1] + np.arange(steps[1]) * (360.0 / steps[1])
    p1, p2 = np.meshgrid(outer, inner, indexing="ij")
    return _plan(
        p1.ravel(),
        p2.ravel(),
        axis,
        ConfigError,
        f"the plan of {steps[0]} outer × {steps[1]} inner angles",
    )


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
