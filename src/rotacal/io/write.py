"""Writing captures in the format given by the extension, never over an existing file by default."""

from __future__ import annotations

import contextlib
import os
import tempfile
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from rotacal.errors import CaptureError, ConfigError

from ._common import FORMATS, NPZ_METADATA_KEY, known_extensions
from ._csv import ENCODING, write_csv
from ._hdf5 import write_hdf5
from ._npz import write_npz
from ._tdms import write_tdms


def _check_columns(columns: Mapping[str, Any]) -> dict[str, np.ndarray]:
    if not isinstance(columns, Mapping) or not columns:
        raise CaptureError("a capture needs at least one column to write (a name and its values)")
    out: dict[str, np.ndarray] = {}
    for name, values in columns.items():
        if not isinstance(name, str) or not name:
            raise ConfigError(f"column names must be non-empty text, not {name!r}")
        if name == NPZ_METADATA_KEY:
            raise ConfigError(f"column name {name!r} is reserved for metadata; rename the column")
        arr = np.asarray(values)
        if arr.ndim != 1 or arr.shape[0] == 0:
            raise CaptureError(
                f"column {name!r} has shape {arr.shape}; each column must be a non-empty 1-D array"
            )
        if arr.dtype.kind not in "iuf":
            raise CaptureError(
                f"column {name!r} holds {arr.dtype} values; a capture column must hold real numbers"
            )
        out[name] = arr
    return out


def write_capture(
    path: str | os.PathLike[str],
    columns: Mapping[str, np.ndarray],
    *,
    group: str | None = None,
    overwrite: bool = False,
    metadata: Mapping[str, Any] | None = None,
) -> Path:
    """Write columns as a capture in the format given by the extension of ``path``.

    CSV: ``# key: value`` metadata comments (JSON values), one header row, numbers as ``repr``
    (they read back bit-for-bit); shorter columns are padded with empty cells. NPZ: one
    uncompressed array per column (memory-mappable), metadata as JSON in ``__metadata__``.
    HDF5: one contiguous dataset per column at the root or under ``group``, metadata as
    attributes. TDMS: one group (``group``, default ``"capture"``), metadata as group properties.
    Binary formats keep the arrays' own numeric dtype; columns may differ in length.

    The file is written to a temporary name beside ``path`` and moved into place, so a failed
    write leaves nothing behind; an existing ``path`` is never replaced unless ``overwrite``.

    Returns
    -------
    Path
        The written file.

    Raises
    ------
    ConfigError
        Unknown extension, missing directory, ``path`` exists (without ``overwrite``), names that
        the format cannot hold, ``group`` given for CSV/NPZ.
    CaptureError
        A column that is not a non-empty 1-D numeric array.
    """
    p = Path(path)
    fmt = FORMATS.get(p.suffix.lower())
    if fmt is None:
        raise ConfigError(
            f"cannot write {p.name}: unknown capture extension {p.suffix or '(none)'!r}; "
            f"use one of {known_extensions()}"
        )
    if group is not None and fmt in ("csv", "npz"):
        raise ConfigError(f"--group applies to HDF5 and TDMS files, not to {p.name}; leave it out")
    if p.is_dir():
        raise ConfigError(f"{p} is a directory; give a file name for the capture")
    if p.exists() and not overwrite:
        raise ConfigError(
            f"{p.name} already exists and will not be overwritten; choose another name or give "
            "--overwrite"
        )
    parent = p.parent if str(p.parent) else Path(".")
    if not parent.is_dir():
        raise ConfigError(f"cannot write {p.name}: directory {parent} does not exist; create it")
    cols = _check_columns(columns)
    meta = dict(metadata or {})
    fd, tmp_name = tempfile.mkstemp(dir=parent, prefix=f".{p.name}.", suffix=p.suffix)
    tmp = Path(tmp_name)
    try:
        if fmt == "csv":
            with os.fdopen(fd, "w", encoding=ENCODING.replace("-sig", ""), newline="\n") as fh:
                write_csv(fh, cols, meta)
        elif fmt == "npz":
            with os.fdopen(fd, "wb") as fb:
                write_npz(fb, cols, meta)
        else:
            os.close(fd)
            if fmt == "hdf5":
                write_hdf5(tmp, cols, group, meta)
            else:
                write_tdms(tmp, cols, group, meta)
        _move_into_place(tmp, p, overwrite)
    except BaseException:
        with contextlib.suppress(OSError):
            tmp.unlink()
        raise
    return p


def _move_into_place(tmp: Path, dest: Path, overwrite: bool) -> None:
    """Rename ``tmp`` to ``dest``; without ``overwrite`` never replace a file (even in a race)."""
    with contextlib.suppress(OSError):
        os.chmod(tmp, 0o666 & ~_umask())
    if overwrite:
        os.replace(tmp, dest)
        return
    try:
        os.link(tmp, dest)
    except FileExistsError:
        raise ConfigError(
            f"{dest.name} already exists and will not be overwritten; choose another name or "
            "give --overwrite"
        ) from None
    except OSError:  # no hard links on this file system: check, then rename
        if dest.exists():
            raise ConfigError(
                f"{dest.name} already exists and will not be overwritten; choose another name "
                "or give --overwrite"
            ) from None
        os.replace(tmp, dest)
        return
    tmp.unlink()


def _umask() -> int:
    """The process umask, read without changing it (Linux); 0o022 elsewhere."""
    try:
        with open("/proc/self/status") as fh:
            for line in fh:
                if line.startswith("Umask:"):
                    return int(line.split()[1], 8)
    except OSError:
        pass
    return 0o022
