"""Constant-rate calibration from pulse timing (seed 004 §5) against the twin and closed forms."""

from __future__ import annotations

import allantools
import numpy as np
import pytest

from rotacal.encoder.pulses import pulse_angle_deg, pulse_rate
from rotacal.encoder.selfcal import self_calibrate
from rotacal.errors import CaptureError, ConfigError
from rotacal.sim.pulses import simulate_pulses, table_angle_deg, table_rate_deg_s
from rotacal.table.rate import allan_versus_angle, calibrate_rate


def _heads(cap):
    return [cap.columns[f"head_{i}"] for i in range(cap.truth["heads"])]


@pytest.fixture(scope="module")
def biased():
    """A table 0.01 % fast with 0.01 % fluctuation and coarse graduation errors."""
    return simulate_pulses(
        heads=8,
        pulses_per_rev=7200,
        rate_deg_s=60.0,
        revolutions=4.2,
        rate_bias_percent=0.01,
        rate_fluctuation_percent=0.01,
        graduation_noise_arcsec=0.3,
        seed=11,
    )


def test_mean_rate_and_bias_against_truth(biased):
    r = calibrate_rate(_heads(biased), pulses_per_rev=7200, set_rate_deg_s=60.0)
    true_mean = biased.truth["mean_rate_whole_revs_deg_s"]
    assert r.mean_rate_deg_s == pytest.approx(true_mean, rel=1e-9)
    assert r.revolutions == 4
    true_bias_pct = 100 * (true_mean - 60.0) / 60.0
    assert r.rate_bias_percent == pytest.approx(true_bias_pct, abs=1e-7)
    assert r.rate_bias_percent == pytest.approx(0.01, abs=2e-3)  # the set bias, ± the fluctuation


def test_compensation_removes_the_scale_deviation_from_the_rate(biased):
    r = calibrate_rate(_heads(biased), pulses_per_rev=7200, average=10)
    assert r.compensated and r.selfcal is not None
    t0 = biased.columns["head_0"]
    k = np.arange(t0.size)
    # the best any 8-head self-calibration can do: compensate with the twin's detectable part
    ideal = pulse_angle_deg(k, 7200, biased.truth["deviation_detectable_arcsec"])
    _, rate_ideal = pulse_rate(t0, ideal, average=10)
    # the twin's continuous rate, averaged over the same 10 intervals
    true_angle = table_angle_deg(biased.truth, t0)
    _, rate_true = pulse_rate(t0, true_angle, average=10)
    nominal_err = np.sqrt(np.mean((r.rate_uncompensated_deg_s - rate_true) ** 2))
    assert np.sqrt(np.mean((r.rate_deg_s - rate_ideal) ** 2)) < 0.1 * nominal_err
    # what stays is the random graduation error at orders that are multiples of 8 (~1/√8)
    comp_err = np.sqrt(np.mean((r.rate_deg_s - rate_true) ** 2))
    assert 0.2 * nominal_err < comp_err < 0.5 * nominal_err


def test_stated_stability_is_the_tables_fluctuation():
    cap = simulate_pulses(heads=12, pulses_per_rev=18000, revolutions=3.2, seed=8)
    r = calibrate_rate(_heads(cap), pulses_per_rev=18000, average=10)
    assert r.rate_deviation_rms_percent == pytest.approx(
        cap.truth["rate_fluctuation_rms_percent"], rel=0.1
    )
    rate_true = table_rate_deg_s(cap.truth, r.time_s)
    assert np.corrcoef(rate_true, r.rate_deg_s)[0, 1] > 0.95


def test_allan_versus_angle_white_timing_noise_closed_form():
    """Only white timing jitter σ_t: s(φ) = √3·σ_t·ω_m/φ."""
    sigma_t, rate = 2e-7, 100.0
    cap = simulate_pulses(
        heads=2,
        pulses_per_rev=3600,
        rate_deg_s=rate,
        revolutions=20,
        harmonics=(),
        graduation_noise_arcsec=0.0,
        head_placement_arcsec=0.0,
        rate_fluctuation_percent=0.0,
        jitter_s=sigma_t,
        seed=3,
    )
    t = cap.columns["head_0"]
    phi, s = allan_versus_angle(
        t, np.arange(t.size) * 0.1, mean_rate_deg_s=rate, angles_deg=[0.1, 1.0, 10.0, 100.0]
    )
    expected = np.sqrt(3) * sigma_t * rate / phi
    # relative scatter of an Allan estimate ~ 1/√(terms); terms ≥ 4800 here
    assert np.allclose(s, expected, rtol=0.06)


def test_allan_versus_angle_agrees_with_allantools(biased):
    """s(φ) linearised is the overlapping ADEV of the time error x = t − θ/ω_m (allantools)."""
    r = calibrate_rate(
        _heads(biased),
        pulses_per_rev=7200,
        compensate=False,
        allan_angles_deg=[0.05, 0.5, 5.0, 50.0, 360.0],
    )
    t = biased.columns["head_0"]
    theta = np.arange(t.size) * 360.0 / 7200
    x = t - theta / r.mean_rate_deg_s
    rate_hz = r.mean_rate_deg_s / (360.0 / 7200)
    taus = np.asarray(r.allan_angle_deg) / r.mean_rate_deg_s
    tau_out, adev, _, _ = allantools.oadev(x, rate=rate_hz, data_type="phase", taus=taus)
    assert np.allclose(tau_out, taus, rtol=1e-9)
    assert np.allclose(r.allan_relative, adev, rtol=2e-3)


