"""A rotary table against an autocollimator and an N-face polygon: the cross-calibration that
separates the polygon's face errors from the table's errors (closure).

At target position k·360°/N the autocollimator sees face j = (k + s_r) mod N, where s_r is how
many faces the polygon was turned on the table before run r. Its reading is

    a[d, r, k] = t[d, k] − f[j] + c[r] + noise,

t[d, k] the table's positional deviation in direction d, f[j] the face error (the angle by which
face j lies beyond its nominal j·360°/N from face 0, in the sense the table turns) and c[r] the
autocollimator's zero in run r. Both the table and the polygon close over 360°: the polygon's
face angles add up to 360° exactly, so Σ f = 0; the zero of the table's deviations is arbitrary
(Σ c = 0 puts it into t). This is the closure or "rosette" cross-calibration of angle metrology
(Evans, Hocken & Estler 1996, closure and error separation: the polygon turned through its
faces against the table, every combination of table position and face measured).

**What the runs can separate.** Write f as its discrete Fourier orders h = 1 … N−1. Turning the
polygon by Δ = s_r − s_0 faces multiplies order h of f by exp(2πi·hΔ/N) and leaves t alone, so an
order is separated from the table exactly when hΔ ≢ 0 (mod N) for some run: a second run turned
by one face already separates every order (noise-free); runs all at the same s separate none (the
curve is then t − f, table and polygon together). Orders not separated are set to zero in f
(attributed to the table) and named, so that the caller can flag them.

The least-squares solution with the constraints (Σ f = 0, Σ c = 0, unresolved orders of f zero) is
the Karush–Kuhn–Tucker system [[AᵀA, Cᵀ], [C, 0]]; the covariance of the estimates is the top-left
block of its inverse times s² = RSS/ν, ν = readings − (unknowns − constraints) (Björck 1996,
§5.1, least squares with linear equality constraints).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
from numpy.typing import NDArray

__all__ = ["PolygonSeparation", "separate_polygon", "unresolved_orders"]

FloatArray = NDArray[np.float64]


@dataclasses.dataclass(frozen=True)
class PolygonSeparation:
    """The face errors f (arcsec, Σ f = 0) with u (None when ν = 0), the run zeros c, the
    table's deviations t[d, k] with their variance, and the corrected readings
    ``deviation[d, r, k]`` = a + f[j] − c[r] (the table's own deviations)."""

    face_errors_arcsec: FloatArray
    face_errors_arcsec_u: FloatArray | None
    run_offsets_arcsec: FloatArray
    table_arcsec: FloatArray
    table_var_arcsec2: FloatArray | None
    deviation: FloatArray
    unresolved: tuple[int, ...]
    residual_rms_arcsec: float
    dof: int
    sigma2: float | None


def unresolved_orders(shifts: NDArray[np.int64], faces: int) -> tuple[int, ...]:
    """Orders h (1 … N/2) of the face errors that the polygon's positions ``shifts`` (faces
    turned, per run) cannot separate from the table: hΔ ≡ 0 (mod N) for every run's Δ."""
    delta = np.asarray(shifts) - shifts[0]
    return tuple(h for h in range(1, faces // 2 + 1) if np.all((h * delta) % faces == 0))


def separate_polygon(
    readings: FloatArray, shifts: NDArray[np.int64], *, separate: bool = True
) -> PolygonSeparation:
    """Separate table and polygon errors from autocollimator readings ``readings[d, r, k]``
    (arcsec) at positions k·360°/N, the polygon turned by ``shifts[r]`` faces in run r.

    ``separate=False`` estimates no face error (every order held at zero: readings already
    corrected by stated face errors); only the run zeros are then fitted."""
    n_dir, n_runs, n = readings.shape
    n_t = n_dir * n
    n_x = n_t + n + n_runs
    d_i, r_i, k_i = (g.ravel() for g in np.indices(readings.shape))
    j_i = (k_i + shifts[r_i]) % n
    rows = np.arange(readings.size)
    design = np.zeros((readings.size, n_x))
    design[rows, d_i * n + k_i] = 1.0
    design[rows, n_t + j_i] = -1.0
    design[rows, n_t + n + r_i] = 1.0
    unresolved = unresolved_orders(shifts, n) if separate else tuple(range(1, n // 2 + 1))
    cons = [np.r_[np.zeros(n_t), np.ones(n), np.zeros(n_runs)]]
    cons.append(np.r_[np.zeros(n_t + n), np.ones(n_runs)])
    j = np.arange(n)
    for h in unresolved:
        for row in (np.cos(2 * np.pi * h * j / n), np.sin(2 * np.pi * h * j / n)):
            if np.linalg.norm(row) > 1e-9 * n:  # the sine of order N/2 is zero at the faces
                cons.append(np.r_[np.zeros(n_t), row, np.zeros(n_runs)])
    c = np.array(cons)
    kkt = np.block([[design.T @ design, c.T], [c, np.zeros((len(cons), len(cons)))]])
    inv = np.linalg.inv(kkt)
    y = readings.ravel()
    x = (inv @ np.r_[design.T @ y, np.zeros(len(cons))])[:n_x]
    resid = y - design @ x
    dof = readings.size - (n_x - len(cons))
    sigma2 = float(resid @ resid) / dof if dof > 0 else None
    cov_diag = np.diag(inv)[:n_x] * sigma2 if sigma2 is not None else None
    faces = x[n_t : n_t + n]
    offsets = x[n_t + n :]
    deviation = (
        readings
        + faces[(np.arange(n)[None, :] + shifts[:, None]) % n][None]
        - offsets[None, :, None]
    )
    return PolygonSeparation(
        face_errors_arcsec=faces,
        face_errors_arcsec_u=None if cov_diag is None else np.sqrt(cov_diag[n_t : n_t + n]),
        run_offsets_arcsec=offsets,
        table_arcsec=x[:n_t].reshape(n_dir, n),
        table_var_arcsec2=None if cov_diag is None else cov_diag[:n_t].reshape(n_dir, n),
        deviation=deviation,
        unresolved=unresolved,
        residual_rms_arcsec=math.sqrt(float(resid @ resid) / y.size),
        dof=dof,
        sigma2=sigma2,
    )
