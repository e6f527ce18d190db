"""A first look at a file: what it is and, for a capture, its columns (:func:`inspect_capture`).

A file that is not a capture (JSON, YAML, Markdown, a licence text, numbers under an extension no
command reads) gets a short answer saying what it is. A capture is read through :mod:`rotacal.io`
(the readers every command uses, so inspect sees exactly what an analysis would) with NaN and inf
kept so they can be counted; large files stream in chunks, so memory stays flat. A column that
cannot be read as numbers (a text label column) is named and the others are still inspected; a
damaged file is refused with one line, as by every command.
"""

from __future__ import annotations

import gzip
import json
import os
import re
from collections.abc import Iterable, Mapping
from pathlib import Path

from rotacal.errors import CaptureError
from rotacal.io import ReadOptions, iter_capture_chunks, read_capture
from rotacal.io._common import DAMAGED_FIX, format_of, known_extensions, sniff
from rotacal.io.capture import MappingArg, _close, _declared, _normalise_mapping, _open_reader
from rotacal.io.capture import _resolve as _resolve_names

from .core import Inspector
from .result import InspectResult

#: Rows per chunk when streaming a capture (bounded memory for any length).
CHUNK_ROWS = 1 << 18
#: Bytes looked at to tell what a file is.
_HEAD_BYTES = 1 << 16
_NUMBER = re.compile(r"^[+-]?(\d+([.,]\d*)?|[.,]\d+)([eE][+-]?\d+)?$|^[+-]?(nan|inf)$", re.I)
_CELL_SPLIT = re.compile(r"[,;\t ]+")
_TEXT_KINDS = {
    ".json": ("json", "a JSON document"),
    ".md": ("markdown", "a Markdown text"),
    ".yaml": ("yaml", "a YAML document"),
    ".yml": ("yaml", "a YAML document"),
}
_NO_FIT = "no analysis command reads it"


def _head(path: Path) -> bytes:
    """The first bytes of a file (decompressed for ``.gz``; raw when that fails)."""
    with open(path, "rb") as fh:
        raw = fh.read(_HEAD_BYTES)
    if path.suffix.lower() == ".gz" and raw[:2] == b"\x1f\x8b":
        try:
            with gzip.open(path, "rb") as fh:
                return fh.read(_HEAD_BYTES)
        except (OSError, EOFError):
            return raw
    return raw


def _looks_like_table(head: bytes, complete: bool) -> bool:
    """Whether text holds rows of numbers: at least half of its lines that are not comments
    (``#``/``%``) or blank hold mostly numbers (a header line and a label column allowed)."""
    text = head.decode("utf-8", "replace")
    lines = text.splitlines()
    if not complete and len(lines) > 1:
        lines = lines[:-1]  # cut off by the head's end
    content = [s.strip() for s in lines if s.strip() and s.strip()[0] not in "#%"]
    if not content:
        return False
    numeric = 0
    for line in content:
        cells = [c for c in _CELL_SPLIT.split(line) if c]
        if cells and 2 * sum(1 for c in cells if _NUMBER.match(c)) >= len(cells):
            numeric += 1
    return numeric > 0 and 2 * numeric >= len(content)


def _capture_format(path: Path) -> str | None:
    """The capture format the file's extension names, or None when no command reads it."""
    try:
        return format_of(path)
    except CaptureError:
        return None


def _not_a_capture(path: Path, kind: str, what: str) -> InspectResult:
    return InspectResult(path=str(path), kind=kind, description=f"{path.name} is {what}")


def _classify(path: Path) -> InspectResult | None:
    """The answer for a file that is not a capture, or None for one to read as a capture."""
    if not path.exists():
        raise CaptureError(f"file {str(path)!r} does not exist; check the path")
    if path.is_dir():
        raise CaptureError(f"{path.name} is a directory, not a file; give a file inside it")
    try:
        head = _head(path)
        size = path.stat().st_size
    except OSError as exc:
        raise CaptureError(
            f"{path.name} cannot be read ({exc.strerror or exc}); check the file"
        ) from None
    if not head:
        return _not_a_capture(path, "empty", f"empty: it holds no data; {_NO_FIT}")
    fmt = _capture_format(path)
    kind = sniff(head[:4096])
    text = kind == "csv"
    if fmt is not None and (fmt != "csv" or not text):
        return None  # a binary capture, or text under a binary extension: the reader judges
    suffix = path.suffix.lower()
    if fmt is None and suffix in _TEXT_KINDS and text:
        kind_name, what = _TEXT_KINDS[suffix]
        if kind_name != "json" or _parses_as_json(path, size):
            return _not_a_capture(path, kind_name, f"{what}, not a capture; {_NO_FIT}")
    if text and _looks_like_table(head, complete=size <= len(head)):
        if fmt is not None:
            return None
        return _not_a_capture(
            path,
            "text-table",
            f"a table of numbers as text, but no command reads a {path.suffix or 'bare'} file "
            f"(they read {known_extensions()}): copy it under a .txt name to analyse it",
        )
    if text:
        return _not_a_capture(path, "text", f"text, not a table of numbers; {_NO_FIT}")
    return _not_a_capture(path, "binary", f"binary data, not a capture rotacal reads; {_NO_FIT}")


def _parses_as_json(path: Path, size: int) -> bool:
    if size > 64 * _HEAD_BYTES:
        return True  # too long to parse for a first look; the extension says it
    try:
        json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return False
    return True


