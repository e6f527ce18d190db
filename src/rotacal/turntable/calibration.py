"""What an orientation error of the turntable does to a multiposition gyro calibration (GyroWheel study).

A multiposition test (GyroWheel study, §2.1, :mod:`rotacal.gyro.multiposition`) estimates the seven drift
coefficients of each gyro axis from ``b1 − b2 = A·β`` (eqs. (5)–(6)), with b2 the Earth-rate
component and A the gravity terms of eq. (3) at the *intended* positions. A turntable whose
instrument frame is off by the small rotation

    ΔR = [[1, −Δθ, Δψ], [Δθ, 1, −Δγ], [−Δψ, Δγ, 1]]                         (eq. (7))

(Δψ about the gyro's y axis, Δθ about z, Δγ about x; ΔR = R_dᵀ·R_t of eqs. (23)–(24)) makes the
gyro feel the row vectors ``ω' = ω·ΔR`` and ``a' = a·ΔR`` (eq. (8)) instead. rotacal's reading of
eqs. (9)–(14):

* the physical outputs are ``b1 = b2' + A'·β_T`` with β_T the true coefficients (default the GyroWheel study
  Table 1) and b2', A' built from ω', a' (eqs. (9)–(10));
* the lab, unaware of the error, solves eq. (6) with the nominal A and b2:
  ``β1 = (AᵀA)⁻¹Aᵀ(b1 − b2)``; eq. (11) gives ``β2 = (A'ᵀA')⁻¹A'ᵀ(b1 − b2') = β_T``, so
  ``Δβ = β1 − β2 = (AᵀA)⁻¹Aᵀ[(b2' − b2) + (A' − A)·β_T]`` (eq. (12));
* eq. (13) as printed, ``Δω = b1 − A·β2 − b2'``, does not contain Δβ although the text says "the
  deviation Δβ results in the rate-sensing error". The default ``method="coefficients"`` follows the
  text: the rate error the wrong coefficients cause at the test positions, ``Δω_vec = A·Δβ``.
  ``method="eq13"`` evaluates the printed formula with the physical b1, which is
  ``(A' − A)·β_T`` (the Earth rate drops out). ``method="earth-rate"`` keeps the Earth-rate
  reading alone, ``Δω_vec = b2' − b2`` (no gravity terms, no fit): the reading behind the paper's
  eq. (16) — for equal limits I its worst case over every orientation is √2·Ωe·I (the Earth rate
  at 45° between two gyro axes), so I = ωm/(√2·Ωe) = 0.02694° for ωm = 0.01 °/h, which the
  paper prints as 0.027°;
* eq. (14): the rate-sensing error of the axis is ``‖Δω_vec‖∞`` (°/h).

The nominal A, its least-squares projector and the hat matrix are fixed per plan, and the changes
``a' − a = a·(ΔR − I)`` are formed directly from the small quantities (no difference of large
numbers), so a whole grid of orientation errors costs a few array products.

The paper does not state its test positions or latitude; rotacal's defaults are
:func:`rotacal.gyro.multiposition.multiposition_plan` (both axes every 45°, 64 positions) and the
twin's latitude 45.75° (:data:`rotacal.sim.multiposition.DEFAULT_LATITUDE_DEG`).

References
----------
Seed 001 (GyroWheel calibration tests: error analysis and turntable error allocation), §2.2–2.3,
eqs. (7)–(16), Table 1, Figures 4–5.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from typing import Any

import numpy as np
from scipy.optimize import brentq, minimize

from rotacal.errors import ConfigError
from rotacal.gyro.multiposition import (
    EARTH_RATE_DEG_H,
    check_multiposition_plan,
    coefficient_names,
    drift_design_matrix,
    earth_rate_and_gravity,
    multiposition_plan,
)
from rotacal.results import Result
from rotacal.sim.multiposition import DEFAULT_LATITUDE_DEG, TABLE1_COEFFICIENTS
from rotacal.turntable.chain import COMPONENTS

__all__ = [
    "COMPONENTS",
    "MAX_ORIENTATION_ERROR_RAD",
    "METHODS",
    "OrientationRequirement",
    "actual_inputs",
    "coefficient_deviation",
    "equal_orientation_limit_rad",
    "orientation_matrix",
    "orientation_requirement",
    "rate_error_surfaces",
    "rate_error_vectors",
    "rate_error_vectors_from_rotation",
    "rate_sensing_error",
    "rate_sensing_error_from_rotation",
]

#: The readings of eq. (13) (see the module docstring): the text's, the formula as printed, and the
#: Earth-rate reading alone (eq. (16)'s).
METHODS = ("coefficients", "eq13", "earth-rate")
#: Largest |orientation error| accepted (rad, 5.7°): eq. (7) is a small-angle model, and a larger
#: value is almost always an angle given in degrees or arcmin instead of radians.
MAX_ORIENTATION_ERROR_RAD = 0.1

_AXES = ("x", "y")
_METHOD_TEXT = {
    "coefficients": "(‖A·Δβ‖∞, the rate error the deviated coefficients cause).",
    "eq13": "(‖(A' − A)·β_T‖∞, the GyroWheel study's eq. (13) as printed).",
    "earth-rate": "(‖b2' − b2‖∞, the Earth-rate reading alone: no gravity terms, no fit).",
}
#: The eight corners (±, ±, ±) of a box of orientation errors, in the order of COMPONENTS.
_CORNERS = np.array(
    [[s1, s2, s3] for s1 in (-1.0, 1.0) for s2 in (-1.0, 1.0) for s3 in (-1.0, 1.0)]
)


# ------------------------------------------------------------------------------------ checks


def _finite_number(name: str, value: Any) -> float:
    try:
        f = float(value)
    except (TypeError, ValueError):
        raise ConfigError(f"{name} must be a number, got {value!r}.") from None
    if not math.isfinite(f):
        raise ConfigError(f"{name} must be finite, got {value!r}.")
    return f


def _method(method: Any) -> str:
    if method not in METHODS:
        raise ConfigError(
            f"method must be one of {', '.join(repr(m) for m in METHODS)}, got {method!r}."
        )
    return str(method)


def _errors(
    dpsi: Any, dtheta: Any, dgamma: Any, *, limit: bool = True
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The three orientation-error arrays (rad), checked and broadcast to one shape."""
    out = []
    for name, v in (("dpsi", dpsi), ("dtheta", dtheta), ("dgamma", dgamma)):
        try:
            arr = np.asarray(v, dtype=float)
        except (TypeError, ValueError):
            raise ConfigError(
                f"{name} must be a number or an array of radians, got {v!r}."
            ) from None
        bad = int(np.count_nonzero(~np.isfinite(arr)))
        if bad:
            raise ConfigError(
                f"{name} has {bad} non-finite value(s) (NaN or inf): give finite orientation "
                "errors in radians."
            )
        if limit and arr.size and float(np.max(np.abs(arr))) > MAX_ORIENTATION_ERROR_RAD:
            raise ConfigError(
                f"{name} reaches {float(np.max(np.abs(arr))):.4g} rad, beyond the small-angle "
                f"model of the GyroWheel study's eq. (7) (|error| ≤ {MAX_ORIENTATION_ERROR_RAD} rad): give "
                "orientation errors in radians (e.g. np.radians(arcmin / 60))."
            )
        out.append(arr)
    try:
        b = np.broadcast_arrays(*out)
    except ValueError:
        raise ConfigError(
            "dpsi, dtheta and dgamma must broadcast to one shape, got shapes "
            f"{out[0].shape}, {out[1].shape} and {out[2].shape}."
        ) from None
    return b[0], b[1], b[2]


