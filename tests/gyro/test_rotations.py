"""Gyro-triad calibration from rotations through known angles: twin, imucal's real recordings."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import numpy as np
import pytest

from rotacal.errors import CaptureError, ConfigError
from rotacal.gyro.rotations import calibrate_triad_rotations, ferraris_sections
from rotacal.sim.gyro_triad import simulate_gyro_rotations

G = 9.81  # imucal's default gravity (m/s²), used in its K_ga

K_TRUE = np.array(
    [
        [1.0210, 0.0062, -0.0044],
        [-0.0038, 0.9870, 0.0051],
        [0.0073, -0.0029, 1.0090],
    ]
)
B_TRUE = np.array([-0.61, 0.35, 0.07])


def _rate(cap):
    return np.column_stack([cap.columns["ux"], cap.columns["uy"], cap.columns["uz"]])


# ------------------------------------------------------------------------------------ twin
def test_noise_free_twin_gives_the_truth() -> None:
    cap = simulate_gyro_rotations(K=K_TRUE, bias=B_TRUE, noise_std=0.0)
    t = cap.truth
    r = calibrate_triad_rotations(_rate(cap), 100.0, t["rotations"], static=t["static"])
    np.testing.assert_allclose(r.scale_misalignment, K_TRUE, atol=1e-12)
    np.testing.assert_allclose(r.bias, B_TRUE, atol=1e-12)
    for rot in r.rotations:
        np.testing.assert_allclose(rot["angle_residual_deg"], 0.0, atol=1e-9)
    assert r.residual_rms < 1e-9


def test_negative_angles_and_raw_counts() -> None:
    """imucal's convention: a 'clockwise' turn is −360°; K comes out in counts per °/s."""
    gain = 16.4
    cap = simulate_gyro_rotations(
        K=-gain * K_TRUE, bias=gain * B_TRUE, angle_deg=-360.0, noise_std=0.0, fs_hz=204.8
    )
    t = cap.truth
    r = calibrate_triad_rotations(
        _rate(cap), 204.8, t["rotations"], static=t["static"], angle_deg=-360.0
    )
    np.testing.assert_allclose(r.scale_misalignment, -gain * K_TRUE, rtol=1e-11)
    np.testing.assert_allclose(r.scale_factors, gain * np.linalg.norm(K_TRUE, axis=1), rtol=1e-11)
    assert np.all(np.diag(r.sensitive_axes) < 0)


@pytest.mark.parametrize("seed", range(4))
def test_noisy_twin_within_its_uncertainty(seed: int) -> None:
    cap = simulate_gyro_rotations(K=K_TRUE, bias=B_TRUE, noise_std=0.1, seed=seed)
    t = cap.truth
    r = calibrate_triad_rotations(_rate(cap), 100.0, t["rotations"], static=t["static"])
    assert np.all(np.abs(r.scale_misalignment - K_TRUE) < 4.5 * r.scale_misalignment_u)
    assert np.all(np.abs(r.bias - B_TRUE) < 4.5 * r.bias_u)
    np.testing.assert_allclose(r.noise_std, 0.1, rtol=0.05)


def test_uncertainty_matches_the_scatter_over_many_twins() -> None:
    z = []
    for seed in range(120):
        cap = simulate_gyro_rotations(
            K=K_TRUE,
            bias=B_TRUE,
            noise_std=0.2,
            seed=100 + seed,
            static_s=2.0,
            rotation_s=3.0,
            margin_s=0.3,
        )
        t = cap.truth
        r = calibrate_triad_rotations(_rate(cap), 100.0, t["rotations"], static=t["static"])
        z.append((r.scale_misalignment - K_TRUE) / r.scale_misalignment_u)
    s = float(np.std(z))
    assert 0.85 < s < 1.15, s  # 120×9 normalised errors: std 1 within sampling


