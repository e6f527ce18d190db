"""Reading captures: :class:`Capture`, :func:`read_capture`, chunked reading, column mapping.

A capture is a table of named 1-D columns in a CSV, NPZ, HDF5 or TDMS file (see the "Captures"
section of INTERFACE.md). Readers check the file's content against its extension, map the file's
own column names onto canonical ones (``--column OLD=NEW``), load only the columns asked for and
refuse anything that would give a silently wrong number: missing columns, non-numeric cells,
NaN/inf, empty columns, columns of unequal length.
"""

from __future__ import annotations

import contextlib
import mmap
import os
import threading
from collections.abc import Callable, Iterable, Iterator, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from rotacal.errors import CaptureError, ConfigError

from ._array_columns import ArrayColumns, split_subscript
from ._common import (
    LIBRARY_ERRORS,
    check_group_unused,
    library_errors,
    name_list,
    open_checked,
)
from ._npz import NpzReader
from ._validate import (
    Reader,
    check_file_names,
    check_requested_name,
    check_values,
    declared_length,
    equal_lengths,
    label,
    reading,
    to_float_column,
)
from .read_options import ReadOptions

PathLike = str | os.PathLike[str]
MappingArg = Mapping[str, str] | Iterable[str] | None


@dataclass
class Capture:
    """Columns of one capture file, under their canonical names.

    Attributes
    ----------
    columns : dict of str to ndarray
        Canonical name -> 1-D float64 column (memory-mapped, read-only, for uncompressed NPZ
        members and contiguous HDF5 datasets stored as float64).
    source : str
        The path as given.
    metadata : dict
        Metadata stored with the capture: CSV ``# key: value`` comments, HDF5 attributes of the
        group, TDMS file and group properties, the NPZ ``__metadata__`` member.
    file_columns : list of str
        Every column the file offers (after mapping), loaded or not; used in messages.
    """

    columns: dict[str, np.ndarray]
    source: str
    metadata: dict[str, Any] = field(default_factory=dict)
    file_columns: list[str] = field(default_factory=list, repr=False)

    @property
    def names(self) -> list[str]:
        """Names of the loaded columns."""
        return list(self.columns)

    def __getitem__(self, name: str) -> np.ndarray:
        try:
            return self.columns[name]
        except KeyError:
            pass
        fname = Path(self.source).name
        if name in self.file_columns:
            loaded = ", ".join(self.names) or "none"
            raise CaptureError(
                f"{fname} column {name!r} is in the file but was not read (read: {loaded}); "
                f"read the capture again asking for {name!r} too"
            )
        have = name_list(self.file_columns or self.names)
        raise CaptureError(
            f"{fname} has no column {name!r} (it has: {have}); map one with --column OLD={name}"
        )

    def __contains__(self, name: object) -> bool:
        return name in self.columns

    def __len__(self) -> int:
        return max((c.shape[0] for c in self.columns.values()), default=0)


def _file_side_first(old: str, new: str) -> tuple[str, str]:
    """``NAME=ARRAY[:,K]`` (INTERFACE.md's spelling) -> ``ARRAY[:,K]=NAME``: the side with the
    column subscript is the file's."""
    if split_subscript(new) is not None and split_subscript(old) is None:
        return new, old
    return old, new


def parse_column_mapping(items: Iterable[str] | None) -> dict[str, str]:
    """Parse ``--column OLD=NEW`` items into ``{OLD: NEW}``.

    A column of a 2-D array may be written either way round: ``data[:,0]=rate_deg_s`` or
    ``rate_deg_s=data[:,0]`` (the side with the subscript is the file's).

    Raises
    ------
    ConfigError
        For an item that is not ``OLD=NEW`` with two non-empty names, the same OLD twice, or
        two OLD names mapped onto the same NEW.
    """
    out: dict[str, str] = {}
    if items is None:
        return out
    if isinstance(items, str):
        items = [items]
    for item in items:
        if not isinstance(item, str):
            raise ConfigError(f"--column {item!r} is not text; write it as OLD=NEW, e.g. ch1=a")
        parts = item.split("=")
        if len(parts) != 2 or not parts[0].strip() or not parts[1].strip():
            raise ConfigError(
                f"--column {item!r} must be OLD=NEW with two names, e.g. --column ch1=a"
            )
        old, new = _file_side_first(parts[0].strip(), parts[1].strip())
        if old in out:
            raise ConfigError(f"--column maps {old!r} twice ({out[old]!r} and {new!r}); keep one")
        out[old] = new
    _check_targets(out)
    return out