def _coefficients(coefficients: Any) -> dict[str, np.ndarray]:
    """β_T of both axes in the order of coefficient_names(axis); missing values from Table 1."""
    given: Mapping[str, Any] = {} if coefficients is None else coefficients
    if not isinstance(given, Mapping):
        raise ConfigError(
            "coefficients must map 'x' and/or 'y' to a mapping of drift coefficients by name, got "
            f"{type(coefficients).__name__}."
        )
    unknown = [k for k in given if k not in _AXES]
    if unknown:
        raise ConfigError(
            f"coefficients has an unknown axis {unknown[0]!r}: use 'x' and/or 'y', each mapping "
            "drift-coefficient names to values."
        )
    out = {}
    for axis in _AXES:
        base = dict(TABLE1_COEFFICIENTS[axis])
        over = given.get(axis, {})
        if not isinstance(over, Mapping):
            raise ConfigError(
                f"coefficients[{axis!r}] must map drift-coefficient names to values, got "
                f"{type(over).__name__}."
            )
        for k, v in over.items():
            if k not in base:
                raise ConfigError(
                    f"unknown drift coefficient {k!r} for the {axis} axis; known: "
                    f"{', '.join(base)}."
                )
            base[k] = _finite_number(f"drift coefficient {axis}.{k}", v)
        out[axis] = np.array([base[k] for k in coefficient_names(axis)])
    return out


# ------------------------------------------------------------------------------------- setup


@dataclasses.dataclass
class _Setup:
    """Everything fixed per plan: nominal inputs, design matrices, projectors, β_T."""

    phi1_deg: np.ndarray
    phi2_deg: np.ndarray
    latitude_deg: float
    earth_rate_deg_h: float
    method: str
    omega: np.ndarray  # (n, 3) °/h, eq. (3)
    gravity: np.ndarray  # (n, 3) g, eq. (3)
    design: dict[str, np.ndarray]  # axis → A (n, 7)
    projector: dict[str, np.ndarray]  # axis → (AᵀA)⁻¹Aᵀ (7, n)
    beta: dict[str, np.ndarray]  # axis → β_T (7,)
    quadratic: dict[str, tuple[np.ndarray, np.ndarray]] = dataclasses.field(
        default_factory=dict
    )  # axis → (W_β, W_ω), see _quadratic_model

    @property
    def positions(self) -> int:
        return int(self.phi1_deg.size)


def _setup(
    phi1_deg: Any,
    phi2_deg: Any,
    latitude_deg: Any,
    coefficients: Any,
    method: Any,
    earth_rate_deg_h: Any,
) -> _Setup:
    meth = _method(method)
    if (phi1_deg is None) != (phi2_deg is None):
        raise ConfigError(
            "give both phi1_deg and phi2_deg (the plan's outer and inner angles, deg), or neither "
            "for the default plan (both axes every 45°)."
        )
    if phi1_deg is None:
        plan = multiposition_plan()
        p1, p2 = plan.phi1_deg, plan.phi2_deg
    else:
        p1, p2 = phi1_deg, phi2_deg
    # Both axes must identify their seven coefficients; these raise ConfigError naming the fault.
    checked = check_multiposition_plan(p1, p2, axis="x")
    check_multiposition_plan(p1, p2, axis="y")
    p1, p2 = checked.phi1_deg, checked.phi2_deg
    we = _finite_number("earth_rate_deg_h", earth_rate_deg_h)
    if we < 0:
        raise ConfigError(f"earth_rate_deg_h must be ≥ 0 °/h, got {earth_rate_deg_h!r}.")
    lat = DEFAULT_LATITUDE_DEG if latitude_deg is None else latitude_deg
    w, a = earth_rate_and_gravity(p1, p2, lat, earth_rate_deg_h=we)  # checks the latitude
    beta = _coefficients(coefficients)
    design, proj = {}, {}
    for axis in _AXES:
        amat = drift_design_matrix(p1, p2, axis=axis)
        q, r = np.linalg.qr(amat)
        design[axis] = amat
        proj[axis] = np.linalg.solve(r, q.T)  # (AᵀA)⁻¹Aᵀ = R⁻¹Qᵀ
    s = _Setup(
        phi1_deg=np.asarray(p1, dtype=float),
        phi2_deg=np.asarray(p2, dtype=float),
        latitude_deg=float(lat),
        earth_rate_deg_h=we,
        method=meth,
        omega=w,
        gravity=a,
        design=design,
        projector=proj,
        beta=beta,
    )
    s.quadratic = _quadratic_model(s)
    return s


