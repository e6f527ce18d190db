"""``rotacal inspect``: a first look at a file before any analysis."""

from __future__ import annotations

from collections.abc import Sequence

import click

from ._app import cli
from ._common import (
    INPUT_FILE,
    _check_outputs,
    _names_capture,
    _publish,
    _status,
)
from ._reading import current_read_options, reading_options


@cli.command("inspect")
@click.argument("capture", type=INPUT_FILE)
@click.option(
    "--json", "json_path", metavar="PATH", help="Write the findings as JSON ('-' = stdout)."
)
@click.option("--report", "report_path", metavar="PATH.html", help="Write an HTML report.")
@click.option(
    "--column",
    "columns",
    multiple=True,
    metavar="OLD=NEW",
    help="Map a column of the file onto a canonical name (repeatable), e.g. col_1=time_s.",
)
@click.option("--group", default=None, help="HDF5 group or TDMS group holding the columns.")
@click.option("--overwrite", is_flag=True, help="Replace existing --json/--report files.")
@reading_options
@_names_capture
def inspect_cmd(
    capture: str,
    json_path: str | None,
    report_path: str | None,
    columns: Sequence[str],
    group: str | None,
    overwrite: bool,
) -> None:
    """First look at a file before any analysis.

    What CAPTURE holds, and which analysis commands it fits. For each column: samples, range, NaN and inf, the share of repeated and of clipped samples,
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
    from rotacal.inspect.text import summary_lines
    from rotacal.io import parse_column_mapping

    _check_outputs(json_path, report_path, overwrite)
    with _status(f"inspecting {capture}"):
        result = inspect_capture(
            capture,
            mapping=parse_column_mapping(columns),
            group=group,
            read_options=current_read_options(),
        )
    _publish(
        result,
        json_path,
        report_path,
        capture,
        "First look at a file",
        "rotacal inspect: columns, sampling, gaps and the analyses that fit",
        ("inspect", "inspect_section"),
    )
    if json_path != "-":
        click.echo("\n".join(summary_lines(result)))