def _check_targets(mapping: Mapping[str, str]) -> None:
    seen: dict[str, str] = {}
    for old, new in mapping.items():
        if new in seen:
            raise ConfigError(
                f"--column maps both {seen[new]!r} and {old!r} onto {new!r}; map only one of them"
            )
        seen[new] = old


def _normalise_mapping(mapping: MappingArg) -> dict[str, str]:
    if mapping is None:
        return {}
    if isinstance(mapping, Mapping):
        out = dict(
            _file_side_first(
                check_requested_name(k, "--column name"), check_requested_name(v, "--column name")
            )
            for k, v in mapping.items()
        )
        _check_targets(out)
        return out
    return parse_column_mapping(mapping)


def _reader_class(fmt: str) -> Any:
    """The reader of a format. HDF5's and TDMS's import h5py and nptdms (~60 and ~35 ms), so they
    are imported when such a file is opened, not with the package."""
    if fmt == "hdf5":
        from ._hdf5 import Hdf5Reader

        return Hdf5Reader
    if fmt == "tdms":
        from ._tdms import TdmsReader

        return TdmsReader
    if fmt == "csv":
        from ._csv import CsvReader

        return CsvReader
    return NpzReader


def _open_reader(
    path: PathLike, group: str | None, read_options: ReadOptions | None = None
) -> Reader:
    """Check the file, open its reader and check the names it offers (one path for all).

    ``read_options`` (delimiter, decimal mark, names of a headerless file) apply to text captures.
    """
    if group is not None and not isinstance(group, str):
        raise ConfigError(f"--group {group!r} is not text; give the group's name")
    p, fmt = open_checked(path)
    if fmt != "csv" and read_options is not None and not read_options.is_default:
        raise ConfigError(
            f"--delimiter, --decimal and --names apply to text captures, not to {p.name} "
            f"({fmt.upper()}, whose columns are named in the file); leave them out"
        )
    cls = _reader_class(fmt)
    if fmt in ("csv", "npz"):
        check_group_unused(p, group)
    with library_errors(p.name, fmt.upper()):
        if fmt == "csv":
            reader: Reader = cls(p, read_options)
        else:
            reader = cls(p) if fmt == "npz" else cls(p, group)
    try:
        if fmt in ("npz", "hdf5"):
            with library_errors(p.name, fmt.upper()):
                reader = ArrayColumns(reader)
        reader.names = check_file_names(reader.fname, reader.names, reader.noun)
    except BaseException:
        _close(reader)
        raise
    return reader


def _close(reader: Reader) -> None:
    """Close a reader; a damaged file failing to close again changes nothing (all was read)."""
    with contextlib.suppress(*LIBRARY_ERRORS):
        reader.close()


