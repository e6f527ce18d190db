"""Uncertainty budgets of the gyro scale factor, 3-axis and rotation calibrations.

Truth comes from outside the budgets: hand-derived closed forms (a straight line through points of
known spread, the folded normal of a three-point nonlinearity, the integrals of a rotation
recording), and the twins run many times with the table's systematic errors drawn per run — the
spread of the results must agree with the reported standard uncertainties within the χ² bounds of
the number of runs.
"""

from __future__ import annotations

import json
import math
import re

import numpy as np
import pytest
from scipy import stats

from rotacal.errors import ConfigError
from rotacal.gyro.rotations import calibrate_triad_rotations
from rotacal.gyro.scale_factor import calibrate_scale_factor, decide_with_u
from rotacal.gyro.triad import calibrate_triad_columns
from rotacal.report.gyro_scale import scale_factor_section
from rotacal.report.html import Report, write_html
from rotacal.report.triad import rotations_section, triad_section
from rotacal.sim.gyro_rates import simulate_gyro_rates
from rotacal.sim.gyro_triad import simulate_gyro_rotations, simulate_gyro_triad
from rotacal.uncertainty import load_specs
from rotacal.uncertainty.specs import TYPE_A_ONLY_NOTE

RUNS = 40  # twin repeats per honesty check
#: Monte Carlo trials of each calibration in the honesty and coverage runs (the single-run checks
#: keep 20 000 or the default). Why 5 000 still catches a defect: the checks compare the spread of
#: RUNS or COVERAGE_RUNS estimates with u, or count misses of the 95 % interval, and what they
#: must catch is u off by ~30 % or a missing budget term. The trials only set the Monte Carlo
#: noise of each run's u(NL) and interval: a standard deviation from N draws has a relative
#: standard error of 1/√(2N) = 1.0 % at N = 5 000, the 2.5 % and 97.5 % quantiles one of about
#: 0.04 σ (√(p(1 − p)/N)/φ(z_p)), i.e. 2 % of U, and both are averaged again over the runs — far
#: below the χ² bounds of s/σ for 40 runs ([0.6, 1.5] at 99.9 %) and the binomial bounds of the
#: misses. Each calibration takes a third of the time it took with 20 000 trials.
HONESTY_MC_TRIALS = 5_000


def _bounds(n: int, p: float = 0.999) -> tuple[float, float]:
    """Two-sided bounds of s/σ for n normal values at probability p (χ² with n − 1 dof)."""
    q = stats.chi2.ppf([(1 - p) / 2, (1 + p) / 2], n - 1)
    lo, hi = np.sqrt(q / (n - 1))
    return float(lo), float(hi)


def _specs(**entries: dict) -> object:
    """{"table.set_rate_relative": {...}} → InstrumentSpecs."""
    tables: dict[str, dict] = {}
    for key, spec in entries.items():
        section, name = key.split("__")
        tables.setdefault(section, {})[name] = spec
    return load_specs(tables)


def _alternating(levels: np.ndarray, d: np.ndarray, n: int) -> np.ndarray:
    """n samples per level, alternating level ± d: mean exactly the level, std d·√(n/(n − 1))."""
    sign = np.where(np.arange(n) % 2 == 0, 1.0, -1.0)
    return (levels[:, None] + d[:, None] * sign[None, :]).ravel()


def _rot_rate(cap) -> np.ndarray:
    return np.column_stack([cap.columns[c] for c in ("ux", "uy", "uz")])


# ---------------------------------------------------------------------- closed forms: scale factor
def test_scale_factor_budget_matches_the_hand_derived_line() -> None:
    x = np.array([-20.0, -10.0, 0.0, 10.0, 20.0])
    n = 4
    d = np.array([1.0, 2.0, 3.0, 4.0, 5.0]) * 1e-3
    s_true = 0.02
    levels = 0.5 + s_true * x + 1e-6 * x**2
    a = 3e-5  # table set-rate error, rectangular ±a
    specs = _specs(table__set_rate_relative={"distribution": "rectangular", "half_width": a})
    r = calibrate_scale_factor(
        np.repeat(x, n), _alternating(levels, d, n), specs=specs, output_unit="V", mc_trials=20_000
    )
    se = d / math.sqrt(3.0)  # std = d·√(4/3), divided by √4
    sxx = float(x @ x)
    u_s0 = math.sqrt(float(np.sum((x / sxx) ** 2 * se**2)))
    nu_s0 = u_s0**4 / float(np.sum((x / sxx * se) ** 4 / (n - 1)))
    s = r.scale_factor
    u_eps = a / math.sqrt(3.0)
    b = r._budgets["scale_factor"]
    assert b.u == pytest.approx(math.hypot(u_s0, s * u_eps), rel=1e-12)
    assert r.scale_factor_u == b.u  # one truth: the field is the budget's u
    assert b.dof_eff == pytest.approx(b.u**4 / (u_s0**4 / nu_s0), rel=1e-9)
    rows = {row.source.split(":")[0]: row for row in b.rows}
    assert rows["S₀"].u == pytest.approx(u_s0, rel=1e-12)
    assert rows["S₀"].dof == pytest.approx(nu_s0, rel=1e-9)
    assert rows["table set-rate error ε"].sensitivity == pytest.approx(-s, rel=1e-12)
    assert rows["table set-rate error ε"].u == pytest.approx(u_eps, rel=1e-12)
    # V0: c_i = 1/N at x̄ = 0, and ε does not enter
    vb = r._budgets["bias"]
    assert vb.u == pytest.approx(math.sqrt(float(np.sum(se**2))) / 5, rel=1e-12)
    assert r.bias_u == vb.u and len(vb.rows) == 1
    assert any("does not enter" in note for note in vb.notes)


