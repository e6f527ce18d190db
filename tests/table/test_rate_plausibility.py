"""Rate plausibility: a set rate off by a factor, and a table still spinning down."""

from __future__ import annotations

import numpy as np
import pytest

from rotacal.sim import simulate_pulses
from rotacal.table import calibrate_rate


@pytest.fixture(scope="module")
def heads():
    cap = simulate_pulses(seed=2)
    return [np.asarray(cap.columns[k]) for k in cap.columns if k.startswith("head_")]


def test_set_rate_ten_times_the_measured_one_names_the_settings(heads) -> None:
    assert calibrate_rate(heads, pulses_per_rev=18000, set_rate_deg_s=300.0).warnings == ()
    (line,) = calibrate_rate(heads, pulses_per_rev=18000, set_rate_deg_s=30.0).warnings
    assert "×10" in line and "--pulses-per-rev" in line


def test_a_table_still_spinning_down_is_not_a_constant_rate(heads) -> None:
    """Time warped t → t + a·t²/T: the rate falls by about 2a over the record (0.2 % here)."""
    t0 = min(h[0] for h in heads)
    span = max(h[-1] for h in heads) - t0
    slowing = [h + 1e-3 * (h - t0) ** 2 / span for h in heads]
    (line,) = calibrate_rate(slowing, pulses_per_rev=18000).warnings
    assert line.startswith("the rate is not constant")
    change = float(line.split("changes by ")[1].split(" %")[0])
    assert change == pytest.approx(-0.2, rel=0.05)  # 1/(1 + 2a·t/T) over the record: −2a
