"""Constant-rate calibration of a rotary table from encoder pulse timing (Kokuyama et al. 2015, §5).

The table turns at a set angular velocity; the encoder's pulse times give the angle at every
pulse. From them: the mean rate over whole revolutions (where the scale's deviation cancels
exactly), its bias against the set rate, the rate over time by the time-difference method with and
without compensation by the self-calibrated deviation (rms and peak deviation in % of rate), and the
relative root Allan variance of angular velocity as a function of rotation angle, s(φ).

Uncertainty (GUM, JCGM 100; Monte Carlo, JCGM 101). The mean rate is the mean over the stated
window of whole revolutions: 360·R over the time of R revolutions of one line. Its inputs are the
timing jitter of the window's two end pulses (Type A, estimated from the pulse times themselves:
the same line one and two revolutions later, where the graduation cancels exactly), the DAQ
timebase (Type B, ``timebase.relative_error``: rate ∝ 1/time) and the graduation — zero, because
the window starts and ends on the same line, and m pitches are exactly 360°. The bias against the
set rate is a property of the table, not of one record: it adds the table's wander, the spread of
the single-revolution rates (Type A); both budgets are validated by the same Monte Carlo (JCGM 101
§8). The rms and peak of the rate deviation are rms/max-type: noise raises them, so their budgets
(:mod:`rotacal.uncertainty.summaries`) state the plain value, the bias of the noise whose level
the capture gives (never of a bound or a specification), and a 95 % interval for the true value.
Each s(φ) point has the χ² uncertainty of its equivalent degrees of freedom (Greenhall & Riley
2003).

Every figure comes from two passes over the chosen pulse train with carried state
(:mod:`rotacal.table.rate_stream`): over an array in chunks here, over the capture file in
:func:`rotacal.table.rate_file.calibrate_rate_file` — the same numbers, in bounded memory.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Iterator, Mapping, Sequence
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from rotacal.encoder.pulses import (
    check_pulse_times,
    check_pulses_per_rev,
    head_columns,
    pair_heads,
)
from rotacal.encoder.selfcal import (
    SelfCalibration,
    check_period,
    head_shifts,
    self_calibrate,
)
from rotacal.errors import CaptureError, ConfigError
from rotacal.results import Result
from rotacal.signal._values import check_setting
from rotacal.table.rate_alignment import (
    _as_deviation,
    accept_alignment,
    align_deviation,
    own_revolutions,
    same_capture,
)
from rotacal.table.rate_allan import (
    allan_uncertainty,
    allan_versus_angle,
)
from rotacal.table.rate_budgets import (
    _TIMEBASE,
    _deviation_sources,
    _mean_rate_budgets,
    _rate_deviation_budgets,
)
from rotacal.table.rate_jitter import timing_jitter
from rotacal.table.rate_plausibility import rate_warnings
from rotacal.table.rate_stream import RatePasses, rate_passes
from rotacal.uncertainty import (
    InstrumentSpecs,
    UncertaintyBudget,
    uncertainty_keys,
)
from rotacal.uncertainty.summaries import ErrorProcess

__all__ = [
    "RateResult",
    "align_deviation",
    "allan_uncertainty",
    "allan_versus_angle",
    "calibrate_rate",
    "timing_jitter",
]

#: Pulses of a single head on which its period (the pulses per revolution) is checked.
PERIOD_CHECK_PULSES = 1 << 19
#: Pulses per chunk when an in-memory train goes through the streamed passes (bounded
#: temporaries; the results do not depend on it).
_ARRAY_CHUNK = 1 << 22

FloatArray = NDArray[np.float64]


@dataclasses.dataclass(frozen=True)
class RateResult(Result):
    """Constant-rate calibration of a table (INTERFACE.md ``rate``).

    Attributes
    ----------
    mean_rate_deg_s : float, deg/s
        Mean angular velocity over the whole revolutions of the record (the scale's deviation
        cancels over a revolution); over the whole record by a straight-line fit when shorter.
    rate_deviation_rms_percent, rate_deviation_peak_percent : float, %
        rms and peak of the averaged rate about the mean, in % of the mean rate, compensated by
        the self-calibrated deviation when one was applied.
    rate_deviation_rms_percent_uncompensated, rate_deviation_peak_percent_uncompensated : float, %
        The same with the nominal pitch (no compensation).
    allan_angle_deg, allan_tau_s : list of float
        Rotation angles φ (deg) and the corresponding τ = φ/ω_m (s).
    allan_relative : list of float
        s(φ) = σ(φ/ω_m)/ω_m (dimensionless), compensated when a deviation was applied.
    allan_relative_uncompensated : list of float
    set_rate_deg_s, rate_bias_deg_s, rate_bias_percent : float or None
        Set rate and mean − set (deg/s and % of the set rate), when a set rate is given.
    timing_jitter_s, timing_jitter_dof : float or None
        Standard deviation (s) of the timing noise of the pulses used, estimated from them (see
        :func:`timing_jitter`), and its degrees of freedom.
    timebase_correction : float
        The stated mean fractional timebase error δ̂ the rates were corrected for (rate·(1 + δ̂));
        0 when none was stated.
    rate_deviation_rms_percent_bias, rate_deviation_peak_percent_bias : float or None, %
        How much the noise whose level the capture gives (the timing jitter with two or more
        whole revolutions, the self-calibration's noise) raises the plain rms and peak; None
        when there is none (e.g. fewer than two revolutions: the jitter estimate is then only an
        upper bound, and a bound or a specification is never subtracted).
    rate_deviation_rms_percent_bias_corrected, rate_deviation_peak_percent_bias_corrected : float
        or None, %
        The plain values less that bias. The 95 % interval for the true value is the JSON
        ``rate_deviation_rms_percent_interval`` / ``rate_deviation_peak_percent_interval``.
    allan_relative_u, allan_relative_U : list of float
        Standard and expanded (p = 95 %) uncertainty of each s(φ) from its equivalent degrees
        of freedom; U is half the width of the χ² interval, so k = U/u differs per point.
    allan_relative_edf : list of float
        Equivalent degrees of freedom of each σ²(φ/ω_m) (Greenhall & Riley 2003).
    allan_relative_interval : list of [float, float]
        The 95 % χ² interval of each s(φ).
    allan_noise_alpha : list of int
        Power-law noise type α assumed for each edf (2 white PM … −2 random-walk FM), from the
        local slope of s(φ).
    head : str
        ``"head_k"`` or ``"all heads"`` (the head-averaged times).
    average : int
        Pulse intervals per averaged rate point.
    revolutions : int
        Whole revolutions in the record used for the mean rate.
    mean_rate_window_s : list of float, s
        [start, stop] of the time over which the mean rate is taken.
    duration_s : float, s
    compensated : bool
    deviation_shift_pulses : int or None
        Deviation index of the head's first pulse (how the curve was aligned with the capture).
    alignment_correlation : float or None
        Correlation of the capture's own angle error with the deviation when it had to be
        aligned by correlation (None when the deviation came from the same capture).
    notes : list of str

    :attr:`time_s`, :attr:`rate_deg_s` and :attr:`rate_uncompensated_deg_s` (the rate points,
    for figures) are empty when the capture was streamed from its file
    (:func:`rotacal.table.rate_file.calibrate_rate_file`): they would grow with the record.

    ``to_dict()`` adds ``<name>_u``/``<name>_U`` for ``mean_rate_deg_s``, ``rate_bias_deg_s``,
    ``rate_bias_percent`` (with a set rate), ``rate_deviation_rms_percent`` and
    ``rate_deviation_peak_percent`` (with ``<name>_interval``: u the standard deviation of the
    summary's error, U half the interval's width), ``k`` (per quantity; a list for
    ``allan_relative``), ``coverage_probability`` and ``uncertainty_budgets``.
    """

    mean_rate_deg_s: float
    rate_deviation_rms_percent: float
    rate_deviation_peak_percent: float
    rate_deviation_rms_percent_uncompensated: float
    rate_deviation_peak_percent_uncompensated: float
    allan_angle_deg: list[float]
    allan_tau_s: list[float]
    allan_relative: list[float]
    allan_relative_uncompensated: list[float]
    set_rate_deg_s: float | None
    rate_bias_deg_s: float | None
    rate_bias_percent: float | None
    head: str
    average: int
    revolutions: int
    mean_rate_window_s: list[float]
    duration_s: float
    compensated: bool
    deviation_shift_pulses: int | None
    alignment_correlation: float | None
    notes: list[str]
    _time_s: FloatArray = dataclasses.field(repr=False)
    _rate_deg_s: FloatArray = dataclasses.field(repr=False)
    _rate_uncompensated_deg_s: FloatArray = dataclasses.field(repr=False)
    _selfcal: SelfCalibration | None = dataclasses.field(repr=False, default=None)
    timing_jitter_s: float | None = None
    timing_jitter_dof: float | None = None
    timebase_correction: float = 0.0
    rate_deviation_rms_percent_bias: float | None = None
    rate_deviation_rms_percent_bias_corrected: float | None = None
    rate_deviation_peak_percent_bias: float | None = None
    rate_deviation_peak_percent_bias_corrected: float | None = None
    allan_relative_u: list[float] = dataclasses.field(default_factory=list)
    allan_relative_U: list[float] = dataclasses.field(default_factory=list)
    allan_relative_edf: list[float] = dataclasses.field(default_factory=list)
    allan_relative_interval: list[list[float]] = dataclasses.field(default_factory=list)
    allan_noise_alpha: list[int] = dataclasses.field(default_factory=list)
    _budgets: dict[str, UncertaintyBudget] = dataclasses.field(repr=False, default_factory=dict)

    def to_dict(self) -> dict[str, Any]:
        out = super().to_dict()
        out.update(uncertainty_keys(self._budgets))
        out["k"]["allan_relative"] = [
            big / u if u > 0 else None
            for big, u in zip(self.allan_relative_U, self.allan_relative_u, strict=True)
        ]
        return out

    @property
    def budgets(self) -> dict[str, UncertaintyBudget]:
        """Uncertainty budgets by JSON key."""
        return dict(self._budgets)

    @property
    def time_s(self) -> FloatArray:
        """Time (s) of each averaged rate point."""
        return self._time_s

    @property
    def rate_deg_s(self) -> FloatArray:
        """Averaged rate (deg/s), compensated when a deviation was applied."""
        return self._rate_deg_s

    @property
    def rate_uncompensated_deg_s(self) -> FloatArray:
        """Averaged rate (deg/s) with the nominal pitch."""
        return self._rate_uncompensated_deg_s

    @property
    def selfcal(self) -> SelfCalibration | None:
        """The self-calibration made from this capture, when one was made."""
        return self._selfcal


def _check_settings(specs: Any, set_rate_deg_s: float | None) -> None:
    """Refuse specs that are not InstrumentSpecs and a set rate that is not finite and non-zero."""
    if specs is not None and not isinstance(specs, InstrumentSpecs):
        raise ConfigError(
            f"specs must be the InstrumentSpecs of load_specs(...), got {type(specs).__name__}."
        )
    if set_rate_deg_s is not None:
        if not math.isfinite(float(set_rate_deg_s)) or float(set_rate_deg_s) == 0:
            raise ConfigError(
                f"set_rate_deg_s must be finite and non-zero, got {set_rate_deg_s!r}."
            )
        check_setting("--set-rate-deg-s", set_rate_deg_s, positive=False, unit="deg/s")


def _head_index(head: int | str, n: int) -> int:
    """The head number of ``head`` (k, "k" or "head_k"), checked against n heads."""
    if isinstance(head, str) and head.startswith("head_"):
        head = head[5:]
    try:
        k = int(head)
    except (TypeError, ValueError):
        raise ConfigError(f"head must be a head number or 'all', got {head!r}.") from None
    if not 0 <= k < n:
        raise ConfigError(f"head {k} does not exist; the capture has head_0 … head_{n - 1}.")
    return k


def calibrate_rate(
    heads: Sequence[ArrayLike] | Mapping[str, ArrayLike],
    *,
    pulses_per_rev: int,
    selfcal: SelfCalibration | Mapping[str, Any] | ArrayLike | None = None,
    head: int | str = 0,
    average: int = 10,
    set_rate_deg_s: float | None = None,
    allan_angles_deg: ArrayLike | None = None,
    compensate: bool = True,
    specs: InstrumentSpecs | None = None,
    readout_resolution_deg: float | None = None,
) -> RateResult:
    """Angular velocity of a table from pulse timing: mean, bias, stability and s(φ).

    Parameters
    ----------
    heads : sequence of array_like, or mapping with ``head_0`` …, s
        Pulse times of every head (head 0 first); one head is enough without self-calibration.
    pulses_per_rev : int
        m, pulses per revolution.
    selfcal : SelfCalibration, its JSON dict, an array of m deviations (arcsec), or None
        The scale deviation used to compensate the angle. None with ≥ 2 heads and a whole
        revolution: self-calibrate this capture (as Kokuyama et al. (2015) do); with one head: no compensation.
        A curve from another capture is aligned to this one by correlation.
    head : int or "all"
        The head whose pulses give the rate (default 0, the reference, as in Kokuyama et al.'s Figure 9)
        or ``"all"`` for the head-averaged times (the average cancels every detectable order of
        the deviation, so compensation changes nothing there).
    average : int
        Pulse intervals averaged per rate point (Kokuyama et al. (2015): 10).
    set_rate_deg_s : float, deg/s, optional
        The commanded rate, for the bias.
    allan_angles_deg : array_like, deg, optional
        Angles φ for s(φ) (default 12 per decade).
    compensate : bool
        Set False to skip compensation (results then equal the uncompensated ones).
    specs : InstrumentSpecs, optional
        The lab's instrument specifications (Type B inputs). Used: ``timebase.relative_error``
        (mean rate and bias; a stated mean error δ̂ corrects the rates by (1 + δ̂), GUM §3.2.4),
        ``encoder.undetectable_harmonics_arcsec`` (what the compensation cannot remove),
        ``encoder.graduation_error_arcsec`` (an uncompensated rate; its mean is a common offset
        that cancels in every rate). None: Type A only. A specification is never subtracted from
        the rate deviation: it widens its interval only.
    readout_resolution_deg : float, deg, optional
        Given when the pulse times are the crossings of virtual marks interpolated from angle or
        counter readings (:mod:`rotacal.table.rate_angle`): the readout's quantum q (360/N for a
        counter; 0 for a continuous readout). Every pulse then sits within a width q of its
        mark, a Type B input of the mean rate, the bias and the rate deviation (JCGM 100
        F.2.2.1; :func:`rotacal.table.rate_budgets._resolution_input`), and the period check of
        a single head is skipped (virtual marks have no graduation pattern; a quantisation
        pattern would be taken for one). None: the times of a real encoder's pulses.

    Returns
    -------
    RateResult
        With uncertainty budgets of the mean rate, the bias, the rms and peak rate deviation
        (plain value, bias of the noise of known level, 95 % interval for the true value) and
        the uncertainty of every s(φ).

    Raises
    ------
    CaptureError, ConfigError
        Bad pulse trains, an unknown head, a deviation curve for another m or one that cannot be
        aligned with this capture.

    References
    ----------
    Kokuyama et al. (2015), §5: time-difference rate with 10-point averaging, Figure 9 (rate
    compensated with the extracted deviation, bias and fluctuation in % of rate), the relative root
    Allan variance s(φ) of Figure 10. JCGM 100:2008 (GUM), JCGM 101:2008 (the budgets); Greenhall
    & Riley 2003 (edf of s(φ)).
    """
    m = check_pulses_per_rev(pulses_per_rev)
    _check_settings(specs, set_rate_deg_s)
    if readout_resolution_deg is not None:
        check_setting("readout_resolution_deg", readout_resolution_deg, positive=False, unit="deg")
        if readout_resolution_deg < 0:
            raise ConfigError(
                f"readout_resolution_deg must be ≥ 0 deg, got {readout_resolution_deg:g}."
            )
    if isinstance(heads, Mapping):
        trains = head_columns(heads)
    else:
        trains = [np.asarray(h, dtype=np.float64) for h in heads]
    if not trains:
        raise CaptureError("no pulse trains given; the capture needs head_0 (and more heads).")
    names = [f"head_{i}" for i in range(len(trains))]
    trains = [check_pulse_times(t, name) for t, name in zip(trains, names, strict=True)]
    n = len(trains)
    use_all = isinstance(head, str) and head == "all"
    k = 0 if use_all else _head_index(head, n)
    notes: list[str] = []

    made: SelfCalibration | None = None
    own_revs: int | None = None  # revolutions of a curve self-calibrated from this capture
    own_shifts: list[int] | None = None
    deviation: FloatArray | None = None
    shift: int | None = None
    correlation: float | None = None
    if compensate and not use_all:
        if selfcal is None and n >= 2:
            try:
                made = self_calibrate(trains, pulses_per_rev=m, specs=specs)
            except CaptureError as e:
                raise CaptureError(
                    f"{e} (the rate is compensated with a self-calibration of this capture; "
                    "give one with --selfcal, or use --no-compensation)"
                ) from None
            selfcal = made
            notes.append(
                f"compensated with the deviation self-calibrated from this capture "
                f"({made.heads} heads, {made.revolutions_used} revolutions)."
            )
        if selfcal is None:
            notes.append("one head and no self-calibration given: the rate is not compensated.")
        else:
            dev = _as_deviation(selfcal, m)
            deviation = dev.values
            here = (float(trains[0][0]), float(trains[0][-1]), int(trains[0].size))
            same = same_capture(dev, here)
            shift = 0  # deviation index of head 0's first pulse
            if same and dev.shifts is not None and len(dev.shifts) == n:
                own_shifts = dev.shifts
                own_revs = own_revolutions(selfcal)
            if not same:
                shift, correlation = align_deviation(trains, deviation, m)
                accept_alignment(shift, correlation, notes)
            if k != 0:
                # head k's first pulse sees the line s_k ahead of the head-0 pulse it pairs with
                pairing = pair_heads(trains, names)
                shifts = dev.shifts or list(head_shifts(n, m, dev.rotation))
                if len(shifts) != n:
                    raise ConfigError(
                        f"the self-calibration is of {len(shifts)} heads, the capture has {n}."
                    )
                shift = (shift + shifts[k] - int(pairing.index_offsets[k])) % m
    elif use_all:
        notes.append(
            "rate from the head-averaged pulse times: the average cancels every detectable order "
            "of the scale deviation, so there is nothing to compensate."
        )

    if use_all:
        if n < 2:
            raise ConfigError("head='all' needs at least 2 heads; the capture has one.")
        pairing = pair_heads(trains, names)
        times = pairing.mean_times_s
        notes.extend(pairing.notes)
        label = "all heads"
    else:
        times = trains[k]
        label = f"head_{k}"
    chunk = _ARRAY_CHUNK

    def chunks() -> Iterator[FloatArray]:
        for start in range(0, times.size, chunk):
            yield times[start : start + chunk]

    return _rate_result(
        chunks,
        int(times.size),
        m=m,
        heads=n,
        k=k,
        use_all=use_all,
        label=label,
        selfcal=selfcal,
        made=made,
        deviation=deviation,
        shift=shift,
        correlation=correlation,
        own=(
            None
            if own_shifts is None or own_revs is None or use_all
            else (own_shifts, k, own_revs, min(1.0, own_revs * m / max(times.size - 1, 1)))
        ),
        average=average,
        set_rate_deg_s=set_rate_deg_s,
        allan_angles_deg=allan_angles_deg,
        specs=specs,
        notes=notes,
        keep_series=True,
        resolution_deg=readout_resolution_deg or None,
        virtual_marks=readout_resolution_deg is not None,
    )


def _rate_result(
    chunks: Callable[[], Iterator[FloatArray]],
    pulses: int,
    *,
    m: int,
    heads: int,
    k: int,
    use_all: bool,
    label: str,
    selfcal: Any,
    made: SelfCalibration | None,
    deviation: FloatArray | None,
    shift: int | None,
    correlation: float | None,
    own: tuple[list[int], int, int, float] | None,
    average: int,
    set_rate_deg_s: float | None,
    allan_angles_deg: ArrayLike | None,
    specs: InstrumentSpecs | None,
    notes: list[str],
    keep_series: bool,
    progress: Callable[[int], None] | None = None,
    run_passes: Callable[..., RatePasses] = rate_passes,
    resolution_deg: float | None = None,
    virtual_marks: bool = False,
) -> RateResult:
    """The analysis of one train of ``pulses`` times given chunk by chunk (both passes of
    :func:`rotacal.table.rate_stream.rate_passes`, or ``run_passes`` with its arguments), its
    budgets and the result (``resolution_deg``, ``virtual_marks``: see ``calibrate_rate``'s
    ``readout_resolution_deg``)."""
    n = heads

    def sources_for(omega: float, jitter: tuple[float, float, bool]) -> list[ErrorProcess]:
        found, more = _deviation_sources(
            m=m,
            heads=n,
            use_all=use_all,
            compensated=deviation is not None,
            selfcal=selfcal,
            specs=specs,
            average=int(average),
            omega=omega,
            jitter=jitter,
            own=own,
            resolution_deg=resolution_deg,
        )
        source_notes[:] = more
        return found

    source_notes: list[str] = []
    passes = run_passes(
        chunks,
        pulses,
        pulses_per_rev=m,
        average=average,
        deviation=deviation,
        shift=shift or 0,
        allan_angles_deg=allan_angles_deg,
        sources_for=sources_for,
        prefix_pulses=max(PERIOD_CHECK_PULSES, 8 * m) if n == 1 else 0,
        keep_series=keep_series,
        progress=progress,
    )
    if n == 1 and pulses > m and not virtual_marks:
        # one head: nothing else checks m; its angle error must repeat once per revolution.
        # Judged on the first PERIOD_CHECK_PULSES pulses (8 revolutions at least; 29 of 18,000
        # pulses): as much evidence as any record of that length, and the whole-record FFT of a
        # long capture was its largest array and a third of its time.
        used = max(PERIOD_CHECK_PULSES, 8 * m)
        head_t, head_angle = passes.prefix
        t_rel = head_t - head_t[0]
        err = head_angle - np.polyval(np.polyfit(t_rel, head_angle, 1), t_rel)
        if not check_period(-err, m, coarse=False):
            judged = f" (judged on its first {used} pulses)" if pulses > used else ""
            notes.append(
                f"one head: {m} pulses per revolution cannot be confirmed from the data's own "
                f"period{judged} (too short a record, or too weak a graduation pattern); a wrong "
                "count scales the rate."
            )
    mean_rate, revs = passes.mean_rate, passes.revolutions
    window = [passes.first_t, passes.window_end]
    if revs < 1:
        notes.append(
            f"less than one whole revolution ({pulses} pulses of {m}): the mean rate is a "
            "straight-line fit of the compensated angle, not exact over revolutions."
        )
    jitter = passes.jitter
    if not jitter[2]:
        notes.append(
            "fewer than two whole revolutions: the timing jitter is estimated along the pulses "
            "and holds the graduation error too (an upper bound)."
        )
    phi, s, s_nom = passes.phi, passes.s, passes.s_nom
    set_rate: float | None = None
    if set_rate_deg_s is not None:
        set_rate = abs(float(set_rate_deg_s))
        if float(set_rate_deg_s) < 0:
            notes.append(
                "pulse times carry no sense of rotation: the mean rate is a magnitude and is "
                f"compared with |set rate| = {set_rate:g} °/s."
            )

    # ---- uncertainty
    correction = specs.mean(_TIMEBASE) if specs is not None else 0.0
    if correction != 0.0:
        notes.append(
            f"{specs.correction_note(_TIMEBASE) if specs is not None else ''} Every rate is "
            f"multiplied by 1 + δ̂ = {1 + correction:.10g}."
        )
    raw_rate = mean_rate  # in the DAQ's seconds, as the rate points
    budgets = _mean_rate_budgets(
        passes.rev_times, passes.short, m, revs, set_rate, specs, jitter, resolution_deg
    )
    mean_rate = budgets["mean_rate_deg_s"].value  # one truth: the field is the budget's value
    bias = bias_pct = None
    if set_rate is not None:
        bias = budgets["rate_bias_deg_s"].value
        bias_pct = budgets["rate_bias_percent"].value
    sources = sources_for(raw_rate, jitter)
    assert passes.peak is not None  # the timing jitter is always a source
    dev_sum = _rate_deviation_budgets(passes.rms_stats, passes.peak, sources, source_notes, specs)
    budgets.update({key: sm.budget for key, sm in dev_sum.items()})
    rms_sum = dev_sum["rate_deviation_rms_percent"]
    peak_sum = dev_sum["rate_deviation_peak_percent"]
    a_u, a_big_u, a_edf, a_lo, a_hi, a_alpha = allan_uncertainty(s, phi, 360.0 / m, pulses)
    factor = 1.0 + correction
    if passes.series is not None:
        t_avg, rate, rate_nom = passes.series
        rate = rate * factor
        rate_nom = rate_nom * factor
    else:
        t_avg = rate = rate_nom = np.zeros(0)
    return RateResult(
        mean_rate_deg_s=float(mean_rate),
        rate_deviation_rms_percent=rms_sum.budget.value,  # one truth: the budgets' values
        rate_deviation_peak_percent=peak_sum.budget.value,
        rate_deviation_rms_percent_uncompensated=passes.rms_nom,
        rate_deviation_peak_percent_uncompensated=passes.peak_nom,
        allan_angle_deg=[float(x) for x in phi],
        allan_tau_s=[float(x / abs(mean_rate)) for x in phi],
        allan_relative=[float(x) for x in s],
        allan_relative_uncompensated=[float(x) for x in s_nom],
        set_rate_deg_s=None if set_rate_deg_s is None else float(set_rate_deg_s),
        rate_bias_deg_s=bias,
        rate_bias_percent=bias_pct,
        head=label,
        average=int(average),
        revolutions=int(revs),
        mean_rate_window_s=window,
        duration_s=float(passes.last_t - passes.first_t),
        compensated=deviation is not None,
        deviation_shift_pulses=shift,
        alignment_correlation=correlation,
        notes=notes,
        _time_s=t_avg,
        _rate_deg_s=rate,
        _rate_uncompensated_deg_s=rate_nom,
        _selfcal=made,
        timing_jitter_s=jitter[0],
        timing_jitter_dof=jitter[1],
        timebase_correction=correction,
        rate_deviation_rms_percent_bias=rms_sum.bias,
        rate_deviation_rms_percent_bias_corrected=rms_sum.bias_corrected,
        rate_deviation_peak_percent_bias=peak_sum.bias,
        rate_deviation_peak_percent_bias_corrected=peak_sum.bias_corrected,
        allan_relative_u=[float(x) for x in a_u],
        allan_relative_U=[float(x) for x in a_big_u],
        allan_relative_edf=[float(x) for x in a_edf],
        allan_relative_interval=[[float(lo), float(hi)] for lo, hi in zip(a_lo, a_hi, strict=True)],
        allan_noise_alpha=[int(x) for x in a_alpha],
        _budgets=budgets,
        warnings=tuple(
            rate_warnings(
                mean_rate_deg_s=float(mean_rate),
                set_rate_deg_s=set_rate,
                trend=passes.trend,
                trend_scale=passes.trend_scale,
            )
        ),
    )
