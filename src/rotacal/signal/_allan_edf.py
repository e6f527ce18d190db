"""Equivalent degrees of freedom of the finite-difference stability variances (private part of
``allan`` and ``deviations``).

Greenhall's algorithm for variances based on finite differences (Greenhall & Riley 2003) for the
overlapping (stride S = m) estimators: unmodified (filter factor F = m; d = 2 the Allan variance,
d = 3 the Hadamard variance) and modified (F = 1; d = 2 the modified Allan and time variances),
for the power-law noises α = 2, 1, 0, −1, −2 (S_y(f) ∝ f^α); and the total variance's edf
(NIST SP 1065, Tables 8 and 5). Whole-array over the cluster sizes.
"""

from __future__ import annotations

import math

import numpy as np

_JMAX = 100
#: Greenhall & Riley 2003, Table 1 (modified variances, F = 1): (a0, a1) by (α, d).
_TABLE1 = {
    (2, 2): (7.0 / 9.0, 1.0 / 2.0),
    (1, 2): (0.997, 0.616),
    (0, 2): (1.033, 0.607),
    (-1, 2): (1.048, 0.534),
    (-2, 2): (1.302, 0.535),
}
#: Greenhall & Riley 2003, Table 2 (unmodified variances, F = m): (a0, a1) by (α, d).
_TABLE2 = {
    (1, 2): (790.0, 410.0),
    (0, 2): (2.0 / 3.0, 1.0 / 3.0),
    (-1, 2): (0.852, 0.375),
    (-2, 2): (1.079, 0.368),
    (1, 3): (9950.0, 6520.0),
    (0, 3): (7.0 / 9.0, 1.0 / 2.0),
    (-1, 3): (0.997, 0.617),
    (-2, 3): (1.033, 0.607),
}
#: Greenhall & Riley 2003, Table 3 (α = 1, unmodified): (b0, b1) by d.
_TABLE3 = {2: (15.23, 12.0), 3: (47.8, 40.0)}
#: NIST SP 1065 (Riley 2008), Table 8: edf of the total variance ≈ b·(T/τ) − c, by α.
_TOTVAR_TABLE = {0: (1.50, 0.0), -1: (1.17, 0.22), -2: (0.93, 0.36)}


def _sw(t: np.ndarray, alpha: int) -> np.ndarray:
    """Greenhall & Riley 2003, eq. (7): the generalised autocovariance of the phase."""
    at = np.abs(t)
    if alpha == 2:
        return -at
    if alpha == 0:
        return at**3
    if alpha == -2:
        return at**5
    if alpha == -4:
        return at**7
    power = {1: 2, -1: 4, -3: 6}[alpha]
    safe = np.where(at > 0, at, 1.0)
    return np.where(at > 0, t**power * np.log(safe), 0.0)


def _sx(t: np.ndarray, f: np.ndarray, alpha: int) -> np.ndarray:
    """Eq. (8): the filter of the unmodified variance (``f`` = F, ``inf`` for the limit)."""
    inf = np.isinf(f)
    fs = np.where(inf, 1.0, f)
    finite = fs**2 * (2.0 * _sw(t, alpha) - _sw(t - 1.0 / fs, alpha) - _sw(t + 1.0 / fs, alpha))
    if not inf.any():
        return finite
    return np.where(inf, _sw(t, alpha + 2), finite)


def _sz(t: np.ndarray, f: np.ndarray, alpha: int, d: int = 2) -> np.ndarray:
    """Eq. (9): the d-th difference of ``sx``, Σ_k (−1)^k·C(2d, d + k)·sx(t + k), |k| ≤ d."""
    out = math.comb(2 * d, d) * _sx(t, f, alpha)
    for k in range(1, d + 1):
        out = out + (-1) ** k * math.comb(2 * d, d + k) * (
            _sx(t - k, f, alpha) + _sx(t + k, f, alpha)
        )
    return out


