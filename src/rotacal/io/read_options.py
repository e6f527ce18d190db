"""How to read a text capture that is not a plain comma-separated file with a header row."""

from __future__ import annotations

import dataclasses


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
    names : tuple of str or None
        Column names of a text capture without a header row, in file order. None: the file's
        first non-comment row is its header.
    """

    delimiter: str | None = None
    decimal: str = "."
    names: tuple[str, ...] | None = None

    @property
    def is_default(self) -> bool:
        return self == ReadOptions()
