"""Tests of rotacal.signal.sinefit against closed forms and independent solvers."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from scipy.optimize import least_squares

from rotacal.errors import CaptureError, ConfigError
from rotacal.signal import (
    HarmonicFitAccumulator,
    SineFit,
    displacement_amplitudes_from_rate,
    estimate_frequency,
    fit_harmonics,
    fit_sine_3p,
    fit_sine_4p,
    snr_db,
    thd_percent,
)

TWO_PI = 2.0 * math.pi


def multisine(t, f, amps, phases, offset=0.0):
    """Closed-form truth: offset + Σ A_h sin(2π h f t + φ_h) (phases at t = 0)."""
    y = np.full(np.shape(t), offset, dtype=float)
    for h, (a, p) in enumerate(zip(amps, phases, strict=True), start=1):
        y = y + a * np.sin(TWO_PI * h * f * t + p)
    return y


def phases_at(fit, f, phases0):
    """Truth phases moved from t = 0 to the fit's t_ref."""
    h = np.arange(1, len(phases0) + 1)
    return np.asarray(phases0) + TWO_PI * h * f * fit.t_ref_s


def wrap(x):
    return np.angle(np.exp(1j * np.asarray(x)))


AMPS = np.array([1.3, 0.11, 0.05, 0.021, 0.013, 0.008, 0.006, 0.004, 0.003, 0.002])
PHASES = np.array([0.3, -1.2, 2.0, 0.7, -2.5, 1.1, -0.4, 2.9, -1.9, 0.05])


# ------------------------------------------------------------------------- clean signals
@pytest.mark.parametrize("method", ["direct", "blocks"])
def test_multiharmonic_clean_recovers_truth(method):
    f = 0.7315
    t = np.linspace(0.37, 0.37 + 13.77 / f, 60_000)  # non-integer number of periods
    y = multisine(t, f, AMPS, PHASES, offset=-0.42)
    fit = fit_harmonics(t, y, harmonics=10, method=method)
    assert abs(fit.frequency_hz / f - 1) < 1e-10
    np.testing.assert_allclose(fit.amplitudes, AMPS, rtol=1e-9)
    assert np.max(np.abs(wrap(fit.phases_rad - phases_at(fit, f, PHASES)))) < 1e-8
    assert abs(fit.offset + 0.42) < 1e-10
    np.testing.assert_allclose(fit.cos_coefs, fit.amplitudes * np.sin(fit.phases_rad), atol=1e-15)
    assert fit.n_samples == t.size
    assert fit.iterations >= 1
    tt = np.linspace(1.0, 9.0, 777)
    np.testing.assert_allclose(fit.evaluate(tt), multisine(tt, f, AMPS, PHASES, -0.42), atol=1e-9)


def test_evaluate_derivative_matches_closed_form():
    f = 2.1
    t = np.linspace(0.0, 5.3, 4000)
    amps, ph = AMPS[:4], PHASES[:4]
    fit = fit_harmonics(t, multisine(t, f, amps, ph, 3.0), harmonics=4)
    tt = np.linspace(0.2, 5.0, 301)
    h = np.arange(1, 5)
    truth = sum(
        TWO_PI * hh * f * a * np.cos(TWO_PI * hh * f * tt + p)
        for hh, a, p in zip(h, amps, ph, strict=True)
    )
    np.testing.assert_allclose(fit.evaluate_derivative(tt), truth, atol=1e-8)
    assert fit.evaluate(np.float64(1.0)).shape == ()


@pytest.mark.parametrize("method", ["direct", "blocks"])
def test_jittered_time_stamps(method):
    rng = np.random.default_rng(7)
    f = 1.37
    n = 80_000
    dt = 7.3 / f / n
    t = np.arange(n) * dt + rng.uniform(-0.3, 0.3, n) * dt + 12.5
    y = multisine(t, f, AMPS[:5], PHASES[:5], offset=0.8)
    fit = fit_harmonics(t, y, harmonics=5, method=method)
    assert abs(fit.frequency_hz / f - 1) < 1e-10
    np.testing.assert_allclose(fit.amplitudes, AMPS[:5], rtol=1e-9)
    assert np.max(np.abs(wrap(fit.phases_rad - phases_at(fit, f, PHASES[:5])))) < 1e-8


