"""The bounded-memory paths of the pulse-timing rate analysis against the whole-array formulas."""

from __future__ import annotations

import numpy as np
import pytest

import rotacal.table.rate as rate_module
import rotacal.table.rate_allan_sums as rate_allan_sums
from rotacal.errors import CaptureError
from rotacal.sim.pulses import simulate_pulses
from rotacal.table.rate import allan_versus_angle, calibrate_rate
from rotacal.table.rate_allan import allan_clusters
from rotacal.table.rate_allan_sums import AllanSums, allan_stride, allan_sum


@pytest.fixture(scope="module")
def train():
    """One head of a twin: 2 heads × 900 pulses × 12 revolutions, fluctuation and graduation."""
    cap = simulate_pulses(heads=2, pulses_per_rev=900, rate_deg_s=120.0, revolutions=12.0, seed=5)
    return cap.columns["head_0"], float(cap.truth["set_rate_deg_s"])


def _whole_array_s(t, a, ks, rate):
    """s(φ) as Kokuyama et al. (2015) §5 define it, with the whole arrays at once, on the record
    decimated to every d-th pulse (d = the stride of each cluster size)."""
    out = []
    for k in ks:
        d = allan_stride(int(k))
        td, ad, kd = t[::d], a[::d], int(k) // d
        omega = (ad[kd:] - ad[:-kd]) / (td[kd:] - td[:-kd])
        diff = omega[kd:] - omega[:-kd]
        out.append(np.sqrt(0.5 * np.mean(diff * diff)) / rate)
    return np.array(out)


@pytest.mark.parametrize("numba", ["0", "1"])
@pytest.mark.parametrize("block", [7, 1000, 1 << 16])
def test_blocked_allan_equals_the_whole_array_formula(train, monkeypatch, block, numba):
    """Blocks that split the record into many, a few, and one give the whole-array s(φ), with
    the NumPy and with the Numba sums."""
    t, rate = train
    a = np.arange(t.size) * 0.4 + 1e-4 * np.sin(np.arange(t.size) * 0.01)
    monkeypatch.setattr(rate_allan_sums, "ALLAN_BLOCK", block)
    monkeypatch.setenv("ROTACAL_NUMBA", numba)
    phi, s = allan_versus_angle(t, a, mean_rate_deg_s=rate, pitch_deg=0.4)
    ks = np.rint(phi / 0.4).astype(np.int64)
    assert ks[0] == 1 and ks[-1] > (t.size - 1) // 4  # the whole range of cluster sizes
    assert max(allan_stride(int(k)) for k in ks) > 1  # decimated clusters among them
    np.testing.assert_allclose(s, _whole_array_s(t, a, ks, rate), rtol=1e-12, atol=0)


