"""Heads that disagree: a self-calibration of swapped head columns is named."""

from __future__ import annotations

import numpy as np

from rotacal.encoder import self_calibrate
from rotacal.sim import simulate_pulses


def _heads(cap, n):
    return [np.asarray(cap.columns[f"head_{i}"]) for i in range(n)]


def test_agreeing_heads_say_nothing_and_swapped_heads_are_named() -> None:
    cap = simulate_pulses(heads=12, revolutions=3.0, seed=3)
    heads = _heads(cap, 12)
    assert self_calibrate(heads, pulses_per_rev=18000).warnings == ()
    heads[3], heads[4] = heads[4], heads[3]  # two head columns wired the wrong way round
    (line,) = self_calibrate(heads, pulses_per_rev=18000).warnings
    assert line.startswith("the heads disagree") and "head_0 … head_11" in line


def test_one_revolution_has_no_repeatability_to_judge_by() -> None:
    cap = simulate_pulses(heads=4, revolutions=1.5, seed=3)
    heads = _heads(cap, 4)
    heads[1], heads[2] = heads[2], heads[1]
    r = self_calibrate(heads, pulses_per_rev=18000)
    assert r.repeatability_rms_arcsec is None and r.warnings == ()
