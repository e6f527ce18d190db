"""The pulse-timing rate analysis of one train over a stream of chunks, with carried state.

:func:`rate_passes` runs everything :func:`rotacal.table.rate.calibrate_rate` computes from the
pulse times of the chosen head (or the head-averaged times) in two passes over its chunks, each
with bounded memory, so that a capture too large for memory is analysed from the file
(:func:`rotacal.io.iter_capture_chunks`) and an array by the very same code:

1. the angles (nominal and compensated) and the rate points of each block of ``average``
   intervals (one pulse carried across chunks); the whole-revolution mean rate (the first pulse
   and pulse R·m, R known from the record's length); the timing jitter (2m + 3 pulses carried,
   :class:`~rotacal.table.rate_jitter.JitterSums`); s(φ)
   (:class:`~rotacal.table.rate_allan_sums.AllanSums`); the rms's sufficient statistics, the
   Welch spectrum and the trend of the rate deviation about a provisional reference (the first
   rate point), moved onto the mean rate at the end (d = a·d₀ + b, exact algebra);
2. the rate deviation again, now about the mean rate: the peak's candidates and their
   Wiener-filtered values (:class:`~rotacal.uncertainty.summaries_peak.PeakCollector`).

References
----------
Kokuyama et al. (2015) §5 (time-difference rate, 10-point averaging, s(φ)); Welch (1967) and
Wiener (1949) for the peak's bias (:mod:`rotacal.uncertainty.summaries_peak`).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Iterator
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from rotacal._jit import use_numba
from rotacal.encoder.pulses import pulse_angle_deg
from rotacal.errors import CaptureError, ConfigError
from rotacal.table.rate_allan import allan_clusters
from rotacal.table.rate_allan_sums import AllanSums, allan_stride
from rotacal.table.rate_jitter import JitterSums
from rotacal.table.rate_plausibility import TrendSums
from rotacal.uncertainty.summaries import (
    ErrorProcess,
    PeakInputs,
    SeriesStats,
    noise_periodogram,
)
from rotacal.uncertainty.summaries_peak import PeakCollector, WelchSums, welch_gain
from rotacal.uncertainty.summaries_rms import MAX_LAG

__all__ = ["PassOne", "RatePasses", "RatePlan", "finish_passes", "rate_passes", "rate_plan"]

FloatArray = NDArray[np.float64]
Chunks = Callable[[], Iterator[FloatArray]]

#: Probability that the union bound behind the peak's candidates may fail (as in summaries).
_CANDIDATE_RISK = 1e-3


class _RatePoints:
    """Angles and block rates of a pulse train fed in chunks (the pulses of an unfinished block
    carried): the same arithmetic per block as :func:`rotacal.encoder.pulses.pulse_rate`."""

    def __init__(
        self,
        m: int,
        average: int,
        deviation: FloatArray | None,
        shift: int,
        jit: bool = False,
        nominal: bool = True,
    ) -> None:
        self.m, self.a, self.dev, self.shift = m, int(average), deviation, int(shift)
        self.jit = jit
        # the uncompensated rates too (compensated ones given): pass 2 needs only the rates
        self.both = deviation is not None and nominal
        self.seen = 0
        self._t = np.zeros(0)
        self._ang = np.zeros(0)
        self._nom = np.zeros(0)

    def angles(self, t: FloatArray) -> tuple[FloatArray, FloatArray]:
        """The nominal and the compensated angles (deg) of the chunk's pulses (the same array
        when nothing is compensated, or the nominal ones are not wanted)."""
        count = np.arange(self.seen, self.seen + t.size)
        self.seen += t.size
        if self.dev is None:
            nom = pulse_angle_deg(count, self.m)
            return nom, nom
        ang = pulse_angle_deg(count, self.m, self.dev, line_offset=self.shift)
        return (pulse_angle_deg(count, self.m) if self.both else ang), ang

    def push(
        self, t: FloatArray, ang: FloatArray, nom: FloatArray
    ) -> tuple[FloatArray, FloatArray, FloatArray]:
        carried = self._t.size
        if self.jit and carried <= self.a < t.size:
            return self._push_compiled(t, ang, nom)
        tt = np.concatenate((self._t, t))
        aa = np.concatenate((self._ang, ang))
        nn = np.concatenate((self._nom, nom)) if self.both else aa
        blocks = max(tt.size - 1, 0) // self.a
        used = blocks * self.a
        if blocks and self.jit:
            from rotacal.table._rate_stream_jit import block_rates

            t_avg, rate, rate_nom = block_rates(tt, aa, nn, self.a, blocks, self.both)
        elif blocks:
            dt = np.diff(tt[: used + 1])
            t_avg = (tt[:used] + 0.5 * dt).reshape(blocks, self.a).mean(axis=1)
            rate = (np.diff(aa[: used + 1]) / dt).reshape(blocks, self.a).mean(axis=1)
            rate_nom = (
                rate
                if not self.both
                else (np.diff(nn[: used + 1]) / dt).reshape(blocks, self.a).mean(axis=1)
            )
        else:
            t_avg = rate = rate_nom = np.zeros(0)
        self._t, self._ang = tt[used:].copy(), aa[used:].copy()
        self._nom = nn[used:].copy() if self.both else self._nom
        return t_avg, rate, rate_nom

    def _push_compiled(
        self, t: FloatArray, ang: FloatArray, nom: FloatArray
    ) -> tuple[FloatArray, FloatArray, FloatArray]:
        """:meth:`push` without a copy of the chunk: the block that spans the carried pulses
        from them and the chunk's first pulses, the others on the chunk itself."""
        from rotacal.table._rate_stream_jit import block_rates

        both = self.both
        lead = self.a + 1 - self._t.size  # the chunk's pulses in the first block
        head_t = np.concatenate((self._t, t[:lead]))
        head_a = np.concatenate((self._ang, ang[:lead]))
        head_n = np.concatenate((self._nom, nom[:lead])) if both else head_a
        first = block_rates(head_t, head_a, head_n, self.a, 1, both)
        start = lead - 1  # the chunk's pulse where the second block starts
        blocks = (t.size - 1 - start) // self.a
        used = start + blocks * self.a
        rest = block_rates(t[start:], ang[start:], nom[start:], self.a, blocks, both)
        self._t, self._ang = t[used:].copy(), ang[used:].copy()
        self._nom = nom[used:].copy() if both else self._nom
        t_avg, rate = np.concatenate((first[0], rest[0])), np.concatenate((first[1], rest[1]))
        return t_avg, rate, np.concatenate((first[2], rest[2])) if both else rate


