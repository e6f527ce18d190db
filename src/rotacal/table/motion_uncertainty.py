"""Uncertainty budgets of the sinusoidal-motion calibration (seed 000), one place for every path.

:func:`motion_budgets` gives the budget of every quantity a :class:`~rotacal.table.MotionResult`
reports — amplitude, frequency, angular-acceleration amplitude, their errors against set values,
THD and the reversing moments — from what the capture gives (the multi-harmonic fit's residual
noise and its covariance, Type A with ν = N − p) and from the lab's instrument specifications
(:class:`~rotacal.uncertainty.InstrumentSpecs`, Type B). It is called by the in-memory and the
chunked calibrations alike; :func:`comparison_budgets` serves
:func:`~rotacal.table.compare_schemes`.

Measurement models (sensitivities analytic):

* OSE: ``A = A_fit + (g₊ − g₋)/7200`` — g± (arcsec) the encoder's reading error at the two
  extremes of the motion (the amplitude is half the stroke between them; two graduation positions
  2A apart, taken as independent); ``f = f_fit·(1 + e)`` — e the timebase's fractional error (a
  clock running e fast stamps every time (1 + e) long, so the fitted frequency is f/(1 + e));
  ``α = A·(2πf)²``, hence ``∂α/∂A = (2πf)²``, ``∂α/∂f = 2α/f``, ``∂α/∂e = 2α``.
* LTS: θ = arctan(D/R) (eq. (15)): ``A = A_fit + c_R·(R − R₀) + c₊·q₊ − c₋·q₋`` with
  ``c_R = ∂A/∂R`` the projection of ``∂θ/∂R = −sin 2θ/(2R)`` onto the fundamental (≈ −A/R) and
  ``c± = ½·∂θ/∂D = ½·R/(R² + D±²)`` at the two extremes (q± the reading's resolution error there,
  not averaged by the fit when the noise does not dither the quantiser); f and α as for the OSE.
* FOG: the rate amplitude A′ and f are fitted; ``A = A′/(2πf_fit·(1 + s)(1 + e))`` and
  ``α = A′·2πf_fit·(1 + e)/(1 + s)`` with s the scale factor's relative error — so
  ``∂A/∂s = −A``, ``∂A/∂e = −A``, ``∂α/∂e = α``, ``∂α/∂s = −α``, ``∂A/∂f_fit = −A/f``.
* Errors against set values: ``100·(y − y_set)/y_set`` with exact set values.
* THD (eq. (1)) by Monte Carlo (JCGM 101): near zero it is biased upward by noise and first-order
  propagation is meaningless (JCGM 102, magnitude of a complex quantity). Each harmonic's
  in-phase and quadrature components are drawn from N(·, u_h²) — the fit's white-noise
  covariance, whose two components of one harmonic have equal variance and no correlation over
  whole periods, so u_h is also the standard uncertainty of A_h. Reported: the plain THD
  (unchanged), the Monte Carlo mean and u, the bias (mean − plain), the probabilistically
  symmetric 95 % interval and a bias-corrected value by noise-power subtraction (below).
* Reversing moments: the estimator's noise over the motion's curvature κ = |θ''| at the extremes
  (OSE: arg max of a noisy sampled parabola — the Chp of eqs. (7)–(8) —, evaluated by a Monte
  Carlo of that estimator; LTS: vertex of the least-squares parabola over ±T/20,
  ``u = s·√3/(κ·W·√n)``, plus that parabola's own error on extremes made asymmetric by the
  harmonics (the estimator applied to the fitted motion); FOG: zero crossing of the fitted rate,
  ``u² = s²(1 + 2H)/(N·κ²) + (τ·u(f)/f)²``), and the timebase: ``∂t/∂e = −(t − t₀)``.

Bias-corrected THD. ``E[Â_h²] = A_h² + 2u_h²`` for the fitted amplitude of a harmonic with
noise, so ``THD_bc = 100·√max(0, Σ_{h≥2}(Â_h² − 2u_h²))/Â_1`` removes the noise power instead of
subtracting the Monte Carlo bias (``2·plain − mean``). On the twin with a pure sine (true THD 0,
FOG at 10 dB, 20 seeds) the mean plain THD is 0.36 %, ``plain − bias`` 0.22 % (the Monte Carlo
adds noise to an estimate that already carries it, so its bias is too small) and the noise-power
subtraction 0.11 %; for a THD well above the noise all three agree within u/5
(tests/table/test_motion_uncertainty.py).

References
----------
Feng R., Yan J., Wu Y., Yu N., Yin X. (2023). Sensors 23:4876, eqs. (1), (2), (7)–(8), (9)–(15).
JCGM 100:2008 (GUM) §5.1.2, §6, G.4; JCGM 101:2008 §7 (Monte Carlo), §8 (validation of GUM);
JCGM 102:2011 §9 (magnitude near zero); IEEE Std 1057-2017 §4.1.3 (fit covariance).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Mapping, Sequence
from typing import Any, Literal

import numpy as np

from rotacal.errors import ConfigError
from rotacal.signal import SineFit
from rotacal.uncertainty import (
    BudgetRow,
    Input,
    InstrumentSpecs,
    MonteCarloResult,
    Normal,
    UncertaintyBudget,
    monte_carlo,
    propagate,
    validate_gum,
)
from rotacal.uncertainty.distributions import Distribution

__all__ = [
    "ReversalDetection",
    "ThdUncertainty",
    "comparison_budgets",
    "motion_budgets",
    "parabola_vertex_bias",
    "reversal_time_u_argmax",
    "reversal_time_u_parabola",
    "reversal_time_u_rate_zero",
    "thd_bias_corrected_percent",
    "thd_uncertainty",
]

#: Monte Carlo trials of the THD (fixed: ~0.1 s; u(THD) to ~0.2 %).
THD_TRIALS = 100_000
#: Seed of the THD Monte Carlo (the same capture always gives the same budget).
THD_SEED = 4876
#: Draws of the Monte Carlo of the OSE's reversal estimator.
REVERSAL_DRAWS = 4000
_P = 0.95
_ARCSEC_PER_DEG = 3600.0
_TYPE_A_ONLY = "no instrument specification stated: Type A only"
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
def _fit_dof(fit: SineFit) -> float:
    """ν = N − p of a refined multi-harmonic fit (p = 2H + 2: offset, H pairs, frequency)."""
    return float(max(fit.n_samples - (2 * fit.harmonics + 2), 1))


def _fit_sigma(fit: SineFit) -> float:
    """s = √(RSS/(N − p)), the residual's standard deviation (unit of the fitted signal)."""
    n = fit.n_samples
    return float(fit.residual_rms * math.sqrt(n / _fit_dof(fit)))


