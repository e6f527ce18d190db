"""The harmonic fit's Numba twins (block moments, residual sums) against NumPy and direct sums."""

from __future__ import annotations

import math

import numpy as np
import pytest

from rotacal import _jit
from rotacal.signal import fit_harmonics
from rotacal.signal._residual import residual_sums


def _direct_rss(t, y, t_ref, f, const, a, b, drift):
    """Σ (y − model)² with every cos(hωτ), sin(hωτ) evaluated directly (no recurrence)."""
    tau = t - t_ref
    model = const + drift * tau
    for h in range(1, a.size + 1):
        model = model + a[h - 1] * np.cos(h * 2 * math.pi * f * tau)
        model = model + b[h - 1] * np.sin(h * 2 * math.pi * f * tau)
    r = y - model
    return float(r @ r)


@pytest.mark.parametrize("jit", [False, True])
def test_residual_sums_match_a_direct_evaluation(jit):
    assert _jit.use_numba(1, jit) == jit  # Numba is a dependency: the twin under test runs
    rng = np.random.default_rng(7)
    t = np.arange(300_001) / 5000.0
    f = 1.37
    a = rng.normal(size=10) * np.logspace(0, -3, 10)
    b = rng.normal(size=10) * np.logspace(0, -3, 10)
    t_ref = 0.5 * (t[0] + t[-1])
    tau = t - t_ref
    clean = 0.25 + 0.01 * tau
    for h in range(1, 11):
        clean = clean + a[h - 1] * np.cos(h * 2 * math.pi * f * tau)
        clean = clean + b[h - 1] * np.sin(h * 2 * math.pi * f * tau)
    y = clean + 1e-6 * rng.standard_normal(t.size)
    models = [(0.25, a, b, 0.01), (0.2, a * 0.999, b, 0.0)]
    got = residual_sums(t, y, t_ref, f, models, jit=jit)
    want = [_direct_rss(t, y, t_ref, f, *m) for m in models]
    # the first model is the truth: its residual is the added noise
    assert got[0] == pytest.approx(t.size * 1e-12, rel=0.01)
    np.testing.assert_allclose(got, want, rtol=1e-9)


@pytest.mark.parametrize("jit", [False, True])
@pytest.mark.parametrize("jitter", [0.0, 1e-3])
def test_residual_sums_on_and_off_the_grid(jit, jitter, monkeypatch):
    # on a uniform grid the table path runs, with a jittered clock (δ far above its bound)
    # the per-sample path: either way the direct evaluation's sums
    from rotacal.signal import _residual

    f = 3.1
    rng, t, t_ref, a, b = _clocked_series(11, jitter, 8)
    y = _direct_model(t, t_ref, f, 0.1, a, b, -0.02) + 1e-6 * rng.standard_normal(t.size)
    models = [(0.1, a, b, -0.02), (0.1, a * 1.001, b, 0.0)]
    calls = []
    plain = _residual.grid_residual_sums
    monkeypatch.setattr(
        _residual, "grid_residual_sums", lambda *args: calls.append(1) or plain(*args)
    )
    got = residual_sums(t, y, t_ref, f, models, jit=jit)
    want = [_direct_rss(t, y, t_ref, f, *m) for m in models]
    np.testing.assert_allclose(got, want, rtol=1e-9)
    assert got[0] == pytest.approx(t.size * 1e-12, rel=0.02)  # the added noise
    if not jit:  # the NumPy path tried the grid and kept its sums only on the grid
        assert calls == [1]
        assert (plain(t, y, t_ref, 2 * math.pi * f, (t[-1] - t[0]) / (t.size - 1), 1e-9,
                      *_arrays(models)) is None) == (jitter > 0)  # fmt: skip


def _clocked_series(seed, jitter, nh):
    """rng, 70,001 times at 2 kHz (jittered by ``jitter`` of a step), their middle, and the
    cos/sin coefficients of ``nh`` harmonics falling from 1 to 1e-3."""
    rng = np.random.default_rng(seed)
    t = np.arange(70_001) / 2000.0
    t = t + jitter * rng.uniform(-0.5, 0.5, t.size) / 2000.0
    a = rng.normal(size=nh) * np.logspace(0, -3, nh)
    b = rng.normal(size=nh) * np.logspace(0, -3, nh)
    return rng, t, 0.5 * (t[0] + t[-1]), a, b


def _direct_model(t, t_ref, f, const, a, b, drift):
    tau = t - t_ref
    model = const + drift * tau
    for h in range(1, a.size + 1):
        model = model + a[h - 1] * np.cos(h * 2 * math.pi * f * tau)
        model = model + b[h - 1] * np.sin(h * 2 * math.pi * f * tau)
    return model


