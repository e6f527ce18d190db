"""Digital twin of a multiposition drift test on a two-axis turntable (GyroWheel study, §2.1).

The gyro (a GyroWheel or any two-axis rate sensor with g-sensitive drift) sits on the inner axis
of a two-axis turntable. Its axes start north-west-up (x north, y west, z up). The outer axis is
horizontal along west (the gyro's y axis at φ1 = 0) and turns by φ1; the inner axis is the
gyro's z axis and turns by φ2. A world vector v (NWU) then has gyro-frame components

    v_g = Rz(φ2) · Ry(φ1) · v          with  Ry(φ) = [[c, 0, −s], [0, 1, 0], [s, 0, c]],
                                             Rz(φ) = [[c, s, 0], [−s, c, 0], [0, 0, 1]]

(passive rotations: the frame turns by +φ about +y, then about its new +z). The twin applies
this to the Earth rate Ω_e·(cos λ, 0, sin λ) and to the up unit vector (the specific force
sensed at rest, 1 g up) to get the inputs at each position, and makes the torquer output in
rate units

    k·i = ω_axis + DF + Dx·ax + Dy·ay + Dz·az + D₁·a₁² + Dzz·az² + D_xy·ax·ay + noise

with D₁ = Dxx, a₁ = ax for the x axis and D₁ = Dyy, a₁ = ay for the y axis (GyroWheel study, eq. (1)
rearranged). The kinematics are written here from the turntable's geometry, not taken from the
method's eq. (3), so agreement between the two checks both.

An orientation error of the gyro on the table (GyroWheel study, §2.2: small rotations Δψ about its y,
Δθ about its z and Δγ about its x axis, the same at every position) turns the gyro's frame by the
rotation vector (Δγ, Δψ, Δθ); the twin applies it exactly (Rodrigues), v_g′ = Rᵀ·v_g.

This module imports only numpy, rotacal.errors and rotacal.sim.sensors.SimCapture (twin rule).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from rotacal.errors import ConfigError
from rotacal.sim.sensors import SimCapture, register_kind

__all__ = [
    "DEFAULT_LATITUDE_DEG",
    "DEFAULT_POSITIONS_DEG",
    "EARTH_RATE_DEG_H",
    "TABLE1_COEFFICIENTS",
    "simulate_multiposition",
]

#: Sidereal Earth rotation rate, 7.292115·10⁻⁵ rad/s, in °/h.
EARTH_RATE_DEG_H = 15.041067
#: Latitude of the twin's laboratory (°): Harbin, where the GyroWheel study's authors work (the paper gives
#: none).
DEFAULT_LATITUDE_DEG = 45.75

#: Nominal drift coefficients of the GyroWheel study, Table 1 (deg/h, deg/h/g, deg/h/g²). The table's y-axis
#: cross term is printed "D(y)xy"; rotacal names it Dyx as INTERFACE.md does.
TABLE1_COEFFICIENTS: dict[str, dict[str, float]] = {
    "x": {
        "DF": -93.3,
        "Dx": -43.2,
        "Dy": 3.5,
        "Dz": -1.2,
        "Dxx": 2.1,
        "Dzz": -0.089,
        "Dxy": 17.4,
    },
    "y": {
        "DF": 105.3,
        "Dx": 2.2,
        "Dy": -33.2,
        "Dz": -0.1,
        "Dyy": -10.6,
        "Dzz": -10.38,
        "Dyx": 47.8,
    },
}


def _grid(step_deg: float) -> tuple[tuple[float, float], ...]:
    a = np.arange(0.0, 360.0, step_deg)
    return tuple((float(p1), float(p2)) for p1 in a for p2 in a)


#: Default positions (φ1, φ2) in degrees: both axes every 45° (64 positions). Both the 90° grid
#: (ax·ay ≡ 0) and inner angles only at odd multiples of 45° (ax² = ay²) would leave a
#: coefficient unidentifiable; this grid does not.
DEFAULT_POSITIONS_DEG: tuple[tuple[float, float], ...] = _grid(45.0)


def _positions(positions: Any) -> np.ndarray:
    if positions is None:
        return np.asarray(DEFAULT_POSITIONS_DEG, dtype=float)
    try:
        p = np.asarray(positions, dtype=float)
    except (TypeError, ValueError):
        raise ConfigError(
            f"positions must be a sequence of (phi1_deg, phi2_deg) pairs, got {positions!r}."
        ) from None
    if p.ndim != 2 or p.shape[1] != 2 or p.shape[0] < 1:
        raise ConfigError(
            f"positions must be a sequence of (phi1_deg, phi2_deg) pairs, got shape {p.shape}."
        )
    if not np.all(np.isfinite(p)):
        raise ConfigError("positions must be finite angles in degrees.")
    return p


def _coefficients(axis: str, coefficients: Mapping[str, float] | None) -> dict[str, float]:
    base = dict(TABLE1_COEFFICIENTS[axis])
    if coefficients is None:
        return base
    bad = [k for k in coefficients if k not in base]
    if bad:
        raise ConfigError(
            f"unknown drift coefficient {bad[0]!r} for the {axis} axis; known: {', '.join(base)}."
        )
    for k, v in coefficients.items():
        try:
            f = float(v)
        except (TypeError, ValueError):
            raise ConfigError(f"drift coefficient {k} must be a number, got {v!r}.") from None
        if not math.isfinite(f):
            raise ConfigError(f"drift coefficient {k} must be finite, got {v!r}.")
        base[k] = f
    return base


def _orientation(value: Any) -> tuple[float, float, float]:
    if value is None:
        return (0.0, 0.0, 0.0)
    try:
        v = tuple(float(x) for x in value)
    except (TypeError, ValueError):
        raise ConfigError(
            f"orientation_error_arcsec must be three angles (Δψ, Δθ, Δγ) in arcsec, got {value!r}."
        ) from None
    if len(v) != 3 or not all(math.isfinite(x) for x in v):
        raise ConfigError(
            f"orientation_error_arcsec must be three finite angles (Δψ, Δθ, Δγ) in arcsec, got "
            f"{value!r}."
        )
    return v[0], v[1], v[2]


def _misaligned(orient: tuple[float, float, float]) -> np.ndarray:
    """Rᵀ for the frame turned by the rotation vector (Δγ, Δψ, Δθ) (about x, y, z; Rodrigues)."""
    dpsi, dtheta, dgamma = (math.radians(x / 3600.0) for x in orient)
    r = np.array([dgamma, dpsi, dtheta])
    angle = float(np.linalg.norm(r))
    if angle == 0.0:
        return np.eye(3)
    k = r / angle
    kx = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    rot = np.eye(3) + math.sin(angle) * kx + (1.0 - math.cos(angle)) * (kx @ kx)
    return rot.T


def gyro_frame(phi1_deg: np.ndarray, phi2_deg: np.ndarray) -> np.ndarray:
    """Direction cosine matrices C (…, 3, 3) with v_gyro = C·v_NWU at each turntable position."""
    p1 = np.radians(np.asarray(phi1_deg, dtype=float))
    p2 = np.radians(np.asarray(phi2_deg, dtype=float))
    c1, s1, c2, s2 = np.cos(p1), np.sin(p1), np.cos(p2), np.sin(p2)
    zero, one = np.zeros_like(p1), np.ones_like(p1)
    ry = np.stack(
        [
            np.stack([c1, zero, -s1], -1),
            np.stack([zero, one, zero], -1),
            np.stack([s1, zero, c1], -1),
        ],
        -2,
    )
    zero2, one2 = np.zeros_like(p2), np.ones_like(p2)
    rz = np.stack(
        [
            np.stack([c2, s2, zero2], -1),
            np.stack([-s2, c2, zero2], -1),
            np.stack([zero2, zero2, one2], -1),
        ],
        -2,
    )
    return np.asarray(rz @ ry)


def simulate_multiposition(
    *,
    positions: Sequence[tuple[float, float]] | np.ndarray | None = None,
    axis: str = "x",
    latitude_deg: float = DEFAULT_LATITUDE_DEG,
    coefficients: Mapping[str, float] | None = None,
    noise_deg_h: float = 0.005,
    repeats: int = 4,
    orientation_error_arcsec: Sequence[float] | None = None,
    seed: int = 0,
    output_limit_deg_h: float | None = None,
) -> SimCapture:
    """Torquer outputs (in rate units) of one gyro axis at each turntable position.

    Parameters
    ----------
    positions : sequence of (φ1, φ2) or None
        Turntable angles (deg), outer then inner; None gives :data:`DEFAULT_POSITIONS_DEG` (both
        axes every 45°, 64 positions).
    axis : {"x", "y"}
        Which gyro axis's output to simulate.
    latitude_deg : float
        Latitude of the laboratory (deg, −90…90).
    coefficients : mapping or None
        Drift coefficients (deg/h, deg/h/g, deg/h/g²) by name (``DF, Dx, Dy, Dz, Dxx, Dzz, Dxy`` for
        x; ``DF, Dx, Dy, Dz, Dyy, Dzz, Dyx`` for y); missing names take the GyroWheel study's Table 1 values.
    noise_deg_h : float
        White noise of each reading (deg/h rms, ≥ 0). The default 0.005 °/h is the scatter of a
        ~100 s average of a tuned dynamically tuned gyro's rebalance output.
    repeats : int
        Readings per position (≥ 1); the rows run through all positions, then again.
    orientation_error_arcsec : (Δψ, Δθ, Δγ) or None
        Orientation error of the gyro's axes on the table (arcsec): rotations about its y, z and
        x axes (GyroWheel study, §2.2, Fig. 3), the same at every position. None: none.
    seed : int
        Seed of ``numpy.random.default_rng``.
    output_limit_deg_h : float or None
        Range of the torquer output (deg/h, > 0): a reading beyond ±output_limit_deg_h is
        reported as ±output_limit_deg_h (a saturated rebalance loop; the truth's ``sensor`` then
        holds ``output_limit_deg_h`` and ``clipped_samples``). None: unlimited.

    Returns
    -------
    SimCapture
        ``kind="multiposition"``, columns ``phi1_deg``, ``phi2_deg`` (deg) and ``output_deg_h``
        (k·i in deg/h). ``truth`` holds ``drift_coefficients``, ``axis``, ``latitude_deg``,
        ``earth_rate_deg_h``, ``positions_deg``, the noise-free ``clean_output_deg_h`` per position,
        the inputs ``earth_rate_components_deg_h`` and ``gravity_components_g`` per position, and
        the settings.

    References
    ----------
    Seed 001 (GyroWheel calibration and turntable error allocation), §2.1, eqs. (1)–(3) and
    Table 1.
    """
    if axis not in ("x", "y"):
        raise ConfigError(f"axis must be 'x' or 'y', got {axis!r}.")
    try:
        lat = float(latitude_deg)
    except (TypeError, ValueError):
        raise ConfigError(f"latitude_deg must be a number, got {latitude_deg!r}.") from None
    if not math.isfinite(lat) or abs(lat) > 90.0:
        raise ConfigError(f"latitude_deg must be between −90 and 90°, got {latitude_deg!r}.")
    try:
        sigma = float(noise_deg_h)
    except (TypeError, ValueError):
        raise ConfigError(f"noise_deg_h must be a number, got {noise_deg_h!r}.") from None
    if not math.isfinite(sigma) or sigma < 0:
        raise ConfigError(f"noise_deg_h must be ≥ 0 deg/h, got {noise_deg_h!r}.")
    if isinstance(repeats, bool) or not float(repeats).is_integer() or int(repeats) < 1:
        raise ConfigError(f"repeats must be a positive integer, got {repeats!r}.")
    reps = int(repeats)
    pos = _positions(positions)
    coef = _coefficients(axis, coefficients)

    c = gyro_frame(pos[:, 0], pos[:, 1])
    orient = _orientation(orientation_error_arcsec)
    c = _misaligned(orient) @ c
    lam = math.radians(lat)
    earth_nwu = EARTH_RATE_DEG_H * np.array([math.cos(lam), 0.0, math.sin(lam)])
    up_nwu = np.array([0.0, 0.0, 1.0])
    w = c @ earth_nwu  # (n, 3) deg/h in the gyro frame
    a = c @ up_nwu  # (n, 3) g: specific force at rest (1 g up)
    ax, ay, az = a[:, 0], a[:, 1], a[:, 2]
    if axis == "x":
        drift = (
            coef["DF"]
            + coef["Dx"] * ax
            + coef["Dy"] * ay
            + coef["Dz"] * az
            + coef["Dxx"] * ax**2
            + coef["Dzz"] * az**2
            + coef["Dxy"] * ax * ay
        )
        omega = w[:, 0]
    else:
        drift = (
            coef["DF"]
            + coef["Dx"] * ax
            + coef["Dy"] * ay
            + coef["Dz"] * az
            + coef["Dyy"] * ay**2
            + coef["Dzz"] * az**2
            + coef["Dyx"] * ax * ay
        )
        omega = w[:, 1]
    clean = omega + drift
    out = np.tile(clean, reps)
    if sigma > 0:
        out = out + np.random.default_rng(seed).normal(0.0, sigma, out.size)
    sensor: dict[str, Any] = {"noise_deg_h": sigma, "repeats": reps, "seed": int(seed)}
    if output_limit_deg_h is not None:
        lim = float(output_limit_deg_h)
        if not (math.isfinite(lim) and lim > 0):
            raise ConfigError(f"output_limit_deg_h must be > 0 deg/h, got {output_limit_deg_h!r}.")
        sensor.update(output_limit_deg_h=lim, clipped_samples=int(np.count_nonzero(abs(out) > lim)))
        out = np.clip(out, -lim, lim)
    truth: dict[str, Any] = {
        "kind": "multiposition",
        "axis": axis,
        "drift_coefficients": coef,
        "latitude_deg": lat,
        "earth_rate_deg_h": EARTH_RATE_DEG_H,
        "positions_deg": pos,
        "clean_output_deg_h": clean,
        "earth_rate_components_deg_h": w,
        "gravity_components_g": a,
        "orientation_error_arcsec": list(orient),
        "rows": int(out.size),
        "sensor": sensor,
    }
    columns = {
        "phi1_deg": np.tile(pos[:, 0], reps),
        "phi2_deg": np.tile(pos[:, 1], reps),
        "output_deg_h": out,
    }
    return SimCapture("multiposition", columns, truth)


register_kind("multiposition", simulate_multiposition)