def _second_derivative(fit: SineFit, t: np.ndarray) -> np.ndarray:
    """d²y/dt² of the fitted model (unit of y per s²): coefficients −(hω)²·(a_h, b_h)."""
    w = 2.0 * math.pi * fit.frequency_hz
    hw2 = (w * np.arange(1, fit.harmonics + 1)) ** 2
    d2 = dataclasses.replace(
        fit, offset=0.0, cos_coefs=-hw2 * fit.cos_coefs, sin_coefs=-hw2 * fit.sin_coefs
    )
    return np.asarray(d2.evaluate(t))


def _one_period(fit: SineFit, points: int = 4096) -> tuple[np.ndarray, np.ndarray]:
    """(τ, model) over one period of the fundamental, uniformly (τ from t_ref, s)."""
    tau = np.arange(points) / (points * fit.frequency_hz)
    return tau, np.asarray(fit.evaluate(fit.t_ref_s + tau))


def _error_spec(specs: InstrumentSpecs | None, key: str) -> Distribution | None:
    """A stated instrument error, which rotacal takes as centred on zero."""
    if specs is None:
        return None
    dist = specs.get(key)
    if dist is None:
        return None
    mean = float(dist.mean)
    if mean != 0.0:
        raise ConfigError(
            f"{specs.source}: {key} has value {mean:g}, but rotacal takes this instrument error as "
            "centred on zero; correct the capture for a known error and state only its "
            "uncertainty (leave out value)."
        )
    return dist


