"""Single-axis gyro scale factor and nonlinearity from a rate-table test (Kokuyama et al. 2015, §4).

The table holds a set rate Ω while the DUT's output is recorded, for several rates. Rows with the
same set rate form one *rate point*; its samples are averaged (keeping n, standard deviation and
standard error). A straight line is fitted to the point means by least squares,

    V(Ω) = S·Ω + V0 + δ(Ω),

S is the scale factor (output unit per °/s), V0 the bias (output unit), δ the residuals, and the
nonlinearity is ``NL = 100·max|δ| / (|S|·FS)`` in %FS (Kokuyama et al. 2015: NL = max|δ|/FS with δ and FS in
the same unit; rotacal converts δ to °/s by S). Seed 004 recommends at least 11 points.

Choices (documented in :func:`calibrate_scale_factor`):

- **Same set rate.** Rates within ``rate_tolerance_deg_s`` (default 0.001 °/s) of their sorted
  neighbour are one point (single linkage): a commanded rate is written identically on every row,
  and no test resolves points closer than a millidegree per second.
- **Unweighted fit.** Every point has equal weight, as in Kokuyama et al. (2015) and IEEE Std 952-1997 /
  IEEE Std 1431-2004 (least-squares straight line through the averaged points). The residuals of a
  real gyro are dominated by its systematic nonlinearity, not by noise: weighting by the points'
  standard errors would let the quietest points define the line and make NL depend on how long
  each point was recorded. On the xinli_turntable recording the unweighted fit reproduces the
  published S = 1.000199, NL = 0.082 %FS; a 1/SE² fit gives 1.000489 and 0.122 %FS.
- **Uncertainties** (one budget per quantity, :mod:`rotacal.gyro.uncertainty`). The measurand S
  is the slope of the least-squares line through the DUT's mean output at the set rates (Kokuyama et al. 2015:
  δ(Ω) is part of the model, reported as NL, not an error of S). Type A: the standard error of
  each point mean (the spread of its samples) propagated through the line, u²(S₀) = Σ c_i²·u_i²
  with c_i = (Ω_i − Ω̄)/Σ(Ω_k − Ω̄)², ν by Welch–Satterthwaite; points of one sample take the
  pooled standard deviation of the others, and when no point has two samples the scatter of the
  points about the line stands for the noise, s²·(AᵀA)⁻¹ with s² = Σδ²/(N − 2), ν = N − 2
  (GUM, JCGM 100:2008, H.3). Type B: ``table.set_rate_relative`` ε, the table's realised rate
  being Ω·(1 + ε), so S = S₀/(1 + ε) (V0 does not depend on ε). S and V0 are validated by Monte
  Carlo. NL, a maximum of |δ|, is biased upward by noise and bounded below by 0: its JSON value
  and budget value are the plain NL, u the standard deviation of NL re-measured (Monte Carlo,
  JCGM 101), the bias from the point means' noise and the bias-corrected NL stand beside
  it, and the budget states a 95 % interval for the TRUE NL (it reaches 0 when the residuals are
  consistent with noise), U being half its width. A lack-of-fit test tells when the points
  scatter about the line more than their noise explains (nonlinearity, or drift between the
  points).

Where the parts live (along the data's path): :mod:`~rotacal.gyro.scale_factor_points` (rate
points, output quantum, saturation), this module (the checks, the point statistics, the line and
NL), :mod:`~rotacal.gyro.scale_factor_budget` (GUM budgets, Monte Carlo, the interval for NL),
:mod:`~rotacal.gyro.scale_factor_requirement` (requirements and verdicts),
:mod:`~rotacal.gyro.scale_factor_result` (the result); a long log read in chunks:
:mod:`~rotacal.gyro.scale_factor_stream`. The names this module held before the split stay
importable from here.

References
----------
Kokuyama W., Watanabe T., Nozato H., Ota A., "Development of angular velocity calibration facility
using self-calibratable rotary encoder", §4 and Table 1.
IEEE Std 952-1997, Annex C (scale factor and nonlinearity from a least-squares line).
NHTSA, FMVSS 126 Laboratory Test Procedure for Electronic Stability Control Systems (2008).
JCGM 100:2008 (GUM) §4.2, §5.1.2, G.4, H.3; JCGM 101:2008 §7, §8; JCGM 102:2011 §9; Efron &
Tibshirani, An Introduction to the Bootstrap (1993) §6, §10; ILAC-G8:09/2019 §4.2 (decision rules
with a guard band).
"""

