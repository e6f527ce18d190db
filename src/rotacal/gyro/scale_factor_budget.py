"""Uncertainty budgets of a gyro's scale factor, bias and nonlinearity (GUM, JCGM 101 Monte Carlo).

Type A from the point means' standard errors through the line, Type B the table's set-rate error;
S and V0 by the GUM validated by Monte Carlo, NL by Monte Carlo with its noise bias and a 95 %
interval for the true NL (see :func:`scale_factor_budgets`).

References
----------
JCGM 100:2008 (GUM) §4.2, §5.1.2, G.4, H.3; JCGM 101:2008 §6.4.9, §7, §8; JCGM 102:2011 §5.3.2,
§9; Efron & Tibshirani, An Introduction to the Bootstrap (1993) §6, §10; David & Nagaraja, Order
Statistics, 3rd ed. (2003) §7.1.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Iterator

import numpy as np

from rotacal.gyro.uncertainty import TScale, linear_gum, monte_carlo_budget, validated
from rotacal.uncertainty.budget import BudgetRow, UncertaintyBudget
from rotacal.uncertainty.distributions import Distribution, Normal
from rotacal.uncertainty.gum import Input, welch_satterthwaite
from rotacal.uncertainty.linear_fit import linear_fit_uncertainty
from rotacal.uncertainty.montecarlo import MonteCarloResult, monte_carlo
from rotacal.uncertainty.quantiles import chi2_ppf
from rotacal.uncertainty.specs import InstrumentSpecs, spec_input, type_a_note

__all__ = ["DEFAULT_MC_TRIALS"]

#: Monte Carlo trials for NL and for validating u(S), u(V0) (JCGM 101 §7.2 asks for ~10⁶ when the
#: interval's ends must hold two digits; 2·10⁵ keeps one calibration well under a second).
DEFAULT_MC_TRIALS = 200_000
#: Seed of the Monte Carlo streams: the same capture gives the same budget.
_MC_SEED = 2026
#: Random numbers held at once by the interval's Monte Carlo (memory).
_CHUNK_ELEMENTS = 4_000_000
#: Point means with ν at or below this are drawn normal in the Monte Carlo (see the note there).
_MC_MIN_DOF = 4.0
#: Lack of fit is reported when Σδ²/(ν·ū²) exceeds the χ²(ν)/ν quantile at this probability.
_LACK_OF_FIT_P = 0.999


def _point_uncertainties(
    counts: np.ndarray,
    std: np.ndarray,
    q: float | None,
    res_std: float,
    dof: int,
    unit: str,
) -> tuple[np.ndarray | None, np.ndarray | None, str]:
    """Standard uncertainty (output unit) and ν of each point mean, and how they were found.

    Points with n ≥ 2 samples: s_i/√n_i, ν = n_i − 1 (a point whose samples are all equal on a
    visible output grid: the rounding, q/√12, ν = ∞). Points of one sample: the pooled standard
    deviation of the others, ν = Σ(n_k − 1). No point with two samples: the residual standard
    deviation of the line (GUM H.3), ν = N − 2; None when N = 2.
    """
    multi = counts > 1
    if multi.any():
        nu_pool = float(np.sum(counts[multi] - 1))
        pooled = math.sqrt(float(np.sum((counts[multi] - 1) * std[multi] ** 2)) / nu_pool)
        sd = np.where(multi, std, pooled)
        u = sd / np.sqrt(counts)
        nu = np.where(multi, counts - 1.0, nu_pool)
        flat = multi & (std == 0)
        if q is not None and flat.any():
            u = np.where(flat, q / math.sqrt(12.0), u)
            nu = np.where(flat, math.inf, nu)
        n_min, n_max = int(counts.min()), int(counts.max())
        n_text = f"{n_min}" if n_min == n_max else f"{n_min}…{n_max}"
        basis = (
            f"Type A: standard errors of the {counts.size} point means ({n_text} samples each) "
            "through the line"
        )
        if not multi.all():
            basis += "; points of one sample take the pooled standard deviation"
        if q is not None and flat.any():
            basis += f"; points without spread take the output rounding q/√12 (q = {q:.3g}{unit})"
        return u, nu, basis
    if dof <= 0:
        return None, None, ""
    u = np.full(counts.size, res_std)
    nu = np.full(counts.size, float(dof))
    basis = (
        f"Type A: one sample per point, so the scatter of the {counts.size} points about the line "
        f"stands for the noise (GUM H.3, ν = {dof})"
    )
    return u, nu, basis


def _quantile_se(x: np.ndarray, q: float) -> float:
    """Monte Carlo standard error of the q-quantile of the values x (their unit): half the
    distance between the order statistics one binomial standard deviation either side of it
    (David & Nagaraja 2003, §7.1)."""
    srt = np.sort(np.asarray(x, dtype=float))
    m = srt.size
    half = math.sqrt(m * q * (1.0 - q))
    i_lo = int(np.clip(math.floor(m * q - half), 0, m - 1))
    i_hi = int(np.clip(math.ceil(m * q + half), 0, m - 1))
    return 0.5 * float(srt[i_hi] - srt[i_lo])


def _nl_interval(
    resid: np.ndarray,
    u_pt: np.ndarray,
    w_dists: list[TScale],
    xc: np.ndarray,
    sxx: float,
    s_fit: float,
    eps_dist: Distribution | None,
    fs: float,
    trials: int,
) -> tuple[float, float, float, float, int]:
    """The 95 % interval for the true NL (%FS), the Monte Carlo standard errors of its ends (%FS)
    and the number of candidate points.

    With e = δ̂ − δ the residual errors (the line's residual projector applied to the errors of
    the point means; independent of the true curve), for any true residuals δ:
    max|δ̂| − max|δ| ≤ |e_k| (k where |δ̂| peaks) and max|δ| ≤ max|δ̂| + |e_j*| (j* where |δ|
    peaks). With τ the 99.9 % quantile of max|e|, both k and j* lie, but for a probability of
    10⁻³, among the points K whose |δ̂| comes within 4τ of max|δ̂| (they have |δ| ≥ max|δ| − 2τ).
    The lower end is max|δ̂| less the 97.5 % quantile of max_K|e_j|, the upper end max|δ̂| plus the
    largest 97.5 % quantile of e_j over K, each divided by |S|·FS/100 drawn with it (S from the
    same errors and the set-rate error ε): each end holds with probability ≥ 97.5 % − 0.1 %.

    Parameters
    ----------
    resid : array
        Residuals δ̂ of the point means from the line (output unit).
    u_pt : array
        Standard uncertainties (t scale) of the point means (output unit).
    w_dists : list of TScale
        One √(ν/χ²_ν) per point, or one shared by all (GUM H.3: a multivariate t).
    xc, sxx : array, float
        Rates less their mean (°/s) and Σxc² ((°/s)²).
    s_fit : float
        Slope of the line against the set rates (output unit per °/s).
    eps_dist : Distribution or None
        Relative set-rate error ε of the table (1).
    fs : float
        Full scale (°/s).
    trials : int
        Monte Carlo trials.

    Returns
    -------
    low, high, se_low, se_high : float
        %FS.
    n_candidates : int

    References
    ----------
    JCGM 101:2008 §6.4.9 (t-distributed means), §7.7 (coverage interval); JCGM 102:2011 §5.3.2
    (multivariate t), §9 (a magnitude near zero); David & Nagaraja, Order Statistics, 3rd ed.
    (2003) §7.1 (Monte Carlo error of a quantile).
    """
    n = resid.size
    a_plain = float(np.max(np.abs(resid)))
    chunk = max(1, min(trials, _CHUNK_ELEMENTS // max(n, 1)))

    def draws() -> Iterator[tuple[np.ndarray, np.ndarray]]:
        """(residual errors (m, N), 100/(|S|·FS) (m,)) in chunks, the same on every call."""
        rng = np.random.default_rng(_MC_SEED + 1)
        done = 0
        while done < trials:
            m = min(chunk, trials - done)
            z = rng.standard_normal((m, n)) * u_pt
            w = np.column_stack([d.sample(rng, m) for d in w_dists])
            e = z * w
            eps = np.zeros(m) if eps_dist is None else eps_dist.sample(rng, m)
            ds = e @ xc / sxx
            pe = e - e.mean(axis=1, keepdims=True) - ds[:, None] * xc
            yield pe, 100.0 * np.abs(1.0 + eps) / (np.abs(s_fit + ds) * fs)
            done += m

    # both passes see the same draws: held in memory when they fit, else drawn again
    held = list(draws()) if trials * n <= 2 * _CHUNK_ELEMENTS else None
    tau = float(
        np.quantile(
            np.concatenate([np.max(np.abs(pe), axis=1) for pe, _ in (held or draws())]), 0.999
        )
    )
    cand = np.flatnonzero(np.abs(resid) >= a_plain - 4.0 * tau)
    lows, highs = [], []
    for pe, g in held or draws():
        pk = pe[:, cand]
        lows.append((a_plain - np.max(np.abs(pk), axis=1)) * g)
        highs.append((a_plain + pk) * g[:, None])
    low_t, high_t = np.concatenate(lows), np.concatenate(highs)
    q_lo, q_hi = 0.025, 0.975
    lo = max(float(np.quantile(low_t, q_lo)), 0.0)
    hi_j = np.quantile(high_t, q_hi, axis=0)
    j = int(np.argmax(hi_j))
    hi = max(float(hi_j[j]), lo)
    return lo, hi, _quantile_se(low_t, q_lo), _quantile_se(high_t[:, j], q_hi), int(cand.size)


def _scale_factor_budgets(
    *,
    rates: np.ndarray,
    means: np.ndarray,
    counts: np.ndarray,
    u_pt: np.ndarray,
    nu_pt: np.ndarray,
    basis: str,
    s_fit: float,
    v0: float,
    nl: float,
    fs: float,
    resid: np.ndarray,
    spec: InstrumentSpecs | None,
    eps_dist: Distribution | None,
    output_unit: str,
    mc_trials: int,
) -> tuple[dict[str, UncertaintyBudget], float, str | None]:
    """Budgets of S, V0 (GUM, validated by Monte Carlo) and NL (Monte Carlo); NL's noise bias
    (%FS; NaN when the noise level is not known apart from the nonlinearity), its 95 % interval
    for the true NL (%FS); a lack-of-fit note (or None).

    The interval for the true NL rests on two inequalities that hold whatever the true residuals
    δ: with e = δ̂ − δ the residual errors (the line's residual projector applied to the errors of
    the point means, independent of the true curve), max|δ̂| − max|e| ≤ max|δ| ≤ max|δ̂| + |e_j*|
    (j* where |δ| peaks). The 97.5 % quantiles of max|e| and of the most widely spread e_j (Monte
    Carlo) then give ends that each hold with probability ≥ 97.5 %, also at NL = 0, where the
    interval becomes [0, high]. u and the noise bias come from re-measuring (parametric
    bootstrap) the residuals shrunk toward the line by √max(0, 1 − tr C/|δ̂|²) (C the covariance
    of e), so that their sum of squares is the unbiased estimate of the true one.

    References
    ----------
    Seed 004 §4; JCGM 100:2008 §5.1.2, G.4.1, H.3; JCGM 101:2008 §6.4.9, §7.6, §7.7, §8;
    JCGM 102:2011 §5.3.2, §9 (a magnitude near zero); Efron B. & Tibshirani R. J., An
    Introduction to the Bootstrap (1993) §6, §10 (parametric bootstrap: standard error, bias);
    Mathai A. M. & Provost S. B., Quadratic Forms in Random Variables (1992) Thm 3.2b.2
    (E|δ̂|² = |δ|² + tr C); David H. A. & Nagaraja H. N., Order Statistics, 3rd ed. (2003) §7.1
    (Monte Carlo error of a quantile).
    """
    ou = output_unit or "output unit"
    unit_s = f"{ou}/(°/s)"
    n = rates.size
    xbar = float(rates.mean())
    xc = rates - xbar
    sxx = float(xc @ xc)
    c_s = xc / sxx  # ∂S₀/∂ȳ_i (1/(°/s))
    c_b = 1.0 / n - xbar * c_s  # ∂V0/∂ȳ_i (1)
    h3 = bool(np.all(counts == 1))
    if h3:
        fit = linear_fit_uncertainty(rates, means)
        u_s0, u_b0 = fit.u_slope, fit.u_intercept
        nu_s = nu_b = float(fit.dof)
    else:
        u_s0 = math.sqrt(float(np.sum((c_s * u_pt) ** 2)))
        u_b0 = math.sqrt(float(np.sum((c_b * u_pt) ** 2)))
        nu_s = welch_satterthwaite(c_s * u_pt, nu_pt)
        nu_b = welch_satterthwaite(c_b * u_pt, nu_pt)
    eps_in = spec_input(spec, "table.set_rate_relative", name="table set-rate error ε")
    eps = 0.0 if eps_in is None else eps_in.value
    type_a = [] if (note := type_a_note(spec, ("table.set_rate_relative",))) is None else [note]
    # a stated mean ε̄ corrects S = S₀/(1 + ε̄) and NL through S (GUM §3.2.4); V0 does not change
    fixed = [] if spec is None else [spec.correction_note("table.set_rate_relative")]
    s_notes = type_a + [n for n in fixed if n is not None]

    s_in = Input("S₀: slope of the line", s_fit, u_s0, nu_s, "normal", unit_s, basis)
    s_inputs, s_sens = [s_in], [1.0 / (1.0 + eps)]
    if eps_in is not None:
        s_inputs.append(eps_in)
        s_sens.append(-s_fit / (1.0 + eps) ** 2)
    gum_s = linear_gum("scale factor S", unit_s, s_fit / (1.0 + eps), s_inputs, s_sens)
    b_in = Input("V0: intercept of the line", v0, u_b0, nu_b, "normal", ou, basis)
    gum_b = linear_gum("bias V0", ou, v0, [b_in], [1.0])
    b_notes = list(type_a)
    if eps_in is not None:
        b_notes.append(
            "table.set_rate_relative does not enter: a relative rate error leaves zero rate at "
            "zero, so the line's intercept does not change."
        )

    # Monte Carlo over the point means and ε (JCGM 101). The error of a point mean is u_i·z_i·w_i
    # with z_i ~ N(0, 1) and w_i = √(ν_i/χ²_ν): a scaled-and-shifted t with ν_i = n_i − 1 (JCGM 101
    # §6.4.9); points that share the residual s of the line (GUM H.3) share one w, a multivariate
    # t (JCGM 102 §5.3.2). A t with ν ≤ 4 has no finite fourth moment, so the standard deviation
    # of the Monte Carlo values would not settle: the re-measurements of S, V0 and NL then use z
    # alone (normal), and S and V0 keep their GUM interval unvalidated. The interval for the true
    # NL (two quantiles) always uses the t.
    heavy = bool(np.any(nu_pt <= _MC_MIN_DOF))
    inputs: dict[str, Distribution] = {f"z{i}": Normal(0.0, float(u_pt[i])) for i in range(n)}
    if h3:
        inputs["w"] = TScale(float(nu_pt[0]))
    else:
        for i in range(n):
            inputs[f"w{i}"] = TScale(float(nu_pt[i]))
    if eps_dist is not None:
        inputs["eps"] = eps_dist
    z_names = [f"z{i}" for i in range(n)]
    w_names = ["w"] if h3 else [f"w{i}" for i in range(n)]
    # The residual errors e = δ̂ − δ = P·(errors of the point means), P = I − H the residual
    # projector of the line (they do not depend on the true curve), C = P·diag(u²)·P.
    proj = np.eye(n) - 1.0 / n - np.outer(xc, xc) / sxx
    var_e = np.einsum("ij,j,ij->i", proj, u_pt**2, proj)  # diagonal of C (output unit²)
    to_nl = 100.0 / fs  # %FS per (output unit / |S|)
    # The base of the re-measurements (parametric bootstrap): the residuals shrunk toward the
    # line so that their sum of squares is the unbiased estimate |δ̂|² − tr C of the true one
    # (E|δ̂|² = |δ|² + tr C, C = P·diag(u²)·P): re-measuring δ̂ itself would count its noise
    # twice. Only when the noise level is known apart from the nonlinearity (n_i ≥ 2); with one
    # sample per point the noise is the scatter about the line itself (then tr C = |δ̂|²), and
    # the data are re-measured as they are, without a bias correction.
    known_noise = not h3
    ss_res = float(resid @ resid)
    shrink = (
        math.sqrt(max(0.0, 1.0 - float(var_e.sum()) / ss_res))
        if known_noise and ss_res > 0
        else 1.0
    )
    base = shrink * resid

    def line_errors(err: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Slope error, intercept error and residual errors P·err of point-mean errors (N, M)."""
        m = err.mean(axis=0)
        ds = c_s @ err
        return ds, m - ds * xbar, err - m - xc[:, None] * ds

    def model(**kw: np.ndarray) -> dict[str, np.ndarray]:
        z = np.stack([kw[k] for k in z_names])  # (N, M): normal part, one row per rate point
        et = z * np.stack([kw[k] for k in w_names])  # the t errors
        e = kw.get("eps", eps)
        ds, db, pe = line_errors(z if heavy else et)
        sf = (s_fit + ds) / (1.0 + e)
        out = {
            "scale factor S": sf,
            "bias V0": v0 + db,
            "nonlinearity NL": to_nl * np.max(np.abs(base[:, None] + pe), axis=0) / np.abs(sf),
        }
        if known_noise:  # the bias: the Type A noise alone at its estimated level, ε at its mean
            _, _, pz = line_errors(z)
            out["max|δ| noise only"] = np.max(np.abs(base[:, None] + pz), axis=0)
        return out

    batch = max(10_000, (4_000_000 // max(n, 1)) // 10_000 * 10_000)
    mc = monte_carlo(model, inputs, trials=mc_trials, seed=_MC_SEED, batch=batch)
    assert isinstance(mc, dict)
    budgets: dict[str, UncertaintyBudget] = {}
    few = (
        f"the point means have ν ≤ {_MC_MIN_DOF:g} (≤ {_MC_MIN_DOF + 1:g} samples, or a line "
        "of few points): the Monte Carlo re-measures them normal (a t with ν ≤ 4 has no settled "
        "standard deviation), so u(NL) leaves out the small-ν widening and S and V0 are not "
        "validated by it; the interval for the true NL keeps the t."
    )
    flat = int(np.count_nonzero(u_pt == 0))
    flat_note = (
        f"{flat} of the {n} points have identical samples and no visible output grid: the "
        "rounding of their means (the output's resolution) is not known here and is not included."
        if flat
        else None
    )
    for key, gum, extra in (("scale_factor", gum_s, s_notes), ("bias", gum_b, b_notes)):
        m = mc[gum.names_out[0]]
        more = list(extra) + ([flat_note] if flat_note else [])
        if float(gum.u[0]) > 0 and m.u > 0 and not heavy:
            budgets[key] = validated(gum, m, more)
        else:
            b = gum.budget(0)
            budgets[key] = dataclasses.replace(
                b, notes=b.notes + tuple(more) + ((few,) if heavy else ())
            )

    m_nl: MonteCarloResult = mc["nonlinearity NL"]
    w_dists = [TScale(float(v)) for v in (nu_pt[:1] if h3 else nu_pt)]
    lo, hi, se_lo, se_hi, n_cand = _nl_interval(
        resid, u_pt, w_dists, xc, sxx, s_fit, eps_dist, fs, mc_trials
    )
    rows = []
    u_eps_part = 0.0
    if eps_in is not None:
        sens = nl / (1.0 + eps)  # NL ∝ (1 + ε): ∂NL/∂ε
        u_eps_part = abs(sens) * eps_in.u
    u_pts_part = math.sqrt(max(m_nl.u**2 - u_eps_part**2, 0.0))
    u2 = m_nl.u**2
    rows.append(
        BudgetRow(
            source=f"point means at the {n} rates",
            value=math.nan,
            unit=ou,
            distribution="multivariate t (GUM H.3)" if h3 else "t, one per point",
            u=math.nan,
            sensitivity=math.nan,
            contribution=u_pts_part,
            share=u_pts_part**2 / u2 if u2 > 0 else 0.0,
            dof=float(np.min(nu_pt)),
            origin=basis.replace(" through the line", ""),
        )
    )
    if eps_in is not None:
        rows.append(
            BudgetRow(
                source=eps_in.name,
                value=eps_in.value,
                unit="",
                distribution=eps_in.description or eps_in.distribution,
                u=eps_in.u,
                sensitivity=nl / (1.0 + eps),
                contribution=u_eps_part,
                share=u_eps_part**2 / u2 if u2 > 0 else 0.0,
                dof=eps_in.dof,
                origin=eps_in.source,
            )
        )
    nl_notes = [
        "NL = 100·max|δ|/(|S|·FS) is a maximum of absolute residuals: noise in the point means "
        "biases it upward (as a magnitude near zero, JCGM 102), and first-order propagation does "
        f"not apply. Monte Carlo (JCGM 101), M = {m_nl.trials} trials (seed {_MC_SEED}) over the "
        "point means and the inputs below; u is the standard deviation of NL re-measured "
        "(parametric bootstrap, JCGM 101 §7.6).",
        f"95 % interval for the TRUE NL: [{lo:.4g}, {hi:.4g}] %FS. The residual errors "
        "e = δ̂ − δ do not depend on the true curve, and max|δ̂| − max_K|e_j| ≤ max|δ| ≤ "
        "max|δ̂| + |e_j*| (j* where the true |δ| peaks; K the points that can hold the peak of "
        f"the true residuals or of the measured ones, here {n_cand} of {n}): the lower end is "
        "max|δ̂| less the 97.5 % quantile of max_K|e_j|, the upper end max|δ̂| plus the largest "
        "97.5 % quantile of e_j in K, both over |S|·FS drawn with S (Monte Carlo, t-distributed "
        "point means) — each end holds with probability ≥ 97.5 % (less 0.1 % for choosing K) "
        "whatever the true NL, also at 0; conservative when the peak is clear. Monte Carlo "
        f"standard errors of the ends ≈ {se_lo:.2g} and {se_hi:.2g} %FS. U is half the "
        "interval's width and k = U/u.",
    ]
    if lo == 0.0:
        nl_notes.append(
            "the residuals are consistent with noise alone (the interval reaches 0): the firm "
            f"statement is the upper end, true NL ≤ {hi:.4g} %FS (p ≥ 97.5 %)."
        )
    bias = math.nan
    if known_noise:
        m_b = mc["max|δ| noise only"]
        a_base = float(np.max(np.abs(base)))
        bias = to_nl * (float(m_b.value) - a_base) / abs(s_fit / (1.0 + eps))
        se_b = to_nl * float(m_b.u) / math.sqrt(m_b.trials) / abs(s_fit / (1.0 + eps))
        nl_notes.append(
            "u and the bias re-measure the residuals shrunk toward the line by the factor "
            f"{shrink:.3g} = √max(0, 1 − tr C/|δ̂|²), which makes their sum of squares the "
            "unbiased estimate |δ̂|² − tr C of the true one (C the covariance of the residual "
            "errors): re-measuring δ̂ itself would count its noise twice. Bias from the noise of "
            "the point means (Type A: its level is the spread of the samples at each rate) "
            f"{bias:+.2g} %FS (Monte Carlo standard error ≈ {se_b:.1g} %FS); bias-corrected NL = "
            f"max(NL − bias, 0) = {max(nl - bias, 0.0):.4g} %FS. A specification (Type B) does "
            "not enter the correction."
        )
        if bias > 0.1 * nl:
            nl_notes.append(
                "the noise makes up much of the plain NL: the bias-corrected value is "
                "approximate; the interval stays valid."
            )
    else:
        nl_notes.append(
            "not bias-corrected: with one sample per point the noise level is the scatter of the "
            "points about the line, which holds the nonlinearity too (an upper bound of the "
            f"noise, not its level); u re-measures the residuals as they are, and the firm "
            f"statement is the upper end, true NL ≤ {hi:.4g} %FS."
        )
    nl_notes.append(
        "contributions: the point means' part is the Monte Carlo u less the set-rate part; the "
        "set-rate part is first order (NL ∝ 1 + ε). A maximum has no sensitivity coefficient "
        "for the point means (—)."
    )
    nl_notes += s_notes
    if heavy:
        nl_notes.append(few)
    if flat_note:
        nl_notes.append(flat_note)
    b_nl = monte_carlo_budget("nonlinearity NL", "%FS", nl, m_nl, rows, nl_notes)
    big_u = 0.5 * (hi - lo)
    if n > 2:  # two points fit the line exactly: NL = 0 says nothing of the truth, no budget
        budgets["nonlinearity_percent_fs"] = dataclasses.replace(
            b_nl,
            U=big_u,
            k=big_u / b_nl.u if b_nl.u > 0 else b_nl.k,
            interval=(lo, hi),
        )
    else:
        bias = math.nan

    # lack of fit: do the points scatter about the line more than their noise explains?
    lof = None
    if not h3 and n > 2:
        var_mean = float(np.mean(u_pt**2))
        if var_mean > 0:
            ratio = float(resid @ resid) / ((n - 2) * var_mean)
            if ratio > chi2_ppf(_LACK_OF_FIT_P, n - 2) / (n - 2):
                s2 = float(resid @ resid) / (n - 2)
                u_h3 = math.sqrt(s2 / sxx) / abs(1.0 + eps)
                lof = (
                    f"lack of fit: the point means scatter about the line {math.sqrt(ratio):.3g} "
                    "times more (rms) than their standard errors explain. That is the "
                    "nonlinearity NL reports (Kokuyama et al. 2015's δ(Ω)) or drift between the points; only "
                    "drift is an uncertainty of S, and u(S) does not hold it — repeat the test to "
                    f"tell. The scatter about the line (GUM H.3) would give u(S) = {u_h3:.2g} "
                    f"{unit_s}."
                )
    return budgets, bias, lof
