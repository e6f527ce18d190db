"""The options of a command that splits one huge capture over the workers of a Dask cluster
(``--workers N`` for a local cluster, ``--scheduler ADDRESS`` for a running one)."""

from __future__ import annotations

from typing import Any, TypeVar

import click

F = TypeVar("F", bound=Any)


def dask_options(what: str) -> Any:
    """``--workers`` and ``--scheduler`` (``what``: the formats and limits of the split path,
    for the help)."""

    def decorate(func: F) -> F:
        func = click.option(
            "--scheduler",
            metavar="ADDRESS",
            default=None,
            help="Split the capture over the workers of the running Dask scheduler at ADDRESS "
            "(tcp://host:8786); they must see the capture at the same path.",
        )(func)
        return click.option(
            "--workers",
            type=click.IntRange(min=1),
            default=None,
            help=f"Split the capture over a local Dask cluster of N worker processes ({what}).",
        )(func)

    return decorate


def split_wanted(workers: int | None, scheduler: str | None, chunked: bool | None) -> bool:
    """Whether the capture is split over Dask workers; refuses contradictory options."""
    if workers is None and scheduler is None:
        return False
    if workers is not None and scheduler is not None:
        raise click.UsageError("give --workers (a local cluster) or --scheduler, not both")
    if chunked is False:
        raise click.UsageError("--in-memory reads the capture in this process; drop it")
    return True