def _spec_input(
    name: str, specs: InstrumentSpecs, key: str, dist: Distribution, unit: str
) -> Input:
    return Input.from_distribution(name, dist, unit=unit, source=f"Type B, {specs.source}")


def _spec_notes(specs: InstrumentSpecs | None, keys: Sequence[str]) -> tuple[str, ...]:
    if specs is None:
        return (_TYPE_A_ONLY,)
    missing = [k for k in keys if specs.get(k) is None]
    if not missing:
        return ()
    return (
        f"not stated in {specs.source}: {', '.join(missing)} — its effect is not in this budget.",
    )


def _with_notes(b: UncertaintyBudget, *notes: str) -> UncertaintyBudget:
    """The budget with ``notes`` added, the rows of inputs that do not enter it (sensitivity
    exactly 0: the outputs of one model share its inputs) left out, and the note on truncating
    a ν_eff above 100 dropped (it moves k by less than 10⁻³ relative)."""
    kept = tuple(n for n in b.notes if not (b.dof_eff > 100 and "truncated to" in n))
    rows = tuple(r for r in b.rows if r.sensitivity != 0.0) or b.rows
    return dataclasses.replace(b, rows=rows, notes=kept + tuple(n for n in notes if n))


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
        y = -0.5 * kappa * tau**2 + s_eff[s:e, None] * rng.standard_normal((e - s, k.size))
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
    for _ in range(2):
        tau = np.broadcast_to(k, (t.size, k.size))
        y = np.asarray(fit.evaluate(centre[:, None] + tau))
        q = k**2 - np.mean(k**2)
        c1 = (y @ k) / float(k @ k)
        c2 = (y @ q) / float(q @ q)
        centre = centre + np.where(c2 != 0, -c1 / (2.0 * np.where(c2 != 0, c2, 1.0)), 0.0)
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
    kappa = np.abs(np.asarray(fit.evaluate_derivative(t)))
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
    """u of every reversing moment: detection (Type A) and timebase (Type B)."""
    times = np.asarray(reversal_times, dtype=float)
    fit = det.fit
    dof = _fit_dof(fit)
    s = _fit_sigma(fit)
    dt = det.sample_interval_s
    if det.method == "rate_zero":
        u_r = reversal_time_u_rate_zero(fit, times)
        kappa = np.abs(np.asarray(fit.evaluate_derivative(times)))
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
    tb = _error_spec(specs, "timebase.relative_error")
    if tb is not None and specs is not None:
        inputs.append(_spec_input("timebase error e", specs, "timebase.relative_error", tb, ""))
        jac.append(-span)
    jrow = np.array(jac)

    def model(*x: float) -> float:
        return t_last + float(np.dot(jrow, x))

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
    ]
    return _with_notes(gum.budget(0), *notes)


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
    """The THD's Monte Carlo evaluation (all in % of the fundamental).

    Attributes
    ----------
    plain : eq. (1) from the fitted amplitudes (the reported ``thd_percent``).
    mc_mean : mean of the Monte Carlo values.
    bias : mc_mean − plain (pp): the noise's upward push.
    bias_corrected : :func:`thd_bias_corrected_percent`.
    u : standard deviation of the Monte Carlo values.
    interval : probabilistically symmetric 95 % coverage interval.
    U, k : half-width of that interval and U/u.
    budget : the UncertaintyBudget (method "Monte Carlo").
    mc : the engine's result.
    """

    plain: float
    mc_mean: float
    bias: float
    bias_corrected: float
    u: float
    U: float
    k: float
    interval: tuple[float, float]
    budget: UncertaintyBudget
    mc: MonteCarloResult