@pytest.mark.parametrize("method", ["direct", "blocks"])
def test_large_offset_small_amplitude(method):
    f = 3.3
    t = np.linspace(0.0, 11.4 / f, 100_000)
    y = multisine(t, f, [1e-3, 2e-5], [0.4, 1.0], offset=1e4)
    fit = fit_harmonics(t, y, harmonics=2, method=method)
    np.testing.assert_allclose(fit.amplitudes, [1e-3, 2e-5], rtol=1e-9)
    assert abs(fit.frequency_hz / f - 1) < 1e-10
    assert abs(fit.offset - 1e4) < 1e-10
    fit3 = fit_sine_3p(t, y - 2e-5 * np.sin(TWO_PI * 2 * f * t + 1.0), f, method=method)
    assert abs(fit3.amplitudes[0] / 1e-3 - 1) < 1e-9


def test_blocks_equal_direct_with_noise():
    rng = np.random.default_rng(3)
    f = 0.91
    t = np.linspace(0.0, 6.6 / f, 60_000)
    y = multisine(t, f, AMPS[:6], PHASES[:6], 0.1) + 0.01 * rng.standard_normal(t.size)
    a = fit_harmonics(t, y, harmonics=6, method="direct")
    b = fit_harmonics(t, y, harmonics=6, method="blocks")
    assert abs(a.frequency_hz / b.frequency_hz - 1) < 1e-12
    np.testing.assert_allclose(b.amplitudes, a.amplitudes, rtol=1e-9, atol=1e-13)
    np.testing.assert_allclose(b.amplitudes_u, a.amplitudes_u, rtol=1e-5)
    assert b.frequency_u_hz == pytest.approx(a.frequency_u_hz, rel=1e-5)
    assert b.residual_rms == pytest.approx(a.residual_rms, rel=1e-6)


@pytest.mark.parametrize("drift_check", [False, True])
def test_blocks_give_the_residual_of_a_nearly_noise_free_record(drift_check):
    """Noise 1e-9 of a unit sine: yᵀy − bᵀp cannot resolve a residual 2e-18 of yᵀy, so the
    in-memory block fit sums it from the samples — the rms is the noise's, not 0, and so are
    the uncertainties that scale with it (the chunked accumulator, without the samples, cannot)."""
    rng = np.random.default_rng(8)
    f = 2.0
    t = np.arange(40_000) / 2000.0
    noise = 1e-9 * rng.standard_normal(t.size)
    y = multisine(t, f, AMPS[:4], PHASES[:4], 0.2) + noise
    a = fit_harmonics(t, y, harmonics=4, method="direct", drift_check=drift_check)
    b = fit_harmonics(t, y, harmonics=4, method="blocks", drift_check=drift_check)
    assert b.residual_rms == pytest.approx(1e-9, rel=0.03)
    assert b.residual_rms == pytest.approx(a.residual_rms, rel=1e-3)
    np.testing.assert_allclose(b.amplitudes_u, a.amplitudes_u, rtol=1e-3)
    assert b.frequency_u_hz == pytest.approx(a.frequency_u_hz, rel=1e-3)
    if drift_check:
        assert b.drift_check.residual_rms == pytest.approx(a.drift_check.residual_rms, rel=1e-3)
    acc = HarmonicFitAccumulator(f, harmonics=4)
    acc.add(t, y)
    # without the samples the residual is rounding (√eps of yᵀy/N either way), not the noise:
    # why the in-memory fit sums it from the samples
    assert not 0.5e-9 < acc.fit(harmonics=4).residual_rms < 2e-9


