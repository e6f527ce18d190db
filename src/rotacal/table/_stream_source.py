"""Chunk sources of the chunked motion calibrations: fresh passes over a capture (private).

A chunk source is a callable that starts a fresh pass over the capture each time it is called;
:class:`Passes` runs those passes, checks that every chunk is a mapping of equal-length 1-D
columns and that every pass sees the same chunks, and reports progress. :func:`chunks_from_file`
makes a chunk source of a capture file (memory-mapped where the format allows, the pages of each
chunk handed back once it has been used, so the process's memory stays flat).
"""

from __future__ import annotations

import os
from collections.abc import Callable, Iterator, Mapping
from typing import Any

import numpy as np

from rotacal.errors import CaptureError, ConfigError
from rotacal.io import iter_capture_chunks

#: A callable that starts a fresh pass over the capture each time it is called.
ChunkSource = Callable[[], Iterator[Mapping[str, np.ndarray]]]

ENCODER_COLUMNS = ("time_s", "a", "b")
LTS_COLUMNS = ("time_s", "displacement_mm")
FOG_COLUMNS = ("time_s", "rate_deg_s")

_INCONSISTENT = (
    "the chunk source gave different chunks on a later pass; chunks() must yield the same "
    "capture, in the same chunks, every time it is called"
)


class Passes:
    """Fresh passes over a chunk source; checks the chunks and that every pass sees the same.

    ``columns`` are the canonical names each chunk must hold, time first; ``example`` names
    the function that makes a chunk source, for the message when ``chunks`` is not callable.
    """

    def __init__(
        self,
        chunks: ChunkSource,
        progress: Callable[[int], None] | None,
        columns: tuple[str, ...] = ENCODER_COLUMNS,
        example: str = "encoder_chunks_from_file(path)",
    ) -> None:
        if not callable(chunks):
            raise ConfigError(
                "chunks must be a callable that starts a fresh pass over the capture each time it "
                f"is called (e.g. {example}), not a {type(chunks).__name__}"
            )
        self._chunks = chunks
        self._progress = progress
        self._done = 0
        self.columns = columns
        self.lengths: list[int] | None = None

    def run(
        self, start: int = 0, stop: int | None = None
    ) -> Iterator[tuple[int, int, dict[str, np.ndarray]]]:
        """``(chunk number, global index of its first sample, columns)`` of the chunks that
        overlap samples ``[start, stop)``; empty chunks are skipped."""
        it = iter(self._chunks())
        offset = 0
        number = 0
        try:
            for raw in it:
                cols = _columns(raw, offset, self.columns)
                n = cols[self.columns[1]].size
                if n == 0:
                    continue
                if self.lengths is not None and (
                    number >= len(self.lengths) or self.lengths[number] != n
                ):
                    raise CaptureError(_INCONSISTENT)
                if stop is not None and offset >= stop:
                    break
                if offset + n > start:
                    yield number, offset, cols
                    self._done += n
                    if self._progress is not None:
                        self._progress(self._done)
                offset += n
                number += 1
            else:
                if self.lengths is not None and number != len(self.lengths):
                    raise CaptureError(_INCONSISTENT)
        finally:
            close = getattr(it, "close", None)
            if close is not None:
                close()


def _quoted(names: tuple[str, ...]) -> str:
    return " and ".join(repr(name) for name in names)


def _columns(raw: Any, offset: int, names: tuple[str, ...]) -> dict[str, np.ndarray]:
    where = f"the chunk starting at sample {offset}"
    listed = ", ".join(names[:-1]) + " and " + names[-1]
    if not isinstance(raw, Mapping):
        raise CaptureError(
            f"{where} is a {type(raw).__name__}, not a mapping of column name to array; "
            f"yield dicts holding {listed}"
        )
    out: dict[str, np.ndarray] = {}
    for name in names:
        if name not in raw:
            have = ", ".join(repr(k) for k in raw) or "none"
            raise CaptureError(
                f"{where} has no column {name!r} (it has: {have}); each chunk must hold "
                f"{listed} (map file columns with --column OLD=NEW)"
            )
        arr = np.asarray(raw[name], dtype=np.float64)
        if arr.ndim != 1:
            raise CaptureError(
                f"column {name!r} in {where} has shape {arr.shape}; chunks must be 1-D"
            )
        out[name] = arr
    time_name, signals = names[0], names[1:]
    n = out[signals[0]].size
    for other in signals[1:]:
        if out[other].size != n:
            raise CaptureError(
                f"columns {signals[0]!r} and {other!r} differ in length in {where} "
                f"({n} and {out[other].size} samples); they must be sampled together."
            )
    nt = out[time_name].size
    if nt != n:
        have = "have" if len(signals) > 1 else "has"
        raise CaptureError(
            f"column {time_name!r} has {nt} samples but {_quoted(signals)} {have} {n} in "
            f"{where}; they must be sampled together."
        )
    return out


def chunks_from_file(
    path: str | os.PathLike[str],
    columns: tuple[str, ...],
    *,
    mapping: Mapping[str, str] | None = None,
    group: str | None = None,
    chunk_rows: int = 2_000_000,
) -> ChunkSource:
    """A chunk source of ``columns`` (canonical names) read from a capture file.

    Each call of the returned function streams the columns with
    :func:`rotacal.io.iter_capture_chunks` (CSV, NPZ, HDF5, TDMS; uncompressed NPZ members and
    contiguous HDF5 datasets are memory-mapped; the reader hands each chunk's pages back once
    the next chunk is asked for). ``chunk_rows`` must be a whole number ≥ 1
    (ConfigError); file errors are raised by the first pass. Once one pass has read the whole
    file with the reader's checks (CRC-32 of NPZ members, NaN/inf), later passes skip them
    (``verified``): the analysis reads the same file up to eight times.
    """
    if isinstance(chunk_rows, bool) or not isinstance(chunk_rows, int | np.integer):
        raise ConfigError(f"chunk_rows must be a whole number of rows, not {chunk_rows!r}")
    if chunk_rows < 1:
        raise ConfigError(f"chunk_rows must be at least 1, not {chunk_rows}")
    rows = int(chunk_rows)

    read_through = False

    def chunks() -> Iterator[dict[str, np.ndarray]]:
        nonlocal read_through
        yield from iter_capture_chunks(
            path, columns, chunk_rows=rows, mapping=mapping, group=group, verified=read_through
        )
        read_through = True  # reached only when the pass ran to the end (and its checks held)

    return chunks
