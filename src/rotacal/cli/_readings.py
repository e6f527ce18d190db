"""Angle and counter captures on the CLI (private): which reading a file holds, its chunks."""

from __future__ import annotations

from collections.abc import Callable, Iterator, Sequence
from typing import Any

import numpy as np

from rotacal.columns import HEAD_NAME
from rotacal.errors import CaptureError

from ._reading import current_read_options

#: Rows per chunk of a streamed pass.
CHUNK_ROWS = 1 << 20


def _reading_options(columns: Sequence[str], group: str | None) -> dict[str, Any]:
    from rotacal.io import parse_column_mapping

    return {
        "mapping": parse_column_mapping(columns),
        "group": group,
        "read_options": current_read_options(),
    }


def reading_name(capture: str, columns: Sequence[str], group: str | None) -> str | None:
    """``"count"`` or ``"angle_deg"`` (``count`` when both) for a capture with ``time_s`` and no
    ``head_k`` pulse column, else None."""
    from rotacal.io import capture_columns

    names = capture_columns(capture, **_reading_options(columns, group))
    if any(HEAD_NAME.match(n) for n in names) or "time_s" not in names:
        return None
    return next((n for n in ("count", "angle_deg") if n in names), None)


def require_reading(capture: str, columns: Sequence[str], group: str | None) -> str:
    """:func:`reading_name`, refusing a capture without one."""
    name = reading_name(capture, columns, group)
    if name is None:
        raise CaptureError(
            "has no columns time_s with angle_deg or count: name yours with --column "
            "YOURS=time_s and --column YOURS=angle_deg (or =count)"
        )
    return name


def reading_chunks(
    capture: str,
    name: str,
    columns: Sequence[str],
    group: str | None,
    progress: Callable[[int], None] | None = None,
) -> Callable[[], Iterator[tuple[np.ndarray, np.ndarray]]]:
    """A chunk source of ``(time_s, name)``: each call a fresh streamed pass over the file;
    ``progress`` gets the rows read so far, summed over the passes."""
    from rotacal.io import iter_capture_chunks

    options = _reading_options(columns, group)
    done = [0]

    def chunks() -> Iterator[tuple[np.ndarray, np.ndarray]]:
        for c in iter_capture_chunks(capture, ("time_s", name), chunk_rows=CHUNK_ROWS, **options):
            done[0] += c["time_s"].size
            if progress is not None:
                progress(done[0])
            yield c["time_s"], c[name]

    return chunks


def reading_length(capture: str, name: str, columns: Sequence[str], group: str | None) -> int:
    """Rows of the reading column."""
    from rotacal.io import capture_length

    return int(capture_length(capture, name, **_reading_options(columns, group)))
