"""The twin's sensor ranges: outputs clip at the range, the truth counts what was beyond it."""

from __future__ import annotations

import math

import numpy as np
import pytest

from rotacal import sim
from rotacal.errors import ConfigError


@pytest.mark.parametrize("level", [0.7, 0.95])
def test_lts_and_fog_clip_at_their_range_with_the_sine_share(level):
    amp = 0.5
    d_amp = 100.0 * math.tan(math.radians(amp))
    whole = {"amplitude_deg": amp, "duration_s": 3.0}  # six whole periods of the 2 Hz motion
    lts = sim.simulate("lts", range_mm=level * d_amp, noise_mm=0.0, **whole)
    d = lts.columns["displacement_mm"]
    assert d.max() == pytest.approx(level * d_amp) and d.min() == pytest.approx(-level * d_amp)
    # closed form: |sin| > c for 2·arccos(c)/π of the time (tan θ ∝ sin θ to 1e-5 at 0.5°)
    share = lts.truth["sensor"]["clipped_samples"] / len(lts)
    assert share == pytest.approx(2 * math.acos(level) / math.pi, abs=0.002)
    rate_amp = 2 * math.pi * 2.0 * amp
    fog = sim.simulate("fog", range_deg_s=level * rate_amp, **whole)
    share = fog.truth["sensor"]["clipped_samples"] / len(fog)
    assert share == pytest.approx(2 * math.acos(level) / math.pi, abs=0.002)
    assert np.max(np.abs(fog.columns["rate_deg_s"])) == pytest.approx(level * rate_amp)


def test_without_a_range_the_truth_is_unchanged():
    assert "range_mm" not in sim.simulate("lts").truth["sensor"]
    assert "clipped_samples" not in sim.simulate("fog").truth["sensor"]
    assert "clipped_samples" not in sim.simulate_multiposition().truth["sensor"]
    assert "clipped_samples" not in sim.simulate_gyro_noise(duration_s=10.0).truth


def test_gyro_twins_clip_at_their_range():
    mp = sim.simulate_multiposition(output_limit_deg_h=120.0)
    y = mp.columns["output_deg_h"]
    assert np.abs(y).max() == 120.0
    assert mp.truth["sensor"]["clipped_samples"] == np.count_nonzero(np.abs(y) == 120.0)
    gn = sim.simulate_gyro_noise(duration_s=100.0, range_deg_s=0.1)
    r = gn.columns["rate_deg_s"]
    assert np.abs(r).max() == 0.1
    assert gn.truth["clipped_samples"] == np.count_nonzero(np.abs(r) == 0.1)
    gr = sim.simulate_gyro_rates(saturation=(1.3, 3.7))
    out = gr.columns["output"]
    assert gr.truth["sensor"]["clipped_samples"] == np.count_nonzero((out == 1.3) | (out == 3.7))


@pytest.mark.parametrize(
    ("kind", "option"),
    [("lts", "range_mm"), ("fog", "range_deg_s")],
)
def test_a_range_must_be_positive(kind, option):
    with pytest.raises(ConfigError, match=option):
        sim.simulate(kind, **{option: 0.0})
    with pytest.raises(ConfigError, match="output_limit_deg_h"):
        sim.simulate_multiposition(output_limit_deg_h=-1.0)
    with pytest.raises(ConfigError, match="range_deg_s"):
        sim.simulate_gyro_noise(duration_s=10.0, range_deg_s=0.0)
