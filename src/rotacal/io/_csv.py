"""CSV captures: one header row of names, comma separated, '#' comment lines allowed.

Numbers are parsed by NumPy's C reader (``np.loadtxt``); Python only looks at the file line by
line on the error path, to name the line and column at fault.
"""

from __future__ import annotations

import codecs
import itertools
import json
import math
import warnings
from collections.abc import Iterable, Iterator, Mapping
from pathlib import Path
from typing import Any

import numpy as np

from rotacal.errors import CaptureError, ConfigError

from ._common import reason
from ._validate import RAGGED_USE, ColumnInfo

ENCODING = "utf-8-sig"
#: rows formatted per piece when writing (bounded memory)
_WRITE_ROWS = 100_000


_NOT_DATA = "#\r\n"  # first characters of lines np.loadtxt skips (comment, empty line)


def _content(line: str) -> str:
    """What np.loadtxt(comments='#') sees of a line: newline and comment removed."""
    return line.rstrip("\r\n").split("#", 1)[0]


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def _empty_to_nan(cell: str) -> float:
    return float(cell) if cell.strip() else math.nan


def _first_bad_utf8(path: Path) -> tuple[int, int, int]:
    """(line, byte offset, byte value) of the first byte of ``path`` that is not UTF-8."""
    line, offset, tail = 1, 0, b""
    with open(path, "rb") as fh:
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