from __future__ import annotations

import dataclasses
import inspect
import math
from collections.abc import Mapping
from typing import Any

import numpy as np

from rotacal.errors import CaptureError, ConfigError
from rotacal.gyro.plausibility import scale_factor_warnings
from rotacal.gyro.resolution import (
    NoiseBlock,
    _block_noise,
    check_blocks_fit,
    noise_block,
    resolution_from_noise,
)
from rotacal.gyro.scale_factor_budget import (
    DEFAULT_MC_TRIALS,
    _point_uncertainties,
    _scale_factor_budgets,
)
from rotacal.gyro.scale_factor_points import (
    DEFAULT_RATE_TOLERANCE_DEG_S,
    PointData,
    _check_saturation,
    _fmt_rate,
    _group,
    _rows,
    output_quantum,
)
from rotacal.gyro.scale_factor_requirement import (
    REQUIREMENTS,
    DecisionWithU,
    RequirementCheck,
    RequirementVerdict,
    _positive,
    decide_with_u,
    evaluate_requirement,
    resolve_requirement,
)
from rotacal.gyro.scale_factor_result import RatePoint, ScaleFactorResult
from rotacal.gyro.sf_items import signed_or_flag
from rotacal.gyro.uncertainty import as_specs
from rotacal.signal._values import check_magnitudes, check_not_copies, check_setting
from rotacal.signal.clipping import check_clipping
from rotacal.uncertainty.budget import UncertaintyBudget
from rotacal.uncertainty.specs import InstrumentSpecs, spec_distribution

__all__ = [
    "DEFAULT_MC_TRIALS",
    "DEFAULT_RATE_TOLERANCE_DEG_S",
    "MIN_POINTS_RECOMMENDED",
    "REQUIREMENTS",
    "DecisionWithU",
    "RatePoint",
    "RequirementCheck",
    "RequirementVerdict",
    "ScaleFactorResult",
    "calibrate_scale_factor",
    "decide_with_u",
    "evaluate_requirement",
    "output_quantum",
    "resolve_requirement",
]

#: Seed 004, §4: "the number of measurement points should be greater than or equal 11".
MIN_POINTS_RECOMMENDED = 11


