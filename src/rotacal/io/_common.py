"""Shared pieces of the capture readers: formats, file checks, column validation.

Nothing here is public; :mod:`rotacal.io` re-exports what users need.
"""

from __future__ import annotations

import codecs
import gzip
import os
import struct
import tokenize
import zipfile
import zlib
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import numpy as np

from rotacal.errors import CaptureError, ConfigError, RotacalError

#: file extension (lower case) -> format name
FORMATS: dict[str, str] = {
    ".csv": "csv",
    ".txt": "csv",
    ".npz": "npz",
    ".h5": "hdf5",
    ".hdf5": "hdf5",
    ".tdms": "tdms",
}
#: text captures rotacal reads but does not write (read like .csv, the separator sniffed); .mat
#: covers the ASCII files some programs save under that name (imu_tk's xsens_gyro.mat)
_READ_ONLY_TEXT = (".dat", ".tsv", ".mat")
#: text capture extensions that may carry a further ``.gz`` (read through gzip)
_GZIP_INNER = (".csv", ".txt", ".dat", ".tsv")
_FORMAT_LABEL = {"csv": "CSV", "npz": "NPZ", "hdf5": "HDF5", "tdms": "TDMS"}
_SNIFF_LABEL = {
    "csv": "CSV text",
    "npz": "a ZIP archive such as NPZ or Excel .xlsx",
    "hdf5": "an HDF5 file",
    "tdms": "a TDMS file",
    "npy": "a single NumPy .npy array",
    "utf16": "UTF-16 text",
    "text8": "text that is not UTF-8, e.g. Latin-1",
    "binary": "binary data of an unknown format",
}
_SNIFF_EXT = {"csv": ".csv", "npz": ".npz", "hdf5": ".h5", "tdms": ".tdms"}
_HDF5_MAGIC = b"\x89HDF\r\n\x1a\n"
#: elements per block when scanning (possibly memory-mapped) columns, to keep memory flat
BLOCK = 1 << 20
#: the name under which NPZ captures keep their metadata (JSON text)
NPZ_METADATA_KEY = "__metadata__"


def known_extensions() -> str:
    """The recognised capture extensions (written and read), as text for messages."""
    return ", ".join(FORMATS)


def _readable_extensions() -> str:
    return ", ".join([*FORMATS, *_READ_ONLY_TEXT, ".csv.gz", ".txt.gz", ".dat.gz"])


def is_gzip(path: Path) -> bool:
    """A text capture compressed with gzip (``name.csv.gz``, ``name.txt.gz`` …)."""
    return path.suffix.lower() == ".gz"


def format_of(path: Path) -> str:
    """Format name from the file extension; unknown extension -> CaptureError."""
    suffix = path.suffix.lower()
    if suffix == ".gz":
        inner = Path(path.stem).suffix.lower()
        if inner in _GZIP_INNER:
            return "csv"
        raise CaptureError(
            f"{path.name}: rotacal reads gzip-compressed text captures "
            f"({', '.join(i + '.gz' for i in _GZIP_INNER)}), not {inner or 'this'!s} files — "
            "decompress it, or name it after its content (e.g. data.csv.gz)"
        )
    fmt = FORMATS.get(suffix) or ("csv" if suffix in _READ_ONLY_TEXT else None)
    if fmt is None:
        raise CaptureError(
            f"{path.name} has an unknown capture extension {path.suffix or '(none)'!r}; "
            f"rotacal reads {_readable_extensions()} — rename or convert the file"
        )
    return fmt


def _gunzipped_head(path: Path, nbytes: int = 4096) -> bytes:
    """The first bytes of a gzip file's content (what was compressed), for sniffing."""
    try:
        with gzip.open(path, "rb") as fh:
            return fh.read(nbytes)
    except (OSError, EOFError, zlib.error) as exc:
        raise damaged(path.name, f"its gzip stream cannot be read ({reason(exc)})") from None


def _matlab_binary(p: Path, head: bytes) -> CaptureError:
    version = head[:19].decode("ascii", "replace").replace("MAT-file", "").strip()
    return CaptureError(
        f"{p.name} is a binary MATLAB MAT-file ({version}), which rotacal cannot read; in MATLAB "
        "save the data as CSV (writematrix) or as HDF5 (save -v7.3, then rename the file .h5)"
    )


