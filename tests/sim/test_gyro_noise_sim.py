"""The static-gyro noise twin against closed forms, and the noise terms recovered from it."""

from __future__ import annotations

import numpy as np
import pytest

from rotacal.errors import ConfigError
from rotacal.gyro.noise import gyro_noise
from rotacal.sim import simulate_gyro_noise


def test_white_part_has_the_set_density():
    cap = simulate_gyro_noise(duration_s=600, arw_deg_rt_h=0.6, bias_instability_deg_h=0.0)
    y = cap.columns["rate_deg_s"]
    # N = 0.6 °/√h = 0.01 °/s·√s → sample std N·√fs = 0.1 °/s at 100 Hz
    assert np.std(y) == pytest.approx(0.1, rel=0.01)


def test_arw_and_bias_instability_recovered_from_the_twin():
    """Two hours at 100 Hz of N = 0.1 °/√h and true flicker B = 2 °/h: both within twice their
    U of the truth (the 95 % coverage itself is tested over 40 seeds in
    tests/gyro/test_noise_fit.py). The former band-limited bias processes added +2 % to N, and B
    read at the curve's minimum came out 7–18 % off."""
    cap = simulate_gyro_noise(duration_s=2 * 3600, arw_deg_rt_h=0.1, bias_instability_deg_h=2.0)
    r = gyro_noise(cap.columns["rate_deg_s"], time_s=cap.columns["time_s"])
    terms = r.noise_terms
    for key, truth in (("arw_deg_rt_h", 0.1), ("bias_instability_deg_h", 2.0)):
        assert abs(terms[key] - truth) <= 2 * terms[f"{key}_U"], (key, terms[key])
    assert terms["arw_deg_rt_h"] == pytest.approx(0.1, rel=0.01)


def test_gauss_markov_bias_is_flat_over_its_band_only():
    """The band-limited stand-in (bias_model="gauss-markov"): its closed-form Allan deviation is
    0.664·B at the band's middle and falls outside it (IEEE 952 Annex C, exponentially
    correlated process), the reason it is not the default."""
    from rotacal.sim.gyro_noise import _gm_allan_plateau

    taus_c = np.logspace(0.0, 3.0, 10)
    mid = _gm_allan_plateau(taus_c, np.sqrt(1e3))
    assert _gm_allan_plateau(taus_c, 0.1) / mid < 0.3
    assert _gm_allan_plateau(taus_c, 3000.0) / mid < 0.75
    cap = simulate_gyro_noise(duration_s=60.0, bias_model="gauss-markov", seed=1)
    assert cap.truth["bias_model"] == "gauss-markov"
    with pytest.raises(ConfigError, match="bias_model"):
        simulate_gyro_noise(bias_model="pink")


def test_bad_settings():
    with pytest.raises(ConfigError):
        simulate_gyro_noise(duration_s=0.1)
    with pytest.raises(ConfigError):
        simulate_gyro_noise(arw_deg_rt_h=-1)
    with pytest.raises(ConfigError, match="bias_band_s"):
        simulate_gyro_noise(bias_band_s=(10.0, 1.0))
