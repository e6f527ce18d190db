"""`rotacal gyro scale-factor` items (sign, runs, temperature) and `rotacal gyro resolution`, end to
end on twins written by `rotacal simulate`: INTERFACE keys against the truth, one-line refusals."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from tests.cli.test_gyro_cli import one_line_error, run


def simulate(path: Path, kind: str, *args: str) -> dict:
    r = run("simulate", kind, "--out", str(path), *args)
    assert r.exit_code == 0, r.output
    return json.loads(Path(str(path) + ".truth.json").read_text())


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    """Three runs of one gyro at 10, 30 and 50 °C, with asymmetry and a run-to-run spread."""
    folder = tmp_path_factory.mktemp("runs")
    paths, truths = [], []
    for i, temp in enumerate((10, 30, 50)):
        path = folder / f"run{i}.npz"
        truths.append(
            simulate(
                path,
                "gyro-rates",
                "--seed",
                str(i),
                "--samples-per-point",
                "400",
                "--asymmetry-ppm",
                "400",
                "--run-scale-factor-std-ppm",
                "30",
                "--temperature-c",
                str(temp),
                "--temperature-ref-c",
                "30",
                "--scale-factor-tc-ppm-per-c",
                "60",
                "--bias-tc-per-c",
                "1e-4",
            )
        )
        paths.append(str(path))
    return paths, truths


def test_runs_at_temperatures_end_to_end(runs, tmp_path, unrendered_figures):
    paths, truths = runs
    out = tmp_path / "sf.json"
    r = run(
        "gyro", "scale-factor", *paths, "--json", str(out), "--report", str(tmp_path / "sf.html")
    )
    assert r.exit_code == 0, r.output
    assert "asymmetry" in r.stdout and "repeatability" in r.stdout
    d = json.loads(out.read_text())
    t = truths[0]
    for key in (
        "scale_factor_temperature_coefficient_ppm_per_c",
        "bias_temperature_coefficient_deg_h_per_c",
    ):
        assert abs(d[key] - t[key]) < 3 * d[f"{key}_u"], key
    # the pooled runs' asymmetry: each run's truth (the same for all) within 3 u
    assert abs(d["asymmetry_ppm"] - t["asymmetry_ppm"]) < 3 * d["asymmetry_ppm_u"]
    assert d["scale_factor_repeatability_ppm"] > 0 and d["scale_factor_repeatability_ppm_u"] > 0
    assert len(d["run_scale_factors"]) == 3
    assert any("different temperatures" in n for n in d["notes"])
    html = (tmp_path / "sf.html").read_text()
    assert "repeatability" in html and "temperature coefficient" in html


def test_temperature_refusals(runs, tmp_path):
    paths, _ = runs
    flat = tmp_path / "flat.npz"
    simulate(flat, "gyro-rates", "--temperature-c", "20", "--samples-per-point", "100")
    one_line_error(run("gyro", "scale-factor", str(flat)), "too small to tell")
    # mapped away, it is analysed without temperature coefficients
    r = run("gyro", "scale-factor", str(flat), "--column", "temperature_c=room_c", "--json", "-")
    assert r.exit_code == 0 and "scale_factor_temperature_coefficient_ppm_per_c" not in r.stdout
    cold = tmp_path / "cold.npz"
    simulate(cold, "gyro-rates", "--samples-per-point", "100")
    one_line_error(run("gyro", "scale-factor", paths[0], str(cold)), "temperature_c column")


def test_resolution_command(tmp_path, unrendered_figures):
    path = tmp_path / "steps.npz"
    truth = simulate(path, "gyro-steps", "--samples-per-dwell", "600")
    out = tmp_path / "steps.json"
    r = run(
        "gyro",
        "resolution",
        str(path),
        "--scale-factor",
        "0.0125",
        "--json",
        str(out),
        "--report",
        str(tmp_path / "steps.html"),
    )
    assert r.exit_code == 0, r.output
    d = json.loads(out.read_text())
    for key in ("threshold_deg_s", "resolution_deg_s"):
        assert abs(d[key] - truth[key]) <= 2 * d[f"{key}_u"], key
    assert d["provenance"]["command"] == "gyro resolution"
    flat = tmp_path / "flat.npz"
    simulate(flat, "gyro-rates", "--samples-per-point", "5")
    one_line_error(
        run("gyro", "resolution", str(flat), "--settle-samples", "4"), "at least 2 samples"
    )