# ------------------------------------------------------------------------------- method
def calibrate_scale_factor(
    rate_deg_s: np.ndarray,
    output: np.ndarray,
    *,
    full_scale_deg_s: float | None = None,
    requirement: str | Mapping[str, Any] | None = None,
    rate_tolerance_deg_s: float = DEFAULT_RATE_TOLERANCE_DEG_S,
    nan_policy: str = "raise",
    output_unit: str = "",
    specs: InstrumentSpecs | None = None,
    mc_trials: int = DEFAULT_MC_TRIALS,
    sample_rate_hz: float | None = None,
    bandwidth_hz: float | None = None,
    allow_clipped: bool = False,
) -> ScaleFactorResult:
    """Scale factor, bias and nonlinearity of a gyro from a rate-table test.

    Rows whose set rates lie within ``rate_tolerance_deg_s`` of each other are one rate point; its
    samples are averaged. An unweighted least-squares line V = S·Ω + V0 through the N point means
    gives S and V0; δ are the point residuals and NL = 100·max|δ|/(|S|·FS) %FS.

    The capture is refused (:class:`~rotacal.errors.CaptureError`) when a set rate is missing, a
    rate point has no finite output, outputs are NaN (unless ``nan_policy="omit"``), a column holds
    values beyond float64's working range (|x| > 1e100, or all below 1e-100), there is only one
    rate, the output copies the set rate (or its negative), the output does not change with the
    rate, the output sits at its rails (:mod:`rotacal.signal.clipping`, with the rate points as
    groups; ``allow_clipped`` analyses it anyway and says so in ``warnings``), or the output
    saturates: at the outer points their mean stops following the rate (local slope below half
    the median slope by more than 5 standard errors).

    The resolution a requirement judges is the smallest rate change the output resolves
    (:func:`rotacal.gyro.resolution.output_resolution`): the larger of the output quantum / |S|
    (when the outputs lie visibly on a grid, :func:`output_quantum`) and the noise of one reading
    at the stated bandwidth / |S| — neither shrinks with the record's length. It does not replace
    the IEEE Std 1431 resolution test with small rate increments.

    Parameters
    ----------
    rate_deg_s : array
        Set rate of the table on each row (°/s).
    output : array
        DUT output on each row (output units: V, LSB, °/s …).
    full_scale_deg_s : float or None
        FS (°/s) for NL; None takes the largest |set rate|.
    requirement : str or mapping or None
        A named requirement (``"fmvss126"``) or a dict of limits (see :func:`resolve_requirement`).
    rate_tolerance_deg_s : float
        Set rates closer than this (°/s, ≥ 0) to their sorted neighbour are one point.
    nan_policy : {"raise", "omit"}
        Non-finite outputs raise, or are left out (with a note).
    output_unit : str
        Name of the output unit, for messages and reports.
    specs : InstrumentSpecs or None
        The lab's instrument specifications (Type B; :func:`rotacal.uncertainty.load_specs`, a
        TOML path or a mapping also work). Used: ``table.set_rate_relative`` (relative error ε of
        the table's set rate, the realised rate being Ω·(1 + ε)); others are ignored. None: the
        budgets hold the capture's Type A part only.
    mc_trials : int
        Monte Carlo trials for NL and for validating u(S) and u(V0) (≥ 2000).
    sample_rate_hz : float or None
        Sample rate of the output (Hz), for the resolution's noise bandwidth (fs/2 by default).
    bandwidth_hz : float or None
        Bandwidth of one reading for the resolution (Hz, ≤ fs/2; needs ``sample_rate_hz``);
        None: the recorded samples' own.
    allow_clipped : bool
        Analyse an output with samples at the rails anyway (``--allow-clipped``); the result's
        ``warnings`` name the clipping. Refused by default.

    Returns
    -------
    ScaleFactorResult
        ``scale_factor`` (output unit per °/s), ``bias`` (output unit), their standard
        uncertainties, ``nonlinearity_percent_fs`` (%FS), ``residuals`` (output unit, one per point),
        the per-point table, the requirement's verdict, the budgets (``_budgets``: GUM for S and V0,
        validated by Monte Carlo; Monte Carlo for NL with its bias and bias-corrected value) and the
        accuracy verdict with U (``decision_with_uncertainty``).

    References
    ----------
    Kokuyama et al. (2015), §4: V(Ω) = S·Ω + V0 + δ(Ω), NL = max|δ|/FS, ≥ 11 points; Table 1
    (FMVSS 126). IEEE Std 952-1997, Annex C. JCGM 100:2008 (GUM), §5.1.2, G.4.1, H.3 (straight-line
    fit and its uncertainties); JCGM 101:2008 §7–8 (Monte Carlo, validation); ILAC-G8:09/2019 §4.2.
    """
    options = dict(locals())  # every keyword after the two columns
    del options["rate_deg_s"], options["output"]
    opts = _check_options(**options)
    rate = np.asarray(rate_deg_s, dtype=float).reshape(-1)
    y = np.asarray(output, dtype=float).reshape(-1)
    if rate.size != y.size:
        raise CaptureError(
            f"column rate_deg_s has {rate.size} rows but column output has {y.size}: they must "
            "have one row per sample."
        )
    if rate.size == 0:
        raise CaptureError("the capture has no rows: it needs rate_deg_s and output samples.")
    bad_rate = np.flatnonzero(~np.isfinite(rate))
    if bad_rate.size:
        raise CaptureError(_bad_rates(bad_rate.size, bad_rate))
    check_magnitudes("rate_deg_s", rate, what="a set rate")
    gid, rates, spread = _group(rate, opts.tol)
    ng = rates.size
    _refuse_one_rate(rates)
    ok = np.isfinite(y)
    counts = np.bincount(gid, weights=ok, minlength=ng).astype(np.int64)
    empty = np.flatnonzero(counts == 0)
    if empty.size:
        raise CaptureError(_empty_point(rates[empty[0]], np.flatnonzero(gid == empty[0])))
    bad_out = np.flatnonzero(~ok)
    notes = _nonfinite_outputs(bad_out.size, bad_out, opts.nan_policy)
    check_magnitudes("output", y[ok] if bad_out.size else y, what="a gyro output")
    check_not_copies({"rate_deg_s": rate, "output": y}, _COPY_WHY)

    # each point's samples less its first finite one (exact for nearby values): the means and
    # the spread keep their digits on a large offset, and a streamed capture does the same
    first = np.full(ng, y.size)
    np.minimum.at(first, gid[ok], np.flatnonzero(ok))
    d = np.where(ok, y - y[first][gid], 0.0)
    means_d = np.bincount(gid, weights=d, minlength=ng) / counts
    dev = np.where(ok, d - means_d[gid], 0.0)
    ss = np.bincount(gid, weights=dev * dev, minlength=ng)
    means = y[first] + means_d
    with np.errstate(invalid="ignore", divide="ignore"):
        std = np.where(counts > 1, np.sqrt(ss / np.maximum(counts - 1, 1)), np.nan)
    _refuse_flat_output(means, opts.unit)
    # samples at the rails: the one detector, with the rate points as groups and the rows at
    # zero rate as rest (rotacal.signal.clipping)
    clipped = check_clipping(
        {"output": y}, allow_clipped=opts.allow_clipped, groups=gid, rest=rates[gid] == 0
    )
    yf, gf = (y[ok], gid[ok]) if bad_out.size else (y, gid)
    check_blocks_fit(opts.noise, counts)
    points = PointData(
        rates=rates,
        spread=spread,
        counts=counts,
        means=means,
        std=std,
        quantum=output_quantum(y, gid),
        noise=_block_noise(yf, gf, ng, opts.noise.block),
        output_abs_max=float(np.max(np.abs(yf), initial=0.0)),
        clipped=clipped,
        notes=tuple(notes),
    )
    return _finish(points, opts)


