"""HDF5 captures: one dataset per column, at the root or under a group (``grp/sub`` allowed).

Contiguous, unfiltered datasets are memory-mapped straight from the file; the others are read
with h5py (whole, or by slices when chunked).
"""

from __future__ import annotations

import json
from collections.abc import Iterator, Mapping
from pathlib import Path
from typing import Any

import h5py
import numpy as np

from rotacal.errors import CaptureError, ConfigError

from ._common import plain


def _groups_with_datasets(f: h5py.File, limit: int = 12) -> list[str]:
    found: list[str] = []

    def visit(name: str, obj: Any) -> None:
        if isinstance(obj, h5py.Group) and any(isinstance(v, h5py.Dataset) for v in obj.values()):
            found.append(name)

    f.visititems(visit)
    return found[:limit]


class Hdf5Reader:
    """Reader of one HDF5 capture."""

    def __init__(self, path: Path, group: str | None) -> None:
        self.path = path
        self.fname = path.name
        try:
            self._file = h5py.File(path, "r")
        except OSError as exc:
            raise CaptureError(
                f"{self.fname} cannot be read as HDF5 ({exc}); check that the file is complete"
            ) from None
        try:
            self._open_group(group)
        except Exception:
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
        self.metadata = {k: plain(v) for k, v in base.attrs.items()}

    def _dset(self, name: str) -> h5py.Dataset:
        d = self._base[name]
        if d.dtype.names is not None or d.dtype.kind not in "iuf":
            raise CaptureError(
                f"{self.fname} dataset {name!r} holds {d.dtype} values, not real numbers; "
                "store each column as a numeric dataset"
            )
        if d.ndim != 1:
            raise CaptureError(
                f"{self.fname} dataset {name!r} has shape {d.shape}; each column must be one "
                "1-D dataset, so split it into one dataset per channel"
            )
        return d

    def length(self, name: str) -> int:
        d = self._base[name]
        return int(d.shape[0]) if d.ndim == 1 else -1

    def _memmap(self, d: h5py.Dataset) -> np.ndarray | None:
        """A read-only memory map of a contiguous, unfiltered dataset, else None."""
        if d.chunks is not None or d.compression is not None or d.external:
            return None
        if self._file.driver != "sec2" or self._file.userblock_size != 0 or d.shape[0] == 0:
            return None
        offset = d.id.get_offset()
        if offset is None:
            return None
        return np.memmap(self.path, dtype=d.dtype, mode="r", offset=offset, shape=d.shape)

    def read(self, names: list[str], ragged: bool) -> dict[str, np.ndarray]:
        out: dict[str, np.ndarray] = {}
        for name in names:
            d = self._dset(name)
            mm = self._memmap(d)
            out[name] = mm if mm is not None else d[...]
        return out

    def chunks(self, names: list[str], chunk_rows: int) -> Iterator[dict[str, np.ndarray]]:
        sources: dict[str, Any] = {}
        for name in names:
            d = self._dset(name)
            mm = self._memmap(d)
            sources[name] = mm if mm is not None else d
        n = self.length(names[0])
        for lo in range(0, n, chunk_rows):
            hi = min(n, lo + chunk_rows)
            yield {name: np.asarray(src[lo:hi]) for name, src in sources.items()}

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
