"""Out-of-core sinusoidal-motion calibration from an optical shaft encoder (Feng et al. 2023, OSE scheme).

:func:`calibrate_encoder_motion_chunked` gives the same :class:`~rotacal.table.MotionResult` as
:func:`~rotacal.table.calibrate_encoder_motion` while reading the capture chunk by chunk, so
memory is set by the chunk size, not by the capture's length. The capture is read in passes, each
a fresh call of ``chunks()``:

1. checks (lengths, NaN/inf, time order across chunks, samples at the rails) and the sample
   count N;
2. the Heydemann fit on the same even stride as in memory (at most 2·10⁵ points);
3. signal phase with the cycle count carried from chunk to chunk (:class:`PhaseState`; a
   per-chunk ``np.unwrap`` would lose whole cycles at the boundaries), the subinterval
   transitions (global index and count k), the phase state at each chunk's start, and a
   decimated copy for the figures; then the reversals from the transition list (the same code
   as in memory, :func:`~rotacal.encoder.plan_reversals`);
4. the signals in each reversing subinterval (eqs. (7)–(8)) and the time of each reversal;
5. the n whole periods between 2n+1 reversals fed to :class:`HarmonicFitAccumulator` (normal
   equations accumulated over chunks; θ recomputed from the saved phase state; a drift term,
   when asked for, comes from the same block moments), with the three-parameter fit at the set
   frequency accumulated beside it — with a drift term, on θ less the fitted drift in a pass of
   its own after the fit;
6. with set values, the angular position error (eq. (2)), its maximum and rms.

Passes 4–6 stop reading after the last sample they need. What grows with the capture is only
per-event: the transition list (16 bytes per transition), the reversal windows, the block
moments of the fit (~1 % of the analysed samples) and the decimated copies (≈ 20 000 points).

References
----------
Feng R., Yan J., Wu Y., Yu N., Yin X. (2023). Methods for Comprehensive Calibration of a
Low-Frequency Angular Acceleration Rotary Table. Sensors 23, 4876, §3, eqs. (1)–(8).
IEEE Std 1057-2017, §4.1.3 (sine fitting).
"""

from __future__ import annotations

import dataclasses
import functools
import math
import mmap
import os
from collections.abc import Callable, Iterator, Mapping
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
from rotacal.errors import CaptureError, ConfigError
from rotacal.io import iter_capture_chunks
from rotacal.results import with_warnings
from rotacal.signal import HarmonicFitAccumulator, SineFit
from rotacal.signal._checks import MAX_GAP, TYPICAL_STEPS, gap_error
from rotacal.signal._values import (
    LARGEST,
    SMALLEST,
    check_magnitudes,
    check_time_span,
    in_working_range,
)
from rotacal.signal.clipping import RailDetector, check_clipping
from rotacal.table.motion import (
    _ELLIPSE_POINTS,
    MotionResult,
    _check_set_values,
    _check_settings,
    _cut,
    _finish,
    _plot_stride,
)
from rotacal.table.motion_drift import (
    detrended_angle,
    drift_free_hysteresis,
    explained_fit,
    fit_motion,
)
from rotacal.table.motion_uncertainty import ReversalDetection
from rotacal.uncertainty import InstrumentSpecs

__all__ = ["ChunkSource", "calibrate_encoder_motion_chunked", "encoder_chunks_from_file"]

#: A callable that starts a fresh pass over the capture each time it is called.
ChunkSource = Callable[[], Iterator[Mapping[str, np.ndarray]]]

_COLUMNS = ("time_s", "a", "b")
_MIN_SAMPLES = 16
#: Analysed spans up to this many samples are gathered and fitted exactly as in memory (16 MB).
_GATHER_MAX_SAMPLES = 1_000_000
#: Samples held back before the first ``HarmonicFitAccumulator.add`` (the in-memory fit takes its
#: working offset from the first 2¹⁶ samples; the same samples give the same offset here).
_FIRST_ADD_SAMPLES = 1 << 16
_SUB_RAD = 2.0 * math.pi / 12.0
_TWO_PI = 2.0 * math.pi


# --------------------------------------------------------------------------------------------
# passes over the chunks
# --------------------------------------------------------------------------------------------


