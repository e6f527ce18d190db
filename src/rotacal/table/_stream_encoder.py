"""The encoder's passes of the chunked OSE calibration (Feng et al. 2023, eqs. (3)-(8)) (private).

2. the Heydemann fit on the same even stride as in memory (at most 2·10⁵ points);
3. signal phase with the cycle count carried from chunk to chunk (:class:`PhaseState`; a
   per-chunk ``np.unwrap`` would lose whole cycles at the boundaries), the reversal candidates
   of the subinterval transitions found chunk by chunk (:class:`CandidateState`: only the open
   run of trend changes is carried, so what is kept grows with the reversals, not the samples),
   the phase state at each chunk's start, and a decimated copy for the figures; then the
   reversals from the candidates (the same code as in memory,
   :func:`~rotacal.encoder.reversals.plan_from_candidates`);
4. the signals in each reversing subinterval (eqs. (7)–(8)) and the time of each reversal;
5. θ of the analysed samples recomputed chunk by chunk from the saved phase state
   (:func:`segment`), for the fit and the position error (:mod:`rotacal.table._stream_fit`).

References
----------
Feng R., Yan J., Wu Y., Yu N., Yin X. (2023). Sensors 23, 4876, §3, eqs. (3)–(8).
Heydemann P. L. M. (1981). Appl. Opt. 20, 3382 (signal correction).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Iterator, Mapping
from typing import Any

import numpy as np

from rotacal._jit import use_numba
from rotacal.encoder import (
    HysteresisRule,
    PhaseState,
    QuadratureCorrection,
    ReversalPlan,
    correct_quadrature,
    fit_quadrature_correction,
    hysteresis_stride,
    reversal_point_in_window,
    reversal_window,
)
from rotacal.encoder._kernel import phase_pass
from rotacal.encoder.reversals import plan_from_candidates, transition_candidates
from rotacal.table._stream_fit import Segment
from rotacal.table._stream_source import Passes
from rotacal.table.motion import _ELLIPSE_POINTS, _plot_stride

MIN_SAMPLES = 16


def correction_pass(passes: Passes, n: int) -> QuadratureCorrection:
    """Pass 2: Heydemann fit on the in-memory stride ⌈N/2·10⁵⌉ (same points, same result)."""
    stride = correction_stride(n)
    parts = [strided_points(off, cols["a"], cols["b"], stride) for _, off, cols in passes.run()]
    return correction_of_points(parts)


def correction_stride(n: int) -> int:
    """The in-memory stride of the Heydemann fit's points for ``n`` samples."""
    return max(1, -(-n // _ELLIPSE_POINTS))


def strided_points(
    off: int, a: np.ndarray, b: np.ndarray, stride: int
) -> tuple[np.ndarray, np.ndarray]:
    """The samples of a chunk (first global index ``off``) whose index is a multiple of stride."""
    s0 = (-off) % stride
    return np.array(a[s0::stride]), np.array(b[s0::stride])


def correction_of_points(parts: list[tuple[np.ndarray, np.ndarray]]) -> QuadratureCorrection:
    """The Heydemann fit of the chunks' strided points, in capture order."""
    a_s = np.concatenate([p[0] for p in parts])
    b_s = np.concatenate([p[1] for p in parts])
    # clipping was judged on every sample in pass 1
    return fit_quadrature_correction(
        a_s, b_s, max_points=max(a_s.size, MIN_SAMPLES), allow_clipped=True
    )


class CandidateState:
    """Reversal candidates of a capture's subinterval transitions, found chunk by chunk.

    :func:`~rotacal.encoder.reversals.transition_candidates` gives the candidates of the whole
    list when it is given a part that starts at a transition turning no trend and ends at one
    (a run of trend changes is never cut). Each chunk's transitions are appended to the carried
    tail; the part up to the last transition before the open run of changes (or up to the last
    transition) is searched, and the tail from there on is carried. The counts, skipped
    transitions, largest step and the range of k are carried as numbers (Feng et al. 2023,
    Sensors 23:4876, §3.1 eqs. (5)–(6)).
    """

    def __init__(self, k_start: float) -> None:
        self.k_range = (k_start, k_start)
        self.n = 0
        self.skipped = 0
        self.max_step = 0
        self._k_before = k_start  # count before the tail's first transition
        self._k_last = k_start  # count after the last transition seen
        self._tail = (np.empty(0, dtype=np.intp), np.empty(0))
        self._found: list[tuple[np.ndarray, np.ndarray, np.ndarray]] = []

    def add(self, indices: np.ndarray, k_after: np.ndarray) -> None:
        """The transitions of the next chunk: sample index and count k after each."""
        if indices.size == 0:
            return
        ka = np.asarray(k_after, dtype=np.float64)
        step = np.abs(np.diff(ka, prepend=self._k_last))
        self.n += int(ka.size)
        self.skipped += int(np.count_nonzero(step > 1.0))
        self.max_step = max(self.max_step, int(step.max()))
        lo, hi = self.k_range
        self.k_range = (min(lo, float(ka.min())), max(hi, float(ka.max())))
        self._k_last = float(ka[-1])
        idx = np.concatenate((self._tail[0], np.asarray(indices, dtype=np.intp)))
        kk = np.concatenate((self._tail[1], ka))
        direction = np.sign(np.diff(kk, prepend=self._k_before))
        turns = direction[1:] != direction[:-1]  # turns[j - 1]: transition j changes the trend
        # the open run of changes at the end starts after the last transition that turns nothing
        calm = np.flatnonzero(~turns)
        cut = int(calm[-1]) + 1 if calm.size else 0  # that transition's place
        if cut > 0:
            self._found.append(transition_candidates(idx[: cut + 1], kk[: cut + 1], self._k_before))
            self._k_before = float(kk[cut - 1])
        self._tail = (idx[cut:], kk[cut:])

    def plan(self, hysteresis_subintervals: int | None, stacklevel: int) -> ReversalPlan:
        """:func:`~rotacal.encoder.plan_reversals` of every transition added."""
        tail_idx, tail_k = self._tail
        parts = [*self._found, transition_candidates(tail_idx, tail_k, self._k_before)]
        kinds = np.concatenate([p[0] for p in parts])
        level = np.concatenate([p[1] for p in parts])
        windows = np.concatenate([p[2] for p in parts])
        return plan_from_candidates(
            kinds,
            level,
            windows,
            transitions=(self.n, self.skipped, self.max_step),
            k_range=self.k_range,
            hysteresis_subintervals=hysteresis_subintervals,
            stacklevel=stacklevel + 1,
        )


@dataclasses.dataclass
class Demod:
    plan: ReversalPlan
    states: list[PhaseState | None]
    plot_t: np.ndarray
    plot_angle: np.ndarray
    plot_a: np.ndarray
    plot_b: np.ndarray
    span_deg: float  # max θ − min θ over the capture
    net_deg: float  # last θ − first θ


@dataclasses.dataclass
class PhaseBlock:
    """What the phase pass keeps of one chunk (:func:`phase_block`): its transitions, the
    state after it, its extremes and end phases (rad) and its decimated copies."""

    indices: np.ndarray
    k_after: np.ndarray
    k_first: float
    k_last: float
    state: PhaseState
    lo: float
    hi: float
    first_phase: float
    last_phase: float
    dec: dict[str, np.ndarray]  # every plot-stride-th t, θ (deg), a, b
    rule: tuple[np.ndarray, np.ndarray] | None  # t and φ a hysteresis rule sees


def phase_block(
    cols: Mapping[str, np.ndarray],
    off: int,
    corr: QuadratureCorrection,
    scale: float,
    state: PhaseState | None,
    k_prev: float | None,
    jit: bool,
    n: int,
    with_rule: bool,
) -> PhaseBlock:
    """The phase pass over one chunk (first global index ``off``) of a capture of ``n``
    samples, entering with the phase ``state`` and the k of the sample before it."""
    run = phase_pass(
        cols["a"], cols["b"], corr, state=state, previous_k=k_prev, offset=off, jit=jit
    )
    phase = run.phase_rad
    s0 = (-off) % _plot_stride(n)
    step = _plot_stride(n)
    dec = {
        "t": np.array(cols["time_s"][s0::step]),
        "angle": phase[s0::step] * scale,
        "a": np.array(cols["a"][s0::step]),
        "b": np.array(cols["b"][s0::step]),
    }
    rule = None
    if with_rule:
        rule_step = hysteresis_stride(n)
        r0 = (-off) % rule_step
        rule = (np.array(cols["time_s"][r0::rule_step]), phase[r0::rule_step])
    return PhaseBlock(
        run.indices,
        run.k_after,
        run.k_first,
        run.k_last,
        run.state,
        run.phase_min_rad,
        run.phase_max_rad,
        float(phase[0]),
        float(phase[-1]),
        dec,
        rule,
    )


class PhaseFold:
    """The phase pass's chunks (:class:`PhaseBlock`) gathered in capture order into the
    reversal plan and the figures' copies (:meth:`finish`); only the reversal candidates' open
    run is carried (:class:`CandidateState`)."""

    def __init__(self) -> None:
        self._found: CandidateState | None = None
        self._dec: dict[str, list[np.ndarray]] = {"t": [], "angle": [], "a": [], "b": []}
        self._rule: list[tuple[np.ndarray, np.ndarray]] = []
        self._lo, self._hi = math.inf, -math.inf
        self._ends: list[float] = []

    def add(self, block: PhaseBlock) -> None:
        if self._found is None:
            self._found = CandidateState(block.k_first)
        self._found.add(block.indices, block.k_after)
        for key, part in block.dec.items():
            self._dec[key].append(part)
        if block.rule is not None:
            self._rule.append(block.rule)
        self._lo, self._hi = min(self._lo, block.lo), max(self._hi, block.hi)
        self._ends[:] = [self._ends[0] if self._ends else block.first_phase, block.last_phase]

    def finish(
        self,
        states: list[PhaseState | None],
        scale: float,
        hysteresis_subintervals: int | None,
        hysteresis_from: HysteresisRule | None,
        stacklevel: int,
    ) -> Demod:
        """The reversal plan and copies of every chunk added; ``states``: the phase state at
        each chunk's start."""
        if hysteresis_subintervals is None and hysteresis_from is not None:
            hysteresis_subintervals = hysteresis_from(
                np.concatenate([r[0] for r in self._rule]),
                np.concatenate([r[1] for r in self._rule]),
            )
        found = self._found
        if found is None:  # no chunk: plan_reversals' answer for no transitions
            found = CandidateState(math.nan)
        plan = found.plan(hysteresis_subintervals, stacklevel=stacklevel + 1)
        return Demod(
            plan=plan,
            states=states,
            plot_t=np.concatenate(self._dec["t"]),
            plot_angle=np.concatenate(self._dec["angle"]),
            plot_a=np.concatenate(self._dec["a"]),
            plot_b=np.concatenate(self._dec["b"]),
            span_deg=(self._hi - self._lo) * scale,
            net_deg=(self._ends[-1] - self._ends[0]) * scale,
        )


def phase_pass_chunked(
    passes: Passes,
    n: int,
    corr: QuadratureCorrection,
    scale: float,
    hysteresis_subintervals: int | None = None,
    hysteresis_from: HysteresisRule | None = None,
) -> Demod:
    """Pass 3: phase with the cycle count carried, transitions, chunk-start states, plot copy
    (and the samples a hysteresis rule sees, as in memory)."""
    jit = use_numba(n)  # by the capture's size, not the chunk's
    state: PhaseState | None = None
    k_prev: float | None = None
    states: list[PhaseState | None] = []
    fold = PhaseFold()
    for _, off, cols in passes.run():
        states.append(state)
        block = phase_block(
            cols, off, corr, scale, state, k_prev, jit, n, hysteresis_from is not None
        )
        state, k_prev = block.state, block.k_last
        fold.add(block)
    return fold.finish(states, scale, hysteresis_subintervals, hysteresis_from, stacklevel=4)


def window_bounds(plan: ReversalPlan, n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """First and last sample (inclusive) that eqs. (7)–(8) read for each reversing window of
    the plan, and each window's Chp where it is already known (a one-sample visit: its sample;
    the others are overwritten once their samples are read)."""
    m = plan.windows.shape[0]
    chp = np.empty(m, dtype=np.intp)
    lo = np.empty(m, dtype=np.int64)
    hi = np.empty(m, dtype=np.int64)
    for w, (first, last) in enumerate(plan.windows.tolist()):
        lo[w], hi[w] = reversal_window(first, last, n)
        chp[w] = first
    return lo, hi, chp


def reversal_index(plan: ReversalPlan, chp: np.ndarray, r: int) -> int:
    """The sample of reversal ``r``: midway between the Chp of its two windows (eq. (8))."""
    w0, w1 = (int(x) for x in plan.pairs[r])
    return (int(chp[w0]) + int(chp[w1])) // 2


def reversals_pass(
    passes: Passes, n: int, corr: QuadratureCorrection, plan: ReversalPlan
) -> tuple[np.ndarray, np.ndarray]:
    """Pass 4: Chp of eqs. (7)–(8) in each window, and the index and time of each reversal.

    Each window's samples are gathered only while the pass is inside it and are dropped as soon
    as its Chp is known, so only the windows open in the current chunk are held.
    """
    lo, hi, chp = window_bounds(plan, n)
    m = lo.size
    n_rev = plan.pairs.shape[0]
    # Ranges to read: the signals of every window wider than one sample ("uv"), the time stamps
    # of the span from a reversal's first window to its last ("t"): its index lies in there.
    ranges: list[tuple[int, int, str, int]] = [
        (int(lo[w]), int(hi[w]), "uv", w) for w in range(m) if hi[w] > lo[w]
    ]
    for r in range(n_rev):
        w0, w1 = (int(x) for x in plan.pairs[r])
        ranges.append((int(min(lo[w0], lo[w1])), int(max(hi[w0], hi[w1])), "t", r))
    indices = np.empty(n_rev, dtype=np.intp)
    times = np.empty(n_rev, dtype=np.float64)
    if not ranges:
        return indices, times
    ranges.sort(key=lambda x: (x[0], x[2] == "t"))
    start = ranges[0][0]
    stop = max(x[1] for x in ranges) + 1
    nxt = 0
    active: dict[int, list[Any]] = {}
    for _, off, cols in passes.run(start, stop):
        end = off + cols["a"].size
        while nxt < len(ranges) and ranges[nxt][0] < end:
            active[nxt] = []
            nxt += 1
        done: list[int] = []
        for i, pieces in active.items():
            r_lo, r_hi, kind, _ = ranges[i]
            s = max(r_lo, off) - off
            e = min(r_hi + 1, end) - off
            if kind == "uv":
                pieces.append(correct_quadrature(cols["a"][s:e], cols["b"][s:e], corr))
            else:
                pieces.append(np.array(cols["time_s"][s:e]))
            if r_hi < end:
                done.append(i)
        # windows before spans: a span's index needs the Chp of its windows, which end in it
        for i in sorted(done, key=lambda j: ranges[j][2] == "t"):
            r_lo, _, kind, key = ranges[i]
            pieces = active.pop(i)
            if kind == "uv":
                us = np.concatenate([p[0] for p in pieces])
                vs = np.concatenate([p[1] for p in pieces])
                chp[key] = r_lo + reversal_point_in_window(us, vs)
            else:
                index = reversal_index(plan, chp, key)
                indices[key] = index
                times[key] = np.concatenate(pieces)[index - r_lo]
    return indices, times


def segment(
    passes: Passes,
    states: list[PhaseState | None],
    corr: QuadratureCorrection,
    scale: float,
    first: int,
    last: int,
) -> Segment:
    """θ (deg) of samples ``first..last``, recomputed chunk by chunk from the saved phase state,
    each call a fresh pass: ``(global index of the piece's first sample, t, θ)``."""

    def pieces() -> Iterator[tuple[int, np.ndarray, np.ndarray]]:
        for number, off, cols in passes.run(first, last + 1):
            theta = chunk_theta(cols, corr, states[number], scale, use_numba(last + 1 - first))
            s = max(first - off, 0)
            e = min(last + 1 - off, theta.size)
            yield off + s, cols["time_s"][s:e], theta[s:e]

    return pieces


def chunk_theta(
    cols: Mapping[str, np.ndarray],
    corr: QuadratureCorrection,
    state: PhaseState | None,
    scale: float,
    jit: bool,
) -> np.ndarray:
    """θ (deg) of every sample of a chunk, entering with the phase ``state``."""
    return phase_pass(
        cols["a"],
        cols["b"],
        corr,
        state=state,
        jit=jit,
        scale=scale,  # θ (deg) block by block in the pass: no temporary of its own
    ).phase_rad
