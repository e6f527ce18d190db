"""An :class:`InspectResult` in words: the column table and the sampling line (terminal, report)."""

from __future__ import annotations

from .result import InspectResult

#: Headings of the column table.
HEADINGS = ("column", "samples", "min", "max", "NaN", "inf", "repeated", "clipped", "step")


def _num(value: float | None) -> str:
    return "-" if value is None else f"{value:.6g}"


def _percent(share: float) -> str:
    return "0" if share == 0 else f"{100 * share:.3g} %"


def column_rows(result: InspectResult) -> list[tuple[str, ...]]:
    """One row of text cells per column, in :data:`HEADINGS` order."""
    return [
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


def sampling_line(result: InspectResult) -> str:
    """The time column's sampling in one line."""
    name = result.time_column
    if name is None:
        return "time: no time_s column (map one with --column NAME=time_s)"
    if result.sample_rate_hz is None or result.sample_interval_s is None:
        return f"time: {name} holds too few forward steps to give a sampling rate"
    gaps = f"{result.gap_count} gap(s)" if result.gap_count else "no gaps"
    order = "" if result.time_increasing else ", not strictly increasing"
    return (
        f"time: {name}, {result.sample_rate_hz:.6g} Hz (interval {result.sample_interval_s:.6g} s, "
        f"jitter {result.sample_interval_jitter_s or 0.0:.2g} s standard deviation), duration "
        f"{result.duration_s:.6g} s, {gaps}{order}"
    )


def fits_line(result: InspectResult) -> str:
    return "fits: " + (", ".join(result.fits) or "no analysis command (see --column)")


def suggestion_line(result: InspectResult) -> str | None:
    if not result.suggested_columns:
        return None
    mappings = " ".join(f"--column {m}" for m in result.suggested_columns)
    return f"suggested: {mappings} (check the unit first)"


def summary_lines(result: InspectResult) -> list[str]:
    """The terminal summary: what the file is, an aligned column table, sampling, fits."""
    lines = [result.description]
    if result.kind != "capture":
        return lines
    rows = column_rows(result)
    widths = [max(len(r[k]) for r in (HEADINGS, *rows)) for k in range(len(HEADINGS))]
    for row in (HEADINGS, *rows):
        cells = [row[0].ljust(widths[0])] + [
            cell.rjust(width) for cell, width in zip(row[1:-1], widths[1:-1], strict=True)
        ]
        lines.append("  ".join([*cells, row[-1]]).rstrip())
    lines.extend(f"{name}: not read ({why})" for name, why in result.unreadable_columns.items())
    lines.extend([sampling_line(result), fits_line(result)])
    suggested = suggestion_line(result)
    if suggested:
        lines.append(suggested)
    return lines