class _Passes:
    """Fresh passes over a chunk source; checks the chunks and that every pass sees the same."""

    def __init__(self, chunks: ChunkSource, progress: Callable[[int], None] | None) -> None:
        if not callable(chunks):
            raise ConfigError(
                "chunks must be a callable that starts a fresh pass over the capture each time it "
                f"is called (e.g. encoder_chunks_from_file(path)), not a {type(chunks).__name__}"
            )
        self._chunks = chunks
        self._progress = progress
        self._done = 0
        self.lengths: list[int] | None = None

    def run(
        self, start: int = 0, stop: int | None = None
    ) -> Iterator[tuple[int, int, dict[str, np.ndarray]]]:
        """``(chunk number, global index of its first sample, columns)`` of the chunks that
        overlap samples ``[start, stop)``; empty chunks are skipped."""
        it = iter(self._chunks())
        offset = 0
        number = 0
        try:
            for raw in it:
                cols = _columns(raw, offset)
                n = cols["a"].size
                if n == 0:
                    continue
                if self.lengths is not None and (
                    number >= len(self.lengths) or self.lengths[number] != n
                ):
                    raise CaptureError(_INCONSISTENT)
                if stop is not None and offset >= stop:
                    break
                if offset + n > start:
                    yield number, offset, cols
                    self._done += n
                    if self._progress is not None:
                        self._progress(self._done)
                offset += n
                number += 1
            else:
                if self.lengths is not None and number != len(self.lengths):
                    raise CaptureError(_INCONSISTENT)
        finally:
            close = getattr(it, "close", None)
            if close is not None:
                close()


_INCONSISTENT = (
    "the chunk source gave different chunks on a later pass; chunks() must yield the same "
    "capture, in the same chunks, every time it is called"
)


def _columns(raw: Any, offset: int) -> dict[str, np.ndarray]:
    where = f"the chunk starting at sample {offset}"
    if not isinstance(raw, Mapping):
        raise CaptureError(
            f"{where} is a {type(raw).__name__}, not a mapping of column name to array; "
            "yield dicts holding time_s, a and b"
        )
    out: dict[str, np.ndarray] = {}
    for name in _COLUMNS:
        if name not in raw:
            have = ", ".join(repr(k) for k in raw) or "none"
            raise CaptureError(
                f"{where} has no column {name!r} (it has: {have}); each chunk must hold "
                "time_s, a and b (map file columns with --column OLD=NEW)"
            )
        arr = np.asarray(raw[name], dtype=np.float64)
        if arr.ndim != 1:
            raise CaptureError(
                f"column {name!r} in {where} has shape {arr.shape}; chunks must be 1-D"
            )
        out[name] = arr
    na, nb, nt = out["a"].size, out["b"].size, out["time_s"].size
    if na != nb:
        raise CaptureError(
            f"columns 'a' and 'b' differ in length in {where} ({na} and {nb} samples); "
            "they must be sampled together."
        )
    if nt != na:
        raise CaptureError(
            f"column 'time_s' has {nt} samples but 'a' and 'b' have {na} in {where}; "
            "they must be sampled together."
        )
    return out


