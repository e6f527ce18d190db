"""The multiposition test an orientation error is judged by, and what the error changes in it.

Private to :mod:`rotacal.turntable.calibration` and :mod:`rotacal.turntable.orientation_limits`:
the checks of their inputs, the nominal plan fixed once (:class:`_Setup`: design matrix A, its
least-squares projector, Earth rate and gravity at the intended positions, the true coefficients
β_T), the changes ``a' − a = a·(ΔR − I)`` and ``ω' − ω`` an orientation error makes (eqs. (8)–(10)),
the coefficient deviation Δβ of eq. (12), the rate-sensing error vectors of eqs. (13)–(14) for the
three readings of eq. (13), and their exact quadratic form in (Δψ, Δθ, Δγ) used to search boxes
of orientation errors. The readings and the model are described in
:mod:`rotacal.turntable.calibration`.

References
----------
Seed 001 (GyroWheel calibration tests: error analysis and turntable error allocation), §2.2–2.3,
eqs. (5)–(14).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from typing import Any

import numpy as np

from rotacal.errors import ConfigError
from rotacal.gyro.multiposition import (
    check_multiposition_plan,
    coefficient_names,
    drift_design_matrix,
    earth_rate_and_gravity,
    multiposition_plan,
)
from rotacal.sim.multiposition import DEFAULT_LATITUDE_DEG, TABLE1_COEFFICIENTS

__all__ = ["MAX_ORIENTATION_ERROR_RAD", "METHODS"]

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
