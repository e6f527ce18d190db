"""Sinusoidal-motion calibration against the twin's truth and closed forms (seed 000)."""

from __future__ import annotations

import numpy as np
import pytest

from rotacal import sim
from rotacal.errors import CaptureError, ConfigError
from rotacal.table import (
    calibrate_encoder_motion,
    calibrate_fog_motion,
    calibrate_lts_motion,
    compare_schemes,
    extreme_reversals,
    position_error,
)

# A distorted motion like the seed's 0.5°/2 Hz run: 2nd and 3rd harmonics, mild stagnation.
DISTORTED = sim.SineMotion(
    amplitude_deg=0.5,
    frequency_hz=2.0,
    harmonics={2: (0.010, 0.4), 3: (0.008, 1.1), 5: (0.002, 2.0)},
)


def _check_against_truth(r, truth, *, thd_pp, amp_rel=2e-4, freq_rel=1e-5):
    assert r.thd_percent == pytest.approx(truth["thd_percent"], abs=thd_pp)
    assert r.amplitude_deg == pytest.approx(truth["amplitude_deg"], rel=amp_rel)
    assert r.frequency_hz == pytest.approx(truth["frequency_hz"], rel=freq_rel)
    accel = truth["angular_acceleration_amplitude_deg_s2"]
    assert r.angular_acceleration_amplitude_deg_s2 == pytest.approx(
        accel, rel=2 * amp_rel + 2 * freq_rel
    )


def test_encoder_scheme_meets_accuracy_bars_on_an_imperfect_encoder():
    cap = sim.simulate_encoder(
        DISTORTED,
        offset_a=0.03,
        offset_b=-0.02,
        amplitude_b=0.97,
        phase_error_rad=np.radians(1.5),
        noise_rms=0.004,
        adc_bits=16,
        seed=3,
    )
    c = cap.columns
    r = calibrate_encoder_motion(c["time_s"], c["a"], c["b"], lines=36000)
    truth = DISTORTED.truth(r.analysis_start_s, r.analysis_stop_s)
    _check_against_truth(r, truth, thd_pp=0.02)
    assert r.periods_used >= 4
    assert "heydemann" in r.notes[0].lower()


def test_encoder_reversal_times_within_milliseconds_of_truth():
    cap = sim.simulate_encoder(DISTORTED, noise_rms=0.002, seed=1)
    c = cap.columns
    r = calibrate_encoder_motion(c["time_s"], c["a"], c["b"], lines=36000)
    t = c["time_s"]
    truth = np.asarray(DISTORTED.truth(t[0], t[-1])["reversal_times_s"])
    assert r.reversal_times_s.size == truth.size
    assert np.max(np.abs(r.reversal_times_s - truth)) < 3e-3


def test_encoder_reversals_survive_a_vibration_near_the_reversals():
    shaky = sim.SineMotion(
        amplitude_deg=0.25, frequency_hz=3.0, vibration_deg=0.0015, vibration_hz=61.0
    )
    cap = sim.simulate_encoder(shaky, noise_rms=0.002, seed=2)
    c = cap.columns
    t = c["time_s"]
    # the vibration really makes the velocity cross zero several times near each reversal
    v = shaky.rate_deg_s(t)
    crossings = np.count_nonzero(np.diff(np.signbit(v)))
    n_true = len(shaky.truth(t[0], t[-1])["reversal_times_s"])
    assert crossings >= n_true + 6
    r = calibrate_encoder_motion(t, c["a"], c["b"], lines=36000)
    truth = np.asarray(shaky.truth(t[0], t[-1])["reversal_times_s"])
    assert r.reversal_times_s.size == truth.size
    assert np.max(np.abs(r.reversal_times_s - truth)) < 0.25 / 61.0


def test_lts_scheme_meets_accuracy_bars():
    m = sim.SineMotion(
        amplitude_deg=0.025, frequency_hz=10.0, harmonics={2: (0.03, 0.2), 3: (0.03, 1.0)}
    )
    cap = sim.simulate_lts(m, radius_mm=100.0, noise_mm=3e-5, seed=4)
    c = cap.columns
    r = calibrate_lts_motion(c["time_s"], c["displacement_mm"], radius_mm=100.0)
    truth = m.truth(r.analysis_start_s, r.analysis_stop_s)
    _check_against_truth(r, truth, thd_pp=0.05)
    t = c["time_s"]
    true_rev = np.asarray(m.truth(t[0], t[-1])["reversal_times_s"])
    assert r.reversal_times_s.size == true_rev.size
    assert np.max(np.abs(r.reversal_times_s - true_rev)) < 2e-3


