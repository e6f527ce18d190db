"""Scale-factor items of IEEE Std 952 / 1431 beyond S, V0 and NL: sign asymmetry and repeatability.

* **Positive and negative scale factors, asymmetry.** IEEE Std 528-2001 defines the scale-factor
  asymmetry as the difference between the scale factor measured with positive inputs and that
  measured with negative inputs, stated as a fraction of the scale factor measured over the whole
  input range; IEEE Std 952-1997 and IEEE Std 1431-2004 list it among the scale-factor items of the
  specification and of the rate-transfer test. rotacal fits the rate points (their means) with two
  slopes and ONE bias, by unweighted least squares,

      V(Ω) = S₊·max(Ω, 0) + S₋·min(Ω, 0) + V0,

  so that the bias — the output at zero input, a single property of the gyro — is shared by both
  halves and is not mistaken for asymmetry (two separate lines, each with its own intercept, would
  let an even-order nonlinearity move into two different biases and hide the asymmetry). The
  asymmetry is ``1e6·(S₊ − S₋)/S`` ppm with S the scale factor of the whole range.
* **Repeatability** (IEEE Std 952-1997 / 1431-2004, scale-factor repeatability: the agreement of
  the scale factor over repeated runs, between which the gyro is turned off or the conditions
  change): ``1e6·s(S_k)/|mean(S_k)|`` ppm, s the sample standard deviation (ddof 1) of the
  per-run scale factors S_k.

Uncertainties (GUM, JCGM 100:2008): S₊ and S₋ — Type A, the point means' standard uncertainties
propagated through the fit, u²(θ) = [(XᵀX)⁻¹Xᵀ·diag(u_i²)·X(XᵀX)⁻¹] (GUM §5.1.2 with the
sensitivities of a linear estimator), plus Type B the table's stated set-rate error ε (both
slopes scale by 1/(1 + ε)), u_B = |S±|·u(ε); the asymmetry's u is Type A only (the common ε
cancels in the ratio; the denominator's own uncertainty is of second order and left out), from
var(S₊) + var(S₋) − 2·cov(S₊, S₋). The repeatability's u is that of a standard deviation of n
normal values, s/√(2(n − 1)) (GUM G.4 / the χ² distribution of s², first order).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from rotacal.errors import CaptureError
from rotacal.results import Result

__all__ = [
    "MIN_POINTS_PER_SIGN",
    "ScaleFactorRepeatability",
    "SignedScaleFactors",
    "least_squares_with_u",
    "scale_factor_repeatability",
    "signed_or_flag",
    "signed_scale_factors",
]

#: Rate points each sign needs: one fixes a slope through the shared bias only when the bias is
#: known exactly; two leave the slope determined by that sign's own points.
MIN_POINTS_PER_SIGN = 2


def least_squares_with_u(
    x: np.ndarray, y: np.ndarray, u: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """θ of the unweighted least-squares fit y ≈ x·θ and its covariance from the standard
    uncertainties u of y: P·diag(u²)·Pᵀ with P = (XᵀX)⁻¹Xᵀ (GUM §5.1.2, the fit being linear in
    y). Raises CaptureError when the columns of x are not independent."""
    norm = np.max(np.abs(x), axis=0)
    xs = x / norm  # the columns scaled alike, for the conditioning of the solve
    if np.linalg.matrix_rank(xs) < x.shape[1]:
        raise CaptureError("the design of the fit has dependent columns")
    pinv = np.linalg.pinv(xs) / norm[:, None]
    return pinv @ y, (pinv * u**2) @ pinv.T


@dataclasses.dataclass(frozen=True)
class SignedScaleFactors(Result):
    """The scale factors of positive and negative inputs and the asymmetry (IEEE Std 528/952).

    ``scale_factor_positive``/``scale_factor_negative`` in output unit per °/s with their standard
    uncertainties ``_u``; ``asymmetry_ppm`` = 1e6·(S₊ − S₋)/S with ``asymmetry_ppm_u``;
    ``bias_common`` (output unit) the one bias of the two-slope fit; ``points_positive`` and
    ``points_negative`` the rate points of each sign (a 0 °/s point belongs to neither slope but
    fixes the bias).
    """

    scale_factor_positive: float
    scale_factor_positive_u: float
    scale_factor_negative: float
    scale_factor_negative_u: float
    asymmetry_ppm: float
    asymmetry_ppm_u: float
    bias_common: float
    points_positive: int
    points_negative: int


def signed_scale_factors(
    rates_deg_s: np.ndarray,
    means: np.ndarray,
    u_means: np.ndarray,
    *,
    scale_factor: float,
    eps_mean: float = 0.0,
    u_eps: float = 0.0,
) -> SignedScaleFactors:
    """S₊, S₋ and the asymmetry from the rate points of a scale-factor test (IEEE Std 528/952).

    Parameters
    ----------
    rates_deg_s : array
        Set rate of each point (°/s).
    means : array
        Mean output of each point (output units).
    u_means : array
        Standard uncertainty of each point mean (output units; Type A).
    scale_factor : float
        S of the whole input range (output units per °/s), the asymmetry's denominator.
    eps_mean, u_eps : float
        Stated mean relative error of the table's set rate and its standard uncertainty
        (dimensionless; ``table.set_rate_relative``): S± = S±₀/(1 + ε̄), u_B = |S±|·u(ε).

    Raises
    ------
    CaptureError
        A sign has fewer than :data:`MIN_POINTS_PER_SIGN` points.
    """
    rates = np.asarray(rates_deg_s, dtype=float)
    y = np.asarray(means, dtype=float)
    u = np.asarray(u_means, dtype=float)
    n_pos, n_neg = int(np.count_nonzero(rates > 0)), int(np.count_nonzero(rates < 0))
    if min(n_pos, n_neg) < MIN_POINTS_PER_SIGN:
        raise CaptureError(
            f"the test has {n_pos} positive and {n_neg} negative rate point(s): the scale factors "
            f"of each sign and the asymmetry need at least {MIN_POINTS_PER_SIGN} of each sign."
        )
    x = np.column_stack([np.maximum(rates, 0.0), np.minimum(rates, 0.0), np.ones_like(rates)])
    theta, cov = least_squares_with_u(x, y, u)
    k = 1.0 + eps_mean
    s_pos, s_neg = theta[0] / k, theta[1] / k
    var_pos, var_neg, cov_pn = cov[0, 0] / k**2, cov[1, 1] / k**2, cov[0, 1] / k**2
    u_pos = math.sqrt(var_pos + (s_pos * u_eps) ** 2)
    u_neg = math.sqrt(var_neg + (s_neg * u_eps) ** 2)
    asym = 1e6 * (s_pos - s_neg) / scale_factor
    asym_u = 1e6 * math.sqrt(max(var_pos + var_neg - 2.0 * cov_pn, 0.0)) / abs(scale_factor)
    return SignedScaleFactors(
        scale_factor_positive=float(s_pos),
        scale_factor_positive_u=u_pos,
        scale_factor_negative=float(s_neg),
        scale_factor_negative_u=u_neg,
        asymmetry_ppm=float(asym),
        asymmetry_ppm_u=asym_u,
        bias_common=float(theta[2]),
        points_positive=n_pos,
        points_negative=n_neg,
    )


@dataclasses.dataclass(frozen=True)
class ScaleFactorRepeatability(Result):
    """Run-to-run repeatability of the scale factor (IEEE Std 952-1997 / 1431-2004).

    ``scale_factor_repeatability_ppm`` = 1e6·s(S_k)/|mean S_k| with ``_u`` = value/√(2(n − 1));
    ``run_scale_factors`` (output unit per °/s) and their ``run_scale_factors_u``;
    ``within_run_ppm`` = 1e6·rms(u(S_k))/|mean S_k|, what the runs' own noise alone would give.
    """

    scale_factor_repeatability_ppm: float
    scale_factor_repeatability_ppm_u: float
    runs: int
    run_scale_factors: tuple[float, ...]
    run_scale_factors_u: tuple[float, ...]
    within_run_ppm: float


def scale_factor_repeatability(
    scale_factors: np.ndarray, scale_factors_u: np.ndarray | None = None
) -> ScaleFactorRepeatability:
    """Run-to-run repeatability (ppm) of the scale factors of n ≥ 2 runs of the same test.

    Parameters
    ----------
    scale_factors : array
        S_k of each run (output units per °/s).
    scale_factors_u : array or None
        Their standard uncertainties (same unit), for ``within_run_ppm``; None: NaN.

    Raises
    ------
    CaptureError
        Fewer than two runs, or a zero mean scale factor.
    """
    s = np.asarray(scale_factors, dtype=float).reshape(-1)
    if s.size < 2:
        raise CaptureError(
            "the scale-factor repeatability needs at least two runs: give several captures, each "
            "a whole test (rate_deg_s and output at two rates or more)."
        )
    mean = float(np.mean(s))
    if mean == 0.0 or not np.all(np.isfinite(s)):
        raise CaptureError("the runs' scale factors average to zero or are not finite.")
    ppm = 1e6 * float(np.std(s, ddof=1)) / abs(mean)
    us = (
        np.full(s.size, math.nan)
        if scale_factors_u is None
        else np.asarray(scale_factors_u, dtype=float).reshape(-1)
    )
    return ScaleFactorRepeatability(
        scale_factor_repeatability_ppm=ppm,
        scale_factor_repeatability_ppm_u=ppm / math.sqrt(2.0 * (s.size - 1)),
        runs=int(s.size),
        run_scale_factors=tuple(float(v) for v in s),
        run_scale_factors_u=tuple(float(v) for v in us),
        within_run_ppm=1e6 * math.sqrt(float(np.mean(us**2))) / abs(mean),
    )


def signed_or_flag(
    rates_deg_s: np.ndarray,
    means: np.ndarray,
    u_means: np.ndarray | None,
    *,
    scale_factor: float,
    eps_mean: float = 0.0,
    u_eps: float = 0.0,
) -> tuple[SignedScaleFactors | None, str | None, str | None]:
    """:func:`signed_scale_factors` for a scale-factor result: (items, note, warning).

    A test of one sign only gets None and a note (asymmetry does not apply); a test with points of
    both signs but too few of one gets None and a warning, so the missing keys are flagged."""
    rates = np.asarray(rates_deg_s, dtype=float)
    u = np.full(rates.size, math.nan) if u_means is None else np.asarray(u_means, dtype=float)
    try:
        return (
            signed_scale_factors(
                rates, means, u, scale_factor=scale_factor, eps_mean=eps_mean, u_eps=u_eps
            ),
            None,
            None,
        )
    except CaptureError as e:
        if np.any(rates > 0) and np.any(rates < 0):
            return None, None, f"no scale factors per sign: {e}"
        return (
            None,
            f"the rates are of one sign: no scale factors per sign nor asymmetry ({e})",
            None,
        )
