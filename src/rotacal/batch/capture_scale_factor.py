"""A long gyro log's scale factor and nonlinearity, as tasks on Dask distributed.

:func:`calibrate_scale_factor_on_dask` gives what
:func:`rotacal.gyro.scale_factor_stream.calibrate_scale_factor_chunked` gives for the same file
(≤ 1e-9 relative, tested), with the two passes of that method split over a cluster's workers,
each reading its own rows of the file (a shared file system; NPZ without compression, HDF5 or
TDMS):

* **Pass 1** — a task per block of ``chunk_rows`` rows finds the groups of set rates in its
  rows; the client merges them in row order into the rate points and makes the refusals of one
  pass (no rows, a single rate, blocks of the bandwidth longer than every point).
* **Pass 2** — a task per block sums everything per rate point (statistics, extremes, levels,
  rails, the resolution's blocks, the quantum's samples) from a state that does not depend on
  the rows before: its first row and the samples of each point before it, known from pass 1.
  The client merges the blocks in row order (:mod:`rotacal.gyro.scale_factor_merge`) and the
  result comes from the merged sums as in one pass, with the same refusals and messages.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator, Mapping, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from rotacal.batch._blocks import CaptureRows, Ticks, block_starts, open_capture, task_round

if TYPE_CHECKING:
    from distributed import Client

    from rotacal.gyro.scale_factor import _Options
    from rotacal.gyro.scale_factor_result import ScaleFactorResult
    from rotacal.gyro.scale_factor_stream import _PointSums, _RatePoints
    from rotacal.io.read_options import ReadOptions

__all__ = ["calibrate_scale_factor_on_dask"]

#: Rows of a block: the unit of work of a task (two columns of 16 MB; pass 2 sorts each block's
#: samples by rate point: 4·10⁶-row blocks cost 12 % more a sample, measured at 10⁸ rows).
CHUNK_ROWS = 1 << 21
_RATE, _OUTPUT = "rate_deg_s", "output"


def _points_task(source: CaptureRows, a: int, b: int, tol: float) -> _RatePoints:
    """Pass 1 over rows [a, b): the groups of set rates (tolerance ``tol``, °/s)."""
    from rotacal.gyro.scale_factor_stream import _RatePoints

    points = _RatePoints(tol, start=a)
    points.add(source.column(_RATE, a, b))
    return points


def _sums_task(
    source: CaptureRows, a: int, b: int, points: _RatePoints, opts: _Options, seen: np.ndarray
) -> _PointSums:
    """Pass 2 over rows [a, b), each rate point having ``seen`` samples before row a."""
    from rotacal.gyro.scale_factor_stream import _PointSums

    rows = source.read(a, b)
    sums = _PointSums(points, opts, start=a, seen=seen)
    sums.add(rows[_RATE], rows[_OUTPUT])
    return sums


def calibrate_scale_factor_on_dask(
    path: str,
    *,
    client: Client,
    mapping: dict[str, str] | None = None,
    group: str | None = None,
    read_options: ReadOptions | None = None,
    chunk_rows: int = CHUNK_ROWS,
    progress: Callable[[int], None] | None = None,
    **options: Any,
) -> ScaleFactorResult:
    """Scale factor, bias and nonlinearity of a gyro from a rate-table log, computed by the
    workers of a Dask cluster (see the module for how the log is split).

    Parameters
    ----------
    path : str
        The log (NPZ saved without compression, HDF5 or TDMS) with columns ``rate_deg_s`` (set
        rate, °/s) and ``output`` (output units), at a path every worker sees.
    client : distributed.Client
        The cluster's client.
    mapping, group, read_options
        How to read the log, as :func:`rotacal.io.read_capture`.
    chunk_rows : int
        Rows of a task's block.
    progress : callable, optional
        Called with the number of tasks done so far (two rounds of one task per block).
    **options
        The keywords of :func:`~rotacal.gyro.scale_factor.calibrate_scale_factor`
        (``full_scale_deg_s`` in °/s, ``requirement``, ``rate_tolerance_deg_s`` in °/s,
        ``output_unit``, ``specs``, ``mc_trials``, ``sample_rate_hz`` and ``bandwidth_hz`` in Hz,
        ``allow_clipped``, ``nan_policy``), with the same defaults.

    Returns
    -------
    ScaleFactorResult
        As ``calibrate_scale_factor_chunked`` over the same file to ≤ 1e-9 relative.

    Raises
    ------
    CaptureError, ConfigError
        As the single-process path, with the same messages; ConfigError also for a log that
        cannot be read from a given row on (CSV, a compressed NPZ member) or a bad chunk_rows.

    References
    ----------
    Kokuyama et al. (2015), §4; Chan, Golub & LeVeque (1983), eq. 2.1.
    """
    from rotacal.gyro.scale_factor import _check_options
    from rotacal.gyro.scale_factor_merge import merge_point_sums, merge_rate_points, points_seen
    from rotacal.gyro.scale_factor_stream import _Reader, check_points, result_of_sums
    from rotacal.io import iter_capture_chunks

    opts = _check_options(**options)
    source, n = open_capture(
        path, (_RATE, _OUTPUT), _RATE, chunk_rows, mapping, group, read_options
    )
    reading: dict[str, Any] = {"mapping": mapping, "group": group, "read_options": read_options}
    starts = block_starts(n, chunk_rows)
    tick = Ticks(progress)

    def chunks(names: Sequence[str]) -> Iterator[Mapping[str, np.ndarray]]:
        return iter_capture_chunks(path, list(names), chunk_rows=chunk_rows, **reading)

    blocks = [(a, min(n, a + chunk_rows)) for a in starts]
    parts = task_round(client, _points_task, [(source, a, b, opts.tol) for a, b in blocks], tick)
    points = merge_rate_points(parts) if parts else _empty_points(opts.tol)
    check_points(points, opts)
    seen = points_seen(parts, points)
    sums = task_round(
        client,
        _sums_task,
        [(source, a, b, points, opts, s) for (a, b), s in zip(blocks, seen, strict=True)],
        tick,
    )
    # a refusal that must find rows (a rate point with no finite output) reads in one pass
    return result_of_sums(points, merge_point_sums(sums), opts, _Reader(chunks, None))


def _empty_points(tol: float) -> _RatePoints:
    from rotacal.gyro.scale_factor_stream import _RatePoints

    return _RatePoints(tol)
