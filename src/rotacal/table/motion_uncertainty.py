"""Uncertainty budgets of the sinusoidal-motion calibration (Feng et al. 2023), one place for every path.

:func:`motion_budgets` gives the budget of every quantity a :class:`~rotacal.table.MotionResult`
reports — amplitude, frequency, angular-acceleration amplitude, their errors against set values,
THD and the reversing moments — from what the capture gives (the multi-harmonic fit's residual
noise and its covariance, Type A with ν = N − p) and from the lab's instrument specifications
(:class:`~rotacal.uncertainty.InstrumentSpecs`, Type B). It is called by the in-memory and the
chunked calibrations alike; :func:`comparison_budgets` serves
:func:`~rotacal.table.compare_schemes`.

Measurement models (sensitivities analytic). A specification stated with a non-zero mean is a
recognised systematic effect: the result is corrected for it (GUM §3.2.4), its row keeps the stated
value and u, and a note says so.

* OSE: ``A = A_fit − (g₊ − g₋)/7200`` — g± (arcsec) the encoder's reading error (reading − true)
  at the two extremes of the motion (the amplitude is half the stroke between them; two
  graduation positions 2A apart, taken as independent; exact for a reading error linear across
  the stroke, and a mean common to both cancels); ``f = f_fit·(1 + e)`` — e the timebase's
  fractional error (a clock running e fast stamps every time (1 + e) long, so the fitted
  frequency is f/(1 + e)); ``α = A·(2πf)²``, hence ``∂α/∂A = (2πf)²``, ``∂α/∂f = 2α/f``,
  ``∂α/∂e = 2α/(1 + e)``.
* LTS: θ = arctan(D/R) (eq. (15)): ``A = A_fit + c_R·(R − R₀) − c₊·q₊ + c₋·q₋`` with
  ``c_R = ∂A/∂R`` the projection of ``∂θ/∂R = −sin 2θ/(2R)`` onto the fundamental (≈ −A/R) and
  ``c± = ½·∂θ/∂D = ½·R/(R² + D±²)`` at the two extremes (q± the reading's resolution error there,
  not averaged by the fit when the noise does not dither the quantiser); f and α as for the OSE.
* FOG: the rate amplitude A′ and f are fitted; ``A = A′/(2πf_fit·(1 + s)(1 + e))`` and
  ``α = A′·2πf_fit·(1 + e)/(1 + s)`` with s the scale factor's relative error — so
  ``∂A/∂s = −A/(1 + s)``, ``∂A/∂e = −A/(1 + e)``, ``∂α/∂e = α/(1 + e)``, ``∂α/∂s = −α/(1 + s)``,
  ``∂A/∂f_fit = −A/f_fit``; every harmonic amplitude scales alike (the THD does not change).
* Errors against set values: ``100·(y − y_set)/y_set`` with exact set values.
* THD (eq. (1)), by Monte Carlo (JCGM 101): near zero it is biased upward by noise and
  first-order propagation is meaningless (JCGM 102, magnitude of a complex quantity). The fitted
  in-phase and quadrature components of harmonic h are N(A_h, u_h²) (the fit's white-noise
  covariance: equal variances, no correlation over whole periods). Reported (the integrator's
  policy B): the plain THD (JSON ``thd_percent`` and the budget's value); u, the standard
  deviation of that estimator, and its noise bias, both simulated at the bias-corrected THD
  (noise power 2Σu_h² removed); the bias-corrected THD; and the 95 % coverage interval for the
  TRUE THD from a Neyman confidence belt — one-sided [0, high] when the measured power is
  consistent with noise — with U its half-width and k = U/u (:func:`thd_uncertainty`).
* Reversing moments: the estimator's noise over the motion's curvature κ = |θ''| at the extremes
  (OSE: arg max of a noisy sampled parabola — the Chp of eqs. (7)–(8) —, evaluated by a Monte
  Carlo of that estimator; LTS: vertex of the least-squares parabola over ±T/20,
  ``u = s·√3/(κ·W·√n)``, plus that parabola's own error on extremes made asymmetric by the
  harmonics (the estimator applied to the fitted motion); FOG: zero crossing of the fitted rate,
  ``u² = s²(1 + 2H)/(N·κ²) + (τ·u(f)/f)²``), and the timebase: ``t = t₀ + (t_stamp − t₀)/(1 + e)``,
  ``∂t/∂e ≈ −(t − t₀)``.

A fit with a linear drift term (``drift=True``, :mod:`rotacal.table.motion_drift`) enters every
budget as it stands: its harmonic amplitudes and their u (the covariance includes the drift
column), ν = N − (2H + 3), and the curvature and rate slopes of its periodic part.

Why the interval is built for the true value: the earlier evaluation drew each harmonic about the
already-biased measured amplitudes, which gives the spread of a re-measurement shifted up by the
bias a second time; on the FOG twin at 20 dB its interval held a true THD of 0 in 0 of 20 runs.
The belt holds the truth at the stated probability at every THD (coverage tests on the twin in
tests/table/test_motion_uncertainty.py).

References
----------
Feng R., Yan J., Wu Y., Yu N., Yin X. (2023). Sensors 23:4876, eqs. (1), (2), (7)–(8), (9)–(15).
JCGM 100:2008 (GUM) §5.1.2, §6, G.4; JCGM 101:2008 §7 (Monte Carlo), §8 (validation of GUM);
JCGM 102:2011 §9 (magnitude near zero); IEEE Std 1057-2017 §4.1.3 (fit covariance);
J. Neyman (1937), Phil. Trans. R. Soc. A 236:333 (confidence belts); G. J. Feldman & R. D. Cousins
(1998), Phys. Rev. D 57:3873 (intervals near a physical boundary).
"""

from __future__ import annotations

import dataclasses
import functools
import math
from collections.abc import Callable, Mapping, Sequence
from typing import Any, Literal

import numpy as np
from scipy import stats
from scipy.optimize import brentq

from rotacal.errors import ConfigError
from rotacal.signal import SineFit
from rotacal.uncertainty import (
    BudgetRow,
    Input,
    InstrumentSpecs,
    UncertaintyBudget,
    numerical_tolerance,
    propagate,
)
from rotacal.uncertainty.notes import tidy
from rotacal.uncertainty.specs import spec_input, type_a_note

__all__ = [
    "ReversalDetection",
    "ThdUncertainty",
    "comparison_budgets",
    "fit_dof",
    "motion_budgets",
    "parabola_vertex_bias",
    "reversal_time_u_argmax",
    "reversal_time_u_parabola",
    "reversal_time_u_rate_zero",
    "thd_bias_corrected_percent",
    "thd_uncertainty",
]

#: Monte Carlo draws of the THD (belt and spread; ~30 ms). Each tail probability of the belt is
#: then known to √(α(1−α)/M) ≈ 7·10⁻⁴ (coverage 95 ± 0.1 %); the standard error of U that
#: follows is stated in the budget (typically well under 1 % of U).
THD_TRIALS = 50_000
#: Seed of the THD Monte Carlo (the same capture always gives the same budget).
THD_SEED = 4876
#: Draws of the Monte Carlo of the OSE's reversal estimator (u to ≈ 1/√(2·4000) ≈ 1.1 %).
REVERSAL_DRAWS = 4000
_P = 0.95
_ARCSEC_PER_DEG = 3600.0
_DEG = "°"

Scheme = Literal["encoder", "lts", "fog"]

