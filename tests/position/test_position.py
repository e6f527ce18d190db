"""rotacal.position against values that do not come from it: ISO 230-2 by hand, the twin's truth
(harmonics, reversal, noise, polygon face errors, graduation), and the refusals."""

from __future__ import annotations

import math
import statistics

import numpy as np
import pytest

from rotacal.errors import CaptureError, ConfigError
from rotacal.position import fit_harmonics, position_accuracy, selfcal_correction
from rotacal.sim.position import harmonic_curve_arcsec, simulate_position
from rotacal.uncertainty.coverage import coverage_factor


def analyse(cap, **kw):
    c = cap.columns
    return position_accuracy(
        c["position_deg"],
        reference_deg=c.get("reference_deg"),
        error_arcsec=c.get("error_arcsec"),
        run=c["run"],
        direction=c["direction"],
        face=c.get("face"),
        **kw,
    )


def amplitudes(truth):
    return np.array([h["amplitude_arcsec"] for h in truth["harmonics"]])


@pytest.fixture(scope="module")
def encoder_twin():
    cap = simulate_position(seed=3)
    return cap, analyse(cap)


# ----------------------------------------------------------------------------- ISO 230-2 by hand
def test_iso230_values_equal_a_hand_evaluation_of_the_definitions():
    # 3 positions, 3 runs, both directions: the definitions evaluated with the statistics module
    up = {0.0: [1.0, 2.0, 1.5], 120.0: [-3.0, -2.0, -2.6], 240.0: [4.0, 4.4, 3.9]}
    down = {0.0: [0.2, 0.9, 0.4], 120.0: [-4.0, -3.1, -3.3], 240.0: [2.9, 3.6, 3.0]}
    pos, err, run, dirn = [], [], [], []
    for sign, table in ((1, up), (-1, down)):
        for p, xs in table.items():
            for j, x in enumerate(xs):
                pos.append(p), err.append(x), run.append(j), dirn.append(sign)
    r = position_accuracy(pos, error_arcsec=err, run=run, direction=dirn, harmonics=0).to_dict()
    m_up = {p: statistics.fmean(v) for p, v in up.items()}
    m_dn = {p: statistics.fmean(v) for p, v in down.items()}
    s_up = {p: statistics.stdev(v) for p, v in up.items()}
    s_dn = {p: statistics.stdev(v) for p, v in down.items()}
    b = {p: m_up[p] - m_dn[p] for p in up}
    bidir = {p: (m_up[p] + m_dn[p]) / 2 for p in up}
    expect = {
        "systematic_deviation_forward": max(m_up.values()) - min(m_up.values()),
        "systematic_deviation_bidirectional": max([*m_up.values(), *m_dn.values()])
        - min([*m_up.values(), *m_dn.values()]),
        "mean_deviation_range": max(bidir.values()) - min(bidir.values()),
        "reversal_value": max(abs(v) for v in b.values()),
        "reversal_value_mean": statistics.fmean(b.values()),
        "repeatability_forward": 4 * max(s_up.values()),
        "repeatability_reverse": 4 * max(s_dn.values()),
        "repeatability_bidirectional": max(
            max(2 * s_up[p] + 2 * s_dn[p] + abs(b[p]), 4 * s_up[p], 4 * s_dn[p]) for p in up
        ),
        "positioning_accuracy_forward": max(m_up[p] + 2 * s_up[p] for p in up)
        - min(m_up[p] - 2 * s_up[p] for p in up),
        "positioning_accuracy_bidirectional": max(
            max(m_up[p] + 2 * s_up[p], m_dn[p] + 2 * s_dn[p]) for p in up
        )
        - min(min(m_up[p] - 2 * s_up[p], m_dn[p] - 2 * s_dn[p]) for p in up),
    }
    for name, value in expect.items():
        assert r[f"{name}_arcsec"] == pytest.approx(value, abs=1e-12), name
        assert r[f"{name}_arcsec_u"] > 0, name
    assert r["error_curve_arcsec"] == pytest.approx(list(bidir.values()), abs=1e-12)
    assert r["error_pp_arcsec"] == pytest.approx(expect["mean_deviation_range"], abs=1e-12)