# ------------------------------------------------------------------------- independent solvers
def test_three_parameter_fit_equals_explicit_lstsq():
    rng = np.random.default_rng(11)
    f = 5.0
    t = np.sort(rng.uniform(0.0, 1.7, 3000))
    y = 0.2 + 0.9 * np.sin(TWO_PI * f * t + 0.3) + 0.05 * rng.standard_normal(t.size)
    fit = fit_sine_3p(t, y, f)
    tau = t - fit.t_ref_s
    design = np.column_stack([np.ones_like(t), np.cos(TWO_PI * f * tau), np.sin(TWO_PI * f * tau)])
    coef, *_ = np.linalg.lstsq(design, y, rcond=None)
    np.testing.assert_allclose([fit.offset, fit.cos_coefs[0], fit.sin_coefs[0]], coef, rtol=1e-10)
    assert fit.frequency_u_hz == 0.0
    assert fit.iterations == 0
    fitb = fit_sine_3p(t, y, f, method="blocks")
    np.testing.assert_allclose(
        [fitb.offset, fitb.cos_coefs[0], fitb.sin_coefs[0]], coef, rtol=1e-9, atol=1e-12
    )
    # covariance of the linear LS: s²(AᵀA)⁻¹
    r = y - design @ coef
    cov = (r @ r) / (t.size - 3) * np.linalg.inv(design.T @ design)
    a, b = coef[1], coef[2]
    amp = math.hypot(a, b)
    u = math.sqrt(a * a * cov[1, 1] + b * b * cov[2, 2] + 2 * a * b * cov[1, 2]) / amp
    assert fit.amplitudes_u[0] == pytest.approx(u, rel=1e-8)


@pytest.mark.parametrize("method", ["direct", "blocks"])
def test_nonlinear_fit_equals_scipy_least_squares(method):
    rng = np.random.default_rng(5)
    f = 1.9
    n = 2500
    t = np.sort(rng.uniform(0.0, 4.4 / f, n))
    amps, ph = [1.0, 0.2, 0.07], [0.5, -0.8, 2.2]
    y = multisine(t, f, amps, ph, 0.3) + 0.02 * rng.standard_normal(n)
    fit = fit_harmonics(t, y, harmonics=3, method=method)
    t_ref = fit.t_ref_s

    def resid(p):
        c, ff = p[0], p[-1]
        a, b = p[1:4], p[4:7]
        tau = t - t_ref
        m = c + sum(
            a[k] * np.cos(TWO_PI * (k + 1) * ff * tau) + b[k] * np.sin(TWO_PI * (k + 1) * ff * tau)
            for k in range(3)
        )
        return y - m

    p0 = np.r_[0.0, np.zeros(3), np.ones(3) * 0.1, f * 1.003]
    sol = least_squares(resid, p0, xtol=1e-15, ftol=1e-15, gtol=1e-15, x_scale="jac")
    assert abs(fit.frequency_hz / sol.x[-1] - 1) < 1e-10
    np.testing.assert_allclose(fit.cos_coefs, sol.x[1:4], atol=1e-8)
    np.testing.assert_allclose(fit.sin_coefs, sol.x[4:7], atol=1e-8)
    assert fit.offset == pytest.approx(sol.x[0], abs=1e-9)
    # uncertainty of f from the Jacobian at scipy's solution
    jac = sol.jac
    s2 = 2 * sol.cost / (n - 8)
    u_f = math.sqrt(s2 * np.linalg.inv(jac.T @ jac)[-1, -1])
    assert fit.frequency_u_hz == pytest.approx(u_f, rel=1e-4)


# ------------------------------------------------------------------------- honest uncertainty
@pytest.mark.parametrize("method", ["direct", "blocks"])
def test_amplitude_uncertainty_matches_scatter(method):
    f = 0.8
    n = 12_000 if method == "blocks" else 3000
    t = np.linspace(0.0, 2.3 / f, n)
    clean = multisine(t, f, [1.0, 0.1], [0.2, 1.0], 0.5)
    sigma = 0.05
    a1, a2, ff, u1, u2, uf = [], [], [], [], [], []
    for seed in range(120):
        rng = np.random.default_rng(seed)
        fit = fit_harmonics(
            t, clean + sigma * rng.standard_normal(n), 0.8, harmonics=2, method=method
        )
        a1.append(fit.amplitudes[0])
        a2.append(fit.amplitudes[1])
        ff.append(fit.frequency_hz)
        u1.append(fit.amplitudes_u[0])
        u2.append(fit.amplitudes_u[1])
        uf.append(fit.frequency_u_hz)
    for val, unc in ((a1, u1), (a2, u2), (ff, uf)):
        ratio = np.std(val, ddof=1) / np.mean(unc)
        assert 0.75 < ratio < 1.3, ratio


