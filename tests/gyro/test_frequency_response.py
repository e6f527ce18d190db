"""`gyro frequency-response` against truths it does not compute: the closed-form H(jω) of a
second-order system written here, the twin's DUT (fn, ζ, bandwidth by root search), the spread of
repeated fits; and its refusals."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import stats
from scipy.optimize import brentq

from rotacal.errors import CaptureError
from rotacal.gyro.frequency_model import bandwidth_from_model, fit_second_order
from rotacal.gyro.frequency_response import calibrate_frequency_response, response_at_frequency
from rotacal.signal import fit_sine_4p
from rotacal.sim.gyro_sine import simulate_gyro_sine

FN, ZETA = 8.0, 0.5
FREQUENCIES = (1.0, 3.0, 6.0, 8.0, 11.0, 16.0)


def h_closed_form(f, fn=FN, zeta=ZETA):
    """H(jω) = ωn²/(ωn² − ω² + 2jζωn·ω), written out here, independent of rotacal."""
    w, wn = 2 * np.pi * np.asarray(f), 2 * np.pi * fn
    return wn**2 / (wn**2 - w**2 + 2j * zeta * wn * w)


def sweep(noise=0.05, reference="encoder", seed=0, frequencies=FREQUENCIES, **kw):
    return [
        simulate_gyro_sine(f, noise_deg_s=noise, reference=reference, seed=seed + i, **kw)
        for i, f in enumerate(frequencies)
    ]


def analyse(caps, **kw):
    kw.setdefault("lines", 3600)
    kw.setdefault("channel_skew_s", 0.0)  # the twin samples every channel at once
    return calibrate_frequency_response([c.columns for c in caps], **kw)


@pytest.fixture(scope="module")
def encoder_sweep():
    caps = sweep()
    return caps, analyse(caps)


def test_each_point_lies_within_its_uncertainty_of_the_closed_form(encoder_sweep):
    _, r = encoder_sweep
    h = h_closed_form(np.array(r.frequency_hz))
    ratio_err = (np.array(r.amplitude_ratio) - np.abs(h)) / np.array(r.amplitude_ratio_u)
    phase_err = (np.array(r.phase_deg) - np.degrees(np.unwrap(np.angle(h)))) / np.array(
        r.phase_deg_u
    )
    # 12 normal deviates at once: the Bonferroni bound of a 0.5 % family-wise false alarm
    bound = stats.norm.ppf(1 - 0.005 / (2 * 2 * len(FREQUENCIES)))
    assert np.all(np.abs(ratio_err) < bound), ratio_err
    assert np.all(np.abs(phase_err) < bound), phase_err
    # the DUT lags, more with frequency; the dB values are the ratios'
    assert np.all(np.diff(r.phase_deg) < 0) and r.phase_deg[0] < 0
    np.testing.assert_allclose(r.amplitude_ratio_db, 20 * np.log10(r.amplitude_ratio))
    np.testing.assert_allclose(r.frequency_hz, FREQUENCIES, rtol=1e-5)


@pytest.mark.parametrize(("noise", "reference"), [(0.05, "encoder"), (1.5, "angle")])
def test_model_recovers_the_twins_dut_at_two_noise_levels(noise, reference, encoder_sweep):
    caps, r = encoder_sweep if noise == 0.05 else (None, None)
    if r is None:
        caps = sweep(noise, reference, seed=50)
        r = analyse(caps)
    truth = caps[0].truth
    for key in ("natural_frequency_hz", "damping_ratio", "bandwidth_hz"):
        err = getattr(r, key) - truth[key]
        assert abs(err) < 3.0 * getattr(r, f"{key}_u"), (key, err, getattr(r, f"{key}_u"))
    assert r.degrees_of_freedom == 2 * len(FREQUENCIES) - 2
    assert r.warnings == ()
    # more noise, larger uncertainty (and it is not zero)
    assert 0 < r.natural_frequency_hz_u < 0.05 * FN


def test_stated_uncertainty_matches_the_spread_of_repeated_sweeps():
    fits = [
        analyse(sweep(1.0, "angle", seed=100 + 10 * k, periods=3, fs_hz=1000.0)) for k in range(16)
    ]
    for key in ("natural_frequency_hz", "damping_ratio", "bandwidth_hz"):
        values = np.array([getattr(r, key) for r in fits])
        u = np.mean([getattr(r, f"{key}_u") for r in fits])
        assert 0.55 < values.std(ddof=1) / u < 1.6, key


def test_table_distortion_does_not_bias_the_fundamental():
    caps = sweep(harmonics={2: (0.05, 0.4), 3: (0.03, 1.1)}, frequencies=(2.0, 6.0, 10.0))
    r = analyse(caps)
    h = h_closed_form(np.array(r.frequency_hz))
    assert np.all(
        np.abs(np.array(r.amplitude_ratio) - np.abs(h)) < 3 * np.array(r.amplitude_ratio_u)
    )
    assert np.all(
        np.abs(np.array(r.phase_deg) - np.degrees(np.angle(h))) < 3 * np.array(r.phase_deg_u)
    )


def test_bandwidth_closed_form_against_root_search():
    assert bandwidth_from_model(10.0, 1 / math.sqrt(2)) == pytest.approx(10.0, rel=1e-14)
    for zeta in (0.05, 0.3, 0.5, 1.0, 2.5):
        found = brentq(
            lambda f, z=zeta: abs(h_closed_form(f, 10.0, z)) - 1 / math.sqrt(2), 1e-3, 1e3
        )
        assert bandwidth_from_model(10.0, zeta) == pytest.approx(found, rel=1e-12)


def test_bandwidth_uncertainty_is_the_propagated_covariance():
    """u(f_3dB) from the gradient against a finite-difference propagation of the covariance."""
    f = np.array(FREQUENCIES)
    h = h_closed_form(f)
    u = np.full(f.size, 0.01)
    fit = fit_second_order(f, np.abs(h), u, np.degrees(np.angle(h)), u * 50)
    assert fit.natural_frequency_hz == pytest.approx(FN, rel=1e-9)
    assert fit.damping_ratio == pytest.approx(ZETA, rel=1e-9)
    eps = 1e-6
    g = np.array(
        [
            (bandwidth_from_model(FN + eps, ZETA) - bandwidth_from_model(FN - eps, ZETA)) / 2 / eps,
            (bandwidth_from_model(FN, ZETA + eps) - bandwidth_from_model(FN, ZETA - eps)) / 2 / eps,
        ]
    )
    assert fit.bandwidth_hz_u == pytest.approx(math.sqrt(g @ fit.covariance @ g), rel=1e-6)


def test_a_common_skew_enters_the_parameters_and_a_fitted_delay_absorbs_it():
    caps = sweep(delay_s=0.002, frequencies=(1.0, 3.0, 6.0, 9.0, 13.0), noise=0.2)
    with_delay = analyse(caps, delay=True)
    assert abs(with_delay.delay_s - 0.002) < 3 * with_delay.delay_s_u
    assert abs(with_delay.natural_frequency_hz - FN) < 3 * with_delay.natural_frequency_hz_u
    without = analyse(caps)
    assert any("does not fit" in w and "--delay" in w for w in without.warnings)
    # the default skew bound (one sample interval) widens u(fn); a fitted delay takes it up
    plain, skewed = analyse(caps[:], channel_skew_s=0.0), analyse(caps, channel_skew_s=None)
    assert skewed.natural_frequency_hz_u > plain.natural_frequency_hz_u
    assert skewed.phase_deg_u[-1] > plain.phase_deg_u[-1]


def test_phase_uncertainty_of_the_sine_fit_matches_its_spread():
    rng = np.random.default_rng(3)
    t = np.arange(400) / 400.0
    phases, u = [], []
    for _ in range(150):
        fit = fit_sine_4p(t, 2.0 * np.sin(2 * np.pi * 3.3 * t + 0.7) + rng.normal(0, 0.5, t.size))
        phases.append(fit.phases_rad[0])
        u.append(fit.phases_u_rad[0])
    assert 0.8 < np.std(phases) / np.mean(u) < 1.2


# ------------------------------------------------------------------------------------ refusals
def test_refuses_fewer_frequencies_than_parameters():
    caps = sweep(frequencies=(2.0, 6.0))
    with pytest.raises(CaptureError, match=r"2 captures .* 3 parameters"):
        analyse(caps, delay=True)
    with pytest.raises(CaptureError, match=r"1 capture .* 2 parameters"):
        analyse(caps[:1])


def test_refuses_repeated_frequencies():
    caps = sweep(frequencies=(2.0, 6.0, 2.0))
    with pytest.raises(CaptureError, match="capture 1 and capture 3 are at the same frequency"):
        analyse(caps)


def test_refuses_a_dut_rate_that_is_not_sinusoidal():
    caps = sweep(frequencies=(2.0, 6.0, 10.0))
    distorted = dict(caps[1].columns)
    distorted["rate_deg_s"] = np.sign(distorted["rate_deg_s"]) * 20.0  # a square wave
    with pytest.raises(CaptureError, match=r"capture 2: .*not sinusoidal.*THD"):
        calibrate_frequency_response([caps[0].columns, distorted, caps[2].columns], lines=3600)
    # long record: the harmonics stay small (THD a few %) while the noise exceeds the sine
    c = simulate_gyro_sine(1.0, noise_deg_s=0.0).columns
    rng = np.random.default_rng(1)
    rate = c["rate_deg_s"] / 30.0 + rng.normal(0, 2.0, c["time_s"].size)
    with pytest.raises(CaptureError, match=r"not sinusoidal.*residual .* exceeds the sine"):
        response_at_frequency(c["time_s"], rate, a=c["a"], b=c["b"], lines=3600)
    with pytest.raises(CaptureError, match="shows no sine"):
        response_at_frequency(
            c["time_s"], rng.normal(0, 1.0, rate.size), a=c["a"], b=c["b"], lines=3600
        )


def test_refuses_reference_and_dut_of_different_lengths():
    cap = simulate_gyro_sine(4.0, reference="angle")
    c = cap.columns
    with pytest.raises(CaptureError, match="same length"):
        response_at_frequency(c["time_s"], c["rate_deg_s"], angle_deg=c["angle_deg"][:-5])
    enc = simulate_gyro_sine(4.0).columns
    with pytest.raises(CaptureError, match="same length"):
        response_at_frequency(
            enc["time_s"], enc["rate_deg_s"], a=enc["a"][1:], b=enc["b"][1:], lines=3600
        )
    with pytest.raises(CaptureError, match="sampled together"):
        response_at_frequency(c["time_s"][:-1], c["rate_deg_s"], angle_deg=c["angle_deg"])


def test_refuses_a_dut_in_antiphase_and_a_capture_without_reference():
    caps = sweep(frequencies=(2.0, 6.0, 10.0), reference="angle")
    flipped = [dict(c.columns, rate_deg_s=-c.columns["rate_deg_s"]) for c in caps]
    with pytest.raises(CaptureError, match="antiphase"):
        calibrate_frequency_response(flipped)
    bare = {k: v for k, v in caps[0].columns.items() if k != "angle_deg"}
    with pytest.raises(CaptureError, match="no reference"):
        calibrate_frequency_response([bare, *(c.columns for c in caps[1:])])


def test_a_stated_timebase_error_corrects_the_frequencies_and_widens_fn():
    from rotacal.uncertainty.specs import load_specs

    e = 2e-3  # a clock 0.2 % fast stamps every interval 0.2 % long
    caps = sweep(reference="angle", frequencies=(1.0, 4.0, 8.0, 12.0))
    slow = [dict(c.columns, time_s=c.columns["time_s"] * (1 + e)) for c in caps]
    plain = calibrate_frequency_response(slow, channel_skew_s=0.0)
    # unstated, the clock makes the table's rate 0.2 % slow against the DUT's: no unit-gain fit
    assert any("does not fit" in w for w in plain.warnings)
    specs = load_specs(
        {"timebase": {"relative_error": {"distribution": "normal", "value": e, "u": 1e-4}}}
    )
    r = calibrate_frequency_response(slow, channel_skew_s=0.0, specs=specs)
    np.testing.assert_allclose(r.frequency_hz, [1.0, 4.0, 8.0, 12.0], rtol=1e-5)
    assert r.warnings == ()
    h = np.abs(h_closed_form(np.array(r.frequency_hz)))
    assert np.all(np.abs(np.array(r.amplitude_ratio) - h) < 3 * np.array(r.amplitude_ratio_u))
    for key in ("natural_frequency_hz", "damping_ratio", "bandwidth_hz"):
        assert abs(getattr(r, key) - caps[0].truth[key]) < 3 * getattr(r, f"{key}_u"), key
    # the timebase's u reaches fn (scaled with every frequency) and each point's ratio
    assert r.natural_frequency_hz_u > FN * 1e-4
    assert min(r.amplitude_ratio_u) > 1e-4 * min(r.amplitude_ratio)