def test_one_sample_per_point_falls_back_to_gum_h3() -> None:
    # JCGM 100:2008 H.3 (the thermometer line): the scatter about the line stands for the noise.
    t = [21.521, 22.012, 22.512, 23.003, 23.507, 23.999, 24.513, 25.002, 25.503, 26.010, 26.511]
    b = [-0.171, -0.169, -0.166, -0.159, -0.164, -0.165, -0.156, -0.157, -0.159, -0.161, -0.160]
    r = calibrate_scale_factor(np.asarray(t) - 20.0, b, mc_trials=20_000)
    assert r.scale_factor_u == pytest.approx(0.00067, abs=5e-6)
    assert r.bias_u == pytest.approx(0.0029, abs=5e-5)
    sb = r._budgets["scale_factor"]
    assert sb.dof_eff == 9 and sb.k == pytest.approx(stats.t.ppf(0.975, 9), rel=1e-12)
    assert "GUM H.3" in sb.rows[0].origin
    assert TYPE_A_ONLY_NOTE in sb.notes


def _three_points(q_hat: float, se: float, n: int = 2000):
    """Three points at −1, 0, +1 °/s with means exactly (−1, q̂/2, 1), so q = y₀ − 2y₁ + y₂ = −q̂,
    and standard errors se (ν = n − 1): residuals q̂·(−1, 2, −1)/6, S = 1, NL = 100·|q̂|/3."""
    d = np.full(3, se * math.sqrt(n - 1))  # std = d·√(n/(n − 1)), SE = d/√(n − 1)
    x = np.array([-1.0, 0.0, 1.0])
    return calibrate_scale_factor(
        np.repeat(x, n), _alternating(x + 0.5 * q_hat * np.array([0.0, 1.0, 0.0]), d, n)
    )


@pytest.mark.parametrize("q_over_sigma", [3.0, 0.5])
def test_nonlinearity_budget_is_the_folded_normal_of_three_points(q_over_sigma: float) -> None:
    # Three points at −1, 0, +1 °/s: the residuals are q·(1, −2, 1)/6 with q = y₀ − 2y₁ + y₂, so
    # NL = 100·|q|/(3·|S|·FS) and the residual errors are q_e·(1, −2, 1)/6, q_e ~ N(0, σ_q²) with
    # σ_q² = 6·se² (t with ν = 1999: normal to 5e-4; S = 1 is independent of q, u(S)/S = 7e-4).
    se = 1e-3
    sigma_q = math.sqrt(6.0) * se
    q_hat = q_over_sigma * sigma_q
    r = _three_points(q_hat, se)
    assert r.nonlinearity_percent_fs == pytest.approx(100 * q_hat / 3, rel=1e-9)
    nl = r._budgets["nonlinearity_percent_fs"]
    assert nl.method == "Monte Carlo" and math.isinf(nl.dof_eff)
    assert nl.value == r.nonlinearity_percent_fs  # one truth: the budget holds the plain NL
    # u and the bias re-measure q shrunk to √(q̂² − σ_q²) (|δ̂|² = q̂²/6, tr C = se²): a folded
    # normal about it
    q_b = math.sqrt(max(q_hat**2 - sigma_q**2, 0.0))
    fold = stats.foldnorm(q_b / sigma_q, scale=sigma_q)
    assert nl.u == pytest.approx(100 / 3 * fold.std(), rel=0.01)
    bias = 100 / 3 * (fold.mean() - q_b)
    mc_se = 5 * nl.u / math.sqrt(200_000)  # 5 Monte Carlo standard errors of a mean
    assert r.nonlinearity_percent_fs_bias == pytest.approx(bias, abs=mc_se)
    # a bounded quantity: the correction stops at 0
    assert r.nonlinearity_percent_fs_bias_corrected == pytest.approx(
        max(100 * q_hat / 3 - bias, 0.0), abs=mc_se
    )
    if q_over_sigma < 1:  # consistent with noise: q_b = 0, all of NL is bias, corrected ≈ 0
        assert q_b == 0 and bias == pytest.approx(100 / 3 * sigma_q * math.sqrt(2 / math.pi))
        assert bias > 0.1 * nl.u
    # the interval for the TRUE NL: max|e| = |q_e|/3 (97.5 % quantile: the folded normal's,
    # 2.2414·σ_q/3), the widest e_j the middle one (2·σ_q/6, one-sided 1.96)
    lo, hi = nl.interval
    assert lo == pytest.approx(
        100 / 3 * max(q_hat - stats.norm.isf(0.0125) * sigma_q, 0.0), abs=0.02 * nl.u
    )
    assert hi == pytest.approx(100 / 3 * (q_hat + stats.norm.isf(0.025) * sigma_q), rel=0.005)
    assert nl.U == pytest.approx((hi - lo) / 2, rel=1e-12)
    assert nl.k == pytest.approx(nl.U / nl.u, rel=1e-12)
    assert r.to_dict()["nonlinearity_percent_fs_interval"] == [lo, hi]
    assert r.nonlinearity_percent_fs_interval == (lo, hi)
    if lo == 0.0:  # consistent with noise: the statement gives [0, high]
        assert "lies in [0.0" in nl.statement()
        assert any("firm statement is the upper end" in note for note in nl.notes)


