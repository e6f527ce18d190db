"""``rotacal inspect``: a first look at a file before any analysis."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import click

from ._app import cli
from ._common import (
    INPUT_FILE,
    _check_outputs,
    _emit_warnings,
    _names_capture,
    _status,
    _write_json,
)
from ._reading import current_read_options, reading_options


@cli.command("inspect")
@click.argument("capture", type=INPUT_FILE)
@click.option(
    "--json", "json_path", metavar="PATH", help="Write the findings as JSON ('-' = stdout)."
)
@click.option(
    "--column",
    "columns",
    multiple=True,
    metavar="OLD=NEW",
    help="Map a column of the file onto a canonical name (repeatable), e.g. col_1=time_s.",
)
@click.option("--group", default=None, help="HDF5 group or TDMS group holding the columns.")
@click.option("--overwrite", is_flag=True, help="Replace an existing --json file.")
@reading_options
@_names_capture
def inspect_cmd(
    capture: str,
    json_path: str | None,
    columns: Sequence[str],
    group: str | None,
    overwrite: bool,
) -> None:
    """A first look at CAPTURE: its columns, sampling, gaps and the commands it fits.

    For each column: samples, range, NaN and inf, the share of repeated and of clipped samples,
    the smallest step (the resolution of a quantised output) and whether it increases. For the
    time column (time_s): sampling rate, jitter of the interval, duration and gaps. Then the
    analysis commands whose columns the file has, --column mappings its names suggest, and
    warnings. A file that is not a capture (JSON, text, Markdown …) gets one line saying what
    it is.

    \b
    Examples:
      rotacal inspect run.csv
      rotacal inspect log.dat --column col_1=time_s --json first-look.json
    """
    from rotacal.inspect import inspect_capture
    from rotacal.io import parse_column_mapping

    _check_outputs(json_path, None, overwrite)
    with _status(f"inspecting {capture}"):
        result = inspect_capture(
            capture,
            mapping=parse_column_mapping(columns),
            group=group,
            read_options=current_read_options(),
        )
    _emit_warnings(result)
    _write_json(result.to_dict(), json_path)
    if json_path != "-":
        click.echo("\n".join(summary_lines(result)))


def _num(value: float | None) -> str:
    return "-" if value is None else f"{value:.6g}"


def _percent(share: float) -> str:
    return "0" if share == 0 else f"{100 * share:.3g} %"


_HEADINGS = ("column", "samples", "min", "max", "NaN", "inf", "repeated", "clipped", "step")


def summary_lines(result: Any) -> list[str]:
    """The terminal summary of an :class:`~rotacal.inspect.InspectResult`: a few lines of
    text and a table of the columns."""
    lines = [result.description]
    if result.kind != "capture":
        return lines
    rows = [
        (
            name,
            str(c.samples),
            _num(c.min),
            _num(c.max),
            str(c.nan),
            str(c.inf),
            _percent(c.repeated_fraction),
            _percent(c.clipped_fraction),
            _num(c.smallest_step) + (" (increasing)" if c.increasing else ""),
        )
        for name, c in result.columns.items()
    ]
    widths = [max(len(r[k]) for r in (_HEADINGS, *rows)) for k in range(len(_HEADINGS))]
    for row in (_HEADINGS, *rows):
        cells = [row[0].ljust(widths[0])] + [
            cell.rjust(width) for cell, width in zip(row[1:-1], widths[1:-1], strict=True)
        ]
        lines.append("  ".join([*cells, row[-1]]).rstrip())
    for name, why in result.unreadable_columns.items():
        lines.append(f"{name}: not read ({why})")
    if result.time_column is not None:
        lines.append(_sampling_line(result))
    else:
        lines.append("time: no time_s column (map one with --column NAME=time_s)")
    lines.append("fits: " + (", ".join(result.fits) or "no analysis command (see --column)"))
    if result.suggested_columns:
        lines.append(
            "suggested: "
            + " ".join(f"--column {m}" for m in result.suggested_columns)
            + " (check the unit first)"
        )
    return lines


def _sampling_line(result: Any) -> str:
    name = result.time_column
    if result.sample_rate_hz is None:
        return f"time: {name} holds too few forward steps to give a sampling rate"
    gaps = f"{result.gap_count} gap(s)" if result.gap_count else "no gaps"
    order = "" if result.time_increasing else ", not strictly increasing"
    return (
        f"time: {name}, {result.sample_rate_hz:.6g} Hz (interval {result.sample_interval_s:.6g} s "
        f"± {result.sample_interval_jitter_s:.2g} s standard deviation), duration "
        f"{result.duration_s:.6g} s, {gaps}{order}"
    )
