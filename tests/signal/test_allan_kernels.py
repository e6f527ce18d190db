"""Tests of the all-τ Allan kernels (rotacal.signal._allan_fast, ._allan_jit).

Truth: the sum of squared second differences written out in long double, and ``np.correlate``
for the lagged products; the Numba twin of the direct sum against the NumPy path (≤ 1e-12).
"""

from __future__ import annotations

import numpy as np
import pytest

from rotacal import _jit
from rotacal.signal import _allan_fast
from rotacal.signal._allan_fast import direct_sums, second_difference_sums
from rotacal.signal._phase import phase_record


def exact_sums(x: np.ndarray, ms: np.ndarray) -> np.ndarray:
    """Σ (x_{i+2m} − 2x_{i+m} + x_i)² in long double, one m at a time (independent reference)."""
    xl = x.astype(np.longdouble)
    n = x.size
    out = [np.sum((xl[2 * m :] - 2 * xl[m : n - m] + xl[: n - 2 * m]) ** 2) for m in ms.tolist()]
    return np.array(out, dtype=np.longdouble)


def red_phase(n: int, seed: int) -> np.ndarray:
    """White FM plus random-walk FM plus a rate ramp: the hard case for the expansion."""
    rng = np.random.default_rng(seed)
    w = rng.standard_normal(n)
    k = np.arange(n, dtype=float)
    return np.cumsum(w) + 1e-2 * np.cumsum(np.cumsum(rng.standard_normal(n))) + 1e-4 * k**2


