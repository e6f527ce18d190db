"""Uncertainty budgets of a constant-rate calibration: the mean rate and the bias against the set
rate (GUM, validated by Monte Carlo, JCGM 101 §8), and the rms and peak of the rate deviation
(:mod:`rotacal.uncertainty.summaries`)."""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
from numpy.typing import NDArray

from rotacal.encoder.selfcal import (
    UNDETECTABLE_SPEC,
    DeviationNoise,
    SelfCalibration,
    noise_gain,
    undetectable_input,
    undetectable_orders,
)
from rotacal.errors import ConfigError
from rotacal.uncertainty import (
    Constant,
    Input,
    InstrumentSpecs,
    UncertaintyBudget,
    linear_fit_uncertainty,
    monte_carlo,
    propagate,
    validate_gum,
)
from rotacal.uncertainty.distributions import Distribution, Normal, Rectangular, StudentT
from rotacal.uncertainty.specs import (
    TYPE_A_ONLY_NOTE,
    corrected_note,
    spec_distribution,
    spec_input,
)
from rotacal.uncertainty.summaries import (
    COVERAGE,
    CirculantError,
    CovarianceCorrection,
    ErrorProcess,
    FilteredWhite,
    PeakInputs,
    SeriesStats,
    Summary,
    drop_large_dof_notes,
    mc_budget,
    rms_budget,
)

__all__ = []

FloatArray = NDArray[np.float64]

#: Trials of the Monte Carlo that validates the mean rate's GUM budget (JCGM 101 §8).
_VALIDATION_TRIALS = 200_000
_TIMEBASE = "timebase.relative_error"
_GRADUATION = "encoder.graduation_error_arcsec"


def _with_notes(
    b: UncertaintyBudget, notes: Sequence[str], method: str | None = None
) -> UncertaintyBudget:
    return dataclasses.replace(b, notes=(*b.notes, *notes), method=method or b.method)


def _validated(
    gum: Any,
    model: Any,
    dists: Mapping[str, Distribution],
    names: Sequence[str],
    unit: str,
    notes: Sequence[str],
) -> dict[str, UncertaintyBudget]:
    """The GUM budgets of ``names`` (the outputs of ``gum``), each validated by one Monte Carlo
    of the same model (JCGM 101 §8); where the GUM interval fails, U is half the Monte Carlo
    probabilistically symmetric 95 % interval (method "Monte Carlo")."""
    mc = monte_carlo(model, dists, trials=_VALIDATION_TRIALS, p=COVERAGE)
    results = mc if isinstance(mc, Mapping) else {names[0]: mc}
    checks = [validate_gum(gum, results[name], j=j, shortest=False) for j, name in enumerate(names)]
    # one decision for all outputs of the model (e.g. a bias in deg/s and in %): the same inputs
    # must not give a validated GUM U for one and a Monte Carlo U for the other
    passed = all(c["passed"] for c in checks)
    out: dict[str, UncertaintyBudget] = {}
    for j, name in enumerate(names):
        budget = drop_large_dof_notes(gum.budget(j))
        res, check = results[name], checks[j]
        unit_j = budget.unit or unit
        if passed:
            out[name] = _with_notes(
                budget,
                [
                    *notes,
                    f"the GUM interval agrees with a Monte Carlo of {res.trials} trials within "
                    f"the numerical tolerance {check['delta']:.2g} {unit_j} (JCGM 101 §8).",
                ],
                "GUM, validated by Monte Carlo",
            )
            continue
        lo, hi = res.interval_symmetric
        big_u = 0.5 * (hi - lo)
        worst = max(max(c["d_low"], c["d_high"]) / c["delta"] for c in checks)
        out[name] = dataclasses.replace(
            budget,
            U=big_u,
            k=big_u / budget.u if budget.u > 0 else budget.k,
            dof_eff=math.inf,
            method="Monte Carlo",
            notes=(
                *(n for n in budget.notes if "truncated to" not in n),
                *notes,
                f"the GUM interval ±{budget.U:.3g} {unit_j} is not validated by a Monte Carlo of "
                f"{res.trials} trials (an end is off by {worst:.2g} times the numerical "
                "tolerance, JCGM 101 §8; a rectangular or a t input with few degrees of freedom "
                f"dominates): U is half the Monte Carlo 95 % interval [{lo:.10g}, {hi:.10g}] "
                f"{unit_j}.",
            ),
        )
    return out


