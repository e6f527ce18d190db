"""Text captures: CSV and the tab-, semicolon- or blank-separated files labs' DAQs write.

The layout (separator, decimal mark, header row or names) is sniffed from the first rows
(:mod:`._text_layout`); ``name.csv.gz`` and the like are read through gzip. Numbers are parsed by
NumPy's C reader (``np.loadtxt``); Python only looks at the file line by line on the error path,
to name the line and column at fault. A decimal comma is turned into a point block-wise (C string
methods) before the same reader sees the rows.
"""

from __future__ import annotations

import codecs
import gzip
import itertools
import json
import math
import warnings
from collections.abc import Iterable, Iterator, Mapping
from pathlib import Path
from typing import IO, Any

import numpy as np

from rotacal.errors import CaptureError, ConfigError

from ._common import BLOCK, is_gzip, reason
from ._text_layout import SNIFF_ROWS, TextLayout, is_number, no_rows, sniff_layout, split_cells
from ._validate import RAGGED_USE, ColumnInfo
from .read_options import ReadOptions

ENCODING = "utf-8-sig"
#: rows formatted per piece when writing (bounded memory)
_WRITE_ROWS = 100_000
#: characters of text turned from decimal comma to point at once
_TEXT_BLOCK = 1 << 23
#: bytes up to the space are blanks (tab, CR, LF, space …; as str.split() sees them): the cells
#: of a blank-separated row are the runs of other bytes
_BLANK_MAX = ord(" ")


_NOT_DATA = "#\r\n"  # first characters of lines np.loadtxt skips (comment, empty line)


def _content(line: str) -> str:
    """What np.loadtxt(comments='#') sees of a line: newline and comment removed."""
    return line.rstrip("\r\n").split("#", 1)[0]


def _empty_to_nan(cell: str) -> float:
    return float(cell) if cell.strip() else math.nan


def _open_bytes(path: Path) -> IO[bytes]:
    if is_gzip(path):
        return gzip.open(path, "rb")  # type: ignore[return-value]  # a GzipFile is IO[bytes]
    return open(path, "rb")


def _first_bad_utf8(path: Path) -> tuple[int, int, int]:
    """(line, byte offset, byte value) of the first byte of ``path`` that is not UTF-8."""
    line, offset, tail = 1, 0, b""
    with _open_bytes(path) as fh:
        while True:
            block = fh.read(1 << 20)
            data = tail + block
            try:
                _text, used = codecs.utf_8_decode(data, "strict", not block)
            except UnicodeDecodeError as exc:
                return line + data.count(b"\n", 0, exc.start), offset + exc.start, data[exc.start]
            line += data.count(b"\n", 0, used)
            offset += used
            tail = data[used:]
            if not block:
                return line, offset, 0


def _blocks_after(path: Path, skip_lines: int) -> Iterator[np.ndarray]:
    """The bytes after the first ``skip_lines`` lines, as uint8 blocks (memory-mapped when the
    file is not compressed)."""
    with _open_bytes(path) as fh:
        for _ in range(skip_lines):
            fh.readline()
        offset = fh.tell()
        if is_gzip(path):
            while block := fh.read(BLOCK * 16):
                yield np.frombuffer(block, dtype=np.uint8)
            return
        fh.seek(0, 2)
        size = fh.tell()
    if size <= offset:
        return
    raw = np.memmap(path, dtype=np.uint8, mode="r", offset=offset)
    for lo in range(0, raw.shape[0], BLOCK * 16):
        yield raw[lo : lo + BLOCK * 16]
    del raw