@pytest.mark.parametrize("jit", [False, True])
def test_direct_sums_both_paths_equal_the_long_double_sum(jit):
    """Short and long cluster sizes, the last one with a single term; blocks cut mid-record."""
    assert _jit.use_numba(1, jit) == jit  # Numba is a dependency: the twin under test runs
    x = red_phase(10_007, seed=1)
    n = x.size
    ms = np.array([1, 2, 7, 64, 1000, 4095, 4096, 4097, (n - 1) // 2 - 1, (n - 1) // 2])
    got = direct_sums(x, ms, jit=jit)
    ref = exact_sums(x, ms)
    rel = np.abs(got / ref - 1.0).astype(np.float64)
    assert rel.max() < 1e-12, rel


def test_direct_sums_twins_agree():
    """The Numba twin and the NumPy path give the same numbers to ≤ 1e-12 relative."""
    x = red_phase(50_000, seed=2)
    ms = np.arange(1, 200)
    a = direct_sums(x, ms, jit=True)
    b = direct_sums(x, ms, jit=False)
    np.testing.assert_allclose(a, b, rtol=1e-12, atol=0)


@pytest.mark.parametrize(("whole", "long_above"), [(0, 1 << 40), (1_000, 1 << 40), (0, 1_000)])
def test_lagged_products_blocked_and_whole_equal_correlate(monkeypatch, whole, long_above):
    """R(ℓ) = Σ z_i z_{i+ℓ} by blocks (whole = 0), by one whole-record power spectrum, and by
    blocks shorter than the lags (the partitioned correlation along the block index)."""
    monkeypatch.setattr(_allan_fast, "_WHOLE_BLOCKS", whole)
    monkeypatch.setattr(_allan_fast, "_LONG_ABOVE", long_above)
    monkeypatch.setattr(_allan_fast, "_LONG_BLOCK", 1024)
    rng = np.random.default_rng(3)
    z = rng.standard_normal(20_011)
    lag_max = 5000
    got = _allan_fast._lagged_products(z, lag_max)
    ref = np.correlate(z, z, mode="full")[z.size - 1 : z.size - 1 + lag_max]
    np.testing.assert_allclose(got, ref, rtol=0, atol=1e-12 * float(z @ z))


@pytest.mark.parametrize("jit", [False, True])
def test_all_sums_with_the_numba_direct_path_equal_the_long_double_sum(jit):
    """With the Numba direct sum more cluster sizes go direct; every value still equals the
    literal sum to 1e-12 on a red-noise record with a rate ramp (all m checked near the ends
    and between groups)."""
    z = phase_record(red_phase(60_000, seed=4), 1.0, "phase")
    ms = np.arange(1, (z.size - 1) // 2 + 1)
    sums, n_direct = second_difference_sums(z, ms, jit=jit)
    if not jit:  # (with the cheaper Numba direct sum, the planner sends most m of so short a
        assert n_direct < ms.size // 10  # record to it; without, the fast method did the work)
    rng = np.random.default_rng(5)
    pick = np.unique(np.concatenate([np.arange(1, 600), rng.integers(1, ms[-1], 300), ms[-40:]]))
    ref = exact_sums(z, pick)
    rel = np.abs(sums[pick - 1] / ref - 1.0).astype(np.float64)
    assert rel.max() < 1e-11, f"max relative error {rel.max():.2e} at m = {pick[np.argmax(rel)]}"


@pytest.mark.parametrize("jit", [False, True])
def test_direct_sums_from_a_first_term(jit):
    """Sums that start at term f (a chunk's new second differences) equal the long-double sum
    of those terms, on both paths."""
    x = red_phase(9_001, seed=6)
    ms = np.array([1, 3, 64, 2000, 4000])
    firsts = np.array([0, 17, 4095, 5000, 999])
    got = direct_sums(x, ms, firsts=firsts, jit=jit)
    n = x.size
    xl = x.astype(np.longdouble)
    ref = np.array(
        [
            np.sum((xl[f + 2 * m :] - 2 * xl[f + m : n - m] + xl[f : n - 2 * m]) ** 2)
            for m, f in zip(ms.tolist(), firsts.tolist(), strict=True)
        ]
    )
    rel = np.abs(got / ref - 1.0).astype(np.float64)
    assert rel.max() < 1e-12, rel


@pytest.mark.parametrize("jit", [False, True])
def test_half_products_equal_the_triangle_sums(jit):
    """H[m] = Σ_rows Σ_{j<m} z[j]·z[j+m] by the divide and conquer (leaves by NumPy or by the
    Numba twin, which gives the same bits) against the sums written out."""
    k, leaf = _allan_fast._smooth_size(700)
    rng = np.random.default_rng(7)
    zs = np.zeros((2, 2 * k + k // 2 + leaf))
    zs[:, : 2 * k] = rng.standard_normal((2, 2 * k))
    got = _allan_fast._half_products(zs, k, leaf, jit)
    ref = np.array([sum(float(zs[r, :m] @ zs[r, m : 2 * m]) for r in range(2)) for m in range(k)])
    np.testing.assert_allclose(got, ref, rtol=0, atol=1e-11 * float(np.sum(zs * zs)))
    other = _allan_fast._half_products(zs, k, leaf, not jit)
    np.testing.assert_array_equal(got, other)


@pytest.mark.parametrize("top", [1, 3])
def test_half_products_with_the_top_levels_from_block_spectra(monkeypatch, top):
    """The top levels of the divide and conquer taken from block spectra (the triangular sum
    over whole blocks) give the triangle sums written out, as the plain recursion does."""
    monkeypatch.setattr(_allan_fast, "TOP_BLOCK", 16)
    monkeypatch.setattr(_allan_fast, "TOP_LEVELS", top)
    k, leaf = _allan_fast._smooth_size(700)
    assert _allan_fast._top_levels(k, leaf) == top
    rng = np.random.default_rng(8)
    zs = np.zeros((2, 2 * k + k // 2 + leaf))
    zs[:, : 2 * k] = rng.standard_normal((2, 2 * k)) + 3.0  # a mean: products do not cancel
    got = _allan_fast._half_products(zs, k, leaf)
    ref = np.array([sum(float(zs[r, :m] @ zs[r, m : 2 * m]) for r in range(2)) for m in range(k)])
    np.testing.assert_allclose(got, ref, rtol=0, atol=1e-11 * float(np.sum(zs * zs)))


def test_prefix_sums_in_blocks_do_not_drift():
    """Prefix sums of 10⁶ squares of a random walk (and of the walk itself) against long-double
    running sums: the blocked sums stay within 1e-14 relative, where one float64 running sum
    drifts ~10× further (what cost S(m) ~1e-10 relative at 10⁷ samples)."""
    rng = np.random.default_rng(11)
    v = np.cumsum(rng.standard_normal(1_000_000))
    got, block_sq = _allan_fast._prefix_sums(v, square=True)
    ref = np.cumsum(v.astype(np.longdouble) ** 2)
    assert got[0] == 0.0 and got.size == v.size + 1
    assert float(np.max(np.abs(got[1:] / ref - 1.0))) < 1e-14
    assert block_sq == pytest.approx(
        float(np.max((v * v)[: v.size // 4096 * 4096].reshape(-1, 4096).sum(axis=1))), rel=1e-12
    )
    plain, _ = _allan_fast._prefix_sums(v)
    ref_plain = np.cumsum(v.astype(np.longdouble))
    assert float(np.max(np.abs(plain[1:] - ref_plain))) < 1e-15 * float(np.abs(v).sum())
