"""Plausibility warnings from the command line: faults speak (that every twin's defaults say
nothing: tests/report/test_warning_free.py)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from rotacal.cli import cli


def run(*args: str):
    return CliRunner().invoke(cli, list(args), prog_name="rotacal")


def simulated(tmp_path: Path, kind: str) -> tuple[str, dict]:
    path = tmp_path / f"{kind}.npz"
    r = run("simulate", kind, "--out", str(path))
    assert r.exit_code == 0, r.output
    return str(path), json.loads(Path(f"{path}.truth.json").read_text())


# Every twin's analysis with its defaults (and ``rate`` of the pulse twin, the example table's
# budget) is checked warning-free in tests/report/test_warning_free.py, on the runs whose reports
# the browser reads: each twin simulated and analysed once per session.


def test_the_issues_encoder_with_a_tenth_of_its_lines_warns_on_stderr(
    tmp_path, analysis_args
) -> None:
    path, truth = simulated(tmp_path, "encoder")
    args = analysis_args("encoder", path, truth)
    args[args.index("--lines") + 1] = "3600"
    r = run(*args, "--json", "-")
    assert r.exit_code == 0, r.output
    d = json.loads(r.stdout)
    assert d["amplitude_error_percent"] == pytest.approx(900.0, rel=1e-3)
    (line,) = d["warnings"]
    assert "--lines" in line and "×10" in line
    assert f"rotacal: warning: {line}" in r.stderr


def _imucal_args(data: Path, *extra: str) -> list[str]:
    ex = data / "example_data"
    return [
        "gyro",
        "rotations",
        str(ex / "example_ferraris_session.csv"),
        "--sections",
        str(ex / "example_ferraris_session_list.json"),
        "--fs-hz",
        "102.4",
        "--column",
        "gyr_x=ux",
        "--column",
        "gyr_y=uy",
        "--column",
        "gyr_z=uz",
        "--json",
        "-",
        *extra,
    ]


def test_imucals_recording_with_defaults_gives_imucals_positive_diagonal(shared_data) -> None:
    data = shared_data("imucal")
    ref = json.loads((data / "example_ferraris_session_cal_computed_imucal2.6.0.json").read_text())
    r = run(*_imucal_args(data))
    assert r.exit_code == 0, r.output
    d = json.loads(r.stdout)
    assert d["warnings"] == []
    np.testing.assert_allclose(d["scale_factors"], np.diag(ref["K_g"]), rtol=5e-5)
    np.testing.assert_allclose(d["bias"], ref["b_g"], rtol=1e-12, atol=0)
    assert np.all(np.diag(d["scale_misalignment"]) > 0)
    # the other sense of turning: every diagonal element negative, each named on stderr
    r = run(*_imucal_args(data, "--angle-deg", "360"))
    assert r.exit_code == 0, r.output
    warnings = json.loads(r.stdout)["warnings"]
    assert len(warnings) == 3 and all("--angle-deg" in w for w in warnings)
    assert r.stderr.count("rotacal: warning: K_") == 3


@pytest.mark.xdist_group("demo")
def test_demo_is_warning_free(demo_run) -> None:
    out, r = demo_run  # the session's one demo (tests/conftest.py), shared with tests/report
    # the real campaign (test_output_convention checks the CLI's part with a stand-in): the files
    # it names are those it wrote, each with one line
    from rotacal.demo import demo_files

    written = sorted(p.relative_to(out).as_posix() for p in out.rglob("*") if p.is_file())
    assert written == sorted(demo_files())
    wrote = [line for line in r.stderr.splitlines() if line.startswith("wrote ")]
    assert wrote == [f"wrote {out / name}" for name in demo_files()]
    results = sorted(p for p in out.glob("*.json") if p.name != "summary.json")  # not a result
    assert len(results) >= 10
    for path in results:
        assert json.loads(path.read_text())["warnings"] == [], path.name
