"""One pulse capture's rate analysis split over the workers of a real ``distributed.LocalCluster``:
the same numbers as the single-process streamed path and as the whole train in memory, the same
refusals with the same messages."""

from __future__ import annotations

import sys
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import cloudpickle
import numpy as np
import pytest
from click.testing import CliRunner
from distributed import Client

import rotacal.uncertainty.summaries_peak as summaries_peak
from rotacal.batch.capture_rate import calibrate_rate_on_dask
from rotacal.batch.testing import largest_difference, split_and_one_process
from rotacal.cli import cli
from rotacal.errors import CaptureError, ConfigError
from rotacal.sim.pulses import simulate_pulses
from rotacal.table.rate import calibrate_rate
from rotacal.table.rate_file import calibrate_rate_file

M = 900
#: blocks shorter than the jitter's 2m + 3 overlap and than the longest Allan terms (deferred
#: across several blocks), not a multiple of the average: a boundary inside a rate point
CHUNK = 997
#: Welch windows of this many rate points (here and on the workers): the windows and the peak's
#: filter cross many block boundaries
WINDOW = 512


def _set_window(size: int) -> None:
    summaries_peak.WINDOW = size


# the workers cannot import this test module (a worker's sys.path need not hold the checkout):
# its functions travel by value
cloudpickle.register_pickle_by_value(sys.modules[__name__])


@pytest.fixture(scope="module")
def windows(dask_client: Client) -> Iterator[None]:
    """Short Welch windows in this process and on every worker for the module's tests."""
    before = summaries_peak.WINDOW
    _set_window(WINDOW)
    dask_client.run(_set_window, WINDOW)
    yield
    _set_window(before)
    dask_client.run(_set_window, before)


@pytest.fixture(scope="module")
def twin(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path, np.ndarray]:
    """A two-head twin (m = 900, 60 revolutions) as NPZ; head 0 less its first 333 pulses alone
    as another NPZ; the deviation self-calibrated from the two heads (another capture for the
    one-head file: it is aligned)."""
    from rotacal.encoder.selfcal import self_calibrate

    cap = simulate_pulses(heads=2, pulses_per_rev=M, rate_deg_s=120.0, revolutions=60.0, seed=5)
    heads = [np.asarray(cap.columns["head_0"]), np.asarray(cap.columns["head_1"])]
    folder = tmp_path_factory.mktemp("pulses")
    np.savez(folder / "two.npz", head_0=heads[0], head_1=heads[1])
    np.savez(folder / "one.npz", head_0=heads[0][333:])
    deviation = np.asarray(self_calibrate(heads, pulses_per_rev=M).deviation_arcsec)
    return folder / "one.npz", folder / "two.npz", deviation


@pytest.mark.parametrize("given", [False, True], ids=["nominal", "aligned-deviation"])
def test_split_over_workers_equals_one_process_and_memory(
    dask_client: Client,
    windows: None,
    twin: tuple[Path, Path, np.ndarray],
    given: bool,
) -> None:
    one, _, deviation = twin
    kw: dict[str, Any] = {"pulses_per_rev": M, "set_rate_deg_s": 120.0}
    kw["selfcal"] = deviation if given else None
    got = calibrate_rate_on_dask(one, client=dask_client, chunk_rows=CHUNK, **kw)
    assert got.compensated is given
    assert (np.load(one)["head_0"].size - 1) // 10 > 5 * WINDOW  # rate points: many windows
    streamed = calibrate_rate_file(one, chunk_rows=CHUNK, **kw)
    assert largest_difference(got.to_dict(), streamed.to_dict()) < 1e-9
    memory = calibrate_rate([np.load(one)["head_0"]], **kw)
    assert largest_difference(got.to_dict(), memory.to_dict()) < 1e-9


def test_a_capture_self_calibrated_first(
    dask_client: Client,
    windows: None,
    twin: tuple[Path, Path, np.ndarray],
) -> None:
    """Two heads, nothing given: the client self-calibrates them, the rate's passes split."""
    _, two, _ = twin
    got = calibrate_rate_on_dask(two, client=dask_client, pulses_per_rev=M, chunk_rows=7777)
    assert got.compensated
    streamed = calibrate_rate_file(two, pulses_per_rev=M, chunk_rows=7777)
    assert largest_difference(got.to_dict(), streamed.to_dict()) < 1e-9


def test_the_first_fault_in_the_file_is_the_one_reported(
    dask_client: Client, twin: tuple[Path, Path, np.ndarray], tmp_path: Path
) -> None:
    """A pulse missing in a late block, a NaN in the block after the next one (within the
    rows the block before reads past its end) and a pair out of order: both paths name the
    pair, with the same message."""
    t = np.load(twin[0])["head_0"].copy()
    t = np.delete(t, 40_000)
    t[21_500] = np.nan
    t[20_001], t[20_002] = t[20_002], t[20_001]
    path = tmp_path / "bad.npz"
    np.savez(path, head_0=t)
    with pytest.raises(CaptureError) as one:
        calibrate_rate_file(path, pulses_per_rev=M, chunk_rows=CHUNK)
    with pytest.raises(CaptureError) as split:
        calibrate_rate_on_dask(path, client=dask_client, pulses_per_rev=M, chunk_rows=CHUNK)
    assert str(split.value) == str(one.value)
    assert "pulse 20002" in str(one.value)


def test_a_damaged_npz_is_refused_as_in_one_process(
    dask_client: Client, twin: tuple[Path, Path, np.ndarray], tmp_path: Path
) -> None:
    """A pulse time changed in its last bit after the file was written: still a valid train,
    only the archive's CRC-32 tells; both paths refuse it with the same message."""
    t = np.load(twin[0])["head_0"]
    data = bytearray(twin[0].read_bytes())
    at = bytes(data).find(t[30_000].tobytes())
    assert at > 0
    data[at] ^= 1
    path = tmp_path / "damaged.npz"
    path.write_bytes(bytes(data))
    with pytest.raises(CaptureError) as one:
        calibrate_rate_file(path, pulses_per_rev=M, chunk_rows=CHUNK)
    with pytest.raises(CaptureError) as split:
        calibrate_rate_on_dask(path, client=dask_client, pulses_per_rev=M, chunk_rows=CHUNK)
    assert str(split.value) == str(one.value)
    assert "CRC-32" in str(one.value)


def test_text_is_refused(dask_client: Client, tmp_path: Path) -> None:
    path = tmp_path / "pulses.csv"
    np.savetxt(path, np.arange(5000) / 1e3, header="head_0", comments="")
    with pytest.raises(ConfigError, match="save it as NPZ without compression"):
        calibrate_rate_on_dask(path, client=dask_client, pulses_per_rev=100)


def test_the_command_splits_over_a_running_scheduler(
    dask_client: Client,
    twin: tuple[Path, Path, np.ndarray],
    tmp_path: Path,
) -> None:
    address = dask_client.scheduler_info()["address"]
    split, one = split_and_one_process(
        ["rate", str(twin[0]), "--pulses-per-rev", str(M)], address, tmp_path
    )
    assert largest_difference(split, one) < 1e-9
    both = CliRunner().invoke(
        cli,
        [
            "rate",
            str(twin[0]),
            "--pulses-per-rev",
            str(M),
            "--workers",
            "2",
            "--scheduler",
            address,
        ],
    )
    assert both.exit_code == 2 and "not both" in both.output