def test_a_dominant_rectangular_rate_error_takes_the_monte_carlo_interval() -> None:
    # JCGM 101 §9.2.4: a dominant rectangular input makes the GUM interval (k ≈ 1.96) too wide;
    # its 95 % interval is ±0.95·a, i.e. k = 0.95·√3 ≈ 1.645.
    a = 1e-3
    specs = _specs(table__set_rate_relative={"distribution": "rectangular", "half_width": a})
    cap = simulate_gyro_rates(samples_per_point=200, seed=3)
    r = calibrate_scale_factor(cap.columns["rate_deg_s"], cap.columns["output"], specs=specs)
    b = r._budgets["scale_factor"]
    assert b.method == "Monte Carlo"  # one of the engine's three names
    assert b.k == pytest.approx(0.95 * math.sqrt(3.0), rel=0.01)
    # the notes state the k that is used, not the GUM's t_p(ν) that was replaced
    assert not any("for k = t_p(ν)" in note for note in b.notes)
    assert any(f"k = U/u = {b.k:.3g}" in note for note in b.notes), b.notes
    assert b.u == pytest.approx(math.sqrt(sum(row.contribution**2 for row in b.rows)), rel=1e-9)
    assert r._budgets["bias"].method == "GUM, validated by Monte Carlo"


def test_a_stated_mean_rate_error_corrects_s() -> None:
    eps = 4e-4
    cap = simulate_gyro_rates(rate_relative_error=eps, samples_per_point=500, seed=2)
    # 20 000 trials: the checks below read S, its u (GUM) and the plain NL, not the MC's tails
    plain = calibrate_scale_factor(
        cap.columns["rate_deg_s"], cap.columns["output"], mc_trials=20_000
    )
    specs = _specs(table__set_rate_relative={"distribution": "normal", "value": eps, "u": 1e-6})
    r = calibrate_scale_factor(
        cap.columns["rate_deg_s"], cap.columns["output"], specs=specs, mc_trials=20_000
    )
    truth = cap.truth["ls_scale_factor"]
    assert abs(plain.scale_factor / truth - 1 - eps) < 5 * plain.scale_factor_u / truth
    assert abs(r.scale_factor / truth - 1) < 5 * r.scale_factor_u / truth
    assert r.nonlinearity_percent_fs == pytest.approx(
        cap.truth["nonlinearity_percent_fs"], abs=3e-3
    )
    assert any("corrects S" in note for note in r.notes)
    # Policy A: the budgets of S and NL say so (the standard text), the bias's does not
    fix = "corrected for the stated mean of table.set_rate_relative = 0.0004"
    assert any(fix in note for note in r._budgets["scale_factor"].notes)
    assert any(fix in note for note in r._budgets["nonlinearity_percent_fs"].notes)
    assert not any(fix in note for note in r._budgets["bias"].notes)
    eps_row = r._budgets["scale_factor"].rows[1]
    assert (eps_row.value, eps_row.u) == (eps, 1e-6)


# ---------------------------------------------------------------------- closed form: rotations
def test_rotation_budget_matches_the_hand_derived_integrals() -> None:
    fs, n_s, n_r, d = 100.0, 400, 300, 0.02
    k_true = np.array([[1.01, 0.004, -0.002], [-0.003, 0.99, 0.001], [0.002, -0.001, 1.005]])
    b_true = np.array([0.3, -0.2, 0.1])
    n = 4 * n_s + 3 * n_r
    omega = np.zeros((n, 3))
    static, rotations, pos = [], {}, 0
    profile = (720.0 * fs / n_r) * np.sin(np.pi * np.arange(n_r) / n_r) ** 2  # Σ/fs = 360°
    for j, ax in enumerate("xyz"):
        static.append((pos, pos + n_s))
        pos += n_s
        omega[pos : pos + n_r, j] = profile
        rotations[ax] = (pos, pos + n_r)
        pos += n_r
    static.append((pos, pos + n_s))
    rate = omega @ k_true.T + b_true
    alt = np.where(np.arange(n) % 2 == 0, d, -d)
    for s, e in static:  # ±d about the bias: the section means are exactly b
        rate[s:e] += alt[s:e, None]
    a_ang, a_t = 20.0, 5e-6
    specs = _specs(
        table__set_angle_arcsec={"distribution": "rectangular", "half_width": a_ang},
        timebase__relative_error={"distribution": "rectangular", "half_width": a_t},
    )
    r = calibrate_triad_rotations(rate, fs, rotations, static=static, specs=specs, angle_deg=360.0)
    np.testing.assert_allclose(r.scale_misalignment, k_true, atol=1e-12)
    noise = d * math.sqrt(4 * n_s / (4 * n_s - 4))  # pooled about each section's mean
    u_theta = noise * math.sqrt(n_r) / fs  # (output unit·s)
    u_b = noise / math.sqrt(4 * n_s)
    t_rot, phi = n_r / fs, 360.0
    for i in range(3):
        kk = k_true[i, i]
        expected = math.sqrt(
            (u_theta / phi) ** 2
            + (u_b * t_rot / phi) ** 2
            + (kk / (phi * 3600.0) * a_ang / math.sqrt(3)) ** 2
            + (kk * a_t / math.sqrt(3)) ** 2
        )
        budget = r._budgets[f"scale_misalignment[{i}][{i}]"]
        assert budget.u == pytest.approx(expected, rel=1e-9)
        assert r.scale_misalignment_u[i, i] == budget.u
        sens = {row.source.split(" ")[0]: row.sensitivity for row in budget.rows}
        assert sens["angle"] == pytest.approx(-kk / (phi * 3600.0), rel=1e-9)
        assert sens["timebase"] == pytest.approx(-kk, rel=1e-9)
        assert sens["bias"] == pytest.approx(-t_rot / phi, rel=1e-9)
        assert r._budgets[f"bias[{i}]"].u == pytest.approx(u_b, rel=1e-12)
    # no spread between the static means: no "offset change" input
    assert not any("offset change" in row.source for b in r._budgets.values() for row in b.rows)


