"""inspect_columns / Inspector against columns built with known answers."""

from __future__ import annotations

import numpy as np
import pytest

from rotacal.errors import CaptureError
from rotacal.inspect import Inspector, inspect_columns


def test_sample_rate_and_duration_of_a_uniform_grid():
    fs, n = 250.0, 10_001
    t = np.arange(n) / fs
    r = inspect_columns({"time_s": t, "x": np.sin(t)})
    assert r.time_column == "time_s" and r.time_increasing is True
    assert r.sample_rate_hz == pytest.approx(fs, rel=1e-12)
    assert r.duration_s == pytest.approx((n - 1) / fs, rel=1e-15)
    assert r.sample_interval_jitter_s < 1e-12 / fs
    assert r.gaps == () and r.gap_count == 0 and r.warnings == ()


def test_jitter_is_the_standard_deviation_of_the_intervals():
    rng = np.random.default_rng(1)
    dt = 0.01 + rng.normal(0.0, 2e-5, 20_000)
    t = np.concatenate(([0.0], np.cumsum(dt)))
    r = inspect_columns({"time_s": t})
    assert r.sample_interval_s == pytest.approx(dt.mean(), rel=1e-12)
    assert r.sample_interval_jitter_s == pytest.approx(dt.std(), rel=1e-9)
    assert r.warnings == ()  # 0.2 % of the interval: below the warning level


def test_large_jitter_is_a_warning():
    rng = np.random.default_rng(2)
    dt = 0.01 * (1 + rng.uniform(-0.2, 0.2, 5_000))
    r = inspect_columns({"time_s": np.cumsum(dt)})
    assert any("jitters by" in w for w in r.warnings)


def test_a_known_gap_is_found_with_its_missing_samples():
    t = np.arange(2_000) * 0.002
    kept = np.concatenate((t[:500], t[550:1500], t[1503:]))
    r = inspect_columns({"time_s": kept})
    assert r.gap_count == 2
    assert [(g.start_s, g.end_s, g.missing_samples) for g in r.gaps] == [
        (t[499], t[550], 50),
        (t[1499], t[1503], 3),
    ]
    assert r.sample_rate_hz == pytest.approx(500.0, rel=1e-9)  # gaps left out of the interval
    assert r.duration_s == pytest.approx(t[-1])
    assert any("2 gap(s)" in w and f"{t[499]:.9g} s" in w for w in r.warnings)


def test_a_step_of_less_than_three_intervals_is_no_gap():
    t = np.arange(1_000) * 0.01
    r = inspect_columns({"time_s": np.delete(t, [100])})  # one sample missing: a 2-step
    assert r.gap_count == 0


def test_nan_and_inf_are_counted_and_the_range_is_of_the_finite_values():
    x = np.linspace(-3.0, 5.0, 200)
    x[[10, 20, 30]] = np.nan
    x[40], x[199] = np.inf, -np.inf
    r = inspect_columns({"rate_deg_s": x})
    c = r.columns["rate_deg_s"]
    assert (c.samples, c.nan, c.inf, c.first_nonfinite_row) == (200, 3, 2, 10)
    assert c.min == -3.0 and c.max == x[198]
    assert c.increasing is False
    assert any("3 NaN and 2 inf" in w and "row 10" in w for w in r.warnings)


def test_repeated_samples_and_the_smallest_step():
    rng = np.random.default_rng(3)
    levels = rng.integers(-400, 400, 5_000)
    x = levels * 0.25  # quantum 0.25, exact in binary
    expected_repeats = int(np.count_nonzero(levels[1:] == levels[:-1]))
    c = inspect_columns({"output": x}).columns["output"]
    assert c.repeated_fraction == expected_repeats / x.size
    assert c.smallest_step == 0.25


def test_the_clipped_fraction_is_the_share_of_samples_at_the_rails():
    t = np.arange(100_000) / 10_000.0
    clean = np.sin(2 * np.pi * 3.0 * t)
    clipped = np.clip(clean, -0.8, 0.8)
    at_rails = np.count_nonzero(np.abs(clean) >= 0.8)
    r = inspect_columns({"time_s": t, "rate_deg_s": clipped, "clean": clean})
    assert r.columns["rate_deg_s"].clipped_fraction == at_rails / clean.size
    assert r.columns["clean"].clipped_fraction == 0.0
    assert sum("clipped" in w for w in r.warnings) == 1


def test_time_that_steps_back_is_reported():
    t = np.arange(100) * 0.1
    t[[40, 41]] = t[[41, 40]]
    r = inspect_columns({"time_s": t})
    assert r.time_increasing is False
    assert any("does not increase at 1 step(s)" in w and "row 41" in w for w in r.warnings)
    t[5] = np.nan  # rows keep their numbers around a NaN time stamp
    chunked = Inspector(["time_s"])
    for lo in range(0, t.size, 30):
        chunked.add({"time_s": t[lo : lo + 30]})
    assert any("at 1 step(s), the first at row 41" in w for w in chunked.result().warnings)


def test_constant_column_is_a_warning():
    r = inspect_columns({"id": np.full(50, 23.0)})
    assert r.columns["id"].repeated_fraction == 49 / 50
    assert any("'id' is constant (23)" in w for w in r.warnings)


def test_chunked_feeding_gives_the_same_summary():
    rng = np.random.default_rng(4)
    t = np.cumsum(0.01 + rng.normal(0, 1e-4, 3_001))
    t = np.delete(t, np.arange(1_000, 1_010))
    x = np.round(rng.normal(0, 3, t.size)) * 0.5
    x[[5, 700, 2_000]] = np.nan
    whole = inspect_columns({"time_s": t, "x": x})
    chunked = Inspector(["time_s", "x"])
    for lo in range(0, t.size, 7):
        chunked.add({"time_s": t[lo : lo + 7], "x": x[lo : lo + 7]})
    parts = chunked.result()
    assert parts.columns == whole.columns
    assert parts.gaps == whole.gaps and parts.gap_count == whole.gap_count == 1
    assert parts.sample_rate_hz == pytest.approx(whole.sample_rate_hz, rel=1e-12)
    assert parts.sample_interval_jitter_s == pytest.approx(whole.sample_interval_jitter_s, rel=1e-9)


def test_suggested_mappings():
    t = np.arange(10) * 0.5
    r = inspect_columns({"Time": t, "Rate_Deg_S": np.ones(10), "output": np.arange(10.0)})
    assert r.suggested_columns == ("Rate_Deg_S=rate_deg_s", "Time=time_s")
    assert r.fits == ()
    headerless = inspect_columns({"col_1": np.arange(10.0), "col_2": t + 0.25, "col_3": t})
    assert headerless.suggested_columns == ("col_2=time_s",)  # col_1 counts, it is no time
    timed = inspect_columns({"time_s": t, "timestamp": t})
    assert timed.suggested_columns == ()  # it has a time column already


def test_a_column_that_is_not_1d_numbers_is_refused():
    with pytest.raises(CaptureError, match="'x' must be a 1-D array"):
        inspect_columns({"x": np.zeros((3, 2))})
    with pytest.raises(CaptureError, match="'y' must be a 1-D array"):
        inspect_columns({"y": np.array(["a", "b"])})
