"""The bounded-memory paths of the pulse-timing rate analysis against the whole-array formulas."""

from __future__ import annotations

import numpy as np
import pytest

import rotacal.table.rate as rate_module
import rotacal.table.rate_allan as rate_allan
from rotacal.errors import CaptureError
from rotacal.sim.pulses import simulate_pulses
from rotacal.table.rate import allan_versus_angle, calibrate_rate


@pytest.fixture(scope="module")
def train():
    """One head of a twin: 2 heads × 900 pulses × 12 revolutions, fluctuation and graduation."""
    cap = simulate_pulses(heads=2, pulses_per_rev=900, rate_deg_s=120.0, revolutions=12.0, seed=5)
    return cap.columns["head_0"], float(cap.truth["set_rate_deg_s"])


def _whole_array_s(t, a, ks, rate):
    """s(φ) as Kokuyama et al. (2015) §5 define it, with the whole arrays at once."""
    out = []
    for k in ks:
        omega = (a[k:] - a[:-k]) / (t[k:] - t[:-k])
        d = omega[k:] - omega[:-k]
        out.append(np.sqrt(0.5 * np.mean(d * d)) / rate)
    return np.array(out)


@pytest.mark.parametrize("block", [7, 1000, 1 << 16])
def test_blocked_allan_equals_the_whole_array_formula(train, monkeypatch, block):
    """Block sizes that split the record into many blocks, a few, and one give the same s(φ)."""
    t, rate = train
    a = np.arange(t.size) * 0.4 + 1e-4 * np.sin(np.arange(t.size) * 0.01)
    monkeypatch.setattr(rate_allan, "ALLAN_BLOCK", block)
    monkeypatch.setattr(rate_allan, "ALLAN_WHOLE_MAX", block)
    phi, s = allan_versus_angle(t, a, mean_rate_deg_s=rate, pitch_deg=0.4)
    ks = np.rint(phi / 0.4).astype(np.int64)
    assert ks[0] == 1 and ks[-1] == (t.size - 1) // 3  # the whole range of cluster sizes
    expected = _whole_array_s(t, a, ks, rate)
    if block > t.size:  # one block: the whole-array arithmetic, to the last bit
        np.testing.assert_array_equal(s, expected)
    else:
        np.testing.assert_allclose(s, expected, rtol=1e-12, atol=0)


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