def _resolve(
    reader: Reader, mapping: dict[str, str], columns: Iterable[str] | None
) -> tuple[list[str], dict[str, str]]:
    """Apply the mapping; return the canonical names of the file and canonical -> file name."""
    fname = reader.fname
    have = reader.names
    normalise = getattr(reader, "normalise", None)  # data[:,-1] -> data[:,5]; text columns
    if normalise is not None:
        mapping = {normalise(old): new for old, new in mapping.items()}
        if columns is not None:
            wanted_raw = [columns] if isinstance(columns, str) else list(columns)
            columns = [normalise(c) if isinstance(c, str) else c for c in wanted_raw]
    for old in mapping:
        if old not in have:
            raise CaptureError(
                f"{fname} has no column {old!r} to map (it has: {name_list(have)}); "
                f"fix --column {old}={mapping[old]}"
            )
    canon: dict[str, str] = {}
    for name in have:
        new = mapping.get(name, name)
        if new in canon:
            other = canon[new]
            own = other if other == new else name
            raise CaptureError(
                f"{fname}: mapping onto {new!r} clashes with the file's own column {own!r}; "
                f"map that one to another name too (--column {own}={own}_raw)"
            )
        canon[new] = name
    available = list(canon)
    if columns is None:
        return available, canon
    wanted = [columns] if isinstance(columns, str) else list(columns)
    if not wanted:
        raise ConfigError("no column was named to read; name at least one column")
    for name in wanted:
        check_requested_name(name)
    missing = [c for c in dict.fromkeys(wanted) if c not in canon]
    if missing:
        names = ", ".join(repr(m) for m in missing)
        one = missing[0]
        raise CaptureError(
            f"{fname} has no column {names} (it has: {name_list(available)}); "
            f"map one with --column OLD={one}"
        )
    return available, {c: canon[c] for c in dict.fromkeys(wanted)}


def _declared(reader: Reader, wanted: dict[str, str]) -> dict[str, int | None]:
    """Check what the file declares of each wanted column; return the declared lengths."""
    lengths: dict[str, int | None] = {}
    for canon, fcol in wanted.items():
        what = label(canon, fcol, reader.noun)
        with reading(reader, what):
            info = reader.describe(fcol)
        lengths[canon] = declared_length(reader.fname, what, info)
    return lengths


def _wanted_lengths(
    reader: Reader, mapped: dict[str, str], columns: Iterable[str]
) -> tuple[dict[str, str], dict[str, int]]:
    """The wanted columns (canonical name → the file's) and the lengths the file declares of
    them (CSV declares none)."""
    _available, wanted = _resolve(reader, mapped, columns)
    lengths = _declared(reader, wanted)
    return wanted, {k: n for k, n in lengths.items() if n is not None}


def capture_columns(
    path: PathLike,
    *,
    mapping: MappingArg = None,
    group: str | None = None,
    read_options: ReadOptions | None = None,
) -> list[str]:
    """The canonical names (after ``mapping``) of the columns a capture offers, from its header
    alone: no data is read. Arguments as for :func:`read_capture`."""
    reader = _open_reader(path, group, read_options)
    try:
        available, _ = _resolve(reader, _normalise_mapping(mapping), None)
        return available
    finally:
        _close(reader)


def read_capture(
    path: PathLike,
    *,
    columns: Iterable[str] | None = None,
    mapping: MappingArg = None,
    group: str | None = None,
    ragged: bool = False,
    read_options: ReadOptions | None = None,
    allow_nonfinite: bool = False,
) -> Capture:
    """Read a capture file into a :class:`Capture` of validated float64 columns.

    Parameters
    ----------
    path : str or path-like
        ``.csv``/``.txt``, ``.npz``, ``.h5``/``.hdf5`` or ``.tdms``; the content must match.
    columns : iterable of str, optional
        Canonical names (after mapping) the caller needs; all must exist and only they are
        loaded. Default: every column.
    mapping : mapping or iterable of "OLD=NEW", optional
        Renames file columns onto canonical names before ``columns`` is checked.
    group : str, optional
        HDF5 group (``grp/sub`` allowed) or TDMS group holding the columns.
    ragged : bool
        Allow columns of different lengths (multi-head pulse files); trailing empty CSV cells
        and trailing NaNs are padding and dropped per column.
    allow_nonfinite : bool
        Keep NaN/inf values instead of refusing them (a first look at a file counts them).

    Returns
    -------
    Capture
        Columns in the units of the file (the canonical names carry them).

    Raises
    ------
    CaptureError
        One line naming the file and the column/row at fault.
    """
    capture, _ = _read(
        path, columns, mapping, group, read_options, ragged=ragged,
        allow_nonfinite=allow_nonfinite, defer=False,
    )  # fmt: skip
    return capture


