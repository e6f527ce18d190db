"""NumPy ``.npz`` captures: one array per column.

Members stored without compression (``np.savez``) are memory-mapped straight from the archive and
their zip CRC-32 is checked over the mapping in blocks (the data are read once more, but no copy
is made); compressed members (``np.savez_compressed``) are decompressed by zipfile, which checks
the CRC itself, whole by :meth:`NpzReader.read` and in pieces by :meth:`NpzReader.chunks`.
Sizes declared by a member's .npy header are compared with what the archive stores before
anything is allocated.
"""

from __future__ import annotations

import io
import json
import struct
import time
import warnings
import zipfile
import zlib
from collections.abc import Iterator, Mapping
from contextlib import ExitStack
from dataclasses import dataclass
from pathlib import Path
from typing import IO, Any, Literal

import numpy as np
from numpy.lib import format as npformat

from rotacal.errors import CaptureError

from ._common import BLOCK, LIBRARY_ERRORS, NPZ_METADATA_KEY, damaged, reason
from ._validate import ColumnInfo

_LOCAL_HEADER = struct.Struct("<4s2B4HL2L2H")  # zipfile.structFileHeader
#: Deflate's largest compression ratio (RFC 1951: 258 bytes from a 2-bit code, ~1032:1); a
#: compressed member that claims to expand further is damaged
_MAX_RATIO = 1032
#: the metadata member holds a short JSON text
_MAX_METADATA_BYTES = 1 << 24


@dataclass
class _Member:
    info: zipfile.ZipInfo
    shape: tuple[int, ...]
    dtype: np.dtype[Any]
    data_offset: int  # bytes from the start of the member's .npy to its data
    fortran: bool = False  # a 2-D array stored column by column

    @property
    def row_items(self) -> int:
        """Values per row: 1 for a column, K for an (N, K) array."""
        return int(np.prod(self.shape[1:], dtype=np.int64)) if len(self.shape) > 1 else 1


def _read_npy_header(fp: IO[bytes]) -> tuple[tuple[int, ...], bool, np.dtype[Any]]:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # numpy's note on headers written by Python 2
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


class _StoredCrc:
    """The zip CRC-32 of a stored (memory-mapped) member, computed over the mapping in blocks.

    The validator feeds it the rows it scans anyway (:meth:`feed`, in order, while the block is
    in cache); :meth:`check` adds what was not fed and compares with the zip entry's CRC.
    """

    def __init__(self, fname: str, member: str, head: bytes, data: np.ndarray, crc: int) -> None:
        self.fname, self.member, self.data, self.expected = fname, member, data, crc
        self.crc = zlib.crc32(head)
        self.done = 0
        self.checked = False

    def feed(self, lo: int, hi: int) -> None:
        if lo == self.done and hi > lo:
            self.crc = zlib.crc32(self.data[lo:hi].data, self.crc)
            self.done = hi

    def check(self) -> None:
        if self.checked:
            return
        n = self.data.shape[0]
        for lo in range(self.done, n, BLOCK):
            self.feed(lo, min(n, lo + BLOCK))
        if self.crc != self.expected:
            raise damaged(
                self.fname,
                f"member {self.member!r} does not match the CRC-32 recorded in the archive "
                "(its bytes changed after it was written)",
            )
        self.checked = True


class _DeflatedCrc:
    """A compressed member: zipfile checks its CRC-32 when the last byte is decompressed."""

    def __init__(self, reader: NpzReader, info: zipfile.ZipInfo) -> None:
        self.reader, self.info = reader, info
        self.checked = False  # set once the whole member went through zipfile

    def feed(self, lo: int, hi: int) -> None:
        return None

    def check(self) -> None:
        if self.checked:
            return
        try:
            with self.reader._zip.open(self.info) as fp:
                while fp.read(1 << 22):
                    pass
        except LIBRARY_ERRORS as exc:
            raise damaged(
                self.reader.fname,
                f"member {self.info.filename!r} fails its zip check ({reason(exc)})",
            ) from None
        self.checked = True