# --------------------------------------------------------------------------- the encoder twin
def test_harmonics_reversal_and_curve_against_the_twin(encoder_twin):
    cap, r = encoder_twin
    d, t = r.to_dict(), cap.truth
    amp = np.array(d["harmonic_amplitudes_arcsec"])
    assert np.all(np.abs(amp - amplitudes(t)) < 3 * np.array(d["harmonic_amplitudes_arcsec_u"]))
    phase = np.array([h["phase_deg"] for h in t["harmonics"]])
    dphi = (np.array(d["harmonic_phases_deg"]) - phase + 180) % 360 - 180
    assert np.all(np.abs(dphi) < 3 * np.array(d["harmonic_phases_deg_u"]))
    err = np.array(d["error_curve_arcsec"]) - t["error_curve_arcsec"]
    assert np.all(np.abs(err) < 3.5 * np.array(d["error_curve_arcsec_u"]))
    assert (
        abs(d["reversal_value_mean_arcsec"] - t["reversal_arcsec"])
        < 3 * d["reversal_value_mean_arcsec_u"]
    )
    assert abs(d["error_pp_arcsec"] - t["error_pp_arcsec"]) < 3 * d["error_pp_arcsec_u"]


def test_repeatability_is_the_spread_of_the_twins_own_noise(encoder_twin):
    cap, r = encoder_twin
    # each s_i is the standard deviation of the noise the twin drew at that position and sense
    noise = np.asarray(cap.truth["noise_per_row_arcsec"]).reshape(2, cap.truth["runs"], -1)
    assert r.by_direction(1, "std") == pytest.approx(noise[0].std(axis=0, ddof=1), abs=1e-6)
    assert r.by_direction(-1, "std") == pytest.approx(noise[1].std(axis=0, ddof=1), abs=1e-6)
    d = r.to_dict()
    s, u = d["repeatability_pooled_std_arcsec"], d["repeatability_pooled_std_arcsec_u"]
    assert abs(s - cap.truth["noise_arcsec"]) < 3 * u


def test_stated_uncertainties_match_the_spread_over_twin_repeats():
    z_amp, z_face = [], []
    for seed in range(30):
        cap = simulate_position(seed=100 + seed, noise_arcsec=0.5)
        d = analyse(cap).to_dict()
        z_amp += list(
            (np.array(d["harmonic_amplitudes_arcsec"]) - amplitudes(cap.truth))
            / d["harmonic_amplitudes_arcsec_u"]
        )
        cap = simulate_position(seed=seed, reference="polygon", positions=12, runs=4)
        d = analyse(cap, polygon_faces=12, harmonics=3).to_dict()
        z_face += list(
            (np.array(d["polygon_face_errors_arcsec"]) - cap.truth["face_errors_arcsec"])
            / d["polygon_face_errors_arcsec_u"]
        )
    assert 0.7 < np.std(z_amp) < 1.35
    assert 0.75 < np.std(z_face) < 1.3


def test_effective_dof_is_welch_satterthwaite():
    """Closed forms of GUM G.2b: one scatter component keeps its ν; an equal exactly known part
    beside it quadruples ν; two equal components of ν each give 2ν; no scatter gives ∞."""
    from rotacal.position.iso230 import scatter_dof

    assert scatter_dof(2.0, [4.0], 4) == pytest.approx(4.0)
    assert scatter_dof(math.sqrt(8.0), [4.0], 4) == pytest.approx(16.0)
    assert scatter_dof(math.sqrt(8.0), [4.0, 4.0], 4) == pytest.approx(8.0)
    assert scatter_dof(1.0, [0.0], 4) == math.inf
    assert scatter_dof(math.nan, [1.0], 4) is None


def test_the_reversal_value_covers_its_truth_95_percent_with_its_effective_dof():
    """ISO 230-2's five runs at one position: B̄ = x̄↑ − x̄↓ holds two scatter estimates of ν = 4
    each, so Welch–Satterthwaite gives 4 ≤ ν_eff ≤ 8, and U = t₉₅(ν_eff)·u covers the true
    reversal in 95 % of 4000 repeats (binomial σ 0.34 %; Welch's interval is a little
    conservative when the two variances are equal, as here), where U = 2u covers ~92 %
    (P(|t₈| ≤ 2) = 0.919)."""
    from rotacal.position.iso230 import axis_statistics

    rng = np.random.default_rng(8)
    true_b = 1.5
    inside_k, inside_2 = 0, 0
    repeats = 4000
    for _ in range(repeats):
        x = rng.normal(0.0, 0.8, size=(2, 5, 1))
        x[0] += true_b
        st = axis_statistics(x, np.zeros(1))
        b, u = st.values["reversal_value_mean"], st.values_u["reversal_value_mean"]
        k = coverage_factor(st.values_dof["reversal_value_mean"])
        inside_k += abs(b - true_b) <= k * u
        inside_2 += abs(b - true_b) <= 2.0 * u
    assert 0.945 <= inside_k / repeats <= 0.97
    assert inside_2 / repeats < 0.935