# ------------------------------------------------------------------------- THD, SNR, eq. (14)
def test_thd_closed_form():
    assert thd_percent([2.0, 0.06, 0.08]) == pytest.approx(5.0, rel=1e-14)
    assert thd_percent([2.0, 0.06, 0.08], harmonics=2) == pytest.approx(3.0, rel=1e-14)
    assert thd_percent([1.0]) == 0.0
    f = 0.5
    t = np.linspace(0.0, 10.25 / f, 20_000)
    amps = [5.0, 0.01, 0.004, 0.003]
    fit = fit_harmonics(t, multisine(t, f, amps, [0, 1, 2, 3]), harmonics=4)
    truth = 100 * math.sqrt(0.01**2 + 0.004**2 + 0.003**2) / 5.0
    assert thd_percent(fit) == pytest.approx(truth, rel=1e-8)
    assert thd_percent(fit.amplitudes) == pytest.approx(truth, rel=1e-8)


def test_thd_of_displacement_from_rate_fit_eq14():
    # θ(t) = Σ A_h sin(2πhft + φ_h) deg  ⇒  rate = Σ 2πhf·A_h cos(2πhft + φ_h) deg/s
    f = 3.0
    amps = np.array([0.25, 0.004, 0.0025, 0.001])
    ph = np.array([0.1, 0.9, -1.4, 2.6])
    t = np.linspace(0.0, 8.6 / f, 30_000)
    h = np.arange(1, 5)
    rate = 0.7 + sum(
        TWO_PI * hh * f * a * np.cos(TWO_PI * hh * f * t + p)
        for hh, a, p in zip(h, amps, ph, strict=True)
    )
    disp = multisine(t, f, amps, ph, 0.0)
    fit_rate = fit_harmonics(t, rate, harmonics=4)
    fit_disp = fit_harmonics(t, disp, harmonics=4)
    disp_amps = displacement_amplitudes_from_rate(fit_rate.amplitudes, fit_rate.frequency_hz)
    np.testing.assert_allclose(disp_amps, amps, rtol=1e-9)
    assert thd_percent(disp_amps) == pytest.approx(thd_percent(fit_disp), rel=1e-8)
    truth = 100 * math.sqrt(np.sum(amps[1:] ** 2)) / amps[0]
    assert thd_percent(disp_amps) == pytest.approx(truth, rel=1e-8)
    # the rate THD is larger: harmonics weighted by h
    assert thd_percent(fit_rate) > thd_percent(disp_amps)


def test_snr_db_against_known_noise():
    rng = np.random.default_rng(1)
    f = 2.0
    t = np.linspace(0.0, 20.3, 200_000)
    amps = [1.0, 0.3]
    sigma = 0.4
    y = multisine(t, f, amps, [0.0, 1.0], 5.0) + sigma * rng.standard_normal(t.size)
    fit = fit_harmonics(t, y, harmonics=2)
    truth = 10 * math.log10((1.0**2 + 0.3**2) / 2 / sigma**2)
    assert snr_db(y, fit, t) == pytest.approx(truth, abs=0.03)
    clean = multisine(t, f, amps, [0.0, 1.0], 5.0)
    assert snr_db(clean, fit_harmonics(t, clean, harmonics=2), t) > 150


# ------------------------------------------------------------------------- 4-parameter fit
@pytest.mark.parametrize("periods", [1.2, 100.0])
@pytest.mark.parametrize("method", ["direct", "blocks"])
def test_four_parameter_converges_from_fft_start(periods, method):
    f = 13.7
    n = 4000 if method == "direct" else 60_000
    t = np.linspace(0.01, 0.01 + periods / f, n)
    y = 0.4 + 2.0 * np.sin(TWO_PI * f * t + 2.2)
    f_start = estimate_frequency(t, y)
    assert abs(f_start / f - 1) < 0.1 / periods
    fit = fit_sine_4p(t, y, method=method)
    assert abs(fit.frequency_hz / f - 1) < 1e-10
    assert abs(fit.amplitudes[0] / 2.0 - 1) < 1e-9
    assert abs(wrap(fit.phases_rad[0] - (2.2 + TWO_PI * f * fit.t_ref_s))) < 1e-8
    assert fit.frequency_u_hz >= 0.0


def test_estimate_frequency_fast_signal_long_record():
    f = 1234.5
    t = np.arange(1_000_000) / 50_000.0  # 24690 periods, 40.5 samples per period
    y = np.cos(TWO_PI * f * t) + 0.1 * np.cos(TWO_PI * 2 * f * t)
    assert abs(estimate_frequency(t, y) / f - 1) < 1e-6
    fit = fit_harmonics(t, y, harmonics=2)
    assert abs(fit.frequency_hz / f - 1) < 1e-12
    np.testing.assert_allclose(fit.amplitudes, [1.0, 0.1], rtol=1e-9)


