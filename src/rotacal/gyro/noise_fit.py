"""IEEE Std 952 noise identification: a generalised least-squares fit of all five terms.

The Allan variance of a gyro whose noise is the sum of the five processes of IEEE Std 952-1997
Annex C is the sum of their Allan variances (Table C.1; eqs. C.5, C.11, C.21, C.25, C.29),

    σ²(τ) = 3Q²/τ² + N²/τ + (2 ln 2/π)·B² + K²τ/3 + R²τ²/2,

linear in c = (Q², N², B², K², R²) ≥ 0 (El-Sheimy, Hou & Niu 2008, IEEE TIM 57(1), Table I and
§III.F, fit the same sum). :func:`fit_noise_terms` fits it to the whole overlapping Allan
variance curve by non-negative generalised least squares: the points of one record are strongly
correlated (they use the same samples), so the weight matrix is the inverse of the *covariance of
the estimator* itself, computed for the fitted mixture (:func:`avar_covariance`), and the fit is
iterated until the covariance and the coefficients agree. The coefficients' covariance is then
(AᵀA)⁻¹ of the whitened design. When the curve departs from the five-term model more than its
noise allows (χ² > ν: a real sensor's anti-aliasing filter at the shortest τ, a periodic error, a
bias instability flat over a band only), a relative model discrepancy δ is added to every
point's standard deviation until χ² = ν (Paule & Mandel 1982): an honest widening, never a
narrowing, which also keeps GLS from a fit that runs outside strongly correlated points that no
member of the model can follow (Peelle's pertinent puzzle).

Covariance of the estimator. σ̂²(m) = Σ_k d_k(m)²/(2m²τ₀²K_m) with d_k(m) = x_{k+2m} − 2x_{k+m} +
x_k the second differences of the phase (angle) x. For Gaussian noise, cov(σ̂²_a, σ̂²_b) =
2·Σ_{k,l} R_ab(l − k)²/(K_a·K_b·4a²b²τ₀⁴), where R_ab(δ) = Σ_{p,r} c_p c_r γ(δ + r − p) is the
cross-covariance of the two second differences and γ the (generalised) autocovariance of the
phase (Greenhall & Riley 2003, §2 and eqs. 7–8): a spike for white PM (Q), −|t|/2 for white FM
(N), t²·ln|t| for flicker FM (B), |t|³ for random-walk FM (K), each scaled so that R_mm(0) gives
the term's Allan variance. R is linear in c, so the covariance is a quadratic form in c whose
moments are computed once per record length and τ grid. A rate ramp is deterministic: it adds only
the cross term 4·D_a·D_b·Σ R (D = the ramp's second difference).
"""

from __future__ import annotations

import dataclasses
import functools
import math
from typing import Any

import numpy as np
from scipy.optimize import nnls
from scipy.special import stdtrit

from rotacal.errors import CaptureError

__all__ = [
    "NOISE_TERM_NAMES",
    "TERM_SLOPES",
    "NoiseFit",
    "avar_covariance",
    "fit_noise_terms",
    "term_avar",
]

#: The five terms of IEEE Std 952-1997 Annex C, in the order of c.
NOISE_TERM_NAMES = (
    "quantization",
    "angle_random_walk",
    "bias_instability",
    "rate_random_walk",
    "rate_ramp",
)
#: Log-log slope of σ(τ) of each term (Table C.1): −1, −½, 0, +½, +1.
TERM_SLOPES = (-1.0, -0.5, 0.0, 0.5, 1.0)
#: (2 ln 2)/π: the Allan variance of flicker rate noise over B² (IEEE Std 952, eq. C.21).
_FLICKER = 2.0 * math.log(2.0) / math.pi
#: Fewest independent clusters N/m for a point of the curve to enter the fit.
MIN_CLUSTERS = 4.0
#: Points per decade kept: neighbours closer than this add nothing but ill-conditioning.
POINTS_PER_DECADE = 6
#: Lags at which a kernel correlation is evaluated at most (a smooth sum; coarser for large m).
_MAX_LAGS = 1024
#: GLS iterations at most (the covariance follows the coefficients).
_MAX_ITER = 8
#: Fewest points fitted (five terms and one degree of freedom).
_MIN_POINTS = 6
#: A shortest-τ point this many of its own standard deviations below the fit is left out (and
#: the fit repeated): a sensor's filter or internal averaging lowers σ(τ) at τ of a few samples,
#: which no term of the model can follow.
_FILTER_Z = 4.0
#: Bisection steps for the model discrepancy δ (log δ from 1e-6 to 10: to 2 % of δ).
_BISECTIONS = 24
#: Coverage probability of the stated intervals.
COVERAGE = 0.95