# ---------------------------------------------------------------------------------- the maths


def _uniform_delta(dpsi: np.ndarray, dtheta: np.ndarray, dgamma: np.ndarray) -> np.ndarray:
    """ΔR − I of eq. (7), shape (..., 3, 3)."""
    z = np.zeros_like(dpsi)
    return np.stack(
        [
            np.stack([z, -dtheta, dpsi], -1),
            np.stack([dtheta, z, -dgamma], -1),
            np.stack([-dpsi, dgamma, z], -1),
        ],
        -2,
    )


def _input_changes(s: _Setup, d: np.ndarray, per_position: bool) -> tuple[np.ndarray, np.ndarray]:
    """ω' − ω and a' − a (row vectors times ΔR − I, eq. (8)), each of shape (..., n, 3).

    ``d`` is ΔR − I: (..., 3, 3) for one ΔR at every position, (..., n, 3, 3) for one per position.
    """
    if per_position:
        dw = np.matmul(s.omega[:, None, :], d)[..., 0, :]
        da = np.matmul(s.gravity[:, None, :], d)[..., 0, :]
    else:
        dw = np.matmul(s.omega, d)
        da = np.matmul(s.gravity, d)
    return dw, da


def _design_change_times_beta(s: _Setup, axis: str, da: np.ndarray) -> np.ndarray:
    """(A' − A)·β_T of eq. (10) from the exact column changes, shape (..., n)."""
    g = s.gravity
    ax, ay, az = g[:, 0], g[:, 1], g[:, 2]
    dx, dy, dz = da[..., 0], da[..., 1], da[..., 2]
    b = s.beta[axis]
    if axis == "x":
        dsq = dx * (2.0 * ax + dx)  # ax'² − ax²
    else:
        dsq = dy * (2.0 * ay + dy)  # ay'² − ay²
    dzz = dz * (2.0 * az + dz)
    dxy = dx * ay + ax * dy + dx * dy  # ax'·ay' − ax·ay
    # column "1" does not change
    return b[1] * dx + b[2] * dy + b[3] * dz + b[4] * dsq + b[5] * dzz + b[6] * dxy


def _deviations(
    s: _Setup, d: np.ndarray, per_position: bool
) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """Per axis: (Δβ (..., 7), Δω_vec (..., n)) for ΔR − I = d, by the setup's method."""
    dw, da = _input_changes(s, d, per_position)
    out = {}
    for k, axis in enumerate(_AXES):
        dab = _design_change_times_beta(s, axis, da)
        # b1 − b2 = (b2' − b2) + (A' − A)β_T + Aβ_T, so Δβ = P·[(b2' − b2) + (A' − A)β_T].
        dbeta = (dw[..., k] + dab) @ s.projector[axis].T
        if s.method == "eq13":
            vec = dab
        elif s.method == "earth-rate":
            vec = dw[..., k]  # b2' − b2: what the axis reads wrong of the Earth rate
        else:
            vec = dbeta @ s.design[axis].T
        out[axis] = (dbeta, vec)
    return out


def _norms(dev: dict[str, tuple[np.ndarray, np.ndarray]]) -> tuple[np.ndarray, np.ndarray]:
    return (
        np.max(np.abs(dev["x"][1]), axis=-1),
        np.max(np.abs(dev["y"][1]), axis=-1),
    )


#: Pairs (j, k) of the quadratic features e_j·e_k, after the three linear ones and three squares.
_CROSS = ((0, 1), (0, 2), (1, 2))


def _features(p: np.ndarray, t: np.ndarray, g: np.ndarray) -> np.ndarray:
    """(ψ, θ, γ, ψ², θ², γ², ψθ, ψγ, θγ), shape (..., 9)."""
    return np.stack([p, t, g, p * p, t * t, g * g, p * t, p * g, t * g], -1)


def _quadratic_model(s: _Setup) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """Per axis, W_β (9, 7) and W_ω (9, n) with Δβ = f(e)·W_β and Δω_vec = f(e)·W_ω.

    For one ΔR of eq. (7) at every position, a' − a is linear in e = (Δψ, Δθ, Δγ) and A' − A is at
    most quadratic, so Δβ and Δω_vec are exactly quadratic in e. Their coefficients come from the
    exact path at e = ±u_j and u_j + u_k (polarisation), which is exact for a quadratic.
    """
    eye = np.eye(3)
    pts = [eye, -eye, np.array([eye[j] + eye[k] for j, k in _CROSS])]
    e = np.concatenate(pts)  # (9, 3): +u_j, −u_j, u_j + u_k
    dev = _deviations(s, _uniform_delta(e[:, 0], e[:, 1], e[:, 2]), per_position=False)
    out = {}
    for axis in _AXES:
        coefs = []
        for q in dev[axis]:  # Δβ (9, 7), then Δω_vec (9, n)
            plus, minus, pair = q[0:3], q[3:6], q[6:9]
            lin = 0.5 * (plus - minus)
            sq = 0.5 * (plus + minus)
            cross = np.array([pair[i] - plus[j] - plus[k] for i, (j, k) in enumerate(_CROSS)])
            coefs.append(np.concatenate([lin, sq, cross]))
        out[axis] = (coefs[0], coefs[1])
    return out


