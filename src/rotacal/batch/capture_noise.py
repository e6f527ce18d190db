"""One huge rate capture's Allan deviation and noise terms, as tasks on Dask distributed.

:func:`gyro_noise_on_dask` gives what :func:`rotacal.gyro.noise_stream.gyro_noise_chunks` gives
for the same file (≤ 1e-9 relative, tested), with the work split over a cluster's workers, each
reading its own rows of the file (a shared file system; NPZ without compression, HDF5 or TDMS):

* **Checks** — one task reads the file through once, in order, with every check of the
  single-process path: the stored checksums, NaN/inf and absurd values, the time column (order,
  gaps, constant rate; the sampling rate) and the rails of clipping, which carry state from row
  to row. It runs beside the sums; its error, if any, is the one reported.
* **Short cluster sizes** (2m ≤ ``history``) — a task per block of ``chunk_rows`` rows
  [a, b) sums the second differences x_{i+2m} − 2x_{i+m} + x_i with i in [a, b), from the rows
  [a, b + history): a second difference does not change when a constant is added to the phase,
  so each task integrates its own rows from zero. It also returns Σ(rate − c) over [a, b).
* **Long cluster sizes** — with the blocks' sums the client knows the phase x at every block
  boundary exactly as a sum of sums. A task per block then reads the three windows at i, i + m
  and i + 2m and adds the second difference at i = a, D = x_{a+2m} − 2x_{a+m} + x_a, to their
  integrals from zero.

The sums of disjoint blocks add up to the whole record's (NIST SP 1065 eq. (11)); the deviation,
its confidence interval and the noise terms then come from them as on one machine.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import TYPE_CHECKING

import numpy as np

from rotacal.batch._blocks import CaptureRows, block_starts, task_round
from rotacal.errors import CaptureError, ConfigError

if TYPE_CHECKING:
    from distributed import Client

    from rotacal.gyro.noise import GyroNoise
    from rotacal.io.read_options import ReadOptions
    from rotacal.uncertainty.specs import InstrumentSpecs

__all__ = ["gyro_noise_on_dask"]

#: Rows of a block: the unit of work of a task (32 MB of float64).
CHUNK_ROWS = 1 << 22
#: Rows read at the start to choose the offset c subtracted from the rate (keeps the phase small).
_OFFSET_ROWS = 1 << 16


def _rate(source: CaptureRows, start: int, stop: int) -> np.ndarray:
    """Rows ``start`` … ``stop - 1`` of the rate column (validated)."""
    return source.column(source.columns[0], start, stop)


def _check_task(
    source: CaptureRows, with_time: bool, fs_hz: float | None, allow_clipped: bool, rows: int
) -> tuple[int, float, tuple[str, ...], float, float]:
    """Read the capture through once with every check of the single-process path: the number
    of samples, the sampling rate (Hz), the clipping warnings and the rate's extremes."""
    from rotacal.gyro.noise_stream import NoiseChecks
    from rotacal.io import iter_capture_chunks
    from rotacal.signal._values import check_magnitudes

    name = source.columns[0]
    checks = NoiseChecks(name, fs_hz)
    n, low, high = 0, math.inf, -math.inf
    columns = [name, *(["time_s"] if with_time else [])]
    for chunk in iter_capture_chunks(
        source.path,
        columns,
        chunk_rows=rows,
        mapping=source.mapping,
        group=source.group,
        read_options=source.read_options,
    ):
        rate = checks.add(chunk)
        check_magnitudes(name, rate, what="rate data", offset=n)
        low, high = min(low, float(rate.min())), max(high, float(rate.max()))
        n += rate.size
    fs, clipped = checks.finish(n, allow_clipped)
    return n, fs, clipped, low, high