def _resolution_input(q: float) -> tuple[Input, Distribution]:
    """The readout's resolution q (deg) at the two ends of a rate's window, a Type B input.

    A crossing time interpolated between readings of quantum q is where the true angle is the
    mark plus an error within a width of q (truncating counter: [0, q); rounding readout:
    [−q/2, q/2)) — JCGM 100:2008 F.2.2.1, whether or not repeated readings vary: when the
    sampling is commensurate with the rotation the errors repeat every revolution and no Type A
    estimate sees them. How the two ends' errors are related depends on the sampling's phase at
    each (commensurate sampling makes them deterministic, not independent), so only the bounds
    of their difference are known, ±q: a rectangular distribution on them (JCGM 100 §4.3.7;
    JCGM 101 §6.4.2), u = q/√3 — wider than two independent rectangles (q/√6), which a
    commensurate twin exceeds.
    """
    return (
        Input(
            name="readout resolution at the window's two ends",
            value=0.0,
            u=q / math.sqrt(3.0),
            distribution="rectangular",
            unit="deg",
            source=(
                f"Type B, JCGM 100 F.2.2.1 and §4.3.7: each end's crossing is within the "
                f"readout's quantum q = {q:.6g}°, so the window's angle within ±q"
            ),
            description="rectangular ±q, q/√3",
        ),
        Rectangular(-q, q),
    )