def term_avar(tau_s: Any) -> np.ndarray:
    """The Allan variance of each term per unit c: (n, 5) columns 3/τ², 1/τ, 2 ln2/π, τ/3, τ²/2.

    ``tau_s`` in s; c = (Q², N², B², K², R²) in the rate unit u: Q in u·s, N in u·√s, B in u,
    K in u/√s, R in u/s (IEEE Std 952-1997, Table C.1).
    """
    t = np.asarray(tau_s, dtype=np.float64)
    return np.stack([3.0 / t**2, 1.0 / t, np.full_like(t, _FLICKER), t / 3.0, t**2 / 2.0], axis=-1)


# ==================================================================== covariance of the estimator
def _gamma(t: np.ndarray, kind: int) -> np.ndarray:
    """Generalised autocovariance of the phase at lag t (samples) of term ``kind`` (1 … 3).

    1 white FM: −|t|/2; 2 flicker FM: t²·ln|t|; 3 random-walk FM: |t|³ (Greenhall & Riley 2003,
    eqs. 7–8 with α = 0, −1, −2). White PM (0) is a spike, handled apart.
    """
    at = np.abs(t)
    if kind == 1:
        return -0.5 * at
    if kind == 2:
        safe = np.where(at > 0, at, 1.0)
        return at * at * np.log(safe)
    return at**3


def _scales(tau0: float) -> np.ndarray:
    """s_t with R = Σ c_t·s_t·Σ c_p c_r γ_t: E[d_m²] = 2m²τ₀²·c_t·g_t(mτ₀) for every m.

    Σ c_p c_r γ(p − r) over the (1, −2, 1) taps at 0, m, 2m is 6 (spike), 2m (−|t|/2),
    8 ln2·m² (t² ln|t|), 8m³ (|t|³); the term variances are 3/τ², 1/τ, 2 ln2/π, τ/3.
    """
    return np.array([1.0, tau0, tau0**2 / (2.0 * math.pi), tau0**3 / 12.0])


_TAPS = np.array([1.0, -2.0, 1.0])


def _kernels(a: int, b: int, lags: np.ndarray) -> np.ndarray:
    """Σ_{p,r} c_p c_r γ_t(δ + r − p) at ``lags`` for t = 1, 2, 3: shape (3, lags)."""
    pa = np.array([0, a, 2 * a], dtype=np.float64)
    pb = np.array([0, b, 2 * b], dtype=np.float64)
    shift = (pb[None, :] - pa[:, None]).ravel()
    w = (_TAPS[:, None] * _TAPS[None, :]).ravel()
    arg = lags[None, :] + shift[:, None]
    return np.stack([(w[:, None] * _gamma(arg, t)).sum(axis=0) for t in (1, 2, 3)])


def _counts(ka: int, kb: int, lags: np.ndarray) -> np.ndarray:
    """#{(k, l): 0 ≤ k < K_a, 0 ≤ l < K_b, l − k = δ}."""
    return np.maximum(0.0, np.minimum(ka, kb - lags) - np.maximum(0.0, -lags))