def _pass_check(passes: _Passes, allow_clipped: bool) -> tuple[int, tuple[str, ...]]:
    """Pass 1: sample count, NaN/inf, time order and clipping (the rails of a and b, state
    carried across chunks), with the in-memory messages and priority; the clipping warnings."""
    rails = {"a": RailDetector("a"), "b": RailDetector("b")}
    counts = dict.fromkeys(_COLUMNS, 0)
    first_bad = dict.fromkeys(_COLUMNS, -1)
    order: tuple[int, Any, Any] | None = None
    first_t: Any = None
    last_t: Any = None
    typical: float | None = None  # the median time step of the first chunk
    gap: tuple[int, float, float] | None = None
    lengths: list[int] = []
    n = 0
    # magnitudes of a and b, as the in-memory check_magnitudes: the first value beyond the working
    # range, and each column's largest |value| (inf once a chunk passes the one-pass test)
    too_large: CaptureError | None = None
    peak = {"a": 0.0, "b": 0.0}
    for _, off, cols in passes.run():
        lengths.append(cols["a"].size)
        for name in ("a", "b", "time_s"):
            x = cols[name]
            if name != "time_s" and in_working_range(x):
                peak[name] = math.inf
                continue
            with np.errstate(over="ignore", invalid="ignore"):
                total = float(np.sum(x))
            if not math.isfinite(total):
                bad = np.flatnonzero(~np.isfinite(x))
                if bad.size:
                    counts[name] += int(bad.size)
                    if first_bad[name] < 0:
                        first_bad[name] = off + int(bad[0])
                    continue
            if name != "time_s" and x.size:
                chunk_peak = float(np.max(np.abs(x)))
                peak[name] = max(peak[name], chunk_peak)
                if chunk_peak > LARGEST and too_large is None:
                    try:
                        check_magnitudes(name, x, what="an encoder signal", offset=off)
                    except CaptureError as exc:
                        too_large = exc
        t = cols["time_s"]
        if order is None:
            if last_t is not None and t[0] - last_t <= 0:
                order = (off, last_t, t[0])
            else:
                steps = np.flatnonzero(np.diff(t) <= 0)
                if steps.size:
                    i = int(steps[0])
                    order = (off + i + 1, t[i], t[i + 1])
        if typical is None and t.size > 1:
            typical = float(np.median(np.diff(t[: TYPICAL_STEPS + 1])))
        if gap is None and typical is not None:
            joined = t if last_t is None else np.concatenate(([last_t], t))
            steps = np.diff(joined)
            g = np.flatnonzero(steps > MAX_GAP * typical)
            if g.size:
                gap = (off + int(g[0]) + (1 if last_t is None else 0), float(steps[g[0]]), typical)
        if first_t is None and t.size:
            first_t = t[0]
        last_t = t[-1]
        n += cols["a"].size
        rails["a"].add(cols["a"], cols["b"])
        rails["b"].add(cols["b"], cols["a"])
    passes.lengths = lengths
    if n < _MIN_SAMPLES:
        raise CaptureError(f"column 'a' has {n} samples; at least {_MIN_SAMPLES} are needed.")
    for name in ("a", "b", "time_s"):
        if counts[name]:
            raise CaptureError(
                f"column '{name}' has {counts[name]} non-finite values (NaN or inf), the first "
                f"at sample {first_bad[name]}; remove or interpolate them before demodulating."
            )
    if too_large is not None:
        raise too_large
    for name in ("a", "b"):
        if 0.0 < peak[name] < SMALLEST:
            check_magnitudes(name, np.array([peak[name]]), what="an encoder signal")
    if order is not None:
        row, before, after = order
        raise CaptureError(
            f"column 'time_s' is not strictly increasing at sample {row} "
            f"({float(before):.9g} s then {float(after):.9g} s); sort or fix the time stamps."
        )
    if gap is not None:
        raise gap_error("time_s", *gap)
    if typical is not None:
        check_time_span("time_s", float(first_t), float(last_t), typical)
    found = {name: det.result() for name, det in rails.items()}
    return n, check_clipping(found, allow_clipped=allow_clipped)


def _pass_correction(passes: _Passes, n: int) -> QuadratureCorrection:
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
        a_s, b_s, max_points=max(a_s.size, _MIN_SAMPLES), allow_clipped=True
    )


@dataclasses.dataclass
class _Demod:
    plan: ReversalPlan
    states: list[PhaseState | None]
    plot_t: np.ndarray
    plot_angle: np.ndarray
    plot_a: np.ndarray
    plot_b: np.ndarray
    span_deg: float  # max θ − min θ over the capture
    net_deg: float  # last θ − first θ


def _pass_phase(
    passes: _Passes,
    n: int,
    corr: QuadratureCorrection,
    scale: float,
    hysteresis_subintervals: int | None = None,
    hysteresis_from: HysteresisRule | None = None,
) -> _Demod:
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
    return _Demod(
        plan=plan,
        states=states,
        plot_t=np.concatenate(dec["t"]),
        plot_angle=np.concatenate(dec["angle"]),
        plot_a=np.concatenate(dec["a"]),
        plot_b=np.concatenate(dec["b"]),
        span_deg=(hi - lo) * scale,
        net_deg=(ends[-1] - ends[0]) * scale,
    )


