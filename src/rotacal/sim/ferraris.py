"""Twin of a Ferraris calibration session: a 6-DOF IMU (gyro and accelerometer triads) resting in
six positions and turned through a known angle about each axis, on the rotating Earth.

The DUT's attitude is a rotation matrix C (columns: its axes in local East-North-Up). At rest in
position j_p (axis j up) or j_a (axis j down) the other axes point at a stated heading; each
rotation about axis j starts from position j_p and turns through the set angle with the rate
profile ``(2φ/T)·sin²(πt/T)``. The sensors see, in the DUT's axes, the specific force
f = Cᵀ·(0, 0, g) (m/s², up at rest) and the angular rate ω = θ̇·e_j + Cᵀ·Ω_E·(0, cos L, sin L)
(°/s, L the latitude, Ω_E the sidereal rate) and give::

    gyro:          u_g = K·ω + b + K_ga·f + n_g          (output unit)
    accelerometer: u_a = M_a·f + b_a + n_a               (M_a = K_a·R_a; output unit)

with white Gaussian noise, then optional clipping and quantisation. The truth (every matrix, the
headings, the sections in imucal's names) is set here, not estimated. Kind ``"ferraris"``.

References
----------
Ferraris F., Grimaldi U., Parvis M. (1995), Sensors and Materials 7(5):311–330 (the session);
Titterton D. H., Weston J. L. (2004), Strapdown Inertial Navigation Technology, 2nd ed., §3.4
(the Earth rate and gravity in local-level axes).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from rotacal.errors import ConfigError
from rotacal.sim.gyro_triad import _bias, _finish_outputs, _matrix
from rotacal.sim.motion import _finite, _nonneg
from rotacal.sim.sensors import SimCapture, register_kind

__all__ = ["simulate_ferraris"]

#: Sidereal rotation rate of the Earth (°/s): 7.2921150·10⁻⁵ rad/s.
EARTH_RATE_DEG_S = math.degrees(7.2921150e-5)
_AXES = "xyz"
_POSITIONS = ("x_p", "x_a", "y_p", "y_a", "z_p", "z_a")
DEFAULT_G_SENSITIVITY = (
    (4.0e-4, -4.5e-4, -3.0e-5),
    (4.3e-4, 4.9e-4, 6.2e-4),
    (1.0e-4, -9.0e-5, 2.4e-4),
)
DEFAULT_ACC_MATRIX = (
    (0.9967, -0.0148, -0.0075),
    (0.0086, 1.0024, 0.0018),
    (0.0136, 0.0021, 1.0233),
)
DEFAULT_ACC_BIAS = (0.54, -0.62, 0.40)


def _attitude(axis: int, up: float, heading_deg: float) -> np.ndarray:
    """C (DUT axes → ENU): axis ``axis`` along ``up``·Up, the next axis (cyclically) horizontal
    at the heading (deg from North towards East), the third completing a right-handed set."""
    h = math.radians(heading_deg)
    c = np.zeros((3, 3))
    c[:, axis] = (0.0, 0.0, up)
    c[:, (axis + 1) % 3] = (math.sin(h), math.cos(h), 0.0)
    c[:, (axis + 2) % 3] = np.cross(c[:, axis], c[:, (axis + 1) % 3])
    return c


def _about(axis: int, theta_deg: np.ndarray) -> np.ndarray:
    """Active rotations about a DUT axis by θ (deg): (n, 3, 3)."""
    t = np.radians(theta_deg)
    c, s = np.cos(t), np.sin(t)
    r = np.zeros((t.size, 3, 3))
    i, j, k = axis, (axis + 1) % 3, (axis + 2) % 3
    r[:, i, i] = 1.0
    r[:, j, j] = c
    r[:, k, k] = c
    r[:, k, j] = s
    r[:, j, k] = -s
    return r


def simulate_ferraris(
    *,
    K: Any = None,
    bias: Any = None,
    g_sensitivity: Any = None,
    acc_matrix: Any = None,
    acc_bias: Any = None,
    latitude_deg: float = 49.6,
    heading_deg: float = 30.0,
    gravity_m_s2: float | None = None,
    earth_rate: bool = True,
    angle_deg: float = -360.0,
    rotation_s: float = 4.0,
    static_s: float = 5.0,
    margin_s: float = 0.5,
    noise_std: float = 0.05,
    acc_noise_std: float = 0.01,
    quantum: float | None = None,
    acc_quantum: float | None = None,
    output_limit: float | None = None,
    acc_output_limit: float | None = None,
    fs_hz: float = 100.0,
    seed: int = 0,
) -> SimCapture:
    """A Ferraris session: six static positions (x_p, x_a, y_p, y_a, z_p, z_a), then a rotation
    about x, y and z, each from its axis-up position.

    Parameters
    ----------
    K, bias : array_like or None
        Gyro scale/misalignment (output unit per °/s) and bias (output unit); None: the defaults
        of :mod:`rotacal.sim.gyro_triad`.
    g_sensitivity : array_like (3, 3) or None
        K_ga (gyro output unit per m/s² of specific force).
    acc_matrix, acc_bias : array_like or None
        M_a = K_a·R_a (accelerometer output unit per m/s²) and b_a (output unit).
    latitude_deg : float
        Latitude of the session (deg).
    heading_deg : float
        Heading of the first horizontal axis in the first position (deg from North); position p
        adds 47°·p (the DUT is set down at a different heading each time, as by hand).
    gravity_m_s2 : float or None
        Local gravity g (m/s²); None: the WGS 84 normal gravity at the latitude, height 0
        (Somigliana's closed form, NIMA TR8350.2 eq. 4-1), as a laboratory there measures it.
    earth_rate : bool
        Include the Earth's rotation in ω (False: a non-rotating Earth).
    angle_deg, rotation_s, static_s, margin_s, fs_hz
        As in :func:`~rotacal.sim.gyro_triad.simulate_gyro_rotations`; each rotation block is
        ``static_s`` of rest in the axis-up position, the turn, ``static_s`` of rest.
    noise_std, acc_noise_std : float
        White noise per sample of the gyro and accelerometer outputs (output units, rms).
    quantum, acc_quantum, output_limit, acc_output_limit : float or None
        Quantisation and clipping of the gyro and accelerometer outputs (output units).
    seed : int
        Seed of ``numpy.random.default_rng``.

    Returns
    -------
    SimCapture
        Kind ``"ferraris"``; columns ``time_s``, ``ux``, ``uy``, ``uz`` (gyro), ``ax``, ``ay``,
        ``az`` (accelerometer). Truth: the matrices and biases, ``latitude_deg``,
        ``gravity_m_s2``, ``headings_deg``, ``angle_deg``, ``sections`` (imucal's names → [start,
        stop), the statics without the margins, the rotations with them).
    """
    k = _matrix(K)
    b = _bias(bias)
    kga = np.asarray(DEFAULT_G_SENSITIVITY if g_sensitivity is None else g_sensitivity, float)
    ma = _matrix(DEFAULT_ACC_MATRIX if acc_matrix is None else acc_matrix)
    ba = np.asarray(DEFAULT_ACC_BIAS if acc_bias is None else acc_bias, dtype=float)
    if kga.shape != (3, 3) or ba.shape != (3,) or not np.isfinite(kga).all():
        raise ConfigError("g_sensitivity must be a finite 3×3 matrix and acc_bias 3 numbers.")
    lat = _finite("latitude_deg", latitude_deg)
    if abs(lat) > 90:
        raise ConfigError(f"latitude_deg must lie in −90…90, got {latitude_deg!r}.")
    if gravity_m_s2 is None:
        s2 = math.sin(math.radians(lat)) ** 2
        g = 9.7803253359 * (1 + 0.00193185265241 * s2) / math.sqrt(1 - 0.00669437999013 * s2)
    else:
        g = _finite("gravity_m_s2", gravity_m_s2)
    ang = _finite("angle_deg", angle_deg)
    fs = _finite("fs_hz", fs_hz)
    if fs <= 0 or ang == 0:
        raise ConfigError("fs_hz must be > 0 and angle_deg non-zero.")
    n_rot = round(_finite("rotation_s", rotation_s) * fs)
    n_rest = round(_finite("static_s", static_s) * fs)
    n_margin = round(_nonneg("margin_s", margin_s) * fs)
    if n_rot < 4 or n_rest < 4 or 2 * n_margin >= n_rest:
        raise ConfigError("rotation_s and static_s must give ≥ 4 samples, static_s > 2·margin_s.")
    omega_n = EARTH_RATE_DEG_S * np.array(
        [0.0, math.cos(math.radians(lat)), math.sin(math.radians(lat))]
    )
    if not earth_rate:
        omega_n[:] = 0.0
    att: list[np.ndarray] = []  # C per sample
    rate: list[np.ndarray] = []  # θ̇·e_j per sample (°/s)
    sections: dict[str, list[int]] = {}
    headings = []
    pos = 0
    for p, name in enumerate(_POSITIONS):
        hd = float(heading_deg) + 47.0 * p
        headings.append(hd)
        c = _attitude(_AXES.index(name[0]), 1.0 if name[2] == "p" else -1.0, hd)
        att.append(np.broadcast_to(c, (n_rest, 3, 3)))
        rate.append(np.zeros((n_rest, 3)))
        sections[name] = [pos + n_margin, pos + n_rest - n_margin]
        pos += n_rest
    shape = (2.0 * fs / n_rot) * np.sin(np.pi * np.arange(n_rot) / n_rot) ** 2  # Σ = fs
    for j, a in enumerate(_AXES):
        c0 = att[_POSITIONS.index(f"{a}_p")][0]
        w = np.zeros(2 * n_rest + n_rot)
        w[n_rest : n_rest + n_rot] = ang * shape
        theta = np.concatenate(([0.0], np.cumsum(0.5 * (w[1:] + w[:-1])) / fs))
        theta *= ang / theta[-1]  # the turn ends exactly at the set angle
        att.append(c0 @ _about(j, theta))
        r = np.zeros((w.size, 3))
        r[:, j] = w
        rate.append(r)
        sections[f"{a}_rot"] = [pos + n_rest - n_margin, pos + n_rest + n_rot + n_margin]
        pos += w.size
    cmat = np.concatenate(att)
    # DUT axes ← ENU is Cᵀ: f = Cᵀ·(0, 0, g), ω = θ̇·e_j + Cᵀ·Ω_n
    f = g * cmat[:, 2, :]
    omega = np.concatenate(rate) + np.einsum("nij,i->nj", cmat, omega_n)
    rng = np.random.default_rng(seed)
    ug = omega @ k.T + b + f @ kga.T + rng.normal(0.0, _nonneg("noise_std", noise_std), f.shape)
    ua = f @ ma.T + ba + rng.normal(0.0, _nonneg("acc_noise_std", acc_noise_std), f.shape)
    ug, clipped_g = _finish_outputs(ug, output_limit, quantum)
    ua, clipped_a = _finish_outputs(ua, acc_output_limit, acc_quantum)
    columns = {"time_s": np.arange(ug.shape[0]) / fs}
    columns.update({n: ug[:, i].copy() for i, n in enumerate(("ux", "uy", "uz"))})
    columns.update({n: ua[:, i].copy() for i, n in enumerate(("ax", "ay", "az"))})
    truth = {
        "kind": "ferraris",
        "scale_misalignment": k.tolist(),
        "bias": b.tolist(),
        "g_sensitivity": kga.tolist(),
        "acc_scale_misalignment": ma.tolist(),
        "acc_bias": ba.tolist(),
        "latitude_deg": lat,
        "gravity_m_s2": g,
        "earth_rate": bool(earth_rate),
        "headings_deg": headings,
        "angle_deg": ang,
        "sections": sections,
        "samples": int(ug.shape[0]),
        "clipped_samples": clipped_g + clipped_a,
        "sensor": {
            "noise_std": float(noise_std),
            "acc_noise_std": float(acc_noise_std),
            "quantum": quantum,
            "acc_quantum": acc_quantum,
            "output_limit": output_limit,
            "acc_output_limit": acc_output_limit,
            "fs_hz": fs,
            "seed": int(seed),
        },
    }
    return SimCapture("ferraris", columns, truth)


register_kind("ferraris", simulate_ferraris)
