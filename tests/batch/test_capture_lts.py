"""One LTS capture's sinusoidal-motion calibration split over the workers of a real
``distributed.LocalCluster``: the reversals and numbers of the single-process chunked path and
of the whole capture in memory, the same refusals with the same messages; the pieces it joins
(rank tallies, the trigger's runs) against one piece."""

from __future__ import annotations

import itertools
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from click.testing import CliRunner
from distributed import Client

import rotacal.table.streaming as streaming
from rotacal import sim
from rotacal.batch.capture_lts import calibrate_lts_motion_on_dask
from rotacal.batch.testing import largest_difference, split_and_one_process
from rotacal.cli import cli
from rotacal.errors import CaptureError
from rotacal.io import write_capture
from rotacal.table import _stream_lts as lts
from rotacal.table import (
    calibrate_lts_motion,
    calibrate_lts_motion_chunked,
    lts_chunks_from_file,
)
from rotacal.table.motion import _plot_stride

MOTION = sim.SineMotion(
    amplitude_deg=0.5, frequency_hz=2.0, harmonics={2: (0.010, 0.4), 3: (0.008, 1.1)}
)
R = 100.0
#: blocks of 2999 rows: ~10 blocks, reversing windows and accumulator blocks cut by them
ROWS = 2999
SET = {"set_amplitude_deg": 0.5, "set_frequency_hz": 2.0}


@pytest.fixture(scope="module")
def capture() -> dict[str, np.ndarray]:
    return sim.simulate_lts(MOTION, radius_mm=R, noise_mm=3e-5, seed=4).columns


@pytest.fixture(scope="module")
def npz(capture: dict[str, np.ndarray], tmp_path_factory: pytest.TempPathFactory) -> Path:
    return write_capture(tmp_path_factory.mktemp("lts") / "lts.npz", capture)


def test_tallies_of_blocks_give_the_exact_order_statistics() -> None:
    """The rank search fed with the blocks' tallies added up finds np.sort's values (ties
    and a narrow cluster that needs a second histogram included)."""
    rng = np.random.default_rng(3)
    x = np.concatenate([rng.normal(size=50_000), np.full(300, 0.25), 1e-9 * rng.random(4000)])
    rng.shuffle(x)
    blocks = np.array_split(x, 7)

    def count(keys: Any, gather: Any) -> lts.Tally:
        first, *rest = (lts.tally([b], keys, gather) for b in blocks)
        for part in rest:
            first.merge(part)
        return first

    ranks = [0, 1000, 27_000, 27_001, x.size - 1]
    got = lts.search_ranks(count, ranks, float(x.min()), float(x.max()))
    assert got == np.sort(x)[ranks].tolist()


def test_runs_joined_in_order_equal_one_piece(capture: dict[str, np.ndarray]) -> None:
    """The trigger's runs of pieces cut at an edge, just after one and at a first decision,
    joined with the state carried, give the extremes of the whole record as one piece."""
    t = capture["time_s"]
    x = lts.lts_angle(capture["displacement_mm"], R)
    mid, h = 0.5 * float(x.max() + x.min()), 0.25 * float(x.max() - x.min())
    state = np.where(x > mid + h, 1, np.where(x < mid - h, -1, 0))
    decided = np.flatnonzero(state)
    changes = decided[np.flatnonzero(np.diff(state[decided])) + 1]
    cuts = [0, int(decided[0]), int(changes[1]), int(changes[2]) + 1, int(changes[4]), x.size]
    step = _plot_stride(x.size)

    def extremes(bounds: list[int]) -> lts.Extremes:
        fold = lts.SwingFold(x.size, h)
        for a, b in itertools.pairwise(bounds):
            fold.add(lts.swing_runs(a, t[a:b], x[a:b], x[a:b], mid, h, step))
        return fold.finish()

    whole, cut = extremes([0, x.size]), extremes(cuts)
    assert whole.index.size >= 8
    for name in ("index", "time", "sign", "plot_t", "plot_angle"):
        assert np.array_equal(getattr(cut, name), getattr(whole, name)), name


def _one_process(path: Path, **kw: Any) -> Any:
    source = lts_chunks_from_file(path, chunk_rows=ROWS)
    return calibrate_lts_motion_chunked(source, radius_mm=R, **kw)


