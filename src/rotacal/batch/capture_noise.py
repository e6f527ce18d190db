"""One huge rate capture's Allan deviation and noise terms, as tasks on Dask distributed.

:func:`gyro_noise_on_dask` gives what :func:`rotacal.gyro.noise_stream.gyro_noise_chunks` gives
for the same file (≤ 1e-9 relative, tested), with the work split over a cluster's workers, each
reading its own rows of the file (a shared file system; NPZ without compression, HDF5 or TDMS):

* **Blocks** — a task per block of ``chunk_rows`` rows [a, b) reads the rate over
  [a, b + history) and the time stamps over [a − 1, b), and

  - checks the block as the single-process path checks a chunk (NaN/inf and absurd values, time
    stamps in order and without gaps, their extreme steps, the rails of clipping): its
    :class:`~rotacal.gyro.noise_stream.NoiseChecks` starts from the state at row a that does
    not depend on the rows before (the time stamp before the block, the typical step of the
    first block, read by the client) and the client merges the blocks' checks in row order —
    the first fault in file order is the one raised;
  - sums the second differences x_{i+2m} − 2x_{i+m} + x_i with i in [a, b) of the short cluster
    sizes (2m ≤ ``history``): a second difference does not change when a constant is added to
    the phase, so each task integrates its own rows from zero. It also returns Σ(rate − c)
    over [a, b).

  One more task recomputes the stored CRC-32s of an NPZ (they cover whole columns), beside them.
* **Long cluster sizes** — with the blocks' sums the client knows the phase x at every block
  boundary exactly as a sum of sums. A task per block then reads the rate at i, i + m and i + 2m
  (each window once for all sizes that need it) and sums d_i² with d_a = x_{a+2m} − 2x_{a+m} +
  x_a and d_{i+1} = d_i + r_{i+2m} − 2r_{i+m} + r_i, in cache-sized pieces.

The sums of disjoint blocks add up to the whole record's (NIST SP 1065 eq. (11)); the deviation,
its confidence interval and the noise terms then come from them as on one machine.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from rotacal.batch._blocks import CaptureRows, Ticks, block_starts, task_round
from rotacal.errors import CaptureError, ConfigError

if TYPE_CHECKING:
    from distributed import Client

    from rotacal.gyro.noise import GyroNoise
    from rotacal.gyro.noise_stream import NoiseChecks
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


@dataclasses.dataclass(frozen=True)
class _Checking:
    """What a block's checks need besides its rows: the sampling rate given (Hz), the rows of
    the record, whether it has a time column and the typical step (s) its first block sets."""

    fs_hz: float | None
    rows: int
    with_time: bool
    typical: float


def _block_task(
    source: CaptureRows,
    a: int,
    b: int,
    c: float,
    ms: np.ndarray,
    history: int,
    checking: _Checking,
) -> tuple[float, np.ndarray, NoiseChecks, float, float]:
    """One block [a, b): its checks, Σ(rate − c) over it and S(m) over the second differences
    at i in [a, b) of each short cluster size ``ms`` (2m ≤ history), in (rate × sample
    interval)²; and the rate's extremes in the block."""
    from rotacal.gyro.noise_stream import NoiseChecks
    from rotacal.signal._allan_fast import direct_sums
    from rotacal.signal._values import check_magnitudes

    n, name = checking.rows, source.columns[0]
    r = _rate(source, a, min(n, b + history))
    rate = r[: b - a]
    chunk = {name: rate}
    previous = None
    if checking.with_time:
        t = source.column("time_s", max(a - 1, 0), b)
        previous, chunk["time_s"] = (float(t[0]), t[1:]) if a else (None, t)
    checks = NoiseChecks.block(
        name, checking.fs_hz, rows=n, start=a, previous=previous, typical=checking.typical
    )
    checks.add(chunk)
    check_magnitudes(name, rate, what="rate data", offset=a)
    x = np.empty(r.size + 1)
    x[0] = 0.0
    np.subtract(r, c, out=x[1:])
    block = float(np.sum(x[1 : b - a + 1]))
    np.cumsum(x[1:], out=x[1:])  # x[t] = phase at a + t, less the phase at a
    sums = np.zeros(ms.size)
    for k, m in enumerate(ms.tolist()):
        count = min(b, n - 2 * m + 1) - a  # terms i in [a, b) with i + 2m ≤ n
        if count > 0:
            sums[k] = direct_sums(x[: count + 2 * m], np.array([m], dtype=np.int64))[0]
    return block, sums, checks, float(rate.min()), float(rate.max())


def _crc_task(source: CaptureRows, columns: list[str], rows: int) -> None:
    """Recompute the CRC-32s an NPZ stores for its columns: a pass over the file in order (the
    blocks' reads check everything else), fed while each chunk is scanned, its pages released."""
    for _ in source.chunks(columns, rows):
        pass


def _phase_at(source: CaptureRows, p: int, boundary: np.ndarray, rows: int, c: float) -> float:
    """x_p (phase at sample p, offset c removed) from the block boundaries' phases and the rows
    between p's block boundary and p."""
    k = p // rows
    return float(boundary[k]) + float(np.sum(_rate(source, k * rows, p) - c))


#: Rows of the pieces the long sums are formed in (cache-sized: no full-size temporaries).
_PIECE = 1 << 16


