"""Coverage factor k = t_p(ν) and the Welch–Satterthwaite effective degrees of freedom.

References
----------
JCGM 100:2008 (GUM) Annex G: G.3, G.4 (eq. (G.2b)), Table G.2.
"""

from __future__ import annotations

import functools
import math
import sys
import threading
from statistics import NormalDist
from typing import TYPE_CHECKING, Any

import numpy as np

from rotacal.errors import ConfigError

if TYPE_CHECKING:
    pass

from rotacal.uncertainty._checked import _number

__all__ = ["coverage_factor", "prefetch_quantiles", "welch_satterthwaite"]


def prefetch_quantiles() -> None:
    """Start importing the quantile functions (scipy.special, ~0.2 s) in a background thread.

    For a command that will compute coverage factors after a long analysis: on a machine with a
    free core the import then runs beside the analysis's whole-array work instead of after it.
    :func:`coverage_factor` imports them as it would anyway (waiting for this import if it is
    still running); a failure here is left for that import to report.
    """
    if "scipy.special" in sys.modules:
        return

    def work() -> None:
        try:
            import scipy.special  # noqa: F401
        except BaseException:  # coverage_factor's own import reports it
            return

    threading.Thread(target=work, name="rotacal-import-quantiles", daemon=True).start()


def coverage_factor(dof: float, p: float = 0.95, *, truncate: bool = True) -> float:
    """The coverage factor k_p = t_p(ν) of a two-sided interval with coverage probability p.

    Parameters
    ----------
    dof : float
        Degrees of freedom ν (> 0; ``math.inf`` gives the normal quantile, 1.959964 for p = 0.95).
    p : float, optional
        Coverage probability, 0 < p < 1 (e.g. 0.95, 0.99). Default 0.95.
    truncate : bool, optional
        Truncate a non-integer ν to the next lower integer before taking the t quantile, as GUM
        G.4.1 note 1 allows (the other option it names is interpolating Table G.2); the
        conservative choice, and the one the GUM's own examples use (H.1: ν_eff = 16.75 →
        t_99(16) = 2.92). A ν within 1e-9 (relative) below an integer counts as that integer.
        Default True; False uses the t distribution at the fractional ν.

    Returns
    -------
    float
        k_p (dimensionless), so that U_p = k_p·u_c.

    Raises
    ------
    ConfigError
        When p is not in (0, 1), ν is NaN or ≤ 0, or ν < 1 with ``truncate``.

    Notes
    -----
    SciPy's ``special.stdtrit`` (``special.ndtri`` for ν = inf) gives the quantile, except from
    ν = :data:`LARGE_DOF` on, where the series in 1/ν of Fisher and Cornish gives it to within
    an ulp or two of SciPy's without importing SciPy (0.2–0.9 s of a command's start; the
    budgets of fits over millions of samples have ν of that size).

    References
    ----------
    JCGM 100:2008 (GUM), G.3.2–G.3.4, G.4.1 (step 3 and note 1), Table G.2; §6.3.
    Abramowitz, M. and Stegun, I. A. (1964), Handbook of Mathematical Functions, 26.7.5.
    """
    pf = _number(p, "coverage probability p")
    if not 0.0 < pf < 1.0:
        raise ConfigError(f"coverage probability p = {pf!r} must be in (0, 1), e.g. 0.95.")
    nu = _number(dof, "degrees of freedom ν")
    if math.isnan(nu) or nu <= 0.0:
        raise ConfigError(f"degrees of freedom ν = {nu!r} must be > 0 (math.inf for none).")
    tail = 0.5 * (1.0 - pf)
    if math.isinf(nu):
        return _upper_quantile(tail, math.inf)
    if truncate:
        nu_t = math.floor(nu + 1e-9 * max(1.0, nu))
        if nu_t < 1:
            raise ConfigError(
                f"ν = {nu:g} truncates to 0 (GUM G.4.1 note 1); an uncertainty with fewer than one "
                "degree of freedom has no t-based coverage factor — give k or more readings."
            )
        nu = float(nu_t)
    return _upper_quantile(tail, nu)