def sniff(head: bytes) -> str:
    """Guess a format from the first bytes of a file (see ``_SNIFF_LABEL``)."""
    if head.startswith(b"PK\x03\x04") or head.startswith(b"PK\x05\x06"):
        return "npz"
    if head.startswith(_HDF5_MAGIC):
        return "hdf5"
    if head.startswith(b"TDSm"):
        return "tdms"
    if head.startswith(b"\x93NUMPY"):
        return "npy"
    if head.startswith((b"\xff\xfe", b"\xfe\xff")):
        return "utf16"
    if b"\x00" in head:
        return "binary"
    try:
        codecs.getincrementaldecoder("utf-8")().decode(head, final=False)
    except UnicodeDecodeError:
        printable = sum(1 for b in head if b >= 32 or b in (9, 10, 13))
        return "text8" if printable >= 0.95 * len(head) else "binary"
    return "csv"


def _hdf5_with_userblock(path: Path) -> bool:
    with open(path, "rb") as fh:
        for off in (512, 1024, 2048, 4096):
            fh.seek(off)
            if fh.read(8) == _HDF5_MAGIC:
                return True
    return False


def open_checked(path: str | os.PathLike[str]) -> tuple[Path, str]:
    """Check that ``path`` is a readable, non-empty file whose content matches its extension.

    Returns the path and the format name. Every failure is a one-line CaptureError.
    """
    p = Path(path)
    fmt = format_of(p)
    if not p.exists():
        raise CaptureError(f"capture file {str(path)!r} does not exist; check the path")
    if p.is_dir():
        raise CaptureError(f"{p.name} is a directory, not a capture file; give a file inside it")
    try:
        with open(p, "rb") as fh:
            head = fh.read(4096)
    except PermissionError:
        raise CaptureError(
            f"{p.name} cannot be read (permission denied); fix its permissions"
        ) from None
    except OSError as exc:
        reason = exc.strerror or exc
        raise CaptureError(f"{p.name} cannot be read ({reason}); check the file") from None
    if not head:
        raise CaptureError(f"{p.name} is empty; give a capture that holds data")
    if is_gzip(p):
        if not head.startswith(b"\x1f\x8b"):
            raise CaptureError(
                f"{p.name} is not gzip-compressed although it is named .gz; rename it without .gz"
            )
        head = _gunzipped_head(p)
        if not head:
            raise CaptureError(f"{p.name} is empty once decompressed; give a capture with data")
    elif p.suffix.lower() == ".mat" and head.startswith(b"MATLAB"):
        raise _matlab_binary(p, head)
    kind = sniff(head)
    if kind == "binary" and fmt == "hdf5" and _hdf5_with_userblock(p):
        kind = "hdf5"
    if kind != fmt:
        label = _FORMAT_LABEL[fmt]
        art = "an" if label[0] in "AEFHILMNORSX" else "a"
        fix = (
            f"rename it to {_SNIFF_EXT[kind]}"
            if kind in _SNIFF_EXT
            else ("save it as UTF-8 CSV" if kind in ("utf16", "text8") else "convert it")
        )
        raise CaptureError(
            f"{p.name} is not {art} {label} file (it looks like {_SNIFF_LABEL[kind]}); {fix}"
        )
    return p, fmt


def check_group_unused(p: Path, group: str | None) -> None:
    if group is not None:
        raise ConfigError(
            f"--group {group!r} applies to HDF5 and TDMS captures, not to {p.name}; leave it out"
        )


def plain(value: Any) -> Any:
    """NumPy scalars/arrays in metadata -> plain Python values."""
    if isinstance(value, bytes):
        return value.decode("utf-8", "replace")
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, np.generic):
        return value.item()
    return value


def _first_true(mask: np.ndarray) -> int:
    return int(np.argmax(mask))


def first_nonfinite(
    x: np.ndarray, start: int = 0, on_block: Callable[[int, int], None] | None = None
) -> int:
    """Index of the first NaN/inf in ``x`` at or after ``start`` (blockwise), or -1.

    ``on_block(lo, hi)`` is called for each block before it is scanned (while it is in cache).
    """
    n = x.shape[0]
    for i in range(start, n, BLOCK):
        if on_block is not None:
            on_block(i, min(n, i + BLOCK))
        block = x[i : i + BLOCK]
        ok = np.isfinite(block)
        if not ok.all():
            return i + _first_true(~ok)
    return -1


def trailing_nan_start(x: np.ndarray) -> int:
    """Length of ``x`` without its trailing NaNs (padding), scanning blockwise from the end."""
    end = x.shape[0]
    while end > 0:
        lo = max(0, end - BLOCK)
        block = x[lo:end]
        nn = ~np.isnan(block)
        if nn.any():
            return lo + int(block.shape[0] - 1 - np.argmax(nn[::-1])) + 1
        end = lo
    return 0


