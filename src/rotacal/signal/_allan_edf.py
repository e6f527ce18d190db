"""Equivalent degrees of freedom of the overlapping Allan variance (private part of ``allan``).

Greenhall's algorithm for variances based on finite differences (Greenhall & Riley 2003),
specialised to the overlapping (stride S = m), unmodified (filter factor F = m), second-difference
(d = 2) estimator, for the power-law noises α = 2, 1, 0, −1, −2 (S_y(f) ∝ f^α). Whole-array over
the cluster sizes.
"""

from __future__ import annotations

import math

import numpy as np

_D = 2
_JMAX = 100
#: Greenhall & Riley 2003, Table 2 (d = 2): (a0, a1) for α = 1, 0, −1, −2.
_TABLE2 = {1: (790.0, 410.0), 0: (2.0 / 3.0, 1.0 / 3.0), -1: (0.852, 0.375), -2: (1.079, 0.368)}
#: Greenhall & Riley 2003, Table 3 (α = 1, d = 2): (b0, b1).
_TABLE3 = (15.23, 12.0)


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


def _sz(t: np.ndarray, f: np.ndarray, alpha: int) -> np.ndarray:
    """Eq. (9) for d = 2: the second difference of ``sx``."""
    return (
        6.0 * _sx(t, f, alpha)
        - 4.0 * (_sx(t - 1.0, f, alpha) + _sx(t + 1.0, f, alpha))
        + _sx(t - 2.0, f, alpha)
        + _sx(t + 2.0, f, alpha)
    )


def _basic_sum(
    j_: np.ndarray, m_: np.ndarray, s_: np.ndarray, f: np.ndarray, alpha: int
) -> np.ndarray:
    """Eq. (10): ``sz(0)² + (1 − J/M)·sz(J/S)² + 2·Σ_{j=1}^{J−1} (1 − j/M)·sz(j/S)²``."""
    zero = np.zeros_like(s_)
    out = _sz(zero, f, alpha) ** 2 + (1.0 - j_ / m_) * _sz(j_ / s_, f, alpha) ** 2
    jj = np.arange(1, _JMAX, dtype=np.float64)[None, :]
    mask = jj < j_[:, None]
    terms = (1.0 - jj / m_[:, None]) * _sz(jj / s_[:, None], f[:, None], alpha) ** 2
    return out + 2.0 * np.where(mask, terms, 0.0).sum(axis=1)


#: Above this many cluster sizes in the r ≤ d + 1 branch, its basic sum (a smooth function of
#: r = M/m alone, with kinks for α ≥ 0) is evaluated on a log-spaced grid and interpolated
#: (measured relative error ≤ 6e-5 of the edf: immaterial for a confidence interval).
_GRID_ABOVE = 512
_GRID_POINTS = 4096


def _limit_sum(r: np.ndarray, alpha: int) -> np.ndarray:
    """Basic sum of the r ≤ d + 1 branch: J = M = J_max, S = J_max/r, F = S (α = 1) or ∞."""

    def exact(rr: np.ndarray) -> np.ndarray:
        mp = _JMAX / rr
        jm = np.full(mp.size, float(_JMAX))
        f = mp if alpha == 1 else np.full(mp.size, math.inf)
        return _basic_sum(jm, jm, mp, f, alpha)

    if r.size <= _GRID_ABOVE:
        return exact(r)
    lo, hi = float(r.min()), float(r.max())
    grid = np.geomspace(lo, hi, _GRID_POINTS)
    return np.exp(np.interp(np.log(r), np.log(grid), np.log(exact(grid))))


def edf_oadev(n_phase: int, m: np.ndarray, alpha: int) -> np.ndarray:
    """Equivalent degrees of freedom of the overlapping ADEV at cluster sizes ``m``.

    ``n_phase`` phase points; ``alpha`` the power-law exponent of the fractional-frequency (rate)
    noise: 2 white PM, 1 flicker PM, 0 white FM, −1 flicker FM, −2 random-walk FM.
    """
    m = np.asarray(m, dtype=np.float64)
    big_m = n_phase - 2.0 * m  # number of second differences
    out = np.empty(m.size)
    if alpha == 2:
        # White PM: the second differences are correlated at lags 0, m and 2m only, so the basic
        # sum (eq. 10) is exact in closed form: edf = 36·M² / (36M + 32(M − m)₊ + 2(M − 2m)₊).
        var = (
            36.0 * big_m + 32.0 * np.maximum(big_m - m, 0.0) + 2.0 * np.maximum(big_m - 2 * m, 0.0)
        )
        return 36.0 * big_m**2 / var
    s_ = m
    j_ = np.minimum(big_m, (_D + 1) * s_)
    r = big_m / s_
    small = j_ <= _JMAX
    table = ~small & (r > _D + 1)
    limit = ~small & ~table
    a0, a1 = _TABLE2[alpha]
    if alpha == 1:
        b0, b1 = _TABLE3
        if small.any():
            f = m[small]
            inv = _basic_sum(j_[small], big_m[small], s_[small], f, 1)
            out[small] = _sz(np.zeros(f.size), f, 1) ** 2 * big_m[small] / inv
        if table.any():
            rt = r[table]
            out[table] = (b0 + b1 * np.log(m[table])) ** 2 * rt / (a0 - a1 / rt)
        if limit.any():
            inv = _limit_sum(r[limit], 1)
            out[limit] = (b0 + b1 * np.log(m[limit])) ** 2 * _JMAX / inv
        return out
    if small.any():
        f = np.where(m[small] * (_D + 1) <= _JMAX, m[small], math.inf)
        inv = _basic_sum(j_[small], big_m[small], s_[small], f, alpha)
        out[small] = _sz(np.zeros(f.size), f, alpha) ** 2 * big_m[small] / inv
    if table.any():
        rt = r[table]
        out[table] = rt / (a0 - a1 / rt)
    if limit.any():
        inv = _limit_sum(r[limit], alpha)
        sz0 = float(_sz(np.zeros(1), np.full(1, math.inf), alpha)[0])
        out[limit] = sz0**2 * _JMAX / inv
    return out