def _from_errors(s: _Setup, dpsi: Any, dtheta: Any, dgamma: Any) -> dict[str, Any]:
    """Per axis (Δβ (..., 7), Δω_vec (..., n)) for orientation errors broadcast together."""
    p, t, g = _errors(dpsi, dtheta, dgamma)
    f = _features(p, t, g)
    return {axis: (f @ wb, f @ wv) for axis, (wb, wv) in s.quadratic.items()}


# ----------------------------------------------------------------------------------- public


def orientation_matrix(dpsi: Any, dtheta: Any, dgamma: Any) -> np.ndarray:
    """The small-angle orientation-error matrix ΔR of the GyroWheel study, eq. (7).

    ``ΔR = [[1, −Δθ, Δψ], [Δθ, 1, −Δγ], [−Δψ, Δγ, 1]]`` (= I + skew(Δγ, Δψ, Δθ)).

    Parameters
    ----------
    dpsi, dtheta, dgamma : float or array
        Orientation errors Δψ (about the gyro's y axis), Δθ (about z), Δγ (about x), rad;
        broadcast together.

    Returns
    -------
    ndarray, shape (..., 3, 3)
        ΔR (dimensionless), one per broadcast element.

    References
    ----------
    Seed 001, §2.2, eq. (7).
    """
    p, t, g = _errors(dpsi, dtheta, dgamma, limit=False)
    return _uniform_delta(p, t, g) + np.eye(3)


def actual_inputs(
    dpsi: Any,
    dtheta: Any,
    dgamma: Any,
    *,
    phi1_deg: Any = None,
    phi2_deg: Any = None,
    latitude_deg: float = DEFAULT_LATITUDE_DEG,
    earth_rate_deg_h: float = EARTH_RATE_DEG_H,
) -> tuple[np.ndarray, np.ndarray]:
    """Earth rate and gravity the gyro really senses with an orientation error (eq. (8)).

    ``ω' = ω·ΔR``, ``a' = a·ΔR`` (row vectors) with ω, a of eq. (3) at each planned position.

    Parameters
    ----------
    dpsi, dtheta, dgamma : float or array
        Orientation errors (rad), broadcast together; |error| ≤ 0.1 rad.
    phi1_deg, phi2_deg : array or None
        Outer and inner angles of the plan (deg); None: both axes every 45° (64 positions).
    latitude_deg : float
        Latitude of the laboratory (deg).
    earth_rate_deg_h : float
        Earth rate Ωe (°/h).

    Returns
    -------
    (omega_deg_h, gravity_g) : (ndarray, ndarray)
        Each of shape (..., n, 3): (ωx', ωy', ωz') in °/h and (ax', ay', az') in g.

    References
    ----------
    Seed 001, §2.1–2.2, eqs. (3), (7) and (8).
    """
    s = _setup(phi1_deg, phi2_deg, latitude_deg, None, "coefficients", earth_rate_deg_h)
    p, t, g = _errors(dpsi, dtheta, dgamma)
    dw, da = _input_changes(s, _uniform_delta(p, t, g), per_position=False)
    return s.omega + dw, s.gravity + da


def coefficient_deviation(
    dpsi: Any,
    dtheta: Any,
    dgamma: Any,
    *,
    phi1_deg: Any = None,
    phi2_deg: Any = None,
    latitude_deg: float = DEFAULT_LATITUDE_DEG,
    coefficients: Mapping[str, Mapping[str, float]] | None = None,
    earth_rate_deg_h: float = EARTH_RATE_DEG_H,
) -> tuple[np.ndarray, np.ndarray]:
    """Deviation Δβ = β1 − β2 of the calibrated drift coefficients (eq. (12)).

    ``Δβ = (AᵀA)⁻¹Aᵀ[(b2' − b2) + (A' − A)·β_T]``: eq. (6) applied by a lab unaware of the
    orientation error, minus the truth β2 = β_T of eq. (11).

    Parameters
    ----------
    dpsi, dtheta, dgamma : float or array
        Orientation errors (rad), broadcast together; |error| ≤ 0.1 rad.
    phi1_deg, phi2_deg : array or None
        The plan (deg); None: both axes every 45° (64 positions).
    latitude_deg : float
        Latitude (deg).
    coefficients : mapping or None
        True drift coefficients β_T, ``{"x": {...}, "y": {...}}`` by the names of
        :func:`rotacal.gyro.multiposition.coefficient_names` (deg/h, deg/h/g, deg/h/g²);
        missing axes or names take the GyroWheel study's Table 1 values.
    earth_rate_deg_h : float
        Earth rate Ωe (°/h).

    Returns
    -------
    (dbeta_x, dbeta_y) : (ndarray, ndarray)
        Each of shape (..., 7), in the order of ``coefficient_names(axis)`` (deg/h, deg/h/g,
        deg/h/g²).

    References
    ----------
    Seed 001, §2.2, eqs. (6), (9)–(12).
    """
    s = _setup(phi1_deg, phi2_deg, latitude_deg, coefficients, "coefficients", earth_rate_deg_h)
    dev = _from_errors(s, dpsi, dtheta, dgamma)
    return dev["x"][0], dev["y"][0]