def _pass_reversals(
    passes: _Passes, n: int, corr: QuadratureCorrection, plan: ReversalPlan
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


def _segment(
    passes: _Passes,
    states: list[PhaseState | None],
    corr: QuadratureCorrection,
    scale: float,
    first: int,
    last: int,
) -> Iterator[tuple[int, np.ndarray, np.ndarray]]:
    """θ (deg) of samples ``first..last``, recomputed chunk by chunk from the saved phase state:
    ``(global index of the piece's first sample, t, θ)``."""
    for number, off, cols in passes.run(first, last + 1):
        phase = phase_pass(
            cols["a"], cols["b"], corr, state=states[number], jit=use_numba(last + 1 - first)
        ).phase_rad
        s = max(first - off, 0)
        e = min(last + 1 - off, phase.size)
        yield off + s, cols["time_s"][s:e], phase[s:e] * scale


def _decimate(g0: int, first: int, step: int, x: np.ndarray) -> np.ndarray:
    """Samples of ``x`` (first global index ``g0``) whose index − first is a multiple of step."""
    return np.array(x[(first - g0) % step :: step])


# --------------------------------------------------------------------------------------------
# public API
# --------------------------------------------------------------------------------------------


def calibrate_encoder_motion_chunked(
    chunks: ChunkSource,
    *,
    lines: int,
    harmonics: int = 10,
    periods: int | None = None,
    set_amplitude_deg: float | None = None,
    set_frequency_hz: float | None = None,
    correction: QuadratureCorrection | None = None,
    progress: Callable[[int], None] | None = None,
    specs: InstrumentSpecs | None = None,
    allow_clipped: bool = False,
    drift: bool = False,
    hysteresis_subintervals: int | None = None,
) -> MotionResult:
    """Sinusoidal-motion calibration from an encoder capture read in chunks (flat memory).

    The same calibration as :func:`~rotacal.table.calibrate_encoder_motion` — Heydemann-corrected
    quadrature demodulation, 12 subintervals per signal period, reversing moments by the odd/even
    trend-change rule and their precise point (eqs. (3)–(8)), n whole periods between 2n+1
    reversals, the IEEE 1057 multi-harmonic fit and THD (eq. (1)), and with set values the
    angular position error (eq. (2)) — and the same result (reversals to the sample, numbers to
    rounding), computed in five or six passes over the capture so that memory is bounded by the
    chunk size (see the module docstring).

    Parameters
    ----------
    chunks : callable
        ``chunks()`` starts a fresh pass over the capture and returns an iterator of mappings
        holding the 1-D arrays ``time_s`` (s), ``a`` and ``b`` (signal unit, e.g. V) of one chunk
        each, in time order; every call must give the same chunks. See
        :func:`encoder_chunks_from_file`.
    lines : int
        Encoder lines (signal periods) per revolution.
    harmonics : int
        N_H, highest harmonic in the fit and the THD (default 10).
    periods : int, optional
        Whole motion periods to analyse (default: all the capture holds).
    set_amplitude_deg, set_frequency_hz : float, optional
        The table's set values (deg, Hz).
    correction : QuadratureCorrection, optional
        A known correction instead of fitting one (skips that pass).
    progress : callable, optional
        Called after each chunk with the number of samples processed so far, summed over the
        passes (at most 6·N for a capture of N samples; passes 4–6 read only what they need).
    specs : InstrumentSpecs, optional
        The lab's instrument specifications (Type B inputs of the budgets, as in memory).
    allow_clipped : bool
        Analyse a capture whose a or b sits at the rails anyway (named in ``warnings``); refused
        by default. Pass 1 judges every sample (:class:`~rotacal.signal.RailDetector`, state
        carried across chunks): the same finding, and message, as in memory.
    drift : bool
        Fit a linear drift term beside the harmonics (``drift_deg_s``), as in memory; with set
        values this costs one more pass (the three-parameter fit of eq. (2) on θ less the drift).
    hysteresis_subintervals : int, optional
        The reversal rule's hysteresis (subintervals), as in memory.

    Returns
    -------
    MotionResult

    Raises
    ------
    CaptureError
        The one-line errors of the in-memory path, with sample indices counted from the start of
        the capture (NaN/inf, time not increasing — also across chunks —, clipping, signals not in
        quadrature, too few reversals), and chunks that are not mappings of equal-length 1-D
        ``time_s``, ``a``, ``b`` or that change from one pass to the next.
    ConfigError
        Bad ``lines``, ``harmonics``, ``periods`` or set values.

    References
    ----------
    Feng et al. (2023), Sensors 23:4876, §3 and eqs. (1)–(8); IEEE Std 1057-2017, §4.1.3;
    Heydemann 1981, Appl. Opt. 20:3382 (signal correction); JCGM 100:2008, JCGM 101:2008
    (budgets, :mod:`rotacal.table.motion_uncertainty`).
    """
    _check_settings(harmonics, periods)
    if int(lines) != lines or lines < 1:
        raise ConfigError(f"--lines must be a positive whole number, got {lines}")
    with_set = set_amplitude_deg is not None or set_frequency_hz is not None
    _check_set_values(set_amplitude_deg, set_frequency_hz)
    passes = _Passes(chunks, progress)
    scale = 360.0 / (_TWO_PI * float(lines))

    n, clipped = _pass_check(passes, allow_clipped)
    corr = correction if correction is not None else _pass_correction(passes, n)
    demod = _pass_phase(
        passes,
        n,
        corr,
        scale,
        hysteresis_subintervals,
        drift_free_hysteresis() if drift else None,
    )
    rev_idx, rev_times = _pass_reversals(passes, n, corr, demod.plan)
    first, last, n_periods = _cut(
        rev_idx, periods, "encoder capture", demod.span_deg, None if drift else demod.net_deg
    )
    t_first, t_last = rev_times[0], rev_times[2 * n_periods]
    f0 = n_periods / (t_last - t_first)
    n_seg = last + 1 - first
    seg_step = _plot_stride(n_seg)
    plot: dict[str, Any] = {
        "t": demod.plot_t,
        "angle_deg": demod.plot_angle,
        "reversal_kinds": demod.plan.kinds,
        "lissajous_raw": (demod.plot_a, demod.plot_b),
        "lissajous_corrected": correct_quadrature(demod.plot_a, demod.plot_b, corr),
        "correction": corr,
        "unit": "deg",
    }
    notes = [f"quadrature correction: {corr.method}"]
    common: dict[str, Any] = {
        "scheme": "encoder",
        "reversal_times": rev_times,
        "periods": n_periods,
        "set_amplitude_deg": set_amplitude_deg,
        "set_frequency_hz": set_frequency_hz,
        "notes": notes,
        "snr": None,
        "specs": specs,
        # sampling interval and capture start for the reversal budget (as in memory)
        "_dt": float(t_last - t_first) / max(last - first, 1),
        "_t0": float(demod.plot_t[0]),
    }

    if n_seg <= _GATHER_MAX_SAMPLES:
        # Small enough to hold: the very arrays, fits and position error of the in-memory path.
        pieces = list(_segment(passes, demod.states, corr, scale, first, last))
        t_seg = np.concatenate([np.array(p[1]) for p in pieces])
        th_seg = np.concatenate([p[2] for p in pieces])
        del pieces
        fit = fit_motion(t_seg, th_seg, f0, harmonics, drift)
        plot["t_used"] = t_seg[::seg_step]
        plot["residual_deg"] = th_seg[::seg_step] - fit.evaluate(t_seg[::seg_step])
        return with_warnings(_result(fit, plot, common, t_seg, th_seg), clipped)

    acc = HarmonicFitAccumulator(f0, harmonics=harmonics)
    # with a drift term, eq. (2)'s fit waits for the drift (a pass of its own, below)
    acc3 = HarmonicFitAccumulator(set_frequency_hz, harmonics=1) if with_set and not drift else None
    dec_t: list[np.ndarray] = []
    dec_th: list[np.ndarray] = []

    def tap() -> Iterator[tuple[int, np.ndarray, np.ndarray]]:
        """The segment's pieces, keeping decimated copies for the figures on the way."""
        for g0, t_piece, th_piece in _segment(passes, demod.states, corr, scale, first, last):
            dec_t.append(_decimate(g0, first, seg_step, t_piece))
            dec_th.append(_decimate(g0, first, seg_step, th_piece))
            yield g0, t_piece, th_piece

    _accumulate([acc] if acc3 is None else [acc, acc3], tap())
    fit = explained_fit(
        lambda with_term: acc.fit(
            f0, harmonics, True, max_iter=50, rtol=1e-12, drift=with_term, drift_check=not with_term
        ),
        drift,
    )
    t_dec = np.concatenate(dec_t)
    plot["t_used"] = t_dec
    plot["residual_deg"] = np.concatenate(dec_th) - fit.evaluate(t_dec)
    extra: dict[str, Any] = {"samples_used": n_seg}
    if with_set and set_amplitude_deg is not None and set_frequency_hz is not None:
        segment = functools.partial(_segment, passes, demod.states, corr, scale, first, last)
        if acc3 is None:  # drift fitted: eq. (2) on θ less the drift, its fit in a pass of its own
            segment = functools.partial(_detrended, segment, fit)
            acc3 = HarmonicFitAccumulator(set_frequency_hz, harmonics=1)
            _accumulate([acc3], segment())
        fit3 = acc3.fit(set_frequency_hz, 1, False, max_iter=1, rtol=1e-12)
        worst, rms, err_dec = _position_error_pass(
            segment, first, last, fit3, set_amplitude_deg, set_frequency_hz
        )
        plot["position_error_deg"] = err_dec
        extra.update(position_error_max_deg=worst, position_error_rms_deg=rms)
    result = _result(fit, plot, common, np.array([t_first, t_last]), None)
    return with_warnings(dataclasses.replace(result, **extra), clipped)


def _result(
    fit: SineFit,
    plot: dict[str, Any],
    common: dict[str, Any],
    t_used: np.ndarray,
    angle_used: np.ndarray | None,
) -> MotionResult:
    common = dict(common)
    detection = ReversalDetection(
        method="argmax",
        fit=fit,
        sample_interval_s=common.pop("_dt"),
        capture_start_s=common.pop("_t0"),
    )
    return _finish(
        detection=detection,
        fit=fit,
        displacement_amplitudes=fit.amplitudes,
        displacement_amplitudes_u=fit.amplitudes_u,
        offset_deg=fit.offset,
        residual_rms_deg=fit.residual_rms,
        t_used=t_used,
        angle_used=angle_used,
        plot=plot,
        **common,
    )


def _detrended(
    segment: Callable[[], Iterator[tuple[int, np.ndarray, np.ndarray]]], fit: SineFit
) -> Iterator[tuple[int, np.ndarray, np.ndarray]]:
    """The pieces of ``segment()`` with θ less the fitted drift (``detrended_angle``)."""
    for g0, t_piece, th_piece in segment():
        yield g0, t_piece, detrended_angle(fit, t_piece, th_piece)


def _accumulate(
    accs: list[HarmonicFitAccumulator], pieces: Iterator[tuple[int, np.ndarray, np.ndarray]]
) -> None:
    """Feed the pieces to each accumulator, the first 2¹⁶ samples as one piece (the in-memory
    fit takes its working offset from them)."""

    def add(t_piece: np.ndarray, th_piece: np.ndarray) -> None:
        for acc in accs:
            acc.add(t_piece, th_piece)

    held: list[tuple[np.ndarray, np.ndarray]] = []
    n_held = 0
    for _, t_piece, th_piece in pieces:
        if n_held < _FIRST_ADD_SAMPLES:
            held.append((np.array(t_piece), th_piece))
            n_held += t_piece.size
            if n_held >= _FIRST_ADD_SAMPLES:
                add(np.concatenate([h[0] for h in held]), np.concatenate([h[1] for h in held]))
                held = []
        else:
            add(t_piece, th_piece)
    if held:
        add(np.concatenate([h[0] for h in held]), np.concatenate([h[1] for h in held]))


def _position_error_pass(
    segment: Callable[[], Iterator[tuple[int, np.ndarray, np.ndarray]]],
    first: int,
    last: int,
    fit3: SineFit,
    set_amplitude_deg: float,
    set_frequency_hz: float,
) -> tuple[float, float, np.ndarray]:
    """Pass 6: eq. (2) against the ideal sinusoid of :func:`~rotacal.table.position_error`."""
    phase0 = float(fit3.phases_rad[0])
    step = _plot_stride(last + 1 - first)
    worst = 0.0
    total = 0.0
    dec: list[np.ndarray] = []
    for g0, t_piece, th_piece in segment():
        ideal = fit3.offset + set_amplitude_deg * np.sin(
            2 * np.pi * set_frequency_hz * (t_piece - fit3.t_ref_s) + phase0
        )
        err = th_piece - ideal
        worst = max(worst, float(np.max(np.abs(err))))
        total += float(err @ err)
        dec.append(_decimate(g0, first, step, err))
    return worst, math.sqrt(total / (last + 1 - first)), np.concatenate(dec)


# --------------------------------------------------------------------------------------------
# files
# --------------------------------------------------------------------------------------------


def _release_pages(arrays: Mapping[str, np.ndarray]) -> None:
    """Drop the pages of memory-mapped chunks from this process once they have been used.

    Pages of a file mapping that were read stay resident (and counted in the process's memory)
    until the kernel needs them; over a long capture that would look like the whole file in
    memory. ``madvise(MADV_DONTNEED)`` gives them back; the data stay in the page cache and a
    later read maps them again. Best effort: nothing happens where madvise is not available.
    """
    dontneed = getattr(mmap, "MADV_DONTNEED", None)
    if dontneed is None:
        return
    for arr in arrays.values():
        base: Any = arr
        while isinstance(base, np.ndarray):
            base = base.base
        if not isinstance(base, mmap.mmap) or arr.nbytes == 0:
            continue
        try:
            anchor = np.frombuffer(base, dtype=np.uint8)
            start = arr.__array_interface__["data"][0] - anchor.__array_interface__["data"][0]
            del anchor
            page_start = start - start % mmap.PAGESIZE
            base.madvise(dontneed, page_start, start + arr.nbytes - page_start)
        except (AttributeError, BufferError, OSError, ValueError):
            continue


def encoder_chunks_from_file(
    path: str | os.PathLike[str],
    *,
    mapping: Mapping[str, str] | None = None,
    group: str | None = None,
    chunk_rows: int = 2_000_000,
) -> ChunkSource:
    """A chunk source for :func:`calibrate_encoder_motion_chunked` reading an encoder capture file.

    Each call of the returned function streams ``time_s``, ``a`` and ``b`` from the file with
    :func:`rotacal.io.iter_capture_chunks` (CSV, NPZ, HDF5, TDMS; uncompressed NPZ members and
    contiguous HDF5 datasets are memory-mapped, and the pages of each chunk are handed back to
    the system once the next chunk is asked for, so the process's memory stays flat).

    Parameters
    ----------
    path : str or path-like
        The capture file.
    mapping : mapping, optional
        File column name -> canonical name (``--column OLD=NEW``).
    group : str, optional
        HDF5 or TDMS group holding the columns.
    chunk_rows : int
        Rows per chunk (default 2·10⁶: ≈ 48 MB of float64 columns, ≈ 0.5 GB of work arrays).

    Returns
    -------
    callable
        ``chunks()`` → iterator of ``{"time_s": ..., "a": ..., "b": ...}`` (s, signal unit).

    Raises
    ------
    ConfigError
        ``chunk_rows`` not a whole number ≥ 1. File errors are raised by the first pass.
    """
    if isinstance(chunk_rows, bool) or not isinstance(chunk_rows, int | np.integer):
        raise ConfigError(f"chunk_rows must be a whole number of rows, not {chunk_rows!r}")
    if chunk_rows < 1:
        raise ConfigError(f"chunk_rows must be at least 1, not {chunk_rows}")
    rows = int(chunk_rows)

    def chunks() -> Iterator[dict[str, np.ndarray]]:
        previous: dict[str, np.ndarray] | None = None
        try:
            for chunk in iter_capture_chunks(
                path, _COLUMNS, chunk_rows=rows, mapping=mapping, group=group
            ):
                if previous is not None:
                    _release_pages(previous)
                previous = chunk
                yield chunk
        finally:
            if previous is not None:
                _release_pages(previous)

    return chunks
