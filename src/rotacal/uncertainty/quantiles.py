"""Quantiles and tail probabilities of the normal, Student-t, χ² and F distributions, from
``scipy.special`` (private).

The same formulas ``scipy.stats`` evaluates for ``norm``, ``t``, ``chi2`` and ``f`` (its ``_ppf``,
``_isf``, ``_sf`` and ``_pdf`` of each), equal to the bit (tests/uncertainty/test_quantiles.py), without
importing ``scipy.stats``: that import costs 0.4–0.5 s, half of a gyro command's whole run, where
only these few numbers are needed.
"""

from __future__ import annotations

import numpy as np

__all__ = ["chi2_ppf", "chi2_sf", "f_sf", "norm_isf", "norm_pdf", "norm_ppf", "t_ppf"]

_SQRT_2PI = np.sqrt(2.0 * np.pi)


def norm_ppf(p: float) -> float:
    """Standard normal quantile z with P(Z ≤ z) = p (0 < p < 1): ``scipy.stats.norm.ppf``."""
    from scipy import special

    return float(special.ndtri(p))


def norm_isf(q: float) -> float:
    """Standard normal z with P(Z > z) = q (0 < q < 1): ``scipy.stats.norm.isf``."""
    from scipy import special

    return float(-special.ndtri(q))


def norm_pdf(z: float) -> float:
    """Standard normal density at z: ``scipy.stats.norm.pdf``."""
    # NumPy's exp, as SciPy's: the libm one differs in the last bit now and then
    return float(np.exp(-(np.float64(z) ** 2) / 2.0) / _SQRT_2PI)


def t_ppf(p: float, dof: float) -> float:
    """Student-t quantile with ν = ``dof`` > 0 degrees of freedom: ``scipy.stats.t.ppf``."""
    from scipy import special

    return float(special.stdtrit(dof, p))


def chi2_ppf(p: float, dof: float) -> float:
    """χ² quantile with ν = ``dof`` > 0: 2·P⁻¹(ν/2, p), P the regularised lower incomplete gamma
    function (``scipy.stats.chi2.ppf``)."""
    from scipy import special

    return float(2.0 * special.gammaincinv(dof / 2.0, p))


def chi2_sf(x: float, dof: float) -> float:
    """P(χ²_ν > x), ν = ``dof`` > 0: ``scipy.stats.chi2.sf``."""
    from scipy import special

    return float(special.chdtrc(dof, x))


def f_sf(x: float, dfn: float, dfd: float) -> float:
    """P(F > x) of Fisher's F with (``dfn``, ``dfd``) degrees of freedom: ``scipy.stats.f.sf``."""
    from scipy import special

    return float(special.fdtrc(dfn, dfd, x))