def rate_error_vectors(
    dpsi: Any,
    dtheta: Any,
    dgamma: Any,
    *,
    phi1_deg: Any = None,
    phi2_deg: Any = None,
    latitude_deg: float = DEFAULT_LATITUDE_DEG,
    coefficients: Mapping[str, Mapping[str, float]] | None = None,
    method: str = "coefficients",
    earth_rate_deg_h: float = EARTH_RATE_DEG_H,
) -> tuple[np.ndarray, np.ndarray]:
    """Rate-sensing error vectors at the test positions (eq. (13), rotacal's reading).

    ``method="coefficients"``: ``A·Δβ`` (the error the deviated coefficients cause);
    ``method="eq13"``: ``b1 − A·β2 − b2' = (A' − A)·β_T`` (the formula as printed);
    ``method="earth-rate"``: ``b2' − b2`` (the Earth-rate reading alone).

    Parameters
    ----------
    dpsi, dtheta, dgamma : float or array
        Orientation errors (rad), broadcast together; |error| ≤ 0.1 rad.
    phi1_deg, phi2_deg, latitude_deg, coefficients, earth_rate_deg_h
        As in :func:`rate_sensing_error`.
    method : {"coefficients", "eq13", "earth-rate"}
        The reading of eq. (13).

    Returns
    -------
    (dw_x, dw_y) : (ndarray, ndarray)
        Each of shape (..., n) (°/h), one value per test position.

    References
    ----------
    Seed 001, §2.2, eqs. (12)–(13).
    """
    s = _setup(phi1_deg, phi2_deg, latitude_deg, coefficients, method, earth_rate_deg_h)
    dev = _from_errors(s, dpsi, dtheta, dgamma)
    return dev["x"][1], dev["y"][1]


def rate_sensing_error(
    dpsi: Any,
    dtheta: Any,
    dgamma: Any,
    *,
    phi1_deg: Any = None,
    phi2_deg: Any = None,
    latitude_deg: float = DEFAULT_LATITUDE_DEG,
    coefficients: Mapping[str, Mapping[str, float]] | None = None,
    method: str = "coefficients",
    earth_rate_deg_h: float = EARTH_RATE_DEG_H,
) -> tuple[np.ndarray, np.ndarray]:
    """Rate-sensing errors Δωx, Δωy caused by an orientation error (eqs. (7)–(14)).

    Whole-array: the nominal design matrices and projectors are built once per call, then any
    grid of orientation errors costs a few array products.

    Parameters
    ----------
    dpsi, dtheta, dgamma : float or array
        Orientation errors Δψ (about y), Δθ (about z), Δγ (about x), rad, broadcast together;
        |error| ≤ 0.1 rad (eq. (7) is a small-angle model).
    phi1_deg, phi2_deg : array or None
        Outer and inner angles of the multiposition plan (deg); both or neither. None: both axes
        every 45° (64 positions). The plan must identify the seven coefficients of both axes.
    latitude_deg : float
        Latitude of the laboratory (deg); default 45.75° (the paper states none).
    coefficients : mapping or None
        True drift coefficients β_T, ``{"x": {...}, "y": {...}}`` (deg/h, deg/h/g, deg/h/g²);
        missing axes or names take the GyroWheel study's Table 1 values.
    method : {"coefficients", "eq13", "earth-rate"}
        ``"coefficients"``: ‖A·Δβ‖∞ (the text's meaning); ``"eq13"``: ‖(A' − A)·β_T‖∞ (eq. (13)
        as printed); ``"earth-rate"``: ‖b2' − b2‖∞ (the Earth-rate reading alone, eq. (16)'s).
        See the module docstring.
    earth_rate_deg_h : float
        Earth rate Ωe (°/h); default sidereal 15.041067.

    Returns
    -------
    (dw_x, dw_y) : (ndarray, ndarray)
        Δωx and Δωy (°/h), of the broadcast shape of the orientation errors.

    Raises
    ------
    ConfigError
        Non-finite or too large orientation errors, shapes that do not broadcast, an unknown
        method or coefficient, a latitude beyond ±90°, a plan that leaves coefficients
        unidentifiable.

    References
    ----------
    Seed 001, §2.2, eqs. (7)–(14) and Table 1.
    """
    s = _setup(phi1_deg, phi2_deg, latitude_deg, coefficients, method, earth_rate_deg_h)
    return _norms(_from_errors(s, dpsi, dtheta, dgamma))


def rate_sensing_error_from_rotation(
    delta_r: Any,
    *,
    phi1_deg: Any,
    phi2_deg: Any,
    latitude_deg: float = DEFAULT_LATITUDE_DEG,
    coefficients: Mapping[str, Mapping[str, float]] | None = None,
    method: str = "coefficients",
    earth_rate_deg_h: float = EARTH_RATE_DEG_H,
) -> tuple[np.ndarray, np.ndarray]:
    """Rate-sensing errors Δωx, Δωy for an orientation error that differs from position to position.

    Same as :func:`rate_sensing_error`, but ΔR is given per test position — e.g. ``ΔR = R_dᵀR_t`` of
    the turntable model (eqs. (23)–(24)) at each (φ1, φ2) of the plan, whose orientation error
    varies with φ2 (eq. (26)). ΔR may be the small-angle matrix or a proper rotation; the inputs
    are ``ω·ΔR`` and ``a·ΔR`` (eq. (8)).

    Parameters
    ----------
    delta_r : array, shape (..., n, 3, 3)
        ΔR at each of the n test positions (dimensionless), in the order of the plan's angles; a
        leading batch shape is allowed. n = 1 applies one ΔR to every position.
    phi1_deg, phi2_deg : array
        Outer and inner angles of the plan (deg), n each.
    latitude_deg, coefficients, method, earth_rate_deg_h
        As in :func:`rate_sensing_error`.

    Returns
    -------
    (dw_x, dw_y) : (ndarray, ndarray)
        Δωx and Δωy (°/h), of shape ``delta_r.shape[:-3]``.

    Raises
    ------
    ConfigError
        A ΔR of the wrong shape, non-finite, or more than 0.1 from the identity in any element;
        the faults of :func:`rate_sensing_error`.

    References
    ----------
    Seed 001, §2.2, eqs. (8)–(14); §3.2, eqs. (23)–(24).
    """
    return _norms(
        _rotation_deviations(
            delta_r, phi1_deg, phi2_deg, latitude_deg, coefficients, method, earth_rate_deg_h
        )
    )


