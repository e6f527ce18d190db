"""A long gyro log's scale factor split over the workers of a real ``distributed.LocalCluster``:
the same numbers as the single-process streamed path, the same refusals with the same messages;
and the merges it rests on (rails, pass 1 and pass 2 of blocks) against one pass, without a
cluster."""

from __future__ import annotations

import itertools
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from distributed import Client

from rotacal.batch.capture_scale_factor import calibrate_scale_factor_on_dask
from rotacal.batch.testing import largest_difference, split_and_one_process
from rotacal.errors import CaptureError
from rotacal.gyro.scale_factor import _check_options
from rotacal.gyro.scale_factor_merge import merge_point_sums, merge_rate_points, points_seen
from rotacal.gyro.scale_factor_stream import (
    _PointSums,
    _RatePoints,
    calibrate_scale_factor_chunked,
    check_points,
    result_of_sums,
    scale_factor_chunks,
)
from rotacal.io import iter_capture_chunks
from rotacal.signal.clipping import RailDetector

#: blocks of the split (several per rate point, and points that come back later in the log)
CHUNK = 7777
#: the resolution's blocks of 10 samples (5 Hz of 100 Hz) carried across blocks of the split
OPTIONS = {"sample_rate_hz": 100.0, "bandwidth_hz": 5.0, "allow_clipped": True}


def _log(seed: int = 2, clip: float | None = None) -> tuple[np.ndarray, np.ndarray]:
    """A continuous rate-table log at 100 Hz: plateaus of uneven lengths, the rates visited
    twice (up, then down); the output quantised (levels), optionally clipped."""
    rng = np.random.default_rng(seed)
    up = [-100.0, -30.0, -10.0, 0.0, 10.0, 30.0, 100.0]
    rates = np.repeat(up + up[::-1], rng.integers(1500, 4000, 2 * len(up)))
    output = 0.0123 * rates + 0.004 + 1e-6 * rates**2 + rng.normal(0.0, 0.002, rates.size)
    output = np.round(output / 0.0005) * 0.0005
    if clip is not None:
        output = np.minimum(output, clip)
    return rates, output


def _one_pass(path: Path, **options: Any) -> dict[str, Any]:
    def chunks(names: Any) -> Any:
        return iter_capture_chunks(path, list(names), chunk_rows=5000)

    return calibrate_scale_factor_chunked(chunks, **options).to_dict()


@pytest.fixture(scope="module")
def npz(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("scale") / "log.npz"
    rates, output = _log(clip=1.2)
    np.savez(path, rate_deg_s=rates, output=output)
    return path


def test_split_over_workers_equals_one_process(dask_client: Client, npz: Path) -> None:
    ticks: list[int] = []
    got = calibrate_scale_factor_on_dask(
        str(npz), client=dask_client, chunk_rows=CHUNK, progress=ticks.append, **OPTIONS
    ).to_dict()
    one = _one_pass(npz, **OPTIONS)
    assert any("clipped" in w for w in one["warnings"])  # the rails' merge is exercised
    assert largest_difference(got, one) < 1e-9
    assert ticks[-1] == 2 * -(-np.load(npz)["output"].size // CHUNK)


def test_a_bad_log_is_refused_with_the_message_of_one_process(
    dask_client: Client, tmp_path: Path
) -> None:
    rates, _ = _log()
    path = tmp_path / "copy.npz"
    np.savez(path, rate_deg_s=rates, output=rates.copy())  # the output copies the set rate
    with pytest.raises(CaptureError) as one:
        _one_pass(path)
    with pytest.raises(CaptureError) as split:
        calibrate_scale_factor_on_dask(str(path), client=dask_client, chunk_rows=CHUNK)
    assert str(split.value) == str(one.value)


def test_the_command_splits_over_a_running_scheduler(
    dask_client: Client, npz: Path, tmp_path: Path
) -> None:
    address = dask_client.scheduler_info()["address"]
    split, one = split_and_one_process(
        ["gyro", "scale-factor", str(npz), "--allow-clipped"], address, tmp_path
    )
    assert largest_difference(split, one) < 1e-9


@pytest.mark.parametrize("seed", range(3))
def test_blocks_merged_in_order_equal_one_pass(seed: int) -> None:
    """Pass 1 and pass 2 of uneven blocks, each fed in chunks of its own, merged in row order:
    the result of one pass over the whole log (resolution blocks carried across the cuts)."""
    rng = np.random.default_rng(seed)
    rates, output = _log(seed, clip=None if seed % 2 else 1.2)
    if seed % 3 == 0:
        order = rng.permutation(rates.size)  # every point in every block
        rates, output = rates[order], output[order]
    opts = _check_options(**OPTIONS)
    one = calibrate_scale_factor_chunked(
        scale_factor_chunks(rates, output, chunk_rows=3001), **OPTIONS
    ).to_dict()
    cuts = [0, *sorted(set(rng.integers(1, rates.size, 7).tolist())), rates.size]
    blocks = list(itertools.pairwise(cuts))
    first = []
    for a, b in blocks:
        part = _RatePoints(opts.tol, start=a)
        part.add(rates[a:b])
        first.append(part)
    points = merge_rate_points(first)
    check_points(points, opts)
    second = []
    for (a, b), seen in zip(blocks, points_seen(first, points), strict=True):
        sums = _PointSums(points, opts, start=a, seen=seen)
        for s in range(a, b, 1234):
            sums.add(rates[s : min(b, s + 1234)], output[s : min(b, s + 1234)])
        second.append(sums)
    got = result_of_sums(points, merge_point_sums(second), opts, None).to_dict()  # type: ignore[arg-type]
    assert largest_difference(got, one) < 1e-9


def _state(det: RailDetector) -> tuple[Any, ...]:
    """What the verdict reads of a detector (a run of one sample counts as one)."""
    det.extremes()
    sides = [
        (s.value, s.count, s.first, max(s.run, 1), s.next_value, s.next_count)
        for s in (det._hi, det._lo)
    ]
    kept = np.concatenate(det._kept).tolist()
    return det._n, det._finite, sides, max(det._elsewhere_run, 1), det._stride, kept


@pytest.mark.parametrize("kind", ["noise", "clipped", "plateaus", "sine"])
def test_rail_detectors_of_blocks_merge_into_one_pass(kind: str) -> None:
    rng = np.random.default_rng(len(kind))
    n = 5000
    x = {
        "noise": np.round(rng.normal(0.0, 2.0, n)),
        "clipped": np.clip(np.round(rng.normal(0.0, 3.0, n)), -2.0, 3.0),
        "plateaus": np.repeat(rng.integers(0, 4, n), rng.integers(1, 30, n))[:n].astype(float),
        "sine": np.round(4.0 * np.sin(np.arange(n) / 50.0)),
    }[kind]
    one = RailDetector("x")
    for s in range(0, n, 97):
        one.add(x[s : s + 97])
    for trial in range(20):
        cuts = [0, *sorted(set(rng.integers(1, n, trial % 9).tolist())), n]
        merged = None
        for a, b in itertools.pairwise(cuts):
            part = RailDetector("x", n, start=a)
            for s in range(a, b, 50):
                part.add(x[s : min(b, s + 50)])
            if merged is None:
                merged = part
            else:
                merged.merge(part)
        assert merged is not None
        assert _state(merged) == _state(one)
        assert merged.result() == one.result()