def test_fog_scheme_meets_accuracy_bar_at_10_db_snr():
    cap = sim.simulate_fog(
        DISTORTED, snr_db=10.0, bias_deg_s=0.3, fs_hz=2000.0, duration_s=40.25, seed=5
    )
    c = cap.columns
    r = calibrate_fog_motion(c["time_s"], c["rate_deg_s"])
    truth = DISTORTED.truth(r.analysis_start_s, r.analysis_stop_s)
    _check_against_truth(r, truth, thd_pp=0.15, amp_rel=5e-3, freq_rel=1e-4)
    assert r.snr_db == pytest.approx(10.0, abs=0.5)


def test_fog_thd_error_over_many_noise_draws_stays_within_the_bar():
    """Not one lucky seed: the worst of ten draws at 10 dB SNR."""
    errs = []
    for seed in range(10):
        c = sim.simulate_fog(
            DISTORTED, snr_db=10.0, fs_hz=2000.0, duration_s=40.25, seed=seed
        ).columns
        r = calibrate_fog_motion(c["time_s"], c["rate_deg_s"])
        errs.append(
            r.thd_percent - DISTORTED.truth(r.analysis_start_s, r.analysis_stop_s)["thd_percent"]
        )
    assert max(abs(e) for e in errs) < 0.15


def test_position_error_of_an_amplitude_error_is_closed_form():
    """θ = (1+ε)A sin(ωt+φ) against set A: ap_err = εA sin(·), max εA, rms εA/√2 (eq. 2)."""
    eps, a_set, f = 1e-3, 0.5, 2.0
    t = np.arange(0, 3.0, 1e-4)
    theta = 0.1 + (1 + eps) * a_set * np.sin(2 * np.pi * f * t + 0.7)
    err = position_error(t, theta, a_set, f)
    assert np.max(np.abs(err)) == pytest.approx(eps * a_set, rel=1e-6)
    assert np.sqrt(np.mean(err**2)) == pytest.approx(eps * a_set / np.sqrt(2), rel=1e-4)


def test_set_values_give_errors_in_percent():
    m = sim.SineMotion(amplitude_deg=0.5 * 1.002, frequency_hz=2.0 * (1 - 1e-4))
    c = sim.simulate_encoder(m, seed=0).columns
    r = calibrate_encoder_motion(
        c["time_s"], c["a"], c["b"], lines=36000, set_amplitude_deg=0.5, set_frequency_hz=2.0
    )
    assert r.amplitude_error_percent == pytest.approx(0.2, abs=2e-3)
    assert r.frequency_error_percent == pytest.approx(-0.01, abs=1e-4)
    # a = A(2πf)²: relative errors add to first order
    assert r.angular_acceleration_error_percent == pytest.approx(0.2 - 0.02, abs=3e-3)
    d = r.to_dict()
    for key in ("amplitude_error_percent", "position_error_max_deg", "position_error_rms_deg"):
        assert key in d
    assert "snr_db" not in d


def test_extreme_reversals_of_a_clean_cosine():
    t = np.arange(0, 2.0, 1e-3)
    x = np.cos(2 * np.pi * 3 * t + 0.3)
    rev = extreme_reversals(t, x)
    truth = (np.arange(1, 12) * np.pi - 0.3) / (2 * np.pi * 3)
    truth = truth[(truth > rev[0] - 0.01) & (truth < rev[-1] + 0.01)]
    np.testing.assert_allclose(rev, truth, atol=1e-6)


def test_compare_schemes_is_reference_minus_other_for_every_quantity():
    c = sim.simulate_encoder(DISTORTED, seed=0).columns
    a = calibrate_encoder_motion(c["time_s"], c["a"], c["b"], lines=36000)
    f = sim.simulate_fog(DISTORTED, snr_db=20.0, seed=0).columns
    b = calibrate_fog_motion(f["time_s"], f["rate_deg_s"])
    row = compare_schemes(a, b)
    assert row.thd_difference_percent == pytest.approx(a.thd_percent - b.thd_percent)
    assert row.amplitude_difference_percent == pytest.approx(
        100 * (a.amplitude_deg - b.amplitude_deg) / a.amplitude_deg
    )
    assert row.frequency_difference_percent == pytest.approx(
        100 * (a.frequency_hz - b.frequency_hz) / a.frequency_hz
    )
    assert row.snr_db == b.snr_db


@pytest.mark.parametrize(
    ("mutate", "message"),
    [
        (lambda t, a, b: (t, np.where(np.arange(a.size) == 100, np.nan, a), b), "sample 100"),
        (lambda t, a, b: (t[::-1].copy(), a, b), "not strictly increasing"),
        (lambda t, a, b: (t[:4000], a[:4000], b[:4000]), "reversing moment"),
    ],
)
def test_bad_encoder_input_raises_capture_error(mutate, message):
    c = sim.simulate_encoder(DISTORTED, seed=0).columns
    t, a, b = mutate(c["time_s"], c["a"], c["b"])
    with pytest.raises(CaptureError, match=message):
        calibrate_encoder_motion(t, a, b, lines=36000)