# -------------------------------------------------------------------------------- the polygon
def test_polygon_face_errors_separated_by_closure():
    cap = simulate_position(seed=5, reference="polygon", positions=12, runs=6)
    r = analyse(cap, polygon_faces=12, harmonics=3)
    d, t = r.to_dict(), cap.truth
    assert d["polygon_separated"] and d["polygon_unresolved_orders"] == []
    assert d["polygon_shifts"] == [0, 1, 2, 3, 4, 5]
    f = np.array(d["polygon_face_errors_arcsec"])
    assert np.all(
        np.abs(f - t["face_errors_arcsec"]) < 3.5 * np.array(d["polygon_face_errors_arcsec_u"])
    )
    err = np.array(d["error_curve_arcsec"]) - t["error_curve_arcsec"]
    assert np.all(np.abs(err - err.mean()) < 3.5 * np.array(d["error_curve_arcsec_u"]))
    assert (
        abs(d["repeatability_pooled_std_arcsec"] - t["noise_arcsec"])
        < 3 * d["repeatability_pooled_std_arcsec_u"]
    )
    # the same readings without the turns named cannot separate: the face errors stay in e(θ)
    fixed = position_accuracy(
        cap.columns["position_deg"],
        error_arcsec=cap.columns["error_arcsec"],
        run=cap.columns["run"],
        direction=cap.columns["direction"],
        polygon_faces=12,
        harmonics=3,
    )
    assert fixed.to_dict()["polygon_separated"] is False
    assert any("cannot be separated" in w for w in fixed.warnings)
    assert not np.any(fixed.to_dict()["polygon_face_errors_arcsec"])


def test_a_certificates_face_errors_correct_a_polygon_never_turned():
    cap = simulate_position(seed=6, reference="polygon", positions=12, runs=5, polygon_step_faces=0)
    t = cap.truth
    r = analyse(
        cap,
        polygon_faces=12,
        harmonics=3,
        polygon_face_errors_arcsec=t["face_errors_arcsec"],
        polygon_face_u_arcsec=0.02,
    )
    d = r.to_dict()
    assert d["polygon_face_errors_source"] == "stated" and not r.warnings
    err = np.array(d["error_curve_arcsec"]) - t["error_curve_arcsec"]
    assert np.all(np.abs(err - err.mean()) < 3.5 * np.array(d["error_curve_arcsec_u"]))
    with pytest.raises(ConfigError, match="give 12 finite values below one turn"):
        analyse(cap, polygon_faces=12, polygon_face_errors_arcsec=[0.0] * 11)


def test_polygon_turned_by_two_faces_leaves_order_six_inseparable():
    cap = simulate_position(
        seed=2, reference="polygon", positions=12, runs=4, polygon_step_faces=2, noise_arcsec=0.0
    )
    d = analyse(cap, polygon_faces=12, harmonics=3).to_dict()
    assert d["polygon_unresolved_orders"] == [6] and not d["polygon_separated"]
    f = np.array(d["polygon_face_errors_arcsec"])
    truth = np.asarray(cap.truth["face_errors_arcsec"])
    alt = np.cos(np.pi * np.arange(12))  # order 6: +1, −1, … at the faces
    assert f @ alt == pytest.approx(0.0, abs=1e-9)  # counted as the table's
    resolved = truth - (truth @ alt) / 12 * alt
    assert f == pytest.approx(resolved, abs=1e-9)  # every other order exact (noise-free)