def _thd_model(nh: int) -> Callable[..., np.ndarray]:
    def model(**x: np.ndarray) -> np.ndarray:
        num = np.zeros_like(x["A1_inphase"])
        for h in range(2, nh + 1):
            num = num + x[f"A{h}_inphase"] ** 2 + x[f"A{h}_quadrature"] ** 2
        return np.asarray(100.0 * np.sqrt(num) / np.hypot(x["A1_inphase"], x["A1_quadrature"]))

    return model


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
    """THD (eq. (1)) with its Monte Carlo uncertainty, bias and bias-corrected value.

    Each harmonic h is (A_h + u_h·z₁, u_h·z₂) in its own in-phase/quadrature frame (the fit's
    isotropic white-noise covariance; the phase of a harmonic does not enter the THD), M =
    ``trials`` draws through :func:`rotacal.uncertainty.monte_carlo`. The budget rows show each
    amplitude with its first-order sensitivity ∂THD/∂A_h for orientation; the first-order GUM u
    is compared with the Monte Carlo interval (JCGM 101 §8) in a note.

    Parameters
    ----------
    amplitudes : array_like — A_1…A_N (unit ``unit``), h = 1 first.
    amplitudes_u : array_like — their standard uncertainties (same unit).
    dof : float — ν of the u_h (N − p of the fit).
    unit : str — unit of the amplitudes (budget text).
    p : float — coverage probability.
    trials : int — Monte Carlo trials M.
    seed : int — seed of the draws.

    Returns
    -------
    ThdUncertainty

    References
    ----------
    Feng et al. 2023, Sensors 23:4876, eq. (1), (14); JCGM 101:2008 §7, §8;
    JCGM 102:2011 §9 (magnitude of a complex quantity near zero).
    """
    a = np.asarray(amplitudes, dtype=float)
    u = np.asarray(amplitudes_u, dtype=float)
    if a.shape != u.shape or a.ndim != 1 or a.size < 1:
        raise ConfigError("amplitudes and amplitudes_u must be 1-D arrays of the same length.")
    if not a[0] > 0 or np.any(a < 0) or np.any(u < 0) or not np.all(np.isfinite(a + u)):
        raise ConfigError("amplitudes must be finite with A_1 > 0, their u finite and ≥ 0.")
    nh = a.size
    root = math.sqrt(float(a[1:] @ a[1:]))
    plain = 100.0 * root / float(a[0])
    inputs: dict[str, Distribution] = {}
    for h in range(1, nh + 1):
        inputs[f"A{h}_inphase"] = Normal(float(a[h - 1]), float(u[h - 1]))
        inputs[f"A{h}_quadrature"] = Normal(0.0, float(u[h - 1]))
    mc = monte_carlo(_thd_model(nh), inputs, trials=trials, p=p, seed=seed)
    assert isinstance(mc, MonteCarloResult)
    lo, hi = mc.interval_symmetric
    big_u = 0.5 * (hi - lo)
    k = big_u / mc.u if mc.u > 0 else 1.959963984540054
    corrected = thd_bias_corrected_percent(a, u)

    # first-order GUM for the rows and the JCGM 101 §8 comparison
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
    notes = [
        f"Monte Carlo (JCGM 101), M = {mc.trials} trials: the in-phase and quadrature components "
        "of every harmonic drawn from N(·, u_h²) (the fit's white-noise covariance); u is the "
        "standard deviation of the THD values.",
        f"Monte Carlo mean {mc.value:.6g} %, bias (mean − plain) {mc.value - plain:+.3g} pp; "
        f"bias-corrected THD {corrected:.6g} % (noise-power subtraction "
        "100·√max(0, Σ(A_h² − 2u_h²))/A_1); 95 % probabilistically symmetric coverage interval "
        f"[{lo:.6g}, {hi:.6g}] %, U its half-width, k = U/u.",
    ]
    if u_gum > 0 and mc.u > 0:
        check = validate_gum(gum, mc, ndigits=1)
        verdict = "agrees" if check["passed"] else "does not agree"
        notes.append(
            f"first-order GUM gives u = {u_gum:.3g} %; its interval {verdict} with the Monte "
            f"Carlo one at one significant digit (JCGM 101 §8)"
            + (
                ""
                if check["passed"]
                else ": first order is not adequate here (harmonics at the noise level push the "
                "THD up, as for a magnitude near zero, JCGM 102)"
            )
            + ". The rows show the first-order sensitivities and shares, for orientation."
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
        u=float(mc.u),
        dof_eff=math.inf,
        k=float(k),
        p=float(p),
        U=float(big_u),
        rows=rows,
        method="Monte Carlo",
        notes=tuple(notes),
    )
    return ThdUncertainty(
        plain=plain,
        mc_mean=float(mc.value),
        bias=float(mc.value) - plain,
        bias_corrected=corrected,
        u=float(mc.u),
        U=float(big_u),
        k=float(k),
        interval=(float(lo), float(hi)),
        budget=budget,
        mc=mc,
    )


