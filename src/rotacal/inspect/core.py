"""The first look at columns of numbers: :class:`Inspector` (chunks) and :func:`inspect_columns`.

Array level: no files here. :mod:`rotacal.inspect.files` feeds it a capture, whole or in chunks.
"""

from __future__ import annotations

import re
from collections.abc import Iterable, Iterator, Mapping
from typing import Any

import numpy as np

from rotacal.columns import CANONICAL_NAMES, fitting_commands
from rotacal.errors import CaptureError

from .result import ColumnSummary, InspectResult
from .stats import ColumnStats, TimeStats

#: A time column's jitter above this share of the interval is worth a warning: methods that
#: take the sampling rate as given (Allan deviation, the sine fits' FFT start) then misplace
#: samples.
JITTER_WARNING = 0.01
#: File column names (letters and digits only, lower case) that mean "time" without a unit
#: other than seconds; an increasing column of that name is suggested as ``time_s``.
_TIME_NAMES = frozenset({"t", "time", "times", "timestamp", "timestamps", "timesec", "seconds"})


def _plain(name: str) -> str:
    return re.sub(r"[^a-z0-9]", "", name.lower())


class Inspector:
    """Collects the statistics of named columns fed in chunks (any subset of them per chunk).

    Parameters
    ----------
    names : iterable of str — the columns to expect.
    time_column : str — the column holding time in s (default ``time_s``); its sampling is
        analysed when it is among ``names``.
    """

    def __init__(self, names: Iterable[str], time_column: str = "time_s") -> None:
        self.time_column = time_column
        self.stats: dict[str, ColumnStats] = {}
        self.time: TimeStats | None = None
        for name in names:
            self.reset(name)

    def reset(self, name: str) -> None:
        """Forget what was fed of column ``name`` (to read it again)."""
        self.stats[name] = ColumnStats(name)
        if name == self.time_column:
            self.time = TimeStats()

    def drop(self, name: str) -> None:
        """Leave column ``name`` out (it could not be read)."""
        self.stats.pop(name, None)
        if name == self.time_column:
            self.time = None

    def add(self, chunk: Mapping[str, np.ndarray]) -> None:
        """Feed the next rows of some columns (1-D float64 arrays, row order per column)."""
        for name, values in chunk.items():
            self.stats[name].add(values)
            if name == self.time_column and self.time is not None:
                self.time.add(values)

    def result(
        self,
        path: str = "",
        *,
        description: str = "",
        format: str | None = None,
        unreadable: Mapping[str, str] | None = None,
        metadata: Mapping[str, Any] | None = None,
    ) -> InspectResult:
        """The :class:`InspectResult` of what was fed, with its warnings."""
        columns = {name: s.summary() for name, s in self.stats.items()}
        unreadable = dict(unreadable or {})
        warnings = [
            *_column_warnings(self.stats, columns),
            *(f"column '{name}' was left out: {why}" for name, why in unreadable.items()),
        ]
        sampling: dict[str, Any] = {}
        if self.time is not None and self.time_column in columns:
            warnings.extend(_time_warnings(self.time_column, self.time))
            sampling = _sampling(self.time_column, self.time, columns[self.time_column])
        return InspectResult(
            path=path,
            kind="capture",
            description=description or f"{len(columns)} column(s) of numbers",
            format=format,
            rows=max((c.samples for c in columns.values()), default=0),
            columns=columns,
            unreadable_columns=unreadable,
            fits=fitting_commands(columns),
            suggested_columns=_suggestions(columns, self.stats),
            metadata=dict(metadata or {}),
            warnings=tuple(warnings),
            **sampling,
        )


def _sampling(name: str, time: TimeStats, column: ColumnSummary) -> dict[str, Any]:
    """The time-column fields of an :class:`InspectResult`."""
    interval = time.interval
    return {
        "time_column": name,
        "time_increasing": column.increasing,
        "sample_rate_hz": 1.0 / interval if interval else None,
        "sample_interval_s": interval,
        "sample_interval_jitter_s": time.jitter,
        "duration_s": time.duration,
        "gaps": time.gap_list(),
        "gap_count": time.gap_count,
    }


