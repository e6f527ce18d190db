"""Tests of rotacal.signal.deviations_stream: MDEV, HDEV, TDEV and TOTDEV of a record in chunks.

Truth: the in-memory :func:`rotacal.signal.deviations.stability_deviation` of the whole record
(itself tested against allantools), to 1e-9 relative — the contract of a streamed path. The
carried history and the phase file's read blocks are made small, and the chunks ragged, so that
every τ's window is split by chunk boundaries, some τ are summed in the reading pass and the
others from the phase file in several blocks.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from click.testing import CliRunner

import rotacal.cli.allan as allan_cli
import rotacal.signal.deviations_stream as stream
from rotacal.cli import cli
from rotacal.errors import CaptureError, ConfigError
from rotacal.signal.deviations import stability_deviation
from rotacal.signal.deviations_stream import ChunkedDeviation

FS = 100.0
N = 6000
SIZES = [1, 37, 1000, 0, 211]  # ragged: one-sample and empty chunks too


@pytest.fixture(scope="module")
def rate() -> np.ndarray:
    """A gyro's rate (°/s): white rate noise, a rate random walk, a rate ramp and an offset."""
    rng = np.random.default_rng(7)
    walk = np.cumsum(2e-3 * rng.standard_normal(N))
    return 0.1 + 0.3 * rng.standard_normal(N) + walk + 1e-5 * np.arange(N)


def fed(kind: str, y: np.ndarray, history: int, taus: str = "octave") -> ChunkedDeviation:
    acc = ChunkedDeviation(kind, taus=taus, history=history, column="gyro_z")
    i = k = 0
    while i < y.size:
        acc.add(y[i : i + SIZES[k % len(SIZES)]])
        i += SIZES[k % len(SIZES)]
        k += 1
    return acc


@pytest.mark.parametrize(
    ("kind", "history", "taus"),
    [
        ("mdev", 16, "octave"),
        ("hdev", 16, "octave"),
        ("totdev", 16, "octave"),
        ("tdev", 64, "decade"),
        ("hdev", 64, "decade"),
        ("totdev", 64, "decade"),
        ("mdev", 1 << 14, "octave"),  # every τ summed in the reading pass
        ("tdev", 1 << 14, "octave"),
    ],
)
def test_equals_the_in_memory_deviation(rate, monkeypatch, kind, history, taus):
    monkeypatch.setattr(stream, "_READ", 7)  # the phase file read in many blocks
    with fed(kind, rate, history, taus) as acc:
        got = acc.result(fs=FS, noise_alpha=-1, confidence=0.95)
    ref = stability_deviation(rate, fs=FS, kind=kind, taus=taus, noise_alpha=-1, confidence=0.95)
    np.testing.assert_array_equal(got.cluster_sizes, ref.cluster_sizes)
    np.testing.assert_array_equal(got.n_terms, ref.n_terms)
    for name in ("tau_s", "deviation", "low", "high", "edf"):
        np.testing.assert_allclose(getattr(got, name), getattr(ref, name), rtol=1e-9, atol=0)
    assert (got.kind, got.n_samples, got.n_phase) == (kind, N, N + 1)
    if history == 16:  # both ways of summing were used, and windows longer than the chunks
        assert got.cluster_sizes.min() <= 16 // 3 < got.cluster_sizes.max()
        assert 3 * got.cluster_sizes.max() > max(SIZES)


def test_adev_kind_equals_chunked_adev(rate):
    """kind="adev" is ChunkedAdev's sums: the in-memory ADEV to 1e-9."""
    with fed("adev", rate, 16) as acc:
        got = acc.result(fs=FS)
    ref = stability_deviation(rate, fs=FS, kind="adev", taus="octave")
    np.testing.assert_allclose(got.deviation, ref.deviation, rtol=1e-9, atol=0)


def test_refusals_name_what_to_fix():
    with pytest.raises(ConfigError, match="kind must be one of"):
        ChunkedDeviation("bogus")
    with pytest.raises(ConfigError, match="taus must be 'octave' or 'decade'"):
        ChunkedDeviation("mdev", taus="log")
    with ChunkedDeviation("hdev", column="gyro_z") as acc:
        acc.add(np.ones(5))
        with pytest.raises(CaptureError, match="at least 9"):
            acc.result(fs=FS)
        acc.add(np.ones(50))
        with pytest.raises(CaptureError, match="constant"):
            acc.result(fs=FS)
        with pytest.raises(CaptureError, match="gyro_z"):
            acc.add(np.array([1.0, np.nan]))


def test_cli_streams_a_large_capture_by_itself(tmp_path, monkeypatch, rate):
    """Above the in-memory limit the command reads in chunks and sums the deviation in the same
    pass: its keys equal those of --in-memory at the same τ."""
    path = tmp_path / "g.npz"
    np.savez(path, gyro_z=rate, time_s=np.arange(N) / FS)
    monkeypatch.setattr(allan_cli, "_IN_MEMORY_MAX_SAMPLES", N - 1)
    monkeypatch.setattr(allan_cli, "_CHUNK_ROWS", 1000)
    monkeypatch.setattr(allan_cli, "_CHUNK_HISTORY", 64)
    base = ["allan", str(path), "--column", "gyro_z", "--deviation", "mdev", "--json", "-"]
    auto = CliRunner().invoke(cli, base, prog_name="rotacal")
    assert auto.exit_code == 0, auto.output
    got = json.loads(auto.stdout)
    assert any("read in chunks" in note for note in got["notes"])
    whole = CliRunner().invoke(cli, [*base, "--in-memory", "--taus", "octave"], prog_name="rotacal")
    assert whole.exit_code == 0, whole.output
    ref = json.loads(whole.stdout)
    assert got["mdev_tau_s"] == ref["mdev_tau_s"]
    for key in ("mdev_deg_s", "mdev_low_deg_s", "mdev_high_deg_s", "mdev_edf", "adev_deg_s"):
        np.testing.assert_allclose(got[key], ref[key], rtol=1e-9, atol=0)
