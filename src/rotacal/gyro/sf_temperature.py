"""Temperature coefficients of a gyro's scale factor and bias (IEEE Std 952-1997 / 1431-2004).

IEEE Std 952 and 1431 specify the scale factor's and the bias's temperature sensitivity (the
change per degree of temperature, from rate-transfer tests at several temperatures). rotacal fits
the rate points of all runs — each point with its set rate Ω_i, its mean output V̄_i and the mean
temperature T_i of its samples — by unweighted least squares with

    V = S0·Ω + a·Ω·ΔT + V0 + b·ΔT   (+ a₂·Ω·ΔT² + b₂·ΔT², the quadratic model),   ΔT = T − T̄,

T̄ the mean of the points' temperatures (the reference temperature). The scale factor's
temperature coefficient at T̄ is ``1e6·a/S0`` ppm/°C (dS/dT over S, the quadratic terms having
no slope at T̄) and the bias's is ``3600·b/S0`` (°/h)/°C (b in output units per °C, converted to
an input rate by S0).

**Model choice.** Linear, unless the quadratic one is supported by the data: at least three
distinct temperatures (0.1 °C apart), at least one degree of freedom left, and an F-test of the
extra sum of squares of the two quadratic terms significant at 5 % (the regression F-test,
e.g. Draper & Smith, Applied Regression Analysis, 3rd ed., §6.1).

**Uncertainty** (GUM, JCGM 100:2008 §5.1.2 with the fit's sensitivities): the point means'
standard uncertainties u_i propagated through the fit (the sandwich (XᵀX)⁻¹Xᵀ·diag(u_i²)·X(XᵀX)⁻¹);
when the points scatter about the model more than u_i explain (χ²/ν > 1, e.g. nonlinearity in Ω or
drift), that covariance is scaled by χ²/ν (the Birge ratio squared), so that the stated u covers
the scatter. The coefficients' u follows to first order (the relative u of S0 is negligible).

Refused (CaptureError): point temperatures spanning less than :data:`MIN_TEMPERATURE_SPAN_C`
(too small to tell a coefficient from the noise of the temperature and of the output), or points
that do not separate S(T) from V0(T) (the design matrix is rank-deficient: two rates at two
temperatures at least are needed).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from rotacal.errors import CaptureError
from rotacal.gyro.sf_items import least_squares_with_u
from rotacal.results import Result

__all__ = ["MIN_TEMPERATURE_SPAN_C", "TemperatureCoefficients", "temperature_coefficients"]

#: Smallest spread of the points' temperatures (°C) from which a coefficient is stated: below
#: it a lab's temperature sensor (±0.1…0.5 °C) and the output's drift over a test dominate.
MIN_TEMPERATURE_SPAN_C = 1.0
_F_ALPHA = 0.05


@dataclasses.dataclass(frozen=True)
class TemperatureCoefficients(Result):
    """The temperature coefficients of S (ppm/°C) and of the bias ((°/h)/°C) at ``temperature_ref_c``.

    ``temperature_model`` is ``"linear"`` or ``"quadratic"`` (see the module); ``temperature_f_p``
    the F-test's p-value for the quadratic terms (None when it could not be run);
    ``temperature_span_c`` the points' max − min temperature; ``temperature_points`` the number of
    points fitted; ``temperature_birge_ratio`` √(χ²/ν) of the fit (1 when ν = 0).
    """

    scale_factor_temperature_coefficient_ppm_per_c: float
    scale_factor_temperature_coefficient_ppm_per_c_u: float
    bias_temperature_coefficient_deg_h_per_c: float
    bias_temperature_coefficient_deg_h_per_c_u: float
    temperature_ref_c: float
    temperature_span_c: float
    temperature_model: str
    temperature_f_p: float | None
    temperature_points: int
    temperature_birge_ratio: float


def _fit(x: np.ndarray, y: np.ndarray, u: np.ndarray) -> tuple[np.ndarray, np.ndarray, float, int]:
    """θ, its covariance (Birge-scaled), the residual sum of squares and ν of one model."""
    try:
        theta, cov = least_squares_with_u(x, y, u)
    except CaptureError:
        raise CaptureError(
            "the rate points do not separate the scale factor's change with temperature from the "
            "bias's: test at least two rates at each of two temperatures."
        ) from None
    resid = y - x @ theta
    dof = y.size - x.shape[1]
    birge2 = float(np.sum((resid / u) ** 2)) / dof if dof > 0 and np.all(u > 0) else 1.0
    return theta, cov * max(birge2, 1.0), float(resid @ resid), dof


def temperature_coefficients(
    rates_deg_s: np.ndarray,
    means: np.ndarray,
    u_means: np.ndarray,
    temperature_c: np.ndarray,
) -> TemperatureCoefficients:
    """Temperature coefficients of S and the bias from rate points at several temperatures.

    Parameters
    ----------
    rates_deg_s : array
        Set rate of each point (°/s).
    means : array
        Mean output of each point (output units).
    u_means : array
        Standard uncertainty of each point mean (output units).
    temperature_c : array
        Mean temperature of each point's samples (°C).

    Returns
    -------
    TemperatureCoefficients
        See the module for the model, its choice and the uncertainties.
    """
    w = np.asarray(rates_deg_s, dtype=float)
    y = np.asarray(means, dtype=float)
    u = np.asarray(u_means, dtype=float)
    t = np.asarray(temperature_c, dtype=float)
    if not np.all(np.isfinite(t)):
        raise CaptureError(
            "column temperature_c holds NaN or inf: every point needs a temperature."
        )
    span = float(np.ptp(t))
    if span < MIN_TEMPERATURE_SPAN_C:
        raise CaptureError(
            f"the rate points' temperatures span {span:.3g} °C, less than "
            f"{MIN_TEMPERATURE_SPAN_C:g} °C: too small to tell the temperature coefficients; test "
            "at temperatures further apart, or map the column away (--column temperature_c=room_c)."
        )
    ref = float(np.mean(t))
    dt = t - ref
    one = np.ones_like(w)
    linear = np.column_stack([w, w * dt, one, dt])
    theta, cov, rss, dof = _fit(linear, y, u)
    model, p_value = "linear", None
    distinct = np.unique(np.round(t, 1)).size
    if distinct >= 3 and dof - 2 >= 1:
        quad = np.column_stack([linear, w * dt**2, dt**2])
        try:
            theta_q, cov_q, rss_q, dof_q = _fit(quad, y, u)
        except CaptureError:
            pass  # the quadratic terms are not identifiable: the linear model stands
        else:
            from scipy.special import fdtrc

            f = ((rss - rss_q) / 2.0) / (rss_q / dof_q) if rss_q > 0 else math.inf
            p_value = float(fdtrc(2, dof_q, f)) if math.isfinite(f) else 0.0
            if p_value < _F_ALPHA:
                model, theta, cov, dof = "quadratic", theta_q, cov_q, dof_q
    s0 = float(theta[0])
    k_s = 1e6 * float(theta[1]) / s0
    k_s_u = 1e6 * math.sqrt(float(cov[1, 1])) / abs(s0)
    k_b = 3600.0 * float(theta[3]) / s0
    k_b_u = 3600.0 * math.sqrt(float(cov[3, 3])) / abs(s0)
    resid = y - (
        linear @ theta[:4]
        if model == "linear"
        else np.column_stack([linear, w * dt**2, dt**2]) @ theta
    )
    birge = math.sqrt(float(np.sum((resid / u) ** 2)) / dof) if dof > 0 and np.all(u > 0) else 1.0
    return TemperatureCoefficients(
        scale_factor_temperature_coefficient_ppm_per_c=k_s,
        scale_factor_temperature_coefficient_ppm_per_c_u=k_s_u,
        bias_temperature_coefficient_deg_h_per_c=k_b,
        bias_temperature_coefficient_deg_h_per_c_u=k_b_u,
        temperature_ref_c=ref,
        temperature_span_c=span,
        temperature_model=model,
        temperature_f_p=p_value,
        temperature_points=int(w.size),
        temperature_birge_ratio=birge,
    )
