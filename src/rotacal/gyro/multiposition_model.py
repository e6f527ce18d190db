"""The multiposition drift model of a gyro on a two-axis turntable (GyroWheel study, seed 001).

The Earth rate and gravity in the gyro frame at each position (eq. (3)), the design matrix A of
the seven drift coefficients (eqs. (1), (2), (4)–(5)), and the sensitivities of the least-squares
coefficients to the latitude and to the turntable's orientation error (eqs. (7)–(11)). The plan
check is :mod:`rotacal.gyro.multiposition_plan`, the calibration :mod:`rotacal.gyro.multiposition`.

References
----------
Seed 001 (GyroWheel calibration tests: error analysis and turntable error allocation), §2.1,
eqs. (1)–(6); §2.2, eqs. (7)–(11).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from scipy.linalg import solve_triangular

from rotacal.errors import CaptureError, ConfigError
from rotacal.signal._values import check_magnitudes, check_not_constant, check_not_copies

__all__ = [
    "COVERAGE_PROBABILITY",
    "EARTH_RATE_DEG_H",
    "coefficient_names",
    "coefficient_units",
    "drift_design_matrix",
    "drift_sensitivities",
    "earth_rate_and_gravity",
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