def _arrays(models):
    return (
        np.array([m[0] for m in models]),
        np.array([m[1] for m in models]),
        np.array([m[2] for m in models]),
        np.array([m[3] for m in models]),
    )


def test_the_fit_is_the_same_with_either_twin(monkeypatch):
    # a record so clean that the normal equations cannot resolve the residual: it is summed
    rng = np.random.default_rng(1)
    t = np.arange(400_000) / 20_000.0
    y = 0.5 * np.sin(2 * math.pi * 0.7 * t) + 0.005 * np.sin(2 * math.pi * 1.4 * t + 0.3)
    y += 2e-7 * rng.standard_normal(t.size) + 3e-4 * t
    monkeypatch.setenv("ROTACAL_NUMBA", "0")
    plain = fit_harmonics(t, y, 0.7, harmonics=10, drift_check=True)
    plain_d = fit_harmonics(t, y, 0.7, harmonics=10, drift=True)
    monkeypatch.delenv("ROTACAL_NUMBA")
    monkeypatch.setattr(_jit, "MIN_SAMPLES", 0)
    assert _jit.use_numba(t.size)
    fast = fit_harmonics(t, y, 0.7, harmonics=10, drift_check=True)
    fast_d = fit_harmonics(t, y, 0.7, harmonics=10, drift=True)
    assert fast.residual_rms == pytest.approx(plain.residual_rms, rel=1e-12)
    assert fast.drift_check is not None and plain.drift_check is not None
    assert fast.drift_check.residual_rms == pytest.approx(plain.drift_check.residual_rms, rel=1e-12)
    # the frequency's iteration ends on a tolerance far above rounding: both take the same steps
    assert fast.iterations == plain.iterations
    # the uncertainties come from (JᵀJ)⁻¹, whose conditioning (frequency column) amplifies the
    # moments' rounding to ~1e-11
    np.testing.assert_allclose(fast.amplitudes_u, plain.amplitudes_u, rtol=1e-10)
    assert fast_d.residual_rms == pytest.approx(plain_d.residual_rms, rel=1e-12)
    # truth: with the drift fitted, the residual is the added noise
    assert fast_d.residual_rms == pytest.approx(2e-7, rel=0.02)
    assert fast_d.drift == pytest.approx(3e-4, rel=1e-3)


def test_block_moments_of_a_fast_motion_match_with_either_twin(monkeypatch):
    # 40 Hz sampled at 50 kHz: blocks of a few dozen samples, thousands of them
    rng = np.random.default_rng(5)
    t = np.arange(500_000) / 50_000.0
    amp = (0.5, 0.01, 0.002)
    y = sum(a * np.sin(2 * math.pi * 40.0 * (h + 1) * t + h) for h, a in enumerate(amp))
    y = y + 1e-5 * rng.standard_normal(t.size)
    monkeypatch.setenv("ROTACAL_NUMBA", "0")
    plain = fit_harmonics(t, y, 40.0, harmonics=10)
    monkeypatch.delenv("ROTACAL_NUMBA")
    monkeypatch.setattr(_jit, "MIN_SAMPLES", 0)
    fast = fit_harmonics(t, y, 40.0, harmonics=10)
    assert fast.iterations == plain.iterations
    assert fast.frequency_hz == pytest.approx(plain.frequency_hz, rel=1e-12)
    # on the scale of the fundamental: harmonics 4..10 are noise of ~1e-8
    np.testing.assert_allclose(fast.amplitudes, plain.amplitudes, rtol=0, atol=1e-12 * amp[0])
    assert fast.residual_rms == pytest.approx(plain.residual_rms, rel=1e-12)
    # truth: the amplitudes put in, the noise as the residual
    np.testing.assert_allclose(fast.amplitudes[:3], amp, rtol=0, atol=3e-7)
    assert fast.residual_rms == pytest.approx(1e-5, rel=0.01)