# ------------------------------------------------------------------------------ the budgets
@dataclasses.dataclass(frozen=True)
class MotionUncertainty:
    """Budgets of one motion calibration (JSON key → budget) and the THD's Monte Carlo."""

    budgets: dict[str, UncertaintyBudget]
    thd: ThdUncertainty


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

    Parameters
    ----------
    scheme : ``"encoder"``, ``"lts"`` or ``"fog"``.
    fit : SineFit — the multi-harmonic fit over the whole periods: of θ (deg) for the OSE and the
        LTS, of the rate (deg/s) for the FOG.
    displacement_amplitudes, displacement_amplitudes_u : array, deg — A_h and u(A_h), h = 1..N.
    reversal_times_s : array, s — every reversing moment reported.
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
        ``angular_acceleration_error_percent``.

    Raises
    ------
    ConfigError
        A stated instrument error with a non-zero value, or ``lts.radius_mm`` whose value is not
        the radius the calibration used.

    References
    ----------
    Feng et al. 2023, Sensors 23:4876, eqs. (1), (2), (7)–(8), (9)–(15); JCGM 100:2008 §5, G.4;
    JCGM 101:2008 §7–8.
    """
    dof = _fit_dof(fit)
    f_fit = float(fit.frequency_hz)
    n_text = f"Type A: multi-harmonic fit, N = {fit.n_samples}, ν = N − {2 * fit.harmonics + 2}"
    inputs: list[Input] = []
    # d(A, f)/d(input) per input, in the order of ``inputs``
    d_amp: list[float] = []
    d_freq: list[float] = []
    d_acc_extra: list[float] = []  # FOG: α is not A·ω² of the inputs' own amplitude row
    amp = float(displacement_amplitudes[0])
    w = 2.0 * math.pi * f_fit
    acc = amp * w * w

    def add(inp: Input, da: float, df: float, dacc: float | None = None) -> None:
        inputs.append(inp)
        d_amp.append(da)
        d_freq.append(df)
        d_acc_extra.append(math.nan if dacc is None else dacc)

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
            acc / a_rate,
        )
        add(
            Input("f (fit)", f_fit, float(fit.frequency_u_hz), dof=dof, unit="Hz", source=n_text),
            -amp / f_fit,
            1.0,
            acc / f_fit,
        )
    else:
        add(
            Input(
                "A (fundamental, fit)",
                amp,
                float(displacement_amplitudes_u[0]),
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
            1.0,
        )
    tb = _error_spec(specs, "timebase.relative_error")
    if tb is not None and specs is not None:
        inp = _spec_input("timebase error e", specs, "timebase.relative_error", tb, "")
        if scheme == "fog":
            add(inp, -amp, f_fit, acc)
        else:
            add(inp, 0.0, f_fit)
    if scheme == "encoder" and specs is not None:
        g = _error_spec(specs, "encoder.graduation_error_arcsec")
        if g is not None:
            c = 1.0 / (2.0 * _ARCSEC_PER_DEG)
            for name, sign in (("at θ max", 1.0), ("at θ min", -1.0)):
                add(
                    _spec_input(
                        f"encoder graduation error {name}",
                        specs,
                        "encoder.graduation_error_arcsec",
                        g,
                        "arcsec",
                    ),
                    sign * c,
                    0.0,
                )
    if scheme == "lts" and specs is not None:
        r_dist = specs.get("lts.radius_mm")
        q = _error_spec(specs, "lts.resolution_um")
        if (r_dist is not None or q is not None) and radius_mm is not None:
            c_r, (c_p, c_m), (t_max, t_min) = _lts_sensitivities(fit, float(radius_mm))
            if r_dist is not None:
                r_mean = float(r_dist.mean)
                if abs(r_mean - radius_mm) > 1e-9 * abs(radius_mm):
                    raise ConfigError(
                        f"{specs.source}: lts.radius_mm states R = {r_mean:g} mm but the "
                        f"calibration used --radius-mm {radius_mm:g}; make them the same."
                    )
                add(
                    Input.from_distribution(
                        "LTS radius R", r_dist, unit="mm", source=f"Type B, {specs.source}"
                    ),
                    c_r,
                    0.0,
                )
            if q is not None:
                for name, c, sign in (
                    (f"LTS resolution at θ max ({t_max:.4g}°)", c_p, 1.0),
                    (f"LTS resolution at θ min ({t_min:.4g}°)", c_m, -1.0),
                ):
                    add(_spec_input(name, specs, "lts.resolution_um", q, "µm"), sign * c, 0.0)
    if scheme == "fog" and specs is not None:
        s = _error_spec(specs, "fog.scale_factor_relative")
        if s is not None:
            add(
                _spec_input("FOG scale-factor error s", specs, "fog.scale_factor_relative", s, ""),
                -amp,
                0.0,
                -acc,
            )

    j_amp = np.array(d_amp)
    j_freq = np.array(d_freq)
    extra = np.array(d_acc_extra)
    # α = A·(2πf)² for OSE/LTS: ∂α = ω²·∂A + (2α/f)·∂f; the FOG rows carry their own ∂α
    j_acc = np.where(np.isnan(extra), w * w * j_amp + 2.0 * acc / f_fit * j_freq, extra)
    rows = [j_amp, j_freq, j_acc]
    values = [amp, f_fit, acc]
    names = ["amplitude_deg", "frequency_hz", "angular_acceleration_amplitude_deg_s2"]
    units = [_DEG, "Hz", "°/s²"]
    with_set = set_amplitude_deg is not None and set_frequency_hz is not None
    if with_set:
        assert set_amplitude_deg is not None and set_frequency_hz is not None
        set_acc = set_amplitude_deg * (2 * math.pi * set_frequency_hz) ** 2
        for val, jr, ref, name in (
            (amp, j_amp, set_amplitude_deg, "amplitude_error_percent"),
            (f_fit, j_freq, set_frequency_hz, "frequency_error_percent"),
            (acc, j_acc, set_acc, "angular_acceleration_error_percent"),
        ):
            rows.append(100.0 * jr / ref)
            values.append(100.0 * (val - ref) / ref)
            names.append(name)
            units.append("%")
    jac = np.vstack(rows)
    x0 = np.array([inp.value for inp in inputs])
    y0 = np.array(values)

    def model(*x: float) -> np.ndarray:  # linearised about the estimates (all first order)
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
        notes = list(_spec_notes(specs, keys))
        b = gum.budget(j)
        sources = " ".join(r.source for r in b.rows if r.sensitivity != 0.0)
        if "encoder graduation" in sources:
            notes.append(
                "the graduation error enters as the reading error at the two extremes of the "
                "stroke (A is half the stroke), the two taken as independent."
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
        budgets[name] = _with_notes(b, *notes)

    thd = thd_uncertainty(displacement_amplitudes, displacement_amplitudes_u, dof=dof)
    budgets["thd_percent"] = thd.budget
    budgets["reversal_times_s"] = _reversal_budget(
        np.asarray(reversal_times_s, dtype=float), detection, specs
    )
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
    return MotionUncertainty(budgets={k: budgets[k] for k in order if k in budgets}, thd=thd)


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
        out[name] = _with_notes(gum.budget(0), note)
    return out
