"""Self-calibration of a multi-head rotary encoder by the equal-division-averaged method (Kokuyama et al. 2015).

n read heads sit at equal intervals around one scale of m lines. Head i reads the same scale
deviation a(k) as head 0, shifted by m·i/n lines: a_i(k) = a(k + m·i/n) (Kokuyama et al., §3;
Masuda & Kajitani 1993; Watanabe et al. 2005). Comparing every head with head 0 at the same
instant gives, for each head-0 pulse j, the angle difference

    D_i(j) = a(j + s_i) − a(j) + c_i,        s_i = round(i·m/n),

with c_i the head's small placement error (a constant). Averaging the n shifted copies cancels every
Fourier order of a(k) except the multiples of n, which no arrangement of n equally spaced heads can
see — the equal-division-averaged (EDA) method.

rotacal solves the same equations per Fourier order as a generalised least-squares fit that takes
into account that every difference shares head 0's noise: for equally spaced heads it reduces
exactly to the EDA average of the shifted copies ("each head's difference curve, shifted back by its
head's offset, averaged over all heads"), and it also honours shifts s_i that are not exactly i·m/n
(m not divisible by n). Orders where the heads give no information (the multiples of n for equal
spacing) are set to zero and listed.

Heads are compared in time, not by pulse index: the angle between head 0's pulse j and the nearest
pulse of head i is their time difference times the local rate (estimated from the head-averaged
pulse times, in which the deviation cancels), so late-starting heads and rate fluctuations do not
bias the curve. The deviation is the average over every whole revolution the heads share, and the
repeatability is each revolution's curve minus that average (Kokuyama et al.'s Figure 5).

Uncertainty (GUM, JCGM 100; Monte Carlo, JCGM 101). The estimator is circulant — the same linear
fit per Fourier order — so its noise has the same variance at every line: the standard uncertainty
of each point is the revolutions' spread pooled over the lines (Type A; ν from the spread of every
detectable order, Welch–Satterthwaite), plus, when the lab states it, the orders no n-head
arrangement can see (``encoder.undetectable_harmonics_arcsec``, Type B). The peak-to-peak and rms
of the curve are max/rms-type: noise biases them upward, so their budgets
(:mod:`rotacal.uncertainty.summaries`) state the plain value, the noise's bias beside it, and a
95 % interval for the true value (closed form for the rms, Monte Carlo for the peak-to-peak), the
noise drawn with the spectrum the revolutions show.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping, Sequence
from typing import Any, Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from rotacal.encoder.plausibility import selfcal_warnings
from rotacal.encoder.pulses import (
    check_heads_not_copies,
    check_pulse_times,
    check_pulses_per_rev,
    head_columns,
    pair_heads,
)
from rotacal.encoder.selfcal_checks import (
    _check_pulses_per_rev_by_closure,
    check_period,
)
from rotacal.encoder.selfcal_fit import (
    RATE_WINDOW,
    _data_shifts,
    _local_rate_deg_s,
    fit_revolutions,
    head_shifts,
    noise_gain,
    undetectable_orders,
)
from rotacal.encoder.selfcal_uncertainty import (
    UNDETECTABLE_SPEC,
    DeviationNoise,
    _bias,
    _deviation_uncertainty,
    _head_offsets_u,
    _order_spread,
    _repeatability_rms,
    undetectable_input,
)
from rotacal.errors import CaptureError, ConfigError
from rotacal.results import Result
from rotacal.uncertainty import (
    InstrumentSpecs,
    UncertaintyBudget,
    coverage_factor,
    uncertainty_keys,
)

# the fit, the checks and the uncertainty live beside this module, along the data's path; their
# public names (and the private ones other modules and tests reach for) are re-exported here
__all__ = [
    "RATE_WINDOW",
    "UNDETECTABLE_SPEC",
    "DeviationNoise",
    "SelfCalibration",
    "check_period",
    "head_shifts",
    "noise_gain",
    "self_calibrate",
    "undetectable_input",
    "undetectable_orders",
]

FloatArray = NDArray[np.float64]


@dataclasses.dataclass(frozen=True)
class SelfCalibration(Result):
    """Scale deviation of a multi-head encoder by self-calibration (INTERFACE.md ``selfcal``).

    Attributes
    ----------
    deviation_arcsec : ndarray, shape (m,), arcsec
        The scale's deviation; the true rotation from head-0 pulse 0 to head-0 pulse j
        (0 ≤ j < m, counted from the first head-0 pulse in the capture) is
        ``j·360/m + (deviation[j] − deviation[0])/3600`` deg. Zero mean; orders that are
        multiples of n are zero (undetectable).
    heads, pulses_per_rev : int
    deviation_pp_arcsec, deviation_rms_arcsec : float, arcsec
        Plain peak-to-peak and rms of ``deviation_arcsec`` (also the budgets' values).
    undetectable_harmonics_note : str
    undetectable_orders : list of int
        Fourier orders (per revolution, 1 … m/2) the heads cannot see.
    revolutions_used : int
        Whole revolutions averaged.
    repeatability_rms_arcsec, repeatability_pp_arcsec : float or None, arcsec
        Spread of the single-revolution curves about their mean (None with one revolution).
    deviation_u_arcsec : float or None, arcsec
        Standard uncertainty of every point of the curve (the same at every line): the
        revolutions' spread pooled over the lines (rms over the lines of std/√R), combined with
        the stated ``encoder.undetectable_harmonics_arcsec`` when given. The same number as each
        element of the JSON ``deviation_arcsec_u``. None with one revolution and no
        specification (with one revolution and the specification: the specification alone).
    deviation_dof : float or None
        Effective degrees of freedom of ``deviation_u_arcsec`` (Welch–Satterthwaite).
    deviation_pp_arcsec_bias, deviation_rms_arcsec_bias : float or None, arcsec
        How much the curve's noise (Type A, from the revolutions) raises the plain peak-to-peak
        and rms; None with one revolution (the noise is then unknown).
    deviation_pp_arcsec_bias_corrected, deviation_rms_arcsec_bias_corrected : float or None
        The plain values less that bias (arcsec). The 95 % interval for the true value (which
        also holds the undetectable orders when their specification is stated) is the JSON
        ``deviation_pp_arcsec_interval`` / ``deviation_rms_arcsec_interval``.
    closure_residual_rms_arcsec : float, arcsec
        rms of what the fitted curve leaves unexplained in the head differences (noise, rate
        changes within a pitch, head misnumbering).
    head_offsets_arcsec : list of float, arcsec
        Each head's placement against its nominal i·360/n, modulo one pitch.
    head_offsets_arcsec_u : list of float or None, arcsec
        Standard uncertainty of each placement (Type A): the spread over the whole revolutions of
        that revolution's mean head difference, s/√R, as the curve's u is made from the
        revolutions; 0 for head 0 (the reference, by definition). None with one revolution.
    head_offsets_dof : float or None
        Degrees of freedom of ``head_offsets_arcsec_u``: R − 1.
    harmonic_amplitudes_arcsec : list of float, arcsec
        Amplitude of orders 1 … min(m/2, 100) of the deviation.
    rotation : str
        ``"forward"`` (head i is i·360/n ahead in the sense of rotation) or ``"reverse"``.
    head_line_shifts : list of int
        The scale line each head sees at the moment head 0 sees line 0 (modulo m).
    first_pulse_time_s, last_pulse_time_s : float, s
        Times of head 0's first (index 0 of ``deviation_arcsec``) and last pulse.
    head0_pulses : int
        Pulses of head 0 in the capture (with the two times: which capture this curve indexes).
    notes : list of str

    ``to_dict()`` adds the uncertainty keys: ``deviation_arcsec_u`` and ``deviation_arcsec_U``
    (arrays of m values, arcsec), ``deviation_pp_arcsec_u``/``_U`` and
    ``deviation_rms_arcsec_u``/``_U``/``_interval`` (arcsec; u the standard deviation of the
    summary's error, U half the interval's width), ``k`` (per quantity), ``coverage_probability``
    and ``uncertainty_budgets``.
    """

    deviation_arcsec: FloatArray
    heads: int
    pulses_per_rev: int
    deviation_pp_arcsec: float
    deviation_rms_arcsec: float
    undetectable_harmonics_note: str
    undetectable_orders: list[int]
    revolutions_used: int
    repeatability_rms_arcsec: float | None
    repeatability_pp_arcsec: float | None
    deviation_u_arcsec: float | None
    deviation_dof: float | None
    deviation_pp_arcsec_bias: float | None
    deviation_pp_arcsec_bias_corrected: float | None
    deviation_rms_arcsec_bias: float | None
    deviation_rms_arcsec_bias_corrected: float | None
    closure_residual_rms_arcsec: float
    head_offsets_arcsec: list[float]
    harmonic_amplitudes_arcsec: list[float]
    rotation: str
    head_line_shifts: list[int]
    first_pulse_time_s: float
    last_pulse_time_s: float
    head0_pulses: int
    notes: list[str]
    _per_revolution_arcsec: FloatArray = dataclasses.field(repr=False)
    _spectrum_arcsec: FloatArray = dataclasses.field(repr=False)
    head_offsets_arcsec_u: list[float] | None = None
    head_offsets_dof: float | None = None
    _noise: DeviationNoise | None = dataclasses.field(repr=False, default=None)
    _point_budget: UncertaintyBudget | None = dataclasses.field(repr=False, default=None)
    _budgets: dict[str, UncertaintyBudget] = dataclasses.field(repr=False, default_factory=dict)

    def to_dict(self) -> dict[str, Any]:
        out = super().to_dict()
        out.update(uncertainty_keys(self._budgets))
        pb = self._point_budget
        if pb is None:
            out["deviation_arcsec_u"] = out["deviation_arcsec_U"] = None
        else:
            m = self.pulses_per_rev
            out["deviation_arcsec_u"] = [pb.u] * m
            out["deviation_arcsec_U"] = [pb.U] * m
            out["k"]["deviation_arcsec"] = pb.k
            out["uncertainty_budgets"]["deviation_arcsec"] = pb.to_dict()
            if out["coverage_probability"] is None:
                out["coverage_probability"] = pb.p
        out["head_offsets_arcsec_U"] = self.head_offsets_arcsec_U
        if self.head_offsets_arcsec_U is not None:
            out["k"]["head_offsets_arcsec"] = self.head_offsets_k
        return out

    @property
    def head_offsets_k(self) -> float | None:
        """Coverage factor of the placements' U: t_95(R − 1) (GUM G.3.2); None with one revolution."""
        if self.head_offsets_dof is None:
            return None
        return coverage_factor(self.head_offsets_dof, 0.95)

    @property
    def head_offsets_arcsec_U(self) -> list[float] | None:
        """Expanded uncertainty of each head placement (arcsec, p = 95 %), None with one revolution."""
        k = self.head_offsets_k
        if k is None or self.head_offsets_arcsec_u is None:
            return None
        return [k * u for u in self.head_offsets_arcsec_u]

    @property
    def budgets(self) -> dict[str, UncertaintyBudget]:
        """Uncertainty budgets by JSON key (``deviation_pp_arcsec``, ``deviation_rms_arcsec``)."""
        return dict(self._budgets)

    @property
    def point_budget(self) -> UncertaintyBudget | None:
        """The budget of one point of the curve (any line; its ``value`` is 0: the budget's
        inputs are errors), None with one revolution and no specification."""
        return self._point_budget

    @property
    def deviation_arcsec_u(self) -> FloatArray | None:
        """Standard uncertainty of every point of ``deviation_arcsec`` (arcsec), or None."""
        pb = self._point_budget
        return None if pb is None else np.full(self.pulses_per_rev, pb.u)

    @property
    def deviation_arcsec_U(self) -> FloatArray | None:
        """Expanded uncertainty (p = 95 %) of every point of ``deviation_arcsec`` (arcsec)."""
        pb = self._point_budget
        return None if pb is None else np.full(self.pulses_per_rev, pb.U)

    @property
    def per_revolution_arcsec(self) -> FloatArray:
        """Each whole revolution's curve, shape (R, m), indexed like ``deviation_arcsec``."""
        return self._per_revolution_arcsec

    @property
    def repeatability_arcsec(self) -> FloatArray:
        """Each revolution minus the mean of all (Kokuyama et al.'s Figure 5), shape (R, m)."""
        return self._per_revolution_arcsec - self.deviation_arcsec

    @property
    def spectrum_arcsec(self) -> FloatArray:
        """Amplitude (arcsec) of every order 0 … m/2 of the deviation."""
        return self._spectrum_arcsec


def self_calibrate(
    heads: Sequence[ArrayLike] | Mapping[str, ArrayLike],
    *,
    pulses_per_rev: int,
    rotation: Literal["auto", "forward", "reverse"] = "auto",
    specs: InstrumentSpecs | None = None,
) -> SelfCalibration:
    """Scale deviation of an n-head encoder by the equal-division-averaged method.

    Parameters
    ----------
    heads : sequence of array_like, or mapping with ``head_0`` … ``head_{n-1}``, s
        Pulse edge times of each head; head 0 is the reference, the heads equally spaced
        (within half a pitch) and numbered in one sense around the scale. Heads may start and
        stop at different times; only the span all of them cover is compared.
    pulses_per_rev : int
        m, pulses per revolution of one head.
    rotation : {"auto", "forward", "reverse"}
        Whether head i lies i·360/n ahead of head 0 in the sense of rotation ("forward") or
        behind ("reverse"); "auto" takes the one whose model explains the head differences
        better (undecidable with 2 heads: forward).
    specs : InstrumentSpecs, optional
        The lab's instrument specifications (Type B inputs). Used:
        ``encoder.undetectable_harmonics_arcsec`` (the rms, arcsec, of the scale's deviation at
        the orders that are multiples of n; a stated mean enters as √(mean² + u²), see
        :func:`undetectable_input`). A timebase error scales the delays and the rate that turns
        them into angles alike, so it does not enter. None: Type A only.

    Returns
    -------
    SelfCalibration
        With the standard uncertainty of every point (the revolutions' spread, Type A) and the
        budgets of the peak-to-peak (Monte Carlo) and rms (closed form) — plain value, noise
        bias, 95 % interval for the true value — when the heads share two or more whole
        revolutions; with one, from ``encoder.undetectable_harmonics_arcsec`` alone when stated.

    Raises
    ------
    CaptureError
        Fewer than 2 heads, bad pulse trains (see :func:`check_pulse_times`), a head that is a
        (time-shifted) copy of head 0 (:func:`~rotacal.encoder.pulses.check_heads_not_copies`:
        copies carry no information about the scale), heads that cannot be paired, less than one
        whole revolution covered by all heads, a pulses_per_rev that does not match the period of
        the data.

    See Also
    --------
    rotacal.encoder.self_calibrate_chunked : the same from heads read in chunks (flat memory).

    References
    ----------
    Kokuyama W., Watanabe T., Nozato H., Ota A., "Development of angular velocity calibration
    facility using self-calibratable rotary encoder", §3: s_i(k) = kΔθ + 360i/n + a_i(k),
    m = 360/Δθ, a_i(k) = a(k + m·i/n); Figures 4–5.
    Masuda T., Kajitani M., "High accuracy calibration system for angular encoders", J. Robotics
    and Mechatronics 5 (1993) — the equal-division-averaged method.
    JCGM 100:2008 (GUM) §4.2, G.4; JCGM 101:2008 §7 (the uncertainty of the curve and its
    summaries).
    """
    m = _check_settings(pulses_per_rev, rotation, specs)
    if isinstance(heads, Mapping):
        trains = head_columns(heads)
    else:
        trains = [np.asarray(h, dtype=np.float64) for h in heads]
    n = len(trains)
    _check_heads(n, m)
    names = [f"head_{i}" for i in range(n)]
    trains = [check_pulse_times(t, name) for t, name in zip(trains, names, strict=True)]
    _check_head0_length(trains[0].size, m)
    check_heads_not_copies(trains, names)
    pairing = pair_heads(trains, names)
    revs = _whole_revolutions(pairing.pulses, m, pairing.notes)
    pitch = 360.0 / m
    rate = _local_rate_deg_s(pairing.mean_times_s, pitch)
    angle_diff = pairing.delays_s[1:]  # s → arcsec in place, shape (n−1, J)
    angle_diff *= rate * 3600.0
    # the pairing's per-pulse delays (now angles) and mean times are not needed past here
    first_paired, pairing_notes = pairing.first, pairing.notes
    del pairing, rate
    period_checked = check_period(angle_diff.mean(axis=0)[: period_check_pulses(m)], m)

    used = angle_diff[:, : revs * m].reshape(n - 1, revs, m).transpose(1, 0, 2)  # (R, n−1, m)
    rev_offsets = used.mean(axis=2)  # (R, n−1)
    offsets_mean = used.mean(axis=(0, 2))
    candidates = ["forward", "reverse"] if rotation == "auto" else [rotation]
    fits = fit_revolutions(used, {c: _data_shifts(n, m, c, offsets_mean) for c in candidates}, m)
    notes = list(pairing_notes)
    sense = _choose_sense({c: fits[c][1] for c in fits}, rotation, n, notes)
    _pulses_per_rev_notes(angle_diff, m, period_checked, notes)
    a, ss, shifts = fits[sense]
    unrolled = np.fft.irfft(a, m, axis=-1)  # (R, m), index j' = head-0 pulse first + r·m + j'
    per_rev = np.roll(unrolled, first_paired % m, axis=1)
    return _assemble(
        _Fitted(
            heads=n,
            pulses_per_rev=m,
            sense=sense,
            shifts=shifts,
            ss=ss,
            mean_curve=unrolled.mean(axis=0),
            per_rev=per_rev,
            spread=None,
            rev_offsets=rev_offsets,
            first_paired=first_paired,
            first_time_s=float(trains[0][0]),
            last_time_s=float(trains[0][-1]),
            head0_pulses=int(trains[0].size),
        ),
        notes,
        specs,
    )


#: Head-averaged differences (pulses of head 0, from the first paired one) on which the period
#: of the data is checked: the check's FFT is then bounded whatever the record's length (a long
#: record repeats the same revolutions; at least two revolutions are always looked at).
PERIOD_CHECK_PULSES = 1 << 21


def period_check_pulses(m: int) -> int:
    """How many head-averaged differences :func:`check_period` is given (see PERIOD_CHECK_PULSES)."""
    return max(PERIOD_CHECK_PULSES, 2 * m)


def closure_check_pulses(m: int) -> int:
    """How many head differences the closure check of m can use (it tries counts up to 4m + 3)."""
    return 4 * m + 4


def _check_settings(pulses_per_rev: Any, rotation: Any, specs: Any) -> int:
    m = check_pulses_per_rev(pulses_per_rev)
    if specs is not None and not isinstance(specs, InstrumentSpecs):
        raise ConfigError(
            f"specs must be the InstrumentSpecs of load_specs(...), got {type(specs).__name__}."
        )
    if rotation not in ("auto", "forward", "reverse"):
        raise ConfigError(f"rotation must be 'auto', 'forward' or 'reverse', got {rotation!r}.")
    return m


def _check_heads(n: int, m: int) -> None:
    if n < 2:
        raise CaptureError(
            f"self-calibration needs at least 2 heads, the capture has {n}; give head_0 … head_{{n-1}}."
        )
    if m < n:
        raise ConfigError(f"pulses_per_rev ({m}) must be at least the number of heads ({n}).")


def _check_head0_length(pulses: int, m: int) -> None:
    if pulses - 1 < m:
        raise CaptureError(
            f"head_0 has {pulses} pulses, less than one revolution of {m}: record at least "
            "one whole revolution (or check --pulses-per-rev)."
        )


def _whole_revolutions(paired: int, m: int, notes: Sequence[str]) -> int:
    revs = paired // m
    if revs < 1:
        raise CaptureError(
            f"all heads together cover only {paired} pulses of head_0, less than one "
            f"revolution of {m} ({'; '.join(notes) or 'the heads overlap too little'})."
        )
    return revs


def _choose_sense(ss: Mapping[str, float], rotation: str, n: int, notes: list[str]) -> str:
    """The sense of rotation whose fit leaves the least (closure sums of squares ``ss``)."""
    sense = min(ss, key=lambda k: ss[k])
    if rotation == "auto" and n == 2:
        sense = "forward"
    if rotation == "auto" and n > 2:
        other = "reverse" if sense == "forward" else "forward"
        if ss[other] < 2.0 * ss[sense]:
            notes.append(
                "the sense of rotation against the head numbering is unclear from the data (both "
                f"fit about as well); took '{sense}'. Give rotation= (--rotation) if you know it."
            )
    return sense


def _pulses_per_rev_notes(
    angle_diff: FloatArray, m: int, period_checked: bool, notes: list[str]
) -> None:
    """The closure check of m (three or more heads) and the notes on what could not be checked.
    ``angle_diff``: head differences (arcsec) from the first paired pulse, at least the first
    :func:`closure_check_pulses` of them (all when the record is shorter)."""
    if not period_checked:
        notes.append(
            f"the data cannot confirm {m} pulses per revolution from their own period (a record "
            "under 1.25 revolutions shared by all heads, or a weak deviation); only near and "
            "whole-ratio mistakes are caught."
        )
    if angle_diff.shape[0] >= 2:
        _check_pulses_per_rev_by_closure(
            angle_diff[:, : closure_check_pulses(m)], m, near=not period_checked
        )
    else:
        notes.append(
            "with two heads every curve fits the head differences exactly: neither the pulses per "
            "revolution nor the fit can be checked from the data."
        )


@dataclasses.dataclass(frozen=True)
class _Fitted:
    """What the result is made of, from either path (in memory, or streamed in chunks).

    ``mean_curve``: the mean over the R revolutions of each one's fitted curve, indexed from the
    first paired head-0 pulse (arcsec, shape (m,)); ``per_rev``: each revolution's curve indexed
    like ``deviation_arcsec`` (shape (R, m), possibly a memory map); ``spread``: Σ_r |A_r − Ā|²
    per rfft order (:func:`_order_spread`; None: computed from ``per_rev``); ``rev_offsets``:
    each revolution's mean head difference (arcsec, shape (R, n − 1)); ``ss``: the closure sum
    of squares of the chosen sense (arcsec²).
    """

    heads: int
    pulses_per_rev: int
    sense: str
    shifts: NDArray[np.int64]
    ss: float
    mean_curve: FloatArray
    per_rev: FloatArray
    spread: FloatArray | None
    rev_offsets: FloatArray
    first_paired: int
    first_time_s: float
    last_time_s: float
    head0_pulses: int


#: Revolutions whose repeatability is formed at a time (the curves may be a memory map).
_REP_BLOCK = 64


def _repeatability_pp(per_rev: FloatArray, deviation: FloatArray) -> float:
    """Largest peak-to-peak over the revolutions of each one's curve minus the mean (arcsec)."""
    worst = -math.inf
    for r0 in range(0, per_rev.shape[0], _REP_BLOCK):
        rep = per_rev[r0 : r0 + _REP_BLOCK] - deviation
        worst = max(worst, float(np.max(rep.max(axis=1) - rep.min(axis=1))))
        if isinstance(per_rev, np.memmap):  # curves spilled by the chunked path: flat memory
            from rotacal.io.capture import release_pages

            release_pages({"curves": per_rev[r0 : r0 + _REP_BLOCK]})
    return worst


def _assemble(fit: _Fitted, notes: list[str], specs: InstrumentSpecs | None) -> SelfCalibration:
    """The SelfCalibration from the fitted revolutions: curve, repeatability, budgets, notes."""
    n, m, sense, shifts = fit.heads, fit.pulses_per_rev, fit.sense, fit.shifts
    revs = fit.rev_offsets.shape[0]
    closure_rms = float(np.sqrt(fit.ss / (revs * (n - 1) * m)))
    deviation = np.roll(fit.mean_curve, fit.first_paired % m)
    undetect = undetectable_orders(n, m, shifts)
    spread = _order_spread(fit.per_rev, deviation) if fit.spread is None else fit.spread
    if revs >= 2:
        rep_rms: float | None = _repeatability_rms(spread, revs, m)
        rep_pp: float | None = _repeatability_pp(fit.per_rev, deviation)
    else:
        rep_rms = rep_pp = None
        notes.append(
            "one whole revolution only: no repeatability and no uncertainty from the data; "
            "record several revolutions."
        )
    noise, point, summaries = _deviation_uncertainty(spread, revs, deviation, undetect, specs)
    budgets = {key: sm.budget for key, sm in summaries.items()}
    # one truth: the JSON values are the budgets' values (the plain summaries of the curve)
    pp = budgets["deviation_pp_arcsec"].value if budgets else float(np.ptp(deviation))
    rms = (
        budgets["deviation_rms_arcsec"].value if budgets else float(np.sqrt(np.mean(deviation**2)))
    )
    amp = np.abs(np.fft.rfft(deviation)) * 2.0 / m
    amp[0] = 0.0
    if m % 2 == 0:
        amp[-1] /= 2.0
    if undetect:
        listed = ", ".join(str(q) for q in undetect[:5])
        more = ", …" if len(undetect) > 5 else ""
        exact = all(q % n == 0 for q in undetect) and m % n == 0
        why = (
            f"are multiples of {n} (the number of heads)"
            if exact
            else "are (nearly) blind to these heads' line shifts"
        )
        note = (
            f"Fourier orders {listed}{more} {why}: they are undetectable by equal-division "
            "averaging and are set to zero; the scale's true deviation may hold them."
        )
    else:
        note = "every Fourier order 1 … m/2 is detectable with these head shifts."
    pitch_arcsec = 360.0 / m * 3600.0
    nominal = np.arange(n) * 360.0 / n * 3600.0
    offsets_mean = fit.rev_offsets.mean(axis=0)
    placed = shifts * pitch_arcsec - np.concatenate(([0.0], offsets_mean))
    if sense == "reverse":
        placed = -placed
    head_off = (placed - nominal + pitch_arcsec / 2) % pitch_arcsec - pitch_arcsec / 2
    head_off[0] = 0.0
    offsets_u, offsets_dof = _head_offsets_u(fit.rev_offsets)
    return SelfCalibration(
        deviation_arcsec=deviation,
        heads=n,
        pulses_per_rev=m,
        deviation_pp_arcsec=pp,
        deviation_rms_arcsec=rms,
        undetectable_harmonics_note=note,
        undetectable_orders=undetect,
        revolutions_used=int(revs),
        repeatability_rms_arcsec=rep_rms,
        repeatability_pp_arcsec=rep_pp,
        deviation_u_arcsec=None if point is None else point.u,
        deviation_dof=None if point is None else point.dof_eff,
        deviation_pp_arcsec_bias=_bias(summaries, "deviation_pp_arcsec"),
        deviation_pp_arcsec_bias_corrected=_bias(summaries, "deviation_pp_arcsec", True),
        deviation_rms_arcsec_bias=_bias(summaries, "deviation_rms_arcsec"),
        deviation_rms_arcsec_bias_corrected=_bias(summaries, "deviation_rms_arcsec", True),
        closure_residual_rms_arcsec=closure_rms,
        head_offsets_arcsec=[float(x) for x in head_off],
        harmonic_amplitudes_arcsec=[float(x) for x in amp[1 : min(m // 2, 100) + 1]],
        rotation=sense,
        head_line_shifts=[int(x) for x in shifts],
        first_pulse_time_s=fit.first_time_s,
        last_pulse_time_s=fit.last_time_s,
        head0_pulses=fit.head0_pulses,
        notes=notes,
        head_offsets_arcsec_u=offsets_u,
        head_offsets_dof=offsets_dof,
        _per_revolution_arcsec=fit.per_rev,
        _spectrum_arcsec=amp,
        _noise=noise,
        _point_budget=point,
        _budgets=budgets,
        warnings=tuple(
            selfcal_warnings(
                closure_residual_rms_arcsec=closure_rms,
                repeatability_rms_arcsec=rep_rms,
                heads=n,
            )
        ),
    )
