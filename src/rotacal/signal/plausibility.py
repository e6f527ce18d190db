"""Plausibility checks shared by every analysis: numbers that are possible but not believable.

An analysis that finishes still may have been given a wrong setting (a line count ten times too
small, a radius in cm instead of mm, a gyro unit in rad/s instead of deg/s) or a model that does
not explain its data. These functions turn such findings into one warning line each — what was
seen, the number, the likely cause and what to check — or None when nothing is implausible. The
analyses add the lines to their result's ``warnings`` (:func:`rotacal.results.with_warnings`);
the CLI prints them on stderr and the report shows them at the top.

Two tests are shared:

* :func:`set_value_warning` — a measured value against the value the user set: a ratio near a
  power of ten or of two (a unit or a count given wrong), or an error beyond a plausible limit;
* :func:`chi_square_test` / :func:`lack_of_fit_warning` — the χ² goodness-of-fit test of a
  least-squares fit against the residuals' stated standard uncertainties (reduced χ², Birge
  ratio, p-value), flagged when p < :data:`LACK_OF_FIT_P`;
* :func:`replicate_lack_of_fit` — the same question where each point was measured several times:
  the lack-of-fit F test (scatter of the point means about the model against the pure error of
  the replicates), flagged at the same p.

References
----------
Birge R. T. (1932), The calculation of errors by the method of least squares, Phys. Rev.
40:207–227 (the ratio R_B = √(χ²/ν)).
Cox M. G. (2002), The evaluation of key comparison data, Metrologia 39:589–595, §5.1 (the χ²
consistency test of a weighted least-squares result, p < 0.05 … 0.001).
NIST/SEMATECH e-Handbook of Statistical Methods (2012), §4.4.4.3 (lack-of-fit test of a model).
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import numpy as np

__all__ = [
    "LACK_OF_FIT_P",
    "SET_VALUE_LIMIT_PERCENT",
    "FitTest",
    "chi_square_test",
    "lack_of_fit_warning",
    "mistaken_factor",
    "replicate_lack_of_fit",
    "set_value_warning",
]

#: p-value below which a fit is flagged: one valid capture in a thousand is flagged by chance.
LACK_OF_FIT_P = 1e-3
#: |measured/set − 1| beyond which a set value is implausible for a calibrated table (%).
SET_VALUE_LIMIT_PERCENT = 20.0
#: How close (relative) a ratio must come to a factor of 10ᵏ or 2^±1 to be named as that factor.
_FACTOR_TOLERANCE = 0.1
#: The mistaken factors named: powers of ten up to 10⁶ and a factor of two (peak vs peak-to-peak,
#: a line count given per channel pair), each with its inverse; π/180 (deg vs rad) too.
_FACTORS = (
    *((10.0**k, f"10^{k}" if k > 1 else "10") for k in range(1, 7)),
    (2.0, "2"),
    (180.0 / math.pi, "180/π (rad vs deg)"),
)


def mistaken_factor(ratio: float, tolerance: float = _FACTOR_TOLERANCE) -> str | None:
    """Name the factor ``ratio`` is close to: ``"×10"``, ``"1/10"``, ``"×2"``, … or None.

    Parameters
    ----------
    ratio : float
        measured / set (dimensionless).
    tolerance : float
        Largest relative distance of ``ratio`` from the factor (dimensionless).
    """
    if not (math.isfinite(ratio) and ratio > 0):
        return None
    for factor, name in _FACTORS:
        if abs(ratio / factor - 1.0) <= tolerance:
            return f"×{name}"
        if abs(ratio * factor - 1.0) <= tolerance:
            return f"1/{name}"
    return None


def set_value_warning(
    quantity: str,
    measured: float,
    set_value: float,
    unit: str,
    check: str,
    *,
    limit_percent: float = SET_VALUE_LIMIT_PERCENT,
) -> str | None:
    """The warning for a measured value implausibly far from the value the user set, else None.

    Implausible: measured/set within 10 % of a power of ten (10…10⁶ or its inverse), of 2 or ½, of
    180/π or π/180 (a count, radius or unit given wrong), or an error beyond ``limit_percent``.

    Parameters
    ----------
    quantity : str
        What was measured, for the message ("amplitude").
    measured, set_value : float
        The measured value and the value set (``unit``).
    unit : str
        Their unit, for the message.
    check : str
        What the user should check, for the message ("--lines, --radius-mm").
    limit_percent : float
        Largest plausible |measured/set − 1| (%).
    """
    if not (math.isfinite(measured) and math.isfinite(set_value)) or set_value == 0:
        return None
    ratio = measured / set_value
    error = 100.0 * (ratio - 1.0)
    factor = mistaken_factor(ratio)
    seen = f"{quantity} {measured:.6g} {unit} is {error:+.4g} % from the set {set_value:.6g} {unit}"
    if factor is not None:
        return f"{seen}: a factor of {factor}, the mark of a setting or unit given wrong — check {check}"
    if abs(error) > limit_percent:
        return f"{seen}, more than ±{limit_percent:g} % that a working table is off: check {check}"
    return None


@dataclasses.dataclass(frozen=True)
class FitTest:
    """χ² goodness-of-fit of a least-squares fit.

    Attributes
    ----------
    chi2 : float
        Σ (residual/u)² (dimensionless).
    dof : int
        Degrees of freedom ν: residuals minus fitted parameters.
    p_value : float
        P(χ²_ν ≥ chi2): the chance that a model that holds scatters this much.
    """

    chi2: float
    dof: int
    p_value: float
    #: The statistic's name in messages: "reduced χ²", or "F" for the replicate test (whose
    #: ``chi2``/``dof`` is F itself, the lack-of-fit over the pure-error mean square).
    statistic: str = "reduced χ²"

    @property
    def reduced_chi2(self) -> float:
        """χ²/ν (1 on average when the model holds and the u are right)."""
        return self.chi2 / self.dof

    @property
    def birge_ratio(self) -> float:
        """R_B = √(χ²/ν): how many times the residuals exceed their stated scatter (Birge 1932)."""
        return math.sqrt(self.reduced_chi2)

    @property
    def lack_of_fit(self) -> bool:
        """True when p < :data:`LACK_OF_FIT_P`."""
        return self.p_value < LACK_OF_FIT_P


def chi_square_test(residuals: Any, u: Any, dof: int) -> FitTest | None:
    """The χ² test of ``residuals`` with standard uncertainties ``u`` and ``dof`` degrees of freedom.

    Parameters
    ----------
    residuals : array_like
        Data minus fitted model (any unit).
    u : array_like or float
        Standard uncertainty of each residual's datum (unit of ``residuals``), from an estimate
        independent of the fit (repeated samples, the noise of a static section).
    dof : int
        Residuals minus fitted parameters.

    Returns
    -------
    FitTest or None
        None when there is nothing to test: ``dof`` < 1, or a u that is not positive and finite.

    References
    ----------
    Cox M. G. (2002), Metrologia 39:589–595, §5.1; Birge R. T. (1932), Phys. Rev. 40:207.
    """
    r0 = np.asarray(residuals, dtype=float)
    uu = np.broadcast_to(np.asarray(u, dtype=float), r0.shape).ravel()
    r = r0.ravel()
    if dof < 1 or r.size == 0 or not (np.all(np.isfinite(uu)) and np.all(uu > 0)):
        return None
    chi2 = float(np.sum((r / uu) ** 2))
    if not math.isfinite(chi2):
        return None
    from rotacal.uncertainty.quantiles import chi2_sf

    return FitTest(chi2, int(dof), chi2_sf(chi2, dof))


def lack_of_fit_warning(what: str, test: FitTest | None, cause: str) -> str | None:
    """The warning for a fit whose χ² test fails (p < :data:`LACK_OF_FIT_P`), else None.

    Parameters
    ----------
    what : str
        The fit, for the message ("the straight line through the rate points").
    test : FitTest or None
        From :func:`chi_square_test`.
    cause : str
        The likely causes and what to check, for the message.
    """
    if test is None or not test.lack_of_fit:
        return None
    p = f"p = {test.p_value:.2g}" if test.p_value >= 1e-16 else "p < 1e-16"
    return (
        f"lack of fit: {what} leaves residuals {test.birge_ratio:.3g} times their expected "
        f"scatter ({test.statistic} {test.reduced_chi2:.3g}, ν = {test.dof}, {p} "
        f"< {LACK_OF_FIT_P:g}): {cause}"
    )


def replicate_lack_of_fit(
    residuals: Any, groups: Any, n_params: int, extra_variance: float = 0.0
) -> FitTest | None:
    """The lack-of-fit F test of a least-squares fit whose points hold replicates.

    With m points (``groups``), N samples and p fitted parameters, the residual sum of squares
    splits into the pure error SS_pe = ΣΣ(r_ij − r̄_i)² (ν = N − m) and the lack of fit
    SS_lof = Σ n_i·r̄_i² (ν = m − p); F = (SS_lof/(m − p))/(SS_pe/(N − m)) follows F(m − p, N − m)
    when the model holds. An ``extra_variance`` v that each point mean carries beyond its repeats
    (the rounding q²/12 of a quantised output, the same at every sample of a point) weighs each
    point by s²/(s²/n_i + v) instead of n_i: F = Σ r̄_i²/(s²/n_i + v)/(m − p), s² = SS_pe/(N − m).

    Parameters
    ----------
    residuals : array_like, (N,)
        Samples minus fitted model (any unit).
    groups : array_like of int, (N,)
        The point each sample belongs to (0 … m − 1).
    n_params : int
        Parameters fitted.
    extra_variance : float
        Variance of each point mean beyond its repeats' scatter (unit of ``residuals`` squared).

    Returns
    -------
    FitTest or None
        ``chi2`` = F·(m − p), ``dof`` = m − p (so ``reduced_chi2`` is F and ``birge_ratio`` √F),
        ``p_value`` = P(F(m − p, N − m) ≥ F); None without replicates or with m ≤ p.

    References
    ----------
    NIST/SEMATECH e-Handbook of Statistical Methods (2012), §4.4.4.3 (lack-of-fit test with
    replicated points); Draper N. R. & Smith H., Applied Regression Analysis, 3rd ed. (1998) §2.1.
    """
    r = np.asarray(residuals, dtype=float).ravel()
    g = np.asarray(groups, dtype=np.intp).ravel()
    if r.size != g.size or r.size == 0:
        return None
    counts = np.bincount(g).astype(float)
    present = counts > 0
    m = int(present.sum())
    df_lof, df_pe = m - int(n_params), r.size - m
    if df_lof < 1 or df_pe < 1:
        return None
    means = np.bincount(g, r)[present] / counts[present]
    ss_pe = float(np.sum((r - (np.bincount(g, r) / np.maximum(counts, 1.0))[g]) ** 2))
    if not ss_pe > 0:
        return None
    s2 = ss_pe / df_pe
    f = float(np.sum(means**2 / (s2 / counts[present] + max(extra_variance, 0.0)))) / df_lof
    from rotacal.uncertainty.quantiles import f_sf

    return FitTest(f * df_lof, df_lof, f_sf(f, df_lof, df_pe), "F")
