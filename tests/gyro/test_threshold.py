"""Threshold and resolution from a small-step test (rotacal.gyro.threshold) against the
gyro-steps twin, whose truth is the closed form max(r, d) and r of its sensor model."""

from __future__ import annotations

import numpy as np
import pytest

from rotacal.errors import CaptureError, ConfigError
from rotacal.gyro.threshold import small_step_test
from rotacal.sim import simulate_gyro_steps


def _test(nominal=True, **kw):
    cap = simulate_gyro_steps(**kw)
    s = cap.truth["scale_factor"] if nominal else None
    return small_step_test(
        cap.columns["rate_deg_s"], cap.columns["output"], scale_factor=s
    ), cap.truth


@pytest.mark.parametrize(
    ("r", "d", "nominal"),
    [(0.0042, 0.007, True), (0.0025, 0.0, True), (0.006, 0.0015, False)],
)
def test_truth_within_stated_uncertainty(r, d, nominal):
    res, truth = _test(nominal, resolution_deg_s=r, dead_zone_deg_s=d, samples_per_dwell=600)
    for key in ("threshold_deg_s", "resolution_deg_s"):
        value, u = getattr(res, key), getattr(res, f"{key}_u")
        lo, hi = getattr(res, key.replace("_deg_s", "_bracket_deg_s"))
        assert lo < truth[key] <= hi + 1e-12, key
        assert abs(value - truth[key]) <= 2 * u, key
    assert res.scale_factor_source == ("nominal" if nominal else "fitted")


def test_a_wrong_gyro_is_caught():
    coarse, _ = _test(resolution_deg_s=0.012, dead_zone_deg_s=0.0, samples_per_dwell=300)
    _, fine = _test(resolution_deg_s=0.0042, samples_per_dwell=300)
    assert abs(coarse.resolution_deg_s - fine["resolution_deg_s"]) > 2 * coarse.resolution_deg_s_u


def test_bounds_and_noise_are_said():
    ideal, _ = _test(resolution_deg_s=0.0, dead_zone_deg_s=0.0, samples_per_dwell=300)
    assert ideal.resolution_bracket_deg_s[0] == 0.0
    assert any("at most" in w for w in ideal.warnings)
    blind, _ = _test(resolution_deg_s=0.0, dead_zone_deg_s=50.0, samples_per_dwell=300)
    assert blind.threshold_deg_s is None and blind.threshold_deg_s_u is None
    assert any("did not reach" in w for w in blind.warnings)
    noisy, _ = _test(noise_std=2.5e-4, samples_per_dwell=50)
    assert any("the noise could turn" in w for w in noisy.warnings)


def test_settling_and_refusals():
    cap = simulate_gyro_steps(samples_per_dwell=20)
    rate, out = cap.columns["rate_deg_s"], cap.columns["output"]
    with pytest.raises(CaptureError, match="at least 2 samples"):
        small_step_test(rate, out, settle_samples=19)
    with pytest.raises(CaptureError, match="one set rate"):
        small_step_test(np.zeros(10), np.ones(10))
    with pytest.raises(ConfigError, match="settle_samples"):
        small_step_test(rate, out, settle_samples=-1)
    with pytest.raises(ConfigError, match="scale_factor"):
        small_step_test(rate, out, scale_factor=0.0)
    with pytest.raises(CaptureError, match="finite"):
        small_step_test(rate, np.where(np.arange(out.size) == 3, np.nan, out))
