"""The multi-harmonic fit with a linear drift term, against explicit least squares and closed forms."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.optimize import minimize_scalar

from rotacal.signal import HarmonicFitAccumulator, fit_harmonics, snr_db

TWO_PI = 2.0 * math.pi
AMPS = np.array([1.3, 0.11, 0.05, 0.021, 0.013])
PHASES = np.array([0.3, -1.2, 2.0, 0.7, -2.5])


def signal(t, f, drift, offset=0.25):
    """Closed-form truth: offset + drift·t + Σ A_h sin(2π h f t + φ_h)."""
    y = offset + drift * t
    for h, (a, p) in enumerate(zip(AMPS, PHASES, strict=True), start=1):
        y = y + a * np.sin(TWO_PI * h * f * t + p)
    return y


def explicit(t, y, f, t_ref, nh, drift=True):
    """Least squares with the explicit design matrix at a fixed f: (params, rss)."""
    tau = t - t_ref
    h = np.arange(1, nh + 1)
    cols = [
        np.ones_like(t),
        np.cos(TWO_PI * f * np.outer(tau, h)),
        np.sin(TWO_PI * f * np.outer(tau, h)),
    ]
    if drift:
        cols.append(tau[:, None])
    a = np.column_stack([c if c.ndim == 2 else c[:, None] for c in cols])
    p, *_ = np.linalg.lstsq(a, y, rcond=None)
    r = y - a @ p
    return p, float(r @ r)


def fit_by(method, t, y, f0, **kw):
    if method == "chunked":
        acc = HarmonicFitAccumulator(f0, harmonics=5)
        for s in range(0, t.size, 7_001):
            acc.add(t[s : s + 7_001], y[s : s + 7_001])
        return acc.fit(f0, 5, **kw)
    return fit_harmonics(t, y, f0, harmonics=5, method=method, **kw)


@pytest.mark.parametrize("method", ["direct", "blocks"])
def test_clean_signal_with_drift_recovers_truth(method):
    f = 0.7315
    t = np.linspace(0.37, 0.37 + 6.4 / f, 40_000)
    y = signal(t, f, drift=0.03)
    fit = fit_harmonics(t, y, f * 1.001, harmonics=5, method=method, drift=True)
    assert abs(fit.frequency_hz / f - 1) < 1e-10
    np.testing.assert_allclose(fit.amplitudes, AMPS, rtol=1e-8)
    assert fit.drift == pytest.approx(0.03, rel=1e-8)
    assert fit.offset == pytest.approx(0.25 + 0.03 * fit.t_ref_s, rel=1e-8)
    np.testing.assert_allclose(fit.evaluate(t), y, atol=1e-9)
    rate = 0.03 + sum(
        a * TWO_PI * h * f * np.cos(TWO_PI * h * f * t + p)
        for h, (a, p) in enumerate(zip(AMPS, PHASES, strict=True), start=1)
    )
    np.testing.assert_allclose(fit.evaluate_derivative(t), rate, atol=1e-7)
    assert fit.n_parameters == 2 * 5 + 3


@pytest.mark.parametrize("method", ["direct", "blocks", "chunked"])
def test_drift_fit_is_the_least_squares_minimum(method):
    rng = np.random.default_rng(5)
    f = 2.0
    t = np.arange(60_000) / 20_000.0
    y = signal(t, f, drift=-0.2) + rng.normal(0, 0.01, t.size)
    fit = fit_by(method, t, y, 1.998, drift=True)
    p, rss = explicit(t, y, fit.frequency_hz, fit.t_ref_s, 5)
    assert fit.drift == pytest.approx(p[-1], rel=1e-9)
    np.testing.assert_allclose(fit.cos_coefs, p[1:6], rtol=1e-8, atol=1e-12)
    np.testing.assert_allclose(fit.sin_coefs, p[6:11], rtol=1e-8, atol=1e-12)
    assert fit.residual_rms == pytest.approx(math.sqrt(rss / t.size), rel=1e-8)
    for df in (-1e-6, 1e-6):  # the refined frequency minimises the residual
        assert explicit(t, y, fit.frequency_hz + df, fit.t_ref_s, 5)[1] > rss


def test_drift_u_is_the_spread_of_the_estimate():
    f = 3.0
    t = np.arange(1_500) / 500.0
    rng = np.random.default_rng(11)
    est, us = [], []
    for _ in range(300):
        y = signal(t, f, drift=0.05) + rng.normal(0, 0.02, t.size)
        fit = fit_harmonics(t, y, f, harmonics=5, drift=True, method="direct")
        est.append(fit.drift)
        us.append(fit.drift_u)
    spread = float(np.std(est, ddof=1))
    assert 0.85 < spread / float(np.mean(us)) < 1.15
    assert abs(float(np.mean(est)) - 0.05) < 4 * spread / math.sqrt(len(est))
    inside = np.abs(np.asarray(est) - 0.05) <= 2 * np.asarray(us)
    assert 0.9 < inside.mean() <= 1.0


@pytest.mark.parametrize("method", ["direct", "blocks"])
def test_drift_check_is_the_refit_with_drift_at_the_final_frequency(method):
    rng = np.random.default_rng(2)
    t = np.arange(80_000) / 40_000.0
    y = signal(t, 1.7, drift=0.01) + rng.normal(0, 1e-3, t.size)
    plain = fit_harmonics(t, y, 1.7, harmonics=5, method=method)
    fit = fit_harmonics(t, y, 1.7, harmonics=5, method=method, drift_check=True)
    # the fit itself is the fit without the check, to the last bit
    assert fit.frequency_hz == plain.frequency_hz and fit.offset == plain.offset
    assert np.array_equal(fit.amplitudes, plain.amplitudes)
    assert np.array_equal(fit.amplitudes_u, plain.amplitudes_u)
    assert plain.drift_check is None and fit.drift is None
    check = fit.drift_check
    assert check is not None
    p, rss = explicit(t, y, fit.frequency_hz, fit.t_ref_s, 5)
    assert check.drift == pytest.approx(p[-1], rel=1e-8)
    np.testing.assert_allclose(check.cos_coefs, p[1:6], rtol=1e-7, atol=1e-12)
    assert check.residual_rms == pytest.approx(math.sqrt(rss / t.size), rel=1e-7)
    # the drift the check sees is the one put in (its frequency is the drift-biased one)
    assert check.drift == pytest.approx(0.01, rel=0.05)


@pytest.mark.parametrize("method", ["direct", "blocks"])
def test_ramp_fitted_without_its_term_converges_to_the_residual_minimum(method):
    """A ramp 8 times the sine's amplitude, fitted without the linear term: Gauss–Newton circles
    the minimum of the large residual (it used to end in "did not converge"); the frequency it
    returns is the minimum found independently by a bounded scalar search."""
    t = np.arange(5_000) / 5_000.0
    y = (
        0.1 * np.sin(TWO_PI * 5 * t + 0.3)
        + 0.005 * np.sin(TWO_PI * 15 * t + 1.0)
        + 0.8 * t
        + np.random.default_rng(1).normal(0, 1e-4, t.size)
    )
    fit = fit_harmonics(t, y, 5.0, harmonics=10, method=method)
    t_ref = fit.t_ref_s
    best = minimize_scalar(
        lambda f: explicit(t, y, f, t_ref, 10, drift=False)[1],
        bounds=(4.98, 5.01),
        method="bounded",
        options={"xatol": 1e-9},
    )
    assert abs(fit.frequency_hz - best.x) < 2e-6
    assert explicit(t, y, fit.frequency_hz, t_ref, 10, drift=False)[1] <= best.fun * (1 + 1e-12)


def test_snr_of_a_fit_with_drift_leaves_the_drift_out():
    rng = np.random.default_rng(4)
    t = np.arange(40_000) / 2_000.0
    noise = rng.normal(0, 0.3, t.size)
    y = signal(t, 1.0, drift=0.1, offset=2.0) + noise
    fit = fit_harmonics(t, y, 1.0, harmonics=5, drift=True)
    want = 10 * math.log10(float(np.sum(AMPS**2) / 2) / float(np.mean(noise**2)))
    assert snr_db(y, fit, t) == pytest.approx(want, abs=0.02)