def _rotation_deviations(
    delta_r: Any,
    phi1_deg: Any,
    phi2_deg: Any,
    latitude_deg: Any,
    coefficients: Any,
    method: Any,
    earth_rate_deg_h: Any,
) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """Per axis (Δβ, Δω_vec) for a ΔR per test position, checked (see the public functions)."""
    s = _setup(phi1_deg, phi2_deg, latitude_deg, coefficients, method, earth_rate_deg_h)
    try:
        r = np.asarray(delta_r, dtype=float)
    except (TypeError, ValueError):
        raise ConfigError("delta_r must be an array of 3 × 3 matrices.") from None
    n = s.positions
    if r.ndim < 3 or r.shape[-2:] != (3, 3) or r.shape[-3] not in (1, n):
        raise ConfigError(
            f"delta_r must have shape (..., {n}, 3, 3) (one ΔR per test position of the plan), "
            f"got {r.shape}."
        )
    if not np.all(np.isfinite(r)):
        raise ConfigError("delta_r has non-finite values (NaN or inf): give finite matrices.")
    d = r - np.eye(3)
    if d.size and float(np.max(np.abs(d))) > MAX_ORIENTATION_ERROR_RAD:
        raise ConfigError(
            f"delta_r differs from the identity by up to {float(np.max(np.abs(d))):.4g}, beyond "
            f"the small orientation errors of the GyroWheel study (≤ {MAX_ORIENTATION_ERROR_RAD} rad): pass "
            "ΔR = R_dᵀ·R_t, not R_t."
        )
    return _deviations(s, d, per_position=True)


def rate_error_vectors_from_rotation(
    delta_r: Any,
    *,
    phi1_deg: Any,
    phi2_deg: Any,
    latitude_deg: float = DEFAULT_LATITUDE_DEG,
    coefficients: Mapping[str, Mapping[str, float]] | None = None,
    method: str = "coefficients",
    earth_rate_deg_h: float = EARTH_RATE_DEG_H,
) -> tuple[np.ndarray, np.ndarray]:
    """Rate-sensing error vectors at the test positions for a ΔR per position (eqs. (8)–(13)).

    The vectors whose ∞-norms :func:`rate_sensing_error_from_rotation` returns (eq. (14)).

    Parameters
    ----------
    delta_r, phi1_deg, phi2_deg, latitude_deg, coefficients, method, earth_rate_deg_h
        As in :func:`rate_sensing_error_from_rotation`.

    Returns
    -------
    (dw_x, dw_y) : (ndarray, ndarray)
        Each of shape ``delta_r.shape[:-3] + (n,)`` (°/h), one value per test position.

    References
    ----------
    Seed 001, §2.2, eqs. (8)–(13); §3.2, eqs. (23)–(24).
    """
    dev = _rotation_deviations(
        delta_r, phi1_deg, phi2_deg, latitude_deg, coefficients, method, earth_rate_deg_h
    )
    return dev["x"][1], dev["y"][1]


# ------------------------------------------------------------------------- the requirement


@dataclasses.dataclass(frozen=True)
class OrientationRequirement(Result):
    """The allowed orientation error for a required calibration accuracy (eqs. (15)–(16)).

    ``limits_rad`` is the box (Iψ, Iθ, Iγ) of largest volume such that at every corner
    (±Iψ, ±Iθ, ±Iγ) both Δωx and Δωy are ≤ ``required_deg_h``; ``equal_limit_rad`` the largest
    I with Iψ = Iθ = Iγ = I (the form of the paper's eq. (16)). ``rate_error_at_limits_deg_h`` is
    the largest Δωx, Δωy over the box's corners (°/h).
    """

    required_deg_h: float
    limits_rad: dict[str, float]
    limits_deg: dict[str, float]
    equal_limit_rad: float
    equal_limit_deg: float
    rate_error_at_limits_deg_h: dict[str, float]
    rate_error_at_equal_limit_deg_h: dict[str, float]
    method: str
    positions: int
    latitude_deg: float
    notes: tuple[str, ...] = ()


def _corner_vectors(s: _Setup, limits: np.ndarray) -> np.ndarray:
    """Δω_vec of both axes at the 8 corners of the box ``limits`` (3,): shape (2, 8, n)."""
    c = _CORNERS * limits
    f = _features(c[:, 0], c[:, 1], c[:, 2])
    return np.stack([f @ s.quadratic[axis][1] for axis in _AXES])


def _corner_max(s: _Setup, limits: np.ndarray) -> np.ndarray:
    """Largest Δωx and Δωy over the corners of the box (°/h), shape (2,)."""
    return np.asarray(np.max(np.abs(_corner_vectors(s, limits)), axis=(1, 2)))


