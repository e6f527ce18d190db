"""Self-calibration of a multi-head encoder from pulse trains read in chunks (flat memory).

The same method and the same numbers as :func:`rotacal.encoder.selfcal.self_calibrate`
(Kokuyama et al. 2015, §3; the equal-division-averaged method of Masuda & Kajitani 1993), for
records too long to hold: 12 heads × 18,000 pulses × 3,000 revolutions are 6.5·10⁸ time stamps
(5 GB), and per-head-per-revolution arrays of the same size. Two passes over the heads:

1. every pulse train is checked and every head paired with head 0 in time
   (:func:`~rotacal.encoder.pulse_stream.pair_heads_streamed`);
2. block by block of whole revolutions: the head delays, the local rate (with the ±RATE_WINDOW
   pulses of context a block needs), the angle differences and the fit of each revolution for
   each sense of rotation tried. What the result needs is accumulated: the sum of the
   revolutions' curves, their spread per Fourier order (Chan's pairwise update of the mean and
   the sum of squared deviations), each revolution's mean head difference (R × (n − 1)
   numbers), the closure sums of squares, and the head differences of the first revolutions
   for the checks of the pulses per revolution. Each revolution's curve (R × m numbers, what the
   repeatability's peak-to-peak and the figure of the single revolutions need) goes to a
   temporary file that the result maps.

The heads' line shifts come from the mean head differences over the whole record; the second
pass starts with those of its first block and is run again in the rare case that the whole
record decides otherwise (a head within noise of half a pitch from its nominal place).
"""

from __future__ import annotations

import dataclasses
import math
import tempfile
from collections.abc import Callable, Iterable, Sequence
from typing import IO, Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from rotacal.encoder.pulse_stream import HeadStream, StreamedPairing, pair_heads_streamed
from rotacal.encoder.selfcal import (
    SelfCalibration,
    _assemble,
    _check_head0_length,
    _check_heads,
    _check_settings,
    _choose_sense,
    _Fitted,
    _pulses_per_rev_notes,
    _whole_revolutions,
    closure_check_pulses,
    period_check_pulses,
)
from rotacal.encoder.selfcal_checks import check_period
from rotacal.encoder.selfcal_fit import RATE_WINDOW, _data_shifts, fit_revolutions
from rotacal.errors import CaptureError
from rotacal.uncertainty import InstrumentSpecs

__all__ = ["self_calibrate_chunked"]

FloatArray = NDArray[np.float64]
#: Head-0 pulses per block of the second pass (rounded to whole revolutions): ~25 MB of delays
#: for 12 heads.
BLOCK_PULSES = 1 << 18

HeadChunks = Callable[[], Sequence[Iterable[ArrayLike]]]