class NpzReader:
    """Reader of one NPZ capture: member names, their .npy declarations and raw arrays."""

    label = "NPZ"
    noun = "column"

    def __init__(self, path: Path) -> None:
        self.path = path
        self.fname = path.name
        self.metadata: dict[str, Any] = {}
        self._size = path.stat().st_size
        self._zip = zipfile.ZipFile(path)
        self._members: dict[str, _Member] = {}
        self._mapped_arrays: dict[str, np.ndarray] = {}
        self._integrity: dict[str, _StoredCrc | _DeflatedCrc] = {}
        try:
            infos = [i for i in self._zip.infolist() if i.filename.endswith(".npy")]
            self._infos = {i.filename[:-4]: i for i in infos}
            self.names = [i.filename[:-4] for i in infos if i.filename[:-4] != NPZ_METADATA_KEY]
            if not self.names:
                raise CaptureError(
                    f"{self.fname} holds no NumPy arrays (.npy members); an NPZ capture holds "
                    "one array per column — write it again, or save the capture as CSV"
                )
            if NPZ_METADATA_KEY in self._infos:
                self._read_metadata(self._infos[NPZ_METADATA_KEY])
        except BaseException:
            self._zip.close()
            raise

    # --- declarations --------------------------------------------------------------------------

    def _member(self, name: str) -> _Member:
        m = self._members.get(name)
        if m is not None:
            return m
        info = self._infos[name]
        try:
            with self._zip.open(info) as fp:
                shape, fortran, dtype = _read_npy_header(fp)
                offset = fp.tell()
        except LIBRARY_ERRORS as exc:
            raise damaged(
                self.fname,
                f"member {info.filename!r} does not start with a valid NumPy array header "
                f"({reason(exc)})",
            ) from None
        m = _Member(info, tuple(int(k) for k in shape), np.dtype(dtype), offset, bool(fortran))
        self._members[name] = m
        return m

    def _max_bytes(self, info: zipfile.ZipInfo) -> int:
        if info.compress_type == zipfile.ZIP_STORED:
            return self._size
        return _MAX_RATIO * min(info.compress_size, self._size)

    def describe(self, name: str) -> ColumnInfo:
        m = self._member(name)
        return ColumnInfo(
            self.noun,
            m.dtype,
            m.shape,
            stored_bytes=m.info.file_size - m.data_offset,
            max_bytes=self._max_bytes(m.info),
        )

    def row_count(self, name: str) -> int:
        return self._member(name).shape[0]

    def _read_metadata(self, info: zipfile.ZipInfo) -> None:
        """The ``__metadata__`` member: JSON text of a dict (anything else is not metadata)."""
        if info.file_size > min(_MAX_METADATA_BYTES, self._max_bytes(info)):
            raise damaged(self.fname, f"its metadata member declares {info.file_size} bytes")
        try:
            with self._zip.open(info) as fp:
                raw = _read_exact(fp, info.file_size + 1)  # to the end: zipfile checks the CRC
            head = io.BytesIO(raw)
            shape, _fortran, dtype = _read_npy_header(head)
            count = int(np.prod(shape, dtype=np.int64))
            if dtype.hasobject or count * dtype.itemsize != len(raw) - head.tell():
                return
            arr = np.frombuffer(raw, dtype=dtype, count=count, offset=head.tell())
        except LIBRARY_ERRORS as exc:
            raise damaged(
                self.fname, f"its metadata member {info.filename!r} is unreadable ({reason(exc)})"
            ) from None
        try:
            meta = json.loads(str(arr.reshape(shape)))
        except ValueError:
            return
        if isinstance(meta, dict):
            self.metadata = meta

    # --- data ----------------------------------------------------------------------------------

    def _member_start(self, m: _Member) -> int:
        """Absolute file offset of the member's bytes (its .npy header), after the zip header."""
        with open(self.path, "rb") as fh:
            fh.seek(m.info.header_offset)
            raw = fh.read(_LOCAL_HEADER.size)
        if len(raw) != _LOCAL_HEADER.size or raw[:4] != b"PK\x03\x04":
            raise damaged(self.fname, f"the zip header of member {m.info.filename!r} is missing")
        fields = _LOCAL_HEADER.unpack(raw)
        return m.info.header_offset + _LOCAL_HEADER.size + fields[10] + fields[11]

    def _mapped(self, name: str) -> np.ndarray | None:
        """A stored member's data as a read-only memory map (None when compressed)."""
        m = self._member(name)
        if m.info.compress_type != zipfile.ZIP_STORED:
            return None
        if name in self._mapped_arrays:
            return self._mapped_arrays[name]
        start = self._member_start(m)
        if start + m.info.file_size > self._size:
            raise damaged(
                self.fname, f"member {m.info.filename!r} runs past the end of the file (truncated)"
            )
        data_start = start + m.data_offset
        if m.shape[0] == 0:
            arr: np.ndarray = np.empty(0, dtype=m.dtype)
        else:
            order: Literal["C", "F"] = "F" if m.fortran and len(m.shape) > 1 else "C"
            arr = np.memmap(
                self.path, dtype=m.dtype, mode="r", offset=data_start, shape=m.shape, order=order
            )
        with open(self.path, "rb") as fh:
            fh.seek(start)
            head = fh.read(m.data_offset)
        # the CRC runs over the bytes in file order: a 2-D array's, flat
        in_file_order = arr.ravel(order="K") if arr.ndim > 1 else arr
        self._integrity[name] = _StoredCrc(
            self.fname, m.info.filename, head, in_file_order, m.info.CRC
        )
        self._mapped_arrays[name] = arr
        return arr

    def integrity(self, name: str) -> _StoredCrc | _DeflatedCrc:
        """The CRC-32 check of a member (see :class:`_StoredCrc`, :class:`_DeflatedCrc`)."""
        if name not in self._integrity and self._mapped(name) is None:
            self._integrity[name] = _DeflatedCrc(self, self._member(name).info)
        return self._integrity[name]

    def read(self, names: list[str], ragged: bool) -> dict[str, np.ndarray]:
        out: dict[str, np.ndarray] = {}
        for name in names:
            mapped = self._mapped(name)
            if mapped is not None:
                out[name] = mapped
                continue
            check = self.integrity(name)
            info = self._member(name).info
            try:
                with self._zip.open(info) as fp, warnings.catch_warnings():
                    warnings.simplefilter("ignore")
                    out[name] = np.asarray(npformat.read_array(fp, allow_pickle=False))
            except LIBRARY_ERRORS as exc:
                raise damaged(
                    self.fname, f"member {info.filename!r} cannot be decompressed ({reason(exc)})"
                ) from None
            # the header declared exactly the member's size, so the last byte was read and
            # zipfile compared the CRC
            check.checked = True
        return out

    def chunks(self, names: list[str], chunk_rows: int) -> Iterator[dict[str, np.ndarray]]:
        n = self.row_count(names[0])
        with ExitStack() as stack:
            sources: dict[str, Any] = {}
            for name in names:
                mapped = self._mapped(name)
                if mapped is not None:
                    sources[name] = mapped
                    continue
                if self._member(name).fortran and len(self._member(name).shape) > 1:
                    sources[name] = self.read([name], False)[name]  # no rows to stream
                    continue
                fp = stack.enter_context(self._zip.open(self._member(name).info))
                _read_npy_header(fp)
                sources[name] = fp
            for lo in range(0, n, chunk_rows):
                hi = min(n, lo + chunk_rows)
                out: dict[str, np.ndarray] = {}
                for name, src in sources.items():
                    if isinstance(src, np.ndarray):
                        out[name] = src[lo:hi]
                        continue
                    m = self._members[name]
                    want = (hi - lo) * m.row_items * m.dtype.itemsize
                    buf = _read_exact(src, want)  # zipfile checks the CRC with the last piece
                    if len(buf) != want:
                        raise damaged(self.fname, f"member {name + '.npy'!r} ends at row {lo}")
                    out[name] = np.frombuffer(buf, dtype=m.dtype).reshape((hi - lo, *m.shape[1:]))
                    if hi == n:
                        self.integrity(name).checked = True
                yield out  # iter_capture_chunks hands the mapped pages back

    def rows(self, names: list[str], start: int, stop: int) -> dict[str, np.ndarray] | None:
        """Rows ``start`` … ``stop - 1`` of each member, mapped from the file; None unless every
        member is stored uncompressed in row order (a compressed member has no row offsets)."""
        out: dict[str, np.ndarray] = {}
        for name in names:
            mapped = self._mapped(name)
            if mapped is None or (self._member(name).fortran and mapped.ndim > 1):
                return None
            out[name] = mapped[start:stop]
        return out

    def locate(self, index: int) -> str:
        return f"row {index} (0-based)"

    def close(self) -> None:
        self._integrity.clear()
        self._mapped_arrays.clear()
        self._zip.close()