def read_capture_deferred(
    path: PathLike,
    *,
    columns: Iterable[str] | None = None,
    mapping: MappingArg = None,
    group: str | None = None,
    read_options: ReadOptions | None = None,
) -> tuple[Capture, DeferredChecks]:
    """:func:`read_capture`, with the scan of the values (NaN/inf) and of the stored CRC-32s
    left to a second thread, so that the caller can analyse the columns meanwhile.

    The scan is deferred only where it is all that is left to check: every column memory-mapped
    or read as 1-D native float64, none empty, all of one length. Otherwise everything is checked
    here, as by :func:`read_capture`, and the returned checks have nothing left to do. The caller
    must use the returned :class:`DeferredChecks` as a context manager around its use of the
    columns, and trust nothing it computed before that block has ended: a fault of the file is
    then raised (the one line :func:`read_capture` gives) in place of whatever the analysis
    raised or returned. Arguments as :func:`read_capture` (the columns of equal length).
    """
    capture, checks = _read(
        path, columns, mapping, group, read_options, ragged=False, allow_nonfinite=False,
        defer=True,
    )  # fmt: skip
    return capture, checks if checks is not None else DeferredChecks(None)


class DeferredChecks:
    """The value and CRC-32 checks of :func:`read_capture_deferred`, running on a thread
    (zlib's CRC-32 and NumPy's scans release the GIL).

    ``with checks: ...`` waits for them at the end of the block; when they found a fault its
    CaptureError is raised, superseding an exception of the block (an analysis of damaged or
    non-finite values may fail in its own words first).
    """

    def __init__(self, job: Callable[[], None] | None) -> None:
        self._error: BaseException | None = None
        self._thread: threading.Thread | None = None
        if job is not None:
            self._thread = threading.Thread(
                target=self._run, args=(job,), name="rotacal-capture-checks", daemon=True
            )
            self._thread.start()

    def _run(self, job: Callable[[], None]) -> None:
        try:
            job()
        except BaseException as exc:  # handed to the caller's thread by wait()
            self._error = exc

    def wait(self) -> None:
        """Block until the checks are done; raise what they found."""
        if self._thread is not None:
            self._thread.join()
        if self._error is not None:
            raise self._error.with_traceback(None)

    def __enter__(self) -> DeferredChecks:
        return self

    def __exit__(self, *exc: object) -> None:
        self.wait()


def _deferrable(raw: dict[str, Any]) -> bool:
    """Whether only the scan of the values is left to check of these raw columns."""
    arrays = list(raw.values())
    return all(
        isinstance(a, np.ndarray)
        and a.ndim == 1
        and a.dtype == np.float64
        and a.dtype.isnative
        and a.shape[0] > 0
        and a.shape[0] == arrays[0].shape[0]
        for a in arrays
    )


def _read(
    path: PathLike,
    columns: Iterable[str] | None,
    mapping: MappingArg,
    group: str | None,
    read_options: ReadOptions | None,
    *,
    ragged: bool,
    allow_nonfinite: bool,
    defer: bool,
) -> tuple[Capture, DeferredChecks | None]:
    """:func:`read_capture` (``defer`` False) and :func:`read_capture_deferred` (True)."""
    mapped = _normalise_mapping(mapping)
    reader = _open_reader(path, group, read_options)
    fname = reader.fname
    owned = True  # closed here, unless the deferred checks still read through it
    try:
        available, wanted = _resolve(reader, mapped, columns)
        _declared(reader, wanted)
        with reading(reader):
            raw = reader.read(list(wanted.values()), ragged)
        defer = defer and _deferrable(raw)
        cols: dict[str, np.ndarray] = {}
        scans: list[tuple[np.ndarray, str, Any]] = []
        for canon, fcol in wanted.items():
            what = label(canon, fcol, reader.noun)
            with reading(reader, what):
                integrity = reader.integrity(fcol)
            cols[canon] = to_float_column(
                raw.pop(fcol),
                fname=fname,
                what=what,
                locate=reader.locate,
                integrity=integrity,
                ragged=ragged,
                allow_nonfinite=allow_nonfinite or defer,
            )
            if defer:
                scans.append((cols[canon], what, integrity))
            elif integrity is not None:
                integrity.check()
        if not ragged:
            equal_lengths(fname, {k: v.shape[0] for k, v in cols.items()})
        capture = Capture(
            columns=cols,
            source=str(path),
            metadata=dict(reader.metadata),
            file_columns=available,
        )
        if not defer:
            return capture, None

        def scan() -> None:
            try:  # column by column, as read_capture checks them: the same fault first
                for col, what, integrity in scans:
                    check_values(col, fname=fname, what=what, locate=reader.locate,
                                 integrity=integrity)  # fmt: skip
                    if integrity is not None:
                        integrity.check()
            finally:
                _close(reader)

        owned = False
        return capture, DeferredChecks(scan)
    finally:
        if owned:
            _close(reader)


