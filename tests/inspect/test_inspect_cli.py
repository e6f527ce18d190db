"""``rotacal inspect`` on the command line, and the fits of every twin capture."""

from __future__ import annotations

import json

import numpy as np
import pytest
from click.testing import CliRunner

from rotacal.cli import cli
from rotacal.columns import COMMANDS
from rotacal.io import write_capture


def run(*args: str):
    return CliRunner().invoke(cli, list(args), prog_name="rotacal")


#: simulate KIND -> the analysis command its capture is made for (INTERFACE.md's tables)
TWIN_FITS = {
    "encoder": "motion encoder",
    "lts": "motion lts",
    "fog": "motion fog",
    "pulses": "selfcal",
    "gyro-rates": "gyro scale-factor",
    "gyro-triad": "gyro triad",
    "gyro-noise": "allan",
    "gyro-rotations": "gyro rotations",
    "ferraris": "gyro accelerometer",
    "multiposition": "gyro multiposition",
    "gyro-sine": "gyro frequency-response",
}


@pytest.mark.parametrize(("kind", "command"), TWIN_FITS.items())
def test_every_twin_capture_fits_its_command(tmp_path, kind, command):
    out = tmp_path / f"{kind}.npz"
    made = run("simulate", kind, "--out", str(out))
    assert made.exit_code == 0, made.output
    result = run("inspect", str(out), "--json", "-")
    assert result.exit_code == 0, result.output
    found = json.loads(result.stdout)
    assert command in found["fits"]
    assert found["kind"] == "capture" and found["warnings"] == []


def test_terminal_summary_and_warning_lines(tmp_path):
    t = np.delete(np.arange(1_000) * 0.01, np.arange(300, 310))
    x = np.sin(t)
    x[3] = np.nan
    path = write_capture(tmp_path / "log.csv", {"time_s": t, "rate_deg_s": x})
    result = run("inspect", str(path))
    assert result.exit_code == 0, result.output
    out = result.stdout.splitlines()
    assert out[0] == "log.csv is a text capture (comma separated, header row) of 2 column(s)"
    assert out[1].split() == list(
        ("column", "samples", "min", "max", "NaN", "inf", "repeated", "clipped", "step")
    )
    low, high = f"{np.nanmin(x):.6g}", f"{np.nanmax(x):.6g}"
    assert out[3].split()[:6] == ["rate_deg_s", "990", low, high, "1", "0"]
    assert any(line.startswith("time: time_s, 100 Hz") and "1 gap(s)" in line for line in out)
    assert "fits: allan, motion fog" in out
    warnings = result.stderr.strip().splitlines()
    assert len(warnings) == 2 and all(w.startswith("rotacal: warning: ") for w in warnings)


def test_json_file_is_written_and_not_replaced_without_overwrite(tmp_path):
    path = write_capture(tmp_path / "c.csv", {"rate_deg_s": np.arange(5.0)})
    target = tmp_path / "look.json"
    assert run("inspect", str(path), "--json", str(target)).exit_code == 0
    written = json.loads(target.read_text())
    assert written["columns"]["rate_deg_s"]["samples"] == 5
    again = run("inspect", str(path), "--json", str(target))
    assert again.exit_code == 2 and "--overwrite" in again.stderr
    assert run("inspect", str(path), "--json", str(target), "--overwrite").exit_code == 0


def test_json_names_the_interface_keys(tmp_path):
    path = write_capture(tmp_path / "c.npz", {"time_s": np.arange(5.0), "x": np.ones(5)})
    found = json.loads(run("inspect", str(path), "--json", "-").stdout)
    assert {
        "columns",
        "sample_rate_hz",
        "sample_interval_jitter_s",
        "duration_s",
        "gaps",
        "fits",
        "warnings",
        "kind",
    } <= set(found)
    assert set(found["columns"]["x"]) >= {
        "samples",
        "min",
        "max",
        "nan",
        "inf",
        "repeated_fraction",
        "clipped_fraction",
    }


