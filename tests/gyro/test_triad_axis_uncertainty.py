"""U of the triad's scale factors |K_i| and misalignment angles against twins with known K."""

from __future__ import annotations

import numpy as np
import pytest

from rotacal.gyro.triad import calibrate_triad_columns, decompose_scale_misalignment
from rotacal.sim.gyro_triad import simulate_gyro_triad

K_TRUE = 10.0 * np.array([[1.02, 0.01, -0.015], [0.005, 0.98, 0.02], [-0.01, 0.012, 1.01]])


@pytest.fixture(scope="module")
def repeats():
    """30 twins with fresh noise: the errors of |K_i| and θ_i against the true K, and their u, U."""
    s_true, _, m_true = decompose_scale_misalignment(K_TRUE)
    out = {"s_err": [], "m_err": [], "s_u": [], "m_u": [], "s_U": [], "m_U": []}
    for seed in range(30):
        cap = simulate_gyro_triad(K=K_TRUE, noise_std=2.0, samples_per_point=50, seed=seed)
        d = calibrate_triad_columns(cap.columns).to_dict()
        out["s_err"].append(np.asarray(d["scale_factors"]) - s_true)
        out["m_err"].append(np.asarray(d["misalignment_deg"]) - m_true)
        for q, key in (("s", "scale_factors"), ("m", "misalignment_deg")):
            out[f"{q}_u"].append(d[f"{key}_u"])
            out[f"{q}_U"].append(d[f"{key}_U"])
    return {k: np.asarray(v) for k, v in out.items()}


@pytest.mark.parametrize("q", ["s", "m"])
def test_stated_u_is_the_spread_over_twins(repeats, q):
    z = repeats[f"{q}_err"] / repeats[f"{q}_u"]
    assert 0.75 < float(np.std(z)) < 1.3  # 90 z-scores: the sd is within ~±0.15 of 1


@pytest.mark.parametrize("q", ["s", "m"])
def test_stated_U_covers_the_true_value(repeats, q):
    covered = np.mean(np.abs(repeats[f"{q}_err"]) <= repeats[f"{q}_U"])
    assert covered >= 0.88


def test_an_aligned_axis_is_flagged_as_bounded():
    """With a perfectly aligned x gyro the angle can only be biased upward: the budget says so."""
    k = np.diag([10.0, 10.0, 10.0])
    k[1, 0] = 0.2  # y clearly misaligned
    cap = simulate_gyro_triad(K=k, noise_std=2.0, samples_per_point=50, seed=1)
    r = calibrate_triad_columns(cap.columns)
    notes_x = " ".join(r.axis_budgets["misalignment_deg[0]"].notes)
    notes_y = " ".join(r.axis_budgets["misalignment_deg[1]"].notes)
    assert "biased upward" in notes_x and "biased upward" not in notes_y
