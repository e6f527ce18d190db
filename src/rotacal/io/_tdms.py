"""NI TDMS captures: the channels of one group.

Files are opened in npTDMS streaming mode (``TdmsFile.open``): only the metadata is read up
front; channel data are read whole or by slices. Before npTDMS sees the file, the chain of
segment lead-ins is walked (NI, "TDMS File Format Internal Structure": each segment starts with
``TDSm``, a table of contents, the version 4712/4713 and the offsets of the next segment and of
the raw data), so that a file cut off while it was written is named as such. npTDMS's own log
lines never reach the terminal: each one means the file is damaged or not as the format says,
and becomes a CaptureError.
"""

from __future__ import annotations

import contextlib
import json
import logging
import struct
from collections.abc import Iterator, Mapping
from pathlib import Path
from typing import IO, Any

import numpy as np
from nptdms import ChannelObject, GroupObject, RootObject, TdmsFile, TdmsWriter

from rotacal.errors import CaptureError

from ._common import damaged, plain, reason
from ._validate import ColumnInfo

DEFAULT_GROUP = "capture"
_LEAD_IN = 28
_BIG_ENDIAN = 1 << 6  # kTocBigEndian
_VERSIONS = (4712, 4713)
_INCOMPLETE = 0xFFFFFFFFFFFFFFFF  # next-segment offset LabVIEW leaves while writing


def check_segments(fh: IO[bytes], fname: str, size: int) -> None:
    """Walk the segment lead-ins; raise CaptureError for a damaged or cut-off file."""
    pos = 0
    count = 0
    while pos < size:
        fh.seek(pos)
        lead = fh.read(_LEAD_IN)
        cut = (
            f": the file is cut off (as when a recording stops while it is written) or damaged "
            f"— record or copy it again, or keep its {count} complete "
            f"segment{'s' if count != 1 else ''} by cutting the file at byte {pos}"
        )
        if len(lead) < _LEAD_IN:
            raise CaptureError(f"{fname} ends inside the header of segment {count + 1}{cut}")
        if lead[:4] != b"TDSm":
            raise damaged(fname, f"segment {count + 1} at byte {pos} does not start with 'TDSm'")
        toc = struct.unpack("<i", lead[4:8])[0]
        order = ">" if toc & _BIG_ENDIAN else "<"
        version, next_offset, raw_offset = struct.unpack(order + "iQQ", lead[8:28])
        if version not in _VERSIONS:
            raise damaged(fname, f"segment {count + 1} at byte {pos} has version {version}")
        if next_offset == _INCOMPLETE:
            raise CaptureError(f"{fname} segment {count + 1} was never finished{cut}")
        end = pos + _LEAD_IN + next_offset
        if raw_offset > next_offset:
            raise damaged(
                fname, f"segment {count + 1} at byte {pos} puts its data past its own end"
            )
        if end > size:
            raise CaptureError(
                f"{fname} ends inside segment {count + 1} ({size - pos} of its "
                f"{end - pos} bytes are there){cut}"
            )
        pos = end
        count += 1


class _Collect(logging.Filter):
    """Keeps npTDMS's log records from every handler (the terminal included) and stores them."""

    def __init__(self) -> None:
        super().__init__()
        self.records: list[logging.LogRecord] = []

    def filter(self, record: logging.LogRecord) -> bool:
        self.records.append(record)
        return False


@contextlib.contextmanager
def _nptdms_quiet(fname: str) -> Iterator[None]:
    """Silence npTDMS's loggers; a WARNING it meant to print becomes a CaptureError."""
    collect = _Collect()
    loggers = [
        logging.getLogger(name)
        for name in list(logging.Logger.manager.loggerDict)
        if name == "nptdms" or name.startswith("nptdms.")
    ]
    for log in loggers:
        log.addFilter(collect)
    try:
        yield
    finally:
        for log in loggers:
            log.removeFilter(collect)
    warned = [r for r in collect.records if r.levelno >= logging.WARNING]
    if warned:
        raise damaged(fname, _meaning(warned[0].getMessage()))


def _meaning(text: str) -> str:
    """What an npTDMS warning says about the file, in a user's words."""
    if text.startswith("Error decoding string"):
        return "a name or property in it is not UTF-8 text"
    if "is not a multiple of the chunk size" in text:
        return "a segment holds a part of a chunk of data (its sizes contradict its contents)"
    if "Cropping data" in text:
        return "a segment of interleaved data holds a part of a row"
    return "npTDMS reports: " + reason(Exception(text))


