"""The options of a command that splits one huge capture over the workers of a Dask cluster
(``--workers N`` for a local cluster, ``--scheduler ADDRESS`` for a running one)."""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from typing import TYPE_CHECKING, Any, TypeVar

import click

from ._common import _sample_progress

if TYPE_CHECKING:
    from distributed import Client

F = TypeVar("F", bound=Any)
R = TypeVar("R")


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


def run_on_dask(
    where: tuple[int | None, str | None],
    tasks: int,
    label: str,
    analysis: Callable[[Client, Callable[[int], None]], R],
    *,
    capture: str,
    columns: list[str],
    rows: int,
    reading: dict[str, Any],
    unit: str = "samples",
) -> R:
    """``analysis(client, progress)`` on the cluster ``where`` (``--workers``, ``--scheduler``)
    with a bar over at most ``tasks`` tasks; its result with a last note "split over N Dask
    workers (``rows`` ``unit``)". The first row of the capture's ``columns`` (of ``rows``; ``reading``: mapping, group
    and read options) is read first, so that a format without row offsets (CSV, a compressed NPZ
    member) is refused before a cluster starts."""
    from rotacal.batch.cluster import dask_client
    from rotacal.io import read_capture_rows

    if rows:  # an empty capture is refused by the analysis itself, with its message
        read_capture_rows(capture, columns, 0, 1, **reading)
    with (
        dask_client(*where, None) as client,
        _sample_progress(tasks, f"{label} (tasks on Dask)") as progress,
    ):
        result = analysis(client, progress)
        used = len(client.scheduler_info().get("workers", {}))
    notes = result.notes  # type: ignore[attr-defined]
    note = f"split over {used} Dask workers ({rows} {unit})"
    return dataclasses.replace(result, notes=type(notes)((*notes, note)))  # type: ignore[type-var]