def _mean_rate_budgets(
    rev_times: FloatArray,
    short: tuple[FloatArray, FloatArray] | None,
    m: int,
    revs: int,
    set_rate: float | None,
    specs: InstrumentSpecs | None,
    jitter: tuple[float, float, bool],
    resolution_deg: float | None = None,
) -> dict[str, UncertaintyBudget]:
    """GUM budgets of the mean rate and of the bias against the set rate, both validated by a
    Monte Carlo of their own model (JCGM 101 §8) — the same inputs give the same U.

    References
    ----------
    JCGM 100:2008 (GUM) §3.2.4 (correction for a stated systematic effect), §4.2–4.3, §5.1
    eq. (10), G.4 (Welch–Satterthwaite); JCGM 101:2008 §6.4.9 (a Type A input with ν degrees of
    freedom as a scaled t), §8 (validation of the GUM uncertainty framework); Kokuyama et al.
    (2015) §3, §5. ``rev_times`` are the times of pulses 0, m, …, R·m; ``short`` the times and
    angles of a record of less than one revolution. ``resolution_deg``: the quantum q (deg) of
    the readout the pulse times were interpolated from (:mod:`rotacal.table.rate_angle`), a Type
    B input (:func:`_resolution_input`).
    """
    sigma_t, sigma_dof, graduation_free = jitter
    tb = spec_input(specs, _TIMEBASE, name="timebase relative error", unit="")
    inputs: list[Input] = []
    dists: dict[str, Distribution] = {}
    notes: list[str] = []
    if revs >= 1:
        span = float(rev_times[revs] - rev_times[0])
        inputs.append(
            Input(
                name="pulse timing jitter at the window's two ends",
                value=0.0,
                u=math.sqrt(2.0) * sigma_t,
                dof=sigma_dof,
                distribution="normal",
                unit="s",
                source=(
                    f"Type A, σ_t = {sigma_t:.3g} s per pulse from the pulse times "
                    + (
                        "(the same line one and two revolutions later)"
                        if graduation_free
                        else "(along the pulses: includes the graduation, an upper bound)"
                    )
                ),
                description="normal, √2·σ_t",
            )
        )
        inputs.append(
            Input(
                name="graduation error over whole revolutions",
                value=0.0,
                u=0.0,
                distribution="constant",
                unit="arcsec",
                source=(
                    "exact: the window starts and ends on the same line, and m pitches make "
                    "exactly 360° whatever the scale's deviation"
                ),
                description="exact (0)",
            )
        )
        turns = 360.0 * revs

        # x = the inputs in the order of ``dists``: end-pulse timing error e (s), graduation g
        # (arcsec)[, readout resolution r (deg)][, timebase δ]
        def rate(*x: Any) -> Any:
            v = dict(zip(dists, x, strict=True))
            f = 1.0 + v.get("d", 0.0)
            return (turns + v["g"] / 3600.0 + v.get("r", 0.0)) / (span - v["e"]) * f

        def grad(*x: float) -> list[float]:  # exact ∂ω/∂x
            v = dict(zip(dists, x, strict=True))
            f = 1.0 + v.get("d", 0.0)
            a, t = turns + v["g"] / 3600.0 + v.get("r", 0.0), span - v["e"]
            parts = {"e": a / t**2 * f, "g": f / (3600.0 * t), "r": f / t, "d": a / t}
            return [parts[k] for k in dists]

        dists["e"] = Normal(0.0, math.sqrt(2.0) * sigma_t)
        dists["g"] = Constant(0.0)
    else:
        assert short is not None
        times, angle = short
        fit = linear_fit_uncertainty(times - times[0], angle)
        inputs.append(
            Input(
                name="straight-line fit of the angle over time",
                value=fit.slope,
                u=fit.u_slope,
                dof=float(fit.dof),
                distribution="normal",
                unit="deg/s",
                source=f"Type A, slope of {fit.n} pulses (residuals taken as independent)",
            )
        )
        notes.append(
            "less than one revolution: the graduation error the compensation leaves is not "
            "averaged out, and its correlated residuals make the fit's u a lower bound."
        )

        span = float(times[-1] - times[0])

        # x = (fitted slope e (deg/s)[, readout resolution r at the two ends (deg)][, δ])
        def rate(*x: Any) -> Any:
            v = dict(zip(dists, x, strict=True))
            return (v["e"] + v.get("r", 0.0) / span) * (1.0 + v.get("d", 0.0))

        def grad(*x: float) -> list[float]:  # exact ∂ω/∂x
            v = dict(zip(dists, x, strict=True))
            f = 1.0 + v.get("d", 0.0)
            parts = {"e": f, "r": f / span, "d": v["e"] + v.get("r", 0.0) / span}
            return [parts[k] for k in dists]

        dists["e"] = Normal(fit.slope, fit.u_slope)
    if resolution_deg is not None:
        res_input, dists["r"] = _resolution_input(resolution_deg)
        inputs.append(res_input)
    dist_tb = spec_distribution(specs, _TIMEBASE)
    if tb is not None and dist_tb is not None:
        inputs.append(tb)
        dists["d"] = dist_tb
        if tb.value != 0.0:
            notes.append(corrected_note(_TIMEBASE, tb.value, "", specs.source if specs else ""))
    elif specs is None:
        notes.append(TYPE_A_ONLY_NOTE)
    else:
        notes.append(
            f"{_TIMEBASE} not stated: the timebase error is not in the budget; rate ∝ 1/time, so "
            "a timebase of ±a makes the rate ∓a (relative)."
        )

    gum = propagate(
        rate,
        inputs,
        jacobian=grad,
        p=COVERAGE,
        names_out=["mean_rate_deg_s"],
        units_out=["deg/s"],
    )
    budgets = _validated(
        gum,
        lambda **kw: rate(*(kw[k] for k in dists)),
        dists,
        ["mean_rate_deg_s"],
        "deg/s",
        notes,
    )
    if set_rate is None:
        return budgets

    # the bias is the table's: its mean rate at this setting, not only in this record
    per_rev = 360.0 / np.diff(rev_times[: revs + 1]) if revs >= 1 else np.zeros(0)
    wander: list[Input] = []
    bias_notes: list[str] = []
    bias_dists = dict(dists)
    if per_rev.size >= 2:
        s_w = float(np.std(per_rev, ddof=1)) / math.sqrt(per_rev.size)
        wander.append(
            Input(
                name="table rate wander between revolutions",
                value=0.0,
                u=s_w,
                dof=float(per_rev.size - 1),
                distribution="normal",
                unit="deg/s",
                source=f"Type A, s/√R of {per_rev.size} single-revolution rates",
            )
        )
        bias_dists["w"] = StudentT(0.0, s_w, float(per_rev.size - 1))
        bias_notes.append(
            "the wander is the spread of the single-revolution rates (it also holds their "
            "timing jitter); it makes the bias a statement about the table at this setting, "
            "not only about this record; in the Monte Carlo it is a scaled t with ν = R − 1 "
            "(JCGM 101 §6.4.9)."
        )
    else:
        bias_notes.append(
            "fewer than two whole revolutions: the table's rate wander between records cannot be "
            "estimated, so the bias budget holds only this record's measurement."
        )
    n_in = len(inputs)
    names = ["rate_bias_deg_s", "rate_bias_percent"]

    def bias(*x: Any) -> Any:
        y = rate(*x[:n_in]) + (x[n_in] if len(x) > n_in else 0.0) - set_rate
        return np.array([y, 100.0 * y / set_rate])

    def bias_grad(*x: float) -> np.ndarray:
        g = np.array([*grad(*x[:n_in]), *([1.0] if len(x) > n_in else [])])
        return np.vstack([g, 100.0 * g / set_rate])

    def bias_mc(**kw: Any) -> dict[str, Any]:
        y = rate(*(kw[k] for k in dists)) + kw.get("w", 0.0) - set_rate
        return {names[0]: y, names[1]: 100.0 * y / set_rate}

    gb = propagate(
        bias,
        [*inputs, *wander],
        jacobian=bias_grad,
        p=COVERAGE,
        names_out=names,
        units_out=["deg/s", "%"],
    )
    extra = [*notes, *bias_notes, f"set rate {set_rate:.10g} deg/s taken as exact (the reference)."]
    budgets.update(_validated(gb, bias_mc, bias_dists, names, "deg/s", extra))
    return budgets