class TdmsReader:
    """Reader of one TDMS capture: the channels of one group, their types and data."""

    label = "TDMS"
    noun = "channel"

    def __init__(self, path: Path, group: str | None) -> None:
        self.path = path
        self.fname = path.name
        self._fh = open(path, "rb")  # given to npTDMS, so that it opens no .tdms_index beside it
        try:
            self._size = path.stat().st_size
            check_segments(self._fh, self.fname, self._size)
            self._fh.seek(0)
            with self.quiet():
                self._file = TdmsFile.open(self._fh)
                self._open_group(group)
        except BaseException:
            self._fh.close()
            raise

    def quiet(self) -> contextlib.AbstractContextManager[None]:
        """The context every npTDMS call runs in (see :func:`_nptdms_quiet`)."""
        return _nptdms_quiet(self.fname)

    def _open_group(self, group: str | None) -> None:
        groups = [g.name for g in self._file.groups()]
        if group is None:
            if not groups:
                raise CaptureError(
                    f"{self.fname} has no channel groups; write the channels in one group"
                )
            if len(groups) > 1:
                raise CaptureError(
                    f"{self.fname} has several groups ({', '.join(groups)}); pick one with --group"
                )
            group = groups[0]
        if group not in groups:
            raise CaptureError(
                f"{self.fname} has no group {group!r} (it has: {', '.join(groups) or 'none'}); "
                "pick one with --group"
            )
        self._group = self._file[group]
        self.names = [c.name for c in self._group.channels()]
        if not self.names:
            raise CaptureError(
                f"{self.fname} group {group!r} has no channels; write one channel per column"
            )
        meta = {k: plain(v) for k, v in self._file.properties.items()}
        meta.update({k: plain(v) for k, v in self._group.properties.items()})
        self.metadata = meta

    def describe(self, name: str) -> ColumnInfo:
        with self.quiet():
            ch = self._group[name]
            dt = ch.dtype
            rows = len(ch)
        if dt is None:
            raise CaptureError(
                f"{self.fname} channel {name!r} holds no numeric data type; write it as a "
                "numeric channel"
            )
        dtype = np.dtype(dt)
        raw_size = getattr(ch.data_type, "size", None)
        # scaled channels come out as float64 from fewer stored bytes per value
        expand = max(1, dtype.itemsize // raw_size) if raw_size else None
        max_bytes = self._size * expand if expand else None
        return ColumnInfo(self.noun, dtype, (rows,), max_bytes=max_bytes)

    def row_count(self, name: str) -> int:
        with self.quiet():
            return len(self._group[name])

    def read(self, names: list[str], ragged: bool) -> dict[str, np.ndarray]:
        with self.quiet():
            return {n: np.asarray(self._group[n][:]) for n in names}

    def chunks(self, names: list[str], chunk_rows: int) -> Iterator[dict[str, np.ndarray]]:
        with self.quiet():
            chans = {n: self._group[n] for n in names}
        total = self.row_count(names[0])
        for lo in range(0, total, chunk_rows):
            hi = min(total, lo + chunk_rows)
            with self.quiet():
                out = {n: np.asarray(ch[lo:hi]) for n, ch in chans.items()}
            yield out

    def rows(self, names: list[str], start: int, stop: int) -> dict[str, np.ndarray]:
        """Rows ``start`` … ``stop - 1`` of each channel (npTDMS reads any slice)."""
        with self.quiet():
            return {n: np.asarray(self._group[n][start:stop]) for n in names}

    def integrity(self, name: str) -> None:
        return None  # TDMS stores no checksums

    def locate(self, index: int) -> str:
        return f"row {index} (0-based)"

    def close(self) -> None:
        try:
            with self.quiet():
                self._file.close()
        finally:
            self._fh.close()


def _property(value: Any) -> Any:
    if isinstance(value, str | float | bool):
        return value
    if isinstance(value, int):
        return value if -(2**31) <= value < 2**31 else float(value)
    return json.dumps(value, default=str)


def write_tdms(
    path: Path, columns: Mapping[str, np.ndarray], group: str | None, metadata: Any
) -> None:
    """Write all columns as channels of one group (default ``capture``) in one segment."""
    gname = DEFAULT_GROUP if group is None else str(group)
    props = {k: _property(v) for k, v in (metadata or {}).items()}
    objects: list[Any] = [RootObject(), GroupObject(gname, properties=props)]
    objects += [ChannelObject(gname, name, np.ascontiguousarray(a)) for name, a in columns.items()]
    with TdmsWriter(str(path)) as writer:
        writer.write_segment(objects)