def test_asking_for_more_periods_than_recorded_is_an_error():
    c = sim.simulate_encoder(DISTORTED, seed=0).columns
    with pytest.raises(CaptureError, match="periods"):
        calibrate_encoder_motion(c["time_s"], c["a"], c["b"], lines=36000, periods=99)
    with pytest.raises(ConfigError):
        calibrate_encoder_motion(c["time_s"], c["a"], c["b"], lines=36000, harmonics=0)


@pytest.mark.parametrize("index", range(5))
def test_table1_scenarios_of_the_twin_meet_the_bars(index):
    """The five runs of the seed's Table 1 on the twin (harmonics, stagnation, creep, sensor errors)."""
    sc = sim.table1_scenarios()[index]
    kind = sc["paper_sensors"][0]
    c = sim.simulate(kind, motion=sc["motion"], **sc["sensors"][kind]).columns
    if kind == "encoder":
        r = calibrate_encoder_motion(c["time_s"], c["a"], c["b"], lines=36000)
        thd_bar = 0.02
    else:
        r = calibrate_lts_motion(c["time_s"], c["displacement_mm"], radius_mm=100.0)
        thd_bar = 0.05
    truth = sc["motion"].truth(r.analysis_start_s, r.analysis_stop_s)
    _check_against_truth(r, truth, thd_pp=thd_bar)
    true_rev = np.asarray(sc["motion"].truth(c["time_s"][0], c["time_s"][-1])["reversal_times_s"])
    assert r.reversal_times_s.size == true_rev.size
    assert np.max(np.abs(r.reversal_times_s - true_rev)) < 3e-3
    # the FOG on the same run at the bar's 10 dB SNR, set through the twin (not measured), with
    # ≥ 10⁵ samples: at 10 dB the THD's scatter is ~50/√N pp, so shorter records cannot hold 0.15
    period = 1 / sc["frequency_hz"]
    fog_options = {
        **sc["sensors"]["fog"],
        "noise_deg_s": 0.0,
        "snr_db": 10.0,
        "fs_hz": 10_000.0,
        "duration_s": max(100.125 * period, 10.0 + 0.125 * period),
    }
    f = sim.simulate("fog", motion=sc["motion"], **fog_options).columns
    rf = calibrate_fog_motion(f["time_s"], f["rate_deg_s"])
    truth_f = sc["motion"].truth(rf.analysis_start_s, rf.analysis_stop_s)
    assert rf.thd_percent == pytest.approx(truth_f["thd_percent"], abs=0.15)


@pytest.mark.parametrize("bias", [0.5, 8.0])
def test_fog_reversals_ignore_the_gyro_bias(bias):
    """The reversals are zero crossings of the motion's rate, not of rate + bias (D0 of eq. 9)."""
    cap = sim.simulate_fog(DISTORTED, snr_db=30.0, bias_deg_s=bias, seed=7)
    c = cap.columns
    r = calibrate_fog_motion(c["time_s"], c["rate_deg_s"])
    truth = np.asarray(DISTORTED.truth(c["time_s"][0], c["time_s"][-1])["reversal_times_s"])
    assert r.reversal_times_s.size == truth.size
    assert np.max(np.abs(r.reversal_times_s - truth)) < 1e-3


def test_undersampled_encoder_is_refused_not_misread():
    """At 1.3 kHz the phase jumps >150° per sample: an answer would be silently wrong."""
    m = sim.SineMotion(amplitude_deg=0.5, frequency_hz=2.0)
    t = np.arange(0, 3.0, 1 / 1300)
    phi = 2 * np.pi * 36000 * m.angle_deg(t) / 360
    with pytest.raises(CaptureError, match="sampled too slowly"):
        calibrate_encoder_motion(t, np.cos(phi), np.sin(phi), lines=36000)


@pytest.mark.parametrize("scheme", ["encoder", "lts", "fog"])
def test_a_gap_in_the_time_stamps_is_refused(scheme):
    cap = sim.simulate(scheme, motion=DISTORTED, seed=1)
    c = {k: np.delete(v, np.s_[20_000:20_100]) for k, v in cap.columns.items()}
    if scheme == "fog":
        c = {k: np.delete(v, np.s_[2000:2600]) for k, v in cap.columns.items()}
    with pytest.raises(CaptureError, match="gap"):
        if scheme == "encoder":
            calibrate_encoder_motion(c["time_s"], c["a"], c["b"], lines=36000)
        elif scheme == "lts":
            calibrate_lts_motion(c["time_s"], c["displacement_mm"], radius_mm=100.0)
        else:
            calibrate_fog_motion(c["time_s"], c["rate_deg_s"])


def test_lts_displacement_beyond_the_radius_is_refused():
    c = sim.simulate_lts(DISTORTED, seed=0).columns
    with pytest.raises(CaptureError, match="radius-mm"):
        calibrate_lts_motion(c["time_s"], c["displacement_mm"] * 1000, radius_mm=0.5)
