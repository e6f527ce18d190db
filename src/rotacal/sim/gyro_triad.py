"""Twins of a 3-axis gyro test: rotations at set rates (robot-manipulator study 2023) and rotations through known angles.

A gyro triad with true scale/misalignment matrix K (output unit per °/s) and bias b (output unit)
gives ``u = K·ω + b + n`` for the angular rate ω (°/s) in its nominal axes, with white Gaussian
noise n. The truth (K, b, which rows carry gross errors, the sections of a rotation recording)
is set here, not estimated, so it stays independent of rotacal's methods.

- :func:`simulate_gyro_triad` — the rate-table test of the robot-manipulator study (2023): constant rates about each axis
  in both directions (Table 2: 6, 18, 30, 60, 90 °/s), several samples per rate point, optional
  gross outliers, output clipping (saturation) and quantisation. Kind ``"gyro-triad"``.
- :func:`simulate_gyro_rotations` — a Ferraris-style recording: rest, a rotation through a known
  angle about x, rest, about y, rest, about z, rest. The rate profile of each rotation is
  ``(2φ/T)·sin²(πt/T)``, whose samples sum to exactly φ·fs (Σ sin²(πk/N) = N/2), so the set angle
  is also the sampled angle. Kind ``"gyro-rotations"``.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from rotacal.errors import ConfigError
from rotacal.sim.motion import _finite, _nonneg
from rotacal.sim.sensors import SimCapture, register_kind

__all__ = [
    "DEFAULT_BIAS",
    "DEFAULT_K",
    "simulate_gyro_rotations",
    "simulate_gyro_triad",
]

#: A plausible MEMS triad: scale errors of a few 10⁻³, misalignments of a few mrad.
DEFAULT_K = (
    (1.0050, 0.0030, -0.0020),
    (-0.0040, 0.9970, 0.0015),
    (0.0025, -0.0010, 1.0020),
)
#: Biases (output unit, here °/s).
DEFAULT_BIAS = (0.5, -0.3, 0.2)
_AXES = "xyz"
_RATE_COLUMNS = ("wx_deg_s", "wy_deg_s", "wz_deg_s")
_OUT_COLUMNS = ("ux", "uy", "uz")
_MAX_ROWS = 50_000_000


def _matrix(k: Any) -> np.ndarray:
    m = np.asarray(DEFAULT_K if k is None else k, dtype=float)
    if m.shape != (3, 3) or not np.isfinite(m).all():
        raise ConfigError(
            f"K must be a finite 3×3 matrix (output unit per °/s), got one of shape {m.shape}."
        )
    if not abs(np.linalg.det(m)) > 1e-12 * np.abs(m).max() ** 3:
        raise ConfigError(
            "K must be invertible: a gyro triad with a singular K cannot be calibrated."
        )
    return m


def _bias(b: Any) -> np.ndarray:
    v = np.asarray(DEFAULT_BIAS if b is None else b, dtype=float)
    if v.shape != (3,) or not np.isfinite(v).all():
        raise ConfigError(f"bias must be 3 finite numbers (output unit), got {b!r}.")
    return v


def _positive_int(name: str, value: Any) -> int:
    if isinstance(value, bool) or not float(value).is_integer() or int(value) < 1:
        raise ConfigError(f"{name} must be a positive integer, got {value!r}.")
    return int(value)


def _finish_outputs(
    u: np.ndarray, output_limit: float | None, quantum: float | None
) -> tuple[np.ndarray, int]:
    clipped = 0
    if output_limit is not None:
        lim = _finite("output_limit", output_limit)
        if lim <= 0:
            raise ConfigError(f"output_limit must be > 0 (output unit), got {output_limit!r}.")
        clipped = int(np.count_nonzero(np.abs(u) > lim))
        np.clip(u, -lim, lim, out=u)
    if quantum is not None:
        q = _finite("quantum", quantum)
        if q <= 0:
            raise ConfigError(f"quantum must be > 0 (output unit), got {quantum!r}.")
        u[...] = q * np.round(u / q)
    return u, clipped


# ------------------------------------------------------------------------------- the robot-manipulator study (2023) test
def simulate_gyro_triad(
    *,
    rates_deg_s: tuple[float, ...] = (6.0, 18.0, 30.0, 60.0, 90.0),
    K: Any = None,
    bias: Any = None,
    noise_std: float = 0.1,
    samples_per_point: int = 500,
    outlier_fraction: float = 0.0,
    outlier_size: float = 20.0,
    outlier_channels: str = "one",
    include_static: bool = False,
    output_limit: float | None = None,
    quantum: float | None = None,
    fs_hz: float = 100.0,
    rate_relative_error: float = 0.0,
    seed: int = 0,
) -> SimCapture:
    """A 3-axis gyro test on a rate table: set rates about each axis, both directions (robot-manipulator study 2023).

    The table turns the DUT about x at +r₁, −r₁, +r₂, …, then about y, then about z (robot-manipulator study 2023,
    Table 2 and Fig. 5); each rate point is held for ``samples_per_point`` samples at ``fs_hz``
    (the transitions between points are not recorded). The outputs are
    ``u = K·ω + b + n``, n white Gaussian with σ = ``noise_std`` per channel. A fraction
    ``outlier_fraction`` of the rows, drawn at random, get a gross error of magnitude
    uniform in [½, 1]·``outlier_size`` with a random sign in one random channel (``"one"``) or
    in all three (``"all"``).

    Parameters
    ----------
    rates_deg_s : tuple of float
        Rate magnitudes (°/s).
    K : array_like (3, 3) or None
        True scale/misalignment matrix (output unit per °/s); None: :data:`DEFAULT_K`.
    bias : array_like (3,) or None
        True bias (output unit); None: :data:`DEFAULT_BIAS`.
    noise_std : float
        White noise per sample and channel (output unit, rms).
    samples_per_point : int
        Samples recorded at each rate point.
    outlier_fraction : float
        Fraction of rows with a gross error, 0 ≤ f < 0.5.
    outlier_size : float
        Largest gross error (output unit).
    outlier_channels : {"one", "all"}
        Channels a gross error hits.
    include_static : bool
        Record a point at rest first.
    output_limit : float or None
        Clip the outputs to ±output_limit (output unit): a saturating gyro.
    quantum : float or None
        Round the outputs to multiples of this step (output unit): an ADC or a digital output.
    fs_hz : float
        Sampling rate for ``time_s`` (Hz).
    rate_relative_error : float
        Relative error ε of the table's rates (dimensionless, > −1): the DUT turns at ω·(1 + ε)
        while the capture records the set rates ω (the effect behind ``table.set_rate_relative``).
    seed : int
        Seed of ``numpy.random.default_rng``.

    Returns
    -------
    SimCapture
        Kind ``"gyro-triad"``; columns ``time_s`` (s), ``wx_deg_s``, ``wy_deg_s``, ``wz_deg_s``
        (°/s), ``ux``, ``uy``, ``uz`` (output unit). Truth: ``scale_misalignment``, ``bias``,
        ``outliers`` (``rows`` and ``columns`` of each corrupted measurement, ``row_set``: the
        distinct rows), the settings, and ``clipped_samples``.

    References
    ----------
    Calibration Method of MEMS Gyroscopes Using a Robot Manipulator, IEEE A&E Systems Magazine,
    March 2023, Table 2, Fig. 5 (the test sequence).
    """
    rates = np.asarray(rates_deg_s, dtype=float).ravel()
    if rates.size == 0 or not np.isfinite(rates).all() or np.any(rates <= 0):
        raise ConfigError(
            f"rates_deg_s must be positive rate magnitudes (°/s), got {rates_deg_s!r}."
        )
    k = _matrix(K)
    b = _bias(bias)
    sigma = _nonneg("noise_std", noise_std)
    spp = _positive_int("samples_per_point", samples_per_point)
    frac = _finite("outlier_fraction", outlier_fraction)
    if not 0.0 <= frac < 0.5:
        raise ConfigError(f"outlier_fraction must lie in [0, 0.5), got {outlier_fraction!r}.")
    size = _nonneg("outlier_size", outlier_size)
    if outlier_channels not in ("one", "all"):
        raise ConfigError(f"outlier_channels must be 'one' or 'all', got {outlier_channels!r}.")
    fs = _finite("fs_hz", fs_hz)
    if fs <= 0:
        raise ConfigError(f"fs_hz must be > 0 Hz, got {fs_hz!r}.")
    eps = _finite("rate_relative_error", rate_relative_error)
    if eps <= -1.0:
        raise ConfigError(f"rate_relative_error must be > −1, got {rate_relative_error!r}.")

    mags = np.ravel(np.column_stack([rates, -rates]))  # +r1, −r1, +r2, −r2, …
    pts = np.zeros((3 * mags.size, 3))
    for j in range(3):
        pts[j * mags.size : (j + 1) * mags.size, j] = mags
    if include_static:
        pts = np.vstack([np.zeros((1, 3)), pts])
    n = pts.shape[0] * spp
    if n > _MAX_ROWS:
        raise ConfigError(f"{n} rows is more than the twin makes at once ({_MAX_ROWS}).")
    omega = np.repeat(pts, spp, axis=0)
    rng = np.random.default_rng(seed)
    u = (omega * (1.0 + eps)) @ k.T + b
    if sigma > 0:
        u += rng.normal(0.0, sigma, u.shape)
    n_out = round(frac * n)
    rows = np.sort(rng.choice(n, size=n_out, replace=False)) if n_out else np.zeros(0, int)
    if outlier_channels == "one":
        o_rows = rows
        o_cols = rng.integers(0, 3, rows.size)
    else:
        o_rows = np.repeat(rows, 3)
        o_cols = np.tile(np.arange(3), rows.size)
    err = rng.choice([-1.0, 1.0], o_rows.size) * size * rng.uniform(0.5, 1.0, o_rows.size)
    u[o_rows, o_cols] += err
    u, clipped = _finish_outputs(u, output_limit, quantum)
    t = np.arange(n) / fs
    columns = {"time_s": t}
    columns.update({name: omega[:, j].copy() for j, name in enumerate(_RATE_COLUMNS)})
    columns.update({name: u[:, j].copy() for j, name in enumerate(_OUT_COLUMNS)})
    truth = {
        "kind": "gyro-triad",
        "scale_misalignment": k.tolist(),
        "bias": b.tolist(),
        "rows": n,
        "points": int(pts.shape[0]),
        "outliers": {
            "rows": o_rows.tolist(),
            "columns": [_OUT_COLUMNS[c] for c in o_cols],
            "errors": err.tolist(),
            "row_set": rows.tolist(),
        },
        "clipped_samples": clipped,
        "sensor": {
            "rates_deg_s": rates.tolist(),
            "noise_std": sigma,
            "samples_per_point": spp,
            "outlier_fraction": frac,
            "outlier_size": size,
            "outlier_channels": outlier_channels,
            "include_static": bool(include_static),
            "output_limit": None if output_limit is None else float(output_limit),
            "quantum": None if quantum is None else float(quantum),
            "fs_hz": fs,
            "rate_relative_error": eps,
            "seed": int(seed),
        },
    }
    return SimCapture("gyro-triad", columns, truth)


# ------------------------------------------------------------------------------- Ferraris rotations
def simulate_gyro_rotations(
    *,
    K: Any = None,
    bias: Any = None,
    angle_deg: float = -360.0,
    rotation_s: float = 4.0,
    static_s: float = 5.0,
    margin_s: float = 0.5,
    noise_std: float = 0.05,
    output_limit: float | None = None,
    quantum: float | None = None,
    fs_hz: float = 100.0,
    angle_error_deg: Any = 0.0,
    seed: int = 0,
) -> SimCapture:
    """A Ferraris-style rotation recording: rest, rotate about x, rest, about y, rest, about z, rest.

    Each rotation turns the DUT through ``angle_deg`` (right-hand rule about the DUT's axis) in
    ``rotation_s`` with the rate profile ``(2φ/T)·sin²(πt/T)`` (peak 2φ/T); its samples sum to
    φ·fs exactly. The outputs are ``u = K·ω + b + n`` with white Gaussian noise.

    Parameters
    ----------
    K, bias : array_like or None
        True scale/misalignment matrix (output unit per °/s) and bias (output unit); None: the
        defaults of :func:`simulate_gyro_triad`.
    angle_deg : float
        Rotation angle (deg, right-hand rule about the axis), non-zero. Default −360: one
        clockwise turn seen from the tip of the +axis, as the Ferraris protocol does it (imucal's
        ``expected_angle=-360``) and as ``calibrate_triad_rotations`` assumes by default.
    rotation_s : float
        Duration of each rotation (s).
    static_s : float
        Duration of each rest between rotations, and before the first and after the last (s).
    margin_s : float
        The truth's rotation sections start this long before the motion and end this long after
        it (s), as a person marking the sections would; less than ``static_s / 2``.
    noise_std : float
        White noise per sample and channel (output unit, rms).
    output_limit, quantum : float or None
        Clipping and quantisation of the outputs (output unit), as in :func:`simulate_gyro_triad`.
    fs_hz : float
        Sampling rate (Hz).
    angle_error_deg : float or sequence of 3 float
        Error of each realised angle (deg; one for all rotations or one each about x, y, z): the
        DUT turns through ``angle_deg + error`` while the set angle stays ``angle_deg`` (the
        effect behind ``table.set_angle_arcsec``; draw it per run to check a budget).
    seed : int
        Seed of ``numpy.random.default_rng``.

    Returns
    -------
    SimCapture
        Kind ``"gyro-rotations"``; columns ``time_s`` (s), ``ux``, ``uy``, ``uz`` (output unit).
        Truth: ``scale_misalignment``, ``bias``, ``angle_deg`` (set), ``angle_realised_deg`` (one
        per rotation), ``rotations`` ({"x": [start, stop],
        …}: half-open sample ranges including the margins), ``motion`` (the exact sample ranges
        of the motion), ``static`` (the rests minus the margins), the settings.

    References
    ----------
    Ferraris F., Grimaldi U., Parvis M. (1995), Sensors and Materials 7(5):311–330 (the recording:
    static positions and rotations through a known angle about each axis).
    """
    k = _matrix(K)
    b = _bias(bias)
    ang = _finite("angle_deg", angle_deg)
    if ang == 0:
        raise ConfigError("angle_deg must be non-zero.")
    fs = _finite("fs_hz", fs_hz)
    if fs <= 0:
        raise ConfigError(f"fs_hz must be > 0 Hz, got {fs_hz!r}.")
    n_rot = round(_finite("rotation_s", rotation_s) * fs)
    n_rest = round(_finite("static_s", static_s) * fs)
    n_margin = round(_nonneg("margin_s", margin_s) * fs)
    if n_rot < 4:
        raise ConfigError(f"rotation_s={rotation_s!r} s gives fewer than 4 samples at {fs:g} Hz.")
    if n_rest < 4 or 2 * n_margin >= n_rest:
        raise ConfigError(
            f"static_s={static_s!r} s must give at least 4 samples and exceed 2·margin_s "
            f"(margin_s={margin_s!r} s)."
        )
    sigma = _nonneg("noise_std", noise_std)
    try:
        errs = np.broadcast_to(np.asarray(angle_error_deg, dtype=float), (3,)).copy()
    except (TypeError, ValueError):
        raise ConfigError(
            f"angle_error_deg must be one number or three (deg), got {angle_error_deg!r}."
        ) from None
    if not np.isfinite(errs).all():
        raise ConfigError(f"angle_error_deg must be finite (deg), got {angle_error_deg!r}.")
    realised = ang + errs
    n = 4 * n_rest + 3 * n_rot
    if n > _MAX_ROWS:
        raise ConfigError(f"{n} samples is more than the twin makes at once ({_MAX_ROWS}).")
    omega = np.zeros((n, 3))
    kk = np.arange(n_rot)
    shape = (2.0 * fs / n_rot) * np.sin(np.pi * kk / n_rot) ** 2  # per deg of angle; Σ = fs
    motion: dict[str, list[int]] = {}
    rotations: dict[str, list[int]] = {}
    static: list[list[int]] = []
    pos = 0
    for j, a in enumerate(_AXES):
        static.append([pos + (n_margin if j else 0), pos + n_rest - n_margin])
        pos += n_rest
        omega[pos : pos + n_rot, j] = realised[j] * shape  # °/s; Σ = realised angle · fs
        motion[a] = [pos, pos + n_rot]
        rotations[a] = [pos - n_margin, pos + n_rot + n_margin]
        pos += n_rot
    static.append([pos + n_margin, pos + n_rest])
    rng = np.random.default_rng(seed)
    u = omega @ k.T + b
    if sigma > 0:
        u += rng.normal(0.0, sigma, u.shape)
    u, clipped = _finish_outputs(u, output_limit, quantum)
    columns = {"time_s": np.arange(n) / fs}
    columns.update({name: u[:, j].copy() for j, name in enumerate(_OUT_COLUMNS)})
    truth = {
        "kind": "gyro-rotations",
        "scale_misalignment": k.tolist(),
        "bias": b.tolist(),
        "angle_deg": ang,
        "angle_realised_deg": realised.tolist(),
        "peak_rate_deg_s": 2.0 * abs(ang) * fs / n_rot,
        "rotations": rotations,
        "motion": motion,
        "static": static,
        "samples": n,
        "clipped_samples": clipped,
        "sensor": {
            "rotation_s": n_rot / fs,
            "static_s": n_rest / fs,
            "margin_s": n_margin / fs,
            "noise_std": sigma,
            "output_limit": None if output_limit is None else float(output_limit),
            "quantum": None if quantum is None else float(quantum),
            "fs_hz": fs,
            "seed": int(seed),
        },
    }
    return SimCapture("gyro-rotations", columns, truth)


register_kind("gyro-triad", simulate_gyro_triad)
register_kind("gyro-rotations", simulate_gyro_rotations)
