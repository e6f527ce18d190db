"""Digital twin of an indexing table's position test against a reference: "position".

The table stops at P target positions θ_i = i·360°/P in R runs, approaching each in the positive
sense and (``bidirectional``) again in the negative sense. Its true positional deviation there is

    e(θ) ± B/2 + n,   e(θ) = Σ_h c_h cos(hθ − φ_h)  (arcsec),

a few harmonics (``harmonics``: (order, amplitude c_h in arcsec, phase φ_h in deg)), half the
reversal value B added on the positive approach and subtracted on the negative one, and white
Gaussian noise n of ``noise_arcsec`` per stop (the table's non-repeatability). The reference reads
it in one of three ways (``reference``):

* ``"encoder"`` — column ``reference_deg``: a reference encoder reads θ_true − g(θ_true)/3600, g
  its graduation error (``graduation``: harmonics as above, none by default). The truth holds g at
  ``graduation_lines`` lines as a ``selfcal`` mapping (``deviation_arcsec``), i.e. what a perfect
  self-calibration of that encoder gives;
* ``"polygon"`` — column ``error_arcsec``: an autocollimator on a ``polygon_faces``-face polygon
  reads e − f_j + z_r, f_j the error of face j = (i + r·s) mod P in front of it (the polygon
  turned by s = ``polygon_step_faces`` faces per run; zero-sum, drawn with rms
  ``face_error_arcsec``) and z_r the autocollimator's zero in run r (``zero_arcsec`` rms); the
  ``face`` column says which face;
* ``"deviation"`` — column ``error_arcsec``: the deviation itself.

Columns ``position_deg``, ``run``, ``direction`` (+1/−1) and the reference's. This module imports
only numpy, rotacal.errors and rotacal.sim (twin rule).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from rotacal.errors import ConfigError
from rotacal.sim.motion import _finite
from rotacal.sim.sensors import SimCapture, register_kind

__all__ = ["DEFAULT_TABLE_HARMONICS", "harmonic_curve_arcsec", "simulate_position"]

#: The default table error: eccentricity, ellipticity, and two smaller orders (arcsec, deg).
DEFAULT_TABLE_HARMONICS: tuple[tuple[int, float, float], ...] = (
    (1, 6.0, 30.0),
    (2, 2.5, -60.0),
    (3, 1.2, 100.0),
    (4, 0.6, 0.0),
)


def harmonic_curve_arcsec(
    theta_deg: np.ndarray, harmonics: Sequence[tuple[int, float, float]]
) -> np.ndarray:
    """Σ c_h cos(hθ − φ_h) (arcsec) at angles ``theta_deg``."""
    th = np.deg2rad(np.asarray(theta_deg, dtype=float))
    out = np.zeros_like(th)
    for h, c, phi in harmonics:
        out += float(c) * np.cos(int(h) * th - np.deg2rad(float(phi)))
    return out


def _harmonics(name: str, items: Sequence[Sequence[float]]) -> list[tuple[int, float, float]]:
    out = []
    for item in items:
        if len(item) != 3 or int(item[0]) != item[0] or int(item[0]) < 1:
            raise ConfigError(f"{name}: each entry is (order ≥ 1, amplitude arcsec, phase deg).")
        out.append((int(item[0]), _finite(name, item[1]), _finite(name, item[2])))
    return out


def simulate_position(
    *,
    positions: int = 24,
    runs: int = 5,
    bidirectional: bool = True,
    harmonics: Sequence[Sequence[float]] = DEFAULT_TABLE_HARMONICS,
    reversal_arcsec: float = 1.5,
    noise_arcsec: float = 0.3,
    reference: str = "encoder",
    graduation: Sequence[Sequence[float]] = (),
    graduation_lines: int = 3600,
    polygon_faces: int | None = None,
    polygon_step_faces: int = 1,
    face_error_arcsec: float = 1.0,
    zero_arcsec: float = 5.0,
    seed: int = 0,
) -> SimCapture:
    """A position test of a table with known error harmonics, reversal and non-repeatability.

    Parameters
    ----------
    positions : int
        P, target positions per run, equally spaced over 360° (with a polygon: its faces).
    runs : int
        R, runs (≥ 1).
    bidirectional : bool
        Approach each position in both senses.
    harmonics : sequence of (int, float, float)
        The table's error: (order, amplitude arcsec, phase deg).
    reversal_arcsec, noise_arcsec : float, arcsec
        B and the rms of the white noise per stop.
    reference : str
        ``"encoder"``, ``"polygon"`` or ``"deviation"``.
    graduation : sequence of (int, float, float)
        The reference encoder's graduation error g (arcsec), as ``harmonics``.
    graduation_lines : int
        Lines of the reference encoder (the length of the truth's ``selfcal`` curve).
    polygon_faces : int, optional
        N of the polygon (default P); P must equal it.
    polygon_step_faces : int
        Faces the polygon is turned between runs.
    face_error_arcsec, zero_arcsec : float, arcsec
        rms of the face errors (zero-sum) and of the autocollimator's zero per run.
    seed : int
        Seed of ``numpy.random.default_rng``.
    """
    if int(positions) != positions or positions < 1 or int(runs) != runs or runs < 1:
        raise ConfigError("positions and runs must be whole numbers ≥ 1.")
    if reference not in ("encoder", "polygon", "deviation"):
        raise ConfigError(f"reference must be encoder, polygon or deviation, got {reference!r}.")
    faces = int(polygon_faces or positions)
    if reference == "polygon" and faces != positions:
        raise ConfigError("a polygon test has one position per face: positions = polygon_faces.")
    table = _harmonics("harmonics", harmonics)
    grad = _harmonics("graduation", graduation)
    b = _finite("reversal_arcsec", reversal_arcsec)
    sigma = _finite("noise_arcsec", noise_arcsec)
    if sigma < 0:
        raise ConfigError("noise_arcsec must be ≥ 0.")
    rng = np.random.default_rng(seed)
    p, r = int(positions), int(runs)
    dirs = (1, -1) if bidirectional else (1,)
    target = np.arange(p) * (360.0 / p)
    true_curve = harmonic_curve_arcsec(target, table)
    d_i, r_i, p_i = (g.ravel() for g in np.indices((len(dirs), r, p)))
    sign = np.asarray(dirs)[d_i]
    noise = rng.normal(0.0, sigma, sign.size)
    deviation = true_curve[p_i] + 0.5 * b * sign + noise
    columns: dict[str, np.ndarray] = {
        "position_deg": target[p_i],
        "run": r_i.astype(float),
        "direction": sign.astype(float),
    }
    truth: dict[str, Any] = {
        "kind": "position",
        "positions_deg": target,
        "error_curve_arcsec": true_curve,
        "error_pp_arcsec": float(np.ptp(true_curve)),
        "harmonics": [{"order": h, "amplitude_arcsec": c, "phase_deg": f} for h, c, f in table],
        "reversal_arcsec": b,
        "noise_arcsec": sigma,
        "noise_per_row_arcsec": noise,
        "runs": r,
        "reference": reference,
        "seed": int(seed),
    }
    if reference == "encoder":
        true_angle = target[p_i] + deviation / 3600.0
        columns["reference_deg"] = true_angle - harmonic_curve_arcsec(true_angle, grad) / 3600.0
        lines = int(graduation_lines)
        truth["graduation"] = [
            {"order": h, "amplitude_arcsec": c, "phase_deg": f} for h, c, f in grad
        ]
        line_curve = harmonic_curve_arcsec(np.arange(lines) * (360.0 / lines), grad)
        truth["selfcal"] = {
            "deviation_arcsec": line_curve - line_curve.mean(),
            "pulses_per_rev": lines,
        }
    elif reference == "polygon":
        f = rng.normal(0.0, _finite("face_error_arcsec", face_error_arcsec), faces)
        f -= f.mean()
        z = rng.normal(0.0, _finite("zero_arcsec", zero_arcsec), r)
        face = (p_i + r_i * int(polygon_step_faces)) % faces
        columns["face"] = face.astype(float)
        columns["error_arcsec"] = deviation - f[face] + z[r_i]
        truth.update(face_errors_arcsec=f, zero_arcsec=z, polygon_step_faces=polygon_step_faces)
    else:
        columns["error_arcsec"] = deviation
    return SimCapture("position", columns, truth)


register_kind("position", simulate_position)
