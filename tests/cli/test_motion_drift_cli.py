"""`rotacal motion … --drift`, `--hysteresis` and `rotacal simulate … --drift-deg-s` on the CLI."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from click.testing import CliRunner

from rotacal.cli import cli

DRIFT_DEG_S = 0.02  # 0.06° over the 3 s capture of a 0.5°, 2 Hz motion


def run(*args: str):
    return CliRunner().invoke(cli, list(args), prog_name="rotacal")


@pytest.fixture(scope="module")
def captures(tmp_path_factory) -> dict[str, Path]:
    folder = tmp_path_factory.mktemp("drift")
    out = {}
    for kind, extra in (
        ("encoder", ["--noise", "0.003"]),
        ("lts", []),
        ("fog", ["--snr-db", "20"]),
    ):
        path = folder / f"{kind}.npz"
        r = run(
            "simulate",
            kind,
            "--harmonic",
            "3:0.02",
            "--drift-deg-s",
            str(DRIFT_DEG_S),
            "--out",
            str(path),
            *extra,
        )
        assert r.exit_code == 0, r.output
        out[kind] = path
    return out


def truth(path: Path) -> dict:
    return json.loads(Path(f"{path}.truth.json").read_text())


def motion(kind: str, path: Path, *args: str):
    extra = {"encoder": ["--lines", "36000"], "lts": ["--radius-mm", "100"], "fog": []}[kind]
    return run("motion", kind, str(path), *extra, "--json", "-", *args)


def test_simulate_writes_the_drift_into_the_truth(captures):
    tr = truth(captures["encoder"])
    assert tr["drift_deg_s"] == DRIFT_DEG_S and tr["motion"]["drift_deg_s"] == DRIFT_DEG_S
    assert tr["thd_percent"] == pytest.approx(2.0, rel=1e-6)  # the periodic part only


@pytest.mark.parametrize("kind", ["encoder", "lts"])
def test_without_drift_the_warning_says_what_to_do(captures, kind):
    r = motion(kind, captures[kind])
    assert r.exit_code == 0, r.stderr
    lines = [ln for ln in r.stderr.splitlines() if ln]
    assert len(lines) == 1 and lines[0].startswith("rotacal: warning: the angle drifts by")
    assert lines[0].endswith("rerun with --drift")
    out = json.loads(r.stdout)
    assert out["warnings"] == [lines[0].removeprefix("rotacal: warning: ")]
    assert "drift_deg_s" not in out


@pytest.mark.parametrize("kind", ["encoder", "lts", "fog"])
def test_with_drift_the_drift_is_reported_and_the_thd_is_true(captures, kind):
    r = motion(kind, captures[kind], "--drift")
    assert r.exit_code == 0, r.stderr
    out = json.loads(r.stdout)
    tr = truth(captures[kind])
    assert out["warnings"] == []
    assert abs(out["drift_deg_s"] - DRIFT_DEG_S) <= 2 * out["drift_deg_s_u"]
    bar = {"encoder": 0.02, "lts": 0.05, "fog": 0.15}[kind]
    assert abs(out["thd_percent"] - tr["thd_percent"]) < bar
    assert ("rate_drift_deg_s2" in out) == (kind == "fog")


def test_fog_steady_drift_needs_no_drift_option(captures):
    r = motion("fog", captures["fog"])
    assert r.exit_code == 0, r.stderr
    assert json.loads(r.stdout)["warnings"] == []


def test_chunked_drift_equals_in_memory(captures):
    whole = json.loads(motion("encoder", captures["encoder"], "--drift", "--in-memory").stdout)
    streamed = motion("encoder", captures["encoder"], "--drift", "--chunked")
    assert streamed.exit_code == 0, streamed.stderr
    chunked = json.loads(streamed.stdout)
    assert chunked["reversal_times_s"] == whole["reversal_times_s"]
    for key in ("thd_percent", "drift_deg_s", "amplitude_deg"):
        assert chunked[key] == pytest.approx(whole[key], rel=1e-9)


def test_hysteresis_option(captures):
    path = captures["encoder"]
    default = json.loads(motion("encoder", path).stdout)
    paper = json.loads(motion("encoder", path, "--hysteresis", "1").stdout)
    # a clean capture: the paper's rule alone finds the same reversals
    assert paper["reversal_times_s"] == default["reversal_times_s"]
    r = motion("encoder", path, "--hysteresis", "0")
    assert r.exit_code == 2
    assert "--hysteresis" in r.stderr and "Traceback" not in r.output
    assert "hysteresis" in run("motion", "encoder", "--help").stdout
