"""``rotacal rate … --window-deg 1,10,360``: rate accuracy and stability over angle windows.

The option, and the one call the rate command makes after its analysis
(:func:`add_windows`): the same pulse train read again in chunks (flat memory for any record),
compensated as the rate was, through :func:`rotacal.table.rate_windows.rate_windows_stream`.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator, Sequence
from pathlib import Path
from typing import Any, TypeVar

import click
import numpy as np

from rotacal.errors import ConfigError

from ._common import _naming_file, _read_heads, _sample_progress
from ._reading import current_read_options

F = TypeVar("F", bound=Callable[..., Any])

#: Pulses read at a time from the head's column.
_CHUNK_ROWS = 1 << 22


def window_option(func: F) -> F:
    """The ``--window-deg`` option of ``rotacal rate``."""
    return click.option(
        "--window-deg",
        "window_deg",
        default=None,
        metavar="W1,W2,…",
        callback=lambda ctx, param, value: None if value is None else parse_windows(value),
        help="Rate accuracy and stability over consecutive windows of these angles (deg), e.g. "
        "1,10,360: each window's mean rate against --set-rate-deg-s, their spread.",
    )(func)


def parse_windows(text: str) -> list[float]:
    """The window angles (deg) of ``--window-deg`` (comma-separated, each > 0)."""
    out: list[float] = []
    for part in text.split(","):
        try:
            w = float(part.strip())
        except ValueError:
            raise ConfigError(
                f"--window-deg {text!r}: {part.strip()!r} is not an angle; give degrees such as "
                "1,10,360."
            ) from None
        if not np.isfinite(w) or w <= 0:
            raise ConfigError(f"--window-deg {text!r}: {part.strip()!r} must be a positive angle.")
        out.append(w)
    return out


def _deviation(result: Any, selfcal: Any, m: int) -> tuple[Any, int, float | None]:
    """The deviation the rate was compensated with, its shift and its point uncertainty."""
    from rotacal.table.rate_alignment import _as_deviation

    if not result.compensated:
        return None, 0, None
    source = result.selfcal if result.selfcal is not None else selfcal
    if isinstance(source, dict):
        u = source.get("deviation_u_arcsec")
    else:
        u = getattr(source, "deviation_u_arcsec", None)
    u = float(u) if isinstance(u, int | float) else None
    return _as_deviation(source, m).values, int(result.deviation_shift_pulses or 0), u


def _times(
    result: Any, capture: str, columns: Sequence[str], group: str | None
) -> tuple[Callable[[], Iterator[Any]], int, int]:
    """The chunks of the train the rate used, its length and the heads averaged in it: the
    head's column read in chunks; the head-averaged times (or a CSV, whose heads are padded)
    in memory."""
    from rotacal.io import capture_length, iter_capture_chunks, parse_column_mapping

    mapping = parse_column_mapping(columns)
    options = current_read_options()
    if result.head == "all heads" or Path(capture).suffix.lower() in (".csv", ".txt"):
        heads = _read_heads(capture, columns, group)
        if result.head == "all heads":
            from rotacal.encoder.pulses import pair_heads

            names = [f"head_{i}" for i in range(len(heads))]
            t = pair_heads(heads, names).mean_times_s
        else:
            t = np.asarray(heads[int(result.head.split("_")[1])], dtype=np.float64)
        averaged = len(heads) if result.head == "all heads" else 1
        return (lambda: iter([t])), int(t.size), averaged
    column = result.head
    n = capture_length(capture, column, mapping=mapping, group=group, read_options=options)

    def chunks() -> Iterator[Any]:
        for part in iter_capture_chunks(
            capture,
            [column],
            chunk_rows=_CHUNK_ROWS,
            mapping=mapping,
            group=group,
            read_options=options,
        ):
            yield part[column]

    return chunks, n, 1


def add_windows(
    result: Any,
    windows_deg: list[float] | None,
    *,
    capture: str,
    columns: Sequence[str],
    group: str | None,
    settings: dict[str, Any],
) -> Any:
    """``result`` with the figures of ``--window-deg`` joined (unchanged without the option)."""
    if windows_deg is None:
        return result
    from rotacal.table.rate_windows import rate_windows_stream
    from rotacal.table.rate_windows_result import with_windows

    m = int(settings["pulses_per_rev"])
    deviation, shift, dev_u = _deviation(result, settings["selfcal"], m)
    with _naming_file(capture):
        chunks, n, averaged = _times(result, capture, columns, group)
        with _sample_progress(n, "angle windows") as progress:
            done = [0]

            def step(pulses: int) -> None:
                done[0] += pulses
                progress(done[0])

            windows = rate_windows_stream(
                chunks,
                pulses_per_rev=m,
                windows_deg=windows_deg,
                set_rate_deg_s=settings["set_rate_deg_s"],
                deviation_arcsec=deviation,
                line_offset=shift,
                deviation_u_arcsec=dev_u,
                timing_jitter_s=result.timing_jitter_s,
                timebase_correction=result.timebase_correction,
                heads_averaged=averaged,
                specs=settings["specs"],
                check=False,  # the rate's analysis checked the same train
                progress=step,
            )
    return with_windows(result, windows)


def window_sections(result: Any) -> list[Any]:
    """The report section of the windows, when the result has them."""
    windows = getattr(result, "windows", None)
    if windows is None:
        return []
    from rotacal.report.rate_windows import rate_windows_section

    return [rate_windows_section(windows)]


def print_windows(result: Any) -> None:
    """One line per window on the terminal: accuracy, stability, peak (each ± u)."""
    windows = getattr(result, "windows", None)
    if windows is None:
        return
    from rotacal.numbers import format_quantity

    def pm(value: float | None, u: float | None) -> str:  # value ± u, rounded as u (k = 1)
        return "—" if value is None or u is None else format_quantity(value, "%", U=u)

    for key, count in windows.window_count.items():
        click.echo(
            f"over {key} deg".ljust(19)
            + f"accuracy {pm(windows.rate_accuracy_percent[key], windows.rate_accuracy_percent_u[key])}"
            + f"  stability {pm(windows.rate_stability_percent[key], windows.rate_stability_percent_u[key])}"
            + f"  peak {pm(windows.rate_stability_peak_percent[key], windows.rate_stability_peak_percent_u[key])}"
            + f"  ({count} windows)"
        )