# ------------------------------------------------------------------------------- shared steps
_COPY_WHY = "a DUT's output differs from the set rate by its noise at least; map the DUT's output"


@dataclasses.dataclass(frozen=True)
class _Options:
    """The options of a calibration, checked (see :func:`calibrate_scale_factor`)."""

    tol: float
    nan_policy: str
    req: dict[str, Any] | None
    spec: InstrumentSpecs | None
    trials: int
    fs_user: float | None
    noise: NoiseBlock
    allow_clipped: bool
    output_unit: str

    @property
    def unit(self) -> str:
        return f" {self.output_unit}" if self.output_unit else ""


def _check_options(**options: Any) -> _Options:
    """Every option of :func:`calibrate_scale_factor` (its defaults for those not given) checked
    before a sample is read (ConfigError naming the option)."""
    signature = inspect.signature(calibrate_scale_factor)
    unknown = [k for k in options if k not in signature.parameters or k in ("rate_deg_s", "output")]
    if unknown:
        raise ConfigError(
            f"unknown option {unknown[0]!r} of the scale-factor calibration; the options are "
            "those of calibrate_scale_factor."
        )
    bound = signature.bind(None, None, **options)
    bound.apply_defaults()
    o = bound.arguments
    nan_policy, rate_tolerance_deg_s, mc_trials = (
        o["nan_policy"],
        o["rate_tolerance_deg_s"],
        o["mc_trials"],
    )
    full_scale_deg_s, requirement = o["full_scale_deg_s"], o["requirement"]
    if nan_policy not in ("raise", "omit"):
        raise ConfigError(f"nan_policy must be 'raise' or 'omit', got {nan_policy!r}.")
    try:
        tol = float(rate_tolerance_deg_s)
    except (TypeError, ValueError):
        raise ConfigError(
            f"rate_tolerance_deg_s must be a number ≥ 0 °/s, got {rate_tolerance_deg_s!r}."
        ) from None
    if not math.isfinite(tol) or tol < 0:
        raise ConfigError(
            f"rate_tolerance_deg_s must be a number ≥ 0 °/s, got {rate_tolerance_deg_s!r}."
        )
    req = None if requirement is None else resolve_requirement(requirement)
    spec = as_specs(o["specs"])
    if isinstance(mc_trials, bool) or not isinstance(mc_trials, (int, np.integer)):
        raise ConfigError(f"mc_trials must be an integer ≥ 2000, got {mc_trials!r}.")
    if mc_trials < 2000:
        raise ConfigError(
            f"mc_trials must be at least 2000 for a 95 % interval (JCGM 101 §7.2), got {mc_trials}."
        )
    fs_user = (
        None
        if full_scale_deg_s is None
        else _positive("full_scale_deg_s", full_scale_deg_s, "the full scale in °/s")
    )
    if fs_user is not None:
        check_setting("--full-scale-deg-s", fs_user, unit="deg/s")
    return _Options(
        tol=tol,
        nan_policy=nan_policy,
        req=req,
        spec=spec,
        trials=int(mc_trials),
        fs_user=fs_user,
        noise=noise_block(o["sample_rate_hz"], o["bandwidth_hz"]),
        allow_clipped=bool(o["allow_clipped"]),
        output_unit=o["output_unit"],
    )