def _check_chunk_rows(chunk_rows: int) -> int:
    if isinstance(chunk_rows, bool) or not isinstance(chunk_rows, int | np.integer):
        raise ConfigError(f"chunk_rows must be a whole number of rows, not {chunk_rows!r}")
    if chunk_rows < 1:
        raise ConfigError(f"chunk_rows must be at least 1, not {chunk_rows}")
    return int(chunk_rows)


def iter_capture_chunks(
    path: PathLike,
    columns: Iterable[str],
    *,
    chunk_rows: int = 1_000_000,
    mapping: MappingArg = None,
    group: str | None = None,
    read_options: ReadOptions | None = None,
    allow_nonfinite: bool = False,
    verified: bool = False,
) -> Iterator[dict[str, np.ndarray]]:
    """Stream a capture in chunks of at most ``chunk_rows`` rows with bounded memory.

    Yields dicts canonical name -> 1-D float64 chunk (all of one length; possibly read-only
    views of a memory map). Concatenating the chunks gives what :func:`read_capture` returns.
    Columns must have equal lengths. Each chunk is validated like :func:`read_capture` (row
    numbers in messages count from the start of the file). The file is checked and opened on the
    first ``next()``. ``allow_nonfinite`` keeps NaN/inf values instead of refusing them.
    ``verified``: the caller has read this file through once already with the checks (a later
    pass of a streaming analysis), so its values are not scanned for NaN/inf nor its stored
    CRC-32s recomputed again (about a third of the time of a pass over an NPZ from the cache).

    Raises
    ------
    CaptureError, ConfigError
    """
    rows = _check_chunk_rows(chunk_rows)
    mapped = _normalise_mapping(mapping)
    reader = _open_reader(path, group, read_options)
    fname = reader.fname
    try:
        wanted, known = _wanted_lengths(reader, mapped, columns)
        if len(known) == len(wanted):  # CSV: unequal lengths show up as empty cells
            equal_lengths(fname, known)
        whats = {canon: label(canon, fcol, reader.noun) for canon, fcol in wanted.items()}
        with reading(reader):
            checks = {
                canon: None if verified else reader.integrity(fcol)
                for canon, fcol in wanted.items()
            }
            pieces = iter(reader.chunks(list(wanted.values()), rows))
        start = 0
        while True:
            with reading(reader):
                raw = next(pieces, None)
            if raw is None:
                break
            out = {
                canon: to_float_column(
                    raw[fcol],
                    fname=fname,
                    what=whats[canon],
                    locate=reader.locate,
                    integrity=checks[canon],
                    offset=start,
                    allow_nonfinite=allow_nonfinite or verified,
                )
                for canon, fcol in wanted.items()
            }
            start += next(iter(out.values())).shape[0]
            yield out
            # the consumer asked for the next chunk: hand the pages of this one back (flat memory)
            release_pages(raw)
        if start == 0:
            raise CaptureError(f"{fname} has no data rows; give a capture with data in it")
        for check in checks.values():
            if check is not None:
                check.check()
    finally:
        _close(reader)