def test_rotation_angle_uncertainty_once_and_stated_means_correct_k() -> None:
    cap = simulate_gyro_rotations(noise_std=0.0, seed=1)
    t = cap.truth
    spec_angle = {"distribution": "rectangular", "half_width": 10.0}
    with pytest.raises(ConfigError, match="give the angle uncertainty once"):
        calibrate_triad_rotations(
            _rot_rate(cap),
            100.0,
            t["rotations"],
            static=t["static"],
            angle_u_deg=0.01,
            specs=_specs(table__set_angle_arcsec=spec_angle),
        )
    # a DAQ clock 1e-4 long: the twin's integrals read 1e-4 large when the angles are 1e-4 large
    eps = 1e-4
    cap = simulate_gyro_rotations(noise_std=0.0, angle_error_deg=-360.0 * eps, seed=1)
    t = cap.truth
    specs = _specs(timebase__relative_error={"distribution": "normal", "value": eps, "u": 1e-7})
    r = calibrate_triad_rotations(_rot_rate(cap), 100.0, t["rotations"], static=t["static"])
    rc = calibrate_triad_rotations(
        _rot_rate(cap), 100.0, t["rotations"], static=t["static"], specs=specs
    )
    k_true = np.asarray(t["scale_misalignment"])
    np.testing.assert_allclose(r.scale_misalignment, k_true * (1 + eps), rtol=1e-9)
    np.testing.assert_allclose(rc.scale_misalignment, k_true, rtol=1e-9)
    assert any("stated mean errors correct K" in note for note in rc.notes)
    fix = "corrected for the stated mean of timebase.relative_error = 0.0001"
    assert any(fix in note for note in rc._budgets["scale_misalignment[0][0]"].notes)
    assert not any(fix in note for note in rc._budgets["bias[0]"].notes)


# ---------------------------------------------------------------------- decision rule (ILAC-G8)
def test_decision_with_u_three_outcomes() -> None:
    assert decide_with_u(0.03, 0.01, 0.05).verdict == "pass with U"
    assert decide_with_u(0.07, 0.01, 0.05).verdict == "fail with U"
    inc = decide_with_u(0.045, 0.01, 0.05)
    assert inc.verdict == "inconclusive" and inc.agrees is False
    assert decide_with_u(0.07, 0.01, 0.05).agrees is True
    assert "does not hold" in inc.line
    # with the interval for the true NL (not centred on the plain value): its ends decide
    assert decide_with_u(0.045, 0.01, 0.05, interval=(0.03, 0.048)).verdict == "pass with U"
    assert decide_with_u(0.056, 0.01, 0.05, interval=(0.051, 0.07)).verdict == "fail with U"
    inc = decide_with_u(0.048, 0.01, 0.05, interval=(0.02, 0.06))
    assert inc.verdict == "inconclusive" and inc.interval == (0.02, 0.06)
    assert "true NL in [0.02, 0.06] %FS" in inc.line


