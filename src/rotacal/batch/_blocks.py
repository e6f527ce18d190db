"""What every analysis of one huge capture on Dask shares: the rows a task reads, the blocks a
record is split into, and a round of tasks whose results come back in block order."""

from __future__ import annotations

import dataclasses
import os
from collections.abc import Callable, Iterator, Sequence
from os import PathLike
from typing import TYPE_CHECKING, Any, TypeVar

import numpy as np

if TYPE_CHECKING:
    from distributed import Client, Future

    from rotacal.io.read_options import ReadOptions
    from rotacal.table._stream_checks import Checked

__all__ = ["CaptureRows", "Ticks", "block_starts", "check_findings", "check_task", "task_round"]

T = TypeVar("T")


@dataclasses.dataclass(frozen=True)
class CaptureRows:
    """Where a task reads its rows: the capture, its columns and how to read it (pickled to the
    workers, which must see ``path``: a shared file system). ``path`` is made absolute where the
    object is made: a running scheduler's workers were started in folders of their own."""

    path: str
    columns: tuple[str, ...]
    mapping: dict[str, str] | None = None
    group: str | None = None
    read_options: ReadOptions | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "path", os.path.abspath(self.path))

    def visible(self) -> None:
        """Refuse, naming the worker, a capture that this process cannot see (a worker on another
        machine without the file system that holds it)."""
        if os.path.exists(self.path):
            return
        from rotacal.errors import CaptureError

        try:
            from distributed import get_worker

            where = f"Dask worker {get_worker().address}"
        except (ImportError, ValueError):
            where = "this process"
        raise CaptureError(
            f"{where} cannot see the capture {self.path}: every worker must see it at the same "
            "path (a shared file system), or use --workers N for workers on this machine"
        )

    def read(self, start: int, stop: int) -> dict[str, np.ndarray]:
        """Rows ``start`` … ``stop - 1`` of every column, validated as the reader validates a
        whole capture (empty arrays when ``stop <= start``)."""
        from rotacal.io import read_capture_rows

        self.visible()
        if stop <= start:
            return {name: np.empty(0) for name in self.columns}
        return read_capture_rows(
            self.path,
            list(self.columns),
            start,
            stop,
            mapping=self.mapping,
            group=self.group,
            read_options=self.read_options,
        )

    def chunks(self, columns: Sequence[str], rows: int) -> Iterator[dict[str, np.ndarray]]:
        """``columns`` of the whole capture in order, in chunks of ``rows`` rows, read and checked
        as the single-process path reads them."""
        from rotacal.io import iter_capture_chunks

        self.visible()
        return iter_capture_chunks(
            self.path,
            list(columns),
            chunk_rows=rows,
            mapping=self.mapping,
            group=self.group,
            read_options=self.read_options,
        )

    def column(self, name: str, start: int, stop: int) -> np.ndarray:
        """Rows ``start`` … ``stop - 1`` of one column."""
        return dataclasses.replace(self, columns=(name,)).read(start, stop)[name]


def check_task(
    source: CaptureRows, rows: int, companions: dict[str, str | None], keep: str | None = None
) -> Checked:
    """A task: the first pass of a single-process motion path over the whole file, in order, in
    chunks of ``rows`` (:func:`~rotacal.table._stream_checks.check_pass` with ``companions``
    and ``keep``)."""
    from rotacal.table._stream_checks import check_pass
    from rotacal.table._stream_source import Passes

    def chunks() -> Iterator[dict[str, np.ndarray]]:
        return source.chunks(source.columns, rows)

    return check_pass(Passes(chunks, None, source.columns), companions, keep=keep)


def check_findings(
    checked: Future,
    n: int,
    path: str,
    allow_clipped: bool,
    raise_faults: Callable[[Checked], object],
) -> tuple[Checked, tuple[str, ...]]:
    """The findings of :func:`check_task` (a future), its faults raised by ``raise_faults`` as
    one process raises them, and the clipping warnings; a file whose rows are not the ``n``
    declared is refused."""
    from rotacal.errors import CaptureError

    found: Checked = checked.result()
    raise_faults(found)
    clipped = found.clipping(allow_clipped)
    if found.n != n:
        raise CaptureError(f"{path}: {found.n} rows were read, {n} declared; the file changed")
    return found, clipped


class Ticks:
    """Counts the tasks that ended, telling ``progress`` (when given) the count after each."""

    def __init__(self, progress: Callable[[int], None] | None) -> None:
        self.done, self.progress = 0, progress

    def __call__(self) -> None:
        self.done += 1
        if self.progress is not None:
            self.progress(self.done)


def open_capture(
    path: str | PathLike[str],
    columns: Sequence[str],
    counted: str,
    chunk_rows: int,
    mapping: dict[str, str] | None = None,
    group: str | None = None,
    read_options: ReadOptions | None = None,
) -> tuple[CaptureRows, int]:
    """The rows the tasks read (``columns``) and the capture's number of rows (of the column
    ``counted``), having refused a ``chunk_rows`` that is not a whole number ≥ 1 and a format without
    row offsets (CSV, a compressed NPZ member) before any work."""
    from rotacal.errors import ConfigError
    from rotacal.io import capture_length

    if isinstance(chunk_rows, bool) or not isinstance(chunk_rows, int) or chunk_rows < 1:
        raise ConfigError(f"chunk_rows must be a whole number ≥ 1, not {chunk_rows!r}")
    source = CaptureRows(str(path), tuple(columns), mapping, group, read_options)
    n = capture_length(path, counted, mapping=mapping, group=group, read_options=read_options)
    source.read(0, min(n, 1))
    return source, n


def block_starts(n: int, rows: int) -> list[int]:
    """The first row of each block of ``rows`` rows that tile rows 0 … n − 1."""
    return list(range(0, n, rows))


def task_round(
    client: Client,
    fn: Callable[..., T],
    arguments: Sequence[tuple[Any, ...]],
    tick: Callable[[], None] | None = None,
) -> list[T]:
    """``fn(*args)`` for each of ``arguments`` as tasks of the cluster, the results in the order
    of ``arguments``; ``tick()`` after each task that ends. The first task's error is raised
    (in the order of ``arguments``), so the message is the one a single process gives first."""
    from distributed import as_completed

    futures = [client.submit(fn, *args, pure=False) for args in arguments]
    for _ in as_completed(futures):
        if tick is not None:
            tick()
    return [f.result() for f in futures]
