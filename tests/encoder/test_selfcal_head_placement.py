"""The head placement errors' Type A uncertainty against the twin's true placements."""

from __future__ import annotations

import numpy as np
import pytest

from rotacal.encoder.selfcal import self_calibrate
from rotacal.sim.pulses import simulate_pulses

HEADS = 4
M = 3600


def _run(seed: int, revolutions: float = 5.2):
    cap = simulate_pulses(
        heads=HEADS,
        pulses_per_rev=M,
        revolutions=revolutions,
        jitter_s=2e-8,
        rate_fluctuation_percent=0.01,
        seed=seed,
    )
    heads = [cap.columns[f"head_{i}"] for i in range(HEADS)]
    return cap, self_calibrate(heads, pulses_per_rev=M)


@pytest.fixture(scope="module")
def repeats():
    """20 twins with fresh noise and fresh placements: each placement's error and its u, U."""
    errors, us, bigs = [], [], []
    for seed in range(20):
        cap, r = _run(seed)
        truth = np.asarray(cap.truth["head_placement_arcsec_values"])
        errors.append(np.asarray(r.head_offsets_arcsec)[1:] - truth[1:])
        us.append(np.asarray(r.head_offsets_arcsec_u)[1:])
        bigs.append(np.asarray(r.head_offsets_arcsec_U)[1:])
    return np.array(errors), np.array(us), np.array(bigs)


def test_stated_U_covers_the_true_placement(repeats):
    errors, _, bigs = repeats
    covered = np.mean(np.abs(errors) <= bigs)
    assert covered >= 0.88  # 95 % stated; 60 cases: 0.88 is ~3 binomial s.d. below


def test_stated_u_matches_the_spread_over_twins(repeats):
    """u is neither much too small nor much too large: it is the errors' standard deviation."""
    errors, us, _ = repeats
    ratio = float(np.std(errors)) / float(np.sqrt(np.mean(us**2)))
    assert 0.7 < ratio < 1.4


def test_head_0_is_the_reference_and_the_json_carries_U():
    _, r = _run(3)
    d = r.to_dict()
    assert d["head_offsets_arcsec_u"][0] == 0.0
    assert d["k"]["head_offsets_arcsec"] == pytest.approx(2.776, abs=1e-3)  # t_95(4), 5 revs
    assert d["head_offsets_arcsec_U"] == pytest.approx(
        [d["k"]["head_offsets_arcsec"] * u for u in d["head_offsets_arcsec_u"]]
    )


def test_one_revolution_has_no_placement_uncertainty():
    _, r = _run(0, revolutions=1.3)
    assert r.revolutions_used == 1
    assert r.head_offsets_arcsec_u is None and r.to_dict()["head_offsets_arcsec_U"] is None
