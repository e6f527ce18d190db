"""IEEE Std 1057 sine fitting (3-parameter, 4-parameter, multi-harmonic), THD and SNR.

Model: ``y ≈ C + Σ_{h=1}^{H} A_h·sin(2π·h·f·(t − t_ref) + φ_h)``, fitted by least squares to
samples ``y`` at times ``t`` (s; increasing, not necessarily uniform; any number of periods ≥ ~1).

Two solvers give the same least-squares solution:

* **direct** — the explicit design matrix solved by QR (``numpy.linalg.lstsq``), the frequency
  refined by Gauss–Newton on the residuals. Used for records shorter than 1.5 periods, whose
  block plan the frequency's wide convergence range could upset.
* **blocks** — :class:`HarmonicFitAccumulator`: the samples are compressed once into per-block
  polynomial moments; every later evaluation of the normal equations (at any trial frequency)
  costs O(blocks·moments·H), independent of N. A 10-harmonic fit with frequency refinement of
  10⁷ uniformly spaced samples takes ~0.07 s on one core at up to a few thousand periods, and
  works chunk-wise for captures that do not fit in memory. Used for everything else: it agrees
  with the direct solver to ~1e-13 and is faster from a few hundred samples on (31,250
  samples, 10 harmonics: 38 ms against 258 ms). A uniformly sampled fast signal, whose blocks
  would hold fewer samples than moments, is summed from its samples at each trial frequency
  instead (O(N·H), whatever the number of periods: 0.1–0.2 s for 10⁷ samples from 10,000 to
  300,000 periods).
"""

from __future__ import annotations

import math
from typing import Any, Literal

import numpy as np

from rotacal.errors import CaptureError, ConfigError
from rotacal.signal._blocks import HarmonicFitAccumulator, moments_for, sums_from_samples
from rotacal.signal._checks import (
    as_pair,
    check_finite,
    check_frequency,
    check_harmonics,
    check_increasing,
    check_record,
    uniform_step,
)
from rotacal.signal._freq import estimate_frequency_unchecked
from rotacal.signal._normal import MAX_COND, StallWatch
from rotacal.signal._result import (
    DriftCheck,
    SineFit,
    build_drift_check,
    build_sine_fit,
    harmonic_series,
)

__all__ = [
    "DriftCheck",
    "HarmonicFitAccumulator",
    "SineFit",
    "displacement_amplitudes_from_rate",
    "estimate_frequency",
    "fit_harmonics",
    "fit_sine_3p",
    "fit_sine_4p",
    "snr_db",
    "thd_percent",
]

Method = Literal["auto", "direct", "blocks"]

_DIRECT_MAX_ELEMENTS = 20_000_000
_SHORT_PERIODS = 1.5
_EPS = float(np.finfo(np.float64).eps)


# ---------------------------------------------------------------------------- frequency estimate
def estimate_frequency(t: Any, y: Any) -> float:
    """Estimate the fundamental frequency of a sampled sine (start value for the fits).

    The largest peak of the Hann-windowed, zero-padded FFT (of block means for long records) is
    interpolated on the log spectrum; for records of fewer than 64 periods the estimate is then
    refined by minimising the residual of a single-sine least-squares fit over ±1.5 FFT bins, so
    that it lies well inside the convergence basin of the iterative fits even for ~1 period.

    Parameters
    ----------
    t : array_like
        Sample times (s), strictly increasing. Non-uniform times are treated as uniform for the
        FFT step (fine for jitter); pass ``frequency_hz`` to the fits for grossly irregular times.
    y : array_like
        Samples (any unit); the fundamental must be the largest spectral line.

    Returns
    -------
    float
        Frequency (Hz).

    References
    ----------
    IEEE Std 1057-2017, §4.1.3.3 (initial estimate for the four-parameter fit).
    """
    ta, ya = as_pair(t, y)
    check_increasing(ta)
    check_finite("y", ya)
    return estimate_frequency_unchecked(ta, ya)