#: The specifications each quantity of each scheme takes (others are ignored).
_AMPLITUDE_SPECS: dict[str, tuple[str, ...]] = {
    "encoder": ("encoder.graduation_error_arcsec",),
    "lts": ("lts.radius_mm", "lts.resolution_um"),
    "fog": ("fog.scale_factor_relative", "timebase.relative_error"),
}
_TIMEBASE = ("timebase.relative_error",)


# ------------------------------------------------------------------------------ small helpers
def fit_dof(fit: SineFit) -> float:
    """ν = N − p of a refined multi-harmonic fit (p = 2H + 2: offset, H pairs, frequency; one
    more with a drift term)."""
    return float(max(fit.n_samples - fit.n_parameters, 1))


def _fit_sigma(fit: SineFit) -> float:
    """s = √(RSS/(N − p)), the residual's standard deviation (unit of the fitted signal)."""
    n = fit.n_samples
    return float(fit.residual_rms * math.sqrt(n / fit_dof(fit)))


def _second_derivative(fit: SineFit, t: np.ndarray) -> np.ndarray:
    """d²y/dt² of the fitted model (unit of y per s²): coefficients −(hω)²·(a_h, b_h) (a drift
    term has none)."""
    w = 2.0 * math.pi * fit.frequency_hz
    hw2 = (w * np.arange(1, fit.harmonics + 1)) ** 2
    d2 = dataclasses.replace(
        fit.periodic(), offset=0.0, cos_coefs=-hw2 * fit.cos_coefs, sin_coefs=-hw2 * fit.sin_coefs
    )
    return np.asarray(d2.evaluate(t))


def _one_period(fit: SineFit, points: int = 4096) -> tuple[np.ndarray, np.ndarray]:
    """(τ, periodic model) over one period of the fundamental, uniformly (τ from t_ref, s)."""
    tau = np.arange(points) / (points * fit.frequency_hz)
    return tau, np.asarray(fit.periodic().evaluate(fit.t_ref_s + tau))


def _stated_mean(specs: InstrumentSpecs | None, key: str) -> float:
    """The stated mean of a specification (0 when not stated): a recognised systematic effect
    the result is corrected for (GUM §3.2.4, the integrator's policy A)."""
    return 0.0 if specs is None else specs.mean(key)


def _spec_notes(specs: InstrumentSpecs | None, keys: Sequence[str]) -> tuple[str, ...]:
    """The "Type A only" note when none of ``keys`` is stated, else the keys not stated."""
    note = type_a_note(specs, keys)
    if note is not None or specs is None:
        return (note,) if note else ()
    missing = [k for k in keys if specs.get(k) is None]
    if not missing:
        return ()
    return (
        f"not stated in {specs.source}: {', '.join(missing)} — its effect is not in this budget.",
    )


def _correction_notes(specs: InstrumentSpecs | None, keys: Sequence[str]) -> tuple[str, ...]:
    """The standard "corrected for the stated mean …" note of every key with a non-zero mean."""
    if specs is None:
        return ()
    out = []
    for key in keys:
        note = specs.correction_note(key)
        if note is None:
            continue
        if key == "encoder.graduation_error_arcsec":
            note += (
                " A reading error common to both extremes cancels in the amplitude (half the "
                "stroke): the correction is 0."
            )
        out.append(note)
    return tuple(out)


# ------------------------------------------------------------------------------ reversing moments
@dataclasses.dataclass(frozen=True)
class ReversalDetection:
    """How a scheme found its reversing moments: what their budget needs.

    Attributes
    ----------
    method : ``"argmax"`` (OSE: the extreme sample of eqs. (7)–(8)), ``"parabola"`` (LTS: vertex of
        a least-squares parabola over ±``half_window_s``) or ``"rate_zero"`` (FOG: zero crossings
        of the fitted rate).
    fit : the fit whose model gives the curvature at the reversals (displacement fit in deg for
        argmax/parabola; the rate fit in deg/s whose zero crossings are the reversals for
        rate_zero), and whose residual is the noise the estimator reads.
    sample_interval_s : sampling interval (s).
    capture_start_s : time of the capture's first sample (s): the timebase error accumulates
        from there (the time origin itself is taken as exact).
    half_window_s : half-width W of the parabola's window (s), parabola only.
    """

    method: Literal["argmax", "parabola", "rate_zero"]
    fit: SineFit
    sample_interval_s: float
    capture_start_s: float
    half_window_s: float = math.nan