def _bad_rates(count: int, first_rows: np.ndarray) -> str:
    return (
        f"column rate_deg_s has {count} non-finite value(s) (NaN or inf) at rows "
        f"{_rows(first_rows, count)} (counted from 0): every row needs the table's set rate."
    )


def _refuse_one_rate(rates: np.ndarray) -> None:
    if rates.size == 1:
        raise CaptureError(
            f"every row of column rate_deg_s has the same set rate ({_fmt_rate(rates[0])}): a "
            f"scale factor needs at least two rates (Kokuyama et al. 2015 recommend ≥ "
            f"{MIN_POINTS_RECOMMENDED})."
        )


def _empty_point(rate: float, rows: np.ndarray, count: int | None = None) -> str:
    n = rows.size if count is None else count
    return (
        f"the rate point {_fmt_rate(rate)} has no samples: all {n} of its outputs are NaN or "
        f"empty (rows {_rows(rows, n)}, counted from 0); fix column output or remove that rate."
    )


def _nonfinite_outputs(count: int, first_rows: np.ndarray, nan_policy: str) -> list[str]:
    """Refuse non-finite outputs, or the note that they were left out."""
    if not count:
        return []
    if nan_policy == "raise":
        raise CaptureError(
            f"column output has {count} non-finite value(s) (NaN or inf) at rows "
            f"{_rows(first_rows, count)} (counted from 0): remove those rows from the capture."
        )
    return [
        f"{count} non-finite output value(s) left out (rows {_rows(first_rows, count)}, counted "
        "from 0)."
    ]


def _refuse_flat_output(means: np.ndarray, unit: str) -> None:
    if np.ptp(means) == 0:
        raise CaptureError(
            "column output does not change with the set rate (every rate point has the same mean "
            f"{means[0]:.6g}{unit}): check that the right output column is mapped."
        )