def _column_warnings(
    stats: Mapping[str, ColumnStats], columns: Mapping[str, ColumnSummary]
) -> Iterator[str]:
    for name, c in columns.items():
        if c.nan or c.inf:
            yield (
                f"column '{name}' holds {c.nan} NaN and {c.inf} inf values (the first at row "
                f"{c.first_nonfinite_row}, rows counted from 0; empty cells count as NaN); "
                "analyses refuse them: remove or fill those rows"
            )
        if c.min is not None and c.min == c.max and c.samples > 1:
            yield f"column '{name}' is constant ({c.min:.6g}): it carries no signal"
        note = stats[name].clipping_note()
        if note is not None:
            yield f"{note}; analyses refuse it unless given --allow-clipped"


def _time_warnings(name: str, time: TimeStats) -> Iterator[str]:
    if time.backward:
        yield (
            f"time column '{name}' does not increase at {time.backward} step(s), the first at "
            f"row {time.first_backward} (rows counted from 0); analyses need strictly "
            "increasing times: sort the rows or drop repeated samples"
        )
    if time.gap_count:
        a, b = time.gaps[0]
        yield (
            f"time column '{name}' has {time.gap_count} gap(s) where samples are missing, the "
            f"first from {a:.9g} s to {b:.9g} s; analyses refuse gaps: analyse the parts on "
            "either side separately"
        )
    interval, jitter = time.interval, time.jitter
    if interval and jitter is not None and jitter > JITTER_WARNING * interval:
        yield (
            f"the sample interval of '{name}' jitters by {100 * jitter / interval:.3g} % "
            f"(standard deviation {jitter:.3g} s of {interval:.6g} s): methods that take a "
            "fixed sampling rate (--fs-hz) misplace samples"
        )


def _suggestions(
    columns: Mapping[str, ColumnSummary], stats: Mapping[str, ColumnStats]
) -> tuple[str, ...]:
    """``OLD=NEW`` mappings onto canonical names the file's columns suggest.

    A name that differs from a canonical one only in case and punctuation (``Rate_Deg_S``); an
    increasing column named like time without another unit (``t``, ``timestamp``), or an
    increasing, not whole-numbered column of a file without header (``col_1``), as ``time_s``
    when the capture has none.
    """
    canonical = {_plain(n): n for n in CANONICAL_NAMES}
    out: dict[str, str] = {}
    taken = set(columns)
    for name in columns:
        target = canonical.get(_plain(name))
        if target is not None and target != name and target not in taken:
            out[name] = target
            taken.add(target)
    if "time_s" not in taken:
        for name, c in columns.items():
            headerless = re.fullmatch(r"col_\d+", name) is not None
            timelike = _plain(name) in _TIME_NAMES or (headerless and not stats[name].integral)
            if c.increasing and timelike and name not in out:
                out[name] = "time_s"
                break
    return tuple(f"{old}={new}" for old, new in out.items())


def inspect_columns(
    columns: Mapping[str, Any], *, time_column: str = "time_s", path: str = ""
) -> InspectResult:
    """A first look at columns of numbers (the array-level function under ``rotacal inspect``).

    Parameters
    ----------
    columns : mapping of str to array_like — each column 1-D, in row order, in its own unit;
        lengths may differ; NaN and inf are counted, not refused.
    time_column : str — the column holding time in s; its sampling (rate, jitter, gaps) is
        analysed when present.
    path : str — the file the columns came from, for the result.

    Returns
    -------
    InspectResult
        ``kind`` ``"capture"``; see :class:`~rotacal.inspect.result.InspectResult`.

    Raises
    ------
    CaptureError
        A column that is not 1-D or not real numbers.
    """
    arrays: dict[str, np.ndarray] = {}
    for name, values in columns.items():
        arr = np.asarray(values)
        if arr.ndim != 1 or arr.dtype.kind not in "iuf":
            raise CaptureError(
                f"column '{name}' must be a 1-D array of real numbers; it holds "
                f"{arr.dtype} values of shape {arr.shape}"
            )
        arrays[name] = arr.astype(np.float64, copy=False)
    inspector = Inspector(arrays, time_column)
    inspector.add(arrays)
    return inspector.result(path)