def test_requirement_within_u_is_inconclusive_and_the_json_is_unchanged() -> None:
    cap = simulate_gyro_rates(samples_per_point=100, noise_std=2e-3, seed=4)
    first = calibrate_scale_factor(
        cap.columns["rate_deg_s"], cap.columns["output"], mc_trials=20_000
    )
    nl = first.nonlinearity_percent_fs
    hi = first._budgets["nonlinearity_percent_fs"].interval[1]
    limit = 0.5 * (nl + hi)  # passes without U, but within the interval for the true NL
    r = calibrate_scale_factor(
        cap.columns["rate_deg_s"],
        cap.columns["output"],
        requirement={"name": "tight", "accuracy_percent_fs": limit},
        mc_trials=20_000,
    )
    assert r.requirement is not None and r.requirement.passed is True
    d = r.decision_with_uncertainty
    assert d is not None and d.verdict == "inconclusive" and not d.agrees
    out = json.loads(json.dumps(r.to_dict()))
    assert set(out["requirement"]) == {"name", "title", "source", "passed", "checks", "note"}
    assert out["decision_with_uncertainty"]["verdict"] == "inconclusive"
    # the default twin: NL 0.0195 %FS, U ≈ 0.001 %FS — clear of 0.05 %FS; a 0.06 %FS one fails
    for twin, verdict in (
        ({}, "pass with U"),
        ({"rates_deg_s": np.linspace(-80, 80, 11), "nonlinearity": (0.0, 5e-9)}, "fail with U"),
    ):
        cap = simulate_gyro_rates(samples_per_point=500, seed=5, **twin)
        fmvss = calibrate_scale_factor(
            cap.columns["rate_deg_s"],
            cap.columns["output"],
            requirement="fmvss126",
            mc_trials=20_000,
        )
        assert fmvss.decision_with_uncertainty.verdict == verdict
        assert fmvss.decision_with_uncertainty.agrees


# ---------------------------------------------------------------------- JSON keys and specs
def test_json_keys_of_every_quantity() -> None:
    cap = simulate_gyro_rates(samples_per_point=200, seed=1)
    d = json.loads(
        json.dumps(
            calibrate_scale_factor(
                cap.columns["rate_deg_s"], cap.columns["output"], mc_trials=20_000
            ).to_dict()
        )
    )
    for name in ("scale_factor", "bias", "nonlinearity_percent_fs"):
        assert isinstance(d[f"{name}_u"], float) and d[f"{name}_U"] > d[f"{name}_u"] > 0
        assert d["k"][name] > 1.5
        assert d["uncertainty_budgets"][name]["rows"]
    assert d["coverage_probability"] == 0.95
    nl = d["nonlinearity_percent_fs"]
    corrected = d["nonlinearity_percent_fs_bias_corrected"]
    assert corrected == pytest.approx(nl - d["nonlinearity_percent_fs_bias"], rel=1e-12)
    assert corrected < nl
    lo, hi = d["nonlinearity_percent_fs_interval"]
    assert 0 <= lo < nl < hi
    assert d["nonlinearity_percent_fs_U"] == pytest.approx((hi - lo) / 2, rel=1e-12)
    assert d["uncertainty_budgets"]["nonlinearity_percent_fs"]["value"] == nl
    assert "nonlinearity_interval_percent_fs" not in d  # one interval, the budget's

    triad = calibrate_triad_columns(simulate_gyro_triad(samples_per_point=20, seed=2).columns)
    rc = simulate_gyro_rotations(seed=2)
    rot = calibrate_triad_rotations(
        _rot_rate(rc), 100.0, rc.truth["rotations"], static=rc.truth["static"]
    )
    for res in (triad, rot):
        d = json.loads(json.dumps(res.to_dict()))
        assert np.asarray(d["scale_misalignment_u"]).shape == (3, 3)
        assert np.asarray(d["scale_misalignment_U"]).shape == (3, 3)
        assert np.asarray(d["bias_u"]).shape == (3,) and np.asarray(d["bias_U"]).shape == (3,)
        assert np.asarray(d["k"]["scale_misalignment"]).shape == (3, 3)
        assert np.asarray(d["k"]["bias"]).shape == (3,)
        axes = {"scale_factors", "misalignment_deg"} if res is triad else set()
        assert set(d["k"]) == {"scale_misalignment", "bias"} | axes
        assert len(d["uncertainty_budgets"]) == 12
        assert "scale_misalignment[2][0]" in d["uncertainty_budgets"]
        np.testing.assert_array_less(d["scale_misalignment_u"], d["scale_misalignment_U"])
        np.testing.assert_array_equal(d["scale_misalignment_u"], res.scale_misalignment_u)
        for b in res._budgets.values():
            assert TYPE_A_ONLY_NOTE in b.notes


@pytest.mark.parametrize(
    ("spec", "needle"),
    [
        ({"distribution": "normal", "u": -1e-5}, "must be ≥ 0"),
        ({"distribution": "lognormal", "u": 1e-5}, "unknown distribution 'lognormal'"),
    ],
)
def test_bad_specifications_are_one_line_config_errors(spec: dict, needle: str) -> None:
    cap = simulate_gyro_rates(samples_per_point=20, seed=1)
    with pytest.raises(ConfigError, match=needle) as info:
        calibrate_scale_factor(
            cap.columns["rate_deg_s"],
            cap.columns["output"],
            specs={"table": {"set_rate_relative": spec}},
        )
    assert "\n" not in str(info.value) and "set_rate_relative" in str(info.value)
    with pytest.raises(ConfigError, match="specs must be"):
        calibrate_triad_columns(simulate_gyro_triad(samples_per_point=5).columns, specs=3.0)


def test_a_specification_that_does_not_apply_is_ignored_with_a_note() -> None:
    cap = simulate_gyro_triad(samples_per_point=10, seed=5)
    specs = _specs(lts__radius_mm={"distribution": "normal", "value": 150.0, "u": 0.02})
    r = calibrate_triad_columns(cap.columns, specs=specs)
    plain = calibrate_triad_columns(cap.columns)
    np.testing.assert_array_equal(r.scale_misalignment_u, plain.scale_misalignment_u)
    assert any("no applicable instrument specification" in n for n in r._budgets["bias[0]"].notes)


