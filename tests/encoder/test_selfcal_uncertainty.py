"""Uncertainty of the self-calibrated deviation (seed 004) against closed forms and the twin."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from scipy import stats

from rotacal.encoder.selfcal import (
    UNDETECTABLE_SPEC,
    mc_budget,
    self_calibrate,
    statistic_samples,
)
from rotacal.errors import ConfigError
from rotacal.sim.pulses import simulate_pulses
from rotacal.uncertainty import Input, InstrumentSpecs, Normal, load_specs

M, N_HEADS = 3600, 4
RUNS = 40


def _heads(cap):
    return [cap.columns[f"head_{i}"] for i in range(cap.truth["heads"])]


def _chi2_bounds(n: int) -> tuple[float, float]:
    """99.9 % bounds of std/σ from n independent values about their known truth (n dof)."""
    lo, hi = stats.chi2.ppf([0.0005, 0.9995], n)
    return math.sqrt(lo / n), math.sqrt(hi / n)


def _undetectable_fraction(m: int, n: int) -> float:
    """Share of an iid curve's variance (its mean removed) at the orders that are multiples of n."""
    q = np.arange(m // 2 + 1)
    weight = np.where((q == 0) | (2 * q == m), 1.0, 2.0)
    hit = (q % n == 0) & (q > 0)
    return float(np.sum(weight[hit]) / m)


@pytest.fixture(scope="module")
def type_a_runs():
    """RUNS twin captures (4 heads × 3600 lines, 3 revolutions), each self-calibrated."""
    out = []
    for k in range(RUNS):
        cap = simulate_pulses(heads=N_HEADS, pulses_per_rev=M, revolutions=3.2, seed=700 + k)
        out.append((cap, self_calibrate(_heads(cap), pulses_per_rev=M)))
    return out


def test_point_u_is_the_revolutions_spread_pooled(type_a_runs):
    """u of every point = √(mean over lines of s²/R): one truth in the field, arrays and budget."""
    _, r = type_a_runs[0]
    per_rev = r.per_revolution_arcsec
    revs = per_rev.shape[0]
    hand = math.sqrt(float(np.mean(per_rev.var(axis=0, ddof=1) / revs)))
    assert r.deviation_u_arcsec == pytest.approx(hand, rel=1e-12)
    assert r.point_budget is not None and r.point_budget.u == r.deviation_u_arcsec
    assert r.deviation_arcsec_u.shape == (M,)
    assert np.all(r.deviation_arcsec_u == r.deviation_u_arcsec)
    # ν from 2(R − 1) per detectable order: thousands, so k is the normal 1.96
    assert r.deviation_dof > 100 * (revs - 1)
    assert r.point_budget.k == pytest.approx(stats.norm.ppf(0.975), abs=2e-3)
    assert r.point_budget.U == pytest.approx(r.point_budget.k * hand)
    assert r.point_budget.rows[0].dof == pytest.approx(r.deviation_dof, rel=1e-9)
    assert any("Type A only" in note for note in r.point_budget.notes)


def test_points_are_honest_type_a(type_a_runs):
    """The curve's error against the twin's detectable truth has the stated u at every line."""
    err2, u2 = [], []
    for cap, r in type_a_runs:
        err = r.deviation_arcsec - np.asarray(cap.truth["deviation_detectable_arcsec"])
        err2.append(np.mean(err**2))
        u2.append(r.deviation_u_arcsec**2)
    ratio = math.sqrt(np.mean(err2) / np.mean(u2))
    lo, hi = _chi2_bounds(RUNS)  # pooled over 3600 lines as well: conservative bounds
    assert lo < ratio < hi, ratio


def test_peak_to_peak_budget_is_honest(type_a_runs):
    """The Monte Carlo u of the peak-to-peak matches the spread of its error; no residual bias."""
    err, us = [], []
    for cap, r in type_a_runs:
        b = r.budgets["deviation_pp_arcsec"]
        assert b.method == "Monte Carlo" and b.value == r.deviation_pp_corrected_arcsec
        assert r.deviation_pp_arcsec - r.deviation_pp_bias_arcsec == pytest.approx(b.value)
        err.append(b.value - cap.truth["deviation_detectable_pp_arcsec"])
        us.append(b.u)
    err = np.asarray(err)
    lo, hi = _chi2_bounds(RUNS)
    assert lo < math.sqrt(np.mean(err**2)) / np.mean(us) < hi
    assert abs(err.mean()) < 4 * err.std(ddof=1) / math.sqrt(RUNS)


def test_points_are_honest_with_the_undetectable_specification():
    """The twin's random graduation puts 1/n of its variance at the undetectable orders; stating
    that rms makes the curve's u cover the full truth (Type B checked per run)."""
    sigma_g, runs = 0.3, 30
    u_spec = sigma_g * math.sqrt(_undetectable_fraction(M, N_HEADS))
    specs = InstrumentSpecs(entries={UNDETECTABLE_SPEC: Normal(0.0, u_spec)}, source="test")
    err2, u2, pp_err, pp_u = [], [], [], []
    for k in range(runs):
        cap = simulate_pulses(
            heads=N_HEADS,
            pulses_per_rev=M,
            revolutions=3.2,
            harmonics=((1, 3.0, 0.3), (2, 0.4, 1.1), (3, 0.15, 2.0)),  # detectable orders only
            graduation_noise_arcsec=sigma_g,
            seed=900 + k,
        )
        r = self_calibrate(_heads(cap), pulses_per_rev=M, specs=specs)
        err = r.deviation_arcsec - np.asarray(cap.truth["deviation_arcsec"])
        err2.append(np.mean(err**2))
        u2.append(r.deviation_u_arcsec**2)
        b = r.budgets["deviation_pp_arcsec"]
        pp_err.append(b.value - cap.truth["deviation_pp_arcsec"])
        pp_u.append(b.u)
    lo, hi = _chi2_bounds(runs)
    assert lo < math.sqrt(np.mean(err2) / np.mean(u2)) < hi
    assert lo < math.sqrt(np.mean(np.square(pp_err))) / np.mean(pp_u) < hi
    # the Type B row dominates and the pieces combine in quadrature
    assert math.sqrt(u2[-1]) > 0.9 * u_spec
    rows = r.point_budget.rows
    assert [row.u for row in rows][1] == pytest.approx(u_spec)
    assert r.point_budget.u == pytest.approx(math.hypot(rows[0].u, rows[1].u))


def test_monte_carlo_budget_closed_form():
    """A noise-free vector with a declared noise: the mean square loses exactly σ² (SIMEX of
    squares is exact for an rms), and its u is the closed-form spread of an rms."""
    n, sigma = 2000, 0.3
    base = np.sin(2 * np.pi * np.arange(n) / 100.0)  # 20 whole periods: ms = 1/2
    inp = Input("noise", 0.0, sigma, unit="arcsec", distribution="normal")
    samples = statistic_samples(
        base,
        [(inp, lambda rng, size: rng.normal(0.0, sigma, (size, n)), True)],
        {"rms": lambda x: np.sqrt(np.mean(x * x, axis=-1))},
    )["rms"]
    b = mc_budget("rms", "arcsec", float(np.sqrt(np.mean(base**2))), samples, [inp])
    assert b.value == pytest.approx(math.sqrt(0.5 - sigma**2), rel=3e-3)
    # var(ms) at the data's noise level, 3·var(ms | 2σ²) − var(ms | 3σ²) = (4σ²·ms − 2σ⁴)/n
    var_ms = (4 * sigma**2 * 0.5 - 2 * sigma**4) / n
    assert b.u == pytest.approx(math.sqrt(var_ms) / (2 * b.value), rel=0.15)
    assert b.k == pytest.approx(1.96, abs=0.1) and b.method == "Monte Carlo"


def test_json_keys_and_one_truth(type_a_runs):
    _, r = type_a_runs[0]
    d = json.loads(json.dumps(r.to_dict()))
    assert len(d["deviation_arcsec_u"]) == len(d["deviation_arcsec_U"]) == M
    assert d["deviation_arcsec_u"][0] == d["deviation_u_arcsec"]
    for name in ("deviation_pp_arcsec", "deviation_rms_arcsec"):
        assert d[f"{name}_u"] == r.budgets[name].u and f"{name}_U" in d
        assert d["k"][name] == pytest.approx(d[f"{name}_U"] / d[f"{name}_u"])
        assert d["uncertainty_budgets"][name]["method"] == "Monte Carlo"
    assert d["k"]["deviation_arcsec"] == pytest.approx(1.96, abs=2e-3)
    assert d["coverage_probability"] == 0.95
    for key in ("deviation_pp_bias_arcsec", "deviation_pp_corrected_arcsec", "deviation_dof"):
        assert isinstance(d[key], float)


def test_one_revolution_has_no_uncertainty_and_says_so():
    cap = simulate_pulses(heads=4, pulses_per_rev=M, revolutions=1.4, seed=3)
    r = self_calibrate(_heads(cap), pulses_per_rev=M)
    assert r.revolutions_used == 1 and r.deviation_u_arcsec is None and not r.budgets
    d = r.to_dict()
    assert d["deviation_arcsec_u"] is None and d["k"] == {}
    assert any("one whole revolution" in note for note in r.notes)


def test_bad_specifications_are_one_line_config_errors():
    with pytest.raises(ConfigError) as e:
        load_specs('[timebase]\nrelative_error = { distribution = "normal", u = -1e-6 }\n')
    assert "\n" not in str(e.value) and "'u'" in str(e.value)
    with pytest.raises(ConfigError) as e:
        load_specs('[timebase]\nrelative_error = { distribution = "lorentz", half_width = 1 }\n')
    assert "\n" not in str(e.value) and "unknown distribution" in str(e.value)
    cap = simulate_pulses(heads=4, pulses_per_rev=M, revolutions=2.2, seed=3)
    with pytest.raises(ConfigError, match="InstrumentSpecs"):
        self_calibrate(_heads(cap), pulses_per_rev=M, specs={"timebase": 1})  # type: ignore[arg-type]
