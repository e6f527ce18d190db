"""`rotacal gyro …` and their twins: INTERFACE keys against the truth, one-line errors."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from rotacal.cli import cli


def run(*args: str):
    return CliRunner().invoke(cli, list(args), prog_name="rotacal")


def one_line_error(result, *needles):
    assert result.exit_code == 2, result.output
    err = result.stderr.strip()
    assert err.count("\n") == 0 and "Traceback" not in result.output, err
    for n in needles:
        assert n.lower() in err.lower(), err


def simulated(tmp_path: Path, kind: str, *args: str) -> tuple[Path, dict]:
    path = tmp_path / f"{kind}.npz"
    r = run("simulate", kind, "--out", str(path), *args)
    assert r.exit_code == 0, r.output
    return path, json.loads(Path(str(path) + ".truth.json").read_text())


def test_scale_factor(tmp_path, unrendered_figures):
    # one-pixel figures: this test never looks at them (tests/report draws and looks at them)
    path, truth = simulated(tmp_path, "gyro-rates")
    r = run(
        "gyro",
        "scale-factor",
        str(path),
        "--requirement",
        "fmvss126",
        "--json",
        "-",
        "--report",
        str(tmp_path / "sf.html"),
    )
    assert r.exit_code == 0, r.output
    d = json.loads(r.stdout)
    for key in ("scale_factor", "bias", "full_scale_deg_s", "nonlinearity_percent_fs", "residuals"):
        assert key in d
    assert d["full_scale_deg_s"] == 100.0
    assert d["scale_factor"] == pytest.approx(truth["ls_scale_factor"], rel=2e-5)
    assert (tmp_path / "sf.html").exists()
    one_line_error(run("gyro", "scale-factor", str(path), "--requirement", "nope"), "nope")


def test_scale_factor_resolution_basis_and_bandwidth(tmp_path):
    path, truth = simulated(tmp_path, "gyro-rates", "--samples-per-point", "4000")
    args = ("gyro", "scale-factor", str(path), "--requirement", "fmvss126", "--output-unit", "V")
    r = run(*args, "--sample-rate-hz", "100", "--bandwidth-hz", "6")
    assert r.exit_code == 0, r.output
    line = next(x for x in r.stdout.splitlines() if "resolution" in x)
    # the twin's 0.05 °/s per sample, averaged over 8 samples (6.25 Hz of 100 Hz): 0.05/√8
    noise = truth["sensor"]["noise_std"] / truth["scale_factor"] / 8**0.5
    value = float(line.split("resolution: ")[1].split(" °/s")[0])
    assert value == pytest.approx(noise, rel=0.08)
    assert line.strip().startswith("FAIL resolution") and "set by the noise" in line
    assert "6.25 Hz (stated 6 Hz: means of 8 samples at 100 Hz)" in line
    d = json.loads(run(*args, "--json", "-").stdout)["resolution"]
    assert d["set_by"] == "noise" and d["bandwidth_hz"] is None
    one_line_error(run(*args, "--bandwidth-hz", "6"), "--bandwidth-hz", "--sample-rate-hz")
    one_line_error(
        run(*args, "--sample-rate-hz", "100", "--bandwidth-hz", "80"), "above", "fs/2 = 50 Hz"
    )


def test_triad(tmp_path):
    path, truth = simulated(tmp_path, "gyro-triad", "--outlier-fraction", "0.02")
    r = run("gyro", "triad", str(path), "--json", "-")
    assert r.exit_code == 0, r.output
    d = json.loads(r.stdout)
    assert np.allclose(d["scale_misalignment"], truth["scale_misalignment"], atol=2e-4)
    assert np.allclose(d["bias"], truth["bias"], atol=5e-3)
    assert d["outliers_rejected"] > 0 and len(d["residual_rms"]) == 3


def test_multiposition(tmp_path):
    path, truth = simulated(tmp_path, "multiposition", "--axis", "y")
    r = run(
        "gyro",
        "multiposition",
        str(path),
        "--axis",
        "y",
        "--latitude-deg",
        str(truth["latitude_deg"]),
        "--json",
        "-",
    )
    assert r.exit_code == 0, r.output
    d = json.loads(r.stdout)
    assert set(d["drift_coefficients"]) == {"DF", "Dx", "Dy", "Dz", "Dyy", "Dzz", "Dyx"}
    for name, value in d["drift_coefficients"].items():
        assert value == pytest.approx(truth["drift_coefficients"][name], abs=0.01)
        assert d["drift_coefficients_u"][name] > 0
    one_line_error(
        run("gyro", "multiposition", str(path), "--axis", "y", "--latitude-deg", "91"), "latitude"
    )


def test_gyro_bad_input(tmp_path):
    bad = tmp_path / "one_rate.csv"
    bad.write_text("rate_deg_s,output\n10,1.0\n10,1.1\n10,0.9\n")
    one_line_error(run("gyro", "scale-factor", str(bad)), "rate")
    nan = tmp_path / "nan.csv"
    nan.write_text("rate_deg_s,output\n10,1.0\n20,nan\n30,3.0\n")
    one_line_error(run("gyro", "scale-factor", str(nan)), "nan")
    plan = tmp_path / "plan.csv"
    rows = "\n".join(f"{w},0,0,{w},0,0" for w in (6, -6, 18, -18, 30, -30))
    plan.write_text("wx_deg_s,wy_deg_s,wz_deg_s,ux,uy,uz\n" + rows + "\n")
    one_line_error(run("gyro", "triad", str(plan)), "rows")
    # rotations about x only: enough rows, but the y and z columns of K cannot be identified
    rows = "\n".join(f"{w},0,0,{w},0,0" for w in (6, -6, 18, -18, 30, -30, 60, -60, 90, -90))
    plan.write_text("wx_deg_s,wy_deg_s,wz_deg_s,ux,uy,uz\n" + rows + "\n")
    one_line_error(run("gyro", "triad", str(plan)), "identif")


def test_rotations_from_the_twin_and_imucal(tmp_path):
    path, truth = simulated(tmp_path, "gyro-rotations")
    r = run("gyro", "rotations", str(path), "--sections", str(path) + ".truth.json", "--json", "-")
    assert r.exit_code == 0, r.output
    d = json.loads(r.stdout)
    assert np.allclose(d["scale_misalignment"], truth["scale_misalignment"], atol=2e-3)
    assert np.allclose(d["bias"], truth["bias"], atol=5e-3)
    bad = tmp_path / "s.json"
    bad.write_text('{"x_rot": [1, 2]}')
    one_line_error(run("gyro", "rotations", str(path), "--sections", str(bad)), "lacks")