def _basic_sum(
    j_: np.ndarray, m_: np.ndarray, s_: np.ndarray, f: np.ndarray, alpha: int, d: int = 2
) -> np.ndarray:
    """Eq. (10): ``sz(0)² + (1 − J/M)·sz(J/S)² + 2·Σ_{j=1}^{J−1} (1 − j/M)·sz(j/S)²``."""
    zero = np.zeros_like(s_)
    out = _sz(zero, f, alpha, d) ** 2 + (1.0 - j_ / m_) * _sz(j_ / s_, f, alpha, d) ** 2
    jj = np.arange(1, _JMAX, dtype=np.float64)[None, :]
    mask = jj < j_[:, None]
    terms = (1.0 - jj / m_[:, None]) * _sz(jj / s_[:, None], f[:, None], alpha, d) ** 2
    return out + 2.0 * np.where(mask, terms, 0.0).sum(axis=1)


#: Above this many cluster sizes in the r ≤ d + 1 branch, its basic sum (a smooth function of
#: r = M/m alone, with kinks for α ≥ 0) is evaluated on a log-spaced grid and interpolated
#: (measured relative error ≤ 6e-5 of the edf: immaterial for a confidence interval).
_GRID_ABOVE = 512
_GRID_POINTS = 4096


def _limit_sum(r: np.ndarray, alpha: int, d: int, filt: str) -> np.ndarray:
    """Basic sum of the r ≤ d + 1 branch: J = M = J_max, S = J_max/r and F = 1 (``filt``
    "one", modified), F = S ("s", unmodified α = 1) or F = ∞ ("inf")."""

    def exact(rr: np.ndarray) -> np.ndarray:
        mp = _JMAX / rr
        jm = np.full(mp.size, float(_JMAX))
        f = {"one": np.ones(mp.size), "s": mp, "inf": np.full(mp.size, math.inf)}[filt]
        return _basic_sum(jm, jm, mp, f, alpha, d)

    if r.size <= _GRID_ABOVE:
        return exact(r)
    lo, hi = float(r.min()), float(r.max())
    grid = np.geomspace(lo, hi, _GRID_POINTS)
    return np.exp(np.interp(np.log(r), np.log(grid), np.log(exact(grid))))


def _white_pm_edf(big_m: np.ndarray, m: np.ndarray, d: int) -> np.ndarray:
    """White PM, unmodified: the d-th differences are correlated at lags q·m (|q| ≤ d) only,
    with correlation ∝ (−1)^q·C(2d, d + q), so the basic sum is exact in closed form:
    edf = M²·C(2d,d)² / Σ_q C(2d, d + q)²·(M − |q|·m)₊ (for d = 2: 36M²/(36M + 32(M − m)₊ +
    2(M − 2m)₊)); where M ≥ d·m it is Greenhall & Riley's case 4, M/(a0 − a1/r)."""
    var = math.comb(2 * d, d) ** 2 * big_m
    for q in range(1, d + 1):
        var = var + 2.0 * math.comb(2 * d, d + q) ** 2 * np.maximum(big_m - q * m, 0.0)
    return math.comb(2 * d, d) ** 2 * big_m**2 / var


