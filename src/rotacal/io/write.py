"""Writing captures in the format given by the extension, never over an existing file by default."""

from __future__ import annotations

import os
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
from .outputs import Writer, write_output


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

    The file is written as every rotacal output is (:mod:`rotacal.io.outputs`): to a temporary
    name beside ``path``, then given its name, so a failed write leaves nothing behind; an existing
    ``path`` is never replaced unless ``overwrite`` (and then atomically), and of several
    processes writing one name exactly one succeeds.

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
    writer = capture_writer(p, columns, group=group, metadata=metadata)
    return write_output(p, writer, label=p.name, overwrite=overwrite)


def capture_format(path: str | os.PathLike[str], group: str | None = None) -> str:
    """The format a capture at ``path`` is written in (from its extension), or a ConfigError."""
    p = Path(path)
    fmt = FORMATS.get(p.suffix.lower())
    if fmt is None:
        raise ConfigError(
            f"cannot write {p.name}: unknown capture extension {p.suffix or '(none)'!r}; "
            f"use one of {known_extensions()}"
        )
    if group is not None and fmt in ("csv", "npz"):
        raise ConfigError(f"--group applies to HDF5 and TDMS files, not to {p.name}; leave it out")
    return fmt


def capture_writer(
    path: str | os.PathLike[str],
    columns: Mapping[str, np.ndarray],
    *,
    group: str | None = None,
    metadata: Mapping[str, Any] | None = None,
) -> Writer:
    """Check columns and options for a capture at ``path``; return what writes it to a file.

    The returned function writes the capture, in the format given by the extension of ``path``,
    to the file it is given (a temporary file of :func:`rotacal.io.outputs.write_outputs`).

    Raises
    ------
    ConfigError
        Unknown extension, ``group`` given for CSV/NPZ, a bad column name.
    CaptureError
        A column that is not a non-empty 1-D numeric array.
    """
    fmt = capture_format(path, group)
    cols = _check_columns(columns)
    meta = dict(metadata or {})

    def write(target: Path) -> None:
        if fmt == "csv":
            with open(target, "w", encoding=ENCODING.replace("-sig", ""), newline="\n") as fh:
                write_csv(fh, cols, meta)
        elif fmt == "npz":
            with open(target, "wb") as fb:
                write_npz(fb, cols, meta)
        elif fmt == "hdf5":
            write_hdf5(target, cols, group, meta)
        else:
            write_tdms(target, cols, group, meta)

    return write