def check_time(
    t: np.ndarray | Sequence[float], name: str = "time_s", *, source: str | None = None
) -> None:
    """Check that a time column is finite and strictly increasing.

    Parameters
    ----------
    t : array_like
        Times in s, 1-D.
    name : str
        Column name used in the message.
    source : str, optional
        File the column came from, named in the message.

    Raises
    ------
    CaptureError
        Naming the first bad row (0-based) when ``t`` is not 1-D, holds NaN/inf, or does not
        strictly increase.
    """
    arr = t if isinstance(t, np.ndarray) else np.asarray(t, dtype=np.float64)
    who = f"{Path(source).name} column {name!r}" if source else f"column {name!r}"
    if arr.ndim != 1:
        raise CaptureError(f"{who} has shape {arr.shape}; a time column must be 1-D")
    if arr.dtype.kind not in "iuf":
        raise CaptureError(f"{who} holds {arr.dtype} values; a time column must hold numbers (s)")
    if arr.dtype.kind == "f":
        bad = first_nonfinite(arr)
        if bad >= 0:
            raise CaptureError(
                f"{who} holds {float(arr[bad])} at row {bad} (0-based); "
                "times must be finite numbers"
            )
    n = arr.shape[0]
    for i in range(0, max(n - 1, 0), BLOCK):
        block = arr[i : i + BLOCK + 1]
        step_ok = np.diff(block) > 0
        if not step_ok.all():
            j = i + _first_true(~step_ok) + 1
            raise CaptureError(
                f"{who} is not strictly increasing at row {j} (0-based): {float(arr[j])!r} s "
                f"follows {float(arr[j - 1])!r} s; sort the capture or drop repeated samples"
            )


# --- damaged files ----------------------------------------------------------------------------

#: What the format libraries (zipfile, zlib, numpy.lib.format, h5py, npTDMS, the codecs) raise on
#: damaged or truncated bytes. Exactly these become CaptureError: another type is a fault of
#: rotacal's own code and must surface as one (the fuzz test fails on it).
LIBRARY_ERRORS: tuple[type[BaseException], ...] = (
    OSError,
    ValueError,  # includes UnicodeDecodeError
    LookupError,  # KeyError, IndexError
    RuntimeError,  # includes NotImplementedError ("compression method is not supported")
    EOFError,
    ArithmeticError,  # OverflowError: a declared size beyond any integer type
    struct.error,
    zlib.error,
    zipfile.BadZipFile,
    tokenize.TokenError,  # numpy's parser of a damaged .npy header
    SyntaxError,
)
#: what a user can do about a damaged capture
DAMAGED_FIX = "copy or export the capture again from the recording"
_REASON_CHARS = 160


def name_list(names: Sequence[str], most: int = 12) -> str:
    """Names for a message: the first ``most`` and how many in all (a (3, N) array has N)."""
    if not names:
        return "none"
    shown = ", ".join(names[:most])
    return shown if len(names) <= most else f"{shown} … ({len(names)} in all)"


def reason(exc: BaseException) -> str:
    """A library's exception as one short line of text for a message."""
    # the message alone: KeyError quotes it, TokenError adds a position tuple
    plain_text = exc.args and isinstance(exc.args[0], str) and not isinstance(exc, UnicodeError)
    text = " ".join((exc.args[0] if plain_text else str(exc)).split()) or type(exc).__name__
    if len(text) > _REASON_CHARS:
        text = text[: _REASON_CHARS - 1] + "…"
    return text


def damaged(fname: str, detail: str) -> CaptureError:
    """The error for a file whose bytes contradict themselves: what is wrong and what to do."""
    return CaptureError(f"{fname} is damaged or incomplete: {detail}; {DAMAGED_FIX}")


@contextmanager
def library_errors(fname: str, label: str, where: str = "") -> Iterator[None]:
    """Turn what a format library raises on bad bytes (LIBRARY_ERRORS) into a CaptureError.

    ``label`` names the format ("HDF5"), ``where`` the part being read ("dataset 'a'").
    rotacal's own errors pass through unchanged.
    """
    try:
        yield
    except RotacalError:
        raise
    except LIBRARY_ERRORS as exc:
        part = f" at {where}" if where else ""
        raise damaged(
            fname, f"its {label} structure cannot be read{part} ({reason(exc)})"
        ) from None
