"""What ``rotacal inspect`` reports about a file: :class:`InspectResult` and its parts."""

from __future__ import annotations

import dataclasses
from typing import Any

from rotacal.results import Result


@dataclasses.dataclass(frozen=True)
class ColumnSummary:
    """One column of a capture at first sight (values in the column's own unit).

    Attributes
    ----------
    samples : int — rows of the column (NaN and inf included).
    min, max : float or None — the smallest and largest finite value (None: no finite value).
    nan, inf : int — NaN and ±inf values (empty cells of a text capture are NaN).
    repeated_fraction : float — share of the samples equal to the one before them (a held,
        stuck or oversampled output; a set rate on its plateaus).
    clipped_fraction : float — share of the finite samples at a rail
        (:func:`rotacal.signal.clipping.find_clipping`); 0 when none is found.
    smallest_step : float or None — the smallest non-zero difference between consecutive
        finite samples: the column's resolution (ADC or output quantum) when it is quantised.
    increasing : bool — two or more values, each finite and larger than the one before it (a
        time or sample-counter column).
    first_nonfinite_row : int or None — row (from 0) of the first NaN or inf.
    """

    samples: int
    min: float | None
    max: float | None
    nan: int
    inf: int
    repeated_fraction: float
    clipped_fraction: float
    smallest_step: float | None
    increasing: bool
    first_nonfinite_row: int | None


@dataclasses.dataclass(frozen=True)
class Gap:
    """Missing samples in the time column: no sample between ``start_s`` and ``end_s``.

    ``missing_samples`` is how many samples at the usual interval fit in between.
    """

    start_s: float
    end_s: float
    missing_samples: int


@dataclasses.dataclass(frozen=True)
class InspectResult(Result):
    """A first look at a file (``rotacal inspect``; INTERFACE.md, "Every result").

    Attributes
    ----------
    path : str — the file as given.
    kind : str — ``"capture"`` for a table of numbers rotacal reads; otherwise what the file is
        (``"json"``, ``"markdown"``, ``"yaml"``, ``"text"``, ``"text-table"`` — numbers in a
        file whose extension no command reads —, ``"no-numbers"`` — a capture format with no
        column of numbers —, ``"binary"``, ``"empty"``).
    description : str — the same in words, with what to do about it.
    format : str or None — the capture format (``"CSV"``, ``"NPZ"``, ``"HDF5"``, ``"TDMS"``).
    rows : int — the longest column's length (0 for a file that is not a capture).
    columns : dict — column name (after ``--column`` mapping) → :class:`ColumnSummary`.
    unreadable_columns : dict — column name → why it cannot be read as numbers.
    time_column : str or None — the column taken as time in s (``time_s``, or ``--time``).
    time_increasing : bool or None — whether it increases strictly (None: no time column).
    sample_rate_hz, sample_interval_s : float or None — 1 / the mean interval, the mean interval
        (gaps and steps that do not advance left out).
    sample_interval_jitter_s : float or None — standard deviation of the intervals (same ones).
    duration_s : float or None — last minus first finite time stamp.
    gaps : tuple of Gap — steps longer than 3 usual intervals (the rule every analysis applies,
        :data:`rotacal.signal._checks.MAX_GAP`); the first ``MAX_LISTED_GAPS``.
    gap_count : int — every gap, listed or not.
    fits : tuple of str — the analysis commands whose columns the capture has
        (:mod:`rotacal.columns`).
    suggested_columns : tuple of str — ``--column OLD=NEW`` mappings onto canonical names that
        the file's names or values suggest (check the unit before using one).
    metadata : dict — what the file stores beside the columns (CSV ``# key: value`` lines, HDF5
        attributes, TDMS properties, NPZ ``__metadata__``).
    """

    path: str
    kind: str
    description: str
    format: str | None = None
    rows: int = 0
    columns: dict[str, ColumnSummary] = dataclasses.field(default_factory=dict)
    unreadable_columns: dict[str, str] = dataclasses.field(default_factory=dict)
    time_column: str | None = None
    time_increasing: bool | None = None
    sample_rate_hz: float | None = None
    sample_interval_s: float | None = None
    sample_interval_jitter_s: float | None = None
    duration_s: float | None = None
    gaps: tuple[Gap, ...] = ()
    gap_count: int = 0
    fits: tuple[str, ...] = ()
    suggested_columns: tuple[str, ...] = ()
    metadata: dict[str, Any] = dataclasses.field(default_factory=dict)
