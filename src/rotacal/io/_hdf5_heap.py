"""A check of HDF5 global heap collections before h5py reads variable-length attributes.

Variable-length strings (h5py's default for text attributes) live in global heap collections.
The HDF5 library walks a collection's objects by their declared sizes; a damaged collection
whose free-space object declares size 0 makes that walk stand still, and the process hangs in
C code that no signal can interrupt (found by ``tests/io/test_fuzz_readers.py``). This module
walks every collection the way the library does (HDF5 File Format Specification, version 3.0,
§III.E "Global Heap") and refuses the file when a walk would not advance or would leave its
collection.

Collections are found by their signature ``GCOL`` with version 1 and a size that fits the file:
a false match in data needs 9 specific bytes and a plausible size (odds below 2**-60 per byte).
The bytes of the group's contiguous datasets, where the bulk of a capture lies, are not scanned.
"""

from __future__ import annotations

import mmap
import struct
from collections.abc import Iterable
from pathlib import Path

from ._common import damaged

_SIGNATURE = b"GCOL\x01"
_HDF5_MAGIC = b"\x89HDF\r\n\x1a\n"


def _size_of_lengths(mm: mmap.mmap) -> int:
    """The superblock's "size of lengths" (bytes of a length field; 8 in nearly every file)."""
    for base in (0, 512, 1024, 2048, 4096):
        if mm[base : base + 8] == _HDF5_MAGIC and len(mm) > base + 14:
            version = mm[base + 8]
            return int(mm[base + 14] if version < 2 else mm[base + 10])
    return 8


def _walk(mm: mmap.mmap, start: int, size: int, length: int) -> str | None:
    """Walk one collection's objects as H5HG's deserializer does; say what is wrong, or None."""
    fmt = {2: "<H", 4: "<I", 8: "<Q"}.get(length)
    if fmt is None:
        return f"its superblock declares {length}-byte lengths"
    header = 8 + length  # object: index (2), references (2), reserved (4), size (length)
    pos = 8 + length  # collection: signature (4), version (1), reserved (3), size (length)
    while pos < size:
        if pos + header > size:  # too small for an object: the rest is free space
            return None
        index = struct.unpack_from("<H", mm, start + pos)[0]
        obj_size = struct.unpack_from(fmt, mm, start + pos + 8)[0]
        need = header + (obj_size + 7) // 8 * 8 if index > 0 else obj_size
        if need < header or need > size - pos:
            return f"object {index} of the global heap at byte {start} declares {obj_size} bytes"
        pos += need
    return None


def check_global_heaps(path: Path, fname: str, skip: Iterable[tuple[int, int]] = ()) -> None:
    """Raise CaptureError when a global heap collection of the file is damaged.

    ``skip`` lists (offset, length) byte ranges not to scan (data of contiguous datasets).
    """
    with open(path, "rb") as fh, mmap.mmap(fh.fileno(), 0, access=mmap.ACCESS_READ) as mm:
        end = len(mm)
        length = _size_of_lengths(mm)
        fmt = {2: "<H", 4: "<I", 8: "<Q"}.get(length, "<Q")
        spans, pos = [], 0
        for off, n in sorted(skip):
            if off > pos:
                spans.append((pos, off))
            pos = max(pos, off + n)
        spans.append((pos, end))
        for lo, hi in spans:
            at = mm.find(_SIGNATURE, lo, hi)
            while at >= 0:
                if at + 8 + length <= end:
                    size = struct.unpack_from(fmt, mm, at + 8)[0]
                    if 8 + length <= size <= end - at:
                        problem = _walk(mm, at, size, length)
                        if problem is not None:
                            raise damaged(fname, problem)
                at = mm.find(_SIGNATURE, at + 1, hi)
