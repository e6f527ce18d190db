"""Fourier harmonics of an angle-dependent error curve, by least squares, with uncertainties.

The error curve e(θ) of a rotary axis is periodic in 360°, so it is described by its harmonics
(orders h per revolution: 1 the eccentricity of a scale or of the axis, 2 its ellipticity, …):

    e(θ) = a₀ + Σ_{h=1}^{H} (a_h cos hθ + b_h sin hθ) = a₀ + Σ c_h cos(hθ − φ_h),

c_h = √(a_h² + b_h²), φ_h = atan2(b_h, a_h). The coefficients are the ordinary least-squares
solution at the measured positions (any spacing; equal spacing over 360° makes the columns
orthogonal). Their covariance is (XᵀX)⁻¹·(s² + ū_ref²): s² = RSS/(P − 2H − 1) from the fit's
residuals (the reading noise and the orders above H), ū_ref² the mean square of the reference's
standard uncertainty at the positions (Type B, taken as independent between positions). u(c_h)
and u(φ_h) follow by first-order propagation with the covariance of (a_h, b_h) (GUM, JCGM
100:2008 §5.1.2); for c_h ≲ 2u(c_h) the amplitude is biased upward by the noise and its phase
meaningless (a note in the result says so).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
from numpy.typing import NDArray

from rotacal.errors import ConfigError
from rotacal.uncertainty.coverage import coverage_factor

__all__ = ["MAX_CONDITION", "HarmonicFit", "fit_harmonics"]

#: Above this condition number of the design matrix the positions do not determine the
#: harmonics asked for (e.g. all positions within a small arc; equal spacing over 360° gives √2):
#: their u would be inflated by up to this factor, and the split between orders meaningless.
MAX_CONDITION = 1e3

FloatArray = NDArray[np.float64]


@dataclasses.dataclass(frozen=True)
class HarmonicFit:
    """Orders 1 … H: amplitude c_h and phase φ_h (cos hθ − φ_h) with u; residual rms and dof.

    ``effective_dof`` is ν_eff of every u (GUM G.4.1, Welch–Satterthwaite): the residual's
    variance with ``dof`` degrees of freedom, the reference's as exactly known; ``coverage_k``
    is t₉₅(ν_eff)."""

    orders: tuple[int, ...]
    cos_arcsec: FloatArray
    sin_arcsec: FloatArray
    amplitudes_arcsec: FloatArray
    amplitudes_arcsec_u: FloatArray
    phases_deg: FloatArray
    phases_deg_u: FloatArray
    mean_arcsec: float
    residual_rms_arcsec: float
    dof: int
    fitted_arcsec: FloatArray  # the model at the positions
    effective_dof: float
    coverage_k: float


def fit_harmonics(
    positions_deg: FloatArray,
    error_arcsec: FloatArray,
    harmonics: int,
    *,
    u_ref_arcsec: FloatArray | None = None,
) -> HarmonicFit:
    """Least-squares Fourier series of order ``harmonics`` through ``error_arcsec`` (arcsec).

    Parameters
    ----------
    positions_deg : ndarray (P,), deg
        Where the curve was measured (any angles; taken modulo 360°).
    error_arcsec : ndarray (P,), arcsec
        The error curve at those positions.
    harmonics : int
        H, the highest order fitted (≥ 1).
    u_ref_arcsec : ndarray (P,), arcsec, optional
        The reference's standard uncertainty at each position.

    Raises
    ------
    ConfigError
        Fewer than 2H + 2 distinct positions modulo 360° (no residual left to estimate u), or
        positions that do not determine the orders asked for (condition number above
        :data:`MAX_CONDITION`).
    """
    theta = np.deg2rad(np.mod(positions_deg, 360.0))
    distinct = np.unique(np.round(np.mod(positions_deg, 360.0), 6) % 360.0).size
    need = 2 * harmonics + 2
    if distinct < need:
        most = max((distinct - 2) // 2, 0)
        raise ConfigError(
            f"--harmonics {harmonics} needs at least {need} distinct positions (modulo 360°) "
            f"to fit and leave a residual for its uncertainty; the capture has {distinct}: ask "
            f"for at most {most} (or measure more positions)"
        )
    orders = np.arange(1, harmonics + 1)
    angle = np.outer(theta, orders)
    design = np.column_stack([np.ones_like(theta), np.cos(angle), np.sin(angle)])
    cond = np.linalg.cond(design)
    if not np.isfinite(cond) or cond > MAX_CONDITION:
        lo, hi = float(np.min(positions_deg)), float(np.max(positions_deg))
        raise ConfigError(
            f"positions from {lo:g}° to {hi:g}° do not determine harmonics 1…{harmonics} "
            f"(condition number {cond:.3g}): spread the positions over the whole revolution or "
            "ask for fewer harmonics (--harmonics 0: none)"
        )
    coef, *_ = np.linalg.lstsq(design, error_arcsec, rcond=None)
    fitted = design @ coef
    resid = error_arcsec - fitted
    dof = theta.size - design.shape[1]
    s2 = float(resid @ resid) / dof
    ref2 = float(np.mean(u_ref_arcsec**2)) if u_ref_arcsec is not None else 0.0
    cov = np.linalg.inv(design.T @ design) * (s2 + ref2)
    a, b = coef[1 : 1 + harmonics], coef[1 + harmonics :]
    ia, ib = orders, orders + harmonics
    va, vb, cab = cov[ia, ia], cov[ib, ib], cov[ia, ib]
    amp = np.hypot(a, b)
    with np.errstate(divide="ignore", invalid="ignore"):
        amp_u = np.sqrt((a * a * va + b * b * vb + 2 * a * b * cab) / (amp * amp))
        phase_u = np.sqrt(b * b * va + a * a * vb - 2 * a * b * cab) / (amp * amp)
    amp_u = np.where(amp > 0, amp_u, np.sqrt(0.5 * (va + vb)))
    # every u² is (s² + u_ref²) times a factor of the design alone: one ν_eff for all
    nu_eff = dof * ((s2 + ref2) / s2) ** 2 if s2 > 0 else math.inf
    return HarmonicFit(
        orders=tuple(int(h) for h in orders),
        cos_arcsec=a,
        sin_arcsec=b,
        amplitudes_arcsec=amp,
        amplitudes_arcsec_u=amp_u,
        phases_deg=np.rad2deg(np.arctan2(b, a)),
        phases_deg_u=np.rad2deg(np.where(amp > 0, phase_u, math.pi)),
        mean_arcsec=float(coef[0]),
        residual_rms_arcsec=math.sqrt(float(resid @ resid) / theta.size),
        dof=dof,
        fitted_arcsec=fitted,
        effective_dof=nu_eff,
        coverage_k=coverage_factor(nu_eff),
    )
