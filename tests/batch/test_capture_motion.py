"""One encoder capture's sinusoidal-motion calibration split over the workers of a real
``distributed.LocalCluster``: the reversals and numbers of the single-process chunked path and
of the whole capture in memory, the same refusals with the same messages."""

from __future__ import annotations

import itertools
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from distributed import Client

import rotacal.table.streaming as streaming
from rotacal import sim
from rotacal.batch.capture_motion import _entry_states, calibrate_encoder_motion_on_dask
from rotacal.batch.testing import largest_difference, split_and_one_process
from rotacal.encoder import correct_quadrature, fit_quadrature_correction
from rotacal.encoder._kernel import phase_pass
from rotacal.errors import CaptureError, ConfigError
from rotacal.io import write_capture
from rotacal.table import (
    calibrate_encoder_motion,
    calibrate_encoder_motion_chunked,
    encoder_chunks_from_file,
)

LINES = 36000
MOTION = sim.SineMotion(
    amplitude_deg=0.5, frequency_hz=2.0, harmonics={2: (0.010, 0.4), 3: (0.008, 1.1)}
)
#: blocks of 9973 rows: ~20 blocks, reversing windows and accumulator blocks cut by them
ROWS = 9973
SET = {"set_amplitude_deg": 0.5, "set_frequency_hz": 2.0}


@pytest.fixture(scope="module")
def capture() -> dict[str, np.ndarray]:
    return sim.simulate_encoder(
        MOTION, offset_a=0.03, amplitude_b=0.97, noise_rms=0.004, adc_bits=16, seed=5
    ).columns


@pytest.fixture(scope="module")
def npz(capture: dict[str, np.ndarray], tmp_path_factory: pytest.TempPathFactory) -> Path:
    return write_capture(tmp_path_factory.mktemp("motion") / "enc.npz", capture)


def test_entry_states_carry_the_cycles_over_a_wrap_at_a_block_start(
    capture: dict[str, np.ndarray],
) -> None:
    """Blocks that start just after the wrapped phase jumps (both ways): the states chained
    from each block unwrapped alone are those of one pass over the blocks in order."""
    a, b = capture["a"], capture["b"]
    corr = fit_quadrature_correction(a, b)
    u, v = correct_quadrature(a, b, corr)
    d = np.diff(np.arctan2(v, u))
    up, down = np.flatnonzero(d > np.pi) + 1, np.flatnonzero(d < -np.pi) + 1
    cuts = [0, *sorted({int(up[5]), int(down[5]), int(up[60]), int(down[60])}), a.size]
    ends = []
    for lo, hi in itertools.pairwise(cuts):
        run = phase_pass(a[lo:hi], b[lo:hi], corr, jit=False)
        ends.append((float(run.phase_rad[0]), run.state))
    state = None
    for (lo, hi), entry in zip(itertools.pairwise(cuts), _entry_states(ends), strict=True):
        assert entry == state
        state = phase_pass(a[lo:hi], b[lo:hi], corr, state=state, jit=False).state


def _one_process(path: Path, **kw: Any) -> Any:
    source = encoder_chunks_from_file(path, chunk_rows=ROWS)
    return calibrate_encoder_motion_chunked(source, lines=LINES, **kw)


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
    if gather is not None:  # the accumulated fit (the analysed span is ~1.3e5 samples)
        monkeypatch.setattr(streaming, "_GATHER_MAX_SAMPLES", gather)
    seen: list[int] = []
    got = calibrate_encoder_motion_on_dask(
        str(npz), client=dask_client, lines=LINES, chunk_rows=ROWS, progress=seen.append, **kw
    )
    one = _one_process(npz, **kw)
    assert np.array_equal(got.reversal_times_s, one.reversal_times_s)
    assert largest_difference(got.to_dict(), one.to_dict()) < 1e-9
    assert seen == list(range(1, len(seen) + 1)) and len(seen) > 3 * (capture["a"].size // ROWS)
    if gather is None:  # and, gathered, the fit of the whole span in memory
        memory = calibrate_encoder_motion(
            capture["time_s"], capture["a"], capture["b"], lines=LINES, **kw
        )
        assert np.array_equal(got.reversal_times_s, memory.reversal_times_s)
        assert largest_difference(got.to_dict(), memory.to_dict()) < 1e-9


def _nan(cols: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    cols["b"][5 * ROWS + 17] = np.nan
    return cols


def _clip(cols: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    cols["a"][:] = np.clip(cols["a"], -0.8, 0.8)
    return cols


def _backwards(cols: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    cols["time_s"][3 * ROWS] = cols["time_s"][3 * ROWS - 1] - 1e-6  # across a block boundary
    return cols


def _short(cols: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    return {k: v[: 2 * ROWS] for k, v in cols.items()}  # 2 reversals: too few


@pytest.mark.parametrize(
    ("damage", "word"),
    [
        (_nan, f"nan at row {5 * ROWS + 17} "),
        (_clip, "clipped"),
        (_backwards, f"not strictly increasing at sample {3 * ROWS} "),
        (_short, "2 reversing moment(s)"),
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
        calibrate_encoder_motion_on_dask(
            str(path), client=dask_client, lines=LINES, chunk_rows=ROWS
        )
    assert str(split.value) == str(one.value)
    assert word in str(split.value)


def test_text_is_refused_before_any_work(
    dask_client: Client, capture: dict[str, np.ndarray], tmp_path: Path
) -> None:
    path = write_capture(tmp_path / "enc.csv", {k: v[:2000] for k, v in capture.items()})
    with pytest.raises(ConfigError, match="save it as NPZ without compression"):
        calibrate_encoder_motion_on_dask(str(path), client=dask_client, lines=LINES)


def test_the_command_splits_over_a_running_scheduler(
    dask_client: Client, npz: Path, tmp_path: Path
) -> None:
    address = dask_client.scheduler_info()["address"]
    split, one = split_and_one_process(
        ["motion", "encoder", str(npz), "--lines", str(LINES)], address, tmp_path
    )
    assert largest_difference(split, one) < 1e-9