@functools.lru_cache(maxsize=4096)
def _pair_moments(a: int, b: int, n_phase: int) -> np.ndarray:
    """The (5, 5) moments M with K_a·K_b·cov-numerator = Σ_tu c_t c_u·M_tu (before scaling).

    Stochastic t, u ∈ {Q, N, B, K}: M_tu = Σ_δ n(δ)·C_t(δ)·C_u(δ); ramp row: Σ_δ n(δ)·C_t(δ).
    Kept by pair (read-only; 4096 pairs ≈ 2 MB), free of τ₀: records of one length whose τ₀
    differ (a clock error, each time column's own) choose other cluster sizes but share many
    pairs, where the whole (n, n) set of :func:`_moments` would be computed anew.
    """
    ka, kb = n_phase - 2 * a, n_phase - 2 * b
    reach = 2 * max(a, b)  # flicker FM correlates beyond the overlap (decays as δ⁻²)
    lo, hi = max(-(ka - 1), -(2 * b + reach)), min(kb - 1, 2 * a + reach)
    q = max(1, (hi - lo) // _MAX_LAGS)
    d = np.arange(lo, hi + 1, q, dtype=np.float64)
    n = _counts(ka, kb, d) * q
    c = _kernels(a, b, d)  # (3, lags)
    out = np.zeros((5, 5))
    out[1:4, 1:4] = (c * n) @ c.T
    out[4, 1:4] = c @ n
    # white PM: R is a spike at δ = p − r; its products with the smooth kernels there
    spike: dict[float, float] = {}
    for p_, cp in zip((0, a, 2 * a), _TAPS, strict=True):
        for r_, cr in zip((0, b, 2 * b), _TAPS, strict=True):
            spike[float(p_ - r_)] = spike.get(float(p_ - r_), 0.0) + cp * cr
    sl = np.array(list(spike))
    sv = np.array(list(spike.values()))
    sn = _counts(ka, kb, sl)
    sc = _kernels(a, b, sl)
    out[0, 0] = float(np.sum(sn * sv * sv))
    out[0, 1:4] = out[1:4, 0] = (sc * (sn * sv)).sum(axis=1)
    out[4, 0] = float(np.sum(sn * sv))
    out.flags.writeable = False
    return out


@functools.lru_cache(maxsize=8)
def _moments(ms: tuple[int, ...], n_phase: int, tau0: float) -> np.ndarray:
    """(n, n, 5, 5): cov(σ̂²_i, σ̂²_j) = Σ_tu c_t c_u·M[i, j, t, u] (rate unit⁴)."""
    s = np.concatenate((_scales(tau0), [1.0]))
    k = len(ms)
    out = np.empty((k, k, 5, 5))
    for i, a in enumerate(ms):
        for j in range(i, k):
            b = ms[j]
            raw = _pair_moments(a, b, n_phase)
            norm = (n_phase - 2 * a) * (n_phase - 2 * b) * 4.0 * a * a * b * b * tau0**4
            m = np.zeros((5, 5))
            m[:4, :4] = 2.0 * raw[:4, :4] * np.outer(s[:4], s[:4]) / norm
            # ramp × noise: 4·D_a·D_b·Σ n·R with D = R_ramp·m²τ₀² (c_R = R²); split over (4, t), (t, 4)
            half = 0.5 * raw[4, :4] * s[:4] / ((n_phase - 2 * a) * (n_phase - 2 * b))
            m[4, :4] = half
            m[:4, 4] = half
            out[i, j] = m
            out[j, i] = m
    return out


def avar_covariance(cluster_sizes: Any, n_phase: int, tau0_s: float, c: Any) -> np.ndarray:
    """Covariance of the overlapping Allan variance estimates of one record at several τ.

    Parameters
    ----------
    cluster_sizes : array_like of int
        m_i (samples per cluster), 1 ≤ m ≤ (N − 1)/2.
    n_phase : int
        Phase points N (rate samples + 1).
    tau0_s : float, s
        Sampling interval.
    c : array_like, 5 values
        (Q², N², B², K², R²) of the noise, rate unit u based (see :func:`term_avar`).

    Returns
    -------
    ndarray (n, n)
        cov(σ̂²(τ_i), σ̂²(τ_j)), in u⁴, for Gaussian noise of the five-term mixture.

    References
    ----------
    C. A. Greenhall and W. J. Riley, "Uncertainty of stability variances based on finite
    differences", Proc. 35th PTTI (2003), §2 (the estimator as a quadratic form, eqs. 7–9);
    IEEE Std 952-1997, Annex C (the five terms).
    """
    ms = tuple(int(m) for m in np.asarray(cluster_sizes).ravel())
    cc = np.asarray(c, dtype=np.float64)
    return np.einsum("ijtu,t,u->ij", _moments(ms, int(n_phase), float(tau0_s)), cc, cc)


# ============================================================================== the fit
@dataclasses.dataclass(frozen=True)
class NoiseFit:
    """The five IEEE 952 terms fitted to one Allan variance curve.

    Attributes
    ----------
    coefficients : ndarray (5,)
        Q, N, B, K, R (rate unit u: u·s, u·√s, u, u/√s, u/s); 0 for a term the fit sets to zero.
    expanded : ndarray (5,)
        U at :data:`COVERAGE`: the interval [max(0, C − U), C + U] holds the 95 % interval of c
        mapped through the square root (see :func:`fit_noise_terms`).
    k : float
        Coverage factor, Student's t at ``dof``.
    dof : int
        Points minus terms fitted (ν of the GLS residual).
    c, c_u : ndarray (5,)
        The variance coefficients (Q², N², B², K², R²) and their standard uncertainties.
    tau_s, avar, avar_fit : ndarray
        The points fitted, their Allan variance and the model's.
    chi2 : float
        Whitened residual sum of squares (≤ ν: the discrepancy makes it ν when it is not 0).
    dropped : int
        Shortest-τ points left out as below the model (a sensor's own filter; see the Notes of
        :func:`fit_noise_terms`).
    discrepancy : float
        δ, the relative model discrepancy added to each point's standard deviation (in
        quadrature, δ·σ̂²) so that χ² = ν; 0 when the five-term model fits within the
        estimator's own covariance.
    """

    coefficients: np.ndarray
    expanded: np.ndarray
    k: float
    dof: int
    c: np.ndarray
    c_u: np.ndarray
    tau_s: np.ndarray
    avar: np.ndarray
    avar_fit: np.ndarray
    chi2: float
    discrepancy: float
    dropped: int = 0

    def intervals(self) -> np.ndarray:
        """(5, 2): the 95 % interval [max(0, C − U), C + U] of each coefficient."""
        c = self.coefficients
        return np.stack([np.maximum(0.0, c - self.expanded), c + self.expanded], axis=1)

    def term_adev(self, tau_s: Any) -> np.ndarray:
        """(5, n): the Allan deviation of each fitted term alone at ``tau_s`` (rate unit)."""
        return np.sqrt(term_avar(tau_s) * self.c).T

    def total_adev(self, tau_s: Any) -> np.ndarray:
        """The fitted model's Allan deviation at ``tau_s`` (rate unit)."""
        return np.sqrt(term_avar(tau_s) @ self.c)


def _select(tau: np.ndarray, sig: np.ndarray, ms: np.ndarray, n_phase: int) -> np.ndarray:
    """Indices of the points fitted: ≥ MIN_CLUSTERS clusters, σ > 0, ≤ POINTS_PER_DECADE."""
    keep = np.flatnonzero(((n_phase - 1) / ms >= MIN_CLUSTERS) & (sig > 0) & np.isfinite(sig))
    if not keep.size:
        return keep
    bins = np.floor(np.log10(tau[keep]) * POINTS_PER_DECADE).astype(np.int64)
    first = np.ones(keep.size, dtype=bool)
    first[1:] = bins[1:] != bins[:-1]
    return keep[first]


def _gls_nnls(g: np.ndarray, v: np.ndarray, cov: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Non-negative GLS: min ‖L⁻¹(v − G·c)‖ with c ≥ 0, LLᵀ = cov. Returns c and L⁻¹G."""
    scale = np.sqrt(np.diag(cov))
    corr = cov / np.outer(scale, scale)
    chol = np.linalg.cholesky(corr + 1e-10 * np.eye(corr.shape[0]))
    a = np.linalg.solve(chol, g / scale[:, None])
    b = np.linalg.solve(chol, v / scale)
    col = np.linalg.norm(a, axis=0)
    col = np.where(col > 0, col, 1.0)
    x, _ = nnls(a / col, b, maxiter=50 * g.shape[1])
    return x / col, a


def _chi2(g: np.ndarray, v: np.ndarray, cov: np.ndarray, c: np.ndarray) -> float:
    """Whitened residual sum of squares (v − G·c)ᵀ cov⁻¹ (v − G·c)."""
    scale = np.sqrt(np.diag(cov))
    chol = np.linalg.cholesky(cov / np.outer(scale, scale) + 1e-10 * np.eye(v.size))
    r = np.linalg.solve(chol, (v - g @ c) / scale)
    return float(r @ r)


def _discrepancy(g: np.ndarray, v: np.ndarray, model_cov: np.ndarray) -> float:
    """The relative model discrepancy δ ≥ 0 with χ² = ν of the fit weighted by
    model_cov + diag((δ·v)²): 0 when the model's own covariance already gives χ² ≤ ν
    (Paule & Mandel 1982; bisection in log δ)."""

    def excess(delta: float) -> float:
        cov = model_cov + np.diag((delta * v) ** 2)
        c, _ = _gls_nnls(g, v, cov)
        return _chi2(g, v, cov, c) - max(1, v.size - int(np.count_nonzero(c > 0)))

    if excess(0.0) <= 0.0:
        return 0.0
    lo, hi = math.log(1e-6), math.log(10.0)
    for _ in range(_BISECTIONS):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if excess(math.exp(mid)) > 0.0 else (lo, mid)
    return math.exp(hi)


def _iterate(
    g: np.ndarray, v: np.ndarray, ms: np.ndarray, n_phase: int, tau0: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, float]:
    """The GLS fit with the covariance of the fitted mixture and the discrepancy δ, iterated
    until c settles: c, the whitened design, the weighting covariance, the model's own, δ."""
    cov = np.diag(2.0 * v * v * ms / (n_phase - 1.0))
    c, a = _gls_nnls(g, v, cov)
    model_cov, delta = cov, 0.0
    for _ in range(_MAX_ITER):
        model_cov = avar_covariance(ms, n_phase, tau0, c)
        delta = _discrepancy(g, v, model_cov)
        cov = model_cov + np.diag((delta * v) ** 2)
        c_new, a = _gls_nnls(g, v, cov)
        done = np.allclose(c_new, c, rtol=1e-6, atol=1e-12 * float(np.max(c_new, initial=0.0)))
        c = c_new
        if done:
            break
    return c, a, cov, model_cov, delta


def _inverse_information(a: np.ndarray) -> np.ndarray:
    """(AᵀA)⁻¹ with the columns scaled to unit norm first (the terms differ by decades)."""
    col = np.linalg.norm(a, axis=0)
    col = np.where(col > 0, col, 1.0)
    return np.linalg.pinv((a / col).T @ (a / col)) / np.outer(col, col)


def fit_noise_terms(
    tau_s: Any, adev: Any, cluster_sizes: Any, n_phase: int, fs_hz: float
) -> NoiseFit:
    """All five IEEE 952 noise terms by non-negative GLS on the whole Allan variance curve.

    Parameters
    ----------
    tau_s : array_like, s
        Averaging times of the curve (any grid: octave, log, all).
    adev : array_like
        Overlapping Allan deviation at ``tau_s`` (rate unit u).
    cluster_sizes : array_like of int
        m = τ·fs of each point.
    n_phase : int
        Phase points N of the record (rate samples + 1).
    fs_hz : float, Hz
        Sampling rate.

    Returns
    -------
    NoiseFit

    Raises
    ------
    CaptureError
        Fewer than six usable points (a record too short to separate five terms).

    Notes
    -----
    Points with ≥ 4 independent clusters N/m are used, thinned to 6 per decade. The first fit
    weighs each point by its own χ² variance 2σ̂⁴·m/N; then, up to 8 times, the covariance of
    the estimator is computed for the fitted mixture (:func:`avar_covariance`) and the fit
    repeated, until c changes by < 1e-6 relative; each time with the discrepancy δ that makes
    χ² = ν when χ² > ν (module). Uncertainty: cov(ĉ) = (AᵀA)⁻¹ (A = L⁻¹G whitened) on the
    terms the fit keeps and those whose slope lies between two kept ones (NNLS may set such a
    term to 0 where the data cannot tell it from its neighbours; leaving it out made the ramp's
    interval too narrow on the five-term twin); ν = points − terms kept; any other term set to
    zero gets the variance it would have if added alone. Each c_j gets [c − k·u, c + k·u] ∩ [0, ∞)
    (k = t_0.975(ν)), mapped by √ to the coefficient; U = the larger distance from C to either
    end, so that C ± U (clipped at 0) holds that interval: one interval per term. The model
    assumes Gaussian noise of the five types and a sensor whose bandwidth is well above 1/τ:
    an output filtered or averaged inside the sensor falls below every term's line at τ of a few
    samples, so the shortest-τ point is left out while it lies more than 4 of its own standard
    deviations below the fit and is its most negative residual (the fit repeated each time; at
    least 6 points stay). A bias-instability process that is flat only over a band (a
    Gauss–Markov sum) is flicker on that band and shows as model discrepancy outside it.

    References
    ----------
    IEEE Std 952-1997, Annex C, Table C.1, eqs. (C.5), (C.11), (C.21), (C.25), (C.29);
    N. El-Sheimy, H. Hou and X. Niu, "Analysis and modeling of inertial sensors using Allan
    variance", IEEE Trans. Instrum. Meas. 57(1), 2008, Table I; Greenhall & Riley 2003 (PTTI),
    §2; R. C. Paule and J. Mandel, "Consensus values and weighting factors", J. Res. NBS 87(5),
    1982 (the discrepancy δ with χ² = ν).
    """
    tau = np.asarray(tau_s, dtype=np.float64)
    sig = np.asarray(adev, dtype=np.float64)
    ms_all = np.asarray(cluster_sizes, dtype=np.int64)
    idx = _select(tau, sig, ms_all, n_phase)
    if idx.size < _MIN_POINTS:
        raise CaptureError(
            f"only {idx.size} τ values have at least {MIN_CLUSTERS:g} independent clusters: too "
            "few to separate the five IEEE 952 noise terms; supply a longer record or more τ."
        )
    tau0 = 1.0 / float(fs_hz)
    dropped = 0
    while True:
        t, v, ms = tau[idx], sig[idx] ** 2, ms_all[idx]
        g = term_avar(t)
        c, a, cov, model_cov, delta = _iterate(g, v, ms, n_phase, tau0)
        z = (v - g @ c) / np.sqrt(np.diag(model_cov))
        if idx.size <= _MIN_POINTS or not (z[0] < -_FILTER_Z and z[0] == z.min()):
            break
        idx, dropped = idx[1:], dropped + 1
    chi2 = _chi2(g, v, cov, c)
    active = np.flatnonzero(c > 0)
    dof = max(1, t.size - active.size)
    # the covariance spans the terms kept and any term whose slope lies between two of them
    # (NNLS may set such a term to 0 where the data cannot tell it from its neighbours)
    span = np.arange(active.min(), active.max() + 1) if active.size else active
    c_u = np.zeros(5)
    if span.size:
        c_u[span] = np.sqrt(np.diag(_inverse_information(a[:, span])))
    for j in np.setdiff1d(np.arange(5), span):
        c_u[j] = math.sqrt(float(_inverse_information(a[:, np.append(span, j)])[-1, -1]))
    k = float(stdtrit(dof, 0.5 + COVERAGE / 2.0))
    coef = np.sqrt(c)
    lo = np.sqrt(np.maximum(0.0, c - k * c_u))
    hi = np.sqrt(c + k * c_u)
    expanded = np.maximum(hi - coef, coef - lo)
    return NoiseFit(
        coefficients=coef,
        expanded=expanded,
        k=k,
        dof=dof,
        c=c,
        c_u=c_u,
        tau_s=t,
        avar=v,
        avar_fit=g @ c,
        chi2=chi2,
        discrepancy=delta,
        dropped=dropped,
    )
