"""`rotacal gyro rotations` with the accelerometer and `rotacal gyro accelerometer`, end to end on a
Ferraris twin and on imucal's recording; refusals in one line."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from .test_gyro_cli import one_line_error, run

ACC = ("--column", "acc_x=ax", "--column", "acc_y=ay", "--column", "acc_z=az")
GYR = ("--column", "gyr_x=ux", "--column", "gyr_y=uy", "--column", "gyr_z=uz")


@pytest.fixture(scope="module")
def session(tmp_path_factory) -> tuple[Path, dict]:
    path = tmp_path_factory.mktemp("ferraris") / "session.csv"
    r = run("simulate", "ferraris", "--out", str(path), "--latitude-deg", "49.6")
    assert r.exit_code == 0, r.output
    return path, json.loads(Path(f"{path}.truth.json").read_text())


def _within(d: dict, key: str, truth, factor: float = 2.0) -> None:
    err = np.abs(np.asarray(d[key]) - np.asarray(truth))
    assert np.all(err <= factor * np.asarray(d[f"{key}_U"])), (key, err, d[f"{key}_U"])


def test_rotations_separate_gravity_and_the_earth_rate(session) -> None:
    path, truth = session
    sec = f"{path}.truth.json"
    r = run(
        "gyro", "rotations", str(path), "--sections", sec, "--latitude-deg", "49.6",
        "--output-unit", "deg/s", "--json", "-",
    )  # fmt: skip
    assert r.exit_code == 0, r.stderr
    d = json.loads(r.stdout)
    _within(d, "scale_misalignment", truth["scale_misalignment"])
    _within(d, "g_sensitivity", truth["g_sensitivity"])
    _within(d, "bias", truth["bias"])
    assert d["latitude_deg"] == 49.6 and d["warnings"] == []
    assert d["accelerometer"]["gravity_m_s2"] == truth["gravity_m_s2"]

    r = run("gyro", "accelerometer", str(path), "--sections", sec, "--latitude-deg", "49.6")
    assert r.exit_code == 0, r.stderr
    assert "9.810345 m/s²" in r.stdout  # the normal gravity at 49.6°, as the twin's
    r = run("gyro", "accelerometer", str(path), "--sections", sec, "--latitude-deg", "49.6",
            "--json", "-")  # fmt: skip
    d = json.loads(r.stdout)
    _within(d, "scale_misalignment", truth["acc_scale_misalignment"])
    _within(d, "bias", truth["acc_bias"])
    assert d["gravity_m_s2"] == pytest.approx(truth["gravity_m_s2"], abs=1e-12)


def test_refusals(session, tmp_path) -> None:
    path, truth = session
    secs = truth["sections"]
    bad = tmp_path / "s.json"
    bad.write_text(json.dumps({k: v for k, v in secs.items() if k != "z_p"}))
    one_line_error(run("gyro", "rotations", str(path), "--sections", str(bad)), "lacks z_p")
    one_line_error(run("gyro", "accelerometer", str(path), "--sections", str(bad)), "z_p")
    bad.write_text(json.dumps({**secs, "x_a": [secs["x_p"][1] - 5, secs["x_a"][1]]}))
    one_line_error(run("gyro", "rotations", str(path), "--sections", str(bad)), "overlap")
    s, e = secs["z_rot"]
    bad.write_text(json.dumps({**secs, "z_rot": [s, (s + e) // 2]}))
    one_line_error(
        run("gyro", "rotations", str(path), "--sections", str(bad), "--output-unit", "deg/s"),
        "not the set -360",
    )
    # the Earth rate and gravity need the accelerometer
    gyro_only = tmp_path / "rot.csv"
    assert run("simulate", "gyro-rotations", "--out", str(gyro_only)).exit_code == 0
    one_line_error(
        run(
            "gyro",
            "rotations",
            str(gyro_only),
            "--sections",
            f"{gyro_only}.truth.json",
            "--latitude-deg",
            "49.6",
        ),
        "accelerometer",
    )


def test_imucal_recording_end_to_end(shared_data) -> None:
    data = shared_data("imucal")
    ex = data / "example_data"
    r = run(
        "gyro", "rotations", str(ex / "example_ferraris_session.csv"),
        "--sections", str(ex / "example_ferraris_session_list.json"), "--fs-hz", "102.4",
        *GYR, *ACC, "--gravity-m-s2", "9.81", "--output-unit", "deg/s", "--json", "-",
    )  # fmt: skip
    assert r.exit_code == 0, r.stderr
    d = json.loads(r.stdout)
    ref = json.loads((data / "example_ferraris_session_cal_computed_imucal2.6.0.json").read_text())
    k_ref = np.asarray(ref["K_g"]) @ np.asarray(ref["R_g"])
    assert np.abs(np.asarray(d["scale_misalignment"]) - k_ref).max() < 3e-6
    np.testing.assert_allclose(d["g_sensitivity"], ref["K_ga"], rtol=1e-10)
    np.testing.assert_allclose(d["accelerometer"]["sensitive_axes"], ref["R_a"], atol=1e-12)