# ---------------------------------------------------------------------------- direct (QR) solver
def _design(tau: np.ndarray, f: float, nh: int, drift: bool = False) -> np.ndarray:
    """Columns ``[1, cos(hωτ)…, sin(hωτ)…]`` and, with ``drift``, ``τ`` last."""
    th = 2.0 * math.pi * f * tau
    h = np.arange(1, nh + 1, dtype=np.float64)
    ang = np.outer(th, h)
    cols = [np.ones((tau.size, 1)), np.cos(ang), np.sin(ang)]
    if drift:
        cols.append(tau[:, None])
    return np.hstack(cols)


def _column_scaled(a: np.ndarray, norms: np.ndarray) -> np.ndarray:
    """``a / norms``, written in Fortran order: LAPACK's layout, which NumPy's ``lstsq`` and ``qr``
    copy a C-ordered matrix into column by column (strided, slow for a tall one); the same
    values, so the same solution."""
    out = np.empty(a.shape, order="F")
    np.divide(a, norms, out=out)
    return out


def _scaled_lstsq(a: np.ndarray, rhs: np.ndarray) -> tuple[np.ndarray, float]:
    norms = np.sqrt(np.einsum("ij,ij->j", a, a))
    norms[norms == 0] = 1.0
    x, _, rank, sv = np.linalg.lstsq(_column_scaled(a, norms), rhs, rcond=None)
    cond = float(sv[0] / sv[-1]) if rank == a.shape[1] and sv[-1] > 0 else math.inf
    return x / norms, cond


def _unit_covariance(j: np.ndarray) -> np.ndarray:
    """(JᵀJ)⁻¹ from the QR factor of the column-scaled Jacobian."""
    norms = np.sqrt(np.einsum("ij,ij->j", j, j))
    norms[norms == 0] = 1.0
    r: np.ndarray = np.asarray(np.linalg.qr(_column_scaled(j, norms), mode="r"), dtype=np.float64)
    rinv = np.linalg.solve(r, np.eye(r.shape[0], dtype=np.float64))
    return (rinv @ rinv.T) / np.outer(norms, norms)


