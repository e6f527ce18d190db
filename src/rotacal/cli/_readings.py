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


def capture_names(capture: str, columns: Sequence[str], group: str | None) -> list[str]:
    """The canonical names of the capture's columns (from its header)."""
    from rotacal.io import capture_columns

    return list(capture_columns(capture, **_reading_options(columns, group)))


def reading_name(names: Sequence[str]) -> str | None:
    """``"count"`` or ``"angle_deg"`` (``count`` when both) for a capture of readings without
    ``head_k`` pulse columns, else None; one without ``time_s`` is refused."""
    if any(HEAD_NAME.match(n) for n in names):
        return None
    name = next((n for n in ("count", "angle_deg") if n in names), None)
    if name is not None and "time_s" not in names:
        raise CaptureError(
            f"no column 'time_s' beside {name} (columns: {', '.join(names)}); name yours with "
            "--column YOURS=time_s"
        )
    return name


def require_reading(capture: str, columns: Sequence[str], group: str | None) -> str:
    """:func:`reading_name` of the capture, refusing one without a reading."""
    names = capture_names(capture, columns, group)
    name = reading_name(names)
    if name is None:
        raise CaptureError(
            f"no column 'angle_deg' or 'count' (columns: {', '.join(names)}); name yours with "
            "--column YOURS=angle_deg (or =count)"
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
    ``progress`` gets the rows read so far, summed over the passes. Once a pass has read the
    whole file with the reader's checks (CRC-32s, NaN/inf), later passes skip them, as
    the motion commands' chunk sources do."""
    from rotacal.io import iter_capture_chunks

    options = _reading_options(columns, group)
    done = [0]
    checked = [False]

    def chunks() -> Iterator[tuple[np.ndarray, np.ndarray]]:
        for c in iter_capture_chunks(
            capture, ("time_s", name), chunk_rows=CHUNK_ROWS, verified=checked[0], **options
        ):
            done[0] += c["time_s"].size
            if progress is not None:
                progress(done[0])
            yield c["time_s"], c[name]
        checked[0] = True  # reached only when the pass ran to the end

    return chunks


def reading_length(capture: str, name: str, columns: Sequence[str], group: str | None) -> int:
    """Rows of the reading column."""
    from rotacal.io import capture_length

    return int(capture_length(capture, name, **_reading_options(columns, group)))
