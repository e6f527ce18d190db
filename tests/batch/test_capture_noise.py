"""One capture's Allan deviation split over the workers of a real ``distributed.LocalCluster``:
the same numbers as the single-process streamed path and as the whole record in memory, the
same refusals with the same messages."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import h5py
import numpy as np
import pytest
from distributed import Client

from rotacal.batch.capture_noise import gyro_noise_on_dask
from rotacal.batch.testing import largest_difference, split_and_one_process
from rotacal.errors import CaptureError, ConfigError
from rotacal.gyro.noise import gyro_noise
from rotacal.gyro.noise_stream import gyro_noise_chunks
from rotacal.io import iter_capture_chunks

N, FS = 300_000, 100.0
#: small blocks and history: ~40 blocks, and both the short and the long cluster sizes
SPLIT = {"chunk_rows": 7777, "history": 1024}


def _record(seed: int = 1) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    rate = 3.0 + 0.01 * rng.standard_normal(N) + np.cumsum(1e-5 * rng.standard_normal(N))
    return np.arange(N) / FS, rate


@pytest.fixture(scope="module")
def npz(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("noise") / "noise.npz"
    t, rate = _record()
    np.savez(path, time_s=t, rate_deg_s=rate)
    return path


def _chunks(path: Path, taus: str) -> dict[str, Any]:
    chunks = iter_capture_chunks(path, ["rate_deg_s", "time_s"], chunk_rows=5000)
    return gyro_noise_chunks(chunks, taus=taus, history=SPLIT["history"]).to_dict()


@pytest.mark.parametrize("taus", ["octave", "decade"])
def test_split_over_workers_equals_one_process_and_memory(
    dask_client: Client, npz: Path, taus: str
) -> None:
    got = gyro_noise_on_dask(str(npz), client=dask_client, taus=taus, **SPLIT).to_dict()
    assert largest_difference(got, _chunks(npz, taus)) < 1e-9
    t, rate = _record()
    assert largest_difference(got, gyro_noise(rate, time_s=t, taus=taus).to_dict()) < 1e-9


def test_an_hdf5_capture_splits_too(dask_client: Client, npz: Path, tmp_path: Path) -> None:
    path = tmp_path / "noise.h5"
    t, rate = _record()
    with h5py.File(path, "w") as f:
        f["time_s"], f["rate_deg_s"] = t, rate
    got = gyro_noise_on_dask(str(path), client=dask_client, **SPLIT).to_dict()
    assert largest_difference(got, _chunks(npz, "octave")) < 1e-9


def _message(error: pytest.ExceptionInfo[Exception]) -> str:
    return str(error.value)


@pytest.mark.parametrize(
    "damage",
    [
        lambda t, r: r.__setitem__(123_456, np.nan),  # a NaN
        lambda t, r: t.__setitem__(slice(200_000, None), t[200_000:] + 5.0),  # a gap in time
        lambda t, r: t.__setitem__(10, t[9]),  # a repeated time stamp in the first block
        lambda t, r: np.minimum(r, np.quantile(r, 0.9), out=r),  # a rail
    ],
    ids=["nan", "gap", "order", "clipped"],
)
def test_a_bad_capture_is_refused_with_the_message_of_one_process(
    dask_client: Client, tmp_path: Path, damage: Any
) -> None:
    t, rate = _record()
    damage(t, rate)
    path = tmp_path / "bad.npz"
    np.savez(path, time_s=t, rate_deg_s=rate)
    with pytest.raises(CaptureError) as one:
        _chunks(path, "octave")
    with pytest.raises(CaptureError) as split:
        gyro_noise_on_dask(str(path), client=dask_client, **SPLIT)
    assert _message(split) == _message(one)


def test_text_is_refused_before_any_work(dask_client: Client, tmp_path: Path) -> None:
    path = tmp_path / "noise.csv"
    t, rate = _record()
    np.savetxt(
        path, np.c_[t[:2000], rate[:2000]], delimiter=",", header="time_s,rate_deg_s", comments=""
    )
    with pytest.raises(ConfigError, match="save it as NPZ without compression"):
        gyro_noise_on_dask(str(path), client=dask_client)


def test_the_command_splits_over_a_running_scheduler(
    dask_client: Client, npz: Path, tmp_path: Path
) -> None:
    address = dask_client.scheduler_info()["address"]
    split, one = split_and_one_process(["allan", str(npz), "--taus", "octave"], address, tmp_path)
    assert largest_difference(split, one) < 1e-9


@pytest.mark.parametrize("jit", [False, True])
def test_long_sums_from_increments_equal_the_literal_sum(jit: bool) -> None:
    """Σ d_i² of the second differences from the rates' increments (in pieces; Numba or NumPy)
    against the literal sum over the phase, and the two paths against each other."""
    from rotacal.batch.capture_noise import _PIECE, _squares_of_second_differences

    if jit:
        pytest.importorskip("numba")
    rng = np.random.default_rng(5)
    m, count = 700, 2 * _PIECE + 123
    rate = 3.0 + 0.01 * rng.standard_normal(count + 2 * m)
    x = np.r_[0.0, np.cumsum(rate - 3.0)]  # the offset taken out: x keeps its digits
    d = x[2 * m : 2 * m + count] - 2.0 * x[m : m + count] + x[:count]
    literal = math.fsum((d * d).tolist())
    r0, r1, r2 = (rate[o : o + count - 1] for o in (0, m, 2 * m))
    got = _squares_of_second_differences(float(d[0]), r0, r1, r2, jit)
    assert abs(got - literal) <= 1e-10 * literal
    assert abs(got - _squares_of_second_differences(float(d[0]), r0, r1, r2, not jit)) <= (
        1e-12 * literal
    )
