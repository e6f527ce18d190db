"""Report section of ``rotacal inspect``: the column table, sampling, gaps and fits."""

from __future__ import annotations

from rotacal.inspect.result import InspectResult
from rotacal.inspect.text import HEADINGS, column_rows, fits_line, sampling_line, suggestion_line
from rotacal.numbers import fixed
from rotacal.report.html import Section, Table
from rotacal.report.wording import paragraph, readable_tables

__all__ = ["inspect_section"]


def inspect_section(result: InspectResult) -> Section:
    """What the file holds: one table row per column, then the sampling and the gaps."""
    paragraphs = [result.description]
    tables = []
    if result.kind == "capture":
        paragraphs.append(sampling_line(result))
        paragraphs.append(fits_line(result))
        suggested = suggestion_line(result)
        if suggested:
            paragraphs.append(suggested)
        paragraphs.extend(
            f"{name}: not read ({why})" for name, why in result.unreadable_columns.items()
        )
        tables.append(
            Table(
                columns=list(HEADINGS),
                rows=[list(row) for row in column_rows(result)],
                caption="Columns of the file",
                note="repeated: share of samples equal to the one before; clipped: share at a "
                "rail; step: the smallest non-zero step between samples (the resolution).",
            )
        )
        if result.gaps:
            tables.append(
                Table(
                    columns=["gap from (s)", "to (s)", "missing samples"],
                    rows=[
                        [fixed(g.start_s, 9), fixed(g.end_s, 9), str(g.missing_samples)]
                        for g in result.gaps
                    ],
                    caption=f"{result.gap_count} gap(s) in {result.time_column}"
                    + (
                        f", the first {len(result.gaps)} listed"
                        if result.gap_count > len(result.gaps)
                        else ""
                    ),
                )
            )
    return Section(
        title="First look",
        paragraphs=[paragraph(p) for p in paragraphs],
        tables=readable_tables(tables),
    )
