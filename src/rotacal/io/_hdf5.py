"""HDF5 captures: one dataset per column, at the root or under a group (``grp/sub`` allowed).

Contiguous, unfiltered datasets are memory-mapped straight from the file; the others are read
with h5py (whole, or by slices when chunked). What a dataset declares (shape, type, where its
bytes are) is compared with the file before anything is read: storage past the end of the file,
chunks that were never written (they would read as fill values) and sizes no file of this size
could hold are refused.
"""

from __future__ import annotations

import json
from collections.abc import Iterator, Mapping
from pathlib import Path
from typing import Any

import h5py
import numpy as np

from rotacal.errors import CaptureError, ConfigError

from ._common import LIBRARY_ERRORS, damaged, plain, reason
from ._hdf5_heap import check_global_heaps
from ._validate import ColumnInfo

#: the most a filter (deflate, LZF, ...) can expand: deflate's ~1032:1 bounds the common ones
_MAX_RATIO = 1032


def _groups_with_datasets(f: h5py.File, limit: int = 12) -> list[str]:
    found: list[str] = []

    def visit(name: str, obj: Any) -> None:
        if isinstance(obj, h5py.Group) and any(isinstance(v, h5py.Dataset) for v in obj.values()):
            found.append(name)

    try:
        f.visititems(visit)
    except LIBRARY_ERRORS:  # a damaged part of the file: name what was found before it
        pass
    return found[:limit]