def _finish(points: PointData, opts: _Options) -> ScaleFactorResult:
    """From the rate points' statistics on: saturation, the line, NL, resolution, budgets, verdict."""
    unit, output_unit, spec = opts.unit, opts.output_unit, opts.spec
    rates, means, std, counts = points.rates, points.means, points.std, points.counts
    ng = rates.size
    with np.errstate(invalid="ignore", divide="ignore"):
        se = std / np.sqrt(counts)
    notes = list(points.notes)
    _check_saturation(rates, means, std, counts, unit)
    # Unweighted least-squares line through the point means (centred for accuracy), against the
    # set rates; the table's stated mean rate error ε̄ (realised rate Ω·(1 + ε̄)) corrects S.
    eps_dist = spec_distribution(spec, "table.set_rate_relative")
    eps_mean = 0.0 if eps_dist is None else float(eps_dist.mean)
    xbar = float(rates.mean())
    ybar = float(means.mean())
    xc = rates - xbar
    sxx = float(xc @ xc)
    s_fit = float(xc @ (means - ybar)) / sxx
    s = s_fit / (1.0 + eps_mean)
    v0 = ybar - s_fit * xbar
    resid = means - (s_fit * rates + v0)
    dof = ng - 2
    if dof > 0:
        res_std = math.sqrt(float(resid @ resid) / dof)
    else:
        res_std = math.nan
        notes.append(
            "two rate points fit the line exactly: the residuals, the nonlinearity and the "
            "uncertainties mean nothing."
        )
    fs_user, tol = opts.fs_user, opts.tol
    fs = fs_user if fs_user is not None else float(np.max(np.abs(rates)))
    scale = abs(s) * fs
    res_pct = 100.0 * resid / scale
    nl = float(np.max(np.abs(res_pct)))

    if ng < MIN_POINTS_RECOMMENDED:
        notes.append(
            f"only {ng} rate points: Kokuyama et al. (2015, §4) recommend at least {MIN_POINTS_RECOMMENDED}."
        )
    if fs_user is not None and fs_user < float(np.max(np.abs(rates))):
        notes.append(
            f"the tested rates reach {float(np.max(np.abs(rates))):g} °/s, beyond the full scale "
            f"{fs_user:g} °/s that NL refers to."
        )
    if float(points.spread.max()) > 0:
        notes.append(
            f"set rates within {tol:g} °/s were merged into one point; the largest spread within "
            f"a point is {float(points.spread.max()):.3g} °/s."
        )
    if eps_mean != 0.0:
        notes.append(
            f"the stated mean set-rate error ε̄ = {eps_mean:.3g} (table.set_rate_relative) "
            f"corrects S: S = S₀/(1 + ε̄), S₀ = {s_fit:.8g} against the set rates."
        )

    q = points.quantum
    res = resolution_from_noise(
        points.noise,
        points.output_abs_max,
        s,
        quantum=q,
        settings=opts.noise,
        output_unit=output_unit,
    )
    resolution, basis = res.resolution_deg_s, res.basis
    notes.append(
        "Unweighted least squares through the point means (Kokuyama et al. 2015, §4, IEEE Std 952 Annex C); "
        "scale_factor_u and bias_u are the combined standard uncertainties of the budgets: the "
        "standard errors of the point means through the line (Type A) and the stated table "
        "set-rate error (Type B); the nonlinearity δ(Ω) is reported as NL, not as an "
        "uncertainty of S."
    )

    budgets: dict[str, UncertaintyBudget] = {}
    nl_bias = nl_corr = math.nan
    u_pt, nu_pt, basis_a = _point_uncertainties(counts, std, q, res_std, dof, unit)
    if u_pt is not None:
        assert nu_pt is not None
        budgets, nl_bias, lof = _scale_factor_budgets(
            rates=rates,
            means=means,
            counts=counts,
            u_pt=u_pt,
            nu_pt=nu_pt,
            basis=basis_a,
            s_fit=s_fit,
            v0=v0,
            nl=nl,
            fs=fs,
            resid=resid,
            spec=spec,
            eps_dist=eps_dist,
            output_unit=output_unit,
            mc_trials=opts.trials,
        )
        nl_corr = max(nl - nl_bias, 0.0) if math.isfinite(nl_bias) else math.nan
        if lof:
            notes.append(lof)
    # S₊, S₋ and the asymmetry (IEEE Std 528/952; rotacal.gyro.sf_items)
    signed, sign_note, sign_warning = signed_or_flag(
        rates,
        means,
        u_pt,
        scale_factor=s,
        eps_mean=eps_mean,
        u_eps=0.0 if eps_dist is None else float(eps_dist.std),
    )
    notes += [sign_note] if sign_note else []
    s_u = budgets["scale_factor"].u if budgets else math.nan
    v0_u = budgets["bias"].u if budgets else math.nan

    decision: DecisionWithU | None = None
    req = opts.req
    if req is not None:
        verdict: RequirementVerdict | None = evaluate_requirement(
            req,
            rate_min_deg_s=float(rates.min()),
            rate_max_deg_s=float(rates.max()),
            nonlinearity_percent_fs=nl,
            full_scale_deg_s=fs,
            resolution_deg_s=resolution,
            resolution_basis=basis,
        )
        if "accuracy_percent_fs" in req and "nonlinearity_percent_fs" in budgets:
            b_nl = budgets["nonlinearity_percent_fs"]
            decision = decide_with_u(
                nl, b_nl.U, req["accuracy_percent_fs"], title=req["title"], interval=b_nl.interval
            )
    else:
        verdict = None

    table = tuple(
        RatePoint(
            float(rates[i]),
            int(counts[i]),
            float(means[i]),
            float(std[i]),
            float(se[i]),
            float(resid[i]),
            float(res_pct[i]),
        )
        for i in range(ng)
    )
    return ScaleFactorResult(
        scale_factor=s,
        bias=v0,
        full_scale_deg_s=fs,
        nonlinearity_percent_fs=nl,
        residuals=resid,
        scale_factor_u=s_u,
        bias_u=v0_u,
        residuals_percent_fs=res_pct,
        rates_deg_s=rates,
        points=table,
        n_points=ng,
        samples_used=int(counts.sum()),
        residual_std=res_std,
        dof=dof,
        output_unit=output_unit,
        rate_tolerance_deg_s=tol,
        resolution_deg_s=resolution,
        resolution_basis=basis,
        output_quantum=q,
        requirement=verdict,
        notes=tuple(notes),
        nonlinearity_percent_fs_bias=nl_bias,
        nonlinearity_percent_fs_bias_corrected=nl_corr,
        decision_with_uncertainty=decision,
        resolution=res,
        _budgets=budgets,
        signed=signed,
        warnings=(
            *points.clipped,
            *([sign_warning] if sign_warning else []),
            *scale_factor_warnings(
                scale_factor=s,
                nonlinearity_percent_fs=nl,
                rates_deg_s=rates,
                residuals=resid,
                point_u=u_pt,
                full_scale_deg_s=fs,
                output_unit=output_unit,
                quantum=q,
            ),
        ),
    )
