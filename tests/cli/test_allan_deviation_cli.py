"""`rotacal allan --deviation`: the deviation's keys and values, the angle path, the refusals.

Truth: allantools 2019.9 on the same record and τ (an independent implementation), and the
record's known white rate noise (MDEV/HDEV/TOTDEV of white rate noise σ at τ = m/fs: HDEV and
TOTDEV equal the ADEV's σ/√m in expectation).
"""

from __future__ import annotations

import json
from pathlib import Path

import allantools
import numpy as np
import pytest
from click.testing import CliRunner

from rotacal.cli import cli

FS = 50.0
SIGMA = 0.02


def run(*args: str):
    return CliRunner().invoke(cli, list(args), prog_name="rotacal")


def capture(path: Path, n: int = 20_000) -> tuple[Path, np.ndarray]:
    rate = 0.3 + SIGMA * np.random.default_rng(2).standard_normal(n)
    np.savez(path, rate_deg_s=rate, time_s=np.arange(n) / FS, angle_deg=np.cumsum(rate) / FS)
    return path, rate


AT = {"mdev": allantools.mdev, "hdev": allantools.ohdev, "tdev": allantools.tdev,
      "totdev": allantools.totdev}  # fmt: skip


@pytest.mark.parametrize("kind", sorted(AT))
def test_deviation_keys_equal_allantools(tmp_path, kind):
    path, rate = capture(tmp_path / "g.npz")
    r = run("allan", str(path), "--deviation", kind, "--taus", "octave", "--json", "-")
    assert r.exit_code == 0, r.output
    data = json.loads(r.stdout)
    unit = "deg" if kind == "tdev" else "deg_s"
    assert data["deviation"] == kind
    tau = np.array(data[f"{kind}_tau_s"])
    dev = np.array(data[f"{kind}_{unit}"])
    t, d, _, _ = AT[kind](rate, rate=FS, data_type="freq", taus=tau)
    np.testing.assert_allclose(dev[: t.size], d, rtol=1e-9)
    lo, hi = np.array(data[f"{kind}_low_{unit}"]), np.array(data[f"{kind}_high_{unit}"])
    assert np.all((lo < dev) & (dev < hi))
    assert len(data[f"{kind}_edf"]) == tau.size
    if kind in ("hdev", "totdev"):  # white rate noise: σ/√m in expectation, within ±3 intervals
        expected = SIGMA / np.sqrt(tau * FS)
        assert np.all(np.abs(dev - expected) <= 3 * (hi - lo) + 1e-12)
    assert "adev_deg_s" in data and "arw_deg_rt_h" in data  # the noise analysis stays


def test_angle_column_is_phase_data(tmp_path):
    """An angle column is the phase (°): its MDEV in °/s equals allantools' of that phase."""
    path, _ = capture(tmp_path / "g.npz")
    angle = np.load(path)["angle_deg"]
    r = run("allan", str(path), "--deviation", "mdev", "--column", "angle_deg", "--angle",
            "--taus", "octave", "--json", "-")  # fmt: skip
    assert r.exit_code == 0, r.output
    data = json.loads(r.stdout)
    t, d, _, _ = allantools.mdev(angle, rate=FS, data_type="phase", taus=data["mdev_tau_s"])
    np.testing.assert_allclose(data["mdev_deg_s"][: t.size], d, rtol=1e-9)


def test_dask_path_refuses_in_one_line(tmp_path):
    path, _ = capture(tmp_path / "g.npz")
    r = run("allan", str(path), "--deviation", "hdev", "--workers", "2", "--taus", "octave")
    assert r.exit_code == 2
    assert "--deviation hdev is not computed on Dask workers" in r.output
    assert "Traceback" not in r.output and len(r.output.strip().splitlines()) == 1


def test_report_has_the_deviation_figure(tmp_path):
    path, _ = capture(tmp_path / "g.npz", n=4000)
    html = tmp_path / "r.html"
    r = run("allan", str(path), "--deviation", "totdev", "--report", str(html))
    assert r.exit_code == 0, r.output
    text = html.read_text()
    assert "Stability: total deviation" in text and text.count("data:image/png") >= 2