# ---------------------------------------------------------------------- honesty: the twins
def _sf_runs(specs=None, half_width: float = 0.0, **twin) -> dict[str, np.ndarray]:
    rng = np.random.default_rng(20260)
    out: dict[str, list[float]] = {k: [] for k in ("eS", "uS", "eb", "ub", "nl", "unl", "bias")}
    out["nl_true"] = []
    for seed in range(RUNS):
        eps = float(rng.uniform(-half_width, half_width)) if half_width else 0.0
        cap = simulate_gyro_rates(seed=seed, rate_relative_error=eps, **twin)
        r = calibrate_scale_factor(
            cap.columns["rate_deg_s"],
            cap.columns["output"],
            specs=specs,
            mc_trials=HONESTY_MC_TRIALS,
        )
        out["eS"].append(r.scale_factor - cap.truth["ls_scale_factor"])
        out["uS"].append(r.scale_factor_u)
        out["eb"].append(r.bias - cap.truth["ls_bias"])
        out["ub"].append(r.bias_u)
        out["nl"].append(r.nonlinearity_percent_fs)
        out["unl"].append(r._budgets["nonlinearity_percent_fs"].u)
        out["bias"].append(r.nonlinearity_percent_fs_bias)
        out["nl_true"].append(cap.truth["nonlinearity_percent_fs"])
    return {k: np.asarray(v) for k, v in out.items()}


@pytest.fixture(scope="module")
def type_a_sf_runs() -> dict[str, np.ndarray]:
    """RUNS Type A twins of 500 samples per point: the honesty check's runs, and the reference
    two other checks compare with (the same seeds, hence computed once)."""
    return _sf_runs(samples_per_point=500)


def test_scale_factor_bias_and_nl_spread_match_their_u_type_a(type_a_sf_runs) -> None:
    lo, hi = _bounds(RUNS)
    o = type_a_sf_runs
    for err, u in (("eS", "uS"), ("eb", "ub"), ("nl", "unl")):
        ratio = np.std(o[err], ddof=1) / np.mean(o[u])
        assert lo < ratio < hi, (err, ratio, lo, hi)
    # the errors of S and V0 are centred on the truth (mean within 4 standard errors of the mean)
    for err, u in (("eS", "uS"), ("eb", "ub")):
        assert abs(np.mean(o[err])) < 4 * np.mean(o[u]) / math.sqrt(RUNS)
    # NL over the runs: its mean exceeds the truth by about the reported Monte Carlo bias
    sem = np.std(o["nl"], ddof=1) / math.sqrt(RUNS)
    excess = np.mean(o["nl"]) - np.mean(o["nl_true"])
    assert abs(excess - np.mean(o["bias"])) < 4 * sem


def test_scale_factor_spread_matches_u_with_the_table_rate_error_drawn_per_run(
    type_a_sf_runs,
) -> None:
    lo, hi = _bounds(RUNS)
    a = 2e-5
    specs = _specs(table__set_rate_relative={"distribution": "rectangular", "half_width": a})
    o = _sf_runs(specs, a, samples_per_point=500)
    ratio = np.std(o["eS"], ddof=1) / np.mean(o["uS"])
    assert lo < ratio < hi, (ratio, lo, hi)
    # the Type B part is a real share of u (otherwise this test would not check it)
    type_a = type_a_sf_runs
    assert np.mean(o["uS"]) > 1.3 * np.mean(type_a["uS"])
    # and without it the budget would be dishonest: the spread exceeds the Type A u
    assert np.std(o["eS"], ddof=1) / np.mean(type_a["uS"]) > 1.2


def test_nonlinearity_bias_correction_moves_toward_the_truth_when_noise_is_large() -> None:
    # noise of the point means as large as the nonlinearity: NL is biased upward
    o = _sf_runs(samples_per_point=500, noise_std=6.25e-3)
    lo, hi = _bounds(RUNS)
    ratio = np.std(o["nl"], ddof=1) / np.mean(o["unl"])
    assert lo < ratio < hi, ratio
    truth = float(np.mean(o["nl_true"]))
    plain = float(np.mean(o["nl"]))
    corrected = float(np.mean(o["nl"] - o["bias"]))
    assert plain - truth > 5 * np.std(o["nl"], ddof=1) / math.sqrt(RUNS)  # visibly biased
    assert np.all(o["bias"] > 0)
    assert abs(corrected - truth) < 0.7 * abs(plain - truth)


#: Coverage runs per case: misses of the 95 % interval must stay within the binomial bounds.
COVERAGE_RUNS = 100