def _article(label: str) -> str:
    """ "a" or "an" before a format's letters as they are spoken (an NPZ, an HDF5, a CSV)."""
    return "an" if label[0] in "AEFHILMNORSX" else "a"


def _how_parsed(reader: object) -> str:
    """How a text capture was parsed ("tab separated, no header row"); "" for other formats."""
    layout = getattr(reader, "layout", None)
    return layout.description if layout is not None else ""


def _layout(
    path: Path, mapping: dict[str, str], group: str | None, options: ReadOptions | None
) -> tuple[list[str], dict[str, int | None], str, dict[str, object], dict[str, str], str]:
    """Column names (after mapping), their declared lengths, the format, the metadata, the
    columns the reader left out as text (labels) and how a text file was parsed — from the
    file's head, without its data."""
    reader = _open_reader(path, group, options)
    try:
        names, wanted = _resolve_names(reader, mapping, None)
        lengths = _declared(reader, wanted)
        # a text reader that recognises label columns leaves them out of its names
        labels = getattr(reader, "text_columns", None) or {}
        text = {
            name: f"column {name!r} holds text ({where}), not numbers"
            for name, where in labels.items()
        }
        return names, lengths, reader.label, dict(reader.metadata), text, _how_parsed(reader)
    finally:
        _close(reader)


def _feed(
    inspector: Inspector,
    path: Path,
    names: list[str],
    ragged: bool,
    **read: object,
) -> None:
    """Feed columns to the inspector: streamed in chunks, or whole when their lengths differ
    (a text capture that fails to stream, e.g. with empty cells, is read whole, padded)."""
    for name in names:
        inspector.reset(name)
    if not ragged:
        try:
            for chunk in iter_capture_chunks(
                path,
                names,
                chunk_rows=CHUNK_ROWS,
                allow_nonfinite=True,
                **read,  # type: ignore[arg-type]
            ):
                inspector.add(chunk)
            return
        except CaptureError:
            if read.get("group") is not None or format_of(path) != "csv":
                raise
            for name in names:
                inspector.reset(name)
    cap = read_capture(path, columns=names, ragged=True, allow_nonfinite=True, **read)  # type: ignore[arg-type]
    inspector.add(cap.columns)


def inspect_capture(
    path: str | os.PathLike[str],
    *,
    mapping: MappingArg = None,
    group: str | None = None,
    read_options: ReadOptions | None = None,
    time_column: str = "time_s",
) -> InspectResult:
    """A first look at a file: what it is, and for a capture its columns, sampling and fits.

    Parameters
    ----------
    path : str or path-like — any file; captures are read as every command reads them.
    mapping : mapping or iterable of "OLD=NEW", optional — as ``--column``.
    group : str, optional — HDF5 or TDMS group holding the columns.
    read_options : ReadOptions, optional — delimiter, decimal mark, names of a text capture.
    time_column : str — the column holding time in s (after mapping).

    Returns
    -------
    InspectResult
        ``kind`` says what the file is; for a capture (``"capture"``) the columns, the
        sampling of the time column, the commands that fit and warnings.

    Raises
    ------
    CaptureError
        A missing file, a damaged capture, a capture none of whose columns holds numbers.
    ConfigError
        A bad ``mapping``, ``group`` or read option.
    """
    p = Path(path)
    answer = _classify(p)
    if answer is not None:
        return answer
    mapped = _normalise_mapping(mapping)
    names, lengths, label, metadata, text, parsed = _layout(p, mapped, group, read_options)
    if not names:  # e.g. only labels, complex or object arrays, numbers with thousands marks
        skipped = f" ({'; '.join(text.values())})" if text else ""
        what = f"text ({parsed})" if parsed else label
        return _not_a_capture(
            p,
            "no-numbers",
            f"{_article(what)} {what} file without a column of numbers{skipped}; {_NO_FIT}",
        )
    known = [n for n in lengths.values() if n is not None]
    ragged = len(known) == len(lengths) and len(set(known)) > 1
    read = {"mapping": mapped, "group": group, "read_options": read_options}
    inspector = Inspector(names, time_column)
    unreadable: dict[str, str] = {}
    try:
        _feed(inspector, p, names, ragged, **read)
    except CaptureError as whole:
        if DAMAGED_FIX in str(whole) or len(names) == 1:
            raise
        unreadable = _feed_one_by_one(inspector, p, names, ragged, read)
        if len(unreadable) == len(names):
            raise whole from None
    count = len(names) + len(text)
    return inspector.result(
        str(path),
        description=(
            f"{p.name} is a text capture ({parsed}) of {count} column(s)"
            if parsed
            else f"{p.name} is {_article(label)} {label} capture of {count} column(s)"
        ),
        format=label,
        unreadable={**text, **unreadable},
        metadata=metadata,
    )


def _feed_one_by_one(
    inspector: Inspector,
    path: Path,
    names: Iterable[str],
    ragged: bool,
    read: Mapping[str, object],
) -> dict[str, str]:
    """Feed each column alone; return the reasons of those that cannot be read as numbers.
    A damaged file is refused as a whole."""
    unreadable: dict[str, str] = {}
    for name in names:
        try:
            _feed(inspector, path, [name], ragged, **read)
        except CaptureError as exc:
            if DAMAGED_FIX in str(exc):
                raise
            inspector.drop(name)
            unreadable[name] = " ".join(str(exc).split())
    return unreadable