def test_more_rotations_by_least_squares_and_oblique_axes() -> None:
    """Both directions about each axis, and one about an oblique axis, combined by least squares."""
    fs = 100.0
    a = simulate_gyro_rotations(K=K_TRUE, bias=B_TRUE, noise_std=0.0, angle_deg=360.0)
    b = simulate_gyro_rotations(K=K_TRUE, bias=B_TRUE, noise_std=0.0, angle_deg=-720.0)
    rate = np.vstack([_rate(a), _rate(b)])
    n = len(a)
    rots = [(ax, *a.truth["rotations"][ax], 360.0) for ax in "xyz"]
    rots += [(ax, s + n, e + n, -720.0) for ax, (s, e) in b.truth["rotations"].items()]
    # an oblique rotation: the same turn about z labelled by its vector
    rots.append(((0.0, 0.0, 2.0), *a.truth["rotations"]["z"], 360.0))
    static = a.truth["static"] + [[s + n, e + n] for s, e in b.truth["static"]]
    r = calibrate_triad_rotations(rate, fs, rots, static=static)
    np.testing.assert_allclose(r.scale_misalignment, K_TRUE, atol=1e-12)
    assert len(r.rotations) == 7


def test_per_sample_offsets_replace_the_static_bias() -> None:
    cap = simulate_gyro_rotations(K=K_TRUE, bias=B_TRUE, noise_std=0.0)
    t = cap.truth
    drift = np.linspace(0.0, 0.05, len(cap))[:, None] * np.array([1.0, -1.0, 0.5])
    rate = _rate(cap) + drift  # a drifting bias, known per sample
    r = calibrate_triad_rotations(rate, 100.0, t["rotations"], bias=B_TRUE + drift)
    np.testing.assert_allclose(r.scale_misalignment, K_TRUE, atol=1e-12)
    # the constant static mean cannot follow the drift: K is off
    r2 = calibrate_triad_rotations(rate, 100.0, t["rotations"], static=t["static"])
    assert np.max(np.abs(r2.scale_misalignment - K_TRUE)) > 1e-5


# ------------------------------------------------------------------------------------ bad input
def _twin_sections():
    cap = simulate_gyro_rotations(K=K_TRUE, bias=B_TRUE, noise_std=0.05)
    return _rate(cap), cap.truth


def test_bad_sections_and_settings() -> None:
    rate, t = _twin_sections()
    rot, st = t["rotations"], t["static"]
    with pytest.raises(ConfigError, match="static sections"):
        calibrate_triad_rotations(rate, 100.0, rot)
    with pytest.raises(ConfigError, match="overlaps rotation x"):
        calibrate_triad_rotations(rate, 100.0, rot, static=[rot["x"]])
    with pytest.raises(ConfigError, match="do not span"):
        calibrate_triad_rotations(rate, 100.0, {"x": rot["x"], "y": rot["y"]}, static=st)
    with pytest.raises(ConfigError, match="stop ≤"):
        calibrate_triad_rotations(rate, 100.0, {**rot, "z": (0, len(rate) + 5)}, static=st)
    with pytest.raises(ConfigError, match="fs_hz"):
        calibrate_triad_rotations(rate, 0.0, rot, static=st)
    with pytest.raises(ConfigError, match="axis"):
        calibrate_triad_rotations(rate, 100.0, [("q", 0, 10)], static=st)
    with pytest.raises(ConfigError, match="z_rot"):
        ferraris_sections({"x_p": (0, 10)})


def test_nan_and_saturation_in_a_rotation() -> None:
    rate, t = _twin_sections()
    s, _ = t["rotations"]["y"]
    bad = rate.copy()
    bad[s + 40, 2] = np.nan
    with pytest.raises(CaptureError, match=f"uz has a non-finite value at row {s + 40}"):
        calibrate_triad_rotations(bad, 100.0, t["rotations"], static=t["static"])
    # peak rate 2·360/4 = 180 °/s: a ±150 °/s gyro clips every turn
    cap = simulate_gyro_rotations(K=K_TRUE, bias=B_TRUE, noise_std=0.05, output_limit=150.0)
    with pytest.raises(CaptureError, match="saturated") as exc:
        calibrate_triad_rotations(
            _rate(cap), 100.0, cap.truth["rotations"], static=cap.truth["static"]
        )
    assert "\n" not in str(exc.value)


# ------------------------------------------------------------------------------------ real data
def _imucal_reference(path: Path) -> dict[str, np.ndarray]:
    ref = json.loads(path.read_text())
    return {
        k: np.asarray(ref[k], dtype=float)
        for k in ("K_a", "R_a", "b_a", "K_g", "R_g", "K_ga", "b_g")
    }


def _imucal_offsets(acc: np.ndarray, ref: dict[str, np.ndarray]) -> np.ndarray:
    """imucal's per-sample gyro offset b_g + K_ga·a, with a its calibrated acceleration
    (R_a⁻¹·K_a⁻¹·(acc − b_a)): its published numbers, in its own model."""
    a_cal = np.linalg.solve(ref["K_a"] @ ref["R_a"], (acc - ref["b_a"]).T).T
    return a_cal @ ref["K_ga"].T + ref["b_g"]


