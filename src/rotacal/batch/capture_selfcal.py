"""The self-calibration of a multi-head encoder (``rotacal selfcal``), as tasks on Dask
distributed.

:func:`self_calibrate_on_dask` gives what
:func:`rotacal.encoder.selfcal_stream.self_calibrate_chunked` gives for the same capture (≤ 1e-9
relative, tested), its two passes run by a cluster's workers, each reading the rows it needs
(a shared file system; NPZ without compression, HDF5 or TDMS):

* **First pass** — a task per group of heads (as many groups as workers) checks their pulse
  trains and pairs each with head 0 in time (:func:`~rotacal.encoder.pulse_stream.pair_with_head0`:
  head 0 read in the chunks of ``chunk_rows`` the single-process command reads, so the same
  counts of index differences; head 0's train checked by the first group's task); the client composes the pairing
  (:func:`~rotacal.encoder.pulse_stream.finish_pairing`, with the refusals of the whole pass).
  When a task refuses its head, one task runs the whole pass in order, so that the message is
  the single-process one: the first fault across heads in time order.
* **Second pass** — a task per block of whole revolutions of paired head-0 pulses
  (:func:`~rotacal.encoder.selfcal_stream.fit_block`) reads each head's matching rows (the
  pairing's index offsets place them; ±RATE_WINDOW pulses of context) and returns the block's
  delays checked for drift, its revolutions' mean head differences, their fits for each sense
  and the head differences of the first pulses. The first block runs alone when the heads'
  line shifts are not yet known (they come from its revolutions, as in one process); the client
  merges the blocks in order (:class:`~rotacal.encoder.selfcal_stream.PassSums`: the same adds
  in the same order) and runs the pass again in the rare case the whole record moves a head to
  another line.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable, Iterator
from typing import TYPE_CHECKING, Any, Literal

import numpy as np

from rotacal.batch._blocks import CaptureRows, Ticks, task_round

if TYPE_CHECKING:
    from distributed import Client

    from rotacal.encoder.pulse_stream import StreamedPairing
    from rotacal.encoder.selfcal import SelfCalibration
    from rotacal.encoder.selfcal_stream import BlockFit, PassSums, Shifts
    from rotacal.io.read_options import ReadOptions
    from rotacal.uncertainty import InstrumentSpecs

__all__ = ["self_calibrate_on_dask"]

#: Pulse times read at a time from each head by the first pass (the single-process command's).
CHUNK_ROWS = 1 << 19
#: Blocks of the fit submitted at a time: each returns its revolutions' fitted orders (~4 MB
#: for 14 revolutions of 18,000 pulses and both senses), merged before the next wave is asked.
WAVE = 16


def _head_chunks(source: CaptureRows, name: str, chunk_rows: int) -> Iterator[np.ndarray]:
    """One head's pulse times in chunks of ``chunk_rows``, as the single-process command reads
    them."""
    chunks = source.chunks([name], chunk_rows)
    return (chunk[name] for chunk in chunks)


def _pair_task(source: CaptureRows, chunk_rows: int) -> StreamedPairing:
    """The first pass in one task, every head read in order: the single-process path's first
    refusal across heads, in time order."""
    from rotacal.encoder.pulse_stream import pair_heads_streamed

    heads = [_head_chunks(source, n, chunk_rows) for n in source.columns]
    return pair_heads_streamed(heads, source.columns)


def _heads_task(source: CaptureRows, chunk_rows: int, i: int, j: int) -> tuple[Any, ...]:
    """Heads i … j − 1's share of the first pass: checked and paired with head 0 (checked too
    when i = 1)."""
    from rotacal.encoder.pulse_stream import pair_with_head0

    names = [source.columns[0], *source.columns[i:j]]
    return pair_with_head0(
        _head_chunks(source, names[0], chunk_rows),
        [_head_chunks(source, name, chunk_rows) for name in names[1:]],
        names,
        check_head0=i == 1,
    )


def _first_pass(
    client: Client, source: CaptureRows, chunk_rows: int, tick: Callable[[], None]
) -> StreamedPairing:
    """A task per group of heads (as many as the cluster has workers): their trains checked and
    paired with head 0's, read in the same chunks as in one process (the same counts), composed
    by the client. A refusal is made again by the whole pass in one task, for the
    single-process message (the first fault in time order across heads)."""
    from rotacal.encoder.pulse_stream import finish_pairing
    from rotacal.errors import RotacalError

    n = len(source.columns)
    groups = max(1, min(n - 1, len(client.scheduler_info().get("workers", {}))))
    edges = [1 + (n - 1) * g // groups for g in range(groups + 1)]
    try:
        parts = task_round(
            client,
            _heads_task,
            [(source, chunk_rows, i, j) for i, j in itertools.pairwise(edges)],
            tick,
        )
    except RotacalError:
        task_round(client, _pair_task, [(source, chunk_rows)])  # raises one process's message
        raise  # a group's share refused what the whole pass accepts: never seen
    counts: list[dict[int, int]] = [{}]
    checks, prefixes = [parts[0][1][0]], [parts[0][2][0]]  # head 0's, from the first group
    for c, check, prefix in parts:
        counts += c[1:]
        checks += check[1:]
        prefixes += prefix[1:]
    # the refusals the pass makes once every train is read (copies, overlap): as in one process
    return finish_pairing(source.columns, checks, prefixes, counts)


def _fit_task(
    source: CaptureRows,
    pairing: StreamedPairing,
    m: int,
    candidates: list[str],
    shifts: Shifts | None,
    p0: int,
    p1: int,
) -> BlockFit:
    """The second pass over paired head-0 pulses [p0, p1), each head's rows read here."""
    from rotacal.encoder.selfcal_stream import fit_block

    read: dict[int, tuple[int, np.ndarray]] = {}

    def take(i: int, a: int, b: int) -> np.ndarray:
        if i not in read:  # head 0 is asked twice (the times and its own zero delay)
            read[i] = (a, np.asarray(source.column(source.columns[i], a, b), dtype=np.float64))
        first, t = read[i]
        return t[a - first : b - first]

    return fit_block(take, pairing, m, candidates, shifts, p0, p1)


