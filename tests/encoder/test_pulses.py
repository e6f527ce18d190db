"""Pulse timing (seed 004 §5): angle, time-difference rate, pairing of heads."""

from __future__ import annotations

import numpy as np
import pytest

from rotacal.encoder.pulses import (
    check_pulse_times,
    head_columns,
    pair_heads,
    pulse_angle_deg,
    pulse_rate,
    whole_revolution_rate,
)
from rotacal.errors import CaptureError, ConfigError


def test_constant_rate_gives_the_rate_exactly():
    m, rate = 1000, 36.0
    t = 0.123 + np.arange(3 * m + 1) * (360.0 / m) / rate
    time_s, r = pulse_rate(t, pulse_angle_deg(np.arange(t.size), m), average=10)
    assert np.allclose(r, rate, rtol=1e-12)
    assert time_s.size == (t.size - 1) // 10
    # block centres: mean of the interval midpoints of each block of 10
    assert time_s[0] == pytest.approx(t[0] + 5 * (t[1] - t[0]))
    mean, revs = whole_revolution_rate(t, m)
    assert revs == 3 and mean == pytest.approx(rate, rel=1e-12)


def test_block_average_is_the_mean_of_interval_rates():
    rng = np.random.default_rng(0)
    t = np.cumsum(rng.uniform(0.9, 1.1, 101))
    angle = np.arange(101) * 2.0
    _, r = pulse_rate(t, angle, average=4)
    per_interval = 2.0 / np.diff(t)
    assert np.allclose(r, per_interval[:100].reshape(25, 4).mean(axis=1))
    with pytest.raises(ConfigError, match="average"):
        pulse_rate(t, angle, average=0)
    with pytest.raises(CaptureError, match="lower --average"):
        pulse_rate(t[:3], angle[:3], average=5)


def test_compensated_angle_follows_the_interface_convention():
    m = 8
    d = np.array([1.0, -2.0, 0.5, 0.0, 3.0, -1.0, -0.5, -1.0])  # arcsec
    k = np.arange(20)
    a = pulse_angle_deg(k, m, d, line_offset=3)
    expected = k * 45.0 + (d[(k + 3) % m] - d[3]) / 3600.0
    assert np.allclose(a, expected, atol=1e-15)
    with pytest.raises(ConfigError, match="pulses_per_rev"):
        pulse_angle_deg(k, 9, d)


def test_pairing_by_time_not_by_index():
    period = 1e-3
    t0 = np.arange(500) * period
    late = t0[37:] + 0.3 * period  # starts 37 pulses late, a third of a pitch behind
    early = t0[:450] - 0.45 * period + period * 5  # index offset −5, nearly half a pitch
    p = pair_heads([t0, late, early])
    assert list(p.index_offsets) == [0, -37, -5]
    # head 1 starts at head-0 pulse 37; head 2's last pulse (449) pairs with head-0 pulse 454
    assert p.first == 37 and p.stop == 455
    assert np.allclose(p.delays_s[1], 0.3 * period)
    assert np.allclose(p.delays_s[2], -0.45 * period)
    assert any("head_1 starts 37 pulses after head_0" in n for n in p.notes)


def test_pulse_train_checks():
    t = np.arange(1000) * 1e-3
    assert check_pulse_times(t).dtype == np.float64
    with pytest.raises(CaptureError, match="about 2 pulse"):
        check_pulse_times(np.delete(t, [300, 301]), "head_3")
    with pytest.raises(CaptureError, match="has 2 pulse"):
        check_pulse_times(t[:2], "head_0")
    with pytest.raises(CaptureError, match="NaN"):
        check_pulse_times(np.r_[t[:5], np.nan, t[6:]])
    # a slow ramp of the rate is not a gap
    ramp = np.cumsum(np.linspace(1e-3, 1.4e-3, 5000))
    check_pulse_times(ramp)


def test_head_columns():
    cols = {"head_1": [1.0, 2.0], "head_0": [0.5, 1.5], "time_s": [0.0]}
    heads = head_columns(cols)
    assert [h[0] for h in heads] == [0.5, 1.0]
    with pytest.raises(CaptureError, match="no head_0"):
        head_columns({"a": [1.0]})


@pytest.mark.parametrize("n", [129, 200, 4097, 100_003])
def test_local_period_by_rows_is_np_interp_to_the_bit(n):
    """The block medians interpolated row by row are np.interp's values, bit for bit."""
    from rotacal.encoder.pulses import _PERIOD_BLOCK, _local_period

    dt = 1.0 + 0.01 * np.random.default_rng(n).standard_normal(n)
    nb = n // _PERIOD_BLOCK
    medians = np.median(dt[: nb * _PERIOD_BLOCK].reshape(nb, _PERIOD_BLOCK), axis=1)
    centres = (np.arange(nb) + 0.5) * _PERIOD_BLOCK
    np.testing.assert_array_equal(_local_period(dt), np.interp(np.arange(n), centres, medians))


@pytest.mark.parametrize("chunk", [1, 37, 1 << 18])
def test_pulse_rate_chunk_by_chunk_is_the_whole_array_formula_to_the_bit(monkeypatch, chunk):
    """Rate points made a few blocks at a time are the whole-record reshape means, bit for bit."""
    import rotacal.encoder.pulses as pulses

    rng = np.random.default_rng(chunk)
    t = np.cumsum(1e-3 * (1.0 + 0.01 * rng.standard_normal(10_007)))
    a = np.arange(t.size) * 0.02 + 1e-5 * rng.standard_normal(t.size)
    monkeypatch.setattr(pulses, "_RATE_CHUNK", chunk)
    time_s, rate = pulse_rate(t, a, average=10)
    dt = np.diff(t)
    n = (dt.size // 10) * 10
    np.testing.assert_array_equal(rate, (np.diff(a) / dt)[:n].reshape(-1, 10).mean(axis=1))
    np.testing.assert_array_equal(time_s, (t[:-1] + 0.5 * dt)[:n].reshape(-1, 10).mean(axis=1))
    with pytest.raises(ConfigError, match="one angle per pulse"):
        pulse_rate(t, a[:-1], average=10)
