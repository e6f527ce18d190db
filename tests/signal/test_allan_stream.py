"""Tests of rotacal.signal.allan_stream: the octave Allan deviation of a record read in chunks.

Truth: the in-memory overlapping_adev of the whole record (to 1e-9, the contract of a chunked
path), allantools on the same record, and the closed form of white rate noise.
"""

from __future__ import annotations

import math

import allantools
import numpy as np
import pytest

from rotacal.errors import CaptureError, ConfigError
from rotacal.signal.allan import overlapping_adev
from rotacal.signal.allan_stream import octave_adev_chunks


def gyro_rate(n: int, seed: int = 1) -> np.ndarray:
    """100 Hz gyro: white rate noise, a rate random walk and a rate ramp (°/s)."""
    rng = np.random.default_rng(seed)
    walk = np.cumsum(2e-5 * rng.standard_normal(n))
    return 0.1 + 0.3 * rng.standard_normal(n) + walk + 1e-6 * np.arange(n)


def pieces(y: np.ndarray, sizes: list[int]) -> list[np.ndarray]:
    """``y`` cut into chunks of the given sizes, cycling through them."""
    out, i, k = [], 0, 0
    while i < y.size:
        out.append(y[i : i + sizes[k % len(sizes)]])
        i += sizes[k % len(sizes)]
        k += 1
    return out


@pytest.mark.parametrize(
    ("history", "sizes"),
    [(1 << 22, [65_536]), (1 << 10, [1000, 1, 3333]), (4, [7777, 0, 12])],
)
def test_equals_the_in_memory_deviation(history, sizes):
    """Carried history long or short (most τ then from the phase file), chunks of any size."""
    y = gyro_rate(300_001)
    ref = overlapping_adev(y, fs=100.0, taus="octave")
    res = octave_adev_chunks(pieces(y, sizes), fs=100.0, history=history)
    np.testing.assert_array_equal(res.tau_s, ref.tau_s)
    np.testing.assert_array_equal(res.n_terms, ref.n_terms)
    np.testing.assert_array_equal(res.edf, ref.edf)
    for name in ("adev", "adev_low", "adev_high"):
        np.testing.assert_allclose(getattr(res, name), getattr(ref, name), rtol=1e-9, atol=0)
    assert (res.n_samples, res.n_phase, res.data_type) == (ref.n_samples, ref.n_phase, "rate")


def test_long_cluster_sizes_read_in_many_blocks(monkeypatch):
    """The phase file read back a few hundred points at a time (the readers pass the end of the
    record at different blocks) gives the same sums."""
    import rotacal.signal.allan_stream as stream

    monkeypatch.setattr(stream, "_READ", 333)
    y = gyro_rate(20_000, seed=2)
    ref = overlapping_adev(y, fs=100.0, taus="octave")
    res = octave_adev_chunks(pieces(y, [4096]), fs=100.0, history=64)
    np.testing.assert_allclose(res.adev, ref.adev, rtol=1e-9, atol=0)


def test_equals_allantools_and_white_noise_closed_form():
    sigma, fs, n = 0.004, 200.0, 400_000
    y = 0.3 + sigma * math.sqrt(fs) * np.random.default_rng(31).standard_normal(n)
    res = octave_adev_chunks(pieces(y, [50_000]), fs=fs, history=1 << 12)
    t, d, _, _ = allantools.oadev(y, rate=fs, data_type="freq", taus="octave")
    np.testing.assert_allclose(res.tau_s, t)
    np.testing.assert_allclose(res.adev, d, rtol=1e-6, atol=0)
    ok = n / res.cluster_sizes >= 9
    dev = res.adev[ok] / (sigma / np.sqrt(res.tau_s[ok])) - 1.0
    assert np.all(np.abs(dev) < 4.0 / np.sqrt(res.edf[ok]))


def test_bad_records_one_clear_line():
    y = gyro_rate(5000)
    y[3217] = math.nan
    with pytest.raises(CaptureError) as exc:
        octave_adev_chunks(pieces(y, [1000]), fs=100.0, column="gyro_z")
    assert "3217" in str(exc.value) and "gyro_z" in str(exc.value)
    with pytest.raises(CaptureError, match="constant"):
        octave_adev_chunks([np.full(400, 0.25), np.full(100, 0.25)], fs=100.0)
    with pytest.raises(CaptureError, match="at least 9"):
        octave_adev_chunks([np.ones(5), np.zeros(2)], fs=100.0)
    with pytest.raises(CaptureError, match="one-dimensional"):
        octave_adev_chunks([np.ones((10, 2))], fs=100.0)
    with pytest.raises(ConfigError, match="history"):
        octave_adev_chunks([np.ones(50)], fs=100.0, history=1000)
    with pytest.raises(ConfigError, match="fs"):
        octave_adev_chunks([gyro_rate(50)], fs=0.0)


def test_numba_direct_sums_give_the_same_deviation(monkeypatch):
    """ROTACAL_NUMBA=1: the chunks' sums by the Numba twin (one pass for all sizes)."""
    y = gyro_rate(100_003, seed=5)
    ref = octave_adev_chunks(pieces(y, [9_999]), fs=100.0, history=1 << 12)
    monkeypatch.setenv("ROTACAL_NUMBA", "1")
    res = octave_adev_chunks(pieces(y, [9_999]), fs=100.0, history=1 << 12)
    np.testing.assert_allclose(res.adev, ref.adev, rtol=1e-12, atol=0)
    np.testing.assert_allclose(res.adev, overlapping_adev(y, fs=100.0).adev, rtol=1e-9, atol=0)
