"""How to read a text capture that is not a plain comma-separated file with a header row."""

from __future__ import annotations

import dataclasses

from rotacal.errors import ConfigError

#: the cell separators a text capture may use (" " stands for any run of blanks)
DELIMITERS = (",", ";", "\t", " ")
#: what ``--delimiter`` accepts, as typed at a command line -> the separator
DELIMITER_WORDS = {
    ",": ",",
    "comma": ",",
    ";": ";",
    "semicolon": ";",
    "\t": "\t",
    "\\t": "\t",
    "tab": "\t",
    " ": " ",
    "space": " ",
    "whitespace": " ",
}
DECIMALS = (".", ",")


def delimiter_from_word(word: str | None) -> str | None:
    """``--delimiter`` as typed (``tab``, ``\\t``, ``;`` …) -> the separator; None stays None."""
    if word is None:
        return None
    key = word if word in DELIMITER_WORDS else word.strip().lower()
    if key not in DELIMITER_WORDS:
        raise ConfigError(
            f"--delimiter {word!r} is not a cell separator rotacal knows; give one of "
            "',' ';' tab space (or leave it out: it is sniffed from the file)"
        )
    return DELIMITER_WORDS[key]


@dataclasses.dataclass(frozen=True)
class ReadOptions:
    """Reading options of a capture (the CLI's ``--delimiter``, ``--decimal``, ``--names``).

    Attributes
    ----------
    delimiter : str or None
        Cell separator of a text capture: ``","``, ``";"``, ``"\\t"`` or ``" "`` (any run of
        blanks). None: sniffed from the file among those four.
    decimal : str
        Decimal mark of a text capture: ``"."`` or ``","`` (then the delimiter cannot be ``,``).
        With ``"."`` a file separated by ``;``, tab or blanks whose numbers all use ``,`` is
        recognised as using the decimal comma.
    names : tuple of str or None
        Column names of a text capture without a header row, in file order. None: the file's
        first non-comment row is its header, unless it holds only numbers (then the columns are
        ``col_1`` … ``col_N``).

    Raises
    ------
    ConfigError
        On construction, for a separator or decimal mark not listed above, ``decimal=","`` with
        ``delimiter=","``, or names that are empty or repeated.
    """

    delimiter: str | None = None
    decimal: str = "."
    names: tuple[str, ...] | None = None

    def __post_init__(self) -> None:
        if self.delimiter is not None and self.delimiter not in DELIMITERS:
            raise ConfigError(
                f"--delimiter {self.delimiter!r} is not a cell separator rotacal knows; give one "
                "of ',' ';' tab space"
            )
        if self.decimal not in DECIMALS:
            raise ConfigError(f"--decimal {self.decimal!r} must be '.' or ','")
        if self.decimal == "," and self.delimiter == ",":
            raise ConfigError(
                "--decimal , cannot go with --delimiter , (a comma cannot both separate cells "
                "and mark decimals); give the file's separator, e.g. --delimiter ';'"
            )
        if self.names is not None:
            names = tuple(self.names)
            if not names or any(not isinstance(n, str) or not n.strip() for n in names):
                raise ConfigError(
                    f"--names {','.join(map(str, names))!r} has an empty name; give one name per "
                    "column, separated by commas, e.g. --names time_s,a,b"
                )
            repeated = sorted({n for n in names if names.count(n) > 1})
            if repeated:
                raise ConfigError(
                    f"--names gives {repeated[0]!r} more than once; give each column its own name"
                )

    @property
    def is_default(self) -> bool:
        return self == ReadOptions()