class Hdf5Reader:
    """Reader of one HDF5 capture: the datasets of one group, their declarations and data."""

    label = "HDF5"
    noun = "dataset"

    def __init__(self, path: Path, group: str | None) -> None:
        self.path = path
        self.fname = path.name
        self._size = path.stat().st_size
        self._file = h5py.File(path, "r")
        try:
            self._open_group(group)
        except BaseException:
            self._file.close()
            raise

    def _open_group(self, group: str | None) -> None:
        f = self._file
        where = "/" if group in (None, "", "/") else str(group).strip("/")
        base = f if where == "/" else f.get(where)
        if base is None or not isinstance(base, h5py.Group):
            have = _groups_with_datasets(f)
            kind = "no group" if base is None else "a dataset, not a group, at"
            raise CaptureError(
                f"{self.fname} has {kind} {group!r} (groups with datasets: "
                f"{', '.join(have) or 'none'}); pick one with --group"
            )
        self._base = base
        self.names = [k for k, v in base.items() if isinstance(v, h5py.Dataset)]
        if not self.names:
            have = [g for g in _groups_with_datasets(f) if g != where]
            hint = f"pick one with --group {have[0]}" if have else "write one dataset per column"
            at = "at its root" if where == "/" else f"in group {where!r}"
            raise CaptureError(
                f"{self.fname} has no datasets {at} (groups with datasets: "
                f"{', '.join(have) or 'none'}); {hint}"
            )
        self.metadata = self._attributes(base)

    def _attributes(self, base: h5py.Group) -> dict[str, Any]:
        """The group's attributes; variable-length ones only after their heaps were checked."""
        out: dict[str, Any] = {}
        heaps_checked = False
        for key in base.attrs:
            try:
                needs_heap = base.attrs.get_id(key).dtype.hasobject
            except TypeError:  # a type h5py cannot represent: not metadata rotacal can show
                continue
            if needs_heap and not heaps_checked:
                check_global_heaps(self.path, self.fname, self._data_extents(base))
                heaps_checked = True
            out[key] = plain(base.attrs[key])
        return out

    def _data_extents(self, base: h5py.Group) -> list[tuple[int, int]]:
        """(offset, bytes) of the group's contiguous datasets: no heap lies inside them."""
        out = []
        for name in self.names:
            d = base[name]
            offset = d.id.get_offset()
            try:
                nbytes = d.dtype.itemsize * int(np.prod(d.shape or (0,), dtype=np.int64))
            except (TypeError, ValueError):
                continue
            # only extents that agree with the declaration (a damaged size must not hide a heap)
            if offset is not None and nbytes == d.id.get_storage_size() <= self._size - offset:
                out.append((int(offset), nbytes))
        return out

    # --- declarations --------------------------------------------------------------------------

    def _dataset(self, name: str) -> h5py.Dataset:
        return self._base[name]

    def describe(self, name: str) -> ColumnInfo:
        d = self._dataset(name)
        try:
            dtype = d.dtype
        except TypeError as exc:  # an HDF5 type with no NumPy equivalent (bitfield, ...)
            raise CaptureError(
                f"{self.fname} dataset {name!r} holds a data type rotacal cannot read "
                f"({reason(exc)}); store each column as numbers"
            ) from None
        shape = () if d.shape is None else tuple(int(k) for k in d.shape)  # None: a null space
        if dtype.kind not in "iuf" or len(shape) != 1 or shape[0] == 0:
            return ColumnInfo(self.noun, dtype, shape)
        layout = d.id.get_create_plist().get_layout()
        stored = int(d.id.get_storage_size())
        if layout == h5py.h5d.COMPACT:  # the data sit in the dataset's header
            return ColumnInfo(self.noun, dtype, shape, stored_bytes=stored, max_bytes=self._size)
        if layout == h5py.h5d.CONTIGUOUS and not d.external:
            offset = d.id.get_offset()
            if offset is None:
                raise damaged(self.fname, f"dataset {name!r} has no data stored (never written)")
            return ColumnInfo(
                self.noun, dtype, shape, stored_bytes=stored, max_bytes=self._size - offset
            )
        if layout == h5py.h5d.CHUNKED:
            self._check_chunks(d, name)
            filtered = d.id.get_create_plist().get_nfilters() > 0
            bound = min(_MAX_RATIO * stored, _MAX_RATIO * self._size) if filtered else stored
            return ColumnInfo(self.noun, dtype, shape, max_bytes=bound)
        return ColumnInfo(self.noun, dtype, shape)  # external or virtual: h5py reads it

    def _check_chunks(self, d: h5py.Dataset, name: str) -> None:
        """Every chunk the shape needs must be stored: a missing one reads as fill values."""
        need = -(-int(d.shape[0]) // int(d.chunks[0]))
        have = int(d.id.get_num_chunks())
        if have < need:
            raise damaged(
                self.fname,
                f"dataset {name!r} stores {have} of its {need} chunks (the rest would read "
                "as fill values, not data)",
            )

    def row_count(self, name: str) -> int:
        return int(self._dataset(name).shape[0])

    # --- data ----------------------------------------------------------------------------------

    def _memmap(self, d: h5py.Dataset) -> np.ndarray | None:
        """A read-only memory map of a contiguous, unfiltered dataset, else None."""
        if d.chunks is not None or d.compression is not None or d.external:
            return None
        if self._file.driver != "sec2" or self._file.userblock_size != 0 or d.shape[0] == 0:
            return None
        offset = d.id.get_offset()
        if offset is None:
            return None
        if offset + d.dtype.itemsize * int(d.shape[0]) > self._size:
            raise damaged(
                self.fname, f"dataset {d.name.rsplit('/', 1)[-1]!r} runs past the end of the file"
            )
        return np.memmap(self.path, dtype=d.dtype, mode="r", offset=offset, shape=d.shape)

    def read(self, names: list[str], ragged: bool) -> dict[str, np.ndarray]:
        out: dict[str, np.ndarray] = {}
        for name in names:
            d = self._dataset(name)
            mm = self._memmap(d)
            out[name] = mm if mm is not None else d[...]
        return out

    def chunks(self, names: list[str], chunk_rows: int) -> Iterator[dict[str, np.ndarray]]:
        sources: dict[str, Any] = {}
        for name in names:
            d = self._dataset(name)
            mm = self._memmap(d)
            sources[name] = mm if mm is not None else d
        n = self.row_count(names[0])
        for lo in range(0, n, chunk_rows):
            hi = min(n, lo + chunk_rows)
            yield {name: np.asarray(src[lo:hi]) for name, src in sources.items()}

    def rows(self, names: list[str], start: int, stop: int) -> dict[str, np.ndarray]:
        """Rows ``start`` … ``stop - 1`` of each dataset (HDF5 reads any slice)."""
        out: dict[str, np.ndarray] = {}
        for name in names:
            d = self._dataset(name)
            mm = self._memmap(d)
            out[name] = np.asarray((mm if mm is not None else d)[start:stop])
        return out

    def integrity(self, name: str) -> None:
        return None  # HDF5 checks its own checksums (metadata, fletcher32 chunks) on reading

    def locate(self, index: int) -> str:
        return f"row {index} (0-based)"

    def close(self) -> None:
        self._file.close()


def write_hdf5(
    path: Path, columns: Mapping[str, np.ndarray], group: str | None, metadata: Any
) -> None:
    """Write one contiguous dataset per column at the root or under ``group``."""
    with h5py.File(path, "w", track_order=True) as f:  # keep the column order
        base: h5py.Group = f
        if group not in (None, "", "/"):
            for part in str(group).strip("/").split("/"):
                base = base[part] if part in base else base.create_group(part, track_order=True)
        for name, arr in columns.items():
            if "/" in name or name in (".", ""):
                raise ConfigError(
                    f"column name {name!r} cannot be an HDF5 dataset name; use one without '/'"
                )
            base.create_dataset(name, data=arr)
        for key, value in (metadata or {}).items():
            if isinstance(value, str | int | float | bool):
                base.attrs[key] = value
            else:
                base.attrs[key] = json.dumps(value, default=str)
