"""IEEE Std 952/1431 scale-factor items against twins with known truth (rotacal.gyro.sf_items,
sf_temperature): each item within its stated uncertainty of the truth, and the checks can fail."""

from __future__ import annotations

import numpy as np
import pytest

from rotacal.errors import CaptureError
from rotacal.gyro import calibrate_scale_factor
from rotacal.gyro.sf_items import scale_factor_repeatability, signed_scale_factors
from rotacal.gyro.sf_temperature import temperature_coefficients
from rotacal.sim import simulate_gyro_rates


def _points(cap):
    """Point means and standard errors by numpy alone (independent of rotacal's grouping)."""
    rate, out = cap.columns["rate_deg_s"], cap.columns["output"]
    rates = np.unique(rate)
    means = np.array([out[rate == r].mean() for r in rates])
    se = np.array([out[rate == r].std(ddof=1) / np.sqrt(np.sum(rate == r)) for r in rates])
    temps = (
        np.array([cap.columns["temperature_c"][rate == r].mean() for r in rates])
        if "temperature_c" in cap.columns
        else None
    )
    return rates, means, se, temps


@pytest.mark.parametrize("nonlinearity", [None, (4e-8, -1.5e-11)])
def test_asymmetry_truth_in_out(nonlinearity):
    cap = simulate_gyro_rates(asymmetry_ppm=500.0, nonlinearity=nonlinearity, seed=3)
    r = calibrate_scale_factor(cap.columns["rate_deg_s"], cap.columns["output"])
    sg, t = r.signed, cap.truth
    assert sg is not None
    for key in ("scale_factor_positive", "scale_factor_negative", "asymmetry_ppm"):
        assert abs(getattr(sg, key) - t[key]) < 3 * getattr(sg, f"{key}_u"), key
    # the check can fail: a symmetric gyro's truth (0 ppm) is far outside the stated u
    assert abs(sg.asymmetry_ppm - 0.0) > 10 * sg.asymmetry_ppm_u
    d = r.to_dict()
    assert d["asymmetry_ppm"] == sg.asymmetry_ppm and "signed" not in d


def test_asymmetry_u_matches_the_spread_of_twin_repeats():
    z = []
    for seed in range(40):
        cap = simulate_gyro_rates(asymmetry_ppm=200.0, samples_per_point=200, seed=seed)
        rates, means, se, _ = _points(cap)
        sg = signed_scale_factors(rates, means, se, scale_factor=cap.truth["ls_scale_factor"])
        z.append((sg.asymmetry_ppm - cap.truth["asymmetry_ppm"]) / sg.asymmetry_ppm_u)
    assert 0.7 < np.std(z) < 1.4 and abs(np.mean(z)) < 0.5


def test_too_few_points_of_one_sign_is_flagged():
    cap = simulate_gyro_rates(rates_deg_s=(-10, 10, 20, 30, 40), samples_per_point=50)
    r = calibrate_scale_factor(cap.columns["rate_deg_s"], cap.columns["output"])
    assert r.signed is None
    assert any("per sign" in w for w in r.warnings)
    d = r.to_dict()
    assert d["scale_factor_positive"] is None and d["asymmetry_ppm"] is None
    one_sign = simulate_gyro_rates(rates_deg_s=(10, 20, 30, 40), samples_per_point=50)
    r = calibrate_scale_factor(one_sign.columns["rate_deg_s"], one_sign.columns["output"])
    assert r.signed is None and not any("per sign" in w for w in r.warnings)
    assert any("one sign" in n for n in r.notes)
    with pytest.raises(CaptureError, match="at least 2 of each sign"):
        signed_scale_factors(np.array([-1.0, 1.0, 2.0]), np.ones(3), np.ones(3), scale_factor=1.0)