@dataclasses.dataclass
class RatePasses:
    """What the two passes give (see the module docstring); units as in RateResult."""

    pulses: int
    points: int
    mean_rate: float
    revolutions: int
    first_t: float
    last_t: float
    window_end: float
    rev_times: FloatArray
    short: tuple[FloatArray, FloatArray] | None
    prefix: tuple[FloatArray, FloatArray]
    jitter: tuple[float, float, bool]
    phi: FloatArray
    s: FloatArray
    s_nom: FloatArray
    rms_stats: SeriesStats
    rms_nom: float
    peak_nom: float
    peak: PeakInputs | None
    trend: TrendSums
    trend_scale: float
    series: tuple[FloatArray, FloatArray, FloatArray] | None


def _candidate_floor(peak: float, n: int, sources: list[ErrorProcess]) -> float:
    """max|d| − Δ of :func:`rotacal.uncertainty.summaries.candidate_positions` (Δ from the
    sources alone: 2·z·σ_D, z = √(2 ln(N/10⁻³)))."""
    drawable = [s for s in sources if s.drawable]
    support = min(n, max(int(getattr(s, "autocov", np.zeros(0)).size) + 1 for s in drawable) + 4)
    g = sum((s.lags(support) for s in drawable), np.zeros(support))
    z = math.sqrt(2.0 * math.log(n / _CANDIDATE_RISK))
    sigma_d = math.sqrt(max(2.0 * (float(g[0]) - float(np.min(g))), 0.0))
    return peak - 2.0 * z * sigma_d


