"""The layout of a text capture: cell separator, decimal mark, header row or given names.

Labs' data-acquisition programs write comma-, semicolon-, tab- or blank-separated text, with a
decimal point or a decimal comma, with a header row or none. :func:`sniff_layout` decides from
the first lines of the file (Python looks at those few lines only; the numbers are parsed later
by NumPy's C reader) and :class:`TextLayout` says how to parse the rest.

Sniffing order (the first that fits wins): a given ``--delimiter``/``--decimal`` restricts the
candidates; then tab, ``;``, ``,``, blanks with the decimal point, then tab, ``;``, blanks with the
decimal comma. A candidate fits when every sampled row splits into the same number of cells (the
header, when there is one, too) and every data cell is a number. A file with one cell per row is
one column, read as blank-separated; its decimal comma is not sniffed (rows "1,5" fit two
comma-separated columns as well): that takes ``--decimal ,``, and a headerless file whose every
sampled row is such a pair is refused until ``--decimal ,`` or ``--delimiter ,`` says which. When no candidate fits, the
separator that splits the first row into the most cells is kept, so that the reader names the row
and cell at fault.
"""

from __future__ import annotations

import dataclasses
import re
from collections.abc import Sequence

from rotacal.errors import CaptureError, ConfigError

from .read_options import ReadOptions

#: data rows looked at to sniff the layout
SNIFF_ROWS = 20
_POINT_ORDER = ("\t", ";", ",", " ")
_COMMA_ORDER = ("\t", ";", " ")
_SEPARATOR_NAME = {",": "','", ";": "';'", "\t": "tab", " ": "blanks"}


def separator_name(delimiter: str) -> str:
    """How a separator is named in a message."""
    return _SEPARATOR_NAME[delimiter]


def split_cells(content: str, delimiter: str) -> list[str]:
    """The cells of one row (comment and newline removed): blanks split on any run of them."""
    return content.split() if delimiter == " " else content.split(delimiter)


def is_number(text: str, decimal: str = ".") -> bool:
    """Whether a cell parses as a float (with ``decimal`` as decimal mark)."""
    if decimal == ",":
        if "." in text:
            return False
        text = text.replace(",", ".")
    try:
        float(text)
    except ValueError:
        return False
    return True


@dataclasses.dataclass(frozen=True)
class TextLayout:
    """How the rows of a text capture are parsed.

    Attributes
    ----------
    delimiter : str
        ``","``, ``";"``, ``"\\t"`` or ``" "`` (any run of blanks; also a file of one column).
    decimal : str
        ``"."`` or ``","``.
    names : list of str
        Column names in file order (the header's, the given ``--names``, or ``col_1`` …).
    has_header : bool
        The first non-comment row is a header (skipped when parsing).
    decimal_sniffed : bool
        The decimal comma was recognised rather than given.
    """

    delimiter: str
    decimal: str
    names: list[str]
    has_header: bool
    decimal_sniffed: bool = False

    @property
    def description(self) -> str:
        """The layout in words, e.g. "tab separated, decimal comma, no header row"."""
        separator = {",": "comma", ";": "semicolon", "\t": "tab", " ": "blank"}[self.delimiter]
        parts = [f"{separator} separated"]
        if self.decimal == ",":
            parts.append("decimal comma")
        parts.append("header row" if self.has_header else "no header row")
        return ", ".join(parts)

    @property
    def numpy_delimiter(self) -> str | None:
        """The ``delimiter`` argument of ``np.loadtxt`` (None: runs of blanks)."""
        return None if self.delimiter == " " else self.delimiter


def _fits(
    rows: Sequence[str], delimiter: str, decimal: str, header: bool, options: ReadOptions
) -> bool:
    counts = {len(split_cells(r, delimiter)) for r in rows}
    if len(counts) != 1:
        return False
    # One cell per row is one column, read as blank-separated; its decimal comma is not sniffed
    # ("1,5" could as well be two columns with a cell missing): it takes --decimal ,.
    if counts == {1} and (delimiter != " " or decimal != options.decimal):
        return False
    data = rows[1:] if header else rows
    return all(is_number(c.strip(), decimal) for r in data for c in split_cells(r, delimiter))