def _short_task(
    source: CaptureRows, a: int, b: int, n: int, c: float, ms: np.ndarray, history: int
) -> tuple[float, np.ndarray]:
    """Σ(rate − c) over rows [a, b), and S(m) over the second differences at i in [a, b) of
    each short cluster size ``ms`` (2m ≤ history), in (rate × sample interval)²."""
    from rotacal.signal._allan_fast import direct_sums

    r = _rate(source, a, min(n, b + history)) - c
    block = float(np.sum(r[: b - a]))
    x = np.zeros(r.size + 1)
    np.cumsum(r, out=x[1:])  # x[t] = phase at a + t, less the phase at a
    sums = np.zeros(ms.size)
    for k, m in enumerate(ms.tolist()):
        count = min(b, n - 2 * m + 1) - a  # terms i in [a, b) with i + 2m ≤ n
        if count > 0:
            sums[k] = direct_sums(x[: count + 2 * m], np.array([m], dtype=np.int64))[0]
    return block, sums


def _phase_at(source: CaptureRows, p: int, boundary: np.ndarray, rows: int, c: float) -> float:
    """x_p (phase at sample p, offset c removed) from the block boundaries' phases and the rows
    between p's block boundary and p."""
    k = p // rows
    return float(boundary[k]) + float(np.sum(_rate(source, k * rows, p) - c))


def _long_task(
    source: CaptureRows,
    a: int,
    b: int,
    n: int,
    c: float,
    ms: np.ndarray,
    boundary: np.ndarray,
    rows: int,
) -> np.ndarray:
    """S(m) over the second differences at i in [a, b) of each long cluster size ``ms``."""

    def integral(start: int, count: int) -> np.ndarray:
        x = np.zeros(count)
        np.cumsum(_rate(source, start, start + count - 1) - c, out=x[1:])
        return x

    sums = np.zeros(ms.size)
    base = integral(a, b - a + 1)
    for k, m in enumerate(ms.tolist()):
        count = min(b, n - 2 * m + 1) - a
        if count <= 0:
            continue
        at = [_phase_at(source, p, boundary, rows, c) for p in (a, a + m, a + 2 * m)]
        d = integral(a + 2 * m, count) - 2.0 * integral(a + m, count)
        d += base[:count]
        d += at[2] - 2.0 * at[1] + at[0]
        sums[k] = float(np.dot(d, d))
    return sums


def _sums(
    client: Client,
    source: CaptureRows,
    starts: list[int],
    n: int,
    c: float,
    short: np.ndarray,
    long: np.ndarray,
    history: int,
    rows: int,
    tick: Callable[[], None],
) -> dict[int, float]:
    """S(m) of every cluster size: the short ones and the blocks' sums in one round of tasks,
    then the long ones (which need the phase at every block boundary) in a second."""
    blocks = task_round(
        client,
        _short_task,
        [(source, a, min(n, a + rows), n, c, short, history) for a in starts],
        tick,
    )
    sums = {int(m): math.fsum(s[k] for _, s in blocks) for k, m in enumerate(short.tolist())}
    if not long.size:
        return sums
    # the phase at each block boundary, a correctly rounded sum of the blocks' sums
    boundary = np.array([math.fsum(b for b, _ in blocks[:k]) for k in range(len(blocks) + 1)])
    parts = task_round(
        client,
        _long_task,
        [(source, a, min(n, a + rows), n, c, long, boundary, rows) for a in starts],
        tick,
    )
    for k, m in enumerate(long.tolist()):
        sums[int(m)] = math.fsum(p[k] for p in parts)
    return sums


