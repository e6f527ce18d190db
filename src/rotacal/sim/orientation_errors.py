"""Digital twin of a turntable's orientation errors measured at many positions (GyroWheel study, §3).

The instrument on the inner axis of the GyroWheel study's two-axis table is turned to each
position (φ1, φ2) and its orientation error is read (an autocollimator on a mirror cube, or a
reference IMU). The twin builds the actual orientation from proper rotations in Table 3's
order, written here independently of :mod:`rotacal.turntable`:

    R_t = Ry(φ1)·Ry(Δφy1)·Rz(Δαz1)·Rx(Δαx1) · Ry(Δεy)·Rx(Δεx) · Rz(φ2)·Ry(Δαy2)·Rz(Δφz2)·Rx(Δαx2)

(active rotations; the intersection error η translates and does not turn), the ideal
R_d = Ry(φ1)·Rz(φ2), ΔR = R_dᵀ·R_t (eq. (23)) and reads Δψ = ΔR[0,2], Δθ = ΔR[1,0],
Δγ = ΔR[2,1] (eq. (24)), plus white noise of the reading.

This module imports only numpy, rotacal.errors and rotacal.sim.sensors (twin rule).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from rotacal.errors import ConfigError
from rotacal.sim.sensors import SimCapture, register_kind

__all__ = ["DEFAULT_TABLE_ERRORS_ARCSEC", "simulate_orientation_errors"]

_ARCSEC = math.pi / (180.0 * 3600.0)

#: The twin's table (arcsec): within the allocation of the GyroWheel study's Table 4 (0.28–0.78
#: arcmin), of both signs, no two alike.
DEFAULT_TABLE_ERRORS_ARCSEC: dict[str, float] = {
    "phi_y1": 9.0,
    "phi_z2": -14.0,
    "alpha_x1": 6.5,
    "alpha_z1": 11.0,
    "alpha_x2": -7.5,
    "alpha_y2": 4.0,
    "eps_x": -10.5,
    "eps_y": 5.5,
    "eta": 0.0,
}


def _rot(axis: int, angle: np.ndarray) -> np.ndarray:
    """Active rotation matrices (…, 3, 3) about x (0), y (1) or z (2)."""
    c, s = np.cos(angle), np.sin(angle)
    m = np.zeros((*np.shape(angle), 3, 3))
    i, j = [(1, 2), (2, 0), (0, 1)][axis]
    m[..., axis, axis] = 1.0
    m[..., i, i] = c
    m[..., j, j] = c
    m[..., i, j] = -s
    m[..., j, i] = s
    return m


def _errors(values: Mapping[str, float] | None) -> dict[str, float]:
    out = dict(DEFAULT_TABLE_ERRORS_ARCSEC)
    for name, v in (values or {}).items():
        if name not in out:
            raise ConfigError(f"unknown table error {name!r}; known: {', '.join(out)}.")
        try:
            f = float(v)
        except (TypeError, ValueError):
            raise ConfigError(f"table error {name} must be a number (arcsec), got {v!r}.") from None
        if not math.isfinite(f) or (name != "eta" and abs(f) > 3600.0):
            raise ConfigError(
                f"table error {name} must be finite and within ±3600 arcsec, got {v!r}."
            )
        out[name] = f
    return out


def _positions(
    positions: Sequence[tuple[float, float]] | np.ndarray | None, outer_steps: int, inner_steps: int
) -> np.ndarray:
    if positions is not None:
        p = np.asarray(positions, dtype=float)
        if p.ndim != 2 or p.shape[1] != 2 or p.shape[0] < 1 or not np.all(np.isfinite(p)):
            raise ConfigError("positions must be finite (phi1_deg, phi2_deg) pairs.")
        return p
    for name, v in (("outer_steps", outer_steps), ("inner_steps", inner_steps)):
        if isinstance(v, bool) or not float(v).is_integer() or not 1 <= int(v) <= 360:
            raise ConfigError(f"{name} must be an integer from 1 to 360, got {v!r}.")
    a1 = np.arange(int(outer_steps)) * 360.0 / int(outer_steps)
    a2 = np.arange(int(inner_steps)) * 360.0 / int(inner_steps)
    return np.stack(np.meshgrid(a1, a2, indexing="ij"), axis=-1).reshape(-1, 2)


def simulate_orientation_errors(
    *,
    errors_arcsec: Mapping[str, float] | None = None,
    positions: Sequence[tuple[float, float]] | np.ndarray | None = None,
    outer_steps: int = 8,
    inner_steps: int = 8,
    noise_arcsec: float = 0.5,
    seed: int = 0,
) -> SimCapture:
    """Orientation errors of the GyroWheel study's two-axis table at each position.

    Parameters
    ----------
    errors_arcsec : mapping, optional
        The table's errors (arcsec; ``eta`` in mm, no effect): names of Table 2 as
        :func:`rotacal.turntable.orientation_error` takes them; missing names take
        :data:`DEFAULT_TABLE_ERRORS_ARCSEC`.
    positions : sequence of (φ1, φ2), optional
        Positions (deg); default a grid of ``outer_steps`` × ``inner_steps`` from 0°.
    outer_steps, inner_steps : int
        Grid steps per turn of each axis (1 fixes that axis at 0°).
    noise_arcsec : float
        White noise of each reading (arcsec rms, ≥ 0; an autocollimator reads to ~0.1–0.5″).
    seed : int
        Seed of ``numpy.random.default_rng``.

    Returns
    -------
    SimCapture
        ``kind="orientation"``, columns ``phi1_deg``, ``phi2_deg``, ``dpsi_arcsec``,
        ``dtheta_arcsec``, ``dgamma_arcsec``; ``truth`` holds ``errors_arcsec``, the noise-free
        readings ``clean_arcsec`` and the settings.

    References
    ----------
    Seed 001, §3.2, eqs. (17)–(24), Table 3.
    """
    e = _errors(errors_arcsec)
    pos = _positions(positions, outer_steps, inner_steps)
    try:
        sigma = float(noise_arcsec)
    except (TypeError, ValueError):
        raise ConfigError(f"noise_arcsec must be a number, got {noise_arcsec!r}.") from None
    if not math.isfinite(sigma) or sigma < 0:
        raise ConfigError(f"noise_arcsec must be ≥ 0 arcsec, got {noise_arcsec!r}.")
    p1, p2 = np.radians(pos[:, 0]), np.radians(pos[:, 1])
    r = {k: np.full(p1.shape, v * _ARCSEC) for k, v in e.items()}
    x, y, z = 0, 1, 2
    actual = (
        _rot(y, p1)
        @ _rot(y, r["phi_y1"])
        @ _rot(z, r["alpha_z1"])
        @ _rot(x, r["alpha_x1"])
        @ _rot(y, r["eps_y"])
        @ _rot(x, r["eps_x"])
        @ _rot(z, p2)
        @ _rot(y, r["alpha_y2"])
        @ _rot(z, r["phi_z2"])
        @ _rot(x, r["alpha_x2"])
    )
    ideal = _rot(y, p1) @ _rot(z, p2)
    dr = np.swapaxes(ideal, -1, -2) @ actual
    clean = np.stack([dr[:, 0, 2], dr[:, 1, 0], dr[:, 2, 1]], axis=-1) / _ARCSEC
    noisy = clean + np.random.default_rng(seed).normal(0.0, sigma, clean.shape)
    truth: dict[str, Any] = {
        "kind": "orientation",
        "errors_arcsec": e,
        "positions_deg": pos.tolist(),
        "clean_arcsec": clean.tolist(),
        "sensor": {"noise_arcsec": sigma, "seed": int(seed)},
    }
    columns = {
        "phi1_deg": pos[:, 0].copy(),
        "phi2_deg": pos[:, 1].copy(),
        "dpsi_arcsec": noisy[:, 0],
        "dtheta_arcsec": noisy[:, 1],
        "dgamma_arcsec": noisy[:, 2],
    }
    return SimCapture("orientation", columns, truth)


register_kind("orientation", simulate_orientation_errors)
