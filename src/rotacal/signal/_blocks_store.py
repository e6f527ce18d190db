"""Where :class:`~rotacal.signal._blocks.HarmonicFitAccumulator` keeps its block moments (private).

The moments of a long capture are what grows with its length (K + 2 numbers a block). They are
kept as records ``(j, P, Q)`` in the order they were added: block indices, and the P and Q
moments of each block, with ``P = None`` for a run of full blocks on the sampling grid (all share
one P row, so it is not stored). A block cut by a chunk boundary appears in two records; the
sums of the normal equations are linear in the moments, so the halves need no merging.

Once the records pass ``keep_bytes`` (8 MB by default) they move to an anonymous temporary file
(unlinked at once, gone with the process), and every later record is written there: the memory
held stays at ``keep_bytes`` plus one group however long the capture. :meth:`MomentStore.groups`
reads them back in groups of about ``rows`` blocks, one group in memory at a time.
"""

from __future__ import annotations

import io
import tempfile
from collections.abc import Iterator

import numpy as np

#: Moments held in memory before the store moves them to a temporary file (bytes).
KEEP_BYTES = 8 << 20
#: Blocks a group of :meth:`MomentStore.groups` gathers (≈ 5.5 MB of Q with 42 moments).
GROUP_ROWS = 16_384

Record = tuple[np.ndarray, np.ndarray | None, np.ndarray]


class MomentStore:
    """Block-moment records of ``width`` moments each, in memory up to ``keep_bytes``, then
    in a temporary file."""

    def __init__(self, width: int, keep_bytes: int | None = None) -> None:
        self.width = width
        self.keep_bytes = KEEP_BYTES if keep_bytes is None else keep_bytes
        self.blocks = 0  # rows of all records
        self._held: list[Record] = []
        self._held_bytes = 0
        self._file: io.FileIO | None = None
        # per spilled record: rows, whether P is stored, byte offset of j in the file
        self._index: list[tuple[int, bool, int]] = []
        self._end = 0

    @property
    def spilled(self) -> bool:
        """Whether the records are in the temporary file."""
        return self._file is not None

    def append(self, j: np.ndarray, p: np.ndarray | None, q: np.ndarray) -> None:
        """Add the moments of ``j.size`` blocks (``p`` None: full blocks on the grid)."""
        if j.size == 0:
            return
        self.blocks += j.size
        if self._file is None:
            self._held.append((j, p, q))
            self._held_bytes += j.nbytes + q.nbytes + (0 if p is None else p.nbytes)
            if self._held_bytes > self.keep_bytes:
                self._spill()
            return
        self._write(j, p, q)

    def _spill(self) -> None:
        raw = tempfile.TemporaryFile(buffering=0)  # unbuffered: a FileIO
        assert isinstance(raw, io.FileIO)
        self._file = raw
        for record in self._held:
            self._write(*record)
        self._held = []
        self._held_bytes = 0

    def _write(self, j: np.ndarray, p: np.ndarray | None, q: np.ndarray) -> None:
        assert self._file is not None
        self._index.append((j.size, p is not None, self._end))
        for arr in (j.astype(np.int64), p, q):
            if arr is not None:
                data = np.ascontiguousarray(arr).data.cast("B")
                self._file.seek(self._end)
                while data:  # a raw file may write less than asked
                    done = self._file.write(data) or 0
                    data = data[done:]
                    self._end += done

    def _read(self, offset: int, count: int, dtype: type) -> np.ndarray:
        assert self._file is not None
        buf = bytearray(count * np.dtype(dtype).itemsize)
        self._file.seek(offset)
        view = memoryview(buf)
        while view:
            got = self._file.readinto(view) or 0
            if got == 0:
                raise OSError("the block moments' temporary file ended early")
            view = view[got:]
        return np.frombuffer(buf, dtype=dtype)

    def records(self, rows: int | None = None) -> Iterator[Record]:
        """Every record in order; spilled ones read back in slices of at most ``rows`` blocks
        (default GROUP_ROWS)."""
        rows = GROUP_ROWS if rows is None else rows
        if self._file is None:
            yield from self._held
            return
        w = self.width
        for n, has_p, off in self._index:
            off_p = off + 8 * n
            off_q = off_p + (8 * n * w if has_p else 0)
            for s in range(0, n, rows):
                e = min(n, s + rows)
                j = self._read(off + 8 * s, e - s, np.int64)
                p = self._read(off_p + 8 * s * w, (e - s) * w, np.float64) if has_p else None
                q = self._read(off_q + 8 * s * w, (e - s) * w, np.float64)
                yield j, None if p is None else p.reshape(-1, w), q.reshape(-1, w)

    def groups(
        self, p_full: np.ndarray, rows: int | None = None
    ) -> Iterator[tuple[np.ndarray, np.ndarray | None, np.ndarray]]:
        """``(j, P, Q)`` of consecutive records gathered to about ``rows`` blocks each (default
        GROUP_ROWS; a full block's P row filled in where records are mixed), a record longer
        than that alone (P None when it is a run of full blocks)."""
        rows = GROUP_ROWS if rows is None else rows
        pending: list[Record] = []
        size = 0

        def gathered() -> tuple[np.ndarray, np.ndarray | None, np.ndarray]:
            if len(pending) == 1:
                return pending[0]
            j = np.concatenate([r[0] for r in pending])
            p = np.concatenate(
                [np.broadcast_to(p_full, r[2].shape) if r[1] is None else r[1] for r in pending]
            )
            q = np.concatenate([r[2] for r in pending])
            return j, p, q

        for record in self.records(rows):
            pending.append(record)
            size += record[0].size
            if size >= rows:
                yield gathered()
                pending, size = [], 0
        if pending:
            yield gathered()