@dataclasses.dataclass(frozen=True)
class RatePlan:
    """What both passes need to know of a train before its first pulse is read (see
    :func:`rate_plan`): a task of a split analysis gets it whole."""

    m: int
    n: int
    average: int
    points: int
    revs: int
    ks: NDArray[np.int64]
    strides: list[int]
    compiled: bool
    deviation: FloatArray | None
    shift: int
    prefix_pulses: int

    @property
    def periods(self) -> tuple[int, ...]:
        """The periods (rate points) the rms statistics are folded over."""
        return (self.m // math.gcd(self.average, self.m),)

    def rate_points(self, nominal: bool = True) -> _RatePoints:
        """A fresh accumulator of the train's rate points."""
        return _RatePoints(self.m, self.average, self.deviation, self.shift, self.compiled, nominal)

    def allan_sums(self) -> AllanSums:
        """Fresh sums of s(φ) (Numba once for the record, not per cluster size)."""
        return AllanSums(self.ks.tolist(), self.strides, jit=self.compiled)

    def jitter_sums(self) -> JitterSums:
        """Fresh sums of the timing jitter."""
        return JitterSums(self.n, self.m, jit=self.compiled)


def rate_plan(
    pulses: int,
    *,
    pulses_per_rev: int,
    average: int,
    deviation: FloatArray | None,
    shift: int,
    allan_angles_deg: ArrayLike | None,
    prefix_pulses: int,
) -> RatePlan:
    """The checks of a train of ``pulses`` times made before any is read, and its plan
    (arguments as :func:`rate_passes`)."""
    m = int(pulses_per_rev)
    n = int(pulses)
    if n < 3:
        raise CaptureError(f"{n} pulse(s) are too few; a pulse train needs more.")
    if isinstance(average, bool) or not isinstance(average, int | np.integer) or average < 1:
        raise ConfigError(f"average must be a whole number of intervals ≥ 1, got {average!r}.")
    points = (n - 1) // int(average)
    if points < 1:
        raise CaptureError(
            f"{n - 1} pulse intervals cannot make one average of {average}; lower --average."
        )
    ks = allan_clusters(n, 360.0 / m, allan_angles_deg)
    plan = RatePlan(
        m=m,
        n=n,
        average=int(average),
        points=points,
        revs=(n - 1) // m,
        ks=ks,
        strides=[allan_stride(int(k)) for k in ks],
        compiled=use_numba(n),  # once for the record: every stride's sums in the compiled twin
        deviation=deviation,
        shift=int(shift),
        prefix_pulses=int(prefix_pulses),
    )
    plan.jitter_sums()  # refuses a train too short for the timing jitter
    return plan


@dataclasses.dataclass
class PassOne:
    """What the first pass gathers (see the module docstring): deviations d₀ about the
    provisional reference ``ref`` (%), the sums of s(φ) and of the jitter, the times kept."""

    allan: AllanSums
    allan_nom: AllanSums | None
    jitter: JitterSums
    stats: SeriesStats
    welch: WelchSums
    trend: TrendSums
    ref: float = math.nan
    nom_sq: float = 0.0
    nom_sum: float = 0.0
    lo0: float = math.nan
    hi0: float = math.nan
    lo_nom: float = math.nan
    hi_nom: float = math.nan
    first_t: float = math.nan
    last_t: float = math.nan
    end_t: float = math.nan
    rev_times: list[FloatArray] = dataclasses.field(default_factory=list)
    prefix_t: list[FloatArray] = dataclasses.field(default_factory=list)
    prefix_a: list[FloatArray] = dataclasses.field(default_factory=list)
    short_t: list[FloatArray] = dataclasses.field(default_factory=list)
    short_a: list[FloatArray] = dataclasses.field(default_factory=list)
    series: list[tuple[FloatArray, FloatArray, FloatArray]] = dataclasses.field(
        default_factory=list
    )

    @classmethod
    def empty(cls, plan: RatePlan) -> PassOne:
        """Nothing seen yet."""
        return cls(
            allan=plan.allan_sums(),
            allan_nom=plan.allan_sums() if plan.deviation is not None else None,
            jitter=plan.jitter_sums(),
            stats=SeriesStats.empty(plan.periods),
            welch=WelchSums(plan.points),
            trend=TrendSums(),
        )

    def merge(self, block: PassOne, heads: tuple[dict[int, Any], dict[int, Any] | None]) -> None:
        """Add what the first pass gathered over the block of pulses that follows (its sums of
        s(φ) from :meth:`AllanSums.starting_at`, ``heads`` their first pulses; its rms
        statistics with the rate points before it as their tail): the same sums as one pass
        over both, to rounding."""
        self.allan.merge(block.allan, heads[0])
        if self.allan_nom is not None and block.allan_nom is not None and heads[1] is not None:
            self.allan_nom.merge(block.allan_nom, heads[1])
        self.jitter.merge(block.jitter)
        stats, part = self.stats, block.stats
        if part.n > stats.n:
            stats.lagged += part.lagged
            for period, sums in stats.folded.items():
                sums += part.folded[period]
            stats.total += part.total
            if stats.head.size < MAX_LAG - 1:
                stats.head = np.concatenate((stats.head, part.head))[: MAX_LAG - 1]
            stats.tail, stats.n = part.tail, part.n
        welch = self.welch
        welch.power_sum += block.welch.power_sum
        welch.dc_sum += block.welch.dc_sum
        welch.dc_sq += block.welch.dc_sq
        welch.count += block.welch.count
        self.trend.merge(block.trend)
        if not math.isnan(block.lo0):
            self.lo0, self.hi0 = np.nanmin([self.lo0, block.lo0]), np.nanmax([self.hi0, block.hi0])
            self.lo_nom = np.nanmin([self.lo_nom, block.lo_nom])
            self.hi_nom = np.nanmax([self.hi_nom, block.hi_nom])
        self.nom_sq += block.nom_sq
        self.nom_sum += block.nom_sum
        if math.isnan(self.first_t):
            self.first_t = block.first_t
        if not math.isnan(block.last_t):
            self.last_t = block.last_t
        if not math.isnan(block.end_t):
            self.end_t = block.end_t
        for name in ("rev_times", "prefix_t", "prefix_a", "short_t", "short_a"):
            getattr(self, name).extend(getattr(block, name))

    def add_extremes(self, d0: FloatArray, dn: FloatArray) -> None:
        """The extremes and the sums of the uncompensated deviations of some rate points."""
        self.lo0, self.hi0 = np.nanmin([self.lo0, d0.min()]), np.nanmax([self.hi0, d0.max()])
        self.nom_sq += float(np.dot(dn, dn))
        self.nom_sum += float(np.sum(dn))
        self.lo_nom = np.nanmin([self.lo_nom, dn.min()])
        self.hi_nom = np.nanmax([self.hi_nom, dn.max()])


#: The second pass: (mean rate in deg/s, the candidates' floor in %, the Wiener gains) → the
#: candidates of the peak and their filtered values.
PeakPass = Callable[[float, float, list[FloatArray]], PeakInputs]


def _first_pass(
    chunks: Chunks,
    plan: RatePlan,
    one: PassOne,
    keep_series: bool,
    progress: Callable[[int], None] | None,
) -> int:
    """The first pass over ``chunks()`` into ``one``; the pulses seen (a function of its own:
    its last chunk is not held through the second pass)."""
    m, revs, prefix_pulses, deviation = plan.m, plan.revs, plan.prefix_pulses, plan.deviation
    rp = plan.rate_points()
    for t in chunks():
        t = np.asarray(t, dtype=np.float64)
        if t.size == 0:
            continue
        i0 = rp.seen
        if i0 == 0:
            one.first_t = float(t[0])
        one.last_t = float(t[-1])
        nom, ang = rp.angles(t)
        if i0 < prefix_pulses:
            one.prefix_t.append(t[: prefix_pulses - i0].copy())
            one.prefix_a.append(nom[: prefix_pulses - i0].copy())
        if revs >= 1:
            first = (-i0) % m
            idx = np.arange(i0 + first, i0 + t.size, m)
            keep = idx <= revs * m
            one.rev_times.append(t[first::m][keep].copy())
            if i0 <= revs * m < i0 + t.size:
                one.end_t = float(t[revs * m - i0])
        else:
            one.short_t.append(t.copy())
            one.short_a.append(ang.copy())
        one.jitter.update(t)
        one.allan.update(t, ang)
        if one.allan_nom is not None:
            one.allan_nom.update(t, nom)
        t_avg, rate, rate_nom = rp.push(t, ang, nom)
        if rate.size:
            if math.isnan(one.ref):
                one.ref = float(rate[0])  # the provisional reference (the same for any chunking)
            d0 = 100.0 * (rate - one.ref) / one.ref
            one.stats.update(d0)
            one.welch.update(d0)
            one.trend.update(t_avg, d0)
            one.add_extremes(
                d0, d0 if deviation is None else 100.0 * (rate_nom - one.ref) / one.ref
            )
            if keep_series:
                one.series.append((t_avg, rate, rate_nom))
        if progress is not None:
            progress(t.size)
    return rp.seen


def rate_passes(
    chunks: Chunks,
    pulses: int,
    *,
    pulses_per_rev: int,
    average: int,
    deviation: FloatArray | None,
    shift: int,
    allan_angles_deg: ArrayLike | None,
    sources_for: Callable[[float, tuple[float, float, bool]], list[ErrorProcess]],
    prefix_pulses: int,
    keep_series: bool = False,
    progress: Callable[[int], None] | None = None,
) -> RatePasses:
    """Run both passes over ``chunks()`` (called once per pass; pulse times in order, s).

    Parameters
    ----------
    chunks : callable
        Returns a fresh iterator over the train's chunks of pulse times.
    pulses : int
        N, the train's length (known from the file up front).
    pulses_per_rev, average : int
        m and the intervals per rate point.
    deviation : ndarray (m,), arcsec, or None
        The scale deviation to compensate with, and ``shift`` its index of the first pulse.
    allan_angles_deg : array_like, deg, optional
        s(φ) angles (default 12 per decade).
    sources_for : callable
        (mean rate in deg/s, timing jitter) → the rate points' error sources (% of rate).
    prefix_pulses : int
        Pulses kept from the start (the one-head period check).
    keep_series : bool
        Keep the rate points (times, rates, uncompensated rates): memory grows with N.
    progress : callable, optional
        Called with the pulses of each chunk handled (both passes).
    """
    plan = rate_plan(
        pulses,
        pulses_per_rev=pulses_per_rev,
        average=average,
        deviation=deviation,
        shift=shift,
        allan_angles_deg=allan_angles_deg,
        prefix_pulses=prefix_pulses,
    )
    one = PassOne.empty(plan)
    seen = _first_pass(chunks, plan, one, keep_series, progress)
    if seen != plan.n:
        raise CaptureError(f"the train held {seen} pulses, not the {plan.n} expected.")

    def second(mean_rate: float, floor: float, gains: list[FloatArray]) -> PeakInputs:
        collector = PeakCollector(plan.points, floor, gains)
        rp2 = plan.rate_points(nominal=False)
        for t in chunks():  # pass 2: the deviation about the mean rate, exactly
            t = np.asarray(t, dtype=np.float64)
            _, ang = rp2.angles(t)
            _, rate, _ = rp2.push(t, ang, ang)
            collector.update(100.0 * (rate - mean_rate) / mean_rate)
            if progress is not None:
                progress(t.size)
        return collector.result()

    return finish_passes(plan, one, sources_for, second, keep_series=keep_series)


def finish_passes(
    plan: RatePlan,
    one: PassOne,
    sources_for: Callable[[float, tuple[float, float, bool]], list[ErrorProcess]],
    second: PeakPass,
    *,
    keep_series: bool = False,
) -> RatePasses:
    """The results of the first pass moved onto the mean rate, with the second pass run by
    ``second`` (over the chunks, or split over workers)."""
    m, revs, points = plan.m, plan.revs, plan.points
    first_t, end_t, ref = one.first_t, one.end_t, one.ref
    short = None
    if revs >= 1:
        mean_rate = 360.0 * revs / (end_t - first_t)
    else:
        st, sa = np.concatenate(one.short_t), np.concatenate(one.short_a)
        short = (st, sa)
        mean_rate = float(np.polyfit(st - st[0], sa, 1)[0])
        end_t = one.last_t
    jit = one.jitter.result()
    # d = a·d₀ + b moves the deviation from the provisional reference onto the mean rate
    a = ref / mean_rate
    b = 100.0 * (ref - mean_rate) / mean_rate
    rms_stats = one.stats.affine(a, b)
    ms_nom = (a * a * one.nom_sq + 2.0 * a * b * one.nom_sum + points * b * b) / points
    peak_nom = max(abs(a * one.hi_nom + b), abs(a * one.lo_nom + b))
    sources = sources_for(mean_rate, jit)
    peak: PeakInputs | None = None
    if sources:
        present = [s for s in sources if s.role != "absent"]
        noise_only = [s for s in sources if s.role == "noise"]
        power = one.welch.power(a, b)
        gains = [welch_gain(power, noise_periodogram(g, points)) for g in (present, noise_only)]
        plain = max(abs(a * one.hi0 + b), abs(a * one.lo0 + b))
        peak = second(mean_rate, _candidate_floor(plain, points, sources), gains)
    with np.errstate(invalid="ignore"):
        s = np.sqrt(0.5 * one.allan.mean_squares()) / abs(mean_rate)
        s_nom = (
            s
            if one.allan_nom is None
            else np.sqrt(0.5 * one.allan_nom.mean_squares()) / abs(mean_rate)
        )
    kept: tuple[FloatArray, FloatArray, FloatArray] | None = None
    if keep_series:
        t_all, r_all, n_all = (np.concatenate([x[i] for x in one.series]) for i in range(3))
        kept = (t_all, r_all, n_all)
    return RatePasses(
        pulses=plan.n,
        points=points,
        mean_rate=mean_rate,
        revolutions=revs,
        first_t=first_t,
        last_t=one.last_t,
        window_end=end_t,
        rev_times=np.concatenate(one.rev_times) if one.rev_times else np.zeros(0),
        short=short,
        prefix=(
            np.concatenate([np.zeros(0), *one.prefix_t]),
            np.concatenate([np.zeros(0), *one.prefix_a]),
        ),
        jitter=jit,
        phi=np.asarray(plan.ks * (360.0 / m), dtype=np.float64),
        s=s,
        s_nom=s_nom,
        rms_stats=rms_stats,
        rms_nom=math.sqrt(max(ms_nom, 0.0)),
        peak_nom=peak_nom,
        peak=peak,
        trend=one.trend,
        trend_scale=a,
        series=kept,
    )
