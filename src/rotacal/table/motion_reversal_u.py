"""Uncertainty of the reversing moments of the sinusoidal-motion calibration (Feng et al. 2023).

One estimator per scheme — the extreme sample of eqs. (7)–(8) (OSE), the vertex of a
least-squares parabola (LTS), the zero crossings of the fitted rate (FOG) — and the budget of the
reversal times (detection, Type A, and the timebase, Type B). Part of
:mod:`rotacal.table.motion_uncertainty`, which re-exports every name.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any, Literal

import numpy as np

from rotacal.errors import ConfigError
from rotacal.signal import SineFit
from rotacal.table._motion_helpers import (
    _P,
    _TIMEBASE,
    _correction_notes,
    _fit_sigma,
    _second_derivative,
    _spec_notes,
    fit_dof,
)
from rotacal.uncertainty import (
    Input,
    InstrumentSpecs,
    UncertaintyBudget,
    propagate,
)
from rotacal.uncertainty.notes import tidy
from rotacal.uncertainty.specs import spec_input

#: Draws of the Monte Carlo of the OSE's reversal estimator (u to ≈ 1/√(2·4000) ≈ 1.1 %).
REVERSAL_DRAWS = 4000


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


def _argmax_inputs(
    name: str, noise_deg: float, curvature_deg_s2: float, sample_interval_s: float
) -> tuple[float, float, float]:
    """σ (deg), κ (deg/s²) and dt (s) as floats, refused unless dt > 0, κ > 0 and σ ≥ 0."""
    sigma, kappa, dt = float(noise_deg), float(curvature_deg_s2), float(sample_interval_s)
    if not (dt > 0 and kappa > 0 and sigma >= 0):
        raise ConfigError(
            f"{name} needs dt > 0, curvature > 0 and noise ≥ 0; got {dt!r}, {kappa!r}, {sigma!r}."
        )
    return sigma, kappa, dt


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
    sigma, kappa, dt = _argmax_inputs(
        "reversal_time_u_argmax", noise_deg, curvature_deg_s2, sample_interval_s
    )
    if sigma == 0.0:
        return dt / math.sqrt(12.0)
    rng = np.random.default_rng(seed)
    phi0 = rng.uniform(0.0, 2.0 * math.pi, draws)
    s_eff = sigma / np.maximum(np.abs(np.sin(phi0)), np.abs(np.cos(phi0)))
    return argmax_error_rms(s_eff, kappa, dt, rng)


def reversal_time_u_argmax_tabulated(
    noise_deg: float, curvature_deg_s2: float, sample_interval_s: float
) -> float:
    """:func:`reversal_time_u_argmax` from its tabulated Monte Carlo, in microseconds.

    ``u/dt`` depends on ``g = σ/(κ·dt²)`` only (:mod:`rotacal.table._argmax_table`, where the
    Monte Carlo of :func:`argmax_error_rms` was run once with 40,000 draws a point); the mixture
    over the signal's phase at the reversal is a Gauss–Legendre average. Beyond the table's
    largest g (10⁷: a noise ten million times the parabola's drop over one sample) the Monte
    Carlo of :func:`reversal_time_u_argmax` runs instead.

    Parameters
    ----------
    noise_deg : float
        σ of the demodulated angle's noise (deg).
    curvature_deg_s2 : float
        |θ''| at the reversal (deg/s²), > 0.
    sample_interval_s : float
        dt (s), > 0.

    Returns
    -------
    float
        u(t_rev) (s).

    References
    ----------
    Feng et al. 2023, Sensors 23:4876, §3.2, eqs. (7)–(8); JCGM 101:2008 §7.
    """
    from rotacal.table import _argmax_table

    sigma, kappa, dt = _argmax_inputs(
        "reversal_time_u_argmax_tabulated", noise_deg, curvature_deg_s2, sample_interval_s
    )
    g = sigma / (kappa * dt * dt)
    if not _argmax_table.in_range(g * math.sqrt(2.0)):
        return reversal_time_u_argmax(sigma, kappa, dt)
    return dt * _argmax_table.u_over_dt(g)


def argmax_error_rms(
    s_eff: np.ndarray,
    kappa: float,
    dt: float,
    rng: np.random.Generator,
    *,
    max_work: int = 4_000_000,
) -> float:
    """rms error (s) of the arg max of ``−κτ²/2 + s_eff[i]·z`` on the sampling grid, one draw per
    entry of ``s_eff`` (the noise σ/|s′| of each draw, deg), the grid's offset uniform.

    The Monte Carlo of :func:`reversal_time_u_argmax` (JCGM 101 §7), also used to tabulate it
    (:mod:`rotacal.table._argmax_table`). At most ``max_work`` normal draws (fewer draws for very
    wide windows, at least 100).
    """
    # beyond a drop of 10 σ_eff the parabola's samples never win the arg max
    half = math.sqrt(2.0 * 10.0 * float(s_eff.max()) / kappa) + 2.0 * dt
    k = np.arange(-math.ceil(half / dt), math.ceil(half / dt) + 1, dtype=float)
    draws = min(s_eff.size, max(100, max_work // k.size))
    s_eff = s_eff[:draws]
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
            u_r = np.array([reversal_time_u_argmax_tabulated(s, k_med, dt)])
            how = (
                "extreme sample of eqs. (7)–(8) (Monte Carlo of that estimator, tabulated over "
                f"σ/(κ·dt²)), angle noise s = {s:.3g} °, sampled every {dt:.3g} s"
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