def _point_errors(autocov_lines: FloatArray, m: int, average: int, scale: float) -> FloatArray:
    """Autocovariance, over the rate points, of the error a curve on the scale lines gives them.

    Rate point i averages ``average`` pulse intervals from boundary line L_i = (i·A + L₀) mod m,
    so an angle error ξ(L) (arcsec) moves it by scale·(ξ(L_i + A) − ξ(L_i))/3600 (%). Along the
    points this is stationary with period P = m/gcd(A, m): c_η(k) = (scale/3600)²·[2c(kA) −
    c(kA + A) − c(kA − A)] (indices of c mod m), k = 0 … P − 1.
    """
    a = int(average)
    period = m // math.gcd(a, m)
    k = np.arange(period)
    c = autocov_lines
    lag = (k * a) % m
    eta = 2.0 * c[lag] - c[(lag + a) % m] - c[(lag - a) % m]
    return np.asarray((scale / 3600.0) ** 2 * eta, dtype=np.float64)


def _deviation_sources(
    *,
    m: int,
    heads: int,
    use_all: bool,
    compensated: bool,
    selfcal: Any,
    specs: InstrumentSpecs | None,
    average: int,
    omega: float,
    jitter: tuple[float, float, bool],
    own: tuple[list[int], int, int, float] | None = None,
    resolution_deg: float | None = None,
) -> tuple[list[ErrorProcess], list[str]]:
    """The errors of the rate points (% of rate): the timing jitter at each point's two ends,
    and the scale-curve errors the angle still holds (the self-calibration's noise, the orders
    it cannot see, an uncompensated graduation), each in its role.

    ``own`` = (head line shifts, rate head, revolutions of the self-calibration, share of the
    rate's pulses inside them) when the curve was self-calibrated from this capture: the rate
    head's timing noise is then also in the curve (:func:`rotacal.encoder.selfcal.noise_gain`),
    and the two partly cancel — a covariance correction of −2·Cov(curve error, the head's angle
    noise) per line. ``resolution_deg``: the quantum q of the readout the pulse times were
    interpolated from — each rate point's angle within ±q (:func:`_resolution_input`; drawn
    as normal of the same u), a bound: it widens the intervals and is never subtracted."""
    sigma_t, sigma_dof, graduation_free = jitter
    scale = 100.0 / (average * 360.0 / m)  # % of rate per degree of boundary angle error
    out: list[ErrorProcess] = []
    notes: list[str] = []
    # crossings of a quantised readout: a jitter within a quantum may be the quantisation's
    # pattern (not white, not of a level the train gives), so it is only a bound
    quantised = resolution_deg is not None and sigma_t * abs(omega) <= resolution_deg
    out.append(
        FilteredWhite(
            Input(
                name="pulse timing jitter",
                value=0.0,
                u=sigma_t,
                dof=sigma_dof,
                distribution="normal",
                unit="s",
                source="Type A, from the pulse times (see timing_jitter)"
                + ("" if graduation_free else "; an upper bound that holds the graduation too")
                + (
                    "; within one quantum of the readout (σ_t·ω ≤ q), it may be the "
                    "quantisation's pattern: a bound"
                    if quantised
                    else ""
                ),
            ),
            "noise" if graduation_free and not quantised else "bound",
            level="timing jitter",
            taps=np.array([-1.0, 1.0]) * scale * abs(omega),
            sigma=sigma_t,
        )
    )

    if resolution_deg is not None:
        res, _ = _resolution_input(resolution_deg)
        out.append(
            FilteredWhite(
                dataclasses.replace(res, name="readout resolution"),
                "bound",
                # q/√6 at each boundary: a point's two ends differ by ±q, rectangular (q/√3)
                taps=np.array([-1.0, 1.0]) * scale,
                sigma=resolution_deg / math.sqrt(6.0),
            )
        )

    def curve(inp: Input, autocov: FloatArray, role: Any) -> CirculantError:
        return CirculantError(inp, role, autocov=_point_errors(autocov, m, average, scale))

    und, und_note = undetectable_input(specs)
    grad = spec_input(specs, _GRADUATION, name="graduation error (not compensated)", unit="arcsec")
    if compensated:
        noise: DeviationNoise | None = None
        dof_sc = math.inf
        if isinstance(selfcal, SelfCalibration):
            noise = selfcal._noise
            pb = selfcal.point_budget
            if noise is not None and pb is not None and pb.rows:
                dof_sc = pb.rows[0].dof  # the revolutions' spread (Type A) alone
            if noise is None:
                notes.append(
                    "the self-calibration has no uncertainty from its data (one revolution): its "
                    "noise is not in the budgets."
                )
        elif isinstance(selfcal, Mapping) and selfcal.get("deviation_arcsec_u") is not None:
            try:
                u_pts = np.asarray(selfcal["deviation_arcsec_u"], dtype=np.float64)
            except (TypeError, ValueError):
                raise ConfigError(
                    "the self-calibration's 'deviation_arcsec_u' must be a list of numbers."
                ) from None
            if u_pts.shape != (m,) or not np.all(np.isfinite(u_pts)) or np.any(u_pts < 0):
                raise ConfigError(
                    f"the self-calibration's 'deviation_arcsec_u' must hold {m} finite values ≥ 0."
                )
            noise = DeviationNoise.white(m, float(np.sqrt(np.mean(u_pts**2))))
            notes.append(
                "the deviation's uncertainty comes from its JSON (one u per line): taken as white "
                "noise of that size (it may already hold the undetectable orders)."
            )
        else:
            notes.append(
                "the deviation was given without its uncertainty: its noise is not in the budgets."
            )
        if noise is not None:
            inp = Input(
                name="noise of the self-calibrated deviation",
                value=0.0,
                u=noise.point_u,
                dof=dof_sc,
                distribution="normal",
                unit="arcsec",
                source="Type A, the self-calibration's budget (per line)",
                description="normal, with the curve's spectrum",
            )
            out.append(curve(inp, noise.autocov(), "noise"))
            if own is not None and own[2] >= 2:
                shifts, head, revs, share = own
                kappa = noise_gain(shifts, m, head)
                s2 = (abs(omega) * sigma_t * 3600.0) ** 2  # the head's angle noise, arcsec²
                cross = np.fft.irfft(kappa.real, m) * (s2 / revs)  # Cov(curve(L), noise(L − ℓ))
                out.append(
                    CovarianceCorrection(
                        Input(
                            name="correlation of the rate head's timing noise with the curve",
                            value=0.0,
                            u=0.0,
                            unit="arcsec",
                            source=(
                                f"the curve was self-calibrated from this capture over {revs} "
                                "revolutions, so it holds this head's own timing noise "
                                f"(gain {float(np.mean(kappa.real[kappa.real != 0])):.3g} per "
                                "order, averaged over the revolutions)"
                            ),
                        ),
                        "noise",
                        level="timing jitter",
                        autocov=_point_errors(-2.0 * share * cross, m, average, scale),
                    )
                )
    if (compensated or use_all) and und is not None:
        n_sc = heads
        if isinstance(selfcal, SelfCalibration):
            n_sc = selfcal.heads
        elif isinstance(selfcal, Mapping) and isinstance(selfcal.get("heads"), int):
            n_sc = int(selfcal["heads"])
        mask = np.zeros(m // 2 + 1, dtype=bool)
        if n_sc >= 2:
            mask[undetectable_orders(n_sc, m)] = True
        model = DeviationNoise(m, np.zeros(m // 2 + 1), mask, und.u)
        out.append(curve(und, model.autocov(undetectable=True), "bound"))
        if und_note:
            notes.append(und_note)
        notes.append(
            f"{UNDETECTABLE_SPEC} is taken as a random curve, white across the undetectable "
            "orders (the cautious choice for a rate: a smooth n-th harmonic of the same rms moves "
            "it far less)."
        )
    elif compensated or use_all:
        notes.append(
            "the orders that are multiples of the number of heads stay in the rate (no "
            f"self-calibration sees them) and are not in its uncertainty; state {UNDETECTABLE_SPEC}."
        )
    if not compensated and not use_all:
        if grad is not None:
            out.append(curve(grad, DeviationNoise.white(m, grad.u).autocov(), "bound"))
            if grad.value != 0.0:
                notes.append(
                    f"the stated mean {grad.value:g} arcsec of {_GRADUATION} is a common offset "
                    "of every reading: a rate takes angle differences, so the correction for it "
                    "is exactly 0 (GUM §3.2.4); its u stays in the budget."
                )
        else:
            notes.append(
                "the rate is not compensated: the scale's graduation error is in it but not in its "
                f"uncertainty; compensate, or state {_GRADUATION}."
            )
    return out, notes


def _rate_deviation_budgets(
    dev_stats: SeriesStats,
    dev_peak: PeakInputs,
    sources: list[ErrorProcess],
    notes: list[str],
    specs: InstrumentSpecs | None,
) -> dict[str, Summary]:
    """Budgets of the rms (closed form) and the peak (Monte Carlo) of the rate deviation.

    A rate point averages A pulse intervals, so an angle error ξ_j at pulse j (deg: the angle's
    error minus ω times the time's error) moves it by (ξ_end − ξ_start)/(A·Δθ) relative: only the
    errors at the block boundaries count.

    References
    ----------
    JCGM 101:2008 §7 (Monte Carlo); Kokuyama et al. (2015) §5 (the time-difference rate,
    10-point averaging); :mod:`rotacal.uncertainty.summaries`.
    """
    extra = [
        *notes,
        "the measurand is the table's rate deviation in this record, so the table's own "
        "fluctuation is the value, not an error; a timebase error scales every rate and the mean "
        "alike and leaves a relative deviation unchanged.",
    ]
    if specs is None:
        extra.append(TYPE_A_ONLY_NOTE)
    return {
        "rate_deviation_rms_percent": rms_budget(
            "rate_deviation_rms_percent", "%", dev_stats, sources, notes=extra
        ),
        "rate_deviation_peak_percent": mc_budget(
            "rate_deviation_peak_percent", "%", dev_peak, sources, statistic="peak", notes=extra
        ),
    }
