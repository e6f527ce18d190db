"""The reading options every capture command takes: ``--delimiter``, ``--decimal``, ``--names``.

The options are consumed here and kept on the click context, so that every reader call of a
command (``_read``, ``_read_heads``, ``capture_length`` …) uses them without each command
passing them on.
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from typing import Any, TypeVar

import click

from rotacal.io import ReadOptions
from rotacal.io.read_options import delimiter_from_word

F = TypeVar("F", bound=Callable[..., Any])
_META_KEY = "rotacal.read_options"


def current_read_options() -> ReadOptions:
    """The reading options of the running command (defaults outside a command)."""
    ctx = click.get_current_context(silent=True)
    if ctx is None:
        return ReadOptions()
    return ctx.meta.get(_META_KEY, ReadOptions())


def reading_options(func: F) -> F:
    """Add ``--delimiter``, ``--decimal`` and ``--names`` to a command that reads a capture."""

    @functools.wraps(func)
    def command(*args: Any, **kwargs: Any) -> Any:
        delimiter = kwargs.pop("delimiter")
        decimal = kwargs.pop("decimal")
        names = kwargs.pop("names")
        options = ReadOptions(
            delimiter=delimiter_from_word(delimiter),
            decimal=decimal,
            names=tuple(n.strip() for n in names.split(",")) if names else None,
        )
        click.get_current_context().meta[_META_KEY] = options
        return func(*args, **kwargs)

    options = [
        click.option(
            "--delimiter",
            default=None,
            metavar="CHAR",
            help="Cell separator of a text capture: ',' ';' 'tab' or 'space' (any run of "
            "blanks) [default: sniffed among them].",
        ),
        click.option(
            "--decimal",
            type=click.Choice([".", ","]),
            default=".",
            show_default=True,
            help="Decimal mark of a text capture (a ';', tab or blank separated file whose "
            "numbers use ',' is recognised by itself).",
        ),
        click.option(
            "--names",
            default=None,
            metavar="A,B,C",
            help="Column names of a text capture without a header row, in file order "
            "[default: col_1, col_2, …].",
        ),
    ]
    wrapped: Any = command
    for option in reversed(options):
        wrapped = option(wrapped)
    return wrapped
