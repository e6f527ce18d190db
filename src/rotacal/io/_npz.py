"""NumPy ``.npz`` captures: one array per column.

Members stored without compression (``np.savez``) are memory-mapped straight from the archive;
compressed members (``np.savez_compressed``) are decompressed whole by :meth:`NpzReader.read`
and in pieces by :meth:`NpzReader.chunks`.
"""

from __future__ import annotations

import json
import struct
import zipfile
from collections.abc import Iterator, Mapping
from contextlib import ExitStack
from dataclasses import dataclass
from pathlib import Path
from typing import IO, Any

import numpy as np
from numpy.lib import format as npformat

from rotacal.errors import CaptureError

from ._common import NPZ_METADATA_KEY

_LOCAL_HEADER = struct.Struct("<4s2B4HL2L2H")  # zipfile.structFileHeader


@dataclass
class _Member:
    info: zipfile.ZipInfo
    shape: tuple[int, ...]
    dtype: np.dtype[Any]
    data_offset: int  # bytes from the start of the member's .npy to its data


def _read_npy_header(fp: IO[bytes]) -> tuple[tuple[int, ...], bool, np.dtype[Any]]:
    version = npformat.read_magic(fp)
    if version == (1, 0):
        return npformat.read_array_header_1_0(fp)
    return npformat.read_array_header_2_0(fp)


def _read_exact(fp: IO[bytes], nbytes: int) -> bytes:
    parts = []
    while nbytes > 0:
        piece = fp.read(nbytes)
        if not piece:
            break
        parts.append(piece)
        nbytes -= len(piece)
    return b"".join(parts)


class NpzReader:
    """Reader of one NPZ capture."""

    def __init__(self, path: Path) -> None:
        self.path = path
        self.fname = path.name
        self.metadata: dict[str, Any] = {}
        try:
            self._zip = zipfile.ZipFile(path)
        except (zipfile.BadZipFile, OSError) as exc:
            raise CaptureError(
                f"{self.fname} cannot be read as NPZ ({exc}); write it again with numpy.savez"
            ) from None
        self._members: dict[str, _Member] = {}
        try:
            self._scan()
        except Exception:
            self._zip.close()
            raise

    def _scan(self) -> None:
        for info in self._zip.infolist():
            if not info.filename.endswith(".npy"):
                continue
            key = info.filename[:-4]
            if key == NPZ_METADATA_KEY:
                self._read_metadata(info)
                continue
            try:
                with self._zip.open(info) as fp:
                    shape, _fortran, dtype = _read_npy_header(fp)
                    offset = fp.tell()
            except (ValueError, OSError, zipfile.BadZipFile) as exc:
                raise CaptureError(
                    f"{self.fname} member {key!r} is not a valid NumPy array ({exc}); "
                    "write the capture again with numpy.savez"
                ) from None
            self._members[key] = _Member(info, tuple(shape), np.dtype(dtype), offset)
        if not self._members:
            raise CaptureError(
                f"{self.fname} holds no NumPy arrays; write one array per column with numpy.savez"
            )
        self.names = list(self._members)

    def _read_metadata(self, info: zipfile.ZipInfo) -> None:
        try:
            with self._zip.open(info) as fp:
                text = str(npformat.read_array(fp, allow_pickle=False))
            meta = json.loads(text)
        except (ValueError, OSError):
            return
        if isinstance(meta, dict):
            self.metadata = meta

    def length(self, name: str) -> int:
        shape = self._members[name].shape
        return shape[0] if len(shape) == 1 else -1

    def _data_start(self, m: _Member) -> int | None:
        """Absolute file offset of the member's array data when it is stored uncompressed."""
        if m.info.compress_type != zipfile.ZIP_STORED or m.dtype.hasobject:
            return None
        with open(self.path, "rb") as fh:
            fh.seek(m.info.header_offset)
            raw = fh.read(_LOCAL_HEADER.size)
        if len(raw) != _LOCAL_HEADER.size or raw[:4] != b"PK\x03\x04":
            return None
        fields = _LOCAL_HEADER.unpack(raw)
        name_len, extra_len = fields[10], fields[11]
        start = m.info.header_offset + _LOCAL_HEADER.size + name_len + extra_len + m.data_offset
        nbytes = int(np.prod(m.shape, dtype=np.int64)) * m.dtype.itemsize
        if m.info.file_size != m.data_offset + nbytes:
            return None
        return start

    def _array(self, name: str) -> np.ndarray:
        m = self._members[name]
        if m.dtype.hasobject:
            raise CaptureError(
                f"{self.fname} member {name!r} holds Python objects, not numbers; "
                "store each column as a numeric array"
            )
        if len(m.shape) != 1:
            raise CaptureError(
                f"{self.fname} column {name!r} has shape {m.shape}; each column must be one "
                "1-D array, so split it into one column per channel"
            )
        start = self._data_start(m)
        if start is not None:
            if m.shape[0] == 0:
                return np.empty(0, dtype=m.dtype)
            return np.memmap(self.path, dtype=m.dtype, mode="r", offset=start, shape=m.shape)
        with self._zip.open(m.info) as fp:
            return np.asarray(npformat.read_array(fp, allow_pickle=False))

    def read(self, names: list[str], ragged: bool) -> dict[str, np.ndarray]:
        return {n: self._array(n) for n in names}

    def chunks(self, names: list[str], chunk_rows: int) -> Iterator[dict[str, np.ndarray]]:
        n = self.length(names[0])
        with ExitStack() as stack:
            sources: dict[str, Any] = {}
            for name in names:
                m = self._members[name]
                if self._data_start(m) is not None or len(m.shape) != 1 or m.dtype.hasobject:
                    sources[name] = self._array(name)  # memory-mapped (or an error)
                else:
                    fp = stack.enter_context(self._zip.open(m.info))
                    _read_npy_header(fp)
                    sources[name] = fp
            for lo in range(0, n, chunk_rows):
                hi = min(n, lo + chunk_rows)
                out: dict[str, np.ndarray] = {}
                for name, src in sources.items():
                    if isinstance(src, np.ndarray):
                        out[name] = src[lo:hi]
                    else:
                        dt = self._members[name].dtype
                        want = (hi - lo) * dt.itemsize
                        buf = _read_exact(src, want)
                        if len(buf) != want:
                            raise CaptureError(
                                f"{self.fname} member {name!r} is truncated at row {lo}; "
                                "write the capture again"
                            )
                        out[name] = np.frombuffer(buf, dtype=dt)
                yield out

    def locate(self, index: int) -> str:
        return f"row {index} (0-based)"

    def close(self) -> None:
        self._zip.close()


def write_npz(fh: IO[bytes], columns: Mapping[str, np.ndarray], metadata: Any) -> None:
    """Write the columns uncompressed (so they can be memory-mapped on reading)."""
    arrays: dict[str, Any] = dict(columns)
    if metadata:
        arrays[NPZ_METADATA_KEY] = np.array(json.dumps(metadata, default=str))
    np.savez(fh, **arrays)