@pytest.mark.parametrize("count", [2, 7, 1000, 25_001])
@pytest.mark.parametrize("turn", [(0.5, 3.0), (3.0, 5.6)])
def test_grid_power_sums_match_the_sums_over_the_blocks(count, turn):
    # the closed form (Dirichlet kernel and its derivatives) against the sum it replaces; up
    # to 5.6 rad per block of harmonic 20: what 28 moments allow (a one-shot fit's long blocks)
    from rotacal.signal._blocks_sums import grid_power_sums

    rng = np.random.default_rng(count)
    block_s = 0.013
    omega = rng.uniform(*turn) / (20 * block_s)
    d_first = -0.5 * count * block_s + rng.uniform(-0.3, 0.3) * block_s
    d = d_first + np.arange(count) * block_s
    got = grid_power_sums(omega, d[0], d[-1], block_s, count, 20, 3)
    for p in range(3):
        want = np.array([np.sum(d**p * np.exp(1j * k * omega * d)) for k in range(21)])
        scale = np.max(np.abs(d)) ** p * count
        np.testing.assert_allclose(got[:, p], want, rtol=0, atol=1e-12 * scale)


@pytest.mark.parametrize("jit", [False, True])
@pytest.mark.parametrize("jitter", [0.0, 1e-3])
def test_residual_tau_sums_match_a_direct_evaluation(jit, jitter):
    # Σ r² and Σ r·τ of one model, on the grid (table path) and off it (per-sample path)
    from rotacal.signal._residual import residual_tau_sums

    f = 2.3
    rng, t, t_ref, a, b = _clocked_series(5, jitter, 6)
    y = _direct_model(t, t_ref, f, 0.1, a, b, 0.0) + 1e-6 * rng.standard_normal(t.size)
    y += 1e-7 * (t - t_ref)  # a drift the model lacks: Σ r·τ far from 0
    model = (0.1, a, b, 0.0)
    r = y - _direct_model(t, t_ref, f, *model)
    rss, r_tau = residual_tau_sums(t, y, t_ref, f, model, jit=jit)
    assert rss == pytest.approx(float(r @ r), rel=1e-9)
    assert r_tau == pytest.approx(float(r @ (t - t_ref)), rel=1e-9)


@pytest.mark.parametrize("jit", [False, True])
@pytest.mark.parametrize("drift", [0.0, 3e-8, 2e-7, 1e-5])
def test_the_drift_checks_residual_is_its_own_residual(jit, drift, monkeypatch):
    # where the fit's residual is summed from the samples, the drift check's follows from the
    # fit's Σ r·τ (no drift; a drift that removes part of the residual) or is summed itself (a
    # drift that removes most of it; one the normal equations resolve): either way it is
    # Σ (y − check model)² summed directly
    rng = np.random.default_rng(3)
    t = np.arange(400_000) / 20_000.0
    y = 0.5 * np.sin(2 * math.pi * 0.7 * t) + 0.005 * np.sin(2 * math.pi * 1.4 * t + 0.3)
    y += 2e-7 * rng.standard_normal(t.size) + drift * (t - t.mean())
    if jit:
        monkeypatch.setattr(_jit, "MIN_SAMPLES", 0)
    else:
        monkeypatch.setenv("ROTACAL_NUMBA", "0")
    fit = fit_harmonics(t, y, 0.7, harmonics=10, drift_check=True)
    check = fit.drift_check
    assert check is not None
    want = _direct_rss(
        t, y, fit.t_ref_s, fit.frequency_hz, check.offset, check.cos_coefs, check.sin_coefs,
        check.drift,
    )  # fmt: skip
    assert check.residual_rms**2 * t.size == pytest.approx(want, rel=1e-9)
    assert check.residual_rms == pytest.approx(2e-7, rel=0.02)  # the added noise


@pytest.mark.parametrize("jitter", [0.0, 1e-3])
def test_residual_sums_split_over_two_threads_are_those_of_one(jitter, monkeypatch):
    """The NumPy grid path's two-thread split (long records) adds the same parts in the same
    order as one thread: the same bits; off the grid both give None."""
    from rotacal.signal import _residual

    f = 3.1
    rng, t, t_ref, a, b = _clocked_series(5, jitter, 8)
    y = _direct_model(t, t_ref, f, 0.1, a, b, -0.02) + 1e-6 * rng.standard_normal(t.size)
    args = (t, y, t_ref, 2 * math.pi * f, (t[-1] - t[0]) / (t.size - 1), 1e-9)
    models = _arrays([(0.1, a, b, -0.02), (0.1, a * 1.001, b, 0.0)])
    monkeypatch.setattr(_residual.os, "cpu_count", lambda: 2)
    monkeypatch.setattr(_residual, "_GRID_GROUP", 4)  # steps of 4096 samples: halves of 8 steps
    one = _residual.grid_residual_sums(*args, *models)
    monkeypatch.setattr(_residual, "SPLIT_SAMPLES", 1000)
    split = _residual.grid_residual_sums(*args, *models)
    assert (one is None) == (split is None) == (jitter > 0)
    assert split == one