class CsvReader:
    """Reader of one text capture (layout sniffed on construction): text in, float64 columns out.

    What is a parse question stays here (cells per row, cells that are not numbers, text that
    is not UTF-8, naming the line); every check of the values is in ``_validate``.
    """

    label = "CSV"
    noun = "column"

    def __init__(self, path: Path, options: ReadOptions | None = None) -> None:
        self.path = path
        self.fname = path.name
        self.options = options or ReadOptions()
        self.metadata: dict[str, Any] = {}
        self.header_lines = 0  # lines before the first data row (np.loadtxt skiprows)
        self.first_row_cells: int | None = None
        self.first_row_line = 0
        try:
            with self._open_text() as fh:
                self._parse_head(fh)
        except UnicodeDecodeError:
            raise self._not_utf8() from None

    def _open_text(self) -> IO[str]:
        if is_gzip(self.path):
            return gzip.open(self.path, "rt", encoding=ENCODING)
        return open(self.path, encoding=ENCODING)

    def _not_utf8(self) -> CaptureError:
        line, offset, value = _first_bad_utf8(self.path)
        return CaptureError(
            f"{self.fname} line {line} is not UTF-8 text (byte 0x{value:02x} at byte {offset}); "
            "save the file as UTF-8 text"
        )

    def _lines(self, skip: int) -> Iterator[str]:
        """The file's text lines after the first ``skip``; bytes that are not UTF-8 are named."""
        try:
            with self._open_text() as fh:
                yield from itertools.islice(fh, skip, None)
        except UnicodeDecodeError:
            raise self._not_utf8() from None

    def _parse_head(self, fh: Iterable[str]) -> None:
        rows: list[str] = []
        lines: list[int] = []
        for lineno, line in enumerate(fh, start=1):
            if not rows:
                stripped = line.strip()
                if not stripped:
                    continue
                if stripped.startswith("#"):
                    self._comment(stripped)
                    continue
            content = _content(line)
            if content.strip():
                rows.append(content.strip() if not rows else content)
                lines.append(lineno)
                if len(rows) > SNIFF_ROWS:
                    break
        if not rows:
            raise no_rows(self.fname)
        self.layout: TextLayout = sniff_layout(self.fname, rows, self.options)
        self.names = self.layout.names
        first = 1 if self.layout.has_header else 0
        self.header_lines = lines[0] if self.layout.has_header else lines[0] - 1
        if len(rows) > first:
            self.first_row_cells = len(split_cells(rows[first], self.layout.delimiter))
            self.first_row_line = lines[first]
        if self.first_row_cells is not None and self.first_row_cells != len(self.names):
            raise CaptureError(
                f"{self.fname} line {self.first_row_line} has {self.first_row_cells} cells but "
                f"the header names {len(self.names)} columns; make every row match the header"
            )
        self._find_text_columns(rows[first:], lines[first:])

    def _find_text_columns(self, rows: list[str], lines: list[int]) -> None:
        """Columns whose sampled cells are all words (labels such as a section's name) are not
        offered as columns of numbers, so that reading every column works; asked for by name,
        they are named as text (:meth:`normalise`)."""
        self.text_columns: dict[str, str] = {}
        split = [split_cells(r, self.layout.delimiter) for r in rows]
        if not split or any(len(cells) != len(self.names) for cells in split):
            return
        for i, name in enumerate(self.names):
            cells = [c[i].strip() for c in split]
            if all(c and not is_number(c, self.layout.decimal) for c in cells):
                self.text_columns[name] = f"{cells[0][:30]!r} on line {lines[0]}"
        self.names = [n for n in self.names if n not in self.text_columns]

    def normalise(self, name: str) -> str:
        """A column asked for by name; a column of text is refused naming what it holds."""
        if name in self.text_columns:
            raise CaptureError(
                f"{self.fname} column {name!r} holds text ({self.text_columns[name]}), not "
                "numbers; name a column of numbers"
            )
        return name

    def _comment(self, stripped: str) -> None:
        """'# key: value' comment lines carry metadata (value JSON where it parses)."""
        body = stripped.lstrip("#").strip()
        key, sep, value = body.partition(":")
        key = key.strip()
        if not sep or not key or " " in key:
            return
        value = value.strip()
        try:
            self.metadata[key] = json.loads(value)
        except ValueError:
            self.metadata[key] = value

    # --- declarations --------------------------------------------------------------------------

    def describe(self, name: str) -> ColumnInfo:
        """A text capture declares no type and no length: both come from reading."""
        return ColumnInfo(self.noun)

    def row_count(self, name: str) -> int:
        """Number of data rows (every column's length in a file without padding)."""
        if self.first_row_cells is None:
            return 0
        skip = set(_NOT_DATA.encode())
        with _open_bytes(self.path) as fh:
            lines = itertools.islice(fh, self.header_lines, None)
            return sum(1 for line in lines if line[0] not in skip and line.strip())

    # --- reading -------------------------------------------------------------------------------

    def _no_data(self) -> CaptureError:
        return CaptureError(
            f"{self.fname} has a header but no data rows; give a capture with data in it"
        )

    def _loadtxt(self, source: Any, idx: list[int], **kw: Any) -> np.ndarray:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", UserWarning)
            return np.loadtxt(
                source,
                dtype=np.float64,
                delimiter=self.layout.numpy_delimiter,
                comments="#",
                usecols=idx,
                ndmin=2,
                **kw,
            )

    def _comma_decimal_rows(self) -> Iterator[list[str]]:
        """The data rows in blocks, each decimal comma turned into a point."""
        try:
            with self._open_text() as fh:
                for _ in range(self.header_lines):
                    fh.readline()
                tail = ""
                while block := fh.read(_TEXT_BLOCK):
                    text = tail + block
                    cut = text.rfind("\n") + 1
                    tail = text[cut:]
                    if cut:
                        yield text[:cut].replace(",", ".").splitlines()
                if tail:
                    yield [tail.replace(",", ".")]
        except UnicodeDecodeError:
            raise self._not_utf8() from None

    def read(self, names: list[str], ragged: bool) -> dict[str, np.ndarray]:
        if self.first_row_cells is None:
            raise self._no_data()
        idx = [self.layout.names.index(n) for n in names]
        self._check_cell_counts(idx, ragged)
        kw: dict[str, Any] = {"converters": _empty_to_nan} if ragged else {}
        try:
            if self.layout.decimal == ",":
                pieces = [self._loadtxt(rows, idx, **kw) for rows in self._comma_decimal_rows()]
                pieces = [p for p in pieces if p.shape[0]]
                data = np.concatenate(pieces) if pieces else np.empty((0, len(idx)))
            else:
                data = self._loadtxt(
                    str(self.path), idx, skiprows=self.header_lines, encoding=ENCODING, **kw
                )
        except ValueError as exc:
            if isinstance(exc, UnicodeDecodeError):
                raise self._not_utf8() from None
            self._diagnose(self._lines(self.header_lines), self.header_lines + 1, idx, ragged)
            raise CaptureError(
                f"{self.fname} could not be parsed as numbers ({reason(exc)}); check its data rows"
            ) from None
        if data.shape[0] == 0:
            raise self._no_data()
        cols = np.ascontiguousarray(data.T)
        del data
        return {n: cols[k] for k, n in enumerate(names)}

    def _cells(self, line: str) -> int:
        d = self.layout.delimiter
        return len(line.split()) if d == " " else line.count(d) + 1

    def rows(self, names: list[str], start: int, stop: int) -> None:
        """None: text has no row offsets (a row range would read the file from its start)."""
        return None

    def chunks(self, names: list[str], chunk_rows: int) -> Iterator[dict[str, np.ndarray]]:
        idx = [self.layout.names.index(n) for n in names]
        lines = self._lines(self.header_lines)
        lineno = self.header_lines + 1
        ncols = len(self.layout.names)
        while True:
            # gather chunk_rows data rows (blank and comment lines do not count)
            pending: list[str] = []
            have = 0
            while have < chunk_rows:
                piece = list(itertools.islice(lines, chunk_rows - have))
                if not piece:
                    break
                pending.extend(piece)
                have += len(piece) - sum(1 for s in piece if s[0] in _NOT_DATA)
            if have == 0:
                return
            # np.loadtxt with usecols ignores extra cells: a shifted row would pass silently
            if any(self._cells(x) != ncols for x in pending if x[0] not in _NOT_DATA):
                self._diagnose(pending, lineno, idx, ragged=False)
            rows = pending
            if self.layout.decimal == ",":
                rows = "".join(pending).replace(",", ".").splitlines()
            try:
                data = self._loadtxt(rows, idx)
            except ValueError as exc:
                self._diagnose(pending, lineno, idx, ragged=False)
                raise CaptureError(
                    f"{self.fname} could not be parsed as numbers near line {lineno} "
                    f"({reason(exc)}); check its data rows"
                ) from None
            lineno += len(pending)
            cols = np.ascontiguousarray(data.T)
            yield {n: cols[k] for k, n in enumerate(names)}

    def _check_cell_counts(self, idx: list[int], ragged: bool) -> None:
        """Every data row must have as many cells as the header: np.loadtxt with usecols ignores
        extra cells, so a shifted or spliced row would otherwise be read silently. One cheap count
        of separators (or, for blank-separated rows, of cell starts) and newlines over the raw
        bytes; the slow line-by-line diagnosis runs only when the counts disagree (it also
        forgives blank and comment lines)."""
        ncols = len(self.layout.names)
        d = self.layout.delimiter
        cells = rows = 0
        last = ord("\n")
        blank_before = True
        for raw in _blocks_after(self.path, self.header_lines):
            if d == " ":
                filled = raw > _BLANK_MAX
                cells += int(np.count_nonzero(filled[1:] & ~filled[:-1]))
                cells += int(filled[0] and blank_before)
                blank_before = not filled[-1]
            else:
                cells += int(np.count_nonzero(raw == ord(d)))
            rows += int(np.count_nonzero(raw == ord("\n")))
            last = int(raw[-1])
        rows += int(last != ord("\n"))
        expected = ncols * rows if d == " " else (ncols - 1) * rows
        if cells != expected:
            self._diagnose(self._lines(self.header_lines), self.header_lines + 1, idx, ragged)

    # --- messages ------------------------------------------------------------------------------

    def _diagnose(self, lines: Iterable[str], lineno: int, idx: list[int], ragged: bool) -> None:
        """Find the first cell np.loadtxt rejected and raise a CaptureError naming it."""
        ncols = len(self.layout.names)
        d, decimal = self.layout.delimiter, self.layout.decimal
        against = "the header names" if self.layout.has_header else "the first row has"
        for ln, line in enumerate(lines, start=lineno):
            content = _content(line)
            if not content:
                continue
            if not content.strip():
                if d == " ":
                    continue  # np.loadtxt skips a line of blanks when blanks separate cells
                if line.strip().startswith("#"):
                    raise CaptureError(
                        f"{self.fname} line {ln} is a comment that does not start the line; "
                        "remove the blanks before its '#'"
                    )
                raise CaptureError(
                    f"{self.fname} line {ln} holds only spaces; delete it or make it a data row"
                )
            cells = split_cells(content, d)
            if len(cells) != ncols:
                pad = " (pad with empty cells)" if d != " " else ""
                raise CaptureError(
                    f"{self.fname} line {ln} has {len(cells)} cells but {against} "
                    f"{ncols} columns; make every row match the header{pad}"
                )
            for i in idx:
                cell = cells[i].strip()
                col = self.layout.names[i]
                if not cell:
                    if ragged:
                        continue
                    raise CaptureError(
                        f"{self.fname} line {ln}, column {col!r} is empty; fill it ({RAGGED_USE} "
                        "leave trailing cells empty)"
                    )
                if not is_number(cell, decimal):
                    hint = self._decimal_hint(cell)
                    raise CaptureError(
                        f"{self.fname} line {ln}, column {col!r}: {cell[:40]!r} is not a number; "
                        f"{hint or 'fix or remove that row'}"
                    )

    def _decimal_hint(self, cell: str) -> str:
        """What to do when a cell would be a number with the other decimal mark."""
        d, decimal = self.layout.delimiter, self.layout.decimal
        if decimal == "." and is_number(cell, ","):
            if d == ",":
                return "its numbers use a decimal comma, so give the cell separator, e.g. --delimiter ';'"
            return "its numbers use a decimal comma: give --decimal ,"
        if decimal == "," and is_number(cell, "."):
            return "its numbers use a decimal point: leave --decimal , out"
        return ""

    def locate(self, index: int) -> str:
        """File line of data row ``index`` (0-based), for messages (scans the file)."""
        k = -1
        for ln, line in enumerate(self._lines(self.header_lines), start=self.header_lines + 1):
            if not _content(line).strip():
                continue
            k += 1
            if k == index:
                return f"line {ln} (data row {index + 1})"
        return f"data row {index + 1}"

    def integrity(self, name: str) -> None:
        return None  # a text capture stores no checksums

    def close(self) -> None:
        return None


