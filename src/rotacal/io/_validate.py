"""The one validation path of every capture reader.

A reader (``_csv``, ``_npz``, ``_hdf5``, ``_tdms``) only turns bytes into arrays: it lists the
columns, describes each one as the file declares it (:class:`ColumnInfo`) and hands out the raw
arrays. Everything a capture must satisfy is checked here, in the same words for every format,
by :func:`read_capture`, :func:`iter_capture_chunks` and :func:`capture_length` alike:

- names asked for are text (a setting: ConfigError), names in the file are text, unique, not empty;
- a column is declared 1-D and numeric (real integers or floats), and no larger than the bytes
  the file holds for it (a damaged header that declares an absurd size is refused before anything
  is allocated);
- integers fit float64 exactly; the values are finite; a column is not empty;
- without ``ragged`` all columns have one length.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np

from rotacal.errors import CaptureError, ConfigError

from ._common import damaged, first_nonfinite, library_errors, name_list, trailing_nan_start

_MAX_EXACT_INT = 2**53
#: what the message tells a user to do about a column that holds several channels
_SPLIT = "so split it into one {noun} per channel"
#: the only captures whose columns may differ in length (read with ragged=True by the CLI)
RAGGED_USE = "only the pulse-timestamp captures of 'rotacal selfcal' and 'rotacal rate' may"


@dataclass(frozen=True)
class ColumnInfo:
    """A column as the file declares it, before any of its data is read.

    Attributes
    ----------
    noun : str
        What the format calls a column, for messages: "column", "dataset", "channel".
    dtype : numpy.dtype or None
        Declared element type; None where the format has no declaration (CSV: text).
    shape : tuple of int or None
        Declared shape; None where only reading tells (CSV).
    stored_bytes : int or None
        Bytes of data the container says it holds for the column (an NPZ member's size, an
        HDF5 dataset's allocated storage); must equal what the shape declares. None: unknown.
    max_bytes : int or None
        The most bytes of data the file can hold for the column (its size on disk, times the
        largest ratio of its compression); the declared size must not exceed it.
    """

    noun: str
    dtype: np.dtype[Any] | None = None
    shape: tuple[int, ...] | None = None
    stored_bytes: int | None = None
    max_bytes: int | None = None


class Integrity(Protocol):
    """A check of a column's bytes against a checksum the file stores (an NPZ member's CRC-32).

    ``feed(lo, hi)`` hands it rows lo..hi-1 while they are scanned anyway (in order);
    ``check()`` covers the rest and raises CaptureError when the bytes changed.
    """

    def feed(self, lo: int, hi: int) -> None: ...
    def check(self) -> None: ...


class Reader(Protocol):
    """What a format reader offers: bytes in; names, declarations and raw arrays out."""

    fname: str
    label: str  # the format, for messages: "CSV", "NPZ", "HDF5", "TDMS"
    noun: str  # what the format calls a column: "column", "dataset", "channel"
    names: list[str]
    metadata: dict[str, Any]

    def describe(self, name: str) -> ColumnInfo: ...
    def row_count(self, name: str) -> int: ...
    def read(self, names: list[str], ragged: bool) -> dict[str, np.ndarray]: ...
    def chunks(self, names: list[str], chunk_rows: int) -> Iterable[dict[str, np.ndarray]]: ...
    def rows(self, names: list[str], start: int, stop: int) -> dict[str, np.ndarray] | None: ...
    def integrity(self, name: str) -> Integrity | None: ...
    def locate(self, index: int) -> str: ...
    def close(self) -> None: ...


@contextmanager
def reading(reader: Reader, where: str = "") -> Iterator[None]:
    """Turn what a format library raises on damaged bytes into a one-line CaptureError."""
    with library_errors(reader.fname, reader.label, where):
        yield


# --- names ------------------------------------------------------------------------------------


def check_requested_name(name: object, what: str = "column name") -> str:
    """A column name given by the caller (``columns``, ``--column``) must be text."""
    if not isinstance(name, str):
        raise ConfigError(f"{what} {name!r} is not text; give column names as text, e.g. time_s")
    if not name:
        raise ConfigError(f"a {what} is empty; give the column's name")
    return name


def check_file_names(fname: str, names: Iterable[object], noun: str) -> list[str]:
    """The file's own column names: text, not empty, each once."""
    out: list[str] = []
    seen: set[str] = set()
    for i, name in enumerate(names):
        if not isinstance(name, str):
            raise CaptureError(
                f"{fname} has a {noun} whose name {name!r} is not text; the file is damaged or "
                "was not written as a capture — write it again"
            )
        if not name:
            raise CaptureError(
                f"{fname} has an empty name in {noun} {i + 1}; give every {noun} a name "
                "(in a CSV header, remove a trailing comma)"
            )
        if name in seen:
            raise CaptureError(
                f"{fname} names {noun} {name!r} more than once; give each {noun} its own name"
            )
        seen.add(name)
        out.append(name)
    return out


def label(canon: str, file_name: str, noun: str = "column") -> str:
    """How a column is named in a message: canonical name, and the file's name if mapped."""
    if canon == file_name:
        return f"{noun} {canon!r}"
    own = "file column" if noun == "column" else noun
    return f"column {canon!r} ({own} {file_name!r})"