def self_calibrate_on_dask(
    path: str,
    *,
    client: Client,
    heads: int,
    pulses_per_rev: int,
    rotation: Literal["auto", "forward", "reverse"] = "auto",
    specs: InstrumentSpecs | None = None,
    mapping: dict[str, str] | None = None,
    group: str | None = None,
    read_options: ReadOptions | None = None,
    chunk_rows: int = CHUNK_ROWS,
    block_pulses: int | None = None,
    spill_dir: str | None = None,
    progress: Callable[[int], None] | None = None,
) -> SelfCalibration:
    """Scale deviation of a multi-head encoder by the equal-division-averaged method, computed
    by the workers of a Dask cluster (see the module for how the capture is split).

    Parameters
    ----------
    path : str
        The capture (NPZ saved without compression, HDF5 or TDMS) with columns ``head_0`` …
        ``head_{heads-1}``: each head's pulse times (s), of any lengths, at a path every worker
        sees.
    client : distributed.Client
        The cluster's client.
    heads : int
        n, the number of heads.
    pulses_per_rev, rotation, specs
        As :func:`~rotacal.encoder.selfcal.self_calibrate` (m pulses per revolution of a head).
    mapping, group, read_options
        How to read the capture, as :func:`rotacal.io.read_capture`.
    chunk_rows : int
        Pulse times read at a time from each head by the first pass.
    block_pulses : int, optional
        Head-0 pulses per task of the second pass (rounded down to whole revolutions; default
        that of ``self_calibrate_chunked``).
    spill_dir : str, optional
        Directory of the client's temporary file of the single-revolution curves.
    progress : callable, optional
        Called with the number of tasks done so far.

    Returns
    -------
    SelfCalibration
        As ``self_calibrate_chunked`` over the same capture to ≤ 1e-9 relative.

    Raises
    ------
    CaptureError, ConfigError
        As the single-process path, with the same messages.

    References
    ----------
    Kokuyama W. et al. (2015), §3; Masuda T., Kajitani M. (1993).
    """
    from rotacal.encoder.selfcal import _check_heads, _check_settings
    from rotacal.encoder.selfcal_stream import (
        BLOCK_PULSES,
        PassSums,
        finish_chunked,
        fit_blocks,
    )

    m = _check_settings(pulses_per_rev, rotation, specs)
    _check_heads(heads, m)
    names = tuple(f"head_{i}" for i in range(heads))
    source = CaptureRows(str(path), names, mapping, group, read_options)
    tick = Ticks(progress)
    pairing = _first_pass(client, source, chunk_rows, tick)
    blocks = fit_blocks(pairing, m, BLOCK_PULSES if block_pulses is None else block_pulses)

    def run_pass(candidates: list[str], shifts: Shifts | None) -> PassSums:
        sums = PassSums(pairing, m, spill_dir)

        def round_(todo: list[tuple[int, int]], given: Shifts | None) -> None:
            # in waves, merged as they come: the client holds WAVE blocks' fits, not the record's
            for w in range(0, len(todo), WAVE):
                args = [
                    (source, pairing, m, candidates, given, a, b) for a, b in todo[w : w + WAVE]
                ]
                for block in task_round(client, _fit_task, args, tick):
                    sums.add(block)

        round_(blocks if shifts is not None else blocks[:1], shifts)
        if shifts is None:  # the line shifts come from the first block's revolutions
            round_(blocks[1:], sums.shifts)
        return sums

    return finish_chunked(pairing, m, rotation, specs, run_pass)