def test_repeatability_against_the_realised_runs():
    runs = [
        simulate_gyro_rates(
            run_scale_factor_std_ppm=300.0, nonlinearity=None, samples_per_point=300, seed=s
        )
        for s in range(8)
    ]
    s, u = [], []
    for c in runs:  # each run's line by numpy alone, u through the slope's weights
        rates, means, se, _ = _points(c)
        s.append(np.polyfit(rates, means, 1)[0])
        w = (rates - rates.mean()) / np.sum((rates - rates.mean()) ** 2)
        u.append(np.sqrt(np.sum(w**2 * se**2)))
    rep = scale_factor_repeatability(np.array(s), np.array(u))
    true_s = np.array([c.truth["run_scale_factor"] for c in runs])
    realised = 1e6 * np.std(true_s, ddof=1) / np.mean(true_s)
    # the realised spread differs from the measured one by the runs' own noise only
    assert abs(rep.scale_factor_repeatability_ppm - realised) < 3 * rep.within_run_ppm + 1.0
    # and the population's 300 ppm lies within the stated u (from 8 runs)
    assert (
        abs(rep.scale_factor_repeatability_ppm - 300.0) < 2.5 * rep.scale_factor_repeatability_ppm_u
    )
    # the check can fail: a gyro without run-to-run spread is far outside
    assert rep.scale_factor_repeatability_ppm > 10 * rep.within_run_ppm
    with pytest.raises(CaptureError, match="at least two runs"):
        scale_factor_repeatability(np.array([1.0]))


def _temperature_runs(temps, k_s=80.0, k_b=2e-4, **kw):
    parts = []
    for i, temp in enumerate(temps):
        cap = simulate_gyro_rates(
            temperature_c=temp,
            temperature_ref_c=float(np.mean(temps)),
            scale_factor_tc_ppm_per_c=k_s,
            bias_tc_per_c=k_b,
            samples_per_point=500,
            seed=10 + i,
            **kw,
        )
        parts.append(_points(cap))
    truth = cap.truth
    rates, means, se, t = (np.concatenate(k) for k in zip(*parts, strict=True))
    return rates, means, se, t, truth


@pytest.mark.parametrize("nonlinearity", [None, (4e-8, -1.5e-11)])
def test_temperature_coefficients_truth_in_out(nonlinearity):
    rates, means, se, t, truth = _temperature_runs(
        (0.0, 20.0, 40.0, 60.0), nonlinearity=nonlinearity
    )
    tc = temperature_coefficients(rates, means, se, t)
    for key in (
        "scale_factor_temperature_coefficient_ppm_per_c",
        "bias_temperature_coefficient_deg_h_per_c",
    ):
        assert abs(getattr(tc, key) - truth[key]) < 3 * getattr(tc, f"{key}_u"), key
    assert tc.temperature_model == "linear" and tc.temperature_ref_c == pytest.approx(30.0)
    # the check can fail: a gyro without temperature dependence is far outside
    assert (
        abs(tc.scale_factor_temperature_coefficient_ppm_per_c)
        > 10 * tc.scale_factor_temperature_coefficient_ppm_per_c_u
    )


def test_temperature_refuses_what_it_cannot_tell():
    rates, means, se, t, _ = _temperature_runs((20.0, 20.5))
    with pytest.raises(CaptureError, match="too small to tell"):
        temperature_coefficients(rates, means, se, t)
    # one rate at each temperature cannot separate S(T) from V0(T)
    with pytest.raises(CaptureError, match="two rates"):
        temperature_coefficients(
            np.array([10.0, 10.0, 10.0]), np.ones(3), np.ones(3), np.array([0.0, 10.0, 20.0])
        )


def test_temperature_u_matches_the_spread_of_twin_repeats():
    z_s, z_b = [], []
    for seed in range(30):
        parts = []
        for i, temp in enumerate((0.0, 20.0, 40.0, 60.0)):
            cap = simulate_gyro_rates(
                temperature_c=temp,
                temperature_ref_c=30.0,
                scale_factor_tc_ppm_per_c=80.0,
                bias_tc_per_c=2e-4,
                nonlinearity=None,
                samples_per_point=200,
                seed=100 * seed + i,
            )
            parts.append(_points(cap))
        tc = temperature_coefficients(*(np.concatenate(k) for k in zip(*parts, strict=True)))
        key_s = "scale_factor_temperature_coefficient_ppm_per_c"
        key_b = "bias_temperature_coefficient_deg_h_per_c"
        z_s.append((getattr(tc, key_s) - cap.truth[key_s]) / getattr(tc, f"{key_s}_u"))
        z_b.append((getattr(tc, key_b) - cap.truth[key_b]) / getattr(tc, f"{key_b}_u"))
    for z in (z_s, z_b):
        assert 0.7 < np.std(z) < 1.4 and abs(np.mean(z)) < 0.6
