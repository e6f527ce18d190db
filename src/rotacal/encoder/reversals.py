"""Reversing moments of the motion from the subinterval transitions (Feng et al. 2023, §3.1–3.3).

The third step of the chain of :mod:`rotacal.encoder.quadrature`: the odd/even rule of trend
changes (eqs. (5)–(6)), rotacal's cluster pruning by hysteresis, the reversing point of eqs.
(7)–(8) and the whole motion periods between 2n+1 reversals (§3.3).
"""

from __future__ import annotations

import dataclasses
import math
import warnings
from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from rotacal.encoder.phase import _transitions
from rotacal.errors import CaptureError, ConfigError
from rotacal.results import Result

FloatArray = NDArray[np.floating[Any]]
_TWO_PI = 2.0 * math.pi


#: Largest phase step (in 30° subintervals) between samples that is still demodulated.
_MAX_SAFE_STEP = 5


class SubdivisionWarning(UserWarning):
    """The sampling is too slow for the 12-fold subdivision (subintervals were skipped)."""


@dataclasses.dataclass(frozen=True)
class Reversals(Result):
    """Reversing moments of the motion (Feng et al. 2023, §3.1–3.2).

    Attributes
    ----------
    indices : ndarray of int
        Sample index of each reversing moment (Chp of eqs. (7)–(8)).
    times_s : ndarray of float
        Time of each reversing moment (s).
    kinds : ndarray of int
        +1 for a maximum of θ, −1 for a minimum; they alternate.
    candidates : int
        Reversals found by the odd/even rule (eqs. (5)–(6)) before cluster pruning.
    hysteresis_subintervals : int
        Excursion (in subintervals) below which neighbouring candidates were treated as one cluster.
    transitions : int
        Subinterval transitions in the capture.
    skipped_transitions : int
        Transitions that jumped over one subinterval or more (sampling too slow for the
        subdivision).
    max_step_subintervals : int
        Largest jump between two samples (subintervals); 1 is the normal value.
    """

    indices: np.ndarray
    times_s: np.ndarray
    kinds: np.ndarray
    candidates: int
    hysteresis_subintervals: int
    transitions: int = 0
    skipped_transitions: int = 0
    max_step_subintervals: int = 0

    def __len__(self) -> int:
        return int(self.indices.size)


# --------------------------------------------------------------------------------------------
# reversals
# --------------------------------------------------------------------------------------------


def _odd_runs(direction: NDArray[np.int8]) -> tuple[NDArray[np.intp], NDArray[np.intp]]:
    """First transition and length of each run of an odd number of consecutive trend changes."""
    change = direction[1:] != direction[:-1]  # change[j-1]: transition j turns the trend
    padded = np.concatenate(([False], change, [False]))
    edges = np.flatnonzero(padded[1:] != padded[:-1])
    starts = edges[0::2]
    lengths = edges[1::2] - starts
    odd = (lengths % 2) == 1
    return starts[odd] + 1, lengths[odd]


def _no_reversals(hyst: int, n_trans: int, skipped: int, max_step: int) -> ReversalPlan:
    """The plan of a capture in which no reversing moment was found."""
    no_windows = np.empty((0, 2), dtype=np.intp)
    return ReversalPlan(
        no_windows,
        no_windows.copy(),
        np.empty(0, dtype=np.int8),
        0,
        hyst,
        n_trans,
        skipped,
        max_step,
    )


def _direction(dk: FloatArray) -> NDArray[np.int8]:
    """sign(dk) as int8 from two comparisons (no float temporary; 0 where dk is 0)."""
    return (dk > 0).view(np.int8) - (dk < 0).view(np.int8)


