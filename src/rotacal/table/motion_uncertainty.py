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
  Carlo of that estimator, run once and tabulated over σ/(κ·dt²); LTS: vertex of the
  least-squares parabola over ±T/20,
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
import math
from collections.abc import Mapping
from typing import Literal

import numpy as np

from rotacal.errors import ConfigError
from rotacal.signal import SineFit

# The budgets' parts live in their own modules; their names stay importable from here.
from rotacal.table._motion_helpers import (  # noqa: F401  (re-exported)
    _DEG,
    _P,
    _TIMEBASE,
    _correction_notes,
    _fit_sigma,
    _one_period,
    _second_derivative,
    _spec_notes,
    _stated_mean,
    fit_dof,
)
from rotacal.table.motion_reversal_u import (  # noqa: F401  (re-exported)
    REVERSAL_DRAWS,
    ReversalDetection,
    _reversal_budget,
    parabola_vertex_bias,
    reversal_time_u_argmax,
    reversal_time_u_argmax_tabulated,
    reversal_time_u_parabola,
    reversal_time_u_rate_zero,
)
from rotacal.table.motion_thd import (  # noqa: F401  (re-exported)
    THD_SEED,
    THD_TRIALS,
    ThdUncertainty,
    _power_split,
    _thd_interval,
    _ThdDraws,
    thd_bias_corrected_percent,
    thd_uncertainty,
)
from rotacal.uncertainty import (
    Input,
    InstrumentSpecs,
    UncertaintyBudget,
    propagate,
)
from rotacal.uncertainty.notes import tidy
from rotacal.uncertainty.specs import spec_input

__all__ = [
    "ReversalDetection",
    "ThdUncertainty",
    "comparison_budgets",
    "fit_dof",
    "motion_budgets",
    "parabola_vertex_bias",
    "reversal_time_u_argmax",
    "reversal_time_u_argmax_tabulated",
    "reversal_time_u_parabola",
    "reversal_time_u_rate_zero",
    "thd_bias_corrected_percent",
    "thd_uncertainty",
]

_ARCSEC_PER_DEG = 3600.0

Scheme = Literal["encoder", "lts", "fog"]

#: The specifications each quantity of each scheme takes (others are ignored).
_AMPLITUDE_SPECS: dict[str, tuple[str, ...]] = {
    "encoder": ("encoder.graduation_error_arcsec",),
    "lts": ("lts.radius_mm", "lts.resolution_um"),
    "fog": ("fog.scale_factor_relative", "timebase.relative_error"),
}


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