@pytest.mark.parametrize(
    ("case", "nonlinearity"),
    [
        ("zero", None),  # a linear gyro with noise: true NL = 0
        ("small", (2e-8, -7.5e-12)),  # true NL 0.0098 %FS, the noise of a point mean 0.0071 %FS
        ("clear", (2e-7, -7.5e-11)),  # true NL 0.098 %FS, 14 times that noise
    ],
)
def test_nonlinearity_interval_covers_the_true_nl(case: str, nonlinearity) -> None:
    # Policy B: the budget's interval is for the TRUE NL and must hold it ~95 % of the time,
    # also at 0 (an interval of the re-measured NL, drawn about the biased plain value, never
    # holds 0). 50 samples per point: a noise of 8.8e-5 V per point mean (0.0071 %FS).
    n = COVERAGE_RUNS
    misses, reaches_zero, nl, u, corrected, truth = 0, 0, [], [], [], []
    for seed in range(n):
        cap = simulate_gyro_rates(seed=seed, nonlinearity=nonlinearity, samples_per_point=50)
        r = calibrate_scale_factor(
            cap.columns["rate_deg_s"], cap.columns["output"], mc_trials=HONESTY_MC_TRIALS
        )
        b = r._budgets["nonlinearity_percent_fs"]
        lo, hi = b.interval
        t = cap.truth["nonlinearity_percent_fs"]
        misses += not lo <= t <= hi
        reaches_zero += lo == 0.0
        nl.append(r.nonlinearity_percent_fs)
        u.append(b.u)
        corrected.append(r.nonlinearity_percent_fs_bias_corrected)
        truth.append(t)
    # the number of misses against Binomial(n, 0.05), two-sided at 99.9 %
    low, high = stats.binom.ppf([0.0005, 0.9995], n, 0.05)
    assert low <= misses <= high, (case, misses, low, high)
    t = float(np.mean(truth))
    plain_err = float(np.mean(nl)) - t
    ratio = float(np.std(nl, ddof=1) / np.mean(u))
    lo_r, hi_r = _bounds(n)
    if case == "clear":
        assert reaches_zero == 0  # a clear NL is told apart from noise in every run
        assert lo_r < ratio < hi_r, ratio
    else:
        assert plain_err > 5 * np.std(nl, ddof=1) / math.sqrt(n)  # the plain NL is biased up
        # the bias correction (Type A noise) removes most of it
        assert abs(float(np.mean(corrected)) - t) < 0.5 * plain_err
        # u is the spread of the estimator; at 0 it errs high (the shrunk base is not 0 when
        # the noise happens to look like a nonlinearity), never low
        assert ratio < hi_r, ratio
        if case == "small":
            assert lo_r < ratio, ratio
        else:
            assert reaches_zero >= 0.9 * n  # consistent with noise: [0, high]


def test_one_sample_per_point_nl_is_not_bias_corrected() -> None:
    # GUM H.3: the noise level is the scatter about the line, which holds the NL too — an upper
    # bound, not a level: no correction (a cautious noise figure must not make NL look better)
    cap = simulate_gyro_rates(samples_per_point=1, noise_std=2e-4, seed=7)
    r = calibrate_scale_factor(cap.columns["rate_deg_s"], cap.columns["output"], mc_trials=20_000)
    d = json.loads(json.dumps(r.to_dict()))
    assert d["nonlinearity_percent_fs_bias"] is None
    assert d["nonlinearity_percent_fs_bias_corrected"] is None
    b = r._budgets["nonlinearity_percent_fs"]
    lo, hi = b.interval
    assert lo <= cap.truth["nonlinearity_percent_fs"] <= hi
    assert any(note.startswith("not bias-corrected") for note in b.notes)
    assert any("not bias-corrected" in line for line in r.summary_lines())


@pytest.mark.parametrize("half_width", [0.0, 1e-3])
def test_triad_k_and_bias_spread_match_their_u(half_width: float) -> None:
    lo, hi = _bounds(RUNS)
    specs = (
        _specs(table__set_rate_relative={"distribution": "rectangular", "half_width": half_width})
        if half_width
        else None
    )
    rng = np.random.default_rng(3003)
    ek, uk, eb, ub = [], [], [], []
    for seed in range(RUNS):
        eps = float(rng.uniform(-half_width, half_width)) if half_width else 0.0
        cap = simulate_gyro_triad(
            samples_per_point=50, noise_std=0.1, rate_relative_error=eps, seed=seed
        )
        r = calibrate_triad_columns(cap.columns, specs=specs)
        ek.append(r.scale_misalignment - np.asarray(cap.truth["scale_misalignment"]))
        uk.append(r.scale_misalignment_u)
        eb.append(r.bias - np.asarray(cap.truth["bias"]))
        ub.append(r.bias_u)
    ratio_k = np.std(ek, axis=0, ddof=1) / np.mean(uk, axis=0)
    ratio_b = np.std(eb, axis=0, ddof=1) / np.mean(ub, axis=0)
    assert np.all((lo < ratio_k) & (ratio_k < hi)), ratio_k
    assert np.all((lo < ratio_b) & (ratio_b < hi)), ratio_b
    if half_width:  # the diagonal is dominated by the table's rate error
        diag = np.diag(np.mean(uk, axis=0))
        assert np.all(diag > 3 * np.mean(uk, axis=0)[0, 1])