def _scale_to_boundary(s: _Setup, shape: np.ndarray, wm: float) -> tuple[float, bool]:
    """Largest t with max corner error of the box t·shape ≤ wm; (t, capped at the 0.1 rad limit)."""
    t_cap = MAX_ORIENTATION_ERROR_RAD / float(np.max(shape))

    def excess(t: float) -> float:
        return float(np.max(_corner_max(s, t * shape))) - wm

    if excess(t_cap) <= 0.0:
        return t_cap, True
    # near-linear response: a small probe gives a good first bracket
    probe = 1e-6 * t_cap
    m = excess(probe) + wm
    lo = min(0.5 * probe * wm / m, t_cap) if m > 0 else probe
    while excess(lo) > 0.0:
        lo *= 0.5
    hi = min(2.0 * lo, t_cap)
    while excess(hi) <= 0.0:
        lo, hi = hi, min(2.0 * hi, t_cap)
    t = brentq(excess, lo, hi, xtol=1e-15 * hi, rtol=4 * np.finfo(float).eps, maxiter=200)
    shrink = 1e-13
    while excess(t) > 0.0:  # brentq may land a hair outside: step to the feasible side
        t = max(t * (1.0 - shrink), lo)
        shrink *= 4.0
    return float(t), False


def _required(required_deg_h: Any) -> float:
    """ωm (°/h) as a float; a non-positive or non-finite one is one ConfigError line."""
    wm = _finite_number("required_deg_h", required_deg_h)
    if wm <= 0:
        raise ConfigError(
            f"required_deg_h must be a positive accuracy in °/h, got {required_deg_h!r}."
        )
    return wm


def equal_orientation_limit_rad(
    required_deg_h: float = 0.01,
    *,
    phi1_deg: Any = None,
    phi2_deg: Any = None,
    latitude_deg: float = DEFAULT_LATITUDE_DEG,
    coefficients: Mapping[str, Mapping[str, float]] | None = None,
    method: str = "coefficients",
    earth_rate_deg_h: float = EARTH_RATE_DEG_H,
) -> float:
    """The equal limit I = Iψ = Iθ = Iγ (rad) of :func:`orientation_requirement` alone.

    The same root (the largest I at which every corner (±I, ±I, ±I) keeps Δωx, Δωy ≤ ωm), hence
    the same number as its ``equal_limit_rad``, without the box of largest volume that SLSQP
    finds there — most of its time, and not needed where only the form of eq. (16) is asked
    (the latitude and plan scan of :func:`rotacal.turntable.seed001.reproduce_seed001`).

    Parameters
    ----------
    required_deg_h : float
        Required calibration accuracy ωm (°/h, > 0).
    phi1_deg, phi2_deg, latitude_deg, coefficients, method, earth_rate_deg_h
        As in :func:`rate_sensing_error`.

    Returns
    -------
    float
        I (rad).

    Raises
    ------
    ConfigError
        As :func:`orientation_requirement`.

    References
    ----------
    Seed 001, §2.2–2.3, eqs. (13)–(16).
    """
    wm = _required(required_deg_h)
    s = _setup(phi1_deg, phi2_deg, latitude_deg, coefficients, method, earth_rate_deg_h)
    return _scale_to_boundary(s, np.ones(3), wm)[0]


def orientation_requirement(
    required_deg_h: float = 0.01,
    *,
    phi1_deg: Any = None,
    phi2_deg: Any = None,
    latitude_deg: float = DEFAULT_LATITUDE_DEG,
    coefficients: Mapping[str, Mapping[str, float]] | None = None,
    method: str = "coefficients",
    earth_rate_deg_h: float = EARTH_RATE_DEG_H,
) -> OrientationRequirement:
    """Allowed orientation error (Iψ, Iθ, Iγ) for a required calibration accuracy ωm (eq. (15)).

    The paper (Figure 5) draws the rectangles of largest area inside Δωx ≤ ωm over (Δψ, Δθ) and
    Δωy ≤ ωm over (Δθ, Δγ). rotacal takes the box of largest volume — maximising
    log Iψ + log Iθ + log Iγ, since the two rectangles share Iθ — such that at every corner
    (±Iψ, ±Iθ, ±Iγ) the full model gives Δωx ≤ ωm and Δωy ≤ ωm (Δω is the ∞-norm of a
    near-linear function of the errors, so the corners are the worst points of the box). It is
    solved by SLSQP in log variables with one smooth constraint ``±Δω_i ≤ ωm`` per corner, axis and
    test position, then scaled so that the worst corner meets ωm (root-finding). The equal limit
    (Iψ = Iθ = Iγ, the form of eq. (16)) is a 1-D root.

    Parameters
    ----------
    required_deg_h : float
        Required calibration accuracy ωm (°/h, > 0); default 0.01 (the GyroWheel study's example, §2.3).
    phi1_deg, phi2_deg, latitude_deg, coefficients, method, earth_rate_deg_h
        As in :func:`rate_sensing_error`.

    Returns
    -------
    OrientationRequirement
        The box and the equal limit (rad and deg), the worst Δωx, Δωy at each (°/h), notes.

    Raises
    ------
    ConfigError
        A non-positive or non-finite ωm; the faults of :func:`rate_sensing_error`.

    References
    ----------
    Seed 001, §2.2–2.3, eqs. (13)–(16), Figures 4–5.
    """
    wm = _required(required_deg_h)
    s = _setup(phi1_deg, phi2_deg, latitude_deg, coefficients, method, earth_rate_deg_h)
    notes: list[str] = [
        f"plan of {s.positions} positions, latitude {s.latitude_deg:g}°, Earth rate "
        f"{s.earth_rate_deg_h:.8g} °/h; Δω by method {s.method!r} " + _METHOD_TEXT[s.method],
        "the paper's 0.027° (eq. (16)) states neither its plan nor its latitude; it is the Earth-rate "
        "reading alone (method 'earth-rate'), ωm/(√2·Ωe) = 0.02694°; rotacal's values are not "
        "tuned toward it.",
    ]
    ones = np.ones(3)
    i_eq, capped_eq = _scale_to_boundary(s, ones, wm)
    if capped_eq:
        notes.append(
            f"the equal limit reaches the small-angle cap {MAX_ORIENTATION_ERROR_RAD} rad: the "
            "requirement is not binding there."
        )
    lo_b = math.log(i_eq) - math.log(1e3)
    hi_b = math.log(MAX_ORIENTATION_ERROR_RAD)

    def cons(x: np.ndarray) -> np.ndarray:
        v = _corner_vectors(s, np.exp(x)).ravel() / wm
        return np.concatenate([1.0 - v, 1.0 + v])

    x0 = np.full(3, math.log(i_eq) - 1e-6)
    res = minimize(
        lambda x: -float(np.sum(x)),
        x0,
        jac=lambda x: -np.ones(3),
        method="SLSQP",
        bounds=[(lo_b, hi_b)] * 3,
        constraints=[{"type": "ineq", "fun": cons}],
        options={"ftol": 1e-13, "maxiter": 500},
    )
    shape = np.exp(np.clip(res.x, lo_b, hi_b)) if np.all(np.isfinite(res.x)) else ones
    t, capped = _scale_to_boundary(s, shape / np.max(shape), wm)
    box = t * shape / np.max(shape)
    if not res.success:
        notes.append(f"SLSQP did not report convergence ({res.message}); the box was verified.")
    if float(np.sum(np.log(box))) < 3.0 * math.log(i_eq):
        box = np.full(3, i_eq)
        notes.append(
            "the optimiser found no box larger than the equal one; the equal box is given."
        )
    if capped:
        notes.append(
            f"a limit reaches the small-angle cap {MAX_ORIENTATION_ERROR_RAD} rad: that component "
            "is not bounded by the requirement."
        )
    at_box = _corner_max(s, box)
    at_eq = _corner_max(s, np.full(3, i_eq))
    if float(np.max(at_box)) > wm * (1 + 1e-9) or float(np.max(at_eq)) > wm * (1 + 1e-9):
        raise RuntimeError("orientation_requirement: the verified box exceeds ωm (a bug).")
    return OrientationRequirement(
        required_deg_h=wm,
        limits_rad=dict(zip(COMPONENTS, (float(v) for v in box), strict=True)),
        limits_deg=dict(zip(COMPONENTS, (math.degrees(float(v)) for v in box), strict=True)),
        equal_limit_rad=float(i_eq),
        equal_limit_deg=math.degrees(i_eq),
        rate_error_at_limits_deg_h={"x": float(at_box[0]), "y": float(at_box[1])},
        rate_error_at_equal_limit_deg_h={"x": float(at_eq[0]), "y": float(at_eq[1])},
        method=s.method,
        positions=s.positions,
        latitude_deg=s.latitude_deg,
        notes=tuple(notes),
    )


