"""The pulse-timing rate analysis of one head streamed from its capture file (bounded memory).

:func:`calibrate_rate_file` gives what :func:`rotacal.table.rate.calibrate_rate` gives for the
same head, to rounding (the same passes, :mod:`rotacal.table.rate_stream`), reading the file
chunk by chunk (:func:`rotacal.io.iter_capture_chunks`, which hands each chunk's mapped pages
back): no self-calibration (one head, or ``compensate=False``), a given deviation curve (a
SelfCalibration, its JSON dict or m values), placed on the capture by a first pass of its own
(:class:`~rotacal.table.rate_alignment.FoldSums`) unless it comes from this very capture, or —
several heads and nothing given — the capture's own self-calibration, streamed too
(:func:`~rotacal.encoder.selfcal_stream.self_calibrate_chunked`, one reader per head).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Iterator, Mapping
from os import PathLike
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from rotacal.encoder.pulses import check_pulse_times, check_pulses_per_rev
from rotacal.encoder.selfcal import SelfCalibration
from rotacal.errors import CaptureError, ConfigError
from rotacal.table.rate import RateResult, _check_settings, _head_index, _rate_result
from rotacal.table.rate_alignment import (
    FoldSums,
    _as_deviation,
    _phase_shift,
    accept_alignment,
    own_revolutions,
    same_capture,
)
from rotacal.table.rate_stream import RatePasses, rate_passes
from rotacal.uncertainty import InstrumentSpecs

__all__ = ["HeadPasses", "calibrate_rate_file", "file_heads"]

FloatArray = NDArray[np.float64]

#: Pulses read per chunk (32 MB of float64).
CHUNK_PULSES = 1 << 22


def file_heads(path: str | PathLike[str], *, mapping: Any = None, group: str | None = None) -> int:
    """The number of head columns (head_0 … head_{n−1}, after ``mapping``) of a capture."""
    from rotacal.io import capture_columns

    names = set(capture_columns(path, mapping=mapping, group=group))
    n = 0
    while f"head_{n}" in names:
        n += 1
    if n == 0:
        raise CaptureError(f"{path}: no column head_0; give the pulse times of head 0 (--column).")
    return n


@dataclasses.dataclass(frozen=True)
class HeadPasses:
    """What runs the passes over a head's column instead of this process: the alignment's
    (pulses N, m → its :class:`~rotacal.table.rate_alignment.FoldSums`) and the rate's two
    (the arguments of :func:`~rotacal.table.rate_stream.rate_passes`)."""

    fold: Callable[[int, int], FoldSums]
    rate: Callable[..., RatePasses]


def _checked(
    path: str | PathLike[str],
    column: str,
    *,
    mapping: Any,
    group: str | None,
    read_options: Any,
    chunk_rows: int,
) -> Callable[[], Iterator[FloatArray]]:
    """A fresh iterator over the column's chunks, each checked as a pulse train with the last
    pulse before it (the same checks as check_pulse_times; pulse numbers of the whole train) on
    the first pass only: the file does not change between passes."""
    from rotacal.io import iter_capture_chunks

    checked = [False]

    def chunks() -> Iterator[FloatArray]:
        check = not checked[0]
        last: FloatArray = np.zeros(0)
        start = 0
        for part in iter_capture_chunks(
            path,
            [column],
            chunk_rows=chunk_rows,
            mapping=mapping,
            group=group,
            read_options=read_options,
        ):
            t = part[column]
            if check:
                joined = np.concatenate((last, t))
                if joined.size >= 3:
                    check_pulse_times(joined, column, first_index=start - last.size)
                last = t[-1:].copy()
            start += t.size
            yield t
        checked[0] = checked[0] or check

    return chunks


def _self_calibrate(
    path: str | PathLike[str],
    heads: int,
    m: int,
    specs: InstrumentSpecs | None,
    *,
    mapping: Any,
    group: str | None,
    read_options: Any,
    chunk_rows: int,
    progress: Callable[[int], None] | None,
) -> SelfCalibration:
    """The capture's own self-calibration, every head read in chunks (one reader per head: heads
    are ragged), as :func:`~rotacal.table.rate.calibrate_rate` makes it in memory."""
    from rotacal.encoder.selfcal_stream import self_calibrate_chunked
    from rotacal.io import iter_capture_chunks

    def one_head(name: str) -> Iterator[FloatArray]:
        parts = iter_capture_chunks(
            path,
            [name],
            chunk_rows=chunk_rows,
            mapping=mapping,
            group=group,
            read_options=read_options,
        )
        return (part[name] for part in parts)

    done = [0]

    def step(total: int) -> None:  # self_calibrate_chunked counts cumulatively; progress per chunk
        if progress is not None:
            progress(total - done[0])
        done[0] = total

    try:
        return self_calibrate_chunked(
            lambda: [one_head(f"head_{i}") for i in range(heads)],
            pulses_per_rev=m,
            specs=specs,
            progress=step,
        )
    except CaptureError as e:
        raise CaptureError(
            f"{e} (the rate is compensated with a self-calibration of this capture; "
            "give one with --selfcal, or use --no-compensation)"
        ) from None


def calibrate_rate_file(
    path: str | PathLike[str],
    *,
    pulses_per_rev: int,
    selfcal: SelfCalibration | Mapping[str, Any] | ArrayLike | None = None,
    head: int | str = 0,
    average: int = 10,
    set_rate_deg_s: float | None = None,
    allan_angles_deg: ArrayLike | None = None,
    compensate: bool = True,
    specs: InstrumentSpecs | None = None,
    mapping: Any = None,
    group: str | None = None,
    read_options: Any = None,
    chunk_rows: int = CHUNK_PULSES,
    progress: Callable[[int], None] | None = None,
    passes_for: Callable[[str], HeadPasses] | None = None,
) -> RateResult:
    """:func:`rotacal.table.rate.calibrate_rate` of one head of a capture file, streamed.

    Parameters as for :func:`~rotacal.table.rate.calibrate_rate` (``head`` a number: the
    head-averaged times need every head at once), plus where the file is (``mapping``, ``group``
    and ``read_options`` as for :func:`rotacal.io.read_capture`), ``chunk_rows`` (pulses per
    chunk), ``progress`` (called with the pulses of each chunk read, every pass) and
    ``passes_for``: given the head's column, what runs the passes over it (default: this
    process over the column's chunks; :mod:`rotacal.batch.capture_rate` splits them over Dask
    workers).

    Raises
    ------
    CaptureError, ConfigError
        As the in-memory path; also a head other than head_0 of a capture of several heads to
        be compensated, a deviation from another capture on one of several heads, and
        ``head="all"`` (those pair the heads in memory: use the in-memory path).

    References
    ----------
    Kokuyama et al. (2015) §5; see :func:`~rotacal.table.rate.calibrate_rate`.
    """
    from rotacal.io import capture_length

    m = check_pulses_per_rev(pulses_per_rev)
    _check_settings(specs, set_rate_deg_s)
    if isinstance(head, str) and head == "all":
        raise ConfigError(
            "the streamed rate analysis takes one head; the head-averaged times need every head "
            "in memory (--in-memory)."
        )
    heads = file_heads(path, mapping=mapping, group=group)
    k = _head_index(head, heads)
    if compensate and heads >= 2 and k != 0:
        raise ConfigError(
            "a head other than head_0 is paired with head 0 in memory; give --head 0 or "
            "--in-memory."
        )
    column = f"head_{k}"
    pulses = capture_length(path, column, mapping=mapping, group=group, read_options=read_options)
    runner = None if passes_for is None else passes_for(column)
    chunks = _checked(
        path, column, mapping=mapping, group=group, read_options=read_options, chunk_rows=chunk_rows
    )
    notes: list[str] = []
    made: SelfCalibration | None = None
    if compensate and selfcal is None and heads >= 2:
        made = _self_calibrate(
            path,
            heads,
            m,
            specs,
            mapping=mapping,
            group=group,
            read_options=read_options,
            chunk_rows=chunk_rows,
            progress=progress,
        )
        selfcal = made
        notes.append(
            f"compensated with the deviation self-calibrated from this capture "
            f"({made.heads} heads, {made.revolutions_used} revolutions)."
        )
    deviation = shift = correlation = None
    own = None
    if compensate and selfcal is not None:
        dev = _as_deviation(selfcal, m)
        deviation = dev.values
        if runner is not None:
            fold = runner.fold(pulses, m)
        else:
            fold = FoldSums(pulses, m)
            for t in chunks():  # the alignment's pass: the head's folded angle error
                fold.update(t)
                if progress is not None:
                    progress(t.size)
        same = same_capture(dev, (fold.t0, fold.last, pulses))
        shift = 0
        revs = own_revolutions(selfcal) if same else None
        if same and dev.shifts is not None and len(dev.shifts) == heads and revs is not None:
            own = (dev.shifts, k, revs, min(1.0, revs * m / max(pulses - 1, 1)))
        if not same:
            if fold.revs < 1:
                raise CaptureError(
                    "aligning a deviation curve from another capture needs at least one whole "
                    f"revolution of the head ({m} pulses); this one has {pulses}."
                )
            if heads >= 2:
                raise ConfigError(
                    "a deviation from another capture is aligned on a capture of several heads "
                    "by self-calibrating it, in memory: give --in-memory."
                )
            shift, correlation = _phase_shift(fold.folded(), deviation, m)
            accept_alignment(shift, correlation, notes)
    elif compensate and heads == 1:
        notes.append("one head and no self-calibration given: the rate is not compensated.")
    return _rate_result(
        chunks,
        pulses,
        m=m,
        heads=heads,
        k=k,
        use_all=False,
        label=column,
        selfcal=selfcal if compensate else None,
        made=made,
        deviation=deviation,
        shift=shift,
        correlation=correlation,
        own=own,
        average=average,
        set_rate_deg_s=set_rate_deg_s,
        allan_angles_deg=allan_angles_deg,
        specs=specs,
        notes=notes,
        keep_series=False,
        progress=progress,
        run_passes=rate_passes if runner is None else runner.rate,
    )
