"""Turntable identification (seed 001, eqs. 17–26): truth in, truth out on the twin, the separable
combinations against the closed form of eq. (26), degenerate position sets, refusals."""

from __future__ import annotations

import math

import numpy as np
import pytest

from rotacal.errors import CaptureError, ConfigError
from rotacal.sim import simulate_orientation_errors
from rotacal.turntable.identify import identify_turntable

COLUMNS = ("phi1_deg", "phi2_deg", "dpsi_arcsec", "dtheta_arcsec", "dgamma_arcsec")
#: Eq. (26): to first order the orientation error depends only on these sums (and not on η).
EQ26_SUMS = {
    "phi_y1 + eps_y",
    "phi_z2 + alpha_z1",
    "alpha_x1 + eps_x",
    "alpha_x2",
    "alpha_y2",
}


def _identify(capture, **kw):
    return identify_turntable(*(capture.columns[c] for c in COLUMNS), **kw)


def _truth(combo, truth):
    return sum(a * truth["errors_arcsec"][n] for n, a in combo["coefficients"].items())


@pytest.fixture(scope="module")
def full_grid():
    cap = simulate_orientation_errors(noise_arcsec=0.5, seed=1)
    return cap, _identify(cap, next_positions=3)


def test_separable_combinations_are_eq26_sums(full_grid):
    _, r = full_grid
    assert {c["name"] for c in r.combinations} == EQ26_SUMS
    assert r.rank == 5 and r.dof == 3 * 64 - 5
    assert set(r.unidentifiable) == {
        "phi_y1",
        "phi_z2",
        "alpha_x1",
        "alpha_z1",
        "eps_x",
        "eps_y",
        "eta",
    }
    groups = {tuple(g["names"]): g for g in r.inseparable}
    assert set(groups) == {
        ("phi_y1", "eps_y"),
        ("phi_z2", "alpha_z1"),
        ("alpha_x1", "eps_x"),
        ("eta",),
    }
    assert all(g["structural"] for g in groups.values())
    assert "position" in groups[("eta",)]["separate_by"][0]
    assert "autocollimator" in groups[("phi_y1", "eps_y")]["separate_by"][0]


def test_u_is_the_closed_form_of_a_balanced_design(full_grid):
    # φ2 every 45°: Σcos = Σsin = Σsin·cos = 0, Σcos² + Σsin² = n, so each of the five sums has
    # information n/s² and u = s/√n exactly
    _, r = full_grid
    for c in r.combinations:
        assert c["u_arcsec"] == pytest.approx(r.s_arcsec / math.sqrt(64), rel=1e-6)
    assert r.errors_u_arcsec["alpha_x2"] == pytest.approx(r.s_arcsec / 8.0, rel=1e-6)


@pytest.mark.parametrize("noise", [0.05, 0.5, 5.0])
def test_truth_within_u_at_three_noise_levels(noise):
    cap = simulate_orientation_errors(noise_arcsec=noise, seed=7, outer_steps=2, inner_steps=12)
    r = _identify(cap, next_positions=0)
    assert r.s_arcsec == pytest.approx(noise, rel=0.25)
    for c in r.combinations:
        assert abs(c["value_arcsec"] - _truth(c, cap.truth)) <= 3.0 * c["u_arcsec"], c
    for name in ("alpha_x2", "alpha_y2"):
        err = r.errors_arcsec[name] - cap.truth["errors_arcsec"][name]
        assert abs(err) <= 3.0 * r.errors_u_arcsec[name]


def test_coverage_over_seeds():
    z = []
    for seed in range(40):
        cap = simulate_orientation_errors(noise_arcsec=0.5, seed=seed, outer_steps=1, inner_steps=8)
        r = _identify(cap, next_positions=0)
        z += [(c["value_arcsec"] - _truth(c, cap.truth)) / c["U_arcsec"] for c in r.combinations]
    z = np.asarray(z)
    within = float(np.mean(np.abs(z) <= 1.0))
    assert 0.88 <= within <= 0.995, within  # 95 % stated, 200 draws
    assert 0.8 <= float(np.std(z * r.k)) <= 1.2  # (value − truth)/u has unit spread


