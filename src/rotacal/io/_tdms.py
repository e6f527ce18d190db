"""NI TDMS captures: the channels of one group.

Files are opened in npTDMS streaming mode (``TdmsFile.open``): only the metadata is read up
front; channel data are read whole or by slices.
"""

from __future__ import annotations

import json
from collections.abc import Iterator, Mapping
from pathlib import Path
from typing import Any

import numpy as np
from nptdms import ChannelObject, GroupObject, RootObject, TdmsFile, TdmsWriter

from rotacal.errors import CaptureError

from ._common import plain

DEFAULT_GROUP = "capture"


class TdmsReader:
    """Reader of one TDMS capture."""

    def __init__(self, path: Path, group: str | None) -> None:
        self.path = path
        self.fname = path.name
        try:
            self._file = TdmsFile.open(path)
        except Exception as exc:  # npTDMS raises several types on a damaged file
            raise CaptureError(
                f"{self.fname} cannot be read as TDMS ({exc}); check that the file is complete"
            ) from None
        try:
            self._open_group(group)
        except Exception:
            self._file.close()
            raise

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

    def _channel(self, name: str) -> Any:
        ch = self._group[name]
        dt = ch.dtype
        if dt is None or np.dtype(dt).kind not in "iuf":
            raise CaptureError(
                f"{self.fname} channel {name!r} holds {dt} values, not real numbers; "
                "write it as a numeric channel"
            )
        return ch

    def length(self, name: str) -> int:
        return len(self._group[name])

    def read(self, names: list[str], ragged: bool) -> dict[str, np.ndarray]:
        return {n: np.asarray(self._channel(n)[:]) for n in names}

    def chunks(self, names: list[str], chunk_rows: int) -> Iterator[dict[str, np.ndarray]]:
        chans = {n: self._channel(n) for n in names}
        total = self.length(names[0])
        for lo in range(0, total, chunk_rows):
            hi = min(total, lo + chunk_rows)
            yield {n: np.asarray(ch[lo:hi]) for n, ch in chans.items()}

    def locate(self, index: int) -> str:
        return f"row {index} (0-based)"

    def close(self) -> None:
        self._file.close()


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
