"""Uncertainty budgets of the IEEE 952 noise terms: hand-derived sensitivities, the JSON's one
interval per term, and the honesty check on the static-gyro twin (spread of the ARW over
independent records against its stated u)."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from scipy import stats

from rotacal.errors import ConfigError
from rotacal.gyro.noise import gyro_noise
from rotacal.sim import simulate_gyro_noise
from rotacal.uncertainty.distributions import Rectangular
from rotacal.uncertainty.specs import InstrumentSpecs, load_specs

NAMED = (
    "arw_deg_rt_h",
    "bias_instability_deg_h",
    "rrw_deg_h_rt_h",
    "quantization_deg",
    "rate_ramp_deg_h2",
)


def _chi2_bounds(n: int, level: float = 0.999) -> tuple[float, float]:
    """Bounds of std/σ for n normal repeats at the two-sided ``level``."""
    tail = 0.5 * (1.0 - level)
    q = stats.chi2.ppf([tail, 1.0 - tail], n - 1)
    return float(np.sqrt(q[0] / (n - 1))), float(np.sqrt(q[1] / (n - 1)))


def test_budget_rows_and_hand_derived_sensitivities():
    specs = load_specs(
        {"timebase": {"relative_error": {"distribution": "rectangular", "half_width": 0.01}}}
    )
    cap = simulate_gyro_noise(
        duration_s=4 * 3600,
        fs_hz=20.0,
        arw_deg_rt_h=0.3,
        bias_instability_deg_h=0.0,
        rrw_deg_h_rt_h=20.0,
        seed=5,
    )
    r = gyro_noise(cap.columns["rate_deg_s"], time_s=cap.columns["time_s"], specs=specs)
    arw = r._budgets["arw_deg_rt_h"]
    row_a, row_b = arw.rows
    # the fit's value, in °/√h, enters with sensitivity 1 (no timebase error stated as a mean)
    assert row_a.sensitivity == pytest.approx(1.0, rel=1e-12)
    assert row_a.value == pytest.approx(r.arw_deg_rt_h, rel=1e-12)
    assert row_a.value == pytest.approx(60.0 * r.fit.coefficients[1], rel=1e-12)
    # a clock long by e makes τ long by e: N_true = N·(1 + e)^(−½), sensitivity −N/2
    assert row_b.sensitivity == pytest.approx(-0.5 * r.arw_deg_rt_h, rel=1e-9)
    assert row_b.u == pytest.approx(0.01 / math.sqrt(3.0), rel=1e-12)
    assert arw.u == pytest.approx(math.hypot(row_a.contribution, row_b.contribution), rel=1e-12)
    # K (°/h/√h); τ long by e: K_true = K·(1 + e)^(+½)
    rrw = r._budgets["rrw_deg_h_rt_h"]
    assert rrw.rows[1].sensitivity == pytest.approx(0.5 * r.rrw_deg_h_rt_h, rel=1e-9)
    low, high = r.noise_terms["rrw_deg_h_rt_h_interval"]
    assert low <= 20.0 <= high


def test_bias_instability_budget_is_the_fits():
    cap = simulate_gyro_noise(duration_s=3600, arw_deg_rt_h=0.1, bias_instability_deg_h=2.0, seed=9)
    r = gyro_noise(cap.columns["rate_deg_s"], fs_hz=100.0)
    b = r._budgets["bias_instability_deg_h"]
    (row,) = b.rows  # slope 0: a timebase error does not move B
    assert row.value == pytest.approx(3600.0 * r.fit.coefficients[2], rel=1e-12)
    assert b.U == pytest.approx(3600.0 * r.fit.expanded[2], rel=1e-9)
    assert any("generalised least-squares" in n for n in b.notes)
    assert any("Type A only" in n for n in b.notes)
    low, high = r.noise_terms["bias_instability_deg_h_interval"]
    assert low <= 2.0 <= high


def test_json_keys_for_every_named_term():
    """Every term has its value, u, U, k and ONE 95 % interval (value ± U clipped at 0), the same
    at the top level and in ``noise_terms``; an absent term has 0 in its interval."""
    cap = simulate_gyro_noise(duration_s=900, seed=2)
    r = gyro_noise(cap.columns["rate_deg_s"], time_s=cap.columns["time_s"])
    d = json.loads(json.dumps(r.to_dict()))
    nested = d["noise_terms"]
    for key in NAMED:
        assert d[f"{key}_u"] > 0 and d[f"{key}_U"] > d[f"{key}_u"]
        assert d["k"][key] == pytest.approx(d[f"{key}_U"] / d[f"{key}_u"])
        assert d["uncertainty_budgets"][key]["u"] == d[f"{key}_u"]
        out = "quantization_arcsec" if key == "quantization_deg" else key
        scale = 3600.0 if key == "quantization_deg" else 1.0
        assert nested[out] == pytest.approx(d[key] * scale, rel=1e-12)
        assert nested[f"{out}_U"] == pytest.approx(d[f"{key}_U"] * scale, rel=1e-12)
        low, high = nested[f"{out}_interval"]
        assert low == pytest.approx(max(0.0, nested[out] - nested[f"{out}_U"]), abs=1e-15)
        assert high == pytest.approx(nested[out] + nested[f"{out}_U"], rel=1e-12)
    assert "intervals" not in d  # the slope method's second interval is gone
    assert nested["rrw_deg_h_rt_h_interval"][0] == 0.0
    assert d["coverage_probability"] == 0.95


def test_bad_specification_is_one_line():
    for spec, msg in (
        ({"distribution": "rectangular", "u": -1e-6}, "≥ 0"),
        ({"distribution": "lognormal", "u": 1e-6}, "unknown distribution"),
    ):
        with pytest.raises(ConfigError, match=msg) as exc:
            load_specs({"timebase": {"relative_error": spec}})
        assert "\n" not in str(exc.value)


@pytest.mark.parametrize("with_timebase", [False, True])
def test_honesty_arw_spread_matches_its_u_on_the_twin(with_timebase):
    """60 independent 10-minute static records (0.3 °/√h, 3 °/h): std(ARW)/mean(u) within the
    χ² bounds for 60 repeats at 99.9 %. With a ±10 % rectangular timebase error drawn per run by
    the twin and stated in the specs, the Type B row is checked too (it is then ~60 % of u²)."""
    n = 60
    half = 0.1
    # ±10 % is far beyond a real clock (load_specs would call it implausible): built in code so
    # that the Type B row carries a real share of u²
    specs = (
        InstrumentSpecs({"timebase.relative_error": Rectangular.centered(0.0, half)})
        if with_timebase
        else None
    )
    rng = np.random.default_rng(11)
    est, us = [], []
    for i in range(n):
        e = float(rng.uniform(-half, half)) if with_timebase else 0.0
        cap = simulate_gyro_noise(duration_s=600.0, seed=2000 + i, timebase_relative_error=e)
        r = gyro_noise(cap.columns["rate_deg_s"], time_s=cap.columns["time_s"], specs=specs)
        est.append(r.arw_deg_rt_h)
        us.append(r._budgets["arw_deg_rt_h"].u)
    ratio = float(np.std(est, ddof=1) / np.mean(us))
    lo, hi = _chi2_bounds(n)
    assert lo < ratio < hi, ratio
    # and no bias: the mean of 60 within 4 standard errors of the truth
    assert abs(np.mean(est) - 0.3) < 4 * np.std(est, ddof=1) / math.sqrt(n)


def test_twin_timebase_error_stretches_the_time_column_only():
    a = simulate_gyro_noise(duration_s=100.0, seed=4)
    b = simulate_gyro_noise(duration_s=100.0, seed=4, timebase_relative_error=0.01)
    np.testing.assert_array_equal(a.columns["rate_deg_s"], b.columns["rate_deg_s"])
    np.testing.assert_allclose(b.columns["time_s"], 1.01 * a.columns["time_s"], rtol=1e-15)
    assert b.truth["timebase_relative_error"] == 0.01
    with pytest.raises(ConfigError, match="timebase_relative_error"):
        simulate_gyro_noise(timebase_relative_error=-1.0)


def test_a_stated_mean_timebase_error_is_corrected_and_said():
    """Policy A: a stated non-zero mean clock error corrects each term by (1 + e)^p (τ of the
    record is τ_true·(1 + e); p the slope of the term's line), the budget says so in the standard
    text and its row keeps the stated value and u. B (slope 0) does not change."""
    e = 1e-3
    cap = simulate_gyro_noise(duration_s=600.0, seed=3, timebase_relative_error=e)
    spec = {"timebase": {"relative_error": {"distribution": "normal", "value": e, "u": 1e-5}}}
    plain = gyro_noise(cap.columns["rate_deg_s"], time_s=cap.columns["time_s"])
    r = gyro_noise(cap.columns["rate_deg_s"], time_s=cap.columns["time_s"], specs=load_specs(spec))
    assert r.arw_deg_rt_h == pytest.approx(plain.arw_deg_rt_h * (1 + e) ** -0.5, rel=1e-12)
    assert r.bias_instability_deg_h == plain.bias_instability_deg_h
    b = r._budgets["arw_deg_rt_h"]
    assert b.value == r.arw_deg_rt_h
    assert any(
        "corrected for the stated mean of timebase.relative_error = 0.001" in n for n in b.notes
    )
    row = b.rows[1]
    assert (row.value, row.u) == (e, 1e-5) and "timebase.relative_error" in row.origin
