"""The block-moment exponential sums against sums over every sample, evaluated directly."""

from __future__ import annotations

import math

import numpy as np
import pytest

from rotacal.signal import HarmonicFitAccumulator, fit_harmonics


def _direct_sums(t, y, y0, t_ref, omega, nh):
    """S_p(k) = Σ τ^p e^{jkωτ}, Y_p(k) = Σ (y − y0)·τ^p e^{jkωτ}, each exponential by np.exp."""
    tau = t - t_ref
    e = np.exp(1j * omega * np.outer(tau, np.arange(2 * nh + 1)))
    yc = y - y0
    s = np.stack([(tau**p) @ e for p in range(3)])
    yv = np.stack([(yc * tau**p) @ e[:, : nh + 1] for p in range(2)])
    return s, yv


@pytest.mark.parametrize("chunks", ["one", "cut", "off grid"])
def test_block_sums_equal_the_sums_over_every_sample(chunks):
    rng = np.random.default_rng(3)
    n, fs, f, nh = 60_000, 10_000.0, 3.1, 6
    t = np.arange(n) / fs
    y = 0.3 + np.sin(2 * math.pi * f * t) + 1e-3 * rng.standard_normal(n)
    if chunks == "off grid":  # a second chunk whose stamps are off the first chunk's grid
        t[n // 2 :] += 0.37 / fs
    acc = HarmonicFitAccumulator(f, harmonics=nh)
    cuts = {"one": [n], "cut": [7_777, 20_001, n], "off grid": [n // 2, n]}[chunks]
    start = 0
    for stop in cuts:
        acc.add(t[start:stop], y[start:stop])
        start = stop
    assert 4 <= acc.block_samples < 4096  # compressed, with several blocks per period
    t_ref = 0.5 * (t[0] + t[-1])
    sums = acc._sums_fn(nh, t_ref)
    for omega in (2 * math.pi * f, 2 * math.pi * f * (1 + 3e-4)):
        s, yv = sums(omega, True)
        s_d, yv_d = _direct_sums(t, y, acc._y0, t_ref, omega, nh)
        for got, want in ((s, s_d), (yv, yv_d)):
            scale = np.abs(want).max(axis=1, keepdims=True)
            assert np.abs(got - want).max() <= 1e-11 * scale.max()
        s0, y0_only = sums(omega, False)
        # without the derivative: the same p = 0 sums (BLAS may add in another order)
        np.testing.assert_allclose(s0[0], s[0], rtol=0, atol=1e-13 * np.abs(s).max())
        np.testing.assert_allclose(y0_only[0], yv[0], rtol=0, atol=1e-13 * np.abs(yv).max())
        _check_without_y_derivative(sums, omega, s, yv)


def _check_without_y_derivative(sums, omega, s, yv):
    """A last step's sums (S with τ, y-sums without): the same S and p = 0 y-sums."""
    s_l, yv_l = sums(omega, True, False)
    assert s_l.shape == s.shape and yv_l.shape == (1, yv.shape[1])
    np.testing.assert_allclose(s_l, s, rtol=0, atol=1e-13 * np.abs(s).max())
    np.testing.assert_allclose(yv_l[0], yv[0], rtol=0, atol=1e-13 * np.abs(yv).max())


@pytest.mark.parametrize("periods", [30, 3000])
def test_block_fit_equals_the_direct_fit_at_many_periods(periods):
    # truth: the explicit design matrix solved by QR (the "direct" method), same samples
    rng = np.random.default_rng(periods)
    n = 60_000
    t = np.arange(n) / 50_000.0
    f = periods / (n / 50_000.0)
    y = 1.0 + 2.0 * np.sin(2 * math.pi * f * t + 0.4) + 0.03 * np.sin(4 * math.pi * f * t)
    y += 1e-3 * rng.standard_normal(n)
    blocks = fit_harmonics(t, y, f * (1 + 1e-6), harmonics=5, method="blocks")
    direct = fit_harmonics(t, y, f * (1 + 1e-6), harmonics=5, method="direct")
    assert blocks.frequency_hz == pytest.approx(direct.frequency_hz, rel=1e-13)
    np.testing.assert_allclose(blocks.amplitudes, direct.amplitudes, rtol=1e-9, atol=1e-13)
    assert blocks.amplitudes[0] == pytest.approx(2.0, rel=1e-4)


def test_moments_moved_to_a_file_give_the_sums_and_fit_held_in_memory(monkeypatch):
    # truth: the same accumulator with its moments in memory (checked against direct sums above)
    from rotacal.signal import _blocks_store

    rng = np.random.default_rng(5)
    n, fs, f, nh = 200_000, 10_000.0, 3.1, 4
    t = np.arange(n) / fs
    y = 0.3 + np.sin(2 * math.pi * f * t) + 0.02 * np.sin(4 * math.pi * f * t)
    y += 1e-3 * rng.standard_normal(n)

    def filled() -> HarmonicFitAccumulator:
        acc = HarmonicFitAccumulator(f, harmonics=nh)
        for start in range(0, n, 7_777):  # blocks cut by the chunks: records hold their halves
            acc.add(t[start : start + 7_777], y[start : start + 7_777])
        return acc

    held = filled()
    monkeypatch.setattr(_blocks_store, "KEEP_BYTES", 4096)
    monkeypatch.setattr(_blocks_store, "GROUP_ROWS", 37)
    spilled = filled()
    assert spilled._store.spilled and not held._store.spilled
    t_ref = 0.5 * (t[0] + t[-1])
    omega = 2 * math.pi * f * (1 + 1e-4)
    pairs = zip(
        spilled._sums_fn(nh, t_ref)(omega, True), held._sums_fn(nh, t_ref)(omega, True), strict=True
    )
    for got, want in pairs:
        assert np.abs(got - want).max() <= 1e-12 * np.abs(want).max()
    a, b = spilled.fit(f * (1 + 1e-5)), held.fit(f * (1 + 1e-5))
    assert a.frequency_hz == pytest.approx(b.frequency_hz, rel=1e-12)
    np.testing.assert_allclose(a.amplitudes, b.amplitudes, rtol=1e-10, atol=1e-13)
    assert spilled.estimate_frequency() == pytest.approx(held.estimate_frequency(), rel=1e-12)


def test_chunks_far_from_the_first_stay_on_the_sampling_grid():
    # stamps 10⁷ samples on are rounded at ~1e-13 s: still the grid (the fast path, no P rows)
    fs, f = 10_000.0, 0.5
    acc = HarmonicFitAccumulator(f, harmonics=10)
    for g0, m in ((0, 1 << 16), (10_000_000, 200_000)):
        t = np.arange(g0, g0 + m) / fs
        acc.add(t, np.sin(2 * math.pi * f * t))
    assert acc.block_samples > 4
    full_runs = [j.size for j, p, _ in acc._store.records() if p is None]
    assert sum(full_runs) >= (200_000 // acc.block_samples) - 1


def test_a_fast_signal_fits_with_longer_blocks_equal_to_the_direct_fit():
    # truth: the explicit design matrix solved by QR, same samples; 1500 samples a period make
    # 57-sample blocks with 22 moments, so the one-shot fit plans 28 (blocks 1.8x longer)
    from rotacal.signal._blocks import moments_for, sums_from_samples
    from rotacal.signal._blocks_sums import taylor_terms

    # the sums refuse a block phase that needs more than 28 terms: θ = 2x stays below 1.8π
    assert taylor_terms(0.9 * math.pi, 28) > 28
    rng = np.random.default_rng(11)
    n, fs = 60_000, 50_000.0
    f = fs / 1500.0
    t = np.arange(n) / fs
    y = 0.5 + 2.0 * np.sin(2 * math.pi * f * t + 0.4) + 0.02 * np.sin(6 * math.pi * f * t - 1.0)
    y += 1e-3 * rng.standard_normal(n)
    assert moments_for(f, 5, 1.0 / fs) == 28 and not sums_from_samples(f, 5, 1.0 / fs)
    assert moments_for(f / 20.0, 5, 1.0 / fs) == 22  # slow: long blocks with 22 already
    blocks = fit_harmonics(t, y, f * (1 + 1e-6), harmonics=5, method="blocks")
    direct = fit_harmonics(t, y, f * (1 + 1e-6), harmonics=5, method="direct")
    assert blocks.frequency_hz == pytest.approx(direct.frequency_hz, rel=1e-13)
    np.testing.assert_allclose(blocks.amplitudes, direct.amplitudes, rtol=1e-9, atol=1e-13)
    np.testing.assert_allclose(blocks.amplitudes_u, direct.amplitudes_u, rtol=1e-6)


@pytest.mark.parametrize("n", [200, 60_000, 60_123])
def test_sums_from_the_samples_equal_the_sums_over_every_sample(n):
    # a record held as it is (segments of 256 samples and a tail): the same sums as one by one
    from rotacal.signal._blocks_grid import grid_sums

    rng = np.random.default_rng(n)
    fs, f, nh = 10_000.0, 97.3, 6
    t = 2.5 + np.arange(n) / fs
    y = 0.3 + np.sin(2 * math.pi * f * t) + 1e-3 * rng.standard_normal(n)
    t_ref = 0.5 * (t[0] + t[-1])
    y0 = float(np.mean(y))
    sums = grid_sums(y, y0, t[0] - t_ref, 1.0 / fs, nh)
    for omega in (2 * math.pi * f, 2 * math.pi * f * (1 + 3e-4)):
        s, yv = sums(omega, True)
        s_d, yv_d = _direct_sums(t, y, y0, t_ref, omega, nh)
        for got, want in ((s, s_d), (yv, yv_d)):
            assert np.abs(got - want).max() <= 1e-11 * np.abs(want).max()
        s0, y0_only = sums(omega, False)
        np.testing.assert_allclose(s0[0], s[0], rtol=0, atol=1e-13 * np.abs(s).max())
        np.testing.assert_allclose(y0_only[0], yv[0], rtol=0, atol=1e-13 * np.abs(yv).max())
        _check_without_y_derivative(sums, omega, s, yv)


@pytest.mark.parametrize("drift", [False, True])
def test_a_fast_signal_fitted_from_its_samples_equals_the_direct_fit(drift):
    # truth: the explicit design matrix solved by QR, same samples; 100 samples a period (blocks
    # of 3 samples with 22 moments): the one-shot fit sums the samples at each frequency
    from rotacal.signal._blocks import sums_from_samples

    rng = np.random.default_rng(13)
    n, fs = 60_000, 50_000.0
    f = fs / 100.0
    t = np.arange(n) / fs
    y = 0.5 + 2.0 * np.sin(2 * math.pi * f * t + 0.4) + 0.02 * np.sin(6 * math.pi * f * t - 1.0)
    y += 1e-3 * rng.standard_normal(n) + 0.05 * t
    assert sums_from_samples(f, 5, 1.0 / fs)
    kw = {"harmonics": 5, "drift": drift, "drift_check": not drift}
    grid = fit_harmonics(t, y, f * (1 + 1e-6), method="blocks", **kw)
    direct = fit_harmonics(t, y, f * (1 + 1e-6), method="direct", **kw)
    assert grid.frequency_hz == pytest.approx(direct.frequency_hz, rel=1e-13)
    np.testing.assert_allclose(grid.amplitudes, direct.amplitudes, rtol=1e-9, atol=1e-13)
    np.testing.assert_allclose(grid.amplitudes_u, direct.amplitudes_u, rtol=1e-6)
    assert grid.residual_rms == pytest.approx(direct.residual_rms, rel=1e-9)
    if drift:
        assert grid.drift == pytest.approx(direct.drift, rel=1e-9)
    else:
        assert grid.drift_check is not None and direct.drift_check is not None
        assert grid.drift_check.drift == pytest.approx(direct.drift_check.drift, rel=1e-9)