def test_rotation_k_spread_matches_u_with_the_angle_error_drawn_per_run() -> None:
    lo, hi = _bounds(RUNS)
    a = 600.0  # arcsec: a hand-turned or coarse table
    specs = _specs(table__set_angle_arcsec={"distribution": "rectangular", "half_width": a})
    rng = np.random.default_rng(1995)
    ek, uk, eb, ub = [], [], [], []
    for seed in range(RUNS):
        err = rng.uniform(-a, a, 3) / 3600.0
        cap = simulate_gyro_rotations(
            noise_std=0.2,
            static_s=2.0,
            rotation_s=3.0,
            margin_s=0.3,
            angle_error_deg=err,
            seed=seed,
        )
        t = cap.truth
        r = calibrate_triad_rotations(
            _rot_rate(cap), 100.0, t["rotations"], static=t["static"], specs=specs
        )
        ek.append(r.scale_misalignment - np.asarray(t["scale_misalignment"]))
        uk.append(r.scale_misalignment_u)
        eb.append(r.bias - np.asarray(t["bias"]))
        ub.append(r.bias_u)
    ratio_k = np.std(ek, axis=0, ddof=1) / np.mean(uk, axis=0)
    ratio_b = np.std(eb, axis=0, ddof=1) / np.mean(ub, axis=0)
    assert np.all((lo < ratio_k) & (ratio_k < hi)), ratio_k
    assert np.all((lo < ratio_b) & (ratio_b < hi)), ratio_b
    # the angle rows of the diagonal are a real part of the budget (or this checks nothing)
    share = [
        row.share
        for i in range(3)
        for row in r._budgets[f"scale_misalignment[{i}][{i}]"].rows
        if row.source.startswith("angle error")
    ]
    assert len(share) == 3 and min(share) > 0.3


# ---------------------------------------------------------------------- twins' systematic effects
def test_twins_apply_the_drawn_systematic_errors() -> None:
    eps = 1e-3
    cap = simulate_gyro_rates(noise_std=0.0, nonlinearity=None, rate_relative_error=eps)
    rates, out = cap.columns["rate_deg_s"], cap.columns["output"]
    np.testing.assert_allclose(out, 2.5 + 0.0125 * rates * (1 + eps), rtol=1e-14)
    assert cap.truth["ls_scale_factor"] == pytest.approx(0.0125, rel=1e-12)
    tri = simulate_gyro_triad(noise_std=0.0, samples_per_point=2, rate_relative_error=eps)
    c = tri.columns
    omega = np.column_stack([c["wx_deg_s"], c["wy_deg_s"], c["wz_deg_s"]])
    k = np.asarray(tri.truth["scale_misalignment"])
    u = omega * (1 + eps) @ k.T + np.asarray(tri.truth["bias"])
    np.testing.assert_allclose(np.column_stack([c["ux"], c["uy"], c["uz"]]), u, rtol=1e-13)
    rot = simulate_gyro_rotations(noise_std=0.0, angle_deg=360.0, angle_error_deg=[0.1, -0.2, 0.3])
    kinv = np.linalg.inv(np.asarray(rot.truth["scale_misalignment"]))
    w = (_rot_rate(rot) - np.asarray(rot.truth["bias"])) @ kinv.T
    for j, ax in enumerate("xyz"):
        s, e = rot.truth["motion"][ax]
        assert w[s:e, j].sum() / 100.0 == pytest.approx(360.0 + [0.1, -0.2, 0.3][j], rel=1e-12)
    assert rot.truth["angle_realised_deg"] == pytest.approx([360.1, 359.8, 360.3])


# ---------------------------------------------------------------------- reports
def test_reports_show_the_budgets_without_nan(tmp_path) -> None:
    specs = _specs(
        table__set_rate_relative={"distribution": "rectangular", "half_width": 1e-5},
        table__set_angle_arcsec={"distribution": "rectangular", "half_width": 30.0},
        timebase__relative_error={"distribution": "rectangular", "half_width": 2e-6},
    )
    cap = simulate_gyro_rates(samples_per_point=500, seed=126)
    sf = calibrate_scale_factor(
        cap.columns["rate_deg_s"],
        cap.columns["output"],
        requirement="fmvss126",
        output_unit="V",
        specs=specs,
        mc_trials=20_000,
    )
    tri = calibrate_triad_columns(simulate_gyro_triad(samples_per_point=20).columns, specs=specs)
    rc = simulate_gyro_rotations(seed=4)
    rot = calibrate_triad_rotations(
        _rot_rate(rc), 100.0, rc.truth["rotations"], static=rc.truth["static"], specs=specs
    )
    sections = [
        scale_factor_section(sf, figures=False),
        triad_section(tri, figures=False),
        rotations_section(rot, figures=False),
    ]
    text = write_html(Report("budgets", sections=sections), tmp_path / "r.html").read_text()
    assert not re.search(r"\bnan\b", text, flags=re.IGNORECASE)
    captions = [t.caption for s in sections for t in s.details]
    # scale factor: S, V0, NL; triad: K, b and |K_i|, θ_i; rotations: K, b
    assert sum(c.startswith("Uncertainty budget of") for c in captions) == 3 + 12 + 6 + 12
    assert "Uncertainty budget of the nonlinearity NL (Monte Carlo)" in text
    assert "pass with U" in text and "V/(°/s)" in text
    assert "table.set_angle_arcsec" in text and "timebase.relative_error" in text
