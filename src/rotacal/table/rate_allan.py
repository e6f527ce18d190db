"""Relative root Allan variance of angular velocity versus rotation angle, s(φ), and its
uncertainty from equivalent degrees of freedom (Kokuyama et al. 2015, §5; Greenhall & Riley 2003)."""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

from rotacal._jit import use_numba
from rotacal.errors import CaptureError, ConfigError
from rotacal.signal.allan import adev_confidence_interval, edf_overlapping_adev
from rotacal.table.rate_allan_sums import (
    ALLAN_FULL_CLUSTERS,
    allan_stride,
    allan_sums,
    decimated_grid,
    grid_stride,
)
from rotacal.uncertainty.summaries import (
    COVERAGE,
)

__all__ = ["allan_clusters", "allan_uncertainty", "allan_versus_angle"]

FloatArray = NDArray[np.float64]

#: Allan points per decade of rotation angle.
ALLAN_POINTS_PER_DECADE = 12


def allan_versus_angle(
    times_s: ArrayLike,
    angle_deg: ArrayLike,
    *,
    mean_rate_deg_s: float,
    angles_deg: ArrayLike | None = None,
    pitch_deg: float | None = None,
) -> tuple[FloatArray, FloatArray]:
    """Relative root Allan variance of angular velocity versus rotation angle, s(φ).

    With angles θ_i at pulse times t_i, the rate over k pulses is ω_i = (θ_{i+k} − θ_i)/(t_{i+k}
    − t_i), the Allan variance σ²(τ) = ½⟨(ω_{i+k} − ω_i)²⟩ (overlapping, averaged over every i)
    and s(φ) = √σ²(φ/ω_m)/ω_m. The seed samples the angle at equal times; here it is sampled at
    equal angles (the pulses), so φ = k·Δθ is exact and τ = φ/ω_m as Kokuyama et al. (2015) convert it.
    From 128 pulses on, the terms are taken every d-th pulse (d divides k, k/d ≥ 64: the
    overlapping Allan variance of the record decimated to every d-th pulse, see
    :mod:`rotacal.table.rate_allan_sums`), so that a stream needs a bounded state and the work
    stays a few passes over the record.

    Parameters
    ----------
    times_s : array_like, s
        Pulse times.
    angle_deg : array_like, deg
        Angle at each pulse (compensated or nominal).
    mean_rate_deg_s : float, deg/s
        ω_m.
    angles_deg : array_like, deg, optional
        Rotation angles φ to evaluate (rounded to whole pulses); default: 12 per decade from
        one pitch to a third of the record.
    pitch_deg : float, deg, optional
        Nominal pitch Δθ (default: the mean angle step).

    Returns
    -------
    phi_deg : ndarray, deg
    s : ndarray
        Relative root Allan variance (dimensionless).

    References
    ----------
    Kokuyama et al. (2015), §5 "Evaluation using root Allan variance": ω_i = (θ_{i+k} −
    θ_i)/(kΔt), σ²(τ) = ½⟨(ω_{i+k} − ω_i)²⟩, τ = φ/ω_m, s(φ) = √σ²(φ/ω_m)/ω_m; Figure 10.
    """
    t = np.asarray(times_s, dtype=np.float64)
    a = np.asarray(angle_deg, dtype=np.float64)
    n = t.size
    pitch = float(pitch_deg) if pitch_deg is not None else float((a[-1] - a[0]) / (n - 1))
    ks = allan_clusters(n, pitch, angles_deg)
    strides = np.array([allan_stride(int(k)) for k in ks], dtype=np.int64)
    jit = use_numba(n)
    s = np.empty(ks.size)
    for d in np.unique(strides).tolist():  # one pass over each decimated record
        sel = np.flatnonzero(strides == d)
        td, ad = (t, a) if d == 1 else (t[::d].copy(), a[::d].copy())
        kd = ks[sel] // d
        counts = td.size - 2 * kd
        sums = allan_sums(td, ad, kd.tolist(), [0] * sel.size, counts.tolist(), jit=jit)
        mean_square = np.asarray(sums) / counts
        s[sel] = np.sqrt(0.5 * mean_square) / abs(mean_rate_deg_s)
    return np.asarray(ks * pitch, dtype=np.float64), s