@pytest.mark.parametrize(
    ("gather", "kw"),
    [(None, SET), (1000, SET), (1000, {**SET, "drift": True})],
    ids=["gathered", "accumulated", "accumulated-drift"],
)
def test_split_over_workers_equals_one_process_and_memory(
    dask_client: Client,
    npz: Path,
    capture: dict[str, np.ndarray],
    monkeypatch: pytest.MonkeyPatch,
    gather: int | None,
    kw: dict[str, Any],
) -> None:
    if gather is not None:  # the accumulated fit (the analysed span is ~2.5e4 samples)
        monkeypatch.setattr(streaming, "_GATHER_MAX_SAMPLES", gather)
    seen: list[int] = []
    got = calibrate_lts_motion_on_dask(
        str(npz), client=dask_client, radius_mm=R, chunk_rows=ROWS, progress=seen.append, **kw
    )
    one = _one_process(npz, **kw)
    assert got.reversal_times_s.size >= 10
    assert np.array_equal(got.reversal_times_s, one.reversal_times_s)
    assert largest_difference(got.to_dict(), one.to_dict()) < 1e-9
    blocks = -(-capture["time_s"].size // ROWS)
    assert seen == list(range(1, len(seen) + 1)) and len(seen) > 5 * blocks
    if gather is None:  # and, gathered, the calibration of the whole capture in memory
        memory = calibrate_lts_motion(
            capture["time_s"], capture["displacement_mm"], radius_mm=R, **kw
        )
        assert np.array_equal(got.reversal_times_s, memory.reversal_times_s)
        assert largest_difference(got.to_dict(), memory.to_dict()) < 1e-9


def _nan(cols: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    cols["displacement_mm"][5 * ROWS + 17] = np.nan
    return cols


def _backwards(cols: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    cols["time_s"][3 * ROWS] = cols["time_s"][3 * ROWS - 1] - 1e-6  # across a block boundary
    return cols


def _reach(cols: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    cols["displacement_mm"][7 * ROWS + 3] = 2 * R
    return cols


def _short(cols: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    return {k: v[: 2 * ROWS] for k, v in cols.items()}  # under 3 reversals: too few


@pytest.mark.parametrize(
    ("damage", "word"),
    [
        (_nan, f"nan at row {5 * ROWS + 17} "),
        (_backwards, f"not strictly increasing at sample {3 * ROWS} "),
        (_reach, "more than R = 100 mm"),
        (_short, "reversing moment(s)"),
    ],
    ids=["nan", "time", "reach", "short"],
)
def test_a_bad_capture_is_refused_with_the_message_of_one_process(
    dask_client: Client, capture: dict[str, np.ndarray], tmp_path: Path, damage: Any, word: str
) -> None:
    bad = damage({k: v.copy() for k, v in capture.items()})
    path = write_capture(tmp_path / "bad.npz", bad)
    with pytest.raises(CaptureError) as one:
        _one_process(path)
    with pytest.raises(CaptureError) as split:
        calibrate_lts_motion_on_dask(str(path), client=dask_client, radius_mm=R, chunk_rows=ROWS)
    assert str(split.value) == str(one.value)
    assert word in str(split.value)


def test_the_command_splits_over_a_running_scheduler(
    dask_client: Client, npz: Path, tmp_path: Path
) -> None:
    address = dask_client.scheduler_info()["address"]
    args = ["motion", "lts", str(npz), "--radius-mm", str(R)]
    sets = ["--set-amplitude-deg", "0.5", "--set-frequency-hz", "2"]
    split, one = split_and_one_process([*args, *sets], address, tmp_path)
    assert largest_difference(split, one) < 1e-9


@pytest.mark.parametrize(
    "options", [["--workers", "2", "--scheduler", "tcp://x:1"], ["--workers", "2", "--in-memory"]]
)
def test_the_command_refuses_contradictory_options(npz: Path, options: list[str]) -> None:
    result = CliRunner().invoke(cli, ["motion", "lts", str(npz), "--radius-mm", str(R), *options])
    assert result.exit_code == 2 and "Traceback" not in result.output