def test_estimate_frequency_of_more_periods_than_its_transform_takes():
    # 1.1·10⁶ samples, 20 a period: the start value comes from the first 2^20 (52,000 periods);
    # truth: the frequency put in, to within 0.01 bin of the whole record
    rng = np.random.default_rng(3)
    n, fs = 1_100_000, 50_000.0
    f = fs / 20.0 * (1 + 0.3 / 55_000)
    t = np.arange(n) / fs
    y = np.cos(TWO_PI * f * t) + 0.1 * np.cos(TWO_PI * 3 * f * t) + 0.01 * rng.standard_normal(n)
    assert abs(estimate_frequency(t, y) - f) * (n / fs) < 0.01
    fit = fit_harmonics(t, y, harmonics=3)
    assert abs(fit.frequency_hz - f) < 5 * fit.frequency_u_hz
    np.testing.assert_allclose(fit.amplitudes, [1.0, 0.0, 0.1], atol=1e-4)


# ------------------------------------------------------------------------- chunked accumulation
def test_accumulator_chunks_equal_one_shot():
    rng = np.random.default_rng(9)
    f = 0.37
    t = 100.0 + np.arange(300_000) * 1e-4  # 11.1 periods
    y = multisine(t, f, AMPS[:8], PHASES[:8], 2.0) + 1e-3 * rng.standard_normal(t.size)
    ref = fit_harmonics(t, y, harmonics=8, method="blocks")
    cuts = np.sort(rng.choice(np.arange(1, t.size), size=12, replace=False))
    acc = HarmonicFitAccumulator(frequency_hz=0.37, harmonics=8)
    for tc, yc in zip(np.split(t, cuts), np.split(y, cuts), strict=True):
        acc.add(tc, yc)
    fit = acc.fit(harmonics=8)
    assert acc.n_samples == t.size
    assert abs(fit.frequency_hz / ref.frequency_hz - 1) < 1e-13
    np.testing.assert_allclose(fit.amplitudes, ref.amplitudes, rtol=1e-10)
    # independent check: explicit design matrix at the fitted frequency
    tau = t[::7] - fit.t_ref_s
    ang = np.outer(TWO_PI * fit.frequency_hz * tau, np.arange(1, 9))
    design = np.hstack([np.ones((tau.size, 1)), np.cos(ang), np.sin(ang)])
    coef, *_ = np.linalg.lstsq(design, y[::7], rcond=None)
    np.testing.assert_allclose(fit.cos_coefs, coef[1:9], atol=5e-5)


def test_accumulator_without_hint_and_nonuniform_chunks():
    rng = np.random.default_rng(4)
    f = 1.1
    n = 200_000
    t = np.cumsum(rng.uniform(0.5, 1.5, n)) * (9.3 / f / n)
    y = multisine(t, f, AMPS[:3], PHASES[:3], -1.0)
    acc = HarmonicFitAccumulator(harmonics=3)
    for tc, yc in zip(np.array_split(t, 5), np.array_split(y, 5), strict=True):
        acc.add(tc, yc)
    assert acc.block_samples > 1
    fit = acc.fit()
    assert abs(fit.frequency_hz / f - 1) < 1e-10
    np.testing.assert_allclose(fit.amplitudes, AMPS[:3], rtol=1e-9)


def test_accumulator_explicit_mode_for_coarse_sampling():
    f = 10.0
    t = np.arange(3000) / 150.0  # 15 samples per period: no compression possible
    y = multisine(t, f, [1.0, 0.05, 0.02], [0.0, 0.5, 1.0], 0.1)
    acc = HarmonicFitAccumulator(frequency_hz=f, harmonics=3)
    acc.add(t[:1000], y[:1000])
    acc.add(t[1000:], y[1000:])
    assert acc.block_samples == 1
    fit = acc.fit(harmonics=3)
    np.testing.assert_allclose(fit.amplitudes, [1.0, 0.05, 0.02], rtol=1e-9)
    assert abs(fit.frequency_hz / f - 1) < 1e-11