def rate_error_surfaces(
    limit_rad: float,
    *,
    n: int = 41,
    phi1_deg: Any = None,
    phi2_deg: Any = None,
    latitude_deg: float = DEFAULT_LATITUDE_DEG,
    coefficients: Mapping[str, Mapping[str, float]] | None = None,
    method: str = "coefficients",
    earth_rate_deg_h: float = EARTH_RATE_DEG_H,
) -> dict[str, Any]:
    """Δωx and Δωy over planes of orientation errors, the data of the GyroWheel study's Figure 4.

    Each plane varies two components over ``[−limit_rad, +limit_rad]`` (n points each) with the
    third at zero; each curve varies one component with the other two at zero.

    Parameters
    ----------
    limit_rad : float
        Half-width of the grid (rad, 0 < limit ≤ 0.1).
    n : int
        Points per grid axis (≥ 2).
    phi1_deg, phi2_deg, latitude_deg, coefficients, method, earth_rate_deg_h
        As in :func:`rate_sensing_error`.

    Returns
    -------
    dict
        ``grid_rad`` (n,); ``x`` and ``y``: for each plane ``"psi_theta"``, ``"theta_gamma"``,
        ``"psi_gamma"`` an (n, n) array of Δω (°/h), first index the first-named component;
        ``curves``: ``{"x": {"psi": (n,), "theta": ..., "gamma": ...}, "y": {...}}``; ``method``,
        ``latitude_deg``, ``positions``, ``units`` ("deg/h").

    References
    ----------
    Seed 001, §2.2, eqs. (7)–(14), Figure 4.
    """
    lim = _finite_number("limit_rad", limit_rad)
    if not 0 < lim <= MAX_ORIENTATION_ERROR_RAD:
        raise ConfigError(
            f"limit_rad must be in (0, {MAX_ORIENTATION_ERROR_RAD}] rad, got {limit_rad!r}."
        )
    if isinstance(n, bool) or not float(n).is_integer() or int(n) < 2:
        raise ConfigError(f"n must be an integer ≥ 2, got {n!r}.")
    s = _setup(phi1_deg, phi2_deg, latitude_deg, coefficients, method, earth_rate_deg_h)
    g = np.linspace(-lim, lim, int(n))
    u, v = np.meshgrid(g, g, indexing="ij")
    z2 = np.zeros_like(u)
    planes = {
        "psi_theta": (u, v, z2),
        "theta_gamma": (z2, u, v),
        "psi_gamma": (u, z2, v),
    }
    out: dict[str, Any] = {"grid_rad": g, "x": {}, "y": {}, "curves": {"x": {}, "y": {}}}
    for name, (p, t, gm) in planes.items():
        wx, wy = _norms(_from_errors(s, p, t, gm))
        out["x"][name], out["y"][name] = wx, wy
    z1 = np.zeros_like(g)
    for k, comp in enumerate(COMPONENTS):
        args = [z1, z1, z1]
        args[k] = g
        wx, wy = _norms(_from_errors(s, *args))
        out["curves"]["x"][comp], out["curves"]["y"][comp] = wx, wy
    out.update(method=s.method, latitude_deg=s.latitude_deg, positions=s.positions, units="deg/h")
    return out