@functools.lru_cache(maxsize=4096)
def _upper_quantile(tail: float, nu: float) -> float:
    """The upper ``tail`` quantile of Student's t with ν degrees of freedom (the normal's for
    ν = inf), kept by its arguments: scipy takes ~0.3 ms a call, and the budgets of every
    calibration ask for the same few (p = 0.95, integer ν) again and again."""
    # scipy.special, not scipy.stats: the same functions (stats.norm.isf(q) is -ndtri(q),
    # stats.t.isf(q, ν) is -stdtrit(ν, q), bit for bit; a test checks it) at ~0.2 s of import
    # instead of ~0.6 s, paid only when a quantile is computed
    if math.isfinite(nu) and nu >= LARGE_DOF:
        return _t_upper_quantile_large_dof(tail, nu)
    from scipy import special

    if math.isinf(nu):
        return float(-special.ndtri(tail))
    return float(-special.stdtrit(nu, tail))


#: From this ν on, the t quantile comes from its asymptotic series in 1/ν (error below 1e-15
#: relative, tested against SciPy), which needs no SciPy import.
LARGE_DOF = 1e5


def _t_upper_quantile_large_dof(tail: float, nu: float) -> float:
    """The upper ``tail`` quantile of Student's t at a large ν (≥ :data:`LARGE_DOF`) from the
    normal quantile z by the series t = z + g₁/ν + g₂/ν² + g₃/ν³ + g₄/ν⁴ (Fisher and Cornish
    (1960); Abramowitz and Stegun (1964), 26.7.5): its first omitted term is below 1e-20 of z at
    ν ≥ 1e5, so the result is z's own rounding (``statistics.NormalDist``, Wichura's AS 241)."""
    z = -NormalDist().inv_cdf(tail)
    z2 = z * z
    g1 = (z2 + 1.0) * z / 4.0
    g2 = ((5.0 * z2 + 16.0) * z2 + 3.0) * z / 96.0
    g3 = (((3.0 * z2 + 19.0) * z2 + 17.0) * z2 - 15.0) * z / 384.0
    g4 = ((((79.0 * z2 + 776.0) * z2 + 1482.0) * z2 - 1920.0) * z2 - 945.0) * z / 92160.0
    return z + (g1 + (g2 + (g3 + g4 / nu) / nu) / nu) / nu


def welch_satterthwaite(contributions: Any, dofs: Any) -> float:
    """The effective degrees of freedom of a sum of independent uncertainty components.

    ``ν_eff = u_c⁴ / Σ_i (u_i⁴/ν_i)`` with ``u_c² = Σ_i u_i²``, where u_i = c_i·u(x_i).

    Parameters
    ----------
    contributions : array_like (n,)
        The components u_i(y) = c_i·u(x_i) (same unit as y; signs are ignored).
    dofs : array_like (n,)
        Their degrees of freedom ν_i (> 0; ``math.inf`` for exactly known ones).

    Returns
    -------
    float
        ν_eff ≥ min ν_i; ``math.inf`` when every ν_i with a non-zero component is infinite (or
        every component is 0).

    Raises
    ------
    ConfigError
        Different lengths, no components, a non-finite component, or ν ≤ 0 / NaN.

    References
    ----------
    JCGM 100:2008 (GUM), G.4.1, eq. (G.2b); Welch (1947), Satterthwaite (1946).
    """
    c = np.asarray(contributions, dtype=np.float64).ravel()
    nu = np.asarray(dofs, dtype=np.float64).ravel()
    if c.size != nu.size:
        raise ConfigError(
            f"welch_satterthwaite got {c.size} contributions and {nu.size} degrees of freedom; "
            "give one ν per contribution."
        )
    if c.size == 0:
        raise ConfigError("welch_satterthwaite needs at least one contribution.")
    if not np.all(np.isfinite(c)):
        i = int(np.flatnonzero(~np.isfinite(c))[0])
        raise ConfigError(f"contribution {i} = {float(c[i])!r} is not finite; give c_i·u(x_i).")
    if np.any(np.isnan(nu)) or np.any(nu <= 0.0):
        i = int(np.flatnonzero(np.isnan(nu) | (nu <= 0.0))[0])
        raise ConfigError(f"degrees of freedom ν_{i} = {nu[i]!r} must be > 0 (math.inf for none).")
    scale = float(np.max(np.abs(c)))
    if scale == 0.0:
        return math.inf
    w = (c / scale) ** 2
    finite = np.isfinite(nu)
    den = float(np.sum(w[finite] ** 2 / nu[finite]))
    if den == 0.0:
        return math.inf
    return float(np.sum(w) ** 2 / den)