def reversal_time_u_argmax(
    noise_deg: float,
    curvature_deg_s2: float,
    sample_interval_s: float,
    *,
    draws: int = REVERSAL_DRAWS,
    seed: int = 0,
) -> float:
    """Standard uncertainty of a reversing moment taken as the extreme sample (OSE, eqs. (7)–(8)).

    Near a reversal θ(t) ≈ θ₀ − κ(t − t₀)²/2. The Chp of eqs. (7)–(8) is the extreme sample of the
    quadrature signal that changes most; that signal is s(φ) with |s′(φ₀)| = max(|sin φ₀|,
    |cos φ₀|) ∈ [1/√2, 1], so its noise seen as angle is σ/|s′|. The spread of the arg max of
    ``−κτ²/2 + (σ/|s′|)·z_i`` on the sampling grid, with a random sub-sample position of t₀ and a
    random φ₀, has no closed form (an extreme-value problem that tends to dt/√12 without noise):
    this function evaluates it by a Monte Carlo of the estimator (JCGM 101 §7), ``draws`` times.

    Parameters
    ----------
    noise_deg : float
        Standard deviation σ of the demodulated angle's noise (deg), e.g. the fit residual's.
    curvature_deg_s2 : float
        |θ''| at the reversal (deg/s²), > 0.
    sample_interval_s : float
        Sampling interval dt (s), > 0.
    draws : int
        Monte Carlo draws (precision of u ≈ 1/√(2·draws)).
    seed : int
        Seed of the draws.

    Returns
    -------
    float
        u(t_rev) (s), the rms of the estimator's error about the true extreme.

    References
    ----------
    Feng et al. 2023, Sensors 23:4876, §3.2, eqs. (7)–(8); JCGM 101:2008 §7.
    """
    dt = float(sample_interval_s)
    kappa = float(curvature_deg_s2)
    sigma = float(noise_deg)
    if not (dt > 0 and kappa > 0 and sigma >= 0):
        raise ConfigError(
            "reversal_time_u_argmax needs dt > 0, curvature > 0 and noise ≥ 0; got "
            f"{dt!r}, {kappa!r}, {sigma!r}."
        )
    if sigma == 0.0:
        return dt / math.sqrt(12.0)
    rng = np.random.default_rng(seed)
    phi0 = rng.uniform(0.0, 2.0 * math.pi, draws)
    s_eff = sigma / np.maximum(np.abs(np.sin(phi0)), np.abs(np.cos(phi0)))
    # beyond a drop of 10 σ_eff the parabola's samples never win the arg max
    half = math.sqrt(2.0 * 10.0 * float(s_eff.max()) / kappa) + 2.0 * dt
    k = np.arange(-math.ceil(half / dt), math.ceil(half / dt) + 1, dtype=float)
    # bounded work: at most ~4·10⁶ samples (fewer draws for very wide windows, ≥ 100)
    draws = min(draws, max(100, 4_000_000 // k.size))
    phi0, s_eff = phi0[:draws], s_eff[:draws]
    offset = rng.uniform(-0.5, 0.5, draws)
    block = max(1, 2_000_000 // k.size)
    sq = 0.0
    for s in range(0, draws, block):
        e = min(draws, s + block)
        tau = (k[None, :] + offset[s:e, None]) * dt
        # y = −κτ²/2 + σ_eff·z, each product and the sum as written so, in place (no temporaries)
        y = rng.standard_normal((e - s, k.size))
        y *= s_eff[s:e, None]
        drop = np.square(tau)
        drop *= -0.5 * kappa
        y += drop
        est = tau[np.arange(e - s), np.argmax(y, axis=1)]
        sq += float(est @ est)
    return math.sqrt(sq / draws)


def reversal_time_u_parabola(
    noise_deg: float, curvature_deg_s2: Any, half_window_s: float, sample_interval_s: float
) -> np.ndarray:
    """Standard uncertainty of a reversing moment found as the vertex of a least-squares parabola.

    Fitting ``c₀ + c₁τ + c₂τ²`` to n samples spread evenly over ±W around the extreme, the vertex
    −c₁/(2c₂) moves by δc₁/κ (c₂ = −κ/2), and u(c₁) = σ/√(Σ τ_i²) = σ·√3/(W·√n). So
    ``u = σ·√3/(κ·W·√n)`` with n = 2W/dt (Feng et al. 2023 §5: the LTS's reversals by extreme
    values; rotacal refines each by this parabola, see :func:`~rotacal.table.extreme_reversals`).

    Parameters
    ----------
    noise_deg : float — σ of the angle (deg).
    curvature_deg_s2 : float or array — |θ''| at the reversal(s) (deg/s²).
    half_window_s : float — W (s).
    sample_interval_s : float — dt (s).

    Returns
    -------
    numpy.ndarray — u (s), one per curvature given.

    References
    ----------
    Feng et al. 2023, Sensors 23:4876, §5; JCGM 100:2008 (GUM) eq. (10).
    """
    kappa = np.atleast_1d(np.asarray(curvature_deg_s2, dtype=float))
    n = max(2.0 * float(half_window_s) / float(sample_interval_s), 5.0)
    return np.asarray(
        float(noise_deg) * math.sqrt(3.0) / (kappa * float(half_window_s) * math.sqrt(n))
    )


def parabola_vertex_bias(
    fit: SineFit, times_s: Any, half_window_s: float, sample_interval_s: float
) -> np.ndarray:
    """Error of the parabola-vertex estimator on the fitted (noise-free) motion at each reversal.

    Harmonics make an extreme asymmetric (a cubic term about it), which moves the vertex of a
    parabola fitted over ±W away from the true extreme. This applies the estimator of
    :func:`~rotacal.table.extreme_reversals` (least-squares parabola on the samples within ±W,
    re-centred on its vertex and fitted again) to the fitted model sampled every dt about each
    of its extremes (Newton on θ' = 0 from ``times_s``) and returns vertex − extreme.

    Parameters
    ----------
    fit : SineFit — the displacement fit (deg).
    times_s : array — the reversal times found (s), start values of the extremes.
    half_window_s, sample_interval_s : float — W and dt (s).

    Returns
    -------
    numpy.ndarray — the estimator's error at each reversal (s).

    References
    ----------
    Feng et al. 2023, Sensors 23:4876, §5 (LTS reversals by extreme values).
    """
    t = np.atleast_1d(np.asarray(times_s, dtype=float)).copy()
    for _ in range(4):  # Newton on θ'(t) = 0: the model's extremes
        d2 = _second_derivative(fit, t)
        t = t - np.asarray(fit.evaluate_derivative(t)) / np.where(d2 != 0, d2, np.inf)
    dt = float(sample_interval_s)
    n_half = max(int(half_window_s / dt), 2)
    k = np.arange(-n_half, n_half + 1, dtype=float) * dt
    centre = t.copy()
    q = k**2 - np.mean(k**2)
    # a batch of reversals at a time, ~2²⁰ model samples each: memory bounded on long captures
    batch = max(1, (1 << 20) // k.size)
    for s in range(0, t.size, batch):
        c = centre[s : s + batch]
        for _ in range(2):
            y = np.asarray(fit.evaluate(c[:, None] + k))
            c1 = (y @ k) / float(k @ k)
            c2 = (y @ q) / float(q @ q)
            c = c + np.where(c2 != 0, -c1 / (2.0 * np.where(c2 != 0, c2, 1.0)), 0.0)
        centre[s : s + batch] = c
    return np.asarray(centre - t)


def reversal_time_u_rate_zero(fit: SineFit, times_s: Any) -> np.ndarray:
    """Standard uncertainty of the zero crossings of a fitted rate model (FOG reversals).

    The fitted rate at t has variance s²(1 + 2H)/N from its offset and H harmonic pairs (white
    noise, whole periods: offset s²/N, each coefficient 2s²/N, cos² + sin² = 1) and its zero moves
    by δrate/κ, κ = |d rate/dt| there; a frequency error δf shifts the phase by τ·δf/f, τ = t −
    t_ref. Hence ``u(t)² = s²(1 + 2H)/(N·κ²) + (τ·u(f)/f)²``.

    Parameters
    ----------
    fit : SineFit — the rate fit (deg/s) whose zero crossings are the reversals.
    times_s : array — the reversal times (s).

    Returns
    -------
    numpy.ndarray — u (s) per reversal.

    References
    ----------
    Feng et al. 2023, Sensors 23:4876, eqs. (9)–(10); IEEE Std 1057-2017 §4.1.3; GUM eq. (10).
    """
    t = np.atleast_1d(np.asarray(times_s, dtype=float))
    kappa = np.abs(np.asarray(fit.periodic().evaluate_derivative(t)))
    kappa = np.where(kappa > 0, kappa, np.nan)
    s = _fit_sigma(fit)
    var_noise = s * s * (1 + 2 * fit.harmonics) / fit.n_samples / kappa**2
    var_f = ((t - fit.t_ref_s) * fit.frequency_u_hz / fit.frequency_hz) ** 2
    return np.asarray(np.sqrt(var_noise + var_f))


def _reversal_budget(
    reversal_times: np.ndarray,
    det: ReversalDetection,
    specs: InstrumentSpecs | None,
) -> UncertaintyBudget:
    """u of every reversing moment: detection (Type A) and timebase (Type B).

    ``reversal_times`` are already corrected for a stated timebase mean (true time)."""
    times = np.asarray(reversal_times, dtype=float)
    fit = det.fit
    dof = fit_dof(fit)
    s = _fit_sigma(fit)
    dt = det.sample_interval_s
    if det.method == "rate_zero":
        u_r = reversal_time_u_rate_zero(fit, times)
        kappa = np.abs(np.asarray(fit.periodic().evaluate_derivative(times)))
        how = (
            f"zero crossings of the {fit.harmonics}-harmonic rate fit, s = {s:.3g} °/s over "
            f"N = {fit.n_samples}"
        )
    else:
        kappa = np.abs(_second_derivative(fit, times))
        if det.method == "parabola":
            u_r = reversal_time_u_parabola(s, kappa, det.half_window_s, dt)
            how = f"vertex of a parabola over ±{det.half_window_s:.3g} s, angle noise s = {s:.3g} °"
        else:
            k_med = float(np.median(kappa)) if kappa.size else 0.0
            if not k_med > 0:
                k_med = float(fit.amplitudes[0]) * (2 * math.pi * fit.frequency_hz) ** 2
            u_r = np.array([reversal_time_u_argmax(s, k_med, dt, seed=fit.n_samples % 2**31)])
            how = (
                f"extreme sample of eqs. (7)–(8) (Monte Carlo of that estimator, "
                f"{REVERSAL_DRAWS} draws), angle noise s = {s:.3g} °, sampled every {dt:.3g} s"
            )
    u_r = u_r[np.isfinite(u_r)]
    u_det = float(np.sqrt(np.mean(u_r**2))) if u_r.size else 0.0
    k_text = f"{float(np.median(kappa)):.4g}" if kappa.size else "—"
    t_last = float(times[-1]) if times.size else float(det.capture_start_s)
    span = t_last - float(det.capture_start_s)
    inputs: list[Input] = []
    jac: list[float] = []
    if det.method == "parabola" and times.size:
        bias = parabola_vertex_bias(fit, times, det.half_window_s, dt)
        u_bias = float(np.sqrt(np.mean(bias**2)))
        inputs.append(
            Input(
                "parabola's error on asymmetric extremes",
                0.0,
                u_bias,
                unit="s",
                source="the estimator applied to the fitted (noise-free) motion about each extreme: "
                f"rms of vertex − extreme over the reversals, largest {np.max(np.abs(bias)):.3g} s",
                description=f"rms u={u_bias:.3g}",
            )
        )
        jac.append(1.0)
    inputs.append(
        Input(
            "reversal detection",
            0.0,
            u_det,
            dof=dof,
            unit="s",
            source=f"Type A: {how}, curvature |θ''| ≈ {k_text} °/s²",
            description=f"normal u={u_det:.3g}",
        )
    )
    jac.append(1.0)
    tb = spec_input(specs, "timebase.relative_error", name="timebase error e")
    if tb is not None:
        inputs.append(tb)
        jac.append(-span / (1.0 + tb.value))  # t = t₀ + (t_stamp − t₀)/(1 + e)
    jrow = np.array(jac)
    x0 = np.array([inp.value for inp in inputs])

    def model(*x: float) -> float:
        return t_last + float(np.dot(jrow, np.asarray(x) - x0))

    gum = propagate(
        model,
        inputs,
        jacobian=lambda *x: jrow,
        p=_P,
        names_out=["reversal_times_s"],
        units_out=["s"],
    )
    notes = [
        "one u for every reversing moment: the detection row is the rms over the reversals; the "
        f"timebase row is for the latest ({t_last:.6g} s, {span:.6g} s after the capture's first "
        "sample, from which a clock error accumulates), earlier ones are affected less.",
        *_spec_notes(specs, _TIMEBASE),
        *_correction_notes(specs, _TIMEBASE),
    ]
    return tidy(gum.budget(0), *notes)


# ------------------------------------------------------------------------------ THD
def thd_bias_corrected_percent(amplitudes: Any, amplitudes_u: Any) -> float:
    """THD with the noise power removed: ``100·√max(0, Σ_{h≥2}(A_h² − 2u_h²))/A_1`` (%).

    A harmonic fitted in white noise has two components with variance u_h² each, so
    ``E[Â_h²] = A_h² + 2u_h²``; subtracting the expected noise power removes the upward bias of
    eq. (1) near zero (a pure sine gives ~0 instead of ~√(2Σu_h²)/A_1).

    Parameters
    ----------
    amplitudes : array_like — A_1, A_2, … (h = 1 first; any common unit).
    amplitudes_u : array_like — their standard uncertainties (same unit).

    Returns
    -------
    float — bias-corrected THD (%), ≥ 0.

    References
    ----------
    Feng et al. 2023, Sensors 23:4876, eq. (1); JCGM 102:2011 §9 (bias of a magnitude near zero).
    """
    a = np.asarray(amplitudes, dtype=float)
    u = np.asarray(amplitudes_u, dtype=float)
    if a.shape != u.shape or a.ndim != 1 or a.size < 1 or not a[0] > 0:
        raise ConfigError("amplitudes and amplitudes_u must be equal 1-D arrays with A_1 > 0.")
    power = float(np.sum(a[1:] ** 2 - 2.0 * u[1:] ** 2))
    return 100.0 * math.sqrt(max(power, 0.0)) / float(a[0])


@dataclasses.dataclass(frozen=True)
class ThdUncertainty:
    """The THD's evaluation (all in % of the fundamental; see :func:`thd_uncertainty`).

    Attributes
    ----------
    plain : eq. (1) from the fitted amplitudes — the reported ``thd_percent`` and the budget's
        value.
    bias_corrected : :func:`thd_bias_corrected_percent` (noise power removed).
    mc_mean : mean of the plain estimator simulated at the bias-corrected THD.
    bias : ``mc_mean − bias_corrected`` (pp): the noise's upward push at that THD.
    u : standard deviation of the plain estimator there.
    interval : 95 % coverage interval for the TRUE THD (lower end 0 when the measured harmonic
        power is consistent with noise).
    U, k : half the interval's width, and U/u.
    U_mc_error : Monte Carlo standard error of U (pp), from the draws' quantile errors.
    trials : Monte Carlo draws M.
    budget : the UncertaintyBudget (method "Monte Carlo", ``interval`` set).
    """

    plain: float
    bias_corrected: float
    mc_mean: float
    bias: float
    u: float
    U: float
    k: float
    interval: tuple[float, float]
    U_mc_error: float
    trials: int
    budget: UncertaintyBudget


class _ThdDraws:
    """Common random numbers of the THD Monte Carlo, reduced to two numbers per draw.

    With harmonic h's true components (√(w_h·P), 0) in its own frame and noise u_h·(z₁, z₂), the
    measured power ``T = Σ_h |Â_h|² = P + 2√P·X + Y`` with ``X = Σ √w_h·u_h·z_h1`` and
    ``Y = Σ u_h²(z_h1² + z_h2²)`` (Σ w_h = 1): one set of draws serves every true power P, so
    the confidence belt is smooth in P (common random numbers) and each evaluation is O(M).
    """

    def __init__(
        self, a: np.ndarray, u: np.ndarray, weights: np.ndarray, trials: int, seed: int
    ) -> None:
        z1, z_power, za, zb = _thd_normals(trials, a.size - 1, seed)
        uh = u[1:]
        self.x = z1 @ (np.sqrt(weights) * uh)
        self.y = z_power @ (uh * uh)
        self.a1_true = float(a[0])
        self.a1 = np.hypot(a[0] + u[0] * za, u[0] * zb)
        self.trials = trials

    def power(self, thd: float) -> float:
        """True harmonic power P (unit of A squared) of a true THD (%)."""
        return (max(thd, 0.0) * self.a1_true / 100.0) ** 2

    def plain(self, thd: float) -> np.ndarray:
        """The plain estimator of eq. (1) in every draw, at a true THD ``thd`` (%)."""
        p = self.power(thd)
        # 100·√max(P + 2√P·X + Y, 0)/A₁, evaluated in that order, in place (no temporaries)
        t = self.x * (2.0 * math.sqrt(p))
        t += p
        t += self.y
        np.maximum(t, 0.0, out=t)
        np.sqrt(t, out=t)
        t *= 100.0
        t /= self.a1
        return t


@functools.lru_cache(maxsize=4)
def _thd_normals(trials: int, nh: int, seed: int) -> tuple[np.ndarray, ...]:
    """The standard normal draws of :class:`_ThdDraws` (z₁, z₁² + z₂², z_a, z_b): one seed, so the
    same for every capture with ``nh`` harmonics above the fundamental — drawn once and kept,
    read-only, instead of again in every calibration (a tenth of a motion calibration's time)."""
    rng = np.random.default_rng(seed)
    z1 = rng.standard_normal((trials, nh))
    z2 = rng.standard_normal((trials, nh))
    za, zb = rng.standard_normal((2, trials))
    drawn = (z1, z1 * z1 + z2 * z2, za, zb)
    for z in drawn:
        z.flags.writeable = False
    return drawn


def _quantile(values: np.ndarray, q: float) -> float:
    return float(np.quantile(values, min(max(q, 0.0), 1.0)))


def _thd_interval(
    draws: _ThdDraws, observed: float, p: float, p_star: float, scale: float
) -> tuple[float, float, float]:
    """Neyman interval [lo, hi] for the true THD and the Monte Carlo standard error of its U.

    Acceptance region of a true THD θ: [Q(θ, α_lo(θ)), Q(θ, 1 − α_hi(θ))], Q the quantile of the
    plain estimator, α_lo + α_hi = 1 − p and ``α_lo(θ) = (1 − p)/2·min(1, P(θ)/P*)``: one-sided
    (α_lo = 0) at a true THD of 0, central from a true power P* on. The split depends on the true
    value only, never on the data, so every θ is covered with probability p (Neyman 1937); the
    interval is {θ : observed ∈ region(θ)}.
    """
    alpha = 1.0 - p

    def a_lo(theta: float) -> float:
        if not p_star > 0:
            return 0.5 * alpha
        return 0.5 * alpha * min(1.0, draws.power(theta) / p_star)

    def lower_edge(theta: float) -> float:
        return _quantile(draws.plain(theta), a_lo(theta))

    def upper_edge(theta: float) -> float:
        return _quantile(draws.plain(theta), 1.0 - (alpha - a_lo(theta)))

    def bracket(edge: Callable[[float], float]) -> float:
        b = observed + 10.0 * scale
        for _ in range(200):
            if edge(b) > observed:
                return b
            b *= 2.0
        raise ConfigError("the THD's confidence belt could not be bracketed; check A_h and u_h.")

    def root(edge: Callable[[float], float]) -> float:
        if edge(0.0) >= observed:
            return 0.0
        b = bracket(edge)
        return float(brentq(lambda th: edge(th) - observed, 0.0, b, xtol=1e-9 * b, rtol=1e-10))

    lo = root(upper_edge)
    hi = root(lower_edge)

    def se(theta: float, edge: Callable[[float], float], q: float) -> float:
        """Standard error of an endpoint: the quantile's √(q(1−q)/M)·dQ/dq over the edge's slope."""
        if not theta > 0:
            return 0.0
        vals = draws.plain(theta)
        d = 0.25 * min(q, 1.0 - q)
        if not d > 0:
            return 0.0
        dq = (_quantile(vals, q + d) - _quantile(vals, q - d)) / (2.0 * d)
        h = 1e-2 * max(theta, scale)
        slope = (edge(theta + h) - edge(max(theta - h, 0.0))) / (theta + h - max(theta - h, 0.0))
        if not slope > 0:
            return 0.0
        return math.sqrt(q * (1.0 - q) / draws.trials) * dq / slope

    se_lo = se(lo, upper_edge, 1.0 - (alpha - a_lo(lo))) if lo > 0 else 0.0
    se_hi = se(hi, lower_edge, a_lo(hi))
    return lo, hi, 0.5 * math.hypot(se_lo, se_hi)


def _power_split(ah: np.ndarray, uh: np.ndarray) -> np.ndarray:
    """Shares w_h of the true harmonic power (Σ w_h = 1) for the Monte Carlo — a nuisance.

    A harmonic counts as detected when |Â_h|² exceeds the χ²₂ quantile of noise alone at
    0.05/(N − 1) (Bonferroni over the harmonics); it gets its excess power Â_h² − 2u_h². The
    power the others may hold (their summed excess, ≥ 0) goes to the noisiest of them: where
    the data cannot say which harmonic holds it, the split that spreads the THD most (largest
    u_h) is taken, so the belt is not made too narrow by a noise-driven split (with unequal u_h,
    as for the FOG). All of it there when nothing is detected.
    """
    n = ah.size
    q = 2.0 * math.log(n / 0.05)  # χ²₂ isf(0.05/n) = −2·ln(0.05/n)
    detected = ah**2 > q * uh**2
    w = np.where(detected, ah**2 - 2.0 * uh**2, 0.0)
    rest = ~detected
    if np.any(rest):
        rem = max(float(np.sum(ah[rest] ** 2 - 2.0 * uh[rest] ** 2)), 0.0)
        noisiest = int(np.flatnonzero(rest)[np.argmax(uh[rest])])
        w[noisiest] += rem
    total = float(w.sum())
    if not total > 0:
        w = np.zeros(n)
        w[int(np.argmax(uh))] = 1.0
        total = 1.0
    return np.asarray(w / total)


def thd_uncertainty(
    amplitudes: Any,
    amplitudes_u: Any,
    *,
    dof: float = math.inf,
    unit: str = _DEG,
    p: float = _P,
    trials: int = THD_TRIALS,
    seed: int = THD_SEED,
) -> ThdUncertainty:
    """THD (eq. (1)) with its standard uncertainty, bias, bias-corrected value and the 95 %
    coverage interval for the true THD, valid down to a true THD of zero.

    Model. The fitted in-phase and quadrature components of harmonic h are N(A_h, u_h²) each
    (the multi-harmonic fit's white-noise covariance: equal variances, uncorrelated over whole
    periods), so the measured power ``T = Σ_{h≥2} |Â_h|²`` has the mean P + 2Σu_h² and a
    (generalised) noncentral χ² distribution; A_1 likewise. The plain THD ``100·√T/|Â_1|`` is
    biased upward by noise and first-order propagation is meaningless near zero (JCGM 102 §9).

    * ``bias_corrected`` removes the expected noise power (:func:`thd_bias_corrected_percent`).
    * ``u`` and ``bias``: the plain estimator simulated (M draws) at the bias-corrected THD, the
      power split over the harmonics as detected (:func:`_power_split`; the undetected part in
      the noisiest harmonic) — its standard deviation and its mean minus that THD. (Simulating at the plain value instead adds the noise a second time.)
    * ``interval``: a Neyman confidence belt of the plain THD over true values, from the same
      draws: coverage p at every true THD, up to the Monte Carlo error √(α(1−α)/M) of each tail
      and the plug-in of A_1, u_h and the power split. One-sided [0, high] when the measured
      power is consistent with noise, central well above it (see :func:`_thd_interval`). For
      equal u_h the belt is the noncentral χ² one of ``T/u²`` (2(N − 1) degrees of freedom);
      with unequal u_h (the FOG: u_h ∝ 1/h) no closed form exists, hence the simulation.
    * ``U`` = half the interval's width, ``k = U/u``; ``U_mc_error`` its Monte Carlo standard
      error.

    Parameters
    ----------
    amplitudes : array_like — A_1…A_N (unit ``unit``), h = 1 first.
    amplitudes_u : array_like — their standard uncertainties (same unit).
    dof : float — ν of the u_h (N − p of the fit; the first-order rows only).
    unit : str — unit of the amplitudes (budget text).
    p : float — coverage probability.
    trials : int — Monte Carlo draws M.
    seed : int — seed of the draws (the same capture always gives the same budget).

    Returns
    -------
    ThdUncertainty

    References
    ----------
    Feng et al. 2023, Sensors 23:4876, eq. (1); JCGM 101:2008 §7 (Monte Carlo), §7.9 (its
    numerical accuracy), §8; JCGM 102:2011 §9 (magnitude of a complex quantity near zero);
    J. Neyman (1937), Phil. Trans. R. Soc. A 236:333, §III (confidence belts); G. J. Feldman &
    R. D. Cousins (1998), Phys. Rev. D 57:3873 (intervals near a physical boundary, without
    choosing one- or two-sided from the data).
    """
    a = np.asarray(amplitudes, dtype=float)
    u = np.asarray(amplitudes_u, dtype=float)
    if a.shape != u.shape or a.ndim != 1 or a.size < 1:
        raise ConfigError("amplitudes and amplitudes_u must be 1-D arrays of the same length.")
    if not a[0] > 0 or np.any(a < 0) or np.any(u < 0) or not np.all(np.isfinite(a + u)):
        raise ConfigError("amplitudes must be finite with A_1 > 0, their u finite and ≥ 0.")
    if isinstance(trials, bool) or not isinstance(trials, int) or trials < 1000:
        raise ConfigError(f"trials must be an integer ≥ 1000, got {trials!r}.")
    nh = a.size
    tail = 0.5 * (1.0 - p)
    root = math.sqrt(float(a[1:] @ a[1:]))
    plain = 100.0 * root / float(a[0])
    corrected = thd_bias_corrected_percent(a, u)
    uh = u[1:]
    noise_free = nh < 2 or not (float(uh @ uh) > 0 or u[0] > 0)
    if noise_free:
        lo = hi = plain
        u_thd, mc_mean, u_mc = 0.0, plain, 0.0
    else:
        draws = _ThdDraws(a, u, _power_split(a[1:], uh), trials, seed)
        at_corrected = draws.plain(corrected)
        mc_mean = float(np.mean(at_corrected))
        u_thd = float(np.std(at_corrected, ddof=1))
        p_star = 4.0 * math.sqrt(float(np.sum(uh**4)))  # 2 standard deviations of T at P = 0
        scale = 100.0 * (math.sqrt(2.0 * float(uh @ uh)) + plain * u[0]) / float(a[0])
        lo, hi, u_mc = _thd_interval(draws, plain, p, p_star, max(scale, 1e-300))
    big_u = 0.5 * (hi - lo)
    k = big_u / u_thd if u_thd > 0 else float(stats.norm.isf(tail))
    bias = mc_mean - corrected

    # first-order GUM for the rows and the comparison with the interval
    sens = np.empty(nh)
    sens[0] = -plain / a[0]
    sens[1:] = 100.0 * a[1:] / (a[0] * root) if root > 0 else 100.0 / a[0]
    ins = [
        Input(f"A_{h}", float(a[h - 1]), float(u[h - 1]), dof=dof, unit=unit)
        for h in range(1, nh + 1)
    ]

    def thd_model(*x: float) -> float:
        xa = np.asarray(x)
        return 100.0 * math.sqrt(float(xa[1:] @ xa[1:])) / float(xa[0])

    gum = propagate(thd_model, ins, jacobian=lambda *x: sens, p=p, names_out=["thd_percent"])
    u_gum = float(gum.u[0])
    side = "two-sided"
    if lo == 0:
        side = "one-sided: the measured harmonic power is consistent with noise"
    notes = [
        f"Monte Carlo (JCGM 101), M = {trials} draws of every harmonic's in-phase and quadrature "
        "components from N(A_h, u_h²) (the fit's white-noise covariance), A_h at the "
        f"bias-corrected THD {corrected:.4g} % (noise power 2Σu_h² subtracted; split over the "
        "harmonics as detected, the undetected part on the noisiest): u is the standard deviation of the plain THD of eq. (1), "
        f"its noise bias {bias:+.3g} pp.",
        f"95 % coverage interval for the true THD [{lo:.4g}, {hi:.4g}] % ({side}): a Neyman "
        "confidence belt of the plain THD over true values from the same draws, one-sided at a "
        "true THD of 0 and central from a true harmonic power of 2 standard deviations of the "
        "noise power on (the split set by the true value, not by the data, so the coverage "
        f"holds near zero too); U is half its width, k = U/u. Monte Carlo standard error of U: "
        f"{u_mc:.2g} pp ({100.0 * u_mc / big_u if big_u > 0 else 0.0:.2g} % of U).",
    ]
    if u_gum > 0 and big_u > 0:
        delta = numerical_tolerance(u_gum, 1)
        y_gum = float(gum.U[0])
        ok = abs(plain - y_gum - lo) <= delta and abs(plain + y_gum - hi) <= delta
        notes.append(
            f"first-order GUM gives u = {u_gum:.3g} %, plain ± U = [{plain - y_gum:.4g}, "
            f"{plain + y_gum:.4g}] %, which "
            + (
                "agrees with the interval at one significant digit of u (JCGM 101 §8)."
                if ok
                else "does not agree with the interval (JCGM 101 §8): first order is not "
                "adequate here (harmonics near the noise push the THD up, as for a magnitude "
                "near zero, JCGM 102)."
            )
            + " The rows show the first-order sensitivities and shares, for orientation."
        )
    notes.append(
        "no instrument specification enters the THD: it is a ratio of amplitudes of one sensor "
        "(scale factors and the timebase cancel)."
    )
    rows = tuple(
        BudgetRow(
            source=f"A_{h} (harmonic {h} of the fit)",
            value=float(a[h - 1]),
            unit=unit,
            distribution="normal, in-phase and quadrature",
            u=float(u[h - 1]),
            sensitivity=float(sens[h - 1]),
            contribution=float(sens[h - 1] * u[h - 1]),
            share=float((sens[h - 1] * u[h - 1]) ** 2 / u_gum**2) if u_gum > 0 else 0.0,
            dof=dof,
            origin="Type A",
        )
        for h in range(1, nh + 1)
    )
    budget = UncertaintyBudget(
        quantity="thd_percent",
        unit="%",
        value=plain,
        u=u_thd,
        dof_eff=math.inf,
        k=float(k),
        p=float(p),
        U=float(big_u),
        rows=rows,
        method="Monte Carlo",
        notes=tuple(notes),
        interval=(float(lo), float(hi)),
    )
    return ThdUncertainty(
        plain=plain,
        bias_corrected=corrected,
        mc_mean=mc_mean,
        bias=bias,
        u=u_thd,
        U=float(big_u),
        k=float(k),
        interval=(float(lo), float(hi)),
        U_mc_error=float(u_mc),
        trials=int(trials),
        budget=budget,
    )


# ------------------------------------------------------------------------------ the budgets
@dataclasses.dataclass(frozen=True)
class MotionUncertainty:
    """Budgets of one motion calibration (JSON key → budget), the THD's evaluation, and the
    results corrected for the stated means of the specifications (GUM §3.2.4).

    Attributes
    ----------
    budgets : JSON key → budget; each budget's ``value`` is the reported result.
    thd : the THD's evaluation (its ``plain`` is ``thd_percent``).
    amplitudes_deg, amplitudes_u_deg : A_h and u(A_h) (deg), h = 1…N, corrected: A_1 is
        ``amplitude_deg``; a scale-factor or timebase mean scales every A_h alike.
    reversal_times_s : the reversing moments (s), in true time when a timebase mean is stated.
    timebase_error : the stated mean e₀ of the timebase's fractional error (0 when none): a time
        stamp t is the true time ``t₀ + (t − t₀)/(1 + e₀)``.
    """

    budgets: dict[str, UncertaintyBudget]
    thd: ThdUncertainty
    amplitudes_deg: np.ndarray
    amplitudes_u_deg: np.ndarray
    reversal_times_s: np.ndarray
    timebase_error: float = 0.0


def _lts_sensitivities(
    fit: SineFit, radius_mm: float
) -> tuple[float, tuple[float, float], tuple[float, float]]:
    """(∂A/∂R in deg/mm, (c₊, c₋) in deg/µm, (θ_max, θ_min) in deg) of θ = arctan(D/R)."""
    tau, theta = _one_period(fit)
    w = 2.0 * math.pi * fit.frequency_hz
    th = np.radians(theta)
    g = -np.degrees(np.sin(2.0 * th) / (2.0 * radius_mm))  # ∂θ/∂R, deg/mm
    da = 2.0 * float(np.mean(g * np.cos(w * tau)))  # change of a_1 (cos) and b_1 (sin)
    db = 2.0 * float(np.mean(g * np.sin(w * tau)))
    a1, b1 = float(fit.cos_coefs[0]), float(fit.sin_coefs[0])
    c_r = (a1 * da + b1 * db) / math.hypot(a1, b1)
    t_max, t_min = float(np.max(theta)), float(np.min(theta))

    def half_dtheta_dd(theta_deg: float) -> float:  # ½·∂θ/∂D in deg per µm
        d = radius_mm * math.tan(math.radians(theta_deg))
        return 0.5 * math.degrees(radius_mm / (radius_mm**2 + d**2)) * 1e-3

    return c_r, (half_dtheta_dd(t_max), half_dtheta_dd(t_min)), (t_max, t_min)


def motion_budgets(
    *,
    scheme: Scheme,
    fit: SineFit,
    displacement_amplitudes: np.ndarray,
    displacement_amplitudes_u: np.ndarray,
    reversal_times_s: np.ndarray,
    detection: ReversalDetection,
    specs: InstrumentSpecs | None = None,
    set_amplitude_deg: float | None = None,
    set_frequency_hz: float | None = None,
    radius_mm: float | None = None,
) -> MotionUncertainty:
    """Every budget of a sinusoidal-motion calibration (see the module docstring for the models).

    A specification stated with a non-zero mean is a recognised systematic effect: the results
    are corrected for it (GUM §3.2.4) and its budget row keeps the stated value and u, with a
    note. Corrections: timebase e₀ → f = f_fit(1 + e₀), reversal times t₀ + (t − t₀)/(1 + e₀)
    and, for the FOG, A = A_fit/(1 + e₀); FOG scale factor s₀ → A = A_fit/(1 + s₀); LTS
    resolution q₀ → A − (c₊ − c₋)·q₀; an encoder reading error common to both extremes cancels.

    Parameters
    ----------
    scheme : ``"encoder"``, ``"lts"`` or ``"fog"``.
    fit : SineFit — the multi-harmonic fit over the whole periods: of θ (deg) for the OSE and the
        LTS, of the rate (deg/s) for the FOG.
    displacement_amplitudes, displacement_amplitudes_u : array, deg — A_h and u(A_h), h = 1..N,
        as fitted (before corrections).
    reversal_times_s : array, s — every reversing moment found (capture's time stamps).
    detection : ReversalDetection — how those were found.
    specs : InstrumentSpecs, optional — the lab's Type B inputs (None: Type A only).
    set_amplitude_deg, set_frequency_hz : float, optional — the set values (deg, Hz).
    radius_mm : float, optional — R of the LTS (mm).

    Returns
    -------
    MotionUncertainty
        ``budgets`` keyed by the JSON names: ``amplitude_deg``, ``frequency_hz``,
        ``angular_acceleration_amplitude_deg_s2``, ``thd_percent``, ``reversal_times_s`` and,
        with set values, ``amplitude_error_percent``, ``frequency_error_percent``,
        ``angular_acceleration_error_percent``; the corrected amplitudes and reversal times.

    Raises
    ------
    ConfigError
        ``lts.radius_mm`` whose value is not the radius the calibration used.

    References
    ----------
    Feng et al. 2023, Sensors 23:4876, eqs. (1), (2), (7)–(8), (9)–(15); JCGM 100:2008 §3.2.4,
    §5, G.4; JCGM 101:2008 §7–8.
    """
    dof = fit_dof(fit)
    f_fit = float(fit.frequency_hz)
    n_text = f"Type A: multi-harmonic fit, N = {fit.n_samples}, ν = N − {2 * fit.harmonics + 2}"
    a_fit = np.asarray(displacement_amplitudes, dtype=float)
    a_fit_u = np.asarray(displacement_amplitudes_u, dtype=float)
    e0 = _stated_mean(specs, "timebase.relative_error")
    s0 = _stated_mean(specs, "fog.scale_factor_relative") if scheme == "fog" else 0.0
    gain = 1.0 / ((1.0 + s0) * (1.0 + e0)) if scheme == "fog" else 1.0
    freq = f_fit * (1.0 + e0)
    amp = float(a_fit[0]) * gain  # + the LTS resolution's correction, below
    inputs: list[Input] = []
    # dA/d(input) and df/d(input) per input, in the order of ``inputs``; dα from them
    d_amp: list[float] = []
    d_freq: list[float] = []

    def add(inp: Input, da: float, df: float) -> None:
        inputs.append(inp)
        d_amp.append(da)
        d_freq.append(df)

    if scheme == "fog":
        a_rate = float(fit.amplitudes[0])
        add(
            Input(
                "A′ (rate amplitude, fit)",
                a_rate,
                float(fit.amplitudes_u[0]),
                dof=dof,
                unit="°/s",
                source=n_text,
            ),
            amp / a_rate,
            0.0,
        )
        # A = A′/(2π·f_fit·(1 + s)(1 + e)): ∂A/∂f_fit = −A/f_fit, ∂f/∂f_fit = 1 + e₀
        add(
            Input("f (fit)", f_fit, float(fit.frequency_u_hz), dof=dof, unit="Hz", source=n_text),
            -amp / f_fit,
            1.0 + e0,
        )
    else:
        add(
            Input(
                "A (fundamental, fit)",
                float(a_fit[0]),
                float(a_fit_u[0]),
                dof=dof,
                unit=_DEG,
                source=n_text,
            ),
            1.0,
            0.0,
        )
        add(
            Input("f (fit)", f_fit, float(fit.frequency_u_hz), dof=dof, unit="Hz", source=n_text),
            0.0,
            1.0 + e0,
        )
    tb = spec_input(specs, "timebase.relative_error", name="timebase error e")
    if tb is not None:
        add(tb, -amp / (1.0 + e0) if scheme == "fog" else 0.0, f_fit)
    if scheme == "encoder":
        c = 1.0 / (2.0 * _ARCSEC_PER_DEG)
        for name, sign in (("at θ max", 1.0), ("at θ min", -1.0)):
            g = spec_input(
                specs, "encoder.graduation_error_arcsec", name=f"encoder graduation error {name}"
            )
            if g is not None:  # reading = true + g: A = A_fit − (g₊ − g₋)/7200
                add(g, -sign * c, 0.0)
    if scheme == "lts" and specs is not None and radius_mm is not None:
        r_in = specs.input("lts.radius_mm", name="LTS radius R")
        q_stated = specs.get("lts.resolution_um") is not None
        if r_in is not None or q_stated:
            c_r, (c_p, c_m), (t_max, t_min) = _lts_sensitivities(fit, float(radius_mm))
            if r_in is not None:
                if abs(r_in.value - radius_mm) > 1e-9 * abs(radius_mm):
                    raise ConfigError(
                        f"{specs.source}: lts.radius_mm states R = {r_in.value:g} mm but the "
                        f"calibration used --radius-mm {radius_mm:g}; make them the same."
                    )
                add(r_in, c_r, 0.0)
            for name, cc, sign in (
                (f"LTS resolution at θ max ({t_max:.4g}°)", c_p, 1.0),
                (f"LTS resolution at θ min ({t_min:.4g}°)", c_m, -1.0),
            ):
                q = specs.input("lts.resolution_um", name=name)
                if q is not None:  # reading = true + q: A = A_fit − c₊·q₊ + c₋·q₋
                    add(q, -sign * cc, 0.0)
                    amp += -sign * cc * q.value
    if scheme == "fog":
        s = spec_input(specs, "fog.scale_factor_relative", name="FOG scale-factor error s")
        if s is not None:
            add(s, -amp / (1.0 + s0), 0.0)

    w = 2.0 * math.pi * freq
    acc = amp * w * w  # α = A·(2πf)² with the corrected A and f (the FOG's too)
    j_amp = np.array(d_amp)
    j_freq = np.array(d_freq)
    j_acc = w * w * j_amp + 2.0 * acc / freq * j_freq  # ∂α = ω²·∂A + (2α/f)·∂f
    rows = [j_amp, j_freq, j_acc]
    values = [amp, freq, acc]
    names = ["amplitude_deg", "frequency_hz", "angular_acceleration_amplitude_deg_s2"]
    units = [_DEG, "Hz", "°/s²"]
    with_set = set_amplitude_deg is not None and set_frequency_hz is not None
    if with_set:
        assert set_amplitude_deg is not None and set_frequency_hz is not None
        set_acc = set_amplitude_deg * (2 * math.pi * set_frequency_hz) ** 2
        for val, jr, ref, name in (
            (amp, j_amp, set_amplitude_deg, "amplitude_error_percent"),
            (freq, j_freq, set_frequency_hz, "frequency_error_percent"),
            (acc, j_acc, set_acc, "angular_acceleration_error_percent"),
        ):
            rows.append(100.0 * jr / ref)
            values.append(100.0 * (val - ref) / ref)
            names.append(name)
            units.append("%")
    jac = np.vstack(rows)
    x0 = np.array([inp.value for inp in inputs])
    y0 = np.array(values)

    def model(*x: float) -> np.ndarray:  # linearised about the (corrected) estimates
        return np.asarray(y0 + jac @ (np.asarray(x) - x0))

    gum = propagate(model, inputs, jacobian=lambda *x: jac, p=_P, names_out=names, units_out=units)
    amp_keys = _AMPLITUDE_SPECS[scheme]
    acc_keys = tuple(dict.fromkeys(amp_keys + _TIMEBASE))
    spec_keys = {
        "amplitude_deg": amp_keys,
        "amplitude_error_percent": amp_keys,
        "frequency_hz": _TIMEBASE,
        "frequency_error_percent": _TIMEBASE,
        "angular_acceleration_amplitude_deg_s2": acc_keys,
        "angular_acceleration_error_percent": acc_keys,
    }
    budgets: dict[str, UncertaintyBudget] = {}
    for j, name in enumerate(names):
        keys = spec_keys[name]
        notes = [*_spec_notes(specs, keys), *_correction_notes(specs, keys)]
        b = gum.budget(j)
        sources = " ".join(r.source for r in b.rows if r.sensitivity != 0.0)
        if "encoder graduation error" in sources:
            notes.append(
                "the graduation error enters as the reading error at the two extremes of the "
                "stroke (A is half the stroke), the two taken as independent: exact for an error "
                "that varies linearly across the stroke."
            )
        if "LTS radius" in sources:
            notes.append(
                "∂A/∂R is the projection of ∂θ/∂R = −sin 2θ/(2R) onto the fundamental (≈ −A/R)."
            )
        if "LTS resolution" in sources:
            notes.append(
                "the resolution enters at the two extremes (½·R/(R² + D²) each): conservative when "
                "the noise dithers the quantiser (it is then in the Type A row too)."
            )
        if name.endswith("_error_percent"):
            notes.append("set values are exact (they define the error).")
        budgets[name] = tidy(b, *notes)

    # every A_h alike for the scale factor and timebase; A_1 also carries the LTS correction
    amps = a_fit * gain
    amps[0] = amp
    amps_u = a_fit_u * gain
    thd = thd_uncertainty(amps, amps_u, dof=dof)
    budgets["thd_percent"] = thd.budget
    t0 = float(detection.capture_start_s)
    times = t0 + (np.asarray(reversal_times_s, dtype=float) - t0) / (1.0 + e0)
    budgets["reversal_times_s"] = _reversal_budget(times, detection, specs)
    order = [
        "amplitude_deg",
        "frequency_hz",
        "angular_acceleration_amplitude_deg_s2",
        "thd_percent",
        "reversal_times_s",
        "amplitude_error_percent",
        "frequency_error_percent",
        "angular_acceleration_error_percent",
    ]
    return MotionUncertainty(
        budgets={k: budgets[k] for k in order if k in budgets},
        thd=thd,
        amplitudes_deg=amps,
        amplitudes_u_deg=amps_u,
        reversal_times_s=times,
        timebase_error=e0,
    )


# ------------------------------------------------------------------------------ comparison
def comparison_budgets(
    reference: Mapping[str, UncertaintyBudget],
    other: Mapping[str, UncertaintyBudget],
    *,
    reference_scheme: str,
    other_scheme: str,
) -> dict[str, UncertaintyBudget]:
    """Budgets of the differences of two schemes on the same run (Feng et al. 2023, Table 1).

    ``thd_difference_percent = THD_ref − THD_other`` (pp), ``amplitude_difference_percent =
    100·(A_ref − A_other)/A_ref`` and ``frequency_difference_percent`` likewise; the inputs are the
    two results with their combined standard uncertainties and ν_eff, taken as independent
    (different sensors; a timebase shared by both would cancel in the frequency difference, so
    this is then conservative).

    Parameters
    ----------
    reference, other : mapping of str to UncertaintyBudget — the two results' budgets.
    reference_scheme, other_scheme : str — their names (row labels).

    Returns
    -------
    dict — ``thd_difference_percent``, ``amplitude_difference_percent``,
    ``frequency_difference_percent`` → UncertaintyBudget.

    References
    ----------
    Feng et al. 2023, Sensors 23:4876, §5, Table 1; JCGM 100:2008 (GUM) eq. (10), G.4.
    """
    out: dict[str, UncertaintyBudget] = {}
    note = (
        "the two schemes' results are taken as independent (different sensors); a shared timebase "
        "would cancel in the frequency difference, so its u is then conservative."
    )
    for name, key, unit in (
        ("thd_difference_percent", "thd_percent", "%"),
        ("amplitude_difference_percent", "amplitude_deg", _DEG),
        ("frequency_difference_percent", "frequency_hz", "Hz"),
    ):
        r, o = reference[key], other[key]
        ins = [
            Input(
                f"{key} by {reference_scheme}",
                r.value,
                r.u,
                dof=r.dof_eff if r.dof_eff > 0 else math.inf,
                unit=unit,
                source=f"its budget ({r.method})",
            ),
            Input(
                f"{key} by {other_scheme}",
                o.value,
                o.u,
                dof=o.dof_eff if o.dof_eff > 0 else math.inf,
                unit=unit,
                source=f"its budget ({o.method})",
            ),
        ]
        if key == "thd_percent":
            jac = np.array([1.0, -1.0])

            def model(a: float, b: float) -> float:
                return a - b
        else:
            jac = np.array([100.0 * o.value / r.value**2, -100.0 / r.value])

            def model(a: float, b: float) -> float:
                return 100.0 * (a - b) / a

        gum = propagate(
            model,
            ins,
            jacobian=lambda *x, jj=jac: jj,
            p=_P,
            names_out=[name],
            units_out=["%" if key != "thd_percent" else "pp"],
        )
        out[name] = tidy(gum.budget(0), note)
    return out