def test_column_mapping_and_suggestions_on_the_command_line(tmp_path):
    path = tmp_path / "daq.csv"
    path.write_text("Time,Rate_Deg_S\n0,1\n0.5,2\n1.0,3\n")
    plain = run("inspect", str(path))
    assert "suggested: --column Rate_Deg_S=rate_deg_s --column Time=time_s" in plain.stdout
    mapped = run(
        "inspect", str(path), "--column", "Time=time_s", "--column", "Rate_Deg_S=rate_deg_s"
    )
    assert "fits: allan, motion fog" in mapped.stdout


def test_a_file_that_is_no_capture_exits_0_with_one_line(tmp_path):
    path = tmp_path / "cal.json"
    path.write_text('{"K": 1}')
    result = run("inspect", str(path))
    assert result.exit_code == 0
    assert (
        result.stdout
        == "cal.json is a JSON document, not a capture; no analysis command reads it\n"
    )


def test_bad_input_is_one_line_and_exit_2(tmp_path):
    missing = run("inspect", str(tmp_path / "none.csv"))
    assert missing.exit_code == 2
    assert missing.stderr.count("\n") == 1 and "does not exist" in missing.stderr
    path = write_capture(tmp_path / "c.csv", {"x": np.arange(3.0)})
    bad_map = run("inspect", str(path), "--column", "y=time_s")
    assert bad_map.exit_code == 2 and "has no column 'y' to map" in bad_map.stderr


#: options each command needs besides its capture (values that pass the option checks)
COMMAND_OPTIONS = {
    "motion encoder": ["--lines", "100"],
    "motion lts": ["--radius-mm", "100"],
    "gyro multiposition": ["--axis", "x", "--latitude-deg", "45"],
    "rate": ["--pulses-per-rev", "360"],
}


@pytest.mark.parametrize(
    "spec", [c for c in COMMANDS if c.required], ids=lambda c: c.command.replace(" ", "-")
)
def test_each_command_reads_the_columns_of_the_table(tmp_path, spec):
    """The table that tells inspect's fits is what the commands read: a capture with all of
    the required columns but one is refused, naming that one."""
    rng = np.random.default_rng(6)
    missing, *rest = spec.required
    kept = {c: rng.normal(size=50) for c in (*rest, "other")}
    path = write_capture(tmp_path / "c.csv", kept)
    options = COMMAND_OPTIONS.get(spec.command, [])
    if spec.command in ("gyro rotations", "gyro accelerometer"):
        sections = tmp_path / "sections.json"
        sections.write_text('{"rotations": {"x": [0, 10]}}')
        options = ["--sections", str(sections)]
    result = run(*spec.command.split(), str(path), *options)
    assert result.exit_code == 2, result.output
    assert f"no column {missing!r}" in result.stderr


def test_report_shows_the_columns_and_the_gaps(tmp_path):
    t = np.delete(np.arange(2_000) * 0.01, np.arange(500, 520))
    path = write_capture(tmp_path / "gappy.csv", {"time_s": t, "rate_deg_s": np.sin(t)})
    report = tmp_path / "look.html"
    result = run("inspect", str(path), "--report", str(report))
    assert result.exit_code == 0, result.output
    html = report.read_text()
    assert "rate_deg_s" in html and "smallest non-zero step" in html
    assert f"{t[499]:.9g}" in html and ">20<" in html  # the gap and its 20 missing samples
    assert "1 gap(s)" in html


def test_a_capture_without_a_column_of_numbers_is_answered(tmp_path):
    """Labels only (a thousands mark makes '1.234,5' text): named, not a refusal."""
    path = tmp_path / "thousands.csv"
    path.write_text("time_s;rate\n0,0;1.234,5\n0,1;1.234,6\n")
    r = CliRunner().invoke(cli, ["inspect", str(path), "--json", "-"])
    assert r.exit_code == 0, r.output
    found = json.loads(r.stdout)
    assert found["kind"] == "no-numbers" and found["fits"] == []
    assert "column 'rate' holds text ('1.234,5' on line 2)" in found["description"]