def _candidates(
    k_after: FloatArray, direction: NDArray[np.int8]
) -> tuple[NDArray[np.intp], NDArray[np.intp], NDArray[np.int8], FloatArray]:
    """Reversal candidates of eqs. (5)–(6): runs of an odd number of consecutive trend changes.

    ``direction`` is the sign of each transition's step of k (:func:`_direction`). Transition j
    leads from subinterval visit j to visit j+1; visit m ≥ 1 holds the count ``k_after[m-1]``. A
    trend change at transition j makes visit j a turning visit, so a run of L changes starting at
    transition j0 has the turning visits j0 .. j0+L-1.

    Returns the first transition j0 and length L of each odd run, its kind (+1: a maximum of θ,
    the direction before the run was increasing) and its level (the extreme k of its turning
    visits: the highest for a maximum, the lowest for a minimum).
    """
    first_change, run_len = _odd_runs(direction)
    if first_change.size == 0:
        return first_change, run_len, np.empty(0, dtype=np.int8), np.empty(0)
    kinds = direction[first_change - 1]
    # the extremes over the turning visits alone (a few per run), not over every transition
    starts, rows = _window_rows(first_change - 1, run_len)
    turning = k_after[rows]
    hi = np.maximum.reduceat(turning, starts)
    lo = np.minimum.reduceat(turning, starts)
    return first_change, run_len, kinds, np.where(kinds > 0, hi, lo)


def reversing_subintervals(
    phase_rad: ArrayLike,
) -> tuple[NDArray[np.intp], NDArray[np.intp], NDArray[np.int8]]:
    """The subintervals holding a reversing moment, exactly as the paper identifies them.

    Runs of an even number of consecutive trend changes hold no reversal (eq. (5)); a run of an
    odd number holds one, in its middle subinterval visit (eq. (6): in {4,5,6,7,8,7,8,7,6,5} the
    second 7). No cluster pruning is applied here (see :func:`find_reversals`).

    Parameters
    ----------
    phase_rad : array_like
        Unwrapped signal phase φ (rad).

    Returns
    -------
    sub_minus, sub_plus : ndarray of int
        First and last sample index (inclusive) of each reversing subinterval visit.
    kinds : ndarray of int8
        +1 where the reversal is a maximum of θ, −1 a minimum.

    References
    ----------
    Feng et al. 2023, Sensors 23:4876, §3.1, eqs. (5)–(6).
    """
    idx, k_after, dk, _ = _transitions(np.asarray(phase_rad, dtype=np.float64))
    if idx.size < 2:
        empty = np.empty(0, dtype=np.intp)
        return empty, empty.copy(), np.empty(0, dtype=np.int8)
    first_change, run_len, kinds, _ = _candidates(k_after, _direction(dk))
    middle = first_change + (run_len - 1) // 2
    return idx[middle - 1], idx[middle] - 1, kinds


#: ``rows → (u, v)``: the corrected signals at the sample indices ``rows`` (int array).
WindowSignals = Callable[[NDArray[np.intp]], tuple[FloatArray, FloatArray]]


def _pinned(plan: ReversalPlan, t: FloatArray, signals: WindowSignals) -> Reversals:
    """The reversals of a plan, each pinned to its Chp (eqs. (7)–(8)) with its time (s).

    The samples of every window are gathered and corrected in one call and eqs. (7)–(8) are
    evaluated for all windows at once (:func:`_points_in_windows`): no Python loop per window.
    """
    first = plan.windows[:, 0]
    last = plan.windows[:, 1]
    chp = first.copy()  # a one-sample visit is its own Chp
    wide = np.flatnonzero(last > first)
    if wide.size:
        lo = np.maximum(first[wide] - 1, 0)
        hi = np.minimum(last[wide] + 1, t.size - 1)
        starts, rows = _window_rows(lo, hi - lo + 1)
        u, v = signals(rows)
        chp[wide] = lo + _points_in_windows(u, v, starts)
    indices = plan.indices(chp)
    return Reversals(
        indices=indices,
        times_s=t[indices],
        kinds=plan.kinds,
        candidates=plan.candidates,
        hysteresis_subintervals=plan.hysteresis_subintervals,
        transitions=plan.transitions,
        skipped_transitions=plan.skipped_transitions,
        max_step_subintervals=plan.max_step_subintervals,
    )