def gyro_noise_on_dask(
    path: str,
    *,
    client: Client,
    column: str = "rate_deg_s",
    fs_hz: float | None = None,
    unit: str = "deg/s",
    taus: str = "octave",
    specs: InstrumentSpecs | None = None,
    allow_clipped: bool = False,
    mapping: dict[str, str] | None = None,
    group: str | None = None,
    read_options: ReadOptions | None = None,
    chunk_rows: int = CHUNK_ROWS,
    history: int | None = None,
    progress: Callable[[int], None] | None = None,
) -> GyroNoise:
    """Overlapping Allan deviation and IEEE 952 noise terms of one rate capture, computed by the
    workers of a Dask cluster (see the module for how the record is split).

    Parameters
    ----------
    path : str
        The capture (NPZ saved without compression, HDF5 or TDMS), at a path every worker sees.
    client : distributed.Client
        The cluster's client.
    column, fs_hz, unit, taus, specs, allow_clipped
        As :func:`rotacal.gyro.noise_stream.gyro_noise_chunks` (fs in Hz; τ at octaves or
        decades).
    mapping, group, read_options
        How to read the capture, as :func:`rotacal.io.read_capture`.
    chunk_rows : int
        Rows of a task's block.
    history : int, optional
        Cluster sizes with 2m ≤ history are summed from a block and the rows after it
        [default: that of the single-process path, :data:`rotacal.signal.allan_stream.DEFAULT_HISTORY`].
    progress : callable, optional
        Called with the number of tasks done so far.

    Returns
    -------
    GyroNoise
        As ``gyro_noise_chunks`` over the same file to ≤ 1e-9 relative.

    Raises
    ------
    CaptureError, ConfigError
        As the single-process path, with the same messages; ConfigError also for a capture that
        cannot be read from a given row on (CSV, a compressed NPZ member).

    References
    ----------
    IEEE Std 952-1997, Annex C; NIST SP 1065 (Riley 2008), eq. (11) and §5.3.
    """
    from rotacal.gyro.noise import noise_of_deviation
    from rotacal.io import capture_columns, capture_length
    from rotacal.signal.allan import MIN_SAMPLES, ONE_SIGMA, _cluster_sizes
    from rotacal.signal.allan_stream import (
        DEFAULT_HISTORY,
        STREAMED_TAUS,
        check_streamed_record,
        deviation_of_streamed_sums,
    )

    if taus not in STREAMED_TAUS:
        raise ConfigError(
            f"taus must be 'octave' or 'decade' for a capture split over workers; got {taus!r}"
        )
    history = DEFAULT_HISTORY if history is None else int(history)
    if chunk_rows < 1 or history < 4:
        raise ConfigError(f"chunk_rows ({chunk_rows}) and history ({history}) must be positive")
    source = CaptureRows(str(path), (column,), mapping, group, read_options)
    n = capture_length(path, column, mapping=mapping, group=group, read_options=read_options)
    names = capture_columns(path, mapping=mapping, group=group, read_options=read_options)
    with_time = "time_s" in names
    n_phase = n + 1
    if n_phase < MIN_SAMPLES:
        check_streamed_record(n_phase, 0.0, 1.0)  # the single-process path's message
    c = float(np.mean(_rate(source, 0, min(n, _OFFSET_ROWS))))
    ms, notes = _cluster_sizes(taus, n_phase, 1.0)  # octave/decade sizes do not depend on fs
    short = ms[2 * ms <= history]
    long = ms[2 * ms > history]
    starts = block_starts(n, chunk_rows)
    done = 0

    def tick() -> None:
        nonlocal done
        done += 1
        if progress is not None:
            progress(done)

    checked = client.submit(
        _check_task, source, with_time, fs_hz, allow_clipped, chunk_rows, pure=False
    )
    try:
        sums = _sums(client, source, starts, n, c, short, long, history, chunk_rows, tick)
    except (CaptureError, ConfigError):
        checked.result()  # the error the single-process path gives first, if the file has one
        raise
    n_checked, fs, clipped, low, high = checked.result()
    tick()
    if n_checked != n:
        raise CaptureError(f"{path}: {n_checked} rows were read, {n} declared; the file changed")
    check_streamed_record(n_phase, low, high)
    adev = deviation_of_streamed_sums(
        np.array([sums[int(m)] for m in ms.tolist()]),
        ms,
        notes,
        n_phase=n_phase,
        fs_hz=fs,
        confidence=ONE_SIGMA,
        noise_alpha=0,
    )
    return noise_of_deviation(adev, unit=unit, column=column, specs=specs, warnings=clipped)