def _ga_bound(
    ref: dict[str, np.ndarray], rotations: dict[str, tuple[int, int]], fs: float
) -> np.ndarray:
    """What imucal's g-sensitivity term moves K by: during the turn about j the accelerometer
    reads ≈ g along j, so imucal removes K_ga[:, j]·g for T_j seconds more than the static
    mean does, i.e. |ΔK_ij| ≈ |K_ga[i, j]|·g·T_j / 360."""
    t = np.array([(rotations[a][1] - rotations[a][0]) / fs for a in "xyz"])
    return np.abs(ref["K_ga"]) * G * t[None, :] / 360.0


def _load_session_102(imucal: Path) -> tuple[np.ndarray, np.ndarray, dict, dict]:
    data = np.loadtxt(
        imucal / "example_data" / "example_ferraris_session.csv", delimiter=",", skiprows=1
    )
    sections = json.loads(
        (imucal / "example_data" / "example_ferraris_session_list.json").read_text()
    )
    return data[:, 1:4], data[:, 4:7], *ferraris_sections(sections)


def _load_session_204(imucal: Path) -> tuple[np.ndarray, np.ndarray, dict, dict]:
    with open(imucal / "example_data" / "annotated_session.csv", newline="") as fh:
        rows = list(csv.reader(fh))
    head = rows[0]
    parts = np.array([r[0] for r in rows[1:]])
    vals = np.array([[float(x) for x in r[1:]] for r in rows[1:]])
    cols = {name: vals[:, i - 1] for i, name in enumerate(head) if i > 0}
    gyr = np.column_stack([cols["gyr_x"], cols["gyr_y"], cols["gyr_z"]])
    acc = np.column_stack([cols["acc_x"], cols["acc_y"], cols["acc_z"]])
    sections = {}
    for name in dict.fromkeys(parts):
        idx = np.flatnonzero(parts == name)
        assert np.all(np.diff(idx) == 1)  # each section is one contiguous block
        sections[str(name)] = (int(idx[0]), int(idx[-1]) + 1)
    return gyr, acc, *ferraris_sections(sections)


SESSIONS = [
    (
        "102.4 Hz, °/s",
        _load_session_102,
        102.4,
        "example_ferraris_session_cal_computed_imucal2.6.0.json",
    ),
    ("204.8 Hz, counts", _load_session_204, 204.8, "tests/snapshots/example_cal.json"),
]


@pytest.mark.parametrize(("name", "load", "fs", "ref_file"), SESSIONS, ids=[s[0] for s in SESSIONS])
def test_real_recordings_agree_with_imucal(name, load, fs, ref_file, shared_data) -> None:
    imucal = shared_data("imucal")
    gyr, acc, rotations, static = load(imucal)
    ref = _imucal_reference(imucal / ref_file)
    k_imucal = ref["K_g"] @ ref["R_g"]

    r = calibrate_triad_rotations(gyr, fs, rotations, static=static, angle_deg=-360.0)
    # the bias is the same pooled mean of the six static sections
    np.testing.assert_allclose(r.bias, ref["b_g"], rtol=1e-12, atol=1e-12)
    # K differs only by imucal's g-sensitivity term, which rotacal does not model (25 % margin
    # for the accelerometer's reading not being exactly g along the axis during a hand-made turn)
    diff = np.abs(r.scale_misalignment - k_imucal)
    assert np.all(diff <= 1.25 * _ga_bound(ref, rotations, fs) + 1e-6 * np.abs(k_imucal).max())
    scale = np.abs(np.diag(k_imucal)).min()
    assert diff.max() / scale < {102.4: 6e-5, 204.8: 2.5e-4}[fs]
    # and within its own stated uncertainty, which holds the spread of the static means
    assert np.all(diff < 3 * r.scale_misalignment_u)

    # with imucal's own per-sample offset b_g + K_ga·a, rotacal gives imucal's K to rounding
    r2 = calibrate_triad_rotations(
        gyr, fs, rotations, bias=_imucal_offsets(acc, ref), angle_deg=-360.0
    )
    np.testing.assert_allclose(r2.scale_misalignment, k_imucal, rtol=0, atol=1e-10 * scale)
    np.testing.assert_allclose(r2.scale_factors, np.diag(ref["K_g"]), rtol=1e-10)
    np.testing.assert_allclose(r2.sensitive_axes, ref["R_g"], atol=1e-10)