def _grid_point(k: int, kmax: int) -> int:
    """k on the decimated grid (:func:`decimated_grid`), not beyond kmax."""
    g = decimated_grid(k)
    if g <= kmax:
        return g
    d = grid_stride(k)
    return d * (kmax // d) if d <= kmax else kmax


def allan_clusters(
    n: int, pitch_deg: float, angles_deg: ArrayLike | None = None
) -> NDArray[np.int64]:
    """Cluster sizes k (pulses) of s(φ) for a record of n pulses: 12 per decade from one pitch
    to a third of the record, plus one revolution, or the requested angles rounded to pulses.

    From 2·:data:`~rotacal.table.rate_allan_sums.ALLAN_FULL_CLUSTERS` pulses on, the grid's
    points are rounded to a multiple of their stride (:func:`decimated_grid`); a requested angle
    whose pulses have no divisor that keeps the stride's work small is rounded the same way,
    one of whole revolutions is kept exact (the scale's deviation cancels there).
    """
    pitch = float(pitch_deg)
    kmax = (n - 1) // 3
    if kmax < 1:
        raise CaptureError(f"{n} pulses are too few for an Allan variance; record more.")
    whole = int(np.rint(360.0 / pitch))
    if angles_deg is None:
        decades = max(math.log10(kmax), 0.0)
        grid = np.rint(np.logspace(0.0, decades, int(decades * ALLAN_POINTS_PER_DECADE) + 1))
        # one revolution, where the scale's deviation cancels (Kokuyama et al.'s Figure 10 dip)
        extra = [whole] if 1 <= whole <= kmax else []
        points = [_grid_point(int(k), kmax) for k in grid]
        return np.unique(np.asarray([*points, *extra], dtype=np.int64))
    req = np.atleast_1d(np.asarray(angles_deg, dtype=np.float64))
    if not np.all(np.isfinite(req)) or np.any(req <= 0):
        raise ConfigError("Allan angles must be finite and > 0 deg.")
    ks = np.unique(np.maximum(1, np.rint(req / pitch)).astype(np.int64))
    too_long = ks[ks > kmax]
    if too_long.size:
        raise ConfigError(
            f"an Allan angle of {too_long[0] * pitch:.6g} deg needs more than a third of the "
            f"record ({kmax * pitch:.6g} deg); drop it or record longer."
        )
    out = []
    for k in ks.tolist():
        poor = k // allan_stride(k) > 8 * ALLAN_FULL_CLUSTERS
        revolutions = whole >= 1 and k % whole == 0
        out.append(k if (revolutions or not poor) else _grid_point(k, kmax))
    return np.unique(np.asarray(out, dtype=np.int64))


def _noise_alpha(phi: FloatArray, s: FloatArray) -> NDArray[np.int64]:
    """Power-law noise type of each s(φ) point from the local log-log slope μ of s(φ)."""
    if phi.size < 2:
        return np.full(phi.size, 2, dtype=np.int64)
    with np.errstate(divide="ignore"):
        mu = np.gradient(np.log(np.maximum(s, 1e-300)), np.log(phi))
    # σ ∝ τ^μ: μ = −1 white (or flicker) PM, −½ white FM, 0 flicker FM, +½ random-walk FM.
    # White PM (the pulses' electronic noise, Kokuyama et al. 2015, §5) only in the leading run of the φ⁻¹
    # slope: a steep fall further out is the 360° dip of the graduation or a fluctuation's
    # notch, over which the FM types' smaller edf is the cautious choice.
    alpha = np.select([mu <= -0.25, mu <= 0.25], [0, -1], -2).astype(np.int64)
    steep = mu <= -0.75
    lead = int(np.argmin(steep)) if not steep.all() else steep.size
    alpha[:lead] = 2
    return alpha


def allan_uncertainty(
    s: ArrayLike, angles_deg: ArrayLike, pitch_deg: float, pulses: int
) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray, FloatArray, NDArray[np.int64]]:
    """Uncertainty of each relative root Allan variance s(φ) from its equivalent dof.

    The angle is sampled at the pulses (equal angles), so the pulse times play the part of the
    phase and φ = k·Δθ the part of τ = m·τ₀: σ²(φ) is the overlapping Allan variance of cluster
    size k over N pulses (of k/d over the ⌈N/d⌉ pulses at stride d when the terms are taken
    every d-th pulse, :func:`allan_versus_angle`). Its edf (Greenhall & Riley 2003) depends on
    the noise type, taken from
    the local slope of s(φ). ν·ŝ²/s² ~ χ²(ν), so u(ŝ) = ŝ/√(2ν) and the 95 % interval is
    [ŝ·√(ν/χ²₀.₉₇₅), ŝ·√(ν/χ²₀.₀₂₅)].

    Parameters
    ----------
    s : array_like
        s(φ) (dimensionless).
    angles_deg : array_like, deg
        φ of each point (whole pulses).
    pitch_deg : float, deg
        Δθ.
    pulses : int
        N, the pulses the variance was computed from.

    Returns
    -------
    u, U, edf, low, high : ndarray
        Standard uncertainty, U (half the width of the 95 % interval), edf, and the interval.
    alpha : ndarray of int
        The noise type assumed at each point.

    References
    ----------
    C. A. Greenhall and W. J. Riley, "Uncertainty of stability variances based on finite
    differences", Proc. 35th PTTI (2003); NIST SP 1065 (Riley 2008) §5.3; Kokuyama et al.
    (2015) §5, s(φ) = √σ²(φ/ω_m)/ω_m.
    """
    sv = np.asarray(s, dtype=np.float64)
    phi = np.asarray(angles_deg, dtype=np.float64)
    ks = np.maximum(1, np.rint(phi / pitch_deg)).astype(np.int64)
    alpha = _noise_alpha(phi, sv)
    # a cluster taken every d-th pulse is the overlapping variance of the decimated record
    strides = np.array([allan_stride(int(k)) for k in ks], dtype=np.int64)
    edf = np.empty(sv.size)
    for a in np.unique(alpha):
        for d in np.unique(strides[alpha == a]):  # one whole-array call per type and stride
            sel = (alpha == a) & (strides == d)
            n_d = -(-int(pulses) // int(d))  # pulses whose index is a multiple of d
            edf[sel] = edf_overlapping_adev(n_d, ks[sel] // d, int(a))
    u = sv / np.sqrt(2.0 * edf)
    low, high = adev_confidence_interval(sv, edf, COVERAGE)
    return u, 0.5 * (high - low), edf, low, high, alpha