def _check_name(name: str) -> None:
    if not name.strip() or name != name.strip() or any(c in name for c in ',"#\r\n'):
        raise ConfigError(
            f"column name {name!r} cannot be written to CSV; use a name without commas, quotes, "
            "'#', line breaks or surrounding spaces"
        )


def write_csv(
    fh: Any, columns: Mapping[str, np.ndarray], metadata: Mapping[str, Any] | None
) -> None:
    """Write a CSV capture to the text file ``fh``: metadata comments, header, repr numbers.

    Shorter columns are padded with empty cells. Numbers are written with Python's ``repr``
    (shortest string that reads back bit-for-bit).
    """
    for name in columns:
        _check_name(name)
    for key, value in (metadata or {}).items():
        if not key or any(c in key for c in ": \r\n"):
            raise ConfigError(
                f"metadata key {key!r} cannot be written to CSV; use a key without spaces or ':'"
            )
        fh.write(f"# {key}: {json.dumps(value, default=str)}\n")
    fh.write(",".join(columns) + "\n")
    arrays = [np.asarray(a, dtype=np.float64) for a in columns.values()]
    n = max(a.shape[0] for a in arrays)
    for lo in range(0, n, _WRITE_ROWS):
        hi = min(n, lo + _WRITE_ROWS)
        cells = []
        for a in arrays:
            strs = list(map(repr, a[lo:hi].tolist()))
            if len(strs) < hi - lo:
                strs.extend([""] * (hi - lo - len(strs)))
            cells.append(strs)
        fh.write("\n".join(map(",".join, zip(*cells, strict=True))))
        fh.write("\n")