def _candidates(options: ReadOptions) -> list[tuple[str, str]]:
    point = [(d, ".") for d in _POINT_ORDER]
    comma = [(d, ",") for d in _COMMA_ORDER]
    pairs = comma if options.decimal == "," else point + comma
    if options.delimiter is not None:
        pairs = [(d, m) for d, m in pairs if d == options.delimiter]
    return pairs


def _first_row_is_header(first: str, delimiter: str, decimal: str) -> bool:
    return not all(is_number(c.strip(), decimal) for c in split_cells(first, delimiter))


_WHOLE = re.compile(r"[+-]?\d+")
_DIGITS = re.compile(r"\d+")


def _check_comma_ambiguity(fname: str, rows: Sequence[str], options: ReadOptions) -> None:
    """Refuse headerless rows like "0,2945" that read either as one column with a decimal comma or
    as two columns of whole numbers: guessing wrong would silently give other numbers."""
    if options.delimiter is not None:
        return
    for row in rows:
        cells = [c.strip() for c in row.split(",")]
        if len(cells) != 2 or not _WHOLE.fullmatch(cells[0]) or not _DIGITS.fullmatch(cells[1]):
            return
    raise ConfigError(
        f"{fname}: rows like {rows[0].strip()!r} read as one column with a decimal comma or as "
        "two columns of whole numbers; give --decimal , (one column) or --delimiter , (two "
        "columns)"
    )


def sniff_layout(fname: str, rows: Sequence[str], options: ReadOptions) -> TextLayout:
    """Decide the layout from the first non-comment rows (comments and newlines removed).

    ``rows[0]`` is the first non-comment row (a header or data), the rest up to
    :data:`SNIFF_ROWS` data rows.

    Raises
    ------
    ConfigError
        ``--names`` given for a file with a header row, or with a count of names other than the
        file's count of columns.
    """
    chosen: tuple[str, str] | None = None
    header = False
    for delimiter, decimal in _candidates(options):
        header = _first_row_is_header(rows[0], delimiter, decimal)
        if _fits(rows, delimiter, decimal, header, options):
            chosen = (delimiter, decimal)
            break
    if chosen is None:
        delimiter = options.delimiter or max(
            _POINT_ORDER, key=lambda d: len(split_cells(rows[0], d))
        )
        decimal = options.decimal
        header = _first_row_is_header(rows[0], delimiter, decimal)
        chosen = (delimiter, decimal)
    delimiter, decimal = chosen
    if (delimiter, decimal, header) == (",", ".", False):
        _check_comma_ambiguity(fname, rows, options)
    cells = [c.strip().strip('"').strip() for c in split_cells(rows[0], delimiter)]
    if options.delimiter is not None and len(cells) == 1:
        other = max(_POINT_ORDER, key=lambda d: len(split_cells(rows[0], d)))
        if len(split_cells(rows[0], other)) > 1:
            raise ConfigError(
                f"--delimiter {separator_name(delimiter)} does not separate the cells of {fname}: "
                f"its first row {rows[0][:50]!r} is split by {separator_name(other)}; give that, "
                "or leave --delimiter out"
            )
    if options.names is not None:
        if header:
            raise ConfigError(
                f"--names is for a file without a header row, but {fname} starts with one "
                f"({', '.join(cells[:6])}{' …' if len(cells) > 6 else ''}); leave --names out "
                "and rename columns with --column OLD=NEW"
            )
        if len(options.names) != len(cells):
            raise ConfigError(
                f"--names gives {len(options.names)} names but {fname} has {len(cells)} columns "
                f"(separated by {separator_name(delimiter)}); give {len(cells)} names"
            )
        names = list(options.names)
    elif header:
        names = cells
    else:
        names = [f"col_{k}" for k in range(1, len(cells) + 1)]
    return TextLayout(
        delimiter=delimiter,
        decimal=decimal,
        names=names,
        has_header=header,
        decimal_sniffed=decimal != options.decimal,
    )


def no_rows(fname: str) -> CaptureError:
    return CaptureError(
        f"{fname} holds only comments or blank lines; give a capture with data rows (and a "
        "header row of column names, or --names)"
    )
