"""Columns of 2-D arrays in NPZ and HDF5 captures: ``data[:,K]`` is column K of array ``data``.

Many programs store a recording as one (N, K) matrix (``np.savez(f, data=m)``, an HDF5 dataset of
K columns) rather than one array per column. :class:`ArrayColumns` wraps the NPZ or HDF5 reader
and offers each column of such an array as a column of its own, named ``data[:,0]`` …
``data[:,K-1]``; the 2-D array is read (memory-mapped where the reader maps it) once, whatever
number of its columns is asked for, and each column is a view of it.

Members that are not columns of numbers — a scalar (``fs_hz``), an array of text (column
labels) — are left out of the names, so that reading every column of such a file works; asking
for one by name still names what it holds.
"""

from __future__ import annotations

import re
from collections.abc import Iterable, Iterator
from typing import Any

import numpy as np

from rotacal.errors import CaptureError, RotacalError

from ._common import LIBRARY_ERRORS, damaged
from ._validate import ColumnInfo, Integrity, Reader, check_declared, label

_SUBSCRIPT = re.compile(r"^(?P<base>.+?)\[\s*:\s*,\s*(?P<k>[+-]?\d+)\s*\]$")


def split_subscript(name: str) -> tuple[str, int] | None:
    """``"data[:,3]"`` -> ``("data", 3)``; None for a name without a column subscript."""
    m = _SUBSCRIPT.match(name)
    return None if m is None else (m.group("base"), int(m.group("k")))


def column_name(base: str, k: int) -> str:
    return f"{base}[:,{k}]"


class _Whole:
    """The integrity check of a 2-D array, done whole once: its rows are not fed one column at a
    time."""

    def __init__(self, inner: Integrity) -> None:
        self.inner = inner

    def feed(self, lo: int, hi: int) -> None:
        return None

    def check(self) -> None:
        self.inner.check()


class ArrayColumns:
    """A reader whose 2-D numeric arrays appear as one column per array column (``name[:,K]``)."""

    def __init__(self, inner: Reader) -> None:
        self.inner = inner
        self.fname = inner.fname
        self.label = inner.label
        self.noun = inner.noun
        self.metadata = inner.metadata
        self._parts: dict[str, tuple[str, int]] = {}  # column name -> (array, column)
        self._shapes: dict[str, tuple[int, ...]] = {}
        self._not_columns: set[str] = set()
        names: list[str] = []
        for name in inner.names:
            declared = self._declaration(name)
            shape = declared.shape if declared is not None else None
            numeric = (
                declared is not None and declared.dtype is not None and declared.dtype.kind in "iuf"
            )
            if declared is not None and shape is not None and numeric and len(shape) == 2:
                self._check_2d(name, declared)
                self._shapes[name] = shape
                for k in range(shape[1]):
                    names.append(column_name(name, k))
                    self._parts[column_name(name, k)] = (name, k)
            elif shape is not None and (len(shape) == 0 or not numeric):
                self._not_columns.add(name)  # a scalar or text (named if asked for)
            else:
                names.append(name)
        self.names = names

    def _declaration(self, name: str) -> ColumnInfo | None:
        """What the file declares of a member; None when that cannot be read (a damaged member
        is named when it is read, not when the file is opened)."""
        try:
            return self.inner.describe(name)
        except (RotacalError, *LIBRARY_ERRORS):  # type: ignore[misc]
            return None

    def _check_2d(self, name: str, info: ColumnInfo) -> None:
        assert info.shape is not None and info.dtype is not None
        declared = int(np.prod(info.shape, dtype=np.int64)) * info.dtype.itemsize
        what = f"{self.noun} {name!r}"
        if info.stored_bytes is not None and declared != info.stored_bytes:
            raise damaged(
                self.fname,
                f"{what} declares shape {info.shape} ({declared} bytes) but the file stores "
                f"{info.stored_bytes} bytes for it",
            )
        if info.max_bytes is not None and declared > info.max_bytes:
            raise damaged(
                self.fname,
                f"{what} declares shape {info.shape} ({declared} bytes), more than the file can "
                f"hold ({info.max_bytes} bytes)",
            )

    def normalise(self, name: str) -> str:
        """A column name as asked for -> the name it has here (``data[:,-1]`` -> ``data[:,5]``).

        Raises CaptureError for a subscript beyond the array's columns or on a 1-D array.
        """
        if name in self._not_columns:
            info = self.inner.describe(name)
            if info.shape == ():
                raise CaptureError(
                    f"{self.fname} {self.noun} {name!r} holds one value, not a column of samples; "
                    "name a column that holds the recording"
                )
            check_declared(self.fname, label(name, name, self.noun), info)
        parts = split_subscript(name)
        if parts is None or name in self._parts:
            return name
        base, k = parts
        shape = self._shapes.get(base)
        if shape is None:
            if base in self.inner.names:
                found = self._declaration(base)
                have = "" if found is None or found.shape is None else f" (shape {found.shape})"
                raise CaptureError(
                    f"{self.fname} {self.noun} {base!r} is not a 2-D array of numbers{have}; "
                    f"name it without [:,{k}]"
                )
            return name  # not in the file: the caller names what the file has
        if not -shape[1] <= k < shape[1]:
            raise CaptureError(
                f"{self.fname} {self.noun} {base!r} has shape {shape}: it has no column {k} "
                f"(columns 0 … {shape[1] - 1}); pick one with --column {base}[:,K]=NAME"
            )
        return column_name(base, k % shape[1])

    def _split(self, names: Iterable[str]) -> tuple[list[str], list[str]]:
        """The arrays to read for ``names``: 2-D arrays (each once) and plain columns."""
        arrays = list(dict.fromkeys(self._parts[n][0] for n in names if n in self._parts))
        plain = [n for n in names if n not in self._parts]
        return arrays, plain

    def describe(self, name: str) -> ColumnInfo:
        if name not in self._parts:
            return self.inner.describe(name)
        base, _k = self._parts[name]
        info = self.inner.describe(base)
        return ColumnInfo(self.noun, info.dtype, (self._shapes[base][0],))

    def row_count(self, name: str) -> int:
        if name in self._parts:
            return self._shapes[self._parts[name][0]][0]
        return self.inner.row_count(name)

    def _columns(self, raw: dict[str, Any], names: Iterable[str]) -> dict[str, np.ndarray]:
        out: dict[str, np.ndarray] = {}
        for name in names:
            if name in self._parts:
                base, k = self._parts[name]
                out[name] = np.asarray(raw[base])[:, k]
            else:
                out[name] = raw[name]
        return out

    def read(self, names: list[str], ragged: bool) -> dict[str, np.ndarray]:
        arrays, plain = self._split(names)
        raw = self.inner.read(arrays + plain, ragged)
        return self._columns(raw, names)

    def chunks(self, names: list[str], chunk_rows: int) -> Iterator[dict[str, np.ndarray]]:
        arrays, plain = self._split(names)
        for raw in self.inner.chunks(arrays + plain, chunk_rows):
            yield self._columns(raw, names)

    def rows(self, names: list[str], start: int, stop: int) -> dict[str, np.ndarray] | None:
        arrays, plain = self._split(names)
        raw = self.inner.rows(arrays + plain, start, stop)
        return None if raw is None else self._columns(raw, names)

    def integrity(self, name: str) -> Integrity | None:
        if name not in self._parts:
            return self.inner.integrity(name)
        inner = self.inner.integrity(self._parts[name][0])
        return None if inner is None else _Whole(inner)

    def locate(self, index: int) -> str:
        return self.inner.locate(index)

    def close(self) -> None:
        self.inner.close()