def read_capture_rows(
    path: PathLike,
    columns: Iterable[str],
    start: int,
    stop: int,
    *,
    mapping: MappingArg = None,
    group: str | None = None,
    read_options: ReadOptions | None = None,
) -> dict[str, np.ndarray]:
    """Rows ``start`` … ``stop - 1`` of a capture's ``columns`` (canonical names), read without
    the rows before them: for analyses that split one capture over many processes.

    Each column is validated as :func:`iter_capture_chunks` validates a chunk (row numbers in
    messages count from the start of the file). A stored checksum covers the whole column and
    is not checked here: a pass over the whole file (:func:`iter_capture_chunks`) checks it.

    Raises
    ------
    ConfigError
        The format has no row offsets (CSV and other text, a compressed NPZ member): convert the
        capture to NPZ saved without compression, HDF5 or TDMS.
    CaptureError
        Unequal column lengths, a range outside the capture, NaN/inf or absurd values.
    """
    mapped = _normalise_mapping(mapping)
    reader = _open_reader(path, group, read_options)
    fname = reader.fname
    try:
        wanted, known = _wanted_lengths(reader, mapped, columns)
        equal_lengths(fname, known)
        n = next(iter(known.values()), None)
        if n is not None and not 0 <= start < stop <= n:
            raise CaptureError(f"{fname}: rows {start}…{stop - 1} are outside its {n} rows")
        with reading(reader):
            raw = reader.rows(list(wanted.values()), start, stop)
        if raw is None:
            raise ConfigError(
                f"{fname}: its {reader.label} data cannot be read from a given row on (text, or "
                "a compressed NPZ member); for parallel analysis save it as NPZ without "
                "compression (numpy.savez), HDF5 or TDMS"
            )
        return {
            canon: to_float_column(
                raw[fcol],
                fname=fname,
                what=label(canon, fcol, reader.noun),
                locate=reader.locate,
                integrity=None,
                offset=start,
                allow_nonfinite=False,
            )
            for canon, fcol in wanted.items()
        }
    finally:
        _close(reader)


def release_pages(arrays: Mapping[str, np.ndarray]) -> None:
    """Drop the pages of memory-mapped chunks from this process once they have been used.

    Pages of a file mapping that were read stay resident (and counted in the process's memory)
    until the kernel needs them; over a long capture that would look like the whole file in
    memory. ``madvise(MADV_DONTNEED)`` gives them back; the data stay in the page cache and a
    later read maps them again. Best effort: nothing happens where madvise is not available.
    """
    dontneed = getattr(mmap, "MADV_DONTNEED", None)
    if dontneed is None:
        return
    for arr in arrays.values():
        base: Any = arr
        while isinstance(base, np.ndarray):
            base = base.base
        if not isinstance(base, mmap.mmap) or arr.nbytes == 0:
            continue
        try:
            anchor = np.frombuffer(base, dtype=np.uint8)
            start = arr.__array_interface__["data"][0] - anchor.__array_interface__["data"][0]
            del anchor
            page_start = start - start % mmap.PAGESIZE
            base.madvise(dontneed, page_start, start + arr.nbytes - page_start)
        except (AttributeError, BufferError, OSError, ValueError):
            continue


def capture_length(
    path: PathLike,
    column: str,
    *,
    mapping: MappingArg = None,
    group: str | None = None,
    read_options: ReadOptions | None = None,
) -> int:
    """Number of rows of ``column`` (canonical name), without reading the data where possible.

    NPZ, HDF5 and TDMS read it from the metadata; CSV counts the data rows (one pass over the
    bytes, no parsing), which for padded (ragged) CSV files is the longest column's length.
    """
    mapped = _normalise_mapping(mapping)
    reader = _open_reader(path, group, read_options)
    try:
        _available, wanted = _resolve(reader, mapped, [column])
        n = _declared(reader, wanted)[column]
        if n is None:
            with reading(reader, label(column, wanted[column], reader.noun)):
                n = reader.row_count(wanted[column])
        return n
    finally:
        _close(reader)
