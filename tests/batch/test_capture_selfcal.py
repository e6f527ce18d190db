"""A multi-head encoder's self-calibration split over the workers of a real
``distributed.LocalCluster``: the same numbers as the single-process chunked path (itself tested
against the in-memory one), the same refusals with the same messages, and the command."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from click.testing import CliRunner
from distributed import Client

from rotacal.batch import capture_selfcal
from rotacal.batch.capture_selfcal import self_calibrate_on_dask
from rotacal.batch.testing import largest_difference, split_and_one_process
from rotacal.cli import cli
from rotacal.encoder import self_calibrate_chunked
from rotacal.errors import CaptureError
from rotacal.io import iter_capture_chunks
from rotacal.sim.pulses import simulate_pulses

M = 360
#: rows read at a time by the first pass, head-0 pulses per task of the second (2 revolutions):
#: neither divides the other nor the heads' lengths
CHUNK, BLOCK = 1000, 800


def _heads(seed: int = 3) -> list[np.ndarray]:
    """5 heads on 360 lines, 9.6 revolutions; head 2 starts 40 pulses late, head 3 stops
    early (the pairing's index offsets and notes)."""
    cap = simulate_pulses(heads=5, pulses_per_rev=M, revolutions=9.6, seed=seed)
    heads = [np.asarray(cap.columns[f"head_{i}"]) for i in range(5)]
    heads[2] = heads[2][40:]
    heads[3] = heads[3][:-100]
    return heads


def _save(path: Path, heads: list[np.ndarray]) -> Path:
    np.savez(path, **{f"head_{i}": h for i, h in enumerate(heads)})
    return path


def _one_process(path: Path, n: int, **kw: Any) -> Any:
    def head(name: str) -> Iterator[np.ndarray]:
        return (c[name] for c in iter_capture_chunks(path, [name], chunk_rows=CHUNK))

    return self_calibrate_chunked(
        lambda: [head(f"head_{i}") for i in range(n)],
        pulses_per_rev=M,
        block_pulses=BLOCK,
        **kw,
    )


def _split(client: Client, path: Path, n: int, **kw: Any) -> Any:
    return self_calibrate_on_dask(
        str(path),
        client=client,
        heads=n,
        pulses_per_rev=M,
        chunk_rows=CHUNK,
        block_pulses=BLOCK,
        **kw,
    )


@pytest.fixture(scope="module")
def capture(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return _save(tmp_path_factory.mktemp("selfcal") / "heads.npz", _heads())


@pytest.mark.parametrize("rotation", ["auto", "reverse"])
def test_split_over_workers_equals_one_process(
    dask_client: Client, capture: Path, rotation: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(capture_selfcal, "WAVE", 2)  # the fit's blocks asked in several waves
    ticks: list[int] = []
    got = _split(dask_client, capture, 5, rotation=rotation, progress=ticks.append)
    one = _one_process(capture, 5, rotation=rotation)
    assert any("head_2 starts" in n for n in one.notes)
    assert one.revolutions_used == 9
    assert one.deviation_pp_arcsec > 1.0 or rotation == "reverse"  # reverse: the wrong sense
    assert largest_difference(got.to_dict(), one.to_dict()) < 1e-9
    np.testing.assert_array_equal(got.per_revolution_arcsec, one.per_revolution_arcsec)
    paired = 3456 - 40 - 100  # head 0's pulses that every head covers
    assert ticks[-1] == 2 + -(-paired // (2 * M))  # a group of heads per worker, a task per block


def _gaps(heads: list[np.ndarray]) -> None:
    """Head 3 loses a pulse early, head 1 later (head 1 is read before head 3 in each chunk,
    and the two are in different tasks of the first pass): head 3's is the first in time."""
    heads[1] = np.delete(heads[1], 2500)
    heads[3] = np.delete(heads[3], 1200)


def _copy(heads: list[np.ndarray]) -> None:
    """Refused once every train is read, by the client."""
    heads[2] = heads[0] + 1e-4


def _drift(heads: list[np.ndarray]) -> None:
    """Head 4 runs away from head 0 late in the record: a check of the fit's block that holds
    it."""
    t = heads[4]
    t[3000:] += np.linspace(0.0, 2.0, t.size - 3000) * float(np.median(np.diff(t)))


@pytest.mark.parametrize(
    ("spoil", "match"),
    [
        (_gaps, "column 'head_3'"),
        (_copy, "'head_2' is a copy of head_0"),
        (_drift, "'head_4' drifts against head_0"),
    ],
)
def test_a_bad_capture_is_refused_with_the_message_of_one_process(
    dask_client: Client, tmp_path: Path, spoil: Any, match: str
) -> None:
    heads = _heads()
    spoil(heads)
    path = _save(tmp_path / "bad.npz", heads)
    with pytest.raises(CaptureError) as one:
        _one_process(path, 5)
    with pytest.raises(CaptureError) as split:
        _split(dask_client, path, 5)
    assert str(split.value) == str(one.value)
    assert match in str(one.value)


def test_the_command_splits_over_a_running_scheduler(
    dask_client: Client, capture: Path, tmp_path: Path
) -> None:
    address = dask_client.scheduler_info()["address"]
    args = ["selfcal", str(capture), "--pulses-per-rev", str(M)]
    split, one = split_and_one_process(args, address, tmp_path)
    assert largest_difference(split, one) < 1e-9
    both = CliRunner().invoke(cli, [*args, "--workers", "2", "--scheduler", address])
    assert both.exit_code == 2 and "not both" in both.output
    memory = CliRunner().invoke(cli, [*args, "--workers", "2", "--in-memory"])
    assert memory.exit_code == 2 and "--in-memory" in memory.output