#: Extra-field id of the padding record that aligns a member's data (the id Android's zipalign
#: uses; zip readers skip records they do not know).
_ALIGN_EXTRA_ID = 0xD935
#: Alignment (bytes) of each member's data in the file: NumPy pads a .npy header to 64 bytes, so
#: the member's local zip header is padded to end on a multiple of 64 too.
_ALIGN = 64
#: Bytes zipfile appends to a local header written with ``force_zip64`` (the Zip64 extra field).
_ZIP64_LOCAL_EXTRA = 20


def write_npz(fh: IO[bytes], columns: Mapping[str, np.ndarray], metadata: Any) -> None:
    """Write the columns uncompressed (so they can be memory-mapped on reading), each member's
    data 64-byte aligned in the file.

    The archive is what ``np.savez`` writes (stored ``NAME.npy`` members, Zip64 local headers,
    read by ``np.load`` alike) plus a padding record in each local header's extra field, so
    that a mapped column is an aligned array: NumPy's reductions and BLAS then take their fast
    paths (an unaligned column makes ``np.dot`` ~10x slower) and nothing needs copying.
    """
    arrays: dict[str, Any] = dict(columns)
    if metadata:
        arrays[NPZ_METADATA_KEY] = np.array(json.dumps(metadata, default=str))
    stamp = time.localtime(time.time())[:6]
    with zipfile.ZipFile(fh, mode="w", compression=zipfile.ZIP_STORED, allowZip64=True) as zf:
        for name, value in arrays.items():
            info = zipfile.ZipInfo(name + ".npy", date_time=stamp)
            info.compress_type = zipfile.ZIP_STORED
            # local header: 30 fixed bytes, the name, the extra field (ours + Zip64's)
            fixed = _LOCAL_HEADER.size + len(info.filename.encode("utf-8")) + _ZIP64_LOCAL_EXTRA
            pad = -(zf.fp.tell() + fixed + 4) % _ALIGN  # type: ignore[union-attr]
            info.extra = struct.pack("<HH", _ALIGN_EXTRA_ID, pad) + bytes(pad)
            with zf.open(info, "w", force_zip64=True) as out:
                npformat.write_array(out, np.asanyarray(value), allow_pickle=False)
