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


def test_fast_length_is_scipys_and_import_free():
    """The FFT length is scipy.fft.next_fast_len(n, real=True) (the same padding, the same
    sums), found without importing scipy.fft: a rate command does not pay for it."""
    import subprocess
    import sys

    from scipy.fft import next_fast_len

    from rotacal.encoder.selfcal_checks import fast_length

    rng = np.random.default_rng(17)
    sizes = [*range(1, 2000), *rng.integers(2000, 10**10, 2000).tolist()]
    assert [fast_length(int(n)) for n in sizes] == [next_fast_len(int(n), real=True) for n in sizes]
    code = "import sys, rotacal.encoder.selfcal_checks; print('scipy.fft' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"