def _piece_squares(d0: float, r0: np.ndarray, r1: np.ndarray, r2: np.ndarray) -> np.ndarray:
    """Σ d_i² over each piece of ``_PIECE`` terms i = 1 … len(r0), with d_0 = d0 and d_{i+1} =
    d_i + (r2_i − r1_i) − (r1_i − r0_i): the second differences of the phase from their
    increments, the rates at i, i + m and i + 2m (differences of neighbouring rates first: the
    rate's offset cancels before it can round the increments)."""
    parts, carry = np.empty(-(-r0.size // _PIECE)), d0
    size = min(r0.size, _PIECE)
    v, w = np.empty(size), np.empty(size)
    for k, lo in enumerate(range(0, r0.size, _PIECE)):
        hi = min(r0.size, lo + _PIECE)
        vv, ww = v[: hi - lo], w[: hi - lo]
        np.subtract(r2[lo:hi], r1[lo:hi], out=vv)
        np.subtract(r1[lo:hi], r0[lo:hi], out=ww)
        vv -= ww
        np.cumsum(vv, out=vv)
        vv += carry
        carry = float(vv[-1])
        parts[k] = np.dot(vv, vv)
    return parts


def _squares_of_second_differences(
    d0: float, r0: np.ndarray, r1: np.ndarray, r2: np.ndarray, jit: bool
) -> float:
    """Σ d_i² for i = 0 … len(r0) (see :func:`_piece_squares`; its Numba twin when ``jit``),
    the pieces' sums added exactly (math.fsum)."""
    if jit:
        from rotacal.batch._capture_noise_jit import piece_squares_jit

        parts = piece_squares_jit(d0, r0, r1, r2, _PIECE)
    else:
        parts = _piece_squares(d0, r0, r1, r2)
    return math.fsum([d0 * d0, *parts.tolist()])


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
    """S(m) over the second differences at i in [a, b) of each long cluster size ``ms``
    (ascending). The rate at offset o from a is read once for the sizes m = o and 2m = o."""
    windows: dict[int, np.ndarray] = {}

    def window(offset: int, count: int) -> np.ndarray:
        have = windows.get(offset)
        if have is None or have.size < count:
            have = windows[offset] = _rate(source, a + offset, a + offset + count)
        return have[:count]

    from rotacal._jit import use_numba

    jit = use_numba(sum(max(0, min(b, n - 2 * m + 1) - a) for m in ms.tolist()))
    sums = np.zeros(ms.size)
    for k, m in enumerate(ms.tolist()):
        for offset in [o for o in windows if 0 < o < m]:
            del windows[offset]  # only larger sizes follow
        count = min(b, n - 2 * m + 1) - a
        if count <= 0:
            continue
        at = [_phase_at(source, p, boundary, rows, c) for p in (a, a + m, a + 2 * m)]
        r0, r1, r2 = (window(o, count - 1) for o in (0, m, 2 * m))
        sums[k] = _squares_of_second_differences(at[2] - 2.0 * at[1] + at[0], r0, r1, r2, jit)
    return sums


def _typical_step(source: CaptureRows, n: int, rows: int) -> float:
    """The typical time step (s) the first block's checks set (the median of its first steps),
    or NaN when those rows are faulty: the first block then raises the fault, as one pass does."""
    from rotacal.signal._checks import TYPICAL_STEPS

    try:
        t = source.column("time_s", 0, min(n, max(2, min(rows, TYPICAL_STEPS + 1))))
    except CaptureError:
        return math.nan
    return float(np.median(np.diff(t))) if t.size > 1 else math.nan


def _sums(
    client: Client,
    source: CaptureRows,
    n: int,
    c: float,
    short: np.ndarray,
    long: np.ndarray,
    history: int,
    rows: int,
    checking: _Checking,
    tick: Callable[[], None],
) -> tuple[dict[int, float], NoiseChecks, float, float]:
    """S(m) of every cluster size, the merged checks and the rate's extremes: the checks, the
    short sizes and the blocks' sums in one round of tasks (beside the CRC pass of an NPZ),
    then the long sizes (which need the phase at every block boundary) in a second."""
    from rotacal.io._common import format_of

    starts = block_starts(n, rows)
    crc = None
    if format_of(Path(source.path)) == "npz":
        columns = [*source.columns, *(["time_s"] if checking.with_time else [])]
        crc = client.submit(_crc_task, source, columns, rows, pure=False)
    try:
        blocks = task_round(
            client,
            _block_task,
            [(source, a, min(n, a + rows), c, short, history, checking) for a in starts],
            tick,
        )
    except BaseException:
        if crc is not None:
            crc.cancel()  # the file is refused already: do not read it through
        raise
    if crc is not None:
        crc.result()  # a damaged file: raised after the blocks' faults, as one pass does
        tick()
    checks = blocks[0][2]
    for block in blocks[1:]:
        checks.merge(block[2])
    low, high = min(b[3] for b in blocks), max(b[4] for b in blocks)
    sums = {int(m): math.fsum(s[k] for _, s, *_ in blocks) for k, m in enumerate(short.tolist())}
    if not long.size:
        return sums, checks, low, high
    # the phase at each block boundary, a correctly rounded sum of the blocks' sums
    boundary = np.array([math.fsum(b[0] for b in blocks[:k]) for k in range(len(blocks) + 1)])
    parts = task_round(
        client,
        _long_task,
        [(source, a, min(n, a + rows), n, c, long, boundary, rows) for a in starts],
        tick,
    )
    for k, m in enumerate(long.tolist()):
        sums[int(m)] = math.fsum(p[k] for p in parts)
    return sums, checks, low, high


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
    from rotacal.gyro.noise_stream import NoiseChecks
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
    NoiseChecks(column, fs_hz)  # a bad fs_hz is refused before anything is read
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
    tick = Ticks(progress)

    checking = _Checking(
        fs_hz=fs_hz,
        rows=n,
        with_time=with_time,
        typical=_typical_step(source, n, chunk_rows) if with_time else math.nan,
    )
    sums, checks, low, high = _sums(
        client, source, n, c, short, long, history, chunk_rows, checking, tick
    )
    fs, clipped = checks.finish(n, allow_clipped)
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