def test_result_to_dict_is_json():
    t = np.linspace(0, 3, 3000)
    fit = fit_sine_4p(t, np.sin(TWO_PI * 1.3 * t))
    assert isinstance(fit, SineFit)
    d = json.loads(json.dumps(fit.to_dict()))
    assert d["frequency_hz"] == pytest.approx(1.3, rel=1e-12)
    assert len(d["amplitudes"]) == 1


# ------------------------------------------------------------------------- errors
def _sine(n=1000, periods=3.0):
    t = np.linspace(0.0, periods, n)
    return t, np.sin(TWO_PI * t)


def test_nan_in_y_or_t_raises_capture_error():
    t, y = _sine()
    y[17] = np.nan
    with pytest.raises(CaptureError, match=r"y contains NaN.*index 17"):
        fit_harmonics(t, y, harmonics=2)
    t, y = _sine()
    t[5] = np.nan
    with pytest.raises(CaptureError, match="t contains NaN"):
        fit_sine_4p(t, y)
    t, y = _sine(300_000, 5.0)
    y[250_000] = np.inf
    acc = HarmonicFitAccumulator(frequency_hz=1.0, harmonics=2)
    with pytest.raises(CaptureError, match="y contains NaN or inf"):
        acc.add(t, y)


def test_time_not_increasing_raises():
    t, y = _sine()
    t[10], t[11] = t[11], t[10]
    with pytest.raises(CaptureError, match="increase strictly"):
        fit_harmonics(t, y, harmonics=2)
    t, y = _sine()
    acc = HarmonicFitAccumulator(frequency_hz=1.0)
    acc.add(t[500:], y[500:])
    with pytest.raises(CaptureError, match="across chunks"):
        acc.add(t[:500], y[:500])


def test_too_short_records_raise():
    t = np.linspace(0.0, 0.6, 500)
    with pytest.raises(CaptureError, match="period"):
        fit_sine_3p(t, np.sin(TWO_PI * t), 1.0)
    t = np.linspace(0.0, 3.0, 4)
    with pytest.raises(CaptureError, match="fewer than"):
        fit_sine_4p(t, np.sin(TWO_PI * t / 3), 1.0 / 3)
    t = np.linspace(0.0, 3.0, 40)
    with pytest.raises(CaptureError, match="fewer than"):
        fit_harmonics(t, np.sin(TWO_PI * t), 1.0, harmonics=20)
    t = np.linspace(0.0, 10.0, 100_000)
    y = np.sin(TWO_PI * 0.5 * t)
    with pytest.raises(CaptureError, match="period"):
        estimate_frequency(t[:3000], y[:3000])
    with pytest.raises(CaptureError, match="pass frequency_hz"):
        HarmonicFitAccumulator().add(t[:3000], y[:3000])
    with pytest.raises(CaptureError, match="no samples"):
        HarmonicFitAccumulator(frequency_hz=1.0).fit()


def test_bad_settings_raise_config_error():
    t, y = _sine()
    with pytest.raises(ConfigError, match="harmonics"):
        fit_harmonics(t, y, harmonics=0)
    with pytest.raises(ConfigError, match="harmonics"):
        HarmonicFitAccumulator(harmonics=0)
    with pytest.raises(ConfigError, match="Nyquist"):
        fit_harmonics(t, y, 1.0, harmonics=200)
    with pytest.raises(ConfigError, match="frequency_hz"):
        fit_sine_3p(t, y, -1.0)
    with pytest.raises(ConfigError):
        thd_percent([1.0, 0.1], harmonics=0)
    with pytest.raises(CaptureError, match="A_1"):
        thd_percent([0.0, 0.1])


def test_thd_uncertainty_matches_monte_carlo_of_the_formula():
    """First-order u(THD) against the spread of eq. (1) over sampled amplitudes (independent)."""
    from rotacal.signal import thd_standard_uncertainty_percent

    a = np.array([1.0, 0.02, 0.04, 0.01])
    u = np.array([1e-3, 1e-3, 2e-3, 1e-3])
    rng = np.random.default_rng(0)
    draws = a + u * rng.standard_normal((200_000, a.size))
    thd = 100 * np.sqrt(np.sum(draws[:, 1:] ** 2, axis=1)) / draws[:, 0]
    assert thd_standard_uncertainty_percent(a, u) == pytest.approx(np.std(thd), rel=0.03)
