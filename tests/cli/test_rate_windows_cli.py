"""`rotacal rate … --window-deg`: the INTERFACE keys, the same numbers as the API, refusals."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from rotacal.cli import cli
from rotacal.sim.pulses import simulate_pulses
from rotacal.table.rate_windows import rate_windows

M = 720
KEYS = ("rate_accuracy_percent", "rate_stability_percent", "rate_stability_peak_percent")


def run(*args: str):
    return CliRunner().invoke(cli, list(args), prog_name="rotacal")


@pytest.fixture(scope="module")
def capture(tmp_path_factory) -> tuple[Path, np.ndarray]:
    """One head of a 720-line scale, 5 revolutions at 120 °/s with a rate ripple, as an NPZ."""
    cap = simulate_pulses(
        heads=2,
        pulses_per_rev=M,
        rate_deg_s=120.0,
        revolutions=5.0,
        rate_fluctuation_percent=0.02,
        fluctuation_hz=[120.0 / 360.0, 1200.0 / 360.0],
        jitter_s=1e-7,
        seed=11,
    )
    t = np.asarray(cap.columns["head_0"])
    path = tmp_path_factory.mktemp("windows") / "head.npz"
    np.savez(path, head_0=t)
    return path, t


def test_keys_per_window_equal_the_api(capture, tmp_path):
    """(The report's section is drawn and read in a browser by tests/report, whose rate run
    gives --window-deg.)"""
    path, t = capture
    out = tmp_path / "r.json"
    r = run(
        "rate", str(path), "--pulses-per-rev", str(M), "--window-deg", "1,10,360",
        "--set-rate-deg-s", "120", "--json", str(out),
    )  # fmt: skip
    assert r.exit_code == 0, r.output
    data = json.loads(out.read_text())
    api = rate_windows(
        t,
        pulses_per_rev=M,
        windows_deg=[1, 10, 360],
        set_rate_deg_s=120.0,
        timing_jitter_s=data["timing_jitter_s"],
    ).to_dict()
    for name in KEYS:
        for suffix in ("", "_u"):
            assert set(data[name + suffix]) == {"1", "10", "360"}
            for key, value in api[name + suffix].items():
                assert data[name + suffix][key] == pytest.approx(value, rel=1e-12)
    assert data["window_count"] == {
        k: (t.size - 1) // (M * int(k) // 360) for k in ("1", "10", "360")
    }
    assert "mean_rate_deg_s" in data  # the rate's own keys stay
    assert "over 1 deg" in r.stdout


@pytest.mark.parametrize(
    ("windows", "needle"),
    [
        ("0.5,1", "--window-deg 0.5"),
        ("1,x", "'x' is not an angle"),
        ("1,-10", "positive"),
        ("1,1440", "--window-deg 1440"),
    ],
)
def test_refusals_are_one_line(capture, windows, needle):
    path, _ = capture
    r = run("rate", str(path), "--pulses-per-rev", str(M), "--window-deg", windows)
    assert r.exit_code == 2, r.output
    err = r.stderr.strip()
    assert err.count("\n") == 0 and "Traceback" not in r.output, err
    assert needle in err, err