def edf_greenhall(
    n_phase: int, m: np.ndarray, alpha: int, d: int = 2, modified: bool = False
) -> np.ndarray:
    """Equivalent degrees of freedom of an overlapping finite-difference variance.

    Greenhall & Riley 2003, §3–4 and Tables 1–3: the variance of the d-th difference of the
    phase at cluster sizes ``m`` (unmodified, F = m: d = 2 Allan, d = 3 Hadamard; ``modified``,
    F = 1: d = 2 modified Allan and time variance), overlapping (S = m), from ``n_phase`` phase
    points, for the power-law exponent ``alpha`` of the rate (fractional-frequency) noise:
    2 white PM, 1 flicker PM, 0 white FM, −1 flicker FM, −2 random-walk FM. Dimensionless.
    """
    m = np.asarray(m, dtype=np.float64)
    span = m * (d + 1) if modified else 1.0 + m * d  # L, the filter's length in phase points
    big_m = n_phase - span + 1.0  # M, the number of terms
    if alpha == 2 and not modified:
        return _white_pm_edf(big_m, m, d)
    out = np.empty(m.size)
    s_ = m
    j_ = np.minimum(big_m, (d + 1) * s_)
    r = big_m / s_
    small = j_ <= _JMAX
    table = ~small & (r > d + 1)
    limit = ~small & ~table
    if modified:
        a0, a1 = _TABLE1[(alpha, d)]
        ones = np.ones(m.size)
        sz0 = float(_sz(np.zeros(1), np.ones(1), alpha, d)[0])
        if small.any():
            out[small] = (
                sz0**2
                * big_m[small]
                / _basic_sum(j_[small], big_m[small], s_[small], ones[small], alpha, d)
            )
        if table.any():
            out[table] = r[table] / (a0 - a1 / r[table])
        if limit.any():
            out[limit] = sz0**2 * _JMAX / _limit_sum(r[limit], alpha, d, "one")
        return out
    a0, a1 = _TABLE2[(alpha, d)]
    if alpha == 1:
        b0, b1 = _TABLE3[d]
        if small.any():
            f = m[small]
            inv = _basic_sum(j_[small], big_m[small], s_[small], f, 1, d)
            out[small] = _sz(np.zeros(f.size), f, 1, d) ** 2 * big_m[small] / inv
        if table.any():
            rt = r[table]
            out[table] = (b0 + b1 * np.log(m[table])) ** 2 * rt / (a0 - a1 / rt)
        if limit.any():
            inv = _limit_sum(r[limit], 1, d, "s")
            out[limit] = (b0 + b1 * np.log(m[limit])) ** 2 * _JMAX / inv
        return out
    if small.any():
        f = np.where(m[small] * (d + 1) <= _JMAX, m[small], math.inf)
        inv = _basic_sum(j_[small], big_m[small], s_[small], f, alpha, d)
        out[small] = _sz(np.zeros(f.size), f, alpha, d) ** 2 * big_m[small] / inv
    if table.any():
        rt = r[table]
        out[table] = rt / (a0 - a1 / rt)
    if limit.any():
        inv = _limit_sum(r[limit], alpha, d, "inf")
        sz0 = float(_sz(np.zeros(1), np.full(1, math.inf), alpha, d)[0])
        out[limit] = sz0**2 * _JMAX / inv
    return out


def edf_oadev(n_phase: int, m: np.ndarray, alpha: int) -> np.ndarray:
    """Equivalent degrees of freedom of the overlapping ADEV at cluster sizes ``m``
    (:func:`edf_greenhall` with d = 2, unmodified)."""
    return edf_greenhall(n_phase, m, alpha, 2, False)


def edf_totdev(n_phase: int, m: np.ndarray, alpha: int) -> np.ndarray:
    """Equivalent degrees of freedom of the total variance at cluster sizes ``m``.

    NIST SP 1065 (Riley 2008), §5.2.11 and Table 8: edf = b·(T/τ) − c for white, flicker and
    random-walk FM (α = 0, −1, −2), T/τ = N/m with N phase points; for the PM noises, where
    Table 8 gives nothing, the simple formulas of Table 5 (Howe, Allan & Barnes 1981): α = 2
    (N + 1)(N − 2m)/(2(N − m)), α = 1 exp(√(ln((N − 1)/2m)·ln((2m + 1)(N − 1)/4))) — what
    Stable32 prints (tested on its GPS 1PPS run) and allantools computes.
    """
    m = np.asarray(m, dtype=np.float64)
    n = float(n_phase)
    if alpha in _TOTVAR_TABLE:
        b, c = _TOTVAR_TABLE[alpha]
        return b * (n / m) - c
    if alpha == 2:
        return (n + 1.0) * (n - 2.0 * m) / (2.0 * (n - m))
    return np.exp(
        np.sqrt(np.log((n - 1.0) / (2.0 * m)) * np.log((2.0 * m + 1.0) * (n - 1.0) / 4.0))
    )