# ------------------------------------------------------------------------------------ plausibility
def test_default_angle_is_the_ferraris_clockwise_turn_and_a_wrong_sign_warns() -> None:
    cap = simulate_gyro_rotations(K=K_TRUE, bias=B_TRUE, noise_std=0.05)
    assert cap.truth["angle_deg"] == -360.0
    t = cap.truth
    r = calibrate_triad_rotations(_rate(cap), 100.0, t["rotations"], static=t["static"])
    assert r.warnings == ()
    np.testing.assert_allclose(r.scale_misalignment, K_TRUE, atol=5e-3)
    # the same recording taken as counter-clockwise turns: K flips sign, and each axis is named
    flipped = calibrate_triad_rotations(
        _rate(cap), 100.0, t["rotations"], static=t["static"], angle_deg=360.0
    )
    np.testing.assert_allclose(flipped.scale_misalignment, -r.scale_misalignment, rtol=1e-12)
    assert len(flipped.warnings) == 3
    for axis, line in zip("xyz", flipped.warnings, strict=True):
        assert f"K_{axis}{axis} = -" in line and "--angle-deg" in line


def test_a_section_cut_while_turning_warns() -> None:
    cap = simulate_gyro_rotations(K=K_TRUE, bias=B_TRUE, noise_std=0.05)
    t = cap.truth
    s, e = t["motion"]["y"]
    cut = {**t["rotations"], "y": [s + (e - s) // 4, e + 10]}  # starts a quarter into the turn
    r = calibrate_triad_rotations(_rate(cap), 100.0, cut, static=t["static"])
    assert len(r.warnings) == 1
    assert "about y" in r.warnings[0] and "starts while turning" in r.warnings[0]


def test_rotations_that_disagree_are_a_lack_of_fit() -> None:
    """Six rotations, one of them 3° short of the angle set: χ² of the angle residuals."""
    a = simulate_gyro_rotations(K=K_TRUE, bias=B_TRUE, noise_std=0.05, seed=1)
    b = simulate_gyro_rotations(K=K_TRUE, bias=B_TRUE, noise_std=0.05, seed=2)
    short = simulate_gyro_rotations(
        K=K_TRUE, bias=B_TRUE, noise_std=0.05, seed=2, angle_error_deg=(0.0, 0.0, 3.0)
    )
    n = len(a)

    def both(second):
        rate = np.vstack([_rate(a), _rate(second)])
        rots = [(ax, *a.truth["rotations"][ax]) for ax in "xyz"]
        rots += [(ax, s + n, e + n) for ax, (s, e) in second.truth["rotations"].items()]
        static = a.truth["static"] + [[s + n, e + n] for s, e in second.truth["static"]]
        return calibrate_triad_rotations(rate, 100.0, rots, static=static)

    assert both(b).warnings == ()
    bad = both(short).warnings
    assert len(bad) == 1 and bad[0].startswith("lack of fit: K·φ through the rotations")


def test_real_recording_with_the_default_convention_agrees_with_imucal(shared_data) -> None:
    """imucal's own recording, its convention by default: K_g, b_g and R_g as imucal prints
    them, to the g-sensitivity term imucal removes and rotacal does not (< 1 u)."""
    imucal = shared_data("imucal")
    gyr, _, rotations, static = _load_session_102(imucal)
    ref = _imucal_reference(imucal / "example_ferraris_session_cal_computed_imucal2.6.0.json")
    r = calibrate_triad_rotations(gyr, 102.4, rotations, static=static)
    assert r.warnings == ()
    assert np.all(np.diag(r.scale_misalignment) > 0)
    np.testing.assert_allclose(r.scale_factors, np.diag(ref["K_g"]), rtol=5e-5)
    assert np.all(np.abs(r.scale_factors - np.diag(ref["K_g"])) < np.diag(r.scale_misalignment_u))
    np.testing.assert_allclose(r.bias, ref["b_g"], rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(r.sensitive_axes, ref["R_g"], atol=1e-4)
    mis_imucal = np.degrees(np.arccos(np.abs(np.diag(ref["R_g"]))))
    np.testing.assert_allclose(r.misalignment_deg, mis_imucal, atol=5e-3)