class CsvReader:
    """Reader of one CSV capture (header parsed on construction): text in, float64 columns out.

    What is a parse question stays here (cells per row, cells that are not numbers, text that
    is not UTF-8, naming the line); every check of the values is in ``_validate``.
    """

    label = "CSV"
    noun = "column"

    def __init__(self, path: Path) -> None:
        self.path = path
        self.fname = path.name
        self.metadata: dict[str, Any] = {}
        self.header_lines = 0  # lines up to and including the header (np.loadtxt skiprows)
        self.first_row_cells: int | None = None
        self.first_row_line = 0
        try:
            with open(path, encoding=ENCODING, newline=None) as fh:
                self._parse_head(fh)
        except UnicodeDecodeError:
            raise self._not_utf8() from None

    def _not_utf8(self) -> CaptureError:
        line, offset, value = _first_bad_utf8(self.path)
        return CaptureError(
            f"{self.fname} line {line} is not UTF-8 text (byte 0x{value:02x} at byte {offset}); "
            "save the file as UTF-8 CSV"
        )

    def _lines(self, skip: int) -> Iterator[str]:
        """The file's text lines after the first ``skip``; bytes that are not UTF-8 are named."""
        try:
            with open(self.path, encoding=ENCODING) as fh:
                yield from itertools.islice(fh, skip, None)
        except UnicodeDecodeError:
            raise self._not_utf8() from None

    def _parse_head(self, fh: Iterable[str]) -> None:
        header: str | None = None
        for lineno, line in enumerate(fh, start=1):
            if header is None:
                stripped = line.strip()
                if not stripped:
                    continue
                if stripped.startswith("#"):
                    self._comment(stripped)
                    continue
                header = _content(stripped).strip()
                self.header_lines = lineno
                continue
            content = _content(line)
            if content:
                self.first_row_cells = len(content.split(","))
                self.first_row_line = lineno
                break
        if header is None:
            raise CaptureError(
                f"{self.fname} has no header row (it holds only comments or blank lines); "
                "give a CSV with a line of column names and data rows"
            )
        names = [c.strip().strip('"').strip() for c in header.split(",")]
        if all(_is_number(c) for c in names):
            raise CaptureError(
                f"{self.fname} has no header row: its first line {header[:60]!r} holds numbers; "
                "add a line of column names such as 'time_s,a,b' above the data"
            )
        if len(names) == 1 and any(sep in header for sep in ";\t "):
            raise CaptureError(
                f"{self.fname} header {header[:60]!r} has no commas; rotacal reads "
                "comma-separated files — save it with ',' between columns"
            )
        self.names = names
        if self.first_row_cells is not None and self.first_row_cells != len(names):
            raise CaptureError(
                f"{self.fname} line {self.first_row_line} has {self.first_row_cells} cells but "
                f"the header names {len(names)} columns; make every row match the header"
            )

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
        """A CSV declares no type and no length: both come from reading."""
        return ColumnInfo(self.noun)

    def row_count(self, name: str) -> int:
        """Number of data rows (every column's length in a file without padding)."""
        if self.first_row_cells is None:
            return 0
        skip = set(_NOT_DATA.encode())
        with open(self.path, "rb") as fh:
            lines = itertools.islice(fh, self.header_lines, None)
            return sum(1 for line in lines if line[0] not in skip)

    # --- reading -------------------------------------------------------------------------------

    def _no_data(self) -> CaptureError:
        return CaptureError(
            f"{self.fname} has a header but no data rows; give a capture with data in it"
        )

    def read(self, names: list[str], ragged: bool) -> dict[str, np.ndarray]:
        if self.first_row_cells is None:
            raise self._no_data()
        idx = [self.names.index(n) for n in names]
        self._check_cell_counts(idx, ragged)
        kw: dict[str, Any] = {"converters": _empty_to_nan} if ragged else {}
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", UserWarning)
                data = np.loadtxt(
                    self.path,
                    dtype=np.float64,
                    delimiter=",",
                    comments="#",
                    skiprows=self.header_lines,
                    usecols=idx,
                    ndmin=2,
                    encoding=ENCODING,
                    **kw,
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

    def chunks(self, names: list[str], chunk_rows: int) -> Iterator[dict[str, np.ndarray]]:
        idx = [self.names.index(n) for n in names]
        lines = self._lines(self.header_lines)
        lineno = self.header_lines + 1
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
            commas = len(self.names) - 1
            if any(x.count(",") != commas for x in pending if x[0] not in _NOT_DATA):
                self._diagnose(pending, lineno, idx, ragged=False)
            try:
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore", UserWarning)
                    data = np.loadtxt(
                        pending,
                        dtype=np.float64,
                        delimiter=",",
                        comments="#",
                        usecols=idx,
                        ndmin=2,
                    )
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
        of commas and newlines over the raw bytes; the slow line-by-line diagnosis runs only when
        the counts disagree (it also forgives blank and comment lines)."""
        with open(self.path, "rb") as fh:
            for _ in range(self.header_lines):
                fh.readline()
            offset = fh.tell()
            fh.seek(0, 2)
            size = fh.tell()
        if size <= offset:
            return
        raw = np.memmap(self.path, dtype=np.uint8, mode="r", offset=offset)
        commas = int(np.count_nonzero(raw == ord(",")))
        rows = int(np.count_nonzero(raw == ord("\n"))) + int(raw[-1] != ord("\n"))
        del raw
        if commas != (len(self.names) - 1) * rows:
            self._diagnose(self._lines(self.header_lines), self.header_lines + 1, idx, ragged)

    # --- messages ------------------------------------------------------------------------------

    def _diagnose(self, lines: Iterable[str], lineno: int, idx: list[int], ragged: bool) -> None:
        """Find the first cell np.loadtxt rejected and raise a CaptureError naming it."""
        ncols = len(self.names)
        for ln, line in enumerate(lines, start=lineno):
            content = _content(line)
            if not content:
                continue
            if not content.strip():
                raise CaptureError(
                    f"{self.fname} line {ln} holds only spaces; delete it or make it a data row"
                )
            cells = content.split(",")
            if len(cells) != ncols:
                raise CaptureError(
                    f"{self.fname} line {ln} has {len(cells)} cells but the header names "
                    f"{ncols} columns; make every row match the header (pad with empty cells)"
                )
            for i in idx:
                cell = cells[i].strip()
                col = self.names[i]
                if not cell:
                    if ragged:
                        continue
                    raise CaptureError(
                        f"{self.fname} line {ln}, column {col!r} is empty; fill it ({RAGGED_USE} "
                        "leave trailing cells empty)"
                    )
                if not _is_number(cell):
                    raise CaptureError(
                        f"{self.fname} line {ln}, column {col!r}: {cell[:40]!r} is not a number; "
                        "fix or remove that row"
                    )

    def locate(self, index: int) -> str:
        """File line of data row ``index`` (0-based), for messages (scans the file)."""
        k = -1
        for ln, line in enumerate(self._lines(self.header_lines), start=self.header_lines + 1):
            if not _content(line):
                continue
            k += 1
            if k == index:
                return f"line {ln} (data row {index + 1})"
        return f"data row {index + 1}"

    def integrity(self, name: str) -> None:
        return None  # a CSV stores no checksums

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