def _fit_direct(
    t: np.ndarray,
    y: np.ndarray,
    f0: float,
    nh: int,
    refine: bool,
    max_iter: int,
    rtol: float,
    drift: bool = False,
    drift_check: bool = False,
) -> SineFit:
    t_ref = 0.5 * (float(t[0]) + float(t[-1]))
    tau = t - t_ref
    y0 = float(np.mean(y))
    yc = y - y0
    h = np.arange(1, nh + 1, dtype=np.float64)
    n_lin = 2 * nh + 1 + (1 if drift else 0)

    def linear(f: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
        a = _design(tau, f, nh, drift)
        p, cond = _scaled_lstsq(a, yc)
        if not cond * cond < MAX_COND:
            raise CaptureError(
                f"the {n_lin}-parameter sine fit at {f:.6g} Hz is ill-conditioned "
                f"(condition number {cond:.3g}); supply a longer record or fewer harmonics."
            )
        r = yc - a @ p
        return a, p, r, float(r @ r)

    def jacobian(a: np.ndarray, p: np.ndarray, f: float) -> np.ndarray:
        # cos(hωτ) and sin(hωτ) are the design's own columns at this f (computed the same way)
        cos_ang, sin_ang = a[:, 1 : nh + 1], a[:, nh + 1 : 2 * nh + 1]
        ca, cb = p[1 : nh + 1], p[nh + 1 : 2 * nh + 1]
        dcol = 2.0 * math.pi * tau * ((cos_ang * cb - sin_ang * ca) @ h)
        return np.hstack([a, dcol[:, None]])

    f = f0
    a, p, r, rss = linear(f)
    iterations = 0
    if refine:
        rss_tol = 64.0 * _EPS * float(yc @ yc) + 1e-300
        stall = StallWatch(rss_tol)
        converged = False
        for _ in range(max_iter):
            iterations += 1
            jac = jacobian(a, p, f)
            step, cond = _scaled_lstsq(jac, r)
            df = float(step[-1])
            if not (math.isfinite(df) and cond * cond < MAX_COND):
                raise CaptureError(
                    f"the frequency refinement at {f:.6g} Hz is ill-conditioned; supply a longer "
                    "record (more periods of the motion)."
                )
            lam = 1.0
            accepted = False
            for _half in range(40):
                f_try = f + lam * df
                if f_try > 0:
                    cand = linear(f_try)
                    if cand[3] <= rss + rss_tol:
                        stall.step(rss, cand[3])
                        f = f_try
                        a, p, r, rss = cand
                        accepted = True
                        break
                lam *= 0.5
            if not accepted or abs(lam * df) <= rtol * abs(f):
                converged = True
                break
        if not converged and not stall.at_minimum:
            raise CaptureError(
                f"the frequency refinement did not converge in {max_iter} iterations (last "
                f"f = {f:.9g} Hz); check that the record holds one dominant sine, or raise "
                "max_iter."
            )
        cov_unit = _unit_covariance(jacobian(a, p, f))
    else:
        cov_unit = _unit_covariance(a)
    check = None
    if drift_check and not drift:
        a_d = np.hstack([a, tau[:, None]])
        p_d, _ = _scaled_lstsq(a_d, yc)
        r_d = yc - a_d @ p_d
        check = build_drift_check(
            params=p_d,
            offset=y0 + float(p_d[0]),
            rss=float(r_d @ r_d),
            n_samples=t.size,
            cov_unit=_unit_covariance(a_d),
        )
    return build_sine_fit(
        frequency_hz=f,
        offset=y0 + float(p[0]),
        cos_coefs=p[1 : nh + 1],
        sin_coefs=p[nh + 1 : 2 * nh + 1],
        t_ref_s=t_ref,
        rss=rss,
        n_samples=t.size,
        iterations=iterations,
        cov_unit=cov_unit,
        refined=refine,
        drift=float(p[-1]) if drift else None,
        drift_check=check,
    )


# ---------------------------------------------------------------------------- public fits
def _fit(
    t: Any,
    y: Any,
    frequency_hz: float | None,
    nh: int,
    refine: bool,
    max_iter: int,
    rtol: float,
    method: str,
    drift: bool = False,
    drift_check: bool = False,
) -> SineFit:
    nh = check_harmonics(nh)
    if method not in ("auto", "direct", "blocks"):
        raise ConfigError(f"method must be 'auto', 'direct' or 'blocks'; got {method!r}.")
    if isinstance(max_iter, bool) or not isinstance(max_iter, (int, np.integer)) or max_iter < 1:
        raise ConfigError(f"max_iter must be an integer ≥ 1; got {max_iter!r}.")
    if not (isinstance(rtol, (int, float)) and math.isfinite(rtol) and rtol > 0):
        raise ConfigError(f"rtol must be a positive number; got {rtol!r}.")
    f_given = None if frequency_hz is None else check_frequency(frequency_hz)
    ta, ya = as_pair(t, y)
    n = ta.size
    n_par = 2 * nh + 1 + (1 if refine else 0) + (1 if drift else 0)
    if n < n_par + 1:
        check_record(n, 1.0, 1.0, nh, n_par)  # raises: too few samples
    dt_u = uniform_step(ta)
    if dt_u is None:
        check_increasing(ta)
    check_finite("y", ya)
    span = float(ta[-1] - ta[0])
    f0 = estimate_frequency_unchecked(ta, ya) if f_given is None else f_given
    check_record(n, span, f0, nh, n_par)
    periods = f0 * span * n / (n - 1)
    if method == "auto":
        short = periods < _SHORT_PERIODS and n * (2 * nh + 2) <= _DIRECT_MAX_ELEMENTS
        method = "direct" if short else "blocks"
    if method == "direct":
        return _fit_direct(
            ta, ya, f0, nh, refine, int(max_iter), float(rtol), bool(drift), bool(drift_check)
        )
    acc = HarmonicFitAccumulator(f0, harmonics=nh, n_moments=moments_for(f0, nh, span / (n - 1)))
    if dt_u is not None and sums_from_samples(f0, nh, dt_u):
        acc._hold_grid(ta, ya, dt_u)
    else:
        # the caller holds every sample: moments up to their size stay in memory (a temporary
        # file would be written once and read back at every trial frequency)
        acc._store.keep_bytes = max(acc._store.keep_bytes, ta.nbytes + ya.nbytes)
        acc._add(ta, ya, uniform_dt=dt_u, y_checked=True)
    return acc.fit(
        f0,
        nh,
        refine,
        max_iter=int(max_iter),
        rtol=float(rtol),
        drift=bool(drift),
        drift_check=bool(drift_check),
        _samples=(ta, ya),
    )


def fit_sine_3p(t: Any, y: Any, frequency_hz: float, *, method: Method = "auto") -> SineFit:
    """Three-parameter sine fit at a known frequency: ``y ≈ C + a·cos(ωτ) + b·sin(ωτ)``.

    Parameters
    ----------
    t : array_like
        Sample times (s), strictly increasing (uniform or not).
    y : array_like
        Samples (any unit), at least ~1 period.
    frequency_hz : float
        The known frequency f (Hz).
    method : {'auto', 'direct', 'blocks'}
        Solver: explicit QR, block moments, or chosen from the record size.

    Returns
    -------
    SineFit
        Offset and amplitude in the unit of y, phase in rad at ``t_ref_s``;
        ``frequency_u_hz = 0``.

    References
    ----------
    IEEE Std 1057-2017, §4.1.3.1 (three-parameter least-squares fit).
    """
    if frequency_hz is None:
        raise ConfigError("fit_sine_3p needs frequency_hz; use fit_sine_4p to estimate it.")
    return _fit(t, y, frequency_hz, 1, False, 1, 1e-12, method)


def fit_sine_4p(
    t: Any,
    y: Any,
    frequency_hz: float | None = None,
    *,
    max_iter: int = 50,
    rtol: float = 1e-12,
    method: Method = "auto",
) -> SineFit:
    """Four-parameter sine fit (offset, amplitude, phase and frequency), iterative.

    Parameters
    ----------
    t : array_like
        Sample times (s), strictly increasing (uniform or not).
    y : array_like
        Samples (any unit), at least ~1 period.
    frequency_hz : float, optional
        Start value of f (Hz); from :func:`estimate_frequency` when omitted.
    max_iter : int
        Largest number of Gauss–Newton iterations.
    rtol : float
        The iteration stops when the frequency step is below ``rtol·f``.
    method : {'auto', 'direct', 'blocks'}
        Solver: explicit QR, block moments, or chosen from the record size.

    Returns
    -------
    SineFit
        Frequency (Hz) and its standard uncertainty, offset and amplitude (unit of y), phase (rad).

    References
    ----------
    IEEE Std 1057-2017, §4.1.3.3 (four-parameter least-squares fit).
    """
    return _fit(t, y, frequency_hz, 1, True, max_iter, rtol, method)


def fit_harmonics(
    t: Any,
    y: Any,
    frequency_hz: float | None = None,
    *,
    harmonics: int = 10,
    refine_frequency: bool = True,
    max_iter: int = 50,
    rtol: float = 1e-12,
    method: Method = "auto",
    drift: bool = False,
    drift_check: bool = False,
) -> SineFit:
    """Multi-harmonic sine fit with the fundamental frequency refined.

    Fits ``y ≈ C + Σ_{h=1}^{H} a_h cos(2πhf(t − t_ref)) + b_h sin(2πhf(t − t_ref))`` (Feng et al.
    2023, eq. (9)); with ``refine_frequency`` f is a parameter too (the IEEE 1057 iterative fit).

    With ``drift`` the model gains a linear term, ``y ≈ C + D·(t − t_ref) + Σ_h …`` (rotacal's
    extension of eq. (9), not in Feng et al. (2023) or IEEE 1057): a slow drift of y is then fitted as D
    instead of leaking into the harmonics. Over n whole periods a ramp D·τ projects onto the
    sine terms as ``b_h = −2D·(−1)^{hn}/(2πhf)``, so without the term a drift reads as harmonic
    distortion; with it the b_h carry slightly more noise (their correlation with τ is
    ``6/(πhn)²`` in r²).

    Parameters
    ----------
    t : array_like
        Sample times (s), strictly increasing (uniform or not).
    y : array_like
        Samples (any unit), at least ~1 period of the fundamental.
    frequency_hz : float, optional
        Fundamental (Hz): the start value, or the fixed value if not ``refine_frequency``.
        From :func:`estimate_frequency` when omitted.
    harmonics : int
        Number of harmonics H ≥ 1 (H·f must stay below the Nyquist frequency).
    refine_frequency : bool
        Fit the frequency as well.
    max_iter, rtol : iteration limit and relative frequency step that ends it.
    method : {'auto', 'direct', 'blocks'}
        Solver: explicit QR (small or short records), block moments (large records), or auto.
    drift : bool
        Fit the linear term D (``SineFit.drift``, unit of y per s, and ``drift_u``).
    drift_check : bool
        Without ``drift``: also refit with D at the final frequency (``SineFit.drift_check``),
        to judge an unfitted drift; one more linear solve (no pass over the samples for the
        block solver, whose sums hold τ already).

    Returns
    -------
    SineFit
        Amplitudes/offset in the unit of y, phases (rad) at ``t_ref_s``, frequency (Hz).

    References
    ----------
    IEEE Std 1057-2017, §4.1.3 (multi-harmonic least-squares sine fit);
    Feng et al. 2023, Sensors 23:4876, eqs. (9)–(10).
    """
    return _fit(
        t, y, frequency_hz, harmonics, refine_frequency, max_iter, rtol, method, drift, drift_check
    )


# ---------------------------------------------------------------------------- figures of merit
def thd_percent(amplitudes: Any, harmonics: int | None = None) -> float:
    """Total harmonic distortion, ``100·sqrt(Σ_{h=2}^{N_H} A_h²)/A_1`` (%).

    Parameters
    ----------
    amplitudes : array_like or SineFit
        Harmonic amplitudes ``A_1, A_2, …`` (h = 1 first; any common unit), or a fit.
    harmonics : int, optional
        The highest order N_H used (default: all given). N_H = 1 gives 0.

    Returns
    -------
    float
        THD in percent.

    References
    ----------
    Feng et al. 2023, Sensors 23:4876, eq. (1); IEEE Std 1057-2017, §4.6.
    """
    if isinstance(amplitudes, SineFit):
        amplitudes = amplitudes.amplitudes
    a = np.asarray(amplitudes, dtype=np.float64)
    if a.ndim != 1 or a.size < 1:
        raise ConfigError(
            f"amplitudes must be a 1-D array A_1..A_N (h = 1 first); got shape {a.shape}."
        )
    nh = a.size if harmonics is None else check_harmonics(harmonics)
    if nh > a.size:
        raise ConfigError(f"harmonics = {nh} but only {a.size} amplitudes were given.")
    a = a[:nh]
    if not np.all(np.isfinite(a)) or np.any(a < 0):
        raise CaptureError("amplitudes must be finite and ≥ 0 (they are magnitudes A_h).")
    if not a[0] > 0:
        raise CaptureError("the fundamental amplitude A_1 is 0; THD is undefined.")
    return float(100.0 * math.sqrt(float(a[1:] @ a[1:])) / a[0])


def thd_standard_uncertainty_percent(amplitudes: Any, amplitudes_u: Any) -> float:
    """First-order standard uncertainty of THD from the amplitudes' standard uncertainties (%).

    The law of propagation of uncertainty applied to eq. (1) with uncorrelated amplitudes:
    ``∂THD/∂A_1 = −THD/A_1`` and ``∂THD/∂A_h = 100·A_h/(A_1·sqrt(Σ_{k≥2} A_k²))`` for h ≥ 2.
    It is sound while THD is well above its own uncertainty; near zero THD is biased upwards by
    noise and first-order propagation understates the spread (JCGM 101/102): treat it as an
    indication there.

    Parameters
    ----------
    amplitudes : array_like — A_1, A_2, … (h = 1 first; any common unit).
    amplitudes_u : array_like — their standard uncertainties (same unit).

    Returns
    -------
    float — u(THD) in percentage points.

    References
    ----------
    Feng et al. 2023, Sensors 23:4876, eq. (1); JCGM 100:2008 (GUM), eq. (10).
    """
    a = np.asarray(amplitudes, dtype=np.float64)
    u = np.asarray(amplitudes_u, dtype=np.float64)
    if a.shape != u.shape or a.ndim != 1 or a.size < 1:
        raise ConfigError("amplitudes and amplitudes_u must be 1-D arrays of the same length.")
    thd = thd_percent(a)
    root = math.sqrt(float(a[1:] @ a[1:]))
    grad = np.empty_like(a)
    grad[0] = -thd / a[0]
    grad[1:] = 100.0 * a[1:] / (a[0] * root) if root > 0 else 100.0 / a[0]
    return float(math.sqrt(float(np.sum((grad * u) ** 2))))


def displacement_amplitudes_from_rate(rate_amplitudes: Any, frequency_hz: float) -> np.ndarray:
    """Displacement amplitudes ``A_h = A'_h/(2π·h·f)`` from the amplitudes of a rate fit.

    Integrating ``A'_h·sin(2πhft + φ_h)`` gives an amplitude ``A'_h/(2πhf)`` (the constant of
    integration and a rate offset D_0 do not enter), so
    ``thd_percent(displacement_amplitudes_from_rate(fit.amplitudes, fit.frequency_hz))`` is the
    displacement THD of eq. (14) from a gyro (rate) fit.

    Parameters
    ----------
    rate_amplitudes : array_like
        Rate amplitudes A'_h, h = 1 first (e.g. deg/s).
    frequency_hz : float
        Fundamental frequency f (Hz).

    Returns
    -------
    numpy.ndarray
        Displacement amplitudes (e.g. deg: rate unit × s).

    References
    ----------
    Feng et al. 2023, Sensors 23:4876, eqs. (11)–(14).
    """
    f = check_frequency(frequency_hz)
    a = np.asarray(rate_amplitudes, dtype=np.float64)
    if a.ndim != 1:
        raise ConfigError(f"rate_amplitudes must be a 1-D array (h = 1 first); got {a.shape}.")
    h = np.arange(1, a.size + 1, dtype=np.float64)
    return a / (2.0 * math.pi * h * f)


def snr_db(y: Any, fit: SineFit, t: Any) -> float:
    """Signal-to-noise ratio of a fit: ``10·log10(mean((model − C)²)/mean((y − model)²))`` (dB).

    The signal is the fitted model without its constant term (and without its drift term, for a
    fit with drift: only the harmonics); the noise is the residual.

    Parameters
    ----------
    y : array_like
        Samples (unit of the fit).
    fit : SineFit
        The fit of ``y``.
    t : array_like
        Sample times (s).

    Returns
    -------
    float
        SNR in dB (``inf`` for a residual of exactly zero).

    References
    ----------
    Feng et al. 2023, Sensors 23:4876, §5 (SNR of the FOG signal against its sine fit).
    """
    ta, ya = as_pair(t, y)
    check_finite("t", ta)
    check_finite("y", ya)
    if ta.size == 0:
        raise CaptureError("y and t are empty; SNR needs samples.")
    w = 2.0 * math.pi * fit.frequency_hz
    sig = 0.0
    noise = 0.0
    step = 1 << 16
    for s in range(0, ta.size, step):
        e = min(ta.size, s + step)
        ac = harmonic_series(w * (ta[s:e] - fit.t_ref_s), fit.cos_coefs, fit.sin_coefs, 0.0)
        r = ya[s:e] - fit.offset - ac
        if fit.drift is not None:
            r -= fit.drift * (ta[s:e] - fit.t_ref_s)
        sig += float(ac @ ac)
        noise += float(r @ r)
    if sig == 0.0:
        raise CaptureError("the fitted signal is zero (all amplitudes 0); SNR is undefined.")
    if noise == 0.0:
        return math.inf
    return 10.0 * math.log10(sig / noise)
