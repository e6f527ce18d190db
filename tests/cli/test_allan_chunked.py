"""`rotacal allan` on the chunked path: the in-memory answer, the same refusals, the choice.

Truth: the in-memory command on the same capture (the deviation to ≤ 1e-9 relative, the noise
terms read off it the same), and the checks of the in-memory path.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

import rotacal.cli.allan as allan_cli
from rotacal.cli import cli

FS = 100.0


def run(*args: str):
    return CliRunner().invoke(cli, list(args), prog_name="rotacal")


def gyro_capture(path: Path, n: int = 200_000, seed: int = 1, **extra: np.ndarray) -> Path:
    """A 100 Hz gyro: white rate noise (ARW), a rate random walk and a small rate ramp."""
    rng = np.random.default_rng(seed)
    rate = 0.1 + 0.05 * rng.standard_normal(n) + np.cumsum(2e-5 * rng.standard_normal(n))
    rate += 1e-7 * np.arange(n)
    np.savez(path, rate_deg_s=rate, time_s=np.arange(n) / FS, **extra)
    return path


@pytest.fixture
def small_chunks(monkeypatch):
    """Chunks of 10 007 rows and 4 096 carried phase values: most τ come from the phase file."""
    monkeypatch.setattr(allan_cli, "_CHUNK_ROWS", 10_007)
    monkeypatch.setattr(allan_cli, "_CHUNK_HISTORY", 4096)


@pytest.mark.parametrize("taus", ["octave", "decade"])
def test_chunked_equals_in_memory(tmp_path, small_chunks, taus):
    capture = gyro_capture(tmp_path / "g.npz")
    out = {}
    for mode in ("--chunked", "--in-memory"):
        r = run("allan", str(capture), "--taus", taus, mode, "--json", "-")
        assert r.exit_code == 0, r.output
        out[mode] = json.loads(r.stdout)
    a, b = out["--chunked"], out["--in-memory"]
    assert a["tau_s"] == b["tau_s"]
    for key in ("adev_deg_s", "adev_low_deg_s", "adev_high_deg_s"):
        np.testing.assert_allclose(a[key], b[key], rtol=1e-9, atol=0)
    for key in ("arw_deg_rt_h", "bias_instability_deg_h", "rrw_deg_h_rt_h", "fs_hz"):
        assert (a[key] is None) == (b[key] is None), key
        if a[key] is not None:
            assert a[key] == pytest.approx(b[key], rel=1e-9), key
    assert a["arw_deg_rt_h"] == pytest.approx(0.05 * 60 / np.sqrt(FS), rel=0.05)  # the truth
    assert a["samples"] == b["samples"] == 200_000
    assert a["uncertainty_budgets"].keys() == b["uncertainty_budgets"].keys()


def test_large_capture_is_chunked_by_itself(tmp_path, monkeypatch, small_chunks):
    monkeypatch.setattr(allan_cli, "_IN_MEMORY_MAX_SAMPLES", 100_000)
    capture = gyro_capture(tmp_path / "g.npz")
    r = run("allan", str(capture), "--json", "-")
    assert r.exit_code == 0, r.output
    data = json.loads(r.stdout)
    ratios = np.diff(np.log2(data["tau_s"]))
    np.testing.assert_allclose(ratios, 1.0)  # octave τ, and a note that says why
    assert any("read in chunks" in note for note in data["notes"])
    r = run("allan", str(capture), "--taus", "all", "--json", "-")
    assert r.exit_code == 2 and "--taus all needs the whole record" in r.stderr
    assert r.stderr.strip().count("\n") == 0


def test_chunked_refusals_name_the_sample(tmp_path, small_chunks):
    n = 60_000
    t = np.arange(n) / FS
    t[41_234:] += 1.0  # a gap
    capture = gyro_capture(tmp_path / "gap.npz", n=n)
    data = dict(np.load(capture))
    np.savez(capture, rate_deg_s=data["rate_deg_s"], time_s=t)
    for mode in ("--chunked", "--in-memory"):
        r = run("allan", str(capture), "--taus", "octave", mode)
        assert r.exit_code == 2 and "gap" in r.stderr and "41234" in r.stderr, r.stderr
    rate = np.full(n, 0.25)
    np.savez(capture, rate_deg_s=rate, time_s=np.arange(n) / FS)
    r = run("allan", str(capture), "--chunked")
    assert r.exit_code == 2 and "constant" in r.stderr
    rate = np.random.default_rng(2).standard_normal(n)
    rate[rate > 1.0] = 1.0  # clipped at a rail
    np.savez(capture, rate_deg_s=rate, time_s=np.arange(n) / FS)
    for mode in ("--chunked", "--in-memory"):
        r = run("allan", str(capture), "--taus", "octave", mode)
        assert r.exit_code == 2 and "clipped" in r.stderr.lower(), r.stderr
    r = run("allan", str(capture), "--chunked", "--angle")
    assert r.exit_code == 2 and "--angle" in r.stderr