def test_noise_free_full_model():
    # the twin's proper rotations differ from the paper's small-angle matrices by O(χ²) ≈ 1e-9 rad
    cap = simulate_orientation_errors(noise_arcsec=0.0, inner_steps=6, outer_steps=2)
    for model in ("seed", "exact"):
        r = _identify(cap, model=model, next_positions=0)
        for c in r.combinations:
            assert abs(c["value_arcsec"] - _truth(c, cap.truth)) < 2e-3
        assert r.s_arcsec < 1e-3


def test_phi2_fixed_is_flagged_and_the_design_repairs_it():
    cap = simulate_orientation_errors(noise_arcsec=0.5, inner_steps=1, outer_steps=8, seed=2)
    r = _identify(cap, next_positions=2)
    assert r.rank == 3
    assert "alpha_x2" in r.unidentifiable and "alpha_y2" in r.unidentifiable
    names = {c["name"] for c in r.combinations}
    assert names == {
        "phi_y1 + alpha_y2 + eps_y",
        "phi_z2 + alpha_z1",
        "alpha_x1 + alpha_x2 + eps_x",
    }
    for c in r.combinations:
        assert abs(c["value_arcsec"] - _truth(c, cap.truth)) <= 3.0 * c["u_arcsec"]
    design_gaps = [g for g in r.inseparable if not g["structural"]]
    assert design_gaps and "next_positions_deg" in design_gaps[0]["separate_by"][0]
    assert r.design["separable_now"] == 3 and r.design["separable_after"] == 5
    assert all(p[1] % 360 != 0 for p in r.next_positions_deg[:1])


def test_allocation_decisions():
    bounds = {"alpha_x2": 17.6, "alpha_y2": 3.95, "phi_y1": 26.8, "eps_y": 26.8}
    big = simulate_orientation_errors(noise_arcsec=0.5, seed=1, errors_arcsec={"alpha_x2": 40.0})
    r = _identify(big, bounds_arcsec=bounds, bounds_source="test", next_positions=0)
    by = {e["name"]: e for e in r.allocation["combinations"]}
    assert by["alpha_x2"]["decision"] == "outside"  # 40 ± 0.1 against 17.6
    assert by["alpha_y2"]["decision"] == "undecided"  # 4.0 ± 0.1 against 3.95
    assert by["phi_y1 + eps_y"]["decision"] == "inside"  # 14.5 against 26.8 + 26.8
    assert by["phi_y1 + eps_y"]["bound_arcsec"] == pytest.approx(53.6)
    assert by["phi_z2 + alpha_z1"]["decision"] == "no bound"
    assert r.allocation["verdict"] == "outside"


def _columns(n=8):
    a = np.arange(n) * 45.0
    return [np.zeros(n), a, np.ones(n), np.ones(n), np.ones(n)]


@pytest.mark.parametrize(
    ("edit", "needle"),
    [
        (lambda c: c[2].__setitem__(3, np.nan), "'dpsi_arcsec' has a non-finite value"),
        (lambda c: c[1].__setitem__(2, 400.0), "'phi2_deg' data row 3"),
        (lambda c: c[4].__setitem__(1, 3e4), "'dgamma_arcsec' data row 2"),
        (lambda c: c.__setitem__(3, np.ones(5)), "5 rows"),
    ],
)
def test_refusals_name_the_column(edit, needle):
    cols = _columns()
    edit(cols)
    with pytest.raises(CaptureError, match=needle):
        identify_turntable(*cols)


def test_too_few_positions():
    with pytest.raises(CaptureError, match="at least 2"):
        identify_turntable(*(c[:1] for c in _columns()))
    with pytest.raises(ConfigError, match="model"):
        identify_turntable(*_columns(), model="paper")
    with pytest.raises(ConfigError, match="rcond"):
        identify_turntable(*_columns(), rcond=1e-300)
    with pytest.raises(ConfigError, match="design step"):
        identify_turntable(*_columns(), design_step_deg=7.0)


def test_large_errors_warn_that_second_order_terms_appear():
    big = dict.fromkeys(("phi_y1", "eps_x", "alpha_z1", "eps_y"), 3000.0)  # 0.015 rad each
    cap = simulate_orientation_errors(errors_arcsec=big, noise_arcsec=0.5)
    r = _identify(cap, next_positions=0)
    assert r.rank == 5 and any("second-order" in w for w in r.warnings)
    quiet = _identify(simulate_orientation_errors(noise_arcsec=0.5), next_positions=0)
    assert quiet.warnings == ()