# ------------------------------------------------------------------ the self-calibrated encoder
def test_selfcal_curve_corrects_the_reference_encoder():
    grad = [(1, 15.0, 20.0), (2, 4.0, 70.0)]
    cap = simulate_position(seed=9, graduation=grad, graduation_lines=3600)
    plain = analyse(cap).to_dict()
    amp_plain = np.array(plain["harmonic_amplitudes_arcsec"]) - amplitudes(cap.truth)
    assert np.abs(amp_plain[0]) > 10 * plain["harmonic_amplitudes_arcsec_u"][0]  # can fail
    selfcal = dict(cap.truth["selfcal"], deviation_u_arcsec=0.05, heads=12)
    # line 0 of the self-calibration sits at reading 90°: its curve is rolled by 900 lines
    rolled = dict(selfcal, deviation_arcsec=np.roll(selfcal["deviation_arcsec"], -900))
    for sc, zero in ((selfcal, 0.0), (rolled, 90.0)):
        d = analyse(cap, selfcal=sc, selfcal_zero_deg=zero).to_dict()
        amp = np.array(d["harmonic_amplitudes_arcsec"])
        assert np.all(
            np.abs(amp - amplitudes(cap.truth)) < 3 * np.array(d["harmonic_amplitudes_arcsec_u"])
        )
        assert d["reference"] == "self-calibrated encoder"
        assert d["reference_u_arcsec"] == pytest.approx(0.05)


def test_a_real_self_calibration_serves_as_reference():
    """The pulse twin's encoder self-calibrated by rotacal's own `selfcal`, then used to read a
    table whose encoder carries the same graduation error: the table's harmonics come out."""
    from rotacal.encoder.selfcal import self_calibrate
    from rotacal.sim import simulate_pulses

    scale = ((1, 15.0, 0.3), (2, 4.0, 1.1))  # A·cos(hθ + φ), φ in rad
    pulses = simulate_pulses(
        heads=4, pulses_per_rev=360, revolutions=3, harmonics=scale, graduation_noise_arcsec=0.0
    )
    heads = [pulses.columns[f"head_{i}"] for i in range(4)]
    selfcal = self_calibrate(heads, pulses_per_rev=360).to_dict()
    zero = pulses.truth["first_line_head0"] * 1.0  # line 0 of the curve is the first pulse's
    grad = [(h, a, -np.rad2deg(p)) for h, a, p in scale]
    cap = simulate_position(seed=4, graduation=grad, graduation_lines=360)
    d = analyse(cap, selfcal=selfcal, selfcal_zero_deg=zero).to_dict()
    amp = np.array(d["harmonic_amplitudes_arcsec"])
    assert np.all(
        np.abs(amp - amplitudes(cap.truth)) < 3 * np.array(d["harmonic_amplitudes_arcsec_u"])
    )
    wrong = analyse(cap, selfcal=selfcal, selfcal_zero_deg=zero + 90.0).to_dict()
    assert (
        abs(wrong["harmonic_amplitudes_arcsec"][0] - 6.0)
        > 10 * wrong["harmonic_amplitudes_arcsec_u"][0]
    )


def test_selfcal_correction_interpolates_the_definition():
    m = 8
    dev = np.array([0.0, 1.0, 3.0, 2.0, -1.0, -2.0, -3.0, 0.0])
    c = selfcal_correction([0.0, 45.0, 67.5, 337.5], {"deviation_arcsec": dev}).correction_arcsec
    # reading j·360/m → deviation[j] − deviation[0]; halfway between lines → the mean of both
    assert c == pytest.approx([0.0, 1.0, 2.0, 0.0])
    with pytest.raises(ConfigError, match="pulses_per_rev"):
        selfcal_correction([0.0], {"deviation_arcsec": dev, "pulses_per_rev": m + 1})


def test_harmonic_fit_is_exact_on_a_noise_free_curve():
    th = np.arange(16) * 22.5
    y = 2.0 + harmonic_curve_arcsec(th, [(1, 3.0, 40.0), (3, 1.0, -20.0)])
    fit = fit_harmonics(th, y, 4)
    assert fit.amplitudes_arcsec == pytest.approx([3.0, 0.0, 1.0, 0.0], abs=1e-12)
    assert fit.phases_deg[[0, 2]] == pytest.approx([40.0, -20.0], abs=1e-9)
    assert fit.mean_arcsec == pytest.approx(2.0) and fit.residual_rms_arcsec < 1e-12


