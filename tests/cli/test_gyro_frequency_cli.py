"""`rotacal simulate gyro-sine` and `rotacal gyro frequency-response` end to end: the INTERFACE
keys against the twin's truth files, the summary, one-line refusals."""

from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from rotacal.cli import cli

FREQUENCIES = ("1", "4", "8", "12")
KEYS = (
    "frequency_hz",
    "amplitude_ratio",
    "amplitude_ratio_db",
    "phase_deg",
    "bandwidth_hz",
    "natural_frequency_hz",
    "damping_ratio",
)


def run(*args: str):
    return CliRunner().invoke(cli, list(args), prog_name="rotacal")


@pytest.fixture(scope="module")
def sweep(tmp_path_factory) -> list[Path]:
    folder = tmp_path_factory.mktemp("sweep")
    paths = []
    for i, f in enumerate(FREQUENCIES):
        path = folder / f"f{f}.npz"
        r = run("simulate", "gyro-sine", "--frequency-hz", f, "--seed", str(i), "--out", str(path))
        assert r.exit_code == 0, r.output
        paths.append(path)
    return paths


def test_end_to_end_against_the_truth_files(sweep):
    r = run(
        "gyro",
        "frequency-response",
        *map(str, sweep),
        "--lines",
        "3600",
        "--channel-skew-s",
        "0",
        "--json",
        "-",
    )
    assert r.exit_code == 0, r.output
    d = json.loads(r.stdout)
    for key in KEYS:
        assert key in d and f"{key}_u" in d, key
    truths = [json.loads(Path(f"{p}.truth.json").read_text()) for p in sweep]
    for key in ("amplitude_ratio", "phase_deg"):
        err = np.array(d[key]) - [t[key] for t in truths]
        assert np.all(np.abs(err) < 3.5 * np.array(d[f"{key}_u"])), (key, err)
    for key in ("natural_frequency_hz", "damping_ratio", "bandwidth_hz"):
        assert abs(d[key] - truths[0][key]) < 3 * d[f"{key}_u"], key
    assert d["captures"] == [p.name for p in sweep]
    assert d["provenance"]["command"] == "gyro frequency-response"
    assert len(d["provenance"]["inputs"]) == len(sweep)


def test_summary_states_u_with_k_and_p(sweep):
    r = run("gyro", "frequency-response", *map(str, sweep), "--lines", "3600")
    assert r.exit_code == 0, r.output
    lines = r.stdout.splitlines()
    assert len(lines) == len(sweep) + 3
    assert lines[-1].startswith("bandwidth −3 dB")
    assert re.search(r" ± [0-9.]+ Hz \(k = [0-9.]+, p = 95 %\)$", lines[-1]), lines[-1]


def test_refusals_are_one_line(sweep, tmp_path):
    one = run("gyro", "frequency-response", str(sweep[0]), "--lines", "3600")
    assert one.exit_code == 2 and "2 parameters" in one.stderr
    assert one.stderr.strip().count("\n") == 0
    twice = run(
        "gyro", "frequency-response", str(sweep[0]), str(sweep[1]), str(sweep[0]), "--lines", "3600"
    )
    assert twice.exit_code == 2 and "same frequency" in twice.stderr
    no_angle = run("gyro", "frequency-response", *map(str, sweep))
    assert no_angle.exit_code == 2 and "angle_deg" in no_angle.stderr
    flipped = run(
        "gyro", "frequency-response", *map(str, sweep), "--lines", "3600", "--dut-sign", "-1"
    )
    assert flipped.exit_code == 2 and "antiphase" in flipped.stderr
