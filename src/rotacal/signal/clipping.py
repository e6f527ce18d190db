"""Samples at the rails: one detector of clipped (saturated) signals for every capture analysis.

A sensor or an ADC that reaches the end of its range reports its rail value instead of the signal:
the column then holds runs of one identical value at its maximum (or minimum), and every amplitude,
THD, scale factor or noise figure computed from it is wrong. :func:`find_clipping` finds such rails
in one column; :class:`RailDetector` does the same over a column fed in chunks (its state is
carried from chunk to chunk, so a streamed capture gives the very same finding as the whole array);
:func:`check_clipping` is what an analysis calls at its entry: it refuses the capture with one line
(:class:`ClippedSignalError`) or, when the user allows clipping, returns the warning lines for the
result's ``warnings``.

The rule
--------
For the column's maximum e (and likewise its minimum) let

* ``c_e`` — samples exactly equal to e; ``L_e`` — the longest run of consecutive samples at e;
* ``c_next`` — samples at the next distinct value inward (the largest value below e);
* ``c_mode`` — samples of the most frequent value other than the two extremes (counted on an
  evenly strided subsample of at most 2¹⁸ samples and scaled by the stride);
* ``L_ref`` — the longest run of identical consecutive samples at any value but the extremes.

e is a rail when ``c_e ≥ 8·c_next`` and at least one of

* (count) ``c_e ≥ 8·max(c_next, c_mode)`` — the extreme holds far more samples than any other
  value: a clipped noisy or unordered signal (FOG, LTS, multiposition rows), whose samples at the
  rail need not be consecutive;
* (run) ``L_e ≥ 8·L_ref`` — the signal stays at the extreme far longer than at any other value:
  a clipped plateau of a coarsely quantised output, whose other levels also hold many samples.

Why 8 separates honest data from clipped data:

* A smooth extreme of a sampled signal (a sine's peak, x ≈ e − κt²) quantised with step q puts at
  most 1/(√2 − 1) = 2.4 times as many samples in its top level as in the next one (the time in the
  top level grows as √p, in the next one as √(p + q) − √p, p ≤ q being the peak's height in its
  level). A flatter extreme (x ≈ e − κt⁴: an encoder channel whose table reverses where the
  channel peaks, the longest honest dwell there is) gives at most 1/(2^¼ − 1) = 5.3. Both hold for
  any quantum, sampling rate and motion; noise spreads the top level further.
* An unquantised signal with noise holds each value once; a noise tail thins out towards the
  extreme.
* A coarsely quantised output whose levels are plateaus (a rate-table test with little noise, a
  set rate repeating) holds about as many samples, in runs as long, at every plateau.
* A rail is reached with a slope: the level just inside it is crossed in a few samples while the
  rail holds the whole excursion beyond it, so ``c_e/c_next`` grows with the clipped share (about
  α·sin α/q for a sine of unit amplitude clipped at cos α, quantum q).

What the analysis knows refines this (keywords of :func:`find_clipping`):

* ``companion`` (a quadrature encoder: the other channel) — a channel sitting at its extreme while
  the other one does not move (spans less than 5 % of its range over those rows) is a table at
  rest where the channel peaks, not a rail; a clipped channel sits at its rail while the other one
  sweeps ±sin α of its amplitude.
* ``rest`` (rows where the sensor is known to be at rest: a gyro's static sections or zero set
  rate) — the level the output shows at rest is where a one-way motion starts, not a rail.
* ``groups`` (rows measured at one set condition: a rate point) — the points, not the column, are
  then the reference: they may hold any number of samples each, and a noise-free output is flat
  at every point. Within a point the output is a plateau with Gaussian noise, whose top level
  holds fewer samples than the next one. A point of ≥ 10 samples is clipped when its samples pile
  up at the extreme (≥ 10 and ≥ 5 % of them, more than 1.5 times the next level inward, its noise
  resolved in ≥ 6 levels) or sit all at it while the other points span ≥ 4 levels each (their
  noise shows; a rail has none). This finds a noisy plateau cut by a rail near its mean, which
  the column's counts miss. On 28 800 simulated Gaussian points (quantum 0.05σ–4σ, 10–5000
  samples) the pile test never fired; it finds a rail within ±0.5σ of a point's mean when the
  quantum is ≤ σ/2. Points of fewer than 10 samples (per-point means) leave the decision to the
  column's rule.

Not judged (``None``): a column with fewer than three distinct finite values (a constant column is
another check's business; a two-level column is digital); non-finite samples are skipped (rows keep
their numbers). Not applied to pulse timestamps (``selfcal``, ``rate``): a time stamp is not a
reading with a range. Measured (``benchmarks/bench_clipping.py``): no false call on any twin kind
(encoder at 8–16 bits, stagnating or moving less than a line; LTS; FOG to 7.7 dB; gyro outputs
with coarse quanta, repeated rates, rest at an extreme) or on the 159 rate, gyro and frequency
columns of the real recordings; every clipped twin called, with its share.

Limits: a rail on a signal quantised so coarsely that its own top level holds a comparable share
(a sine clipped at 95 % of its amplitude: about 8 bits or fewer over the signal's range) is not
told from quantisation; a noise-free quantised output that stays at its extreme 8 times longer
than anywhere else, with no rest rows, points or companion to tell, is called clipped; a rail
that holds fewer samples than 8 times the busiest other value and has no longer runs (a few rows
of per-point means) is not found.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from typing import Any

import numpy as np

from rotacal._jit import use_numba
from rotacal.errors import CaptureError
from rotacal.signal._values import LARGEST, SMALLEST

__all__ = [
    "RAIL_RATIO",
    "ClippedSignalError",
    "Clipping",
    "Rail",
    "RailDetector",
    "check_clipping",
    "find_clipping",
    "find_quadrature_clipping",
    "quadrature_rail_detectors",
]

#: How many times more samples (or a longer stay) a rail holds than the honest reference.
RAIL_RATIO = 8.0
#: A channel at its extreme while its quadrature companion spans less than this share of its
#: range over those rows is at rest, not clipped.
COMPANION_SPAN = 0.05
#: Samples processed at a time (fits the CPU cache; bounds the temporaries).
_PIECE = 1 << 16
#: Largest subsample kept for the most frequent value (evenly strided, power-of-two stride).
_SUBSAMPLE = 1 << 18
# Grouped rule (see the module docstring): a point of at least _GROUP_MIN samples whose noise
# is resolved (≥ _GROUP_RESOLVED_LEVELS levels) piles ≥ 5 % of them at the extreme, more than
# 1.5 times the next level; or sits all at it while the other points span ≥ 4 levels each.
_GROUP_MIN = 10
_GROUP_PILE_FRACTION = 0.05
_GROUP_PILE_RATIO = 1.5
_GROUP_RESOLVED_LEVELS = 6
_GROUP_NOISY_LEVELS = 4


@dataclasses.dataclass(frozen=True)
class Rail:
    """One rail of a clipped column.

    Attributes
    ----------
    side : "maximum" or "minimum"
    value : float — the rail value (the column's unit).
    samples : int — samples exactly at it.
    first_row : int — index of the first of them (counted from 0).
    longest_run : int — the longest run of consecutive samples at it.
    """

    side: str
    value: float
    samples: int
    first_row: int
    longest_run: int


@dataclasses.dataclass(frozen=True)
class Clipping:
    """The rails found in one column (see :func:`find_clipping`)."""

    column: str
    samples: int
    rails: tuple[Rail, ...]

    @property
    def share(self) -> float:
        """Fraction of the column's (finite) samples at its rails."""
        return sum(r.samples for r in self.rails) / self.samples

    def describe(self) -> str:
        """``column 'x' is clipped …: 12.3 % of its N samples sit at its rails (…)``."""
        where = "; ".join(
            f"{_percent(r.samples / self.samples)} at the {r.side} {r.value:.6g} from row "
            f"{r.first_row}"
            for r in self.rails
        )
        where += "; rows counted from 0"
        noun = "rails" if len(self.rails) > 1 else "rail"
        return (
            f"column '{self.column}' is clipped (a saturated sensor or ADC): "
            f"{_percent(self.share)} of its {self.samples} samples sit at its {noun} ({where})"
        )

    def refusal(self) -> str:
        """The one-line refusal: what is wrong and what to do."""
        return (
            f"{self.describe()}; use a record that stays within the sensor's range, or "
            "--allow-clipped to analyse it anyway."
        )

    def warning(self) -> str:
        """The warning line when the user analyses the column anyway."""
        return (
            f"{self.describe()}; analysed anyway (--allow-clipped): the results are biased by "
            "the clipping."
        )


class ClippedSignalError(CaptureError):
    """A column of the capture is clipped; ``clippings`` holds what was found."""

    def __init__(self, message: str, clippings: tuple[Clipping, ...] = ()) -> None:
        super().__init__(message)
        self.clippings = clippings


def _percent(share: float) -> str:
    pct = 100.0 * share
    return f"{pct:.1f} %" if pct >= 0.1 else f"{pct:.2g} %"


class _Side:
    """State of one end of the column (the maximum, or the minimum through ``sign``)."""

    __slots__ = (
        "comp_hi",
        "comp_lo",
        "count",
        "first",
        "next_count",
        "next_value",
        "run",
        "sign",
        "value",
    )

    def __init__(self, sign: float) -> None:
        self.sign = sign  # +1: the maximum; −1: the minimum (values compared as sign·x)
        self.value = -math.inf  # the extreme so far, as sign·x
        self.count = 0
        self.first = -1
        self.run = 0  # longest run at the extreme so far
        self.next_value = -math.inf  # the next distinct value inward, as sign·x
        self.next_count = 0
        self.comp_lo = math.inf  # the companion's range over the rows at the extreme
        self.comp_hi = -math.inf

    def merge(
        self, top: float, k_top: int, first: int, second: float, k_second: int, comp: tuple
    ) -> int:
        """Fold a piece's two largest distinct values (as sign·x) in; return a demoted run."""
        demoted = 0
        if top > self.value:
            if second > self.value:
                self.next_value, self.next_count = second, k_second
            elif second == self.value:
                self.next_value, self.next_count = second, k_second + self.count
            else:
                self.next_value, self.next_count = self.value, self.count
            demoted, self.run = self.run, 0
            self.value, self.count, self.first = top, k_top, first
            self.comp_lo, self.comp_hi = comp
        elif top == self.value:
            self.count += k_top
            self.comp_lo, self.comp_hi = min(self.comp_lo, comp[0]), max(self.comp_hi, comp[1])
            if second > self.next_value:
                self.next_value, self.next_count = second, k_second
            elif second == self.next_value:
                self.next_count += k_second
        elif top > self.next_value:
            self.next_value, self.next_count = top, k_top
        elif top == self.next_value:
            self.next_count += k_top
        return demoted


def _range(x: np.ndarray) -> tuple[float, float]:
    """(min, max) of the finite values of ``x``; (inf, −inf) when there are none."""
    lo, hi, _ = _finite_range(x)
    return lo, hi


def _finite_range(x: np.ndarray) -> tuple[float, float, bool]:
    """:func:`_range` of ``x`` and whether all its values are finite."""
    if x.size == 0:
        return math.inf, -math.inf, True
    lo, hi = float(x.min()), float(x.max())
    if math.isfinite(lo) and math.isfinite(hi):
        return lo, hi, True
    xf = x[np.isfinite(x)]
    return (float(xf.min()), float(xf.max()), False) if xf.size else (math.inf, -math.inf, False)


def _final_stride(rows: int) -> int:
    """The stride of the subsample once ``rows`` rows are fed: the smallest power of two that
    leaves at most ``_SUBSAMPLE`` of them (what :meth:`RailDetector._subsample`'s halving ends
    at, whatever the chunking)."""
    stride = 1
    while -(-rows // stride) > _SUBSAMPLE:
        stride *= 2
    return stride


class RailDetector:
    """Finds the rails of one column fed in chunks, in row order (see the module docstring).

    ``add(values)`` as often as needed, then ``result()``. Feeding the whole column at once or in
    any chunking gives the same result.

    Parameters
    ----------
    column : str — the column's name, for the messages.
    rows : int, optional — the column's length, when known before it is fed: the subsample then
        starts at its final stride (the same samples kept, without thinning them again and again).
    start : int, optional — the row of the first sample fed, when this detector sees one block
        of a column split over several processes: :meth:`merge` then folds it into the
        detector of the rows before it (``rows`` is required: every block keeps the same rows).
    """

    def __init__(self, column: str, rows: int | None = None, *, start: int | None = None) -> None:
        self.column = column
        self._n = 0 if start is None else int(start)  # samples fed (finite or not): row numbers
        self._start = self._n
        # a block's first run (value, length, whether it spans every sample fed so far): the
        # run continues the one the rows before left open, which the block cannot see
        self._lead: tuple[float, int, bool] | None = None
        if start is not None:
            if rows is None:
                raise ValueError("a block's RailDetector needs the column's length (rows)")
            self._lead = (math.nan, 0, True)
        self._finite = 0
        self._hi = _Side(1.0)
        self._lo = _Side(-1.0)
        self._elsewhere_run = 0  # longest run at a value that is neither extreme
        self._open_value = math.nan  # the run still open at the end of the last piece
        self._open_len = 0
        self._stride = 1 if rows is None else _final_stride(rows)
        self._kept: list[np.ndarray] = []
        self._kept_n = 0
        self._comp_lo = math.inf  # the companion's range over the whole column
        self._comp_hi = -math.inf
        self._with_companion = False

    # ---------------------------------------------------------------------------------- feeding
    def add(self, values: Any, companion: Any = None) -> None:
        """Feed the next samples of the column (1-D, any real dtype), with the same rows of the
        quadrature companion when there is one (it must be given with every chunk, or never)."""
        x = np.asarray(values, dtype=np.float64).reshape(-1)
        c = None
        if companion is not None:
            c = np.asarray(companion, dtype=np.float64).reshape(-1)
            if c.size != x.size:
                raise CaptureError(
                    f"column '{self.column}' and its companion differ in length ({x.size} and "
                    f"{c.size} samples); they must be sampled together."
                )
            self._with_companion = True
        if self._lead is not None and self._lead[2] and x.size:
            self._extend_lead(x)
        for s in range(0, x.size, _PIECE):
            self._add_piece(x[s : s + _PIECE], None if c is None else c[s : s + _PIECE])

    def _extend_lead(self, x: np.ndarray) -> None:
        """Grow the block's first run by the samples of ``x`` equal to it (block mode only)."""
        value, length, _ = self._lead  # type: ignore[misc]
        if length == 0:
            value = float(x[0])
        differ = x != value  # NaN differs from everything: it never extends a run
        i = int(np.argmax(differ))
        self._lead = (value, length + i, False) if differ[i] else (value, length + x.size, True)

    def merge(self, later: RailDetector) -> None:
        """Fold in ``later``, a detector of the rows that follow this one's (made with
        ``start`` = this one's rows fed, and the same ``rows``): the state becomes the one a
        single detector fed both in order reaches, for finite samples (NaN or inf never form a
        run, and a column holding them is refused by the analyses before rails are judged).

        Why this is exact: the extremes and the next values inward are the two largest distinct
        values with their counts, which merge as in :meth:`_Side.merge`; a run counts at an
        extreme when its value is the final extreme and elsewhere otherwise (a run listed at an
        extreme that is later passed is demoted), so ``later``'s runs move with their values;
        the run open at the end of this one joins ``later``'s first run when they share a value;
        the subsample keeps the rows that are multiples of the one final stride.
        """
        if later._lead is None or later._start != self._n or later._stride != self._stride:
            raise ValueError("merge needs the detector of the rows that follow, made with start")
        for mine, theirs in ((self._hi, later._hi), (self._lo, later._lo)):
            demoted = mine.merge(
                theirs.value,
                theirs.count,
                theirs.first,
                theirs.next_value,
                theirs.next_count,
                (theirs.comp_lo, theirs.comp_hi),
            )
            if theirs.value == mine.value:
                mine.run = max(mine.run, theirs.run)
            else:
                demoted = max(demoted, theirs.run)
            self._elsewhere_run = max(self._elsewhere_run, demoted, later._elsewhere_run)
        value, length, whole = later._lead
        joins = self._open_len > 0 and length > 0 and value == self._open_value
        if self._lead is not None and self._lead[2]:  # this one is a single run so far
            first, count, _ = self._lead
            self._lead = (
                later._lead
                if count == 0
                else (first, count + length, whole)
                if joins
                else (first, count, False)
            )
        if joins and whole:  # later is one run, continuing the open one: it stays open
            self._open_len += length
        else:
            if joins:
                self._classify(np.array([value]), np.array([self._open_len + length]))
                self._open_len = 0
            self._close_open_run()
            self._open_value, self._open_len = later._open_value, later._open_len
        self._n, self._finite = later._n, self._finite + later._finite
        self._kept += later._kept
        self._kept_n += later._kept_n
        self._comp_lo = min(self._comp_lo, later._comp_lo)
        self._comp_hi = max(self._comp_hi, later._comp_hi)
        self._with_companion = self._with_companion or later._with_companion

    def _add_piece(
        self,
        x: np.ndarray,
        comp: np.ndarray | None,
        ranges: tuple[tuple[float, float, bool], tuple[float, float]] | None = None,
    ) -> None:
        """One piece; ``ranges`` = (:func:`_finite_range` of x, :func:`_range` of comp) when
        the caller has them already (a quadrature pair: each channel's is the other's)."""
        g0 = self._n
        self._n += x.size
        if x.size == 0:
            return
        lo, hi, clean = _finite_range(x) if ranges is None else ranges[0]
        xf = x
        if not clean:  # NaN or inf: judge the finite ones
            xf = x[np.isfinite(x)]
            if xf.size == 0:
                self._close_open_run()
                return
        self._finite += xf.size
        self._subsample(x, g0)
        if comp is not None:
            c_lo, c_hi = _range(comp) if ranges is None else ranges[1]
            self._comp_lo, self._comp_hi = min(self._comp_lo, c_lo), max(self._comp_hi, c_hi)
        for side, top in ((self._hi, hi), (self._lo, lo)):
            if side.sign * top < side.next_value:
                continue  # below both of the two largest values so far: nothing to add
            at = x == top
            k = int(np.count_nonzero(at))
            first = g0 + int(np.argmax(at))
            if side.sign > 0:
                second = float(np.max(xf, where=xf < top, initial=-math.inf))
            else:
                second = float(np.min(xf, where=xf > top, initial=math.inf))
            k2 = int(np.count_nonzero(xf == second)) if math.isfinite(second) else 0
            span = _range(comp[at]) if comp is not None else (math.inf, -math.inf)
            demoted = side.merge(side.sign * top, k, first, side.sign * second, k2, span)
            self._elsewhere_run = max(self._elsewhere_run, demoted)
        self._runs(x)

    def _subsample(self, x: np.ndarray, g0: int) -> None:
        """Keep the samples whose row is a multiple of the stride; double it when too many."""
        self._kept.append(x[(-g0) % self._stride :: self._stride].copy())
        self._kept_n += self._kept[-1].size
        while self._kept_n > _SUBSAMPLE:
            kept = np.concatenate(self._kept)[::2]
            self._kept, self._kept_n = [kept], kept.size
            self._stride *= 2

    def _runs(self, x: np.ndarray) -> None:
        """Runs of identical consecutive samples: at the extremes, and the longest elsewhere.

        Only runs of two or more samples are listed (a float column has none); the piece's first
        run continues the one left open by the previous piece, its last one stays open.
        """
        same = np.flatnonzero(x[1:] == x[:-1])  # x[i + 1] == x[i]
        if same.size == 0 and not (self._open_len and x[0] == self._open_value):
            # no run of two or more in the piece nor across its start (a float column's usual
            # case): only the open run closes, and the last sample opens the next one
            self._close_open_run()
            self._open_value, self._open_len = float(x[-1]), 1
            return
        breaks = np.flatnonzero(np.diff(same) != 1)
        starts = same[np.concatenate(([0], breaks + 1))] if same.size else same
        ends = same[np.concatenate((breaks, [same.size - 1]))] + 1 if same.size else same
        if not (starts.size and starts[0] == 0):  # the first sample is a run of its own
            starts = np.concatenate(([0], starts))
            ends = np.concatenate(([0], ends))
        lens = (ends - starts + 1).astype(np.int64)
        vals = x[starts]
        if self._open_len and x[0] == self._open_value:
            lens[0] += self._open_len
        else:
            self._close_open_run()
        last = x.size - 1
        if ends[-1] == last:
            self._open_value, self._open_len = float(vals[-1]), int(lens[-1])
            vals, lens = vals[:-1], lens[:-1]
        else:
            self._open_value, self._open_len = float(x[last]), 1
        self._classify(vals, lens)

    def _close_open_run(self) -> None:
        # a run of one sample changes no verdict: every use of a run length takes max(run, 1)
        if self._open_len > 1:
            self._classify(np.array([self._open_value]), np.array([self._open_len]))
        self._open_value, self._open_len = math.nan, 0

    def _classify(self, vals: np.ndarray, lens: np.ndarray) -> None:
        if vals.size == 0:
            return
        at_hi = vals == self._hi.value
        at_lo = vals == -self._lo.value
        if at_hi.any():
            self._hi.run = max(self._hi.run, int(lens[at_hi].max()))
        if at_lo.any():
            self._lo.run = max(self._lo.run, int(lens[at_lo].max()))
        other = ~(at_hi | at_lo) & np.isfinite(vals)
        if other.any():
            self._elsewhere_run = max(self._elsewhere_run, int(lens[other].max()))

    # ---------------------------------------------------------------------------------- verdict
    def extremes(self) -> list[tuple[Rail, bool]]:
        """Both extremes as :class:`Rail` candidates with the rule's verdict on each; empty when
        the column is not judged (fewer than three distinct finite values)."""
        self._close_open_run()
        hi, lo = self._hi, self._lo
        if self._finite == 0 or hi.next_count == 0 or hi.next_value <= -lo.value:
            return []
        out = []
        for side in (hi, lo):
            rail = Rail(
                side="maximum" if side.sign > 0 else "minimum",
                value=side.sign * side.value,
                samples=side.count,
                first_row=side.first,
                longest_run=max(side.run, 1),
            )
            out.append((rail, self._verdict(side)))
        return out

    def in_working_range(self) -> bool:
        """Whether every sample fed was finite and the largest magnitude is 0 or within
        [SMALLEST, LARGEST] (:mod:`rotacal.signal._values`): the column then passes
        :func:`~rotacal.signal._values.check_magnitudes`, whose pass over it a caller holding
        this detector can spare (False: run it, it names the fault)."""
        if self._lead is not None or self._finite == 0 or self._finite != self._n:
            return False
        big = max(abs(self._hi.value), abs(self._lo.value))
        return big == 0.0 or SMALLEST <= big <= LARGEST

    def _verdict(self, side: _Side) -> bool:
        if side.count < RAIL_RATIO * side.next_count:
            return False  # the extreme of a smooth peak or of a noise tail
        if self._with_companion:
            full = self._comp_hi - self._comp_lo
            if not side.comp_hi - side.comp_lo >= COMPANION_SPAN * full:
                return False  # at rest where this channel peaks: the other one stands still
        if side.count >= RAIL_RATIO * max(side.next_count, self._mode_elsewhere()):
            return True
        return max(side.run, 1) >= RAIL_RATIO * max(self._elsewhere_run, 1)

    def result(self) -> Clipping | None:
        """The rails found, or None (not clipped, or not judged: see the module docstring)."""
        rails = tuple(rail for rail, ok in self.extremes() if ok)
        return Clipping(self.column, self._finite, rails) if rails else None

    def _ratios(self) -> dict[str, tuple[float, float, float]]:
        """For benchmarks: per side, (c_e/c_next, c_e/max(c_next, c_mode), L_e/L_ref)."""
        self._close_open_run()
        hi, lo = self._hi, self._lo
        if self._finite == 0 or hi.next_count == 0 or hi.next_value <= -lo.value:
            return {}
        mode = self._mode_elsewhere()
        return {
            name: (
                side.count / side.next_count,
                side.count / max(side.next_count, mode),
                max(side.run, 1) / max(self._elsewhere_run, 1),
            )
            for name, side in (("maximum", hi), ("minimum", lo))
        }

    def _mode_elsewhere(self) -> int:
        """Samples of the most frequent value other than the extremes (subsample × stride)."""
        sub = np.concatenate(self._kept) if self._kept else np.empty(0)
        sub = sub[np.isfinite(sub) & (sub != self._hi.value) & (sub != -self._lo.value)]
        if sub.size == 0:
            return 0
        _, counts = np.unique(sub, return_counts=True)
        return int(counts.max()) * self._stride


def _grouped_rail(y: np.ndarray, groups: np.ndarray, value: float) -> bool | None:
    """The grouped rule of the module docstring for the extreme ``value``; None when no point at
    the extreme holds enough samples to show its noise (the column's rule then decides)."""
    ok = np.isfinite(y)
    yf, gf = y[ok], groups[ok]
    levels: np.ndarray | None = None  # distinct values per point, when needed
    verdict: bool | None = None
    for g in np.unique(gf[yf == value]):
        vals = yf[gf == g]
        if vals.size < _GROUP_MIN:
            continue
        verdict = False
        k_ext = int(np.count_nonzero(vals == value))
        if k_ext == vals.size:
            if levels is None:
                pairs = np.unique(np.column_stack((gf, yf)), axis=0)
                labels, levels = np.unique(pairs[:, 0], return_counts=True)
                sizes = np.bincount(np.searchsorted(labels, gf), minlength=labels.size)
                levels = levels[(labels != g) & (sizes >= _GROUP_MIN)]
            if levels.size and float(np.median(levels)) >= _GROUP_NOISY_LEVELS:
                return True  # flat at the extreme while the other points show their noise
            continue
        if k_ext < max(_GROUP_MIN, _GROUP_PILE_FRACTION * vals.size):
            continue
        below = vals[vals != value]
        if np.unique(below).size + 1 < _GROUP_RESOLVED_LEVELS:
            continue  # too coarse for the point's noise to show its shape
        nearest = below.max() if value > below.max() else below.min()
        if k_ext > _GROUP_PILE_RATIO * np.count_nonzero(below == nearest):
            return True
    return verdict


def find_clipping(
    values: Any,
    column: str,
    *,
    companion: Any = None,
    rest: Any = None,
    groups: Any = None,
) -> Clipping | None:
    """The rails of one column, or None when it is not clipped (the rule and its reasons: see
    :mod:`rotacal.signal.clipping`).

    Parameters
    ----------
    values : array_like — the column's samples in row (time) order, any unit.
    column : str — its name, for the messages.
    companion : array_like, optional — the other channel of a quadrature pair (same rows): a
        channel at its extreme while the companion stands still is at rest, not clipped.
    rest : array_like of bool, optional — rows where the sensor is at rest (static sections, zero
        set rate): the level the column shows there is not a rail.
    groups : array_like of int, optional — the set condition (rate point) of each row: the
        grouped rule then judges the extremes instead of the column's counts and runs.

    Returns
    -------
    Clipping or None
    """
    det = RailDetector(column, int(np.size(values)))
    det.add(values, companion)
    judged = det.extremes()
    if not judged:
        return None
    y = np.asarray(values, dtype=np.float64).reshape(-1)
    at_rest = None
    if rest is not None:
        mask = np.asarray(rest, dtype=bool).reshape(-1)
        at_rest = y[mask] if mask.size == y.size else None
    rails = []
    for rail, ok in judged:
        if at_rest is not None and np.any(at_rest == rail.value):
            continue  # where the sensor rests, not a rail
        if groups is not None:  # the points explain piles and runs: judge within them
            grouped = _grouped_rail(y, np.asarray(groups).reshape(-1), rail.value)
            ok = ok if grouped is None else grouped
        if ok:
            rails.append(rail)
    return Clipping(column, det._finite, tuple(rails)) if rails else None


def find_quadrature_clipping(
    a: Any, b: Any, names: tuple[str, str] = ("a", "b"), *, jit: bool | None = None
) -> tuple[Clipping | None, Clipping | None]:
    """:func:`find_clipping` of each channel of a quadrature pair with the other as its
    companion, ``(of a, of b)``: the findings of two calls. The arguments, and how the pair is
    read, as :func:`quadrature_rail_detectors`."""
    det_a, det_b = quadrature_rail_detectors(a, b, names, jit=jit)
    return det_a.result(), det_b.result()


def quadrature_rail_detectors(
    a: Any, b: Any, names: tuple[str, str] = ("a", "b"), *, jit: bool | None = None
) -> tuple[RailDetector, RailDetector]:
    """The :class:`RailDetector` of each channel of a quadrature pair, fed the whole pair with
    the other channel as its companion, ``(of a, of b)``: their ``result()`` is
    :func:`find_quadrature_clipping`'s, and :meth:`RailDetector.in_working_range` tells a
    caller whether the column's values need checking again.

    The two detectors are fed piece by piece in turn, so each piece of both channels is read
    from memory once for both; a long pair (:func:`rotacal._jit.use_numba`) is read once by a
    compiled pass (:mod:`rotacal.signal._clipping_jit`) that leaves both in the same state.

    Parameters
    ----------
    a, b : array_like — the two channels, same rows (any unit).
    names : (str, str) — their column names, for the messages.
    jit : bool, optional — force the compiled pass (True) or the NumPy detectors (False);
        default by size.
    """
    x = np.asarray(a, dtype=np.float64).reshape(-1)
    y = np.asarray(b, dtype=np.float64).reshape(-1)
    det_a, det_b = RailDetector(names[0], x.size), RailDetector(names[1], y.size)
    if x.size != y.size:
        det_a.add(x, y)  # its one-line refusal
    det_a._with_companion = det_b._with_companion = True
    if x.size and use_numba(x.size, jit) and _compiled_pass(x, y, det_a, det_b):
        return det_a, det_b
    for s in range(0, x.size, _PIECE):
        xp, yp = x[s : s + _PIECE], y[s : s + _PIECE]
        rx, ry = _finite_range(xp), _finite_range(yp)
        det_a._add_piece(xp, yp, (rx, ry[:2]))
        det_b._add_piece(yp, xp, (ry, rx[:2]))
    return det_a, det_b


def _compiled_pass(x: np.ndarray, y: np.ndarray, det_a: RailDetector, det_b: RailDetector) -> bool:
    """Both detectors' state from one compiled pass over the pair; False (nothing set) when a
    value is not finite, which the NumPy detectors then judge."""
    from rotacal.signal import _clipping_jit as k

    st = np.zeros((2, k.STATE_FIELDS))
    for o in (0, k.SIDE_FIELDS):  # each side starts as _Side does
        st[:, o] = st[:, o + 3] = -math.inf
        st[:, o + 2] = -1.0
        st[:, o + 5], st[:, o + 6] = math.inf, -math.inf
    ranges = np.array([math.inf, -math.inf, math.inf, -math.inf])
    if not k.quadrature_rails(x, y, st, ranges):
        return False
    for det, row, comp in ((det_a, st[0], ranges[2:]), (det_b, st[1], ranges[:2])):
        det._n = det._finite = x.size
        for side, o in ((det._hi, 0), (det._lo, k.SIDE_FIELDS)):
            side.value, side.next_value = float(row[o]), float(row[o + 3])
            side.count, side.first = int(row[o + 1]), int(row[o + 2])
            side.next_count, side.run = int(row[o + 4]), int(row[o + 7])
            side.comp_lo, side.comp_hi = float(row[o + 5]), float(row[o + 6])
        det._elsewhere_run = int(row[k.ELSEWHERE])
        det._open_value, det._open_len = float(row[k.OPEN_VALUE]), int(row[k.OPEN_LEN])
        det._comp_lo, det._comp_hi = float(comp[0]), float(comp[1])
        # the subsample of the most frequent value: the rows at the final stride (a view)
        det._kept = [(x if det is det_a else y)[:: det._stride]]
        det._kept_n = det._kept[0].size
    return True


def check_clipping(
    columns: Mapping[str, Any],
    *,
    allow_clipped: bool = False,
    **context: Any,
) -> tuple[str, ...]:
    """Refuse clipped columns, or return the warning lines when clipping is allowed.

    Parameters
    ----------
    columns : mapping — column name → its samples, or → a :class:`Clipping` (or None) already
        found (a streamed capture's :class:`RailDetector` result).
    allow_clipped : bool — analyse a clipped capture anyway (``--allow-clipped``).
    **context : ``rest`` or ``groups`` for every column (see :func:`find_clipping`).

    Returns
    -------
    tuple of str — one warning line per clipped column (empty when none is clipped).

    Raises
    ------
    ClippedSignalError
        A column is clipped and ``allow_clipped`` is False: one line naming the column, the share
        of its samples at the rails, the rail values and their first rows, and what to do.
    """
    found: list[Clipping] = []
    for name, values in columns.items():
        if values is None or isinstance(values, Clipping):
            clip = values
        else:
            clip = find_clipping(values, name, **context)
        if clip is not None:
            found.append(clip)
    if not found:
        return ()
    if not allow_clipped:
        also = "".join(f" Column '{c.column}' is clipped too." for c in found[1:])
        raise ClippedSignalError(found[0].refusal() + also, tuple(found))
    return tuple(c.warning() for c in found)