def _window_rows(
    lo: NDArray[np.intp], sizes: NDArray[np.intp]
) -> tuple[NDArray[np.intp], NDArray[np.intp]]:
    """Start of each window in the concatenation of windows ``lo .. lo + size − 1``, and the
    sample index of every row of that concatenation."""
    starts = np.cumsum(sizes) - sizes
    rows = np.arange(int(sizes.sum()), dtype=np.intp)
    rows += np.repeat(lo - starts, sizes)
    return starts, rows


def _points_in_windows(u: FloatArray, v: FloatArray, starts: NDArray[np.intp]) -> NDArray[np.intp]:
    """:func:`reversal_point_in_window` of each window of the concatenated ``u``, ``v`` (windows
    start at ``starts``, each of ≥ 2 samples; the last ends at the arrays' end), as offsets.

    The sums Σu, Σv are ``np.add.reduceat``'s, also for a single window, so that a window gives
    the same Chp whether it is evaluated alone (a chunked caller) or among all the others.
    """
    ends = np.append(starts[1:], u.size) - 1
    sizes = ends - starts + 1
    qu = np.add.reduceat(u, starts) - sizes * 0.5 * (u[starts] + u[ends])
    qv = np.add.reduceat(v, starts) - sizes * 0.5 * (v[starts] + v[ends])
    take_u = np.abs(qu) >= np.abs(qv)
    q = np.where(take_u, qu, qv)
    # the extreme eq. (8) asks for: the maximum of the chosen signal if q > 0, else its minimum,
    # i.e. the first maximum of the signal times sign(q) (a negation is exact)
    per_row = np.repeat(np.arange(starts.size), sizes)
    seg = np.where(take_u[per_row], u, v)
    seg *= np.where(q < 0, -1.0, 1.0)[per_row]
    top = np.maximum.reduceat(seg, starts)
    offset = np.arange(u.size, dtype=np.intp) - starts[per_row]
    at_top = np.where(seg == top[per_row], offset, u.size)
    out = np.minimum.reduceat(at_top, starts)
    return np.where((q > 0) | (q < 0), out, (sizes - 1) // 2)  # q = 0 (or NaN): the middle


def reversal_window(first: int, last: int, n_samples: int) -> tuple[int, int]:
    """Samples that eqs. (7)–(8) read for the reversing subinterval visit ``[first, last]``.

    rotacal takes the sums of eqs. (7)–(8) with the samples just outside [Sub⁻, Sub⁺] as
    endpoints (both lie in the subinterval the motion came from and returned to), so that the
    sign of q stays right when [Sub⁻, Sub⁺] spans several visits of the extreme subinterval.

    Parameters
    ----------
    first, last : int
        Sub⁻ and Sub⁺, first and last sample index (inclusive) of the visit.
    n_samples : int
        Samples in the capture.

    Returns
    -------
    lo, hi : int
        First and last sample index (inclusive) to read; ``lo == hi == first`` when the visit is
        a single sample (its Chp is that sample, nothing needs reading).

    References
    ----------
    Feng et al. 2023, Sensors 23:4876, §3.2, eqs. (7)–(8).
    """
    if last <= first:
        return first, first
    return max(first - 1, 0), min(last + 1, n_samples - 1)


def reversal_point_in_window(u_window: ArrayLike, v_window: ArrayLike) -> int:
    """Chp of eqs. (7)–(8) within the samples of :func:`reversal_window`, as an offset.

    ``qu = Σ u − n·(u_first + u_last)/2`` and likewise ``qv``; the signal with the larger |q|
    changes most; Chp is its maximum if q > 0, its minimum if q < 0 (the middle sample if q = 0).

    Parameters
    ----------
    u_window, v_window : array_like
        Corrected signals (dimensionless) at samples ``lo .. hi`` of :func:`reversal_window`.

    Returns
    -------
    int
        Chp − lo (samples).

    References
    ----------
    Feng et al. 2023, Sensors 23:4876, §3.2, eqs. (7)–(8).
    """
    us = np.asarray(u_window, dtype=np.float64).reshape(-1)
    vs = np.asarray(v_window, dtype=np.float64).reshape(-1)
    if us.size < 2:
        return 0
    return int(_points_in_windows(us, vs, np.zeros(1, dtype=np.intp))[0])


@dataclasses.dataclass(frozen=True)
class ReversalPlan:
    """Reversing moments found from the subinterval transitions, before their precise point.

    Everything of :func:`find_reversals` except eqs. (7)–(8), which need the signals: a chunked
    caller reads the samples of each window in a later pass over the capture.

    Attributes
    ----------
    windows : ndarray of int, shape (m, 2)
        ``[Sub⁻, Sub⁺]`` (sample indices, inclusive) of each reversing subinterval visit whose
        Chp is needed; see :func:`reversal_window` for the samples to read.
    pairs : ndarray of int, shape (r, 2)
        Rows of ``windows`` for each reversal: its index is ``(chp[p0] + chp[p1]) // 2``
        (``p0 == p1`` for a reversal that is a single candidate).
    kinds : ndarray of int8
        +1 for a maximum of θ, −1 for a minimum.
    candidates, hysteresis_subintervals, transitions, skipped_transitions, max_step_subintervals
        As in :class:`Reversals`.
    """

    windows: np.ndarray
    pairs: np.ndarray
    kinds: np.ndarray
    candidates: int
    hysteresis_subintervals: int
    transitions: int
    skipped_transitions: int
    max_step_subintervals: int

    def indices(self, chp: ArrayLike) -> NDArray[np.intp]:
        """Sample index of each reversal from the Chp (sample index) of every window."""
        c = np.asarray(chp, dtype=np.intp)
        if self.pairs.shape[0] == 0:
            return np.empty(0, dtype=np.intp)
        return (c[self.pairs[:, 0]] + c[self.pairs[:, 1]]) // 2


def plan_reversals(
    transition_indices: ArrayLike,
    k_after: ArrayLike,
    k_start: float,
    *,
    hysteresis_subintervals: int | None = None,
    stacklevel: int = 2,
) -> ReversalPlan:
    """Reversing moments from the list of subinterval transitions (steps 1–3 of find_reversals).

    Parameters
    ----------
    transition_indices : array_like of int
        Sample index of every transition of the capture, increasing.
    k_after : array_like
        Subinterval count k after each transition.
    k_start : float
        k of the capture's first sample.
    hysteresis_subintervals : int, optional
        See :func:`find_reversals`.
    stacklevel : int
        Passed to :func:`warnings.warn` for the :class:`SubdivisionWarning`.

    Returns
    -------
    ReversalPlan
        Windows whose Chp (eqs. (7)–(8)) is still to be found, and how they make reversals.

    References
    ----------
    Feng et al. 2023, Sensors 23:4876, §3.1 eqs. (3)–(6).
    """
    idx = np.asarray(transition_indices, dtype=np.intp)
    ka = np.asarray(k_after, dtype=np.float64)
    k0 = float(k_start)
    n_trans = int(idx.size)
    direction, skipped, max_step, k_range = _steps(ka, k0)
    if n_trans < 2:
        first_change = run_len = np.empty(0, dtype=np.intp)
        kinds = np.empty(0, dtype=np.int8)
        level: FloatArray = np.empty(0)
    else:
        first_change, run_len, kinds, level = _candidates(ka, direction)
    return plan_from_candidates(
        kinds,
        level,
        _windows(idx, ka, first_change, run_len, level),
        transitions=(n_trans, skipped, max_step),
        k_range=k_range,
        hysteresis_subintervals=hysteresis_subintervals,
        stacklevel=stacklevel + 1,
    )


#: Transitions per chunk of :func:`_steps`: a chunk's steps of k stay in the L2 cache while
#: they are counted, compared and signed.
_STEP_CHUNK = 1 << 16


def _steps(ka: FloatArray, k0: float) -> tuple[NDArray[np.int8], int, int, tuple[float, float]]:
    """What the plan needs of the steps ``dk`` of k (``np.diff(ka, prepend=k0)``), chunk by chunk
    without the whole array of them: their signs (:func:`_direction`), how many skipped a
    subinterval (|dk| > 1), the largest |dk| and the lowest and highest k (with ``k0``)."""
    n = ka.size
    direction = np.empty(n, dtype=np.int8)
    if n == 0:
        return direction, 0, 0, (k0, k0)
    skipped = 0
    tops, los, his = [], [], []  # of each chunk; np.max/np.min keep a NaN, as max() of dk did
    buf = np.empty(min(n, _STEP_CHUNK))
    for s in range(0, n, _STEP_CHUNK):
        e = min(n, s + _STEP_CHUNK)
        dk = buf[: e - s]
        if s == 0:
            dk[0] = ka[0] - k0
            np.subtract(ka[1:e], ka[: e - 1], out=dk[1:])
        else:
            np.subtract(ka[s:e], ka[s - 1 : e - 1], out=dk)
        skipped += int(np.count_nonzero(dk > 1.0)) + int(np.count_nonzero(dk < -1.0))
        tops.append(np.maximum(dk.max(), -dk.min()))
        los.append(ka[s:e].min())
        his.append(ka[s:e].max())
        np.subtract((dk > 0).view(np.int8), (dk < 0).view(np.int8), out=direction[s:e])
    top, lo, hi = float(np.max(tops)), float(np.min(los)), float(np.max(his))
    return direction, skipped, int(top), (min(k0, lo), max(k0, hi))


def _windows(
    idx: NDArray[np.intp],
    ka: FloatArray,
    first_change: NDArray[np.intp],
    run_len: NDArray[np.intp],
    level: FloatArray,
) -> NDArray[np.intp]:
    """[Sub⁻, Sub⁺] of each candidate (rows of shape (m, 2)): the candidate whose run of trend
    changes starts at transition j0 spans from the first to the last of its turning visits at
    its level (transitions j0 − 1 .. j0 + L − 2 lead into them), all candidates at once."""
    m = int(first_change.size)
    if m == 0:
        return np.empty((0, 2), dtype=np.intp)
    starts, rows = _window_rows(first_change - 1, run_len)
    per_row = np.repeat(np.arange(m), run_len)
    place = np.arange(rows.size, dtype=np.intp) - starts[per_row]  # turning visit r of its run
    at_level = ka[rows] == level[per_row]  # the run's extreme level is reached in every run
    first_r = np.minimum.reduceat(np.where(at_level, place, rows.size), starts)
    last_r = np.maximum.reduceat(np.where(at_level, place, -1), starts)
    out = np.empty((m, 2), dtype=np.intp)
    out[:, 0] = idx[first_change - 1 + first_r]
    out[:, 1] = idx[first_change + last_r] - 1
    return out


def transition_candidates(
    transition_indices: ArrayLike, k_after: ArrayLike, k_before: float
) -> tuple[NDArray[np.int8], FloatArray, NDArray[np.intp]]:
    """Reversal candidates of eqs. (5)–(6) in a list of transitions: kind, level and window
    ``[Sub⁻, Sub⁺]`` of each, as :func:`plan_reversals` finds them.

    For a part of a capture's list (a chunked caller) the candidates are those of the whole list
    when the part starts at a transition that turns no trend and ends at one, ``k_before`` being
    the count before its first transition (k of sample 0 for the capture's first).

    References
    ----------
    Feng et al. 2023, Sensors 23:4876, §3.1 eqs. (5)–(6).
    """
    idx = np.asarray(transition_indices, dtype=np.intp)
    ka = np.asarray(k_after, dtype=np.float64)
    if idx.size < 2:
        return np.empty(0, dtype=np.int8), np.empty(0), np.empty((0, 2), dtype=np.intp)
    dk = np.diff(ka, prepend=float(k_before))
    first_change, run_len, kinds, level = _candidates(ka, _direction(dk))
    return kinds.astype(np.int8), level, _windows(idx, ka, first_change, run_len, level)


def plan_from_candidates(
    kinds: NDArray[np.int8],
    level: FloatArray,
    windows: NDArray[np.intp],
    *,
    transitions: tuple[int, int, int],
    k_range: tuple[float, float],
    hysteresis_subintervals: int | None = None,
    stacklevel: int = 2,
) -> ReversalPlan:
    """Steps 2–3 of :func:`plan_reversals` from the candidates of eqs. (5)–(6) (kind, level,
    ``windows[c]`` = [Sub⁻, Sub⁺] of candidate c, shape (m, 2)): the checks of the steps between samples, the
    clusters closer than the hysteresis and the windows of each reversal.

    ``transitions`` is ``(transitions, skipped transitions, largest step in subintervals)`` of the
    capture, ``k_range`` its lowest and highest subinterval count (the default hysteresis is 10 %
    of it, at least 2).

    References
    ----------
    Feng et al. 2023, Sensors 23:4876, §3.1 eqs. (5)–(6).
    """
    n_trans, skipped, max_step = transitions
    if hysteresis_subintervals is not None and (
        isinstance(hysteresis_subintervals, bool)
        or int(hysteresis_subintervals) != hysteresis_subintervals
        or hysteresis_subintervals < 1
    ):
        raise ConfigError(
            f"hysteresis_subintervals={hysteresis_subintervals!r} must be a whole number ≥ 1."
        )
    if max_step >= _MAX_SAFE_STEP:
        # A jump of 5 subintervals is 150° of the signal period: one more and the unwrapping
        # cannot tell forward from backward, so the angle would be silently wrong.
        raise CaptureError(
            f"the encoder phase jumps by up to {30 * max_step}° of a signal period between two "
            "samples: the capture is sampled too slowly for the motion (or too noisy) to be "
            "demodulated — sample faster (at least 12 samples per signal period at the highest "
            "rate)."
        )
    if skipped:
        warnings.warn(
            f"{skipped} of {n_trans} subinterval transitions skipped subintervals (largest jump "
            f"{max_step} of 12 per signal period): the sampling is too slow for the subdivision"
            + ("; above 5 the phase unwrapping itself is ambiguous." if max_step > 5 else "."),
            SubdivisionWarning,
            stacklevel=stacklevel,
        )
    k_lo, k_hi = k_range
    if hysteresis_subintervals is None:
        hyst = max(2, round(0.1 * (k_hi - k_lo)))
    else:
        hyst = int(hysteresis_subintervals)
    n_cand = int(np.asarray(kinds).size)
    if n_trans < 2 or n_cand == 0:
        return _no_reversals(hyst, n_trans, skipped, max_step)

    # rotacal's extension: clusters of candidates closer than the hysteresis.
    linked = np.abs(np.diff(level)) < hyst
    cluster_start = np.flatnonzero(np.concatenate(([True], ~linked)))
    cluster_size = np.diff(np.append(cluster_start, n_cand))
    keep = cluster_size % 2 == 1
    rev_kinds = np.asarray(kinds)[cluster_start[keep]].astype(np.int8)

    # Each kept cluster gives the window of its first candidate and, when it has more than one
    # candidate, that of its last (a cluster straddles the reversal symmetrically: the reversal
    # lies midway between the Chp of its outermost extremes, both of the cluster's kind).
    first = cluster_start[keep]
    two = cluster_size[keep] > 1
    place = np.cumsum(1 + two) - (1 + two)  # row of each cluster's first window
    rows = np.empty(int(first.size + np.count_nonzero(two)), dtype=np.intp)
    rows[place] = first
    rows[place[two] + 1] = first[two] + cluster_size[keep][two] - 1
    pairs = np.column_stack((place, place + two)).astype(np.intp)
    return ReversalPlan(
        windows=np.asarray(windows, dtype=np.intp).reshape(-1, 2)[rows],
        pairs=pairs,
        kinds=rev_kinds,
        candidates=n_cand,
        hysteresis_subintervals=hyst,
        transitions=n_trans,
        skipped_transitions=skipped,
        max_step_subintervals=max_step,
    )


def find_reversals(
    t: ArrayLike,
    u: ArrayLike,
    v: ArrayLike,
    phase_rad: ArrayLike,
    *,
    hysteresis_subintervals: int | None = None,
) -> Reversals:
    """Reversing moments of the motion, each pinned to one sample.

    1. Subinterval count ``k = ⌊φ/(π/6)⌋``; a transition is a sample where k changes, its
       direction the sign of the change (eqs. (3)–(4)).
    2. A trend change is a transition whose direction differs from the previous one. A run of an
       even number of consecutive trend changes holds no reversal (eq. (5)); an odd run holds one
       (eq. (6)): a *candidate*, a maximum of θ if the direction before the run was increasing,
       else a minimum. Its *level* is the extreme k of the run's turning visits (the highest for
       a maximum, the lowest for a minimum).
    3. *rotacal's extension* (not in the paper): a vibration superposed on the motion near a
       reversal moves it back and forth by more than one subinterval, so the candidates of step 2
       come in extra max/min pairs. Neighbouring candidates (which alternate max/min) whose levels
       differ by less than ``hysteresis_subintervals`` are linked into a cluster; a cluster of an
       odd number of candidates is one reversal, of the kind of its first candidate, an even
       number none.
    4. Where the reversal lies: for a single candidate, the window ``[Sub⁻, Sub⁺]`` runs from the
       first to the last of its turning visits that sit at its level (in eq. (6)'s
       {4,5,6,7,8,7,8,7,6,5} that is 8-7-8, the two visits of 8 and the 7 between them); for a
       cluster, the windows of its first and last candidate (both of the cluster's kind).
    5. In each window the sums ``qu``, ``qv`` of eqs. (7)–(8), with the samples just outside
       ``[Sub⁻, Sub⁺]`` as endpoints (:func:`reversal_window`), pick the signal that changes
       most; Chp is its minimum if q < 0 and its maximum if q > 0. Within a run of trend changes
       k alternates between two neighbouring levels, so a window spans at most 60° of φ, over
       which at least one signal is monotonic in φ (the one that changes most, unless the other
       is near its own extreme), and then its extreme is that of φ. The
       sign of q is set against the endpoints, which lie in the neighbouring level: when most of
       a long window sits in that level too, q can point to the dip instead (2 of 977 reversals
       of a noisy synthetic capture with a vibration faster than the motion). A single
       candidate's reversing moment is its Chp; a cluster's is the sample midway between the
       Chp of its first and last candidate (the cluster straddles the reversal symmetrically).

    How this differs from the paper's literal rule, also with the pruning off: the paper takes
    the *middle* turning visit of an odd run as the reversing subinterval (eq. (6): the second
    7) and searches eqs. (7)–(8) between that visit's own endpoints; rotacal searches the visits
    at the run's extreme level, where θ is extreme (in the example the paper's 7 lies in the dip
    between the two visits of 8), with one sample more on each side (:func:`reversal_window`).
    :func:`reversing_subintervals` gives the paper's middle visits exactly.

    The hysteresis. Neighbouring candidates always differ by at least 2 subintervals (between a
    maximum and the next minimum the motion goes down twice in a row), so a hysteresis of 1 or 2
    links none: every candidate of step 2 is a reversal, which is the paper's odd/even rule of
    eqs. (5)–(6) — with the reversing point of steps 4–5, not the paper's. The default is not
    that rule: it is 10 % of the span of k over the capture (at least 2), which prunes vibration
    pairs up to a tenth of the stroke. A table that drifts spans more than it swings, so the
    sinusoidal-motion calibration with ``drift=True`` passes 10 % of the span without the drift
    (:func:`demodulate`'s ``hysteresis_from``).

    Parameters
    ----------
    t : array_like
        Time of each sample (s).
    u, v : array_like
        Corrected signals ≈ (cos φ, sin φ) (dimensionless).
    phase_rad : array_like
        Unwrapped phase φ (rad) from :func:`unwrapped_phase`.
    hysteresis_subintervals : int, optional
        Smallest difference in level (30° subintervals of the signal period) between a maximum
        and a neighbouring minimum that keeps them apart (step 3); 1 or 2 turns the pruning off.
        Default: 10 % of the peak-to-peak of k, at least 2.

    Returns
    -------
    Reversals
        Sample indices, times (s) and kinds (+1 maximum of θ, −1 minimum).

    Warns
    -----
    SubdivisionWarning
        When k jumps by more than one subinterval between samples (sampling too slow for the
        subdivision); directions stay valid while jumps are below 6 subintervals (π).

    References
    ----------
    Feng et al. 2023, Sensors 23:4876, §3.1 eqs. (3)–(6) and §3.2 eqs. (7)–(8).
    """
    tt = np.asarray(t, dtype=np.float64)
    uu = np.asarray(u, dtype=np.float64)
    vv = np.asarray(v, dtype=np.float64)
    phase = np.asarray(phase_rad, dtype=np.float64)
    if not (tt.shape == uu.shape == vv.shape == phase.shape) or phase.ndim != 1:
        raise CaptureError(
            "t, u, v and phase_rad must be one-dimensional and of equal length, got "
            f"{tt.shape}, {uu.shape}, {vv.shape} and {phase.shape}."
        )
    idx, k_after, _, k0 = _transitions(phase)
    plan = plan_reversals(
        idx, k_after, k0, hysteresis_subintervals=hysteresis_subintervals, stacklevel=3
    )
    return _pinned(plan, tt, lambda rows: (uu[rows], vv[rows]))


def intercept_periods(reversals: Reversals, n_periods: int | None = None) -> tuple[int, int, int]:
    """Sample range of n whole motion periods, bounded by 2n+1 reversing moments.

    The first ``2n+1`` reversals are used; the range runs from the first of them to the last,
    inclusive.

    Parameters
    ----------
    reversals : Reversals
        From :func:`find_reversals`.
    n_periods : int, optional
        Number of motion periods wanted; None takes as many as the capture holds.

    Returns
    -------
    first, last, n : int
        First and last (inclusive) sample index, and the number of periods n.

    Raises
    ------
    CaptureError
        Fewer than 2n+1 reversals (fewer than 3 when ``n_periods`` is None).
    ConfigError
        ``n_periods`` below 1.

    References
    ----------
    Feng et al. 2023, Sensors 23:4876, §3.3.
    """
    count = len(reversals.indices)
    available = (count - 1) // 2 if count else 0
    if n_periods is not None:
        if isinstance(n_periods, bool) or int(n_periods) != n_periods or n_periods < 1:
            raise ConfigError(f"n_periods={n_periods!r} must be a whole number ≥ 1.")
        n = int(n_periods)
    else:
        n = max(available, 1)
    if n > available:
        raise CaptureError(
            f"the capture holds {count} reversing moments, enough for {available} whole motion "
            f"periods, but {n} were asked for ({2 * n + 1} reversals needed); record a longer "
            "capture or ask for fewer periods."
        )
    return int(reversals.indices[0]), int(reversals.indices[2 * n]), n