class _Sense:
    """What the second pass accumulates for one sense of rotation."""

    def __init__(self, shifts: NDArray[np.int64], m: int, spill_dir: str | None) -> None:
        self.shifts = shifts
        self.ss: list[float] = []
        self.curve_sum = np.zeros(m)
        self.count = 0
        self.mean = np.zeros(m // 2 + 1, dtype=complex)
        self.spread = np.zeros(m // 2 + 1)
        self.spill: IO[bytes] = tempfile.TemporaryFile(dir=spill_dir)

    def add(self, a: NDArray[np.complex128], ss: float, m: int, roll: int) -> None:
        """Add the fitted orders ``a`` (shape (k, m//2 + 1)) of k more revolutions."""
        curves = np.fft.irfft(a, m, axis=-1)
        self.curve_sum += curves.sum(axis=0)
        self.ss.append(ss)
        # Chan et al. (1979): merge the block's mean and sum of squared deviations
        k = a.shape[0]
        mean_b = a.mean(axis=0)
        spread_b = np.sum(np.abs(a - mean_b) ** 2, axis=0)
        delta = mean_b - self.mean
        total = self.count + k
        self.spread += spread_b + np.abs(delta) ** 2 * (self.count * k / total)
        self.mean += delta * (k / total)
        self.count = total
        np.roll(curves, roll, axis=1).tofile(self.spill)

    def curves(self, m: int) -> FloatArray:
        """The spilled curves, shape (R, m), as a read-only memory map."""
        self.spill.flush()
        return np.memmap(self.spill, dtype=np.float64, mode="r", shape=(self.count, m))


@dataclasses.dataclass
class _Prefix:
    """Head differences of the first pulses, for the checks of the pulses per revolution."""

    mean: list[FloatArray] = dataclasses.field(default_factory=list)  # head-averaged
    diff: list[FloatArray] = dataclasses.field(default_factory=list)  # every head


def self_calibrate_chunked(
    head_chunks: HeadChunks,
    *,
    pulses_per_rev: int,
    rotation: Literal["auto", "forward", "reverse"] = "auto",
    specs: InstrumentSpecs | None = None,
    block_pulses: int = BLOCK_PULSES,
    spill_dir: str | None = None,
    progress: Callable[[int], None] | None = None,
) -> SelfCalibration:
    """:func:`~rotacal.encoder.selfcal.self_calibrate` from heads read in chunks, flat memory.

    Parameters
    ----------
    head_chunks : callable
        Called once per pass (twice, rarely three times) with no argument; returns one iterable
        per head (head 0 first) of its pulse times (s) in chunks of any lengths. Heads may have
        different lengths and start and stop at different times, as in ``self_calibrate``.
    pulses_per_rev, rotation, specs
        As :func:`~rotacal.encoder.selfcal.self_calibrate`.
    block_pulses : int
        Head-0 pulses per block of the fit (rounded down to whole revolutions, at least one).
    spill_dir : str, optional
        Directory of the temporary file of the single-revolution curves (R·m·8 bytes per sense
        of rotation tried; default: the system's temporary directory).
    progress : callable, optional
        Called with the time stamps processed so far (over both passes: twice the total).

    Returns
    -------
    SelfCalibration
        Equal to the in-memory result to rounding (every number of ``to_dict()``);
        ``per_revolution_arcsec`` is a read-only memory map of a temporary file.

    Raises
    ------
    CaptureError, ConfigError
        As ``self_calibrate``; a gap, a copy or a drifting head is refused when it is read. The
        drift check compares each head's delay with 0.75 of the median head-0 pulse interval of
        the block it is in (in memory: of the whole record).

    References
    ----------
    Kokuyama W. et al. (2015), §3; Masuda T., Kajitani M. (1993); Chan T. F., Golub G. H.,
    LeVeque R. J., "Updating formulae and a pairwise algorithm for computing sample
    variances", Stanford CS report STAN-CS-79-773 (1979).
    """
    m = _check_settings(pulses_per_rev, rotation, specs)
    heads = head_chunks()
    n = len(heads)
    _check_heads(n, m)
    names = [f"head_{i}" for i in range(n)]
    pairing = pair_heads_streamed(heads, names, progress)
    done = pairing.timestamps
    return finish_chunked(
        pairing,
        m,
        rotation,
        specs,
        lambda candidates, shifts: _fit_pass(
            head_chunks(),
            pairing,
            m,
            candidates,
            shifts,
            block_pulses,
            spill_dir,
            None if progress is None else (lambda k: progress(done + k)),
        ),
    )


Shifts = dict[str, NDArray[np.int64]]


@dataclasses.dataclass
class BlockFit:
    """One block's share of the second pass: each revolution's mean head difference
    (``offsets``, (k, n − 1)), the fit of each sense (orders (k, m//2 + 1), sum of squares),
    the heads' line shifts used and the head differences of the first pulses it holds."""

    shifts: Shifts
    offsets: FloatArray
    fits: dict[str, tuple[NDArray[np.complex128], float]]
    mean: FloatArray | None
    diff: FloatArray | None


def fit_blocks(pairing: StreamedPairing, m: int, block_pulses: int) -> list[tuple[int, int]]:
    """The blocks [p0, p1) of paired head-0 pulses of the second pass (whole revolutions of
    ``block_pulses`` rounded down, at least one)."""
    block = max(1, int(block_pulses) // m) * m
    total = pairing.pulses
    return [(p0, min(p0 + block, total)) for p0 in range(0, total, block)]


def fit_block(
    take: Callable[[int, int, int], FloatArray],
    pairing: StreamedPairing,
    m: int,
    candidates: list[str],
    shifts: Shifts | None,
    p0: int,
    p1: int,
) -> BlockFit:
    """The second pass over paired head-0 pulses [p0, p1): delays, local rate, angle
    differences and each whole revolution's fit (Kokuyama et al. 2015, §3), by the arithmetic
    of ``self_calibrate`` (the same bits).

    ``take(i, a, b)``: pulses a … b − 1 of head i (s). ``shifts``: the heads' line shifts per
    sense, or None to take them from this block's revolutions (the first block's).
    """
    n = pairing.index_offsets.size
    lo, total, off = pairing.first, pairing.pulses, pairing.index_offsets
    revs = total // m
    w = min(RATE_WINDOW, max(1, (total - 1) // 2))
    pitch = 360.0 / m
    # the rate at pulse p is taken over p ± w, clamped to the record's inner pulses
    c0 = min(max(p0, w), total - w - 1)
    c1 = min(max(p1 - 1, w), total - w - 1)
    q0, q1 = min(p0, c0 - w), max(p1, c1 + w + 1)
    t0 = take(0, lo + q0, lo + q1)
    delays = np.empty((n, q1 - q0))
    for i in range(n):
        delays[i] = take(i, lo + q0 + int(off[i]), lo + q1 + int(off[i])) - t0
    _check_drift(delays, t0, pairing)
    mean_times = t0 + delays.mean(axis=0)
    idx = np.clip(np.arange(p0, p1), w, total - w - 1) - q0
    rate = 2 * w * pitch / (mean_times[idx + w] - mean_times[idx - w])
    diff = delays[1:, p0 - q0 : p1 - q0] * (rate * 3600.0)  # arcsec, (n − 1, p1 − p0)
    del delays, mean_times, rate
    need_mean = min(total, period_check_pulses(m))
    need_diff = min(total, closure_check_pulses(m))
    mean = diff.mean(axis=0)[: need_mean - p0] if p0 < need_mean else None
    first = diff[:, : need_diff - p0].copy() if p0 < need_diff else None
    k = max(0, (min(p1, revs * m) - p0) // m)  # whole revolutions in this block
    used = diff[:, : k * m].reshape(n - 1, k, m).transpose(1, 0, 2)  # (k, n − 1, m)
    offsets = used.mean(axis=2)
    if shifts is None:
        mean0 = offsets.mean(axis=0)
        shifts = {c: _data_shifts(n, m, c, mean0) for c in candidates}
    fits = fit_revolutions(used, shifts, m) if k > 0 else {}
    return BlockFit(shifts, offsets, {c: (f[0], f[1]) for c, f in fits.items()}, mean, first)


class PassSums:
    """The second pass's blocks merged in order (what ``self_calibrate_chunked`` keeps)."""

    def __init__(self, pairing: StreamedPairing, m: int, spill_dir: str | None) -> None:
        self.m, self.roll, self.spill_dir = m, pairing.first % m, spill_dir
        self.senses: dict[str, _Sense] | None = None
        self.rev_offsets: list[FloatArray] = []
        self.prefix = _Prefix()

    @property
    def shifts(self) -> Shifts | None:
        """The line shifts the blocks after the first use (None before the first)."""
        return None if self.senses is None else {c: s.shifts for c, s in self.senses.items()}

    def add(self, block: BlockFit) -> None:
        """Merge the next block."""
        if block.mean is not None:
            self.prefix.mean.append(block.mean)
        if block.diff is not None:
            self.prefix.diff.append(block.diff)
        if not block.fits:
            return
        self.rev_offsets.append(block.offsets)
        if self.senses is None:
            self.senses = {c: _Sense(block.shifts[c], self.m, self.spill_dir) for c in block.fits}
        for c, (a, ss) in block.fits.items():
            self.senses[c].add(a, ss, self.m, self.roll)


def _fit_pass(
    heads: Sequence[Iterable[ArrayLike]],
    pairing: StreamedPairing,
    m: int,
    candidates: list[str],
    shifts: Shifts | None,
    block_pulses: int,
    spill_dir: str | None,
    progress: Callable[[int], None] | None,
) -> PassSums:
    """The second pass in one process: :func:`fit_block` over the blocks in order, the heads
    read once in order; ``shifts`` as there."""
    n = pairing.index_offsets.size
    if len(heads) != n:
        raise CaptureError(
            f"the capture gave {len(heads)} heads on its second reading, {n} on its first."
        )
    streams = [HeadStream(h, f"head_{i}", check=False) for i, h in enumerate(heads)]
    sums = PassSums(pairing, m, spill_dir)
    if shifts is not None:
        sums.senses = {c: _Sense(shifts[c], m, spill_dir) for c in candidates}
    for p0, p1 in fit_blocks(pairing, m, block_pulses):
        sums.add(
            fit_block(
                lambda i, a, b: streams[i].take(a, b), pairing, m, candidates, sums.shifts, p0, p1
            )
        )
        if progress is not None:
            progress(p1 * n)
    return sums


def finish_chunked(
    pairing: StreamedPairing,
    m: int,
    rotation: str,
    specs: InstrumentSpecs | None,
    run_pass: Callable[[list[str], Shifts | None], PassSums],
) -> SelfCalibration:
    """The second pass (``run_pass(candidates, shifts)``, again in the rare case that the whole
    record moves a head to another line) and the result, from the first pass's pairing."""
    n = pairing.index_offsets.size
    _check_head0_length(pairing.sizes[0], m)
    revs = _whole_revolutions(pairing.pulses, m, pairing.notes)
    candidates: list[str] = ["forward", "reverse"] if rotation == "auto" else [rotation]
    shifts: Shifts | None = None
    while True:
        sums = run_pass(candidates, shifts)
        senses = sums.senses
        assert senses is not None  # revs ≥ 1: the first block holds a whole revolution
        rev_offsets = np.concatenate(sums.rev_offsets)
        offsets_mean = rev_offsets.mean(axis=0)
        final = {c: _data_shifts(n, m, c, offsets_mean) for c in candidates}
        if all(np.array_equal(final[c], senses[c].shifts) for c in candidates):
            break
        for s in senses.values():
            s.spill.close()
        shifts = final  # the whole record places a head on another line: fit again with it
    prefix = sums.prefix
    head_mean = np.concatenate(prefix.mean)
    period_checked = check_period(head_mean, m)
    notes = list(pairing.notes)
    sense = _choose_sense({c: float(np.sum(senses[c].ss)) for c in candidates}, rotation, n, notes)
    _pulses_per_rev_notes(np.concatenate(prefix.diff, axis=1), m, period_checked, notes)
    chosen = senses[sense]
    for other in senses.values():
        if other is not chosen:
            other.spill.close()
    return _assemble(
        _Fitted(
            heads=n,
            pulses_per_rev=m,
            sense=sense,
            shifts=chosen.shifts,
            ss=math.fsum(chosen.ss),
            mean_curve=chosen.curve_sum / revs,
            per_rev=chosen.curves(m),
            spread=chosen.spread,
            rev_offsets=rev_offsets,
            first_paired=pairing.first,
            first_time_s=pairing.first_times_s[0],
            last_time_s=pairing.last_times_s[0],
            head0_pulses=pairing.sizes[0],
        ),
        notes,
        specs,
    )


def _check_drift(delays: FloatArray, t0: FloatArray, pairing: StreamedPairing) -> None:
    """Refuse a head whose paired pulse drifts away from head 0's (as ``pair_heads``; the
    pulse period is the median of head 0's intervals in this block)."""
    period = float(np.median(np.diff(t0)))
    worst = np.abs(delays).max(axis=1)
    bad = np.flatnonzero(worst > 0.75 * period)
    if bad.size:
        i = int(bad[0])
        jj = int(np.argmax(np.abs(delays[i])))
        raise CaptureError(
            f"column 'head_{i}' drifts against head_0: near t = {t0[jj]:.9g} s its paired pulse "
            f"is {worst[i] / period:.2f} pulse periods away, so it has a different number of "
            "pulses per revolution or lost/extra pulses; every head must read the same scale."
        )