def test_harmonic_effective_dof_is_welch_satterthwaite():
    """The fit's residual variance s² has P − 2H − 1 degrees of freedom; a reference u equal to
    s at every position makes each u² half residual, so ν_eff = 4·(P − 2H − 1) (GUM G.2b)."""
    th = np.arange(16) * 22.5
    y = harmonic_curve_arcsec(th, [(1, 3.0, 40.0)]) + np.random.default_rng(2).normal(0, 0.4, 16)
    alone = fit_harmonics(th, y, 2)
    assert alone.dof == 11 and alone.effective_dof == pytest.approx(11.0)
    assert alone.coverage_k == pytest.approx(coverage_factor(11))
    s = alone.residual_rms_arcsec * math.sqrt(16 / 11)  # residual rms is over P, s² over P − 2H − 1
    with_ref = fit_harmonics(th, y, 2, u_ref_arcsec=np.full(16, s))
    assert with_ref.effective_dof == pytest.approx(44.0)
    curve = harmonic_curve_arcsec(th, [(1, 3.0, 40.0)])  # no residual: the reference's u alone
    assert fit_harmonics(th, curve, 2, u_ref_arcsec=np.full(16, 0.1)).effective_dof > 1e6


# ------------------------------------------------------------------------------------ refusals
def test_too_few_positions_for_the_harmonics_asked():
    cap = simulate_position(seed=1, positions=8, runs=2)
    with pytest.raises(
        ConfigError, match=r"--harmonics 4 needs at least 10 distinct positions.*at most 3"
    ):
        analyse(cap, harmonics=4)
    arc = np.arange(12) * 5.0  # all within 55°: the orders are not determined
    with pytest.raises(ConfigError, match="do not determine harmonics"):
        fit_harmonics(arc, np.zeros(12), 3)


def test_polygon_positions_must_cover_360_degrees():
    cap = simulate_position(seed=1, reference="polygon", positions=12, runs=2)
    keep = cap.columns["position_deg"] < 300.0
    cols = {k: v[keep] for k, v in cap.columns.items()}
    with pytest.raises(CaptureError, match=r"12 positions k·30° covering 360°.*misses 300°, 330°"):
        position_accuracy(
            cols["position_deg"], error_arcsec=cols["error_arcsec"], run=cols["run"],
            direction=cols["direction"], polygon_faces=12,
        )  # fmt: skip


def test_runs_with_different_position_sets_are_refused():
    pos = [0, 90, 180, 270, 0, 90, 180, 270]
    run = [0, 0, 0, 0, 1, 1, 1, 1]
    with pytest.raises(
        CaptureError,
        match=r"run 1 in direction \+1 has no reading at 180° and readings at 45° that the others lack",
    ):
        position_accuracy([*pos[:6], 45, 270], error_arcsec=np.zeros(8), run=run, harmonics=0)
    with pytest.raises(CaptureError, match="reads position 90° 2 times"):
        position_accuracy([*pos[:6], 90, 270], error_arcsec=np.zeros(8), run=run, harmonics=0)
    with pytest.raises(CaptureError, match="direction: row 2"):
        position_accuracy(pos, error_arcsec=np.zeros(8), direction=[1, 1, 0, 1, 1, 1, 1, 1])


def test_one_run_gives_no_repeatability_and_says_so():
    r = position_accuracy(np.arange(12) * 30.0, error_arcsec=np.sin(np.arange(12)), harmonics=2)
    d = r.to_dict()
    assert (
        d["repeatability_forward_arcsec"] is None
        and d["positioning_accuracy_forward_arcsec"] is None
    )
    assert d["reversal_value_arcsec"] is None
    assert any("one run" in w for w in r.warnings)
    assert math.isfinite(d["error_pp_arcsec"]) and d["error_pp_arcsec_u"] is None


def test_values_no_table_can_give_are_refused():
    pos = np.arange(8) * 45.0
    with pytest.raises(CaptureError, match="error_arcsec"):
        position_accuracy(pos, error_arcsec=np.r_[np.zeros(7), 1e300], harmonics=0)
    with pytest.raises(CaptureError, match="position_deg"):
        position_accuracy(np.r_[pos[:7], 1e12], error_arcsec=np.zeros(8), harmonics=0)
    with pytest.raises(ConfigError, match="--reference-u-arcsec nan"):
        position_accuracy(pos, error_arcsec=np.zeros(8), reference_u_arcsec=math.nan)
    with pytest.raises(ConfigError, match="--selfcal-zero-deg nan"):
        selfcal_correction(pos, {"deviation_arcsec": [0.0, 1.0]}, zero_deg=math.nan)
    with pytest.raises(ConfigError, match=r"reference_deg.*or.*error_arcsec"):
        position_accuracy(pos, reference_deg=pos, error_arcsec=np.zeros(8))
