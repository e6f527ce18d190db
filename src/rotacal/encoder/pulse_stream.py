"""Pulse trains read in chunks: the checks of :func:`~rotacal.encoder.pulses.check_pulse_times`
with carried state, a buffered window over one head's pulses, and the pairing of every head with
head 0 in time (:func:`~rotacal.encoder.pulses.pair_heads`) over a whole record in one pass.

Each head comes as its own sequence of chunks of any lengths (heads are ragged: they start and
stop at different times); memory holds a few chunks per head, never a whole head.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Iterable, Iterator, Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray

from rotacal.encoder.pulses import (
    _PERIOD_BLOCK,
    _sorted_search,
    block_medians,
    check_heads_not_copies,
    pairing_notes,
    refuse_bad_intervals,
)
from rotacal.errors import CaptureError
from rotacal.signal._checks import TYPICAL_STEPS
from rotacal.signal._values import check_time_span

FloatArray = NDArray[np.float64]

#: Pulses of each head kept from its start for the check that no head copies head 0 (a copy is
#: head 0's times shifted by one constant; its first pulses show it as well as all of them).
COPY_CHECK_PULSES = 1 << 16

_EMPTY = np.zeros(0)


class TrainCheck:
    """:func:`~rotacal.encoder.pulses.check_pulse_times` over a pulse train fed in chunks.

    The same tests with the same local period: medians of blocks of 64 intervals, linearly
    interpolated between block centres (constant before the first centre and after the last),
    so an interval is judged once the median of the block after it is known. Raises at the
    first fault (the in-memory check counts every gap of the record first).
    """

    def __init__(self, name: str) -> None:
        self.name = name
        self.pulses = 0
        self.first = self.last = float("nan")
        self._typical: list[FloatArray] = []
        self._typical_n = 0
        self._carry = _EMPTY  # intervals of the block not yet complete
        self._meds = _EMPTY  # block medians from block self._med0 on
        self._med0 = 0
        self._pend = _EMPTY  # pulse times from pulse self._p0 on whose intervals are unjudged
        self._p0 = 0

    def feed(self, t: FloatArray) -> None:
        """Check the next pulses (s) of the train."""
        if t.ndim != 1:
            raise CaptureError(
                f"column '{self.name}' must be 1-D pulse times, got shape {t.shape}."
            )
        if t.size == 0:
            return
        bad = np.flatnonzero(~np.isfinite(t))
        if bad.size:
            raise CaptureError(
                f"column '{self.name}' has a NaN or inf at pulse {self.pulses + int(bad[0])}."
            )
        joined = t if self.pulses == 0 else np.concatenate(([self.last], t))
        dt = np.diff(joined)
        bad = np.flatnonzero(~(dt > 0))
        if bad.size:
            i = int(bad[0]) + max(self.pulses - 1, 0)
            a, b = joined[int(bad[0])], joined[int(bad[0]) + 1]
            raise CaptureError(
                f"column '{self.name}' is not strictly increasing at pulse {i + 1} "
                f"({a:.9g} s then {b:.9g} s); pulse times must be sorted and distinct."
            )
        if self.pulses == 0:
            self.first = float(t[0])
        self.pulses += t.size
        self.last = float(t[-1])
        if self._typical_n < TYPICAL_STEPS:
            take = dt[: TYPICAL_STEPS - self._typical_n]
            self._typical.append(take)
            self._typical_n += take.size
        c = np.concatenate((self._carry, dt))
        full = c.size // _PERIOD_BLOCK * _PERIOD_BLOCK
        meds = block_medians(c[:full])
        self._meds = np.concatenate((self._meds, meds))
        self._carry = c[full:]
        self._pend = (
            t if self._pend.size == 0 and self._p0 == 0 else np.concatenate((self._pend, t))
        )
        if self.pulses - 1 > 2 * _PERIOD_BLOCK:
            self._judge(final=False)

    def finish(self) -> None:
        """Check what the whole train decides: its length, time span and last intervals."""
        if self.pulses < 3:
            raise CaptureError(
                f"column '{self.name}' has {self.pulses} pulse(s); a pulse train needs more."
            )
        typical = float(np.median(np.concatenate(self._typical)))
        check_time_span(self.name, self.first, self.last, typical, "pulse interval")
        self._judge(final=True)

    def _judge(self, *, final: bool) -> None:
        size, half = _PERIOD_BLOCK, _PERIOD_BLOCK // 2
        intervals = self.pulses - 1
        known = self._med0 + self._meds.size  # blocks whose median is known
        last_centre = half + size * (known - 1)
        end = intervals if final else last_centre
        if end <= self._p0:
            return
        t = self._pend[: end - self._p0 + 1]
        dt = np.diff(t)
        if intervals <= 2 * size:  # a short train (final only): one median, as in memory
            period = np.full(dt.size, float(np.median(dt)))
        else:
            # the local period of rotacal.encoder.pulses._local_period, by the same operations
            # (the same bits): flat before the first block centre and after the last, else
            # rows of `size` intervals between two centres; self._p0 is 0 or half + k·size
            period = np.empty(dt.size)
            p = self._p0
            if p == 0:
                period[:half] = self._meds[0]
                p = half
            rows = (min(end, last_centre) - p) // size
            if rows > 0:
                b0 = (p - half) // size - self._med0
                meds = self._meds[b0 : b0 + rows + 1]
                slope = (meds[1:] - meds[:-1]) / float(size)
                inner = period[p - self._p0 : p - self._p0 + rows * size].reshape(rows, size)
                np.multiply(slope[:, None], np.arange(size, dtype=np.float64)[None, :], out=inner)
                inner += meds[:-1, None]
                p += rows * size
            period[p - self._p0 :] = self._meds[-1]  # after the last centre (final only)
        ratio = np.divide(dt, period, out=period)
        self._refuse(ratio, t, int(self._p0))
        self._pend = self._pend[end - self._p0 :].copy()
        self._p0 = end
        keep = max(0, (end - half) // size) - self._med0
        if keep > 0:
            self._meds = self._meds[keep:].copy()
            self._med0 += keep

    def _refuse(self, ratio: FloatArray, t: FloatArray, first: int) -> None:
        refuse_bad_intervals(self.name, ratio, t, first)


class HeadStream:
    """A window over one head's pulses, read chunk by chunk (each chunk checked on arrival).

    ``buf`` holds pulses ``start … start + buf.size − 1``; ``prefix`` the first
    COPY_CHECK_PULSES of the head. ``check=False``: a train already checked (no checks, no
    prefix).
    """

    def __init__(self, chunks: Iterable[ArrayLike], name: str, *, check: bool = True) -> None:
        self._it: Iterator[ArrayLike] = iter(chunks)
        self.check = TrainCheck(name)
        self._checking = check
        self.buf = _EMPTY
        self.start = 0
        self.done = False
        self.prefix = _EMPTY
        self.read = 0  # pulses read so far

    def pull(self) -> bool:
        """Read the next chunk into the window; False at the end of the head."""
        if self.done:
            return False
        raw = next(self._it, None)
        if raw is None:
            self.done = True
            if self._checking:
                self.check.finish()
            return False
        # a copy: the reader may hand back the pages of a memory-mapped chunk once it moves on
        chunk = np.array(raw, dtype=np.float64)
        if self._checking:
            self.check.feed(chunk)
        if self._checking and self.prefix.size < COPY_CHECK_PULSES:
            self.prefix = np.concatenate(
                (self.prefix, chunk[: COPY_CHECK_PULSES - self.prefix.size])
            )
        if self.buf.size == 0:
            self.buf, self.start = chunk, self.read
        else:
            self.buf = np.concatenate((self.buf, chunk))
        self.read += chunk.size
        return True

    def drop_before(self, k: int) -> None:
        """Forget the pulses before pulse ``k``."""
        cut = min(max(k - self.start, 0), self.buf.size)
        if cut:
            self.buf = self.buf[cut:].copy()
            self.start += cut

    def take(self, a: int, b: int) -> FloatArray:
        """Pulses a … b − 1 (a at or after the window's start; b within the head)."""
        while self.start + self.buf.size < b and self.pull():
            pass
        if self.start + self.buf.size < b or a < self.start:
            raise CaptureError(
                f"column '{self.check.name}' ended while pulse {b - 1} was needed; the heads "
                "changed between two readings of the capture."
            )
        self.drop_before(a)
        return self.buf[: b - a]

    def until_time(self, t: float, keep_from: float) -> None:
        """Read until the window holds a pulse after ``t`` s (or the head ends), keeping the
        pulses from the last one before ``keep_from`` s on."""
        while (self.buf.size == 0 or self.buf[-1] <= t) and self.pull():
            self.keep_after(keep_from)

    def keep_after(self, t: float) -> None:
        """Forget the pulses before the last one before ``t`` s."""
        keep = int(np.searchsorted(self.buf, t)) - 1
        self.drop_before(self.start + max(keep, 0))

    def drain(self) -> None:
        """Read (and check) the rest of the head."""
        while self.pull():
            self.buf = _EMPTY
            self.start = self.read


@dataclasses.dataclass(frozen=True)
class StreamedPairing:
    """The pairing of :func:`~rotacal.encoder.pulses.pair_heads` without the per-pulse arrays.

    ``index_offsets``, ``first``, ``stop`` and ``notes`` as there; ``sizes``, ``first_times_s``
    and ``last_times_s`` per head; ``timestamps``: pulses of all heads.
    """

    index_offsets: NDArray[np.int64]
    first: int
    stop: int
    sizes: list[int]
    first_times_s: list[float]
    last_times_s: list[float]
    notes: tuple[str, ...]

    @property
    def pulses(self) -> int:
        return self.stop - self.first

    @property
    def timestamps(self) -> int:
        return sum(self.sizes)


def _mode_of(counts: dict[int, int]) -> int:
    """The most frequent value (the smallest of equally frequent ones), as pair_heads takes it."""
    best = max(counts.values())
    return min(k for k, c in counts.items() if c == best)


def pair_heads_streamed(
    heads: Sequence[Iterable[ArrayLike]],
    names: Sequence[str],
    progress: Callable[[int], None] | None = None,
) -> StreamedPairing:
    """Check every head's pulse train and pair it with head 0 in time, in one pass of chunks.

    The same pairing as :func:`~rotacal.encoder.pulses.pair_heads` (Kokuyama et al. 2015, §3:
    the heads are compared at the same instant): for every head-0 pulse inside head i's record,
    the nearest pulse of head i; the head's index offset is the most frequent difference over
    the whole record. Every head is checked as :func:`check_pulse_times` checks it, and no head
    may copy head 0 (:func:`check_heads_not_copies`, on the first COPY_CHECK_PULSES of each).

    Parameters
    ----------
    heads : sequence of iterables of array_like, s
        Each head's pulse times in chunks of any lengths, head 0 first.
    names : sequence of str
        Column names for messages.
    progress : callable, optional
        Called with the pulses read so far (all heads).

    Raises
    ------
    CaptureError
        As :func:`check_pulse_times`, :func:`check_heads_not_copies` and :func:`pair_heads`.
    """
    counts, checks, prefixes = pair_with_head0(heads[0], heads[1:], names, progress=progress)
    return finish_pairing(names, checks, prefixes, counts)


def finish_pairing(
    names: Sequence[str],
    checks: Sequence[TrainCheck],
    prefixes: Sequence[FloatArray],
    counts: Sequence[dict[int, int]],
) -> StreamedPairing:
    """The pairing from what one pass over the heads gathered: each head's checked train, its
    first COPY_CHECK_PULSES and, for head i ≥ 1, the counts of its index differences to head 0
    (:func:`pair_heads_streamed`'s last step; the refusals of :func:`pair_heads`)."""
    check_heads_not_copies(list(prefixes), names)
    c0 = checks[0]
    offsets = np.zeros(len(checks), dtype=np.int64)
    lo, hi = 0, c0.pulses
    for i in range(1, len(checks)):
        ci = checks[i]
        if ci.last < c0.first or ci.first > c0.last or not counts[i]:
            raise CaptureError(
                f"column '{names[i]}' ({ci.first:.6g}–{ci.last:.6g} s) does not overlap head_0 "
                f"({c0.first:.6g}–{c0.last:.6g} s) in time; the heads must be recorded together."
            )
        offsets[i] = _mode_of(counts[i])
        lo = max(lo, -int(offsets[i]))
        hi = min(hi, ci.pulses - int(offsets[i]))
    if hi - lo < 2:
        raise CaptureError(
            "the heads overlap for fewer than 2 pulses of head_0; record all heads together."
        )
    spans = [(c.first, c.last, c.pulses) for c in checks]
    return StreamedPairing(
        index_offsets=offsets,
        first=lo,
        stop=hi,
        sizes=[c.pulses for c in checks],
        first_times_s=[c.first for c in checks],
        last_times_s=[c.last for c in checks],
        notes=tuple(pairing_notes(names, spans, offsets, lo, hi)),
    )


def pair_with_head0(
    head0: Iterable[ArrayLike],
    heads: Sequence[Iterable[ArrayLike]],
    names: Sequence[str],
    *,
    check_head0: bool = True,
    progress: Callable[[int], None] | None = None,
) -> tuple[list[dict[int, int]], list[TrainCheck], list[FloatArray]]:
    """The pass of :func:`pair_heads_streamed` over head 0 and ``heads`` (all the others, or
    some of them: each head's counts depend on head 0's chunks and its own alone): every train
    checked (head 0's when ``check_head0``) and, per head i, the counts of its index
    differences to head 0. ``names``: head 0's then the heads'. Returns the counts (head 0's
    empty), the checks and the first COPY_CHECK_PULSES of each head, head 0 first (unchecked:
    an empty prefix)."""
    s0 = HeadStream(head0, names[0], check=check_head0)
    streams = [HeadStream(h, name) for h, name in zip(heads, names[1:], strict=True)]
    counts: list[dict[int, int]] = [{} for _ in streams]
    while s0.pull():
        for si, ci in zip(streams, counts, strict=True):
            _nearest_offsets(si, s0.buf, s0.start, ci)
        s0.drop_before(s0.read)
        if progress is not None:
            progress(s0.read + sum(s.read for s in streams))
    for s in streams:
        s.drain()
    if progress is not None:
        progress(s0.read + sum(s.read for s in streams))
    every = [s0, *streams]
    return [{}, *counts], [s.check for s in every], [s.prefix for s in every]


def _nearest_offsets(si: HeadStream, t0: FloatArray, j0: int, counts: dict[int, int]) -> None:
    """Count, for the head-0 pulses ``t0`` (indices from ``j0``) inside head i's record, the
    index difference to head i's nearest pulse (as :func:`pair_heads`)."""
    si.until_time(float(t0[-1]), float(t0[0]))
    if si.buf.size == 0:
        return
    first_i = si.check.first
    last_i = si.buf[-1] if si.done else np.inf  # not done: a later pulse of head i exists
    # t0 increases: the pulses inside head i's record are one run of them
    a = int(np.searchsorted(t0, first_i, side="left"))
    b = int(np.searchsorted(t0, last_i, side="right"))
    if b > a:
        q = t0[a:b]
        local = _sorted_search(si.buf, q)
        np.maximum(local, 1 - si.start, out=local)  # pair_heads clips at the record's pulse 1
        nearer_left = (q - si.buf[local - 1]) < (si.buf[local] - q)
        diff = local - nearer_left  # the nearest pulse (window index)
        diff -= np.arange(b - a)
        diff += si.start - j0 - a  # − the head-0 pulse's index
        low, high = int(diff.min()), int(diff.max())
        if high - low <= 4 * diff.size:  # nearly always one or two values: count, not sort
            n = np.bincount(diff - low)
            values = np.flatnonzero(n)
            n, values = n[values], values + low
        else:
            values, n = np.unique(diff, return_counts=True)
        for v, c in zip(values.tolist(), n.tolist(), strict=True):
            counts[v] = counts.get(v, 0) + c
    # the next head-0 pulses come after this chunk's last one
    si.keep_after(float(t0[-1]))
