"""One fibre-optic gyro capture's sinusoidal-motion calibration split over the workers of a real
``distributed.LocalCluster``: the reversals and numbers of the single-process chunked path and
of the whole capture in memory, the same refusals with the same messages."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest
from distributed import Client

import rotacal.table.streaming as streaming
from rotacal import sim
from rotacal.batch.capture_fog import calibrate_fog_motion_on_dask
from rotacal.batch.testing import largest_difference, split_and_one_process
from rotacal.errors import CaptureError, ConfigError
from rotacal.io import write_capture
from rotacal.table import calibrate_fog_motion, calibrate_fog_motion_chunked, fog_chunks_from_file

MOTION = sim.SineMotion(
    amplitude_deg=0.5, frequency_hz=2.0, harmonics={2: (0.010, 0.4), 3: (0.008, 1.1)}
)
#: blocks of 2477 rows: ~8 blocks, accumulator blocks and zero crossings cut by them
ROWS = 2477
SET = {"set_amplitude_deg": 0.5, "set_frequency_hz": 2.0}


@pytest.fixture(scope="module")
def capture() -> dict[str, np.ndarray]:
    motion = sim.simulate_fog(MOTION, snr_db=40.0, bias_deg_s=0.02, duration_s=10.0, seed=5)
    return motion.columns


@pytest.fixture(scope="module")
def npz(capture: dict[str, np.ndarray], tmp_path_factory: pytest.TempPathFactory) -> Path:
    return write_capture(tmp_path_factory.mktemp("fog") / "fog.npz", capture)


def _one_process(path: Path, **kw: Any) -> Any:
    return calibrate_fog_motion_chunked(fog_chunks_from_file(path, chunk_rows=ROWS), **kw)


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
    if gather is not None:  # the accumulated fit, the angle's prefixes over the blocks
        monkeypatch.setattr(streaming, "_GATHER_MAX_SAMPLES", gather)
    seen: list[int] = []
    got = calibrate_fog_motion_on_dask(
        str(npz), client=dask_client, chunk_rows=ROWS, progress=seen.append, **kw
    )
    one = _one_process(npz, **kw)
    assert np.array_equal(got.reversal_times_s, one.reversal_times_s)
    assert largest_difference(got.to_dict(), one.to_dict()) < 1e-9
    assert seen == list(range(1, len(seen) + 1)) and len(seen) > 3 * (
        capture["time_s"].size // ROWS
    )
    if gather is None:  # and, gathered, the fit of the whole span in memory
        memory = calibrate_fog_motion(capture["time_s"], capture["rate_deg_s"], **kw)
        assert largest_difference(got.to_dict(), memory.to_dict()) < 1e-9


def test_a_slow_motion_takes_the_start_frequency_from_a_strided_copy(
    dask_client: Client, tmp_path: Path
) -> None:
    """The first 2²⁰ samples hold ~3 periods (< 4): the start frequency comes from every
    stride-th sample of the capture, which the split reads itself, as the check pass keeps it."""
    slow = sim.SineMotion(amplitude_deg=0.5, frequency_hz=0.15)
    cols = sim.simulate_fog(slow, snr_db=40.0, fs_hz=50_000.0, duration_s=26.0, seed=2).columns
    path = write_capture(tmp_path / "slow.npz", cols)
    got = calibrate_fog_motion_on_dask(str(path), client=dask_client, chunk_rows=1 << 18)
    one = calibrate_fog_motion_chunked(fog_chunks_from_file(path, chunk_rows=1 << 18))
    assert np.array_equal(got.reversal_times_s, one.reversal_times_s)
    assert largest_difference(got.to_dict(), one.to_dict()) < 1e-9


def _nan(cols: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    cols["rate_deg_s"][5 * ROWS + 17] = np.nan
    return cols


def _clip(cols: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    top = 0.8 * float(np.max(cols["rate_deg_s"]))
    cols["rate_deg_s"][:] = np.clip(cols["rate_deg_s"], -top, top)
    return cols


def _backwards(cols: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    cols["time_s"][3 * ROWS] = cols["time_s"][3 * ROWS - 1] - 1e-6  # across a block boundary
    return cols


def _short(cols: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    return {k: v[: 2 * ROWS // 5] for k, v in cols.items()}  # too few reversals


@pytest.mark.parametrize(
    ("damage", "word"),
    [
        (_nan, f"{5 * ROWS + 17}"),
        (_clip, "clipped"),
        (_backwards, f"{3 * ROWS}"),
        (_short, "reversing moment(s)"),
    ],
    ids=["nan", "clipped", "time", "short"],
)
def test_a_bad_capture_is_refused_with_the_message_of_one_process(
    dask_client: Client, capture: dict[str, np.ndarray], tmp_path: Path, damage: Any, word: str
) -> None:
    bad = damage({k: v.copy() for k, v in capture.items()})
    path = write_capture(tmp_path / "bad.npz", bad)
    with pytest.raises(CaptureError) as one:
        _one_process(path)
    with pytest.raises(CaptureError) as split:
        calibrate_fog_motion_on_dask(str(path), client=dask_client, chunk_rows=ROWS)
    assert str(split.value) == str(one.value)
    assert word in str(split.value)


def test_text_is_refused_before_any_work(
    dask_client: Client, capture: dict[str, np.ndarray], tmp_path: Path
) -> None:
    path = write_capture(tmp_path / "fog.csv", {k: v[:2000] for k, v in capture.items()})
    with pytest.raises(ConfigError, match="save it as NPZ without compression"):
        calibrate_fog_motion_on_dask(str(path), client=dask_client)


def test_the_command_splits_over_a_running_scheduler(
    dask_client: Client, npz: Path, tmp_path: Path
) -> None:
    address = dask_client.scheduler_info()["address"]
    split, one = split_and_one_process(
        ["motion", "fog", str(npz), "--set-amplitude-deg", "0.5", "--set-frequency-hz", "2"],
        address,
        tmp_path,
    )
    assert largest_difference(split, one) < 1e-9