# --- what the file declares -------------------------------------------------------------------


def check_declared(fname: str, what: str, info: ColumnInfo) -> None:
    """Check a column's declaration: numeric, 1-D, a size the file can hold. Nothing is read."""
    dt = info.dtype
    if dt is not None and (dt.names is not None or dt.hasobject or dt.kind not in "iuf"):
        shown = "Python objects" if dt.hasobject else f"{dt} values"
        raise CaptureError(
            f"{fname} {what} holds {shown}, not real numbers; store each column as numbers"
        )
    shape = info.shape
    if shape is None:
        return
    if len(shape) != 1:
        raise CaptureError(
            f"{fname} {what} has shape {shape}, not 1-D; each column must be one 1-D array, "
            + _SPLIT.format(noun=info.noun)
        )
    if dt is None:
        return
    declared = int(shape[0]) * dt.itemsize
    if info.stored_bytes is not None and declared != info.stored_bytes:
        raise damaged(
            fname,
            f"{what} declares {shape[0]} values ({declared} bytes) but the file stores "
            f"{info.stored_bytes} bytes for it",
        )
    if info.max_bytes is not None and declared > info.max_bytes:
        raise damaged(
            fname,
            f"{what} declares {shape[0]} values ({declared} bytes), more than the file can "
            f"hold ({info.max_bytes} bytes)",
        )


def declared_length(fname: str, what: str, info: ColumnInfo) -> int | None:
    """Rows a 1-D column declares (after :func:`check_declared`), or None when unknown."""
    check_declared(fname, what, info)
    return None if info.shape is None else int(info.shape[0])


# --- the values -------------------------------------------------------------------------------


def to_float_column(
    raw: Any,
    *,
    fname: str,
    what: str,
    locate: Callable[[int], str],
    integrity: Integrity | None = None,
    ragged: bool = False,
    offset: int = 0,
    allow_nonfinite: bool = False,
) -> np.ndarray:
    """Validate one raw column and return it as 1-D float64 (memory-mapped data stays mapped).

    ``what`` names the column in messages; ``locate(i)`` describes absolute row ``i``;
    ``offset`` is the absolute row of ``raw[0]`` (chunks). ``integrity`` is fed the rows as
    they are scanned, and checked before a NaN/inf is blamed on the data rather than on damage.
    ``allow_nonfinite`` keeps NaN/inf values (``rotacal inspect`` counts them) instead of refusing.
    """
    arr = raw if isinstance(raw, np.ndarray) else np.asarray(raw)
    check_declared(fname, what, ColumnInfo("column", arr.dtype, arr.shape))
    if arr.dtype.kind in "iu":
        if arr.size and max(abs(int(arr.min())), abs(int(arr.max()))) > _MAX_EXACT_INT:
            raise CaptureError(
                f"{fname} {what} holds integers beyond 2**53 that float64 cannot represent "
                "exactly; scale them (e.g. ticks to seconds) before saving"
            )
        out = arr.astype(np.float64)
    elif arr.dtype != np.float64 or not arr.dtype.isnative:
        with np.errstate(invalid="ignore"):  # a signalling NaN: the finite check names it
            out = arr.astype(np.float64)
    else:
        out = np.asarray(arr)  # a memmap becomes a plain ndarray view of the same mapping
    if ragged:
        out = out[: trailing_nan_start(out)]
    if out.shape[0] == 0:
        raise CaptureError(f"{fname} {what} is empty; give a capture with data in it")
    if not allow_nonfinite:
        check_values(
            out, fname=fname, what=what, locate=locate, integrity=integrity, ragged=ragged,
            offset=offset,
        )  # fmt: skip
    return out


def check_values(
    out: np.ndarray,
    *,
    fname: str,
    what: str,
    locate: Callable[[int], str],
    integrity: Integrity | None = None,
    ragged: bool = False,
    offset: int = 0,
) -> None:
    """Refuse a NaN/inf in the float64 column ``out`` (arguments as :func:`to_float_column`),
    feeding ``integrity`` the rows as they are scanned; damage (a CRC-32 that does not match) is
    blamed before the value. Touches nothing but ``out`` and ``integrity``, so it can run on a
    second thread while the column is analysed (:class:`rotacal.io.capture.DeferredChecks`)."""
    feed = None if integrity is None else (lambda lo, hi: integrity.feed(offset + lo, offset + hi))
    bad = first_nonfinite(out, on_block=feed)
    if bad >= 0:
        if integrity is not None:
            integrity.check()
        where = locate(offset + bad)
        hint = (
            f"; only trailing cells may be empty (padding), and {RAGGED_USE} have them"
            if ragged
            else "; remove or fix that row"
        )
        value = float(out[bad])
        raise CaptureError(f"{fname} {what} holds {value} at {where}, not a finite number{hint}")


def equal_lengths(fname: str, lengths: dict[str, int]) -> None:
    """Without ``ragged`` every loaded column must have the same length."""
    if len(set(lengths.values())) > 1:
        shown = name_list([f"{k}: {v}" for k, v in lengths.items()])
        raise CaptureError(
            f"{fname} columns have different lengths ({shown}); trim them to one length "
            f"({RAGGED_USE} differ)"
        )