def test_other_head_and_all_heads(biased):
    heads = _heads(biased)
    r5 = calibrate_rate(heads, pulses_per_rev=7200, head=5)
    r0 = calibrate_rate(heads, pulses_per_rev=7200, head=0)
    assert r5.head == "head_5" and r5.compensated
    assert r5.rate_deviation_rms_percent == pytest.approx(r0.rate_deviation_rms_percent, rel=0.1)
    # head 5 compensated against the truth at its own pulses
    t5 = heads[5]
    true = table_angle_deg(biased.truth, t5) - table_angle_deg(biased.truth, t5[:1])
    d = r0.selfcal.deviation_arcsec
    k = np.arange(t5.size)
    comp = (
        k * 0.05 + (d[(k + r5.deviation_shift_pulses) % 7200] - d[r5.deviation_shift_pulses]) / 3600
    )
    und = np.asarray(biased.truth["deviation_arcsec"]) - np.asarray(
        biased.truth["deviation_detectable_arcsec"]
    )
    resid = (true - comp) * 3600
    assert np.sqrt(np.mean((resid - resid.mean()) ** 2)) < 3 * np.sqrt(np.mean(und**2)) + 0.02
    ra = calibrate_rate(heads, pulses_per_rev=7200, head="all")
    assert ra.head == "all heads" and not ra.compensated
    start, stop = ra.mean_rate_window_s
    true_mean = (
        table_angle_deg(biased.truth, np.array([stop]))
        - table_angle_deg(biased.truth, np.array([start]))
    )[0] / (stop - start)
    assert ra.mean_rate_deg_s == pytest.approx(true_mean, rel=1e-9)


def test_deviation_from_another_capture_is_aligned(biased):
    heads = _heads(biased)
    sc = self_calibrate(heads, pulses_per_rev=7200)
    later = [h[h.searchsorted(heads[0][2500]) :] for h in heads]  # the "next" capture
    r = calibrate_rate(later, pulses_per_rev=7200, selfcal=sc.deviation_arcsec)
    assert r.deviation_shift_pulses == 2500
    assert r.alignment_correlation > 0.9
    # one head only: matched on orders ≥ 2 (the table's once-per-rev fluctuation mimics order 1)
    r1 = calibrate_rate(later[:1], pulses_per_rev=7200, selfcal=sc.deviation_arcsec)
    assert r1.deviation_shift_pulses == 2500 and r1.compensated
    with pytest.raises(CaptureError, match="does not match"):
        calibrate_rate(
            later, pulses_per_rev=7200, selfcal=np.random.default_rng(0).normal(size=7200)
        )
    with pytest.raises(ConfigError, match="7000 pulses per revolution"):
        calibrate_rate(later, pulses_per_rev=7200, selfcal=np.zeros(7000))
    # the JSON form of the same capture needs no alignment
    r_same = calibrate_rate(heads, pulses_per_rev=7200, selfcal=sc.to_dict())
    assert r_same.deviation_shift_pulses == 0 and r_same.alignment_correlation is None


def test_interface_keys_and_bad_settings(biased):
    heads = _heads(biased)
    d = calibrate_rate(heads[:1], pulses_per_rev=7200).to_dict()
    for key in (
        "mean_rate_deg_s",
        "rate_deviation_rms_percent",
        "allan_angle_deg",
        "allan_relative",
    ):
        assert key in d
    assert not d["compensated"]
    with pytest.raises(ConfigError, match="head 9 does not exist"):
        calibrate_rate(heads, pulses_per_rev=7200, head=9)
    with pytest.raises(ConfigError, match="head must be"):
        calibrate_rate(heads, pulses_per_rev=7200, head="left")
    with pytest.raises(ConfigError, match="set_rate_deg_s"):
        calibrate_rate(heads, pulses_per_rev=7200, set_rate_deg_s=float("nan"))


def test_a_different_capture_with_the_same_first_time_is_aligned(biased):
    """DAQs that zero the time at the first edge: the first time alone does not identify a capture."""
    heads = _heads(biased)
    sc = self_calibrate(heads, pulses_per_rev=7200).to_dict()
    later = [h[h.searchsorted(heads[0][2500]) :] for h in heads]
    t0 = later[0][0]
    later = [h - t0 + heads[0][0] for h in later]  # same first time as the self-calibrated capture
    r = calibrate_rate(later, pulses_per_rev=7200, selfcal=sc)
    assert r.deviation_shift_pulses == 2500 and r.alignment_correlation > 0.9


def test_selfcal_json_faults_are_config_errors(biased):
    heads = _heads(biased)
    sc = self_calibrate(heads, pulses_per_rev=7200).to_dict()
    for key, value, needle in [
        ("first_pulse_time_s", "x", "must be a number"),
        ("rotation", "left", "'forward' or 'reverse'"),
        ("pulses_per_rev", 3600.5, "whole number"),
        ("deviation_arcsec", [[0.0] * 7200], "one list"),
    ]:
        bad = {**sc, key: value}
        with pytest.raises(ConfigError, match=needle):
            calibrate_rate(heads, pulses_per_rev=7200, selfcal=bad)


def test_negative_set_rate_is_compared_by_magnitude(biased):
    r = calibrate_rate(_heads(biased)[:1], pulses_per_rev=7200, set_rate_deg_s=-60.0)
    assert abs(r.rate_bias_percent) < 0.05
    assert any("no sense of rotation" in n for n in r.notes)


def test_short_multi_head_record_points_to_no_compensation():
    cap = simulate_pulses(heads=4, pulses_per_rev=3000, revolutions=0.9, seed=1)
    with pytest.raises(CaptureError, match="no-compensation"):
        calibrate_rate(_heads(cap), pulses_per_rev=3000)
    r = calibrate_rate(_heads(cap), pulses_per_rev=3000, compensate=False)
    assert r.revolutions == 0 and any("straight-line fit" in n for n in r.notes)
