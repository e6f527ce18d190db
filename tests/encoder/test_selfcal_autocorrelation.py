"""The period check's autocorrelation against the direct sum."""

from __future__ import annotations

import numpy as np
import pytest

from rotacal.encoder.selfcal_checks import _autocorrelation


@pytest.mark.parametrize("n", [1, 7, 1000, 4099])
def test_autocorrelation_is_the_direct_sum(n):
    rng = np.random.default_rng(n)
    x = rng.standard_normal(n) + np.sin(np.arange(n) * 0.3)
    direct = np.correlate(x, x, mode="full")[n - 1 :]  # Σ_i x_i·x_{i+ℓ}, ℓ = 0 … n − 1
    lags = max(1, (3 * n) // 4)
    got = _autocorrelation(x, lags)
    assert got.shape == (lags,)
    np.testing.assert_allclose(got, direct[:lags], rtol=0, atol=1e-12 * direct[0])
