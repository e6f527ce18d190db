"""The encoder's passes of the chunked OSE calibration (Feng et al. 2023, eqs. (3)-(8)) (private).

2. the Heydemann fit on the same even stride as in memory (at most 2·10⁵ points);
3. signal phase with the cycle count carried from chunk to chunk (:class:`PhaseState`; a
   per-chunk ``np.unwrap`` would lose whole cycles at the boundaries), the subinterval
   transitions (global index and count k), the phase state at each chunk's start, and a
   decimated copy for the figures; then the reversals from the transition list (the same code
   as in memory, :func:`~rotacal.encoder.plan_reversals`);
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
from collections.abc import Iterator
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
    plan_reversals,
    reversal_point_in_window,
    reversal_window,
)
from rotacal.encoder._kernel import phase_pass
from rotacal.table._stream_fit import Segment
from rotacal.table._stream_source import Passes
from rotacal.table.motion import _ELLIPSE_POINTS, _plot_stride

MIN_SAMPLES = 16


def correction_pass(passes: Passes, n: int) -> QuadratureCorrection:
    """Pass 2: Heydemann fit on the in-memory stride ⌈N/2·10⁵⌉ (same points, same result)."""
    stride = max(1, -(-n // _ELLIPSE_POINTS))
    parts_a: list[np.ndarray] = []
    parts_b: list[np.ndarray] = []
    for _, off, cols in passes.run():
        s0 = (-off) % stride
        parts_a.append(np.array(cols["a"][s0::stride]))
        parts_b.append(np.array(cols["b"][s0::stride]))
    a_s = np.concatenate(parts_a)
    b_s = np.concatenate(parts_b)
    # clipping was judged on every sample in pass 1
    return fit_quadrature_correction(
        a_s, b_s, max_points=max(a_s.size, MIN_SAMPLES), allow_clipped=True
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
    step = _plot_stride(n)
    jit = use_numba(n)  # by the capture's size, not the chunk's
    state: PhaseState | None = None
    k_prev: float | None = None
    k_start = math.nan
    trans_idx: list[np.ndarray] = []
    trans_k: list[np.ndarray] = []
    states: list[PhaseState | None] = []
    dec: dict[str, list[np.ndarray]] = {"t": [], "angle": [], "a": [], "b": []}
    rule_step = hysteresis_stride(n)
    rule_t: list[np.ndarray] = []
    rule_phase: list[np.ndarray] = []
    lo, hi = math.inf, -math.inf
    ends: list[float] = []
    for _, off, cols in passes.run():
        states.append(state)
        run = phase_pass(
            cols["a"], cols["b"], corr, state=state, previous_k=k_prev, offset=off, jit=jit
        )
        phase, state = run.phase_rad, run.state
        if k_prev is None:
            k_start = run.k_first
        k_prev = run.k_last
        trans_idx.append(run.indices)
        trans_k.append(run.k_after)
        s0 = (-off) % step
        dec["t"].append(np.array(cols["time_s"][s0::step]))
        dec["angle"].append(phase[s0::step] * scale)
        dec["a"].append(np.array(cols["a"][s0::step]))
        dec["b"].append(np.array(cols["b"][s0::step]))
        if hysteresis_from is not None:
            r0 = (-off) % rule_step
            rule_t.append(np.array(cols["time_s"][r0::rule_step]))
            rule_phase.append(phase[r0::rule_step])
        lo, hi = min(lo, run.phase_min_rad), max(hi, run.phase_max_rad)
        ends[:] = [ends[0] if ends else float(phase[0]), float(phase[-1])]
        del phase
    all_idx = np.concatenate(trans_idx)
    del trans_idx
    all_k = np.concatenate(trans_k)
    del trans_k
    if hysteresis_subintervals is None and hysteresis_from is not None:
        hysteresis_subintervals = hysteresis_from(
            np.concatenate(rule_t), np.concatenate(rule_phase)
        )
    plan = plan_reversals(
        all_idx, all_k, k_start, hysteresis_subintervals=hysteresis_subintervals, stacklevel=4
    )
    return Demod(
        plan=plan,
        states=states,
        plot_t=np.concatenate(dec["t"]),
        plot_angle=np.concatenate(dec["angle"]),
        plot_a=np.concatenate(dec["a"]),
        plot_b=np.concatenate(dec["b"]),
        span_deg=(hi - lo) * scale,
        net_deg=(ends[-1] - ends[0]) * scale,
    )


def reversals_pass(
    passes: Passes, n: int, corr: QuadratureCorrection, plan: ReversalPlan
) -> tuple[np.ndarray, np.ndarray]:
    """Pass 4: Chp of eqs. (7)–(8) in each window, and the index and time of each reversal.

    Each window's samples are gathered only while the pass is inside it and are dropped as soon
    as its Chp is known, so only the windows open in the current chunk are held.
    """
    windows = plan.windows
    m = windows.shape[0]
    n_rev = plan.pairs.shape[0]
    chp = np.empty(m, dtype=np.intp)
    lo = np.empty(m, dtype=np.int64)
    hi = np.empty(m, dtype=np.int64)
    for w, (first, last) in enumerate(windows.tolist()):
        lo[w], hi[w] = reversal_window(first, last, n)
        chp[w] = first  # final for a one-sample visit, overwritten otherwise
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
                w0, w1 = (int(x) for x in plan.pairs[key])
                index = (int(chp[w0]) + int(chp[w1])) // 2
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
            phase = phase_pass(
                cols["a"], cols["b"], corr, state=states[number], jit=use_numba(last + 1 - first)
            ).phase_rad
            s = max(first - off, 0)
            e = min(last + 1 - off, phase.size)
            yield off + s, cols["time_s"][s:e], phase[s:e] * scale

    return pieces
