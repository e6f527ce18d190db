"""`rotacal simulate position` and `rotacal position` end to end: the keys against the twin's truth
files, the self-calibration file as reference, the report, one-line refusals (exit 2)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from rotacal.cli import cli


def run(*args: str):
    return CliRunner().invoke(cli, list(args), prog_name="rotacal")


@pytest.fixture(scope="module")
def captures(tmp_path_factory) -> dict[str, Path]:
    folder = tmp_path_factory.mktemp("position")
    paths = {"encoder": folder / "enc.csv", "polygon": folder / "poly.npz"}
    r = run("simulate", "position", "--graduation", "1:12:0", "--out", str(paths["encoder"]))
    assert r.exit_code == 0, r.output
    r = run(
        "simulate", "position", "--reference", "polygon", "--positions", "12", "--runs", "6",
        "--out", str(paths["polygon"]),
    )  # fmt: skip
    assert r.exit_code == 0, r.output
    return paths


def truth(path: Path) -> dict:
    return json.loads(Path(f"{path}.truth.json").read_text())


def test_selfcal_file_as_reference_against_the_truth(captures, tmp_path):
    path = captures["encoder"]
    t = truth(path)
    selfcal = tmp_path / "selfcal.json"
    selfcal.write_text(json.dumps({**t["selfcal"], "deviation_u_arcsec": 0.05}))
    specs = tmp_path / "specs.toml"  # the reference encoder's reading error: rectangular ±1″
    specs.write_text(
        '[encoder]\ngraduation_error_arcsec = { distribution = "rectangular", half_width = 1.0 }\n'
    )
    r = run(
        "position", str(path), "--selfcal", str(selfcal), "--specs", str(specs), "--json", "-"
    )  # fmt: skip
    assert r.exit_code == 0, r.output
    d = json.loads(r.stdout)
    amp = np.array([h["amplitude_arcsec"] for h in t["harmonics"]])
    assert np.all(
        np.abs(np.array(d["harmonic_amplitudes_arcsec"]) - amp)
        < 3 * np.array(d["harmonic_amplitudes_arcsec_u"])
    )
    for key in ("error_pp_arcsec", "repeatability_bidirectional_arcsec", "reversal_value_arcsec"):
        assert key in d and f"{key}_u" in d, key
    assert d["selfcal"]["lines"] == 3600
    assert d["reference_u_arcsec"] == pytest.approx(np.hypot(0.05, 1 / np.sqrt(3)))
    assert d["provenance"]["command"] == "position"
    assert len(d["provenance"]["inputs"]) == 3


def test_polygon_report_and_summary(captures, tmp_path, unrendered_figures):
    # the figure itself is drawn and read in a browser by tests/report (cli_runs)
    report = tmp_path / "poly.html"
    r = run(
        "position", str(captures["polygon"]), "--polygon-faces", "12", "--harmonics", "3",
        "--report", str(report),
    )  # fmt: skip
    assert r.exit_code == 0, r.output
    assert "reference polygon: 12 positions, 6 run(s), both directions" in r.stdout
    html = report.read_text()
    assert "Position accuracy" in html and "ISO 230-2" in html and "data:image/png" in html


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (["--harmonics", "6"], "--harmonics 6 needs at least 14 distinct positions"),
        (["--polygon-faces", "8"], "a 8-face polygon needs the 8 positions"),
        (["--column", "error_arcsec=x"], "no column 'reference_deg' or 'error_arcsec'"),
    ],
)
def test_refusals_are_one_line(captures, extra, message):
    r = run("position", str(captures["polygon"]), *extra)
    assert r.exit_code == 2
    assert message in r.stderr and len(r.stderr.strip().splitlines()) == 1, r.stderr