def test_decimated_terms_are_every_dth_term_of_the_full_sum(train):
    """A cluster at stride d sums exactly the terms j = 0, d, 2d … of the full overlapping sum."""
    t, _ = train
    a = np.arange(t.size) * 0.4 + 1e-4 * np.cos(np.arange(t.size) * 0.003)
    k, d = 640, 10
    omega = (a[k:] - a[:-k]) / (t[k:] - t[:-k])
    full = (omega[k:] - omega[:-k]) ** 2
    td, ad = t[::d], a[::d]
    got = allan_sum(td, ad, k // d, 0, td.size - 2 * (k // d), jit=False)
    assert got == pytest.approx(float(np.sum(full[::d])), rel=1e-12)


@pytest.mark.parametrize("numba", [False, True])
@pytest.mark.parametrize("chunk", [997, 5000])
def test_streamed_allan_sums_equal_the_in_memory_ones(train, chunk, numba):
    """Fed in chunks (shorter than the longest cluster), the carried state gives the sums of the
    whole record: ≤ 1e-12 relative, the same number of terms."""
    t, rate = train
    a = np.arange(t.size) * 0.4 + 1e-4 * np.sin(np.arange(t.size) * 0.01)
    ks = allan_clusters(t.size, 0.4)
    strides = [allan_stride(int(k)) for k in ks]
    acc = AllanSums(ks, strides, jit=numba)
    for start in range(0, t.size, chunk):
        acc.update(t[start : start + chunk], a[start : start + chunk])
    s = np.sqrt(0.5 * acc.mean_squares()) / rate
    counts = [-(-t.size // d) - 2 * (int(k) // d) for k, d in zip(ks, strides, strict=True)]
    np.testing.assert_array_equal(acc.counts, counts)
    np.testing.assert_allclose(s, _whole_array_s(t, a, ks, rate), rtol=1e-12, atol=0)
    held = sum(tt.size for tt, _, _ in acc._tails.values())
    assert held < 4 * 2 * 2 * 64 * len(acc._tails)  # bounded by the clusters, not the record


def test_grid_keeps_one_revolution_exact_and_rounds_long_clusters():
    """The default grid has k = m exactly; long clusters are multiples of their stride."""
    ks = allan_clusters(10_000_000, 360.0 / 18000)
    assert 18000 in ks.tolist()
    for k in ks.tolist():
        d = allan_stride(k)
        assert k % d == 0 and (k < 128 or k // d >= 64)
        if k != 18000:
            assert k // d < 2 * 64 + 1
    long_ = ks[ks >= 128]
    ratios = long_[1:] / long_[:-1]  # still 12 per decade: 10^(1/12) = 1.21 apart, ± rounding
    assert ratios.max() < 1.25 and long_[-1] > 10_000_000 // 4


def test_blocked_allan_white_timing_noise_closed_form():
    """Only white timing jitter σ_t, blocks far shorter than the record: s(φ) = √3·σ_t·ω_m/φ."""
    sigma_t, rate = 2e-7, 100.0
    rng = np.random.default_rng(8)
    n = 200_000
    t = np.arange(n) * (0.1 / rate) + rng.normal(0.0, sigma_t, n)
    phi, s = allan_versus_angle(
        t, np.arange(n) * 0.1, mean_rate_deg_s=rate, angles_deg=[0.1, 1.0, 10.0]
    )
    # relative scatter of an Allan estimate ~ 1/√(terms); terms ≥ 60,000 here
    np.testing.assert_allclose(s, np.sqrt(3) * sigma_t * rate / phi, rtol=0.03)


@pytest.fixture(scope="module")
def long_head():
    """One head of 15 revolutions of 600 pulses with a coarse graduation pattern."""
    cap = simulate_pulses(
        heads=2,
        pulses_per_rev=600,
        rate_deg_s=90.0,
        revolutions=15.0,
        graduation_noise_arcsec=1.0,
        seed=12,
    )
    return cap.columns["head_0"]


def test_single_head_period_check_on_a_prefix_keeps_the_result(long_head, monkeypatch):
    """Checking the period on the first 8 revolutions gives the result of the whole record."""
    whole = calibrate_rate([long_head], pulses_per_rev=600)
    monkeypatch.setattr(rate_module, "PERIOD_CHECK_PULSES", 10)  # 8 revolutions: 4800 pulses
    prefix = calibrate_rate([long_head], pulses_per_rev=600)
    assert not any("cannot be confirmed" in n for n in whole.notes)  # the twin's m is confirmed
    assert prefix.to_dict() == whole.to_dict()


def test_single_head_period_check_on_a_prefix_still_refuses_a_wrong_count(long_head, monkeypatch):
    """A wrong pulses-per-revolution (the twin has 600) is refused from the prefix too."""
    monkeypatch.setattr(rate_module, "PERIOD_CHECK_PULSES", 10)
    with pytest.raises(CaptureError, match="repeats every 600 pulses"):
        calibrate_rate([long_head], pulses_per_rev=500)


@pytest.mark.parametrize("block", [5, 1 << 16])
def test_blocked_timing_jitter_equals_the_whole_array_filter(train, block):
    """The same-line and pulse differences block by block give the whole-array convolution's
    mean square (≤ 1e-12 relative) and the same number of terms."""
    import rotacal.table.rate_jitter as rate_jitter

    t, _ = train
    m = 900
    sums = rate_jitter.JitterSums(t.size, m)
    for start in range(0, t.size, block):  # chunks that cut the 2m + 3 overlap many times
        sums.update(t[start : start + block])
    d = t[2 * m :] - 2.0 * t[m:-m] + t[: -2 * m]
    e = np.convolve(d, np.array([1.0, -3.0, 3.0, -1.0])[::-1], mode="valid")
    assert sums.count == e.size
    sigma, _, exact = sums.result()
    assert exact
    assert sigma**2 * 120.0 == pytest.approx(float(np.mean(e * e)), rel=1e-12)
    assert sums.result() == pytest.approx(rate_jitter.timing_jitter(t, m), rel=1e-12)


def test_requested_angles_keep_whole_revolutions_and_round_poor_clusters():
    """A whole revolution is kept to the pulse; a cluster with no small stride (a prime number
    of pulses) is rounded to the decimated grid, by less than 1/64 of itself."""
    m = 18000
    pitch = 360.0 / m
    prime = 1_000_003  # no divisor: its stride would be 1
    ks = allan_clusters(10_000_000, pitch, [360.0, 720.0, prime * pitch])
    assert ks[0] == m and ks[1] == 2 * m
    assert ks[2] != prime and abs(ks[2] - prime) < prime / 64
    assert ks[2] // allan_stride(int(ks[2])) < 2 * 64 + 1
    # decreasing angles (a negative mean step) hold no whole revolution: no negative cluster
    assert (allan_clusters(1000, -0.4) > 0).all()
