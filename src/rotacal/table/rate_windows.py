"""Rate accuracy and stability over angle windows: a rate table's acceptance figures.

A rate table's datasheet states its rate accuracy and rate stability "over 1°", "over 10°" and
"over 360°". The test behind those words (the rate-stability test of commercial rate tables that
Kokuyama et al. (2015), §5 describe: "comparing the elapsed time to rotate through a known angle";
IEEE Std 1431-2004 and IEEE Std 952-1997 take the table's rate from the same kind of encoder
timing) cuts the record into consecutive, non-overlapping windows of W degrees and takes the mean
rate of each, ``ω_i = Θ_i/(t_end,i − t_start,i)``. For each W, with the N window rates:

- ``rate_accuracy_percent`` = 100·(ω̄ − Ω_set)/Ω_set, ω̄ the mean of the N window rates;
- ``rate_stability_percent`` = 100·s(ω_i)/ω̄, s the standard deviation (N − 1);
- ``rate_stability_peak_percent`` = 100·max|ω_i − ω̄|/ω̄.

A window of W° spans k = W·m/360 pulse pitches of an m-line encoder (rounded to whole pitches;
the angle used is k·360/m). Its angle Θ_i is k pitches, plus, with a self-calibration, the
difference of the scale's deviation at its two end lines (``pulse_angle_deg``'s convention).
A window of 360° (any multiple of m pitches) starts and ends on the same line, so the graduation
error cancels exactly and the 360° figures hold the table alone; over 1° the graduation error
between the end lines enters every window rate (relative error Δd/W), which is why datasheets
state a looser stability over small angles and why the compensated angle matters there.

Uncertainty (GUM, JCGM 100), per window, relative to the rate: the timing noise of its two end
pulses, √2·σ_t/T (σ_t from the pulse times, T = W/ω̄); the angle error of its two end lines,
√2·u_line/(3600·W) (u_line the self-calibration's point uncertainty and the undetectable orders
when compensated, the stated ``encoder.graduation_error_arcsec`` when not; zero at multiples of
360°); for times interpolated from an angle readout or counter of quantum q, its resolution:
each end within a width q (JCGM 100 F.2.2.1), the window's angle within ±q, rectangular
(§4.3.7), q/(√3·W) at every W, 360° included. Together σ_w. Then

- ω̄: the end-point terms of a mean of consecutive windows telescope (√2·σ_t/(N·T)), the stated
  timebase error ``timebase.relative_error`` and the statistics of N windows, s/√N;
- the stability s: the statistics of N windows, s/√(2(N − 1)), what the measurement noise
  (σ_w without the resolution) may add to it, s − √(s² − σ_w²) (the plain value is not
  corrected for it), and the resolution's q/(√3·W): its errors need not be random, and they
  move s either way by at most their own standard deviation (a norm's triangle inequality);
- the peak: u(ω̄) and the largest shift noise gives one of N windows, σ_w·max(1, √(2·ln N)).

Every figure comes from one pass over the pulse times in chunks with carried state
(:class:`WindowSums`: the last window boundary carried across chunks, shifted sums of the rates
added exactly with ``math.fsum``), so a record of any length streams in bounded memory;
:func:`window_rates` computes the same window rates from a whole array for figures and tests.

References
----------
Kokuyama W., Watanabe T., Nozato H., Ota A. (2015), "Development of angular velocity
calibration facility using self-calibratable rotary encoder", §3 (the compensated angle), §5
(rate from pulse timing; rate stability as elapsed time through a known angle). IEEE Std
1431-2004, IEEE Std 952-1997 (rate-table tests of gyros). JCGM 100:2008 (GUM).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Iterable, Iterator, Sequence
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from rotacal.encoder.pulses import check_pulse_times
from rotacal.errors import CaptureError, ConfigError
from rotacal.results import Result
from rotacal.uncertainty.coverage import coverage_factor

__all__ = [
    "RateWindows",
    "WindowSums",
    "rate_windows",
    "rate_windows_stream",
    "window_coverage_factor",
    "window_key",
    "window_pitches",
    "window_rates",
]

FloatArray = NDArray[np.float64]

#: Window rates kept for the figure of each window size; longer records keep the least and the
#: largest rate of each block of consecutive windows (the block a power of two).
TRACE_POINTS = 4096
#: A timestamp's float64 spacing above this fraction of a window's duration earns a warning.
_RESOLUTION_WARN = 1e-7
#: Pulses per chunk when a whole array is streamed through :class:`WindowSums`.
_ARRAY_CHUNK = 1 << 22


def window_key(window_deg: float) -> str:
    """The JSON key of a window: ``"1"``, ``"10"``, ``"360"``, ``"0.5"``."""
    return f"{float(window_deg):g}"


def window_pitches(window_deg: float, pulses_per_rev: int) -> int:
    """k, the whole pulse pitches of one window of ``window_deg`` (deg) on an m-line encoder.

    Refuses a window that is not a finite positive angle or that spans fewer than 2 pitches.
    """
    w = float(window_deg)
    m = int(pulses_per_rev)
    if not math.isfinite(w) or w <= 0:
        raise ConfigError(f"--window-deg {window_deg!r}: a window must be a positive angle (deg).")
    k = round(w * m / 360.0)
    if k < 2:
        raise ConfigError(
            f"--window-deg {window_key(w)}: the window spans {w * m / 360.0:.3g} pulse pitch(es) "
            f"of {360.0 / m:.6g}° (m = {m}), fewer than 2; choose windows of at least "
            f"{720.0 / m:.6g}°."
        )
    return k


def _window_angles(
    start: NDArray[np.int64], k: int, m: int, deviation: FloatArray | None, shift: int
) -> FloatArray | float:
    """Angle (deg) of the windows starting at pulse numbers ``start``: k pitches, plus the
    deviation's difference between the end lines (index (pulse + shift) mod m)."""
    nominal = k * (360.0 / m)
    if deviation is None or k % m == 0:
        return nominal
    a = (start + shift) % m
    b = (start + k + shift) % m
    return nominal + (deviation[b] - deviation[a]) / 3600.0


def window_rates(
    times_s: ArrayLike,
    *,
    pulses_per_rev: int,
    window_deg: float,
    deviation_arcsec: ArrayLike | None = None,
    line_offset: int = 0,
) -> tuple[FloatArray, FloatArray]:
    """The mean rate of every consecutive, non-overlapping window of one head's whole array.

    Parameters
    ----------
    times_s : array_like, s
        Pulse times of one head, in order.
    pulses_per_rev : int
        m, pulses per revolution.
    window_deg : float, deg
        W; a window spans k = round(W·m/360) ≥ 2 pitches, the first starts at the first pulse.
    deviation_arcsec : array_like (m,), arcsec, optional
        The scale's deviation (INTERFACE.md ``selfcal``), to compensate the window angles.
    line_offset : int
        Deviation index of the first pulse.

    Returns
    -------
    (start_s, rate_deg_s) : ndarrays
        Start time (s) and mean rate Θ/(t_end − t_start) (deg/s) of each window.

    References
    ----------
    Kokuyama et al. (2015), §5: rate as a known angle over its elapsed time.
    """
    m = int(pulses_per_rev)
    k = window_pitches(window_deg, m)
    t = np.asarray(times_s, dtype=np.float64)
    edges = t[::k]
    count = (t.size - 1) // k
    edges = edges[: count + 1]
    dev = None if deviation_arcsec is None else np.asarray(deviation_arcsec, dtype=np.float64)
    start = np.arange(count, dtype=np.int64) * k
    angle = _window_angles(start, k, m, dev, int(line_offset))
    return edges[:-1].copy(), angle / np.diff(edges)


class _Trace:
    """The window rates of one size for a figure: every rate while they are few, then the least
    and the largest of each block of 2^j consecutive windows (blocks merge in pairs)."""

    def __init__(self, points: int = TRACE_POINTS) -> None:
        self.cap = int(points)
        self.block = 1
        self.index = np.zeros(0, dtype=np.int64)  # first window of each block
        self.lo = np.zeros(0)
        self.hi = np.zeros(0)

    def add(self, first: int, rates: FloatArray) -> None:
        if not rates.size:
            return
        ids = (first + np.arange(rates.size)) // self.block
        cut = np.flatnonzero(np.diff(ids)) + 1
        starts = np.concatenate(([0], cut))
        lo = np.minimum.reduceat(rates, starts)
        hi = np.maximum.reduceat(rates, starts)
        idx = ids[starts] * self.block
        if self.index.size and self.index[-1] == idx[0]:  # the carried, unfinished block
            self.lo[-1] = min(self.lo[-1], lo[0])
            self.hi[-1] = max(self.hi[-1], hi[0])
            idx, lo, hi = idx[1:], lo[1:], hi[1:]
        self.index = np.concatenate((self.index, idx))
        self.lo = np.concatenate((self.lo, lo))
        self.hi = np.concatenate((self.hi, hi))
        while self.index.size > self.cap:
            self._halve()

    def _halve(self) -> None:
        self.block *= 2
        groups = self.index // self.block
        starts = np.concatenate(([0], np.flatnonzero(np.diff(groups)) + 1))
        self.index = groups[starts] * self.block
        self.lo = np.minimum.reduceat(self.lo, starts)
        self.hi = np.maximum.reduceat(self.hi, starts)


class WindowSums:
    """The windows of one size over a pulse train fed in chunks (in order), with carried state.

    Keeps the last window boundary (its pulse number and time) across chunks, so a window may
    straddle any number of chunks; sums the rates shifted by the first window's rate, per chunk
    by NumPy and across chunks exactly (``math.fsum``); the least and largest rate; a
    :class:`_Trace` for the figure. :meth:`update` takes each chunk in order.
    """

    def __init__(
        self,
        window_deg: float,
        pulses_per_rev: int,
        *,
        deviation_arcsec: FloatArray | None = None,
        line_offset: int = 0,
        trace_points: int = TRACE_POINTS,
    ) -> None:
        self.window_deg = float(window_deg)
        self.m = int(pulses_per_rev)
        self.k = window_pitches(window_deg, self.m)
        self.dev = deviation_arcsec
        self.shift = int(line_offset)
        self.seen = 0
        self.count = 0
        self.first_t = math.nan
        self.last_t = math.nan
        self._edge_j = -1
        self._edge_t = math.nan
        self.ref = math.nan
        self._s1: list[float] = []
        self._s2: list[float] = []
        self.lo = math.inf
        self.hi = -math.inf
        self.trace = _Trace(trace_points)

    def update(self, t: FloatArray) -> None:
        """Add the next pulse times (s) of the train."""
        t = np.asarray(t, dtype=np.float64)
        if not t.size:
            return
        if self.seen == 0:
            self.first_t = float(t[0])
        first = (-self.seen) % self.k  # offset of the chunk's first window boundary
        edges_t = t[first :: self.k]
        edges_j = self.seen + first + self.k * np.arange(edges_t.size, dtype=np.int64)
        self.seen += t.size
        self.last_t = float(t[-1])
        if self._edge_j >= 0:
            edges_t = np.concatenate(([self._edge_t], edges_t))
            edges_j = np.concatenate(([self._edge_j], edges_j))
        if edges_t.size:
            self._edge_t, self._edge_j = float(edges_t[-1]), int(edges_j[-1])
        if edges_t.size < 2:
            return
        angle = _window_angles(edges_j[:-1], self.k, self.m, self.dev, self.shift)
        rates = angle / np.diff(edges_t)
        if math.isnan(self.ref):
            self.ref = float(rates[0])
        x = rates - self.ref
        self._s1.append(float(np.sum(x)))
        self._s2.append(float(np.dot(x, x)))
        self.lo = min(self.lo, float(rates.min()))
        self.hi = max(self.hi, float(rates.max()))
        self.trace.add(self.count, rates)
        self.count += rates.size

    def moments(self) -> tuple[float, float]:
        """(mean rate, standard deviation of the window rates with N − 1), deg/s."""
        n = self.count
        s1, s2 = math.fsum(self._s1), math.fsum(self._s2)
        mean = self.ref + s1 / n
        var = (s2 - s1 * s1 / n) / (n - 1) if n > 1 else math.nan
        return mean, math.sqrt(max(var, 0.0))


@dataclasses.dataclass(frozen=True)
class WindowTrace:
    """The window rates of one size for a figure: the first window of each block, the least and
    largest rate (deg/s) of the block, the block's length in windows and the window's angle."""

    index: FloatArray
    lo: FloatArray
    hi: FloatArray
    block: int
    window_deg: float


def window_coverage_factor(count: int, p: float = 0.95) -> float:
    """k = t_p(N − 1) of a window result: the spread of N window rates has N − 1 degrees of
    freedom (``count`` = N; at least 1). The report and the certificate both state U = k·u.

    References
    ----------
    JCGM 100:2008 (GUM), G.3–G.4 (Student's t for ν degrees of freedom).
    """
    return coverage_factor(max(int(count) - 1, 1), p)


@dataclasses.dataclass(frozen=True)
class RateWindows(Result):
    """Rate accuracy and stability over angle windows (INTERFACE.md ``rate … --window-deg``).

    Every mapping is keyed by the window as written (``"1"``, ``"10"``, ``"360"``).

    Attributes
    ----------
    rate_accuracy_percent, rate_accuracy_percent_u : dict of float or None, %
        100·(ω̄ − Ω_set)/Ω_set and its standard uncertainty; None without a set rate.
    rate_stability_percent, rate_stability_percent_u : dict of float, %
        100·s(ω_i)/ω̄ over consecutive, non-overlapping windows, and its standard uncertainty.
    rate_stability_peak_percent, rate_stability_peak_percent_u : dict of float, %
        100·max|ω_i − ω̄|/ω̄ and its standard uncertainty.
    window_mean_rate_deg_s, window_mean_rate_deg_s_u : dict of float, deg/s
        ω̄, the mean of the window rates.
    window_count : dict of int
        N, the whole windows in the record.
    window_pulses : dict of int
        k, the pulse pitches of one window.
    window_angle_deg : dict of float, deg
        k·360/m, the angle each window spans (W rounded to whole pitches).
    window_noise_percent : dict of float, %
        σ_w, the measurement noise of one window rate (timing and line errors), % of rate.
    set_rate_deg_s : float or None, deg/s
    compensated : bool
        Whether the window angles hold the self-calibrated deviation.
    notes : list of str
    """

    rate_accuracy_percent: dict[str, float | None]
    rate_accuracy_percent_u: dict[str, float | None]
    rate_stability_percent: dict[str, float]
    rate_stability_percent_u: dict[str, float]
    rate_stability_peak_percent: dict[str, float]
    rate_stability_peak_percent_u: dict[str, float]
    window_mean_rate_deg_s: dict[str, float]
    window_mean_rate_deg_s_u: dict[str, float]
    window_count: dict[str, int]
    window_pulses: dict[str, int]
    window_angle_deg: dict[str, float]
    window_noise_percent: dict[str, float]
    set_rate_deg_s: float | None
    compensated: bool
    notes: list[str]
    _traces: dict[str, WindowTrace] = dataclasses.field(repr=False, default_factory=dict)

    @property
    def traces(self) -> dict[str, WindowTrace]:
        """The window rates of each size for figures (see :class:`WindowTrace`)."""
        return dict(self._traces)


@dataclasses.dataclass(frozen=True)
class _Noise:
    """The inputs of the windows' uncertainty: σ_t (s), the line error u_line (arcsec) that a
    window's two ends carry (0 when not known), the timebase's relative u, the timebase
    correction δ̂ the rates are multiplied by (1 + δ̂), the readout's resolution u_q = q/√6
    (deg) per end, so that a window's two ends differ by √2·u_q = q/√3, the rectangular ±q
    (0: exact marks)."""

    jitter_s: float
    line_arcsec: float
    timebase_u: float
    timebase_correction: float
    resolution_deg: float = 0.0


def _finish(
    sums: Sequence[WindowSums],
    set_rate_deg_s: float | None,
    noise: _Noise,
    compensated: bool,
    notes: list[str],
) -> RateWindows:
    """The keys of every window size from its sums (see the module docstring for the budget)."""
    out: dict[str, dict[str, Any]] = {
        f.name: {}
        for f in dataclasses.fields(RateWindows)
        if f.name.startswith(("rate_", "window_"))
    }
    warnings: list[str] = []
    traces: dict[str, WindowTrace] = {}
    factor = 1.0 + noise.timebase_correction
    set_rate = None if set_rate_deg_s is None else abs(float(set_rate_deg_s))
    for ws in sums:
        key = window_key(ws.window_deg)
        n = ws.count
        if n < 2:
            raise CaptureError(
                f"--window-deg {key}: the record of {ws.seen} pulses holds {n} whole window(s) "
                f"of {ws.k} pulse pitches; at least 2 are needed (a shorter window or a longer "
                "record)."
            )
        mean, std = ws.moments()
        mean, std = mean * factor, std * factor
        lo, hi = ws.lo * factor, ws.hi * factor
        angle = ws.k * 360.0 / ws.m
        duration = angle / abs(mean)
        line = 0.0 if ws.k % ws.m == 0 else noise.line_arcsec
        # the end angle errors: the line's (none over whole revolutions) and the readout's
        # resolution (at any window: the sampling need not repeat every revolution)
        end_deg = math.hypot(line / 3600.0, noise.resolution_deg)
        sigma_noise = math.hypot(
            math.sqrt(2.0) * noise.jitter_s / duration, math.sqrt(2.0) * line / 3600.0 / angle
        )
        res_w = math.sqrt(2.0) * noise.resolution_deg / angle
        sigma_w = math.hypot(sigma_noise, res_w)
        rel_s = std / abs(mean)
        u_mean_rel = math.sqrt(
            (math.sqrt(2.0) * noise.jitter_s / (n * duration)) ** 2
            + (math.sqrt(2.0) * end_deg / (n * angle)) ** 2
            + noise.timebase_u**2
            + rel_s**2 / n
        )
        inflation = rel_s - math.sqrt(max(rel_s**2 - sigma_noise**2, 0.0))
        # the resolution's errors ε need not be random (commensurate sampling): they may lower s
        # as well as raise it, by at most s(ε) (the standard deviation is a norm), ≈ res_w
        u_stab = math.hypot(rel_s / math.sqrt(2.0 * (n - 1)), inflation, res_w)
        peak = max(hi - mean, mean - lo) / abs(mean)
        u_peak = math.hypot(u_mean_rel, sigma_w * max(1.0, math.sqrt(2.0 * math.log(n))))
        out["rate_stability_percent"][key] = 100.0 * rel_s
        out["rate_stability_percent_u"][key] = 100.0 * u_stab
        out["rate_stability_peak_percent"][key] = 100.0 * peak
        out["rate_stability_peak_percent_u"][key] = 100.0 * u_peak
        out["window_mean_rate_deg_s"][key] = mean
        out["window_mean_rate_deg_s_u"][key] = abs(mean) * u_mean_rel
        if set_rate is None:
            out["rate_accuracy_percent"][key] = out["rate_accuracy_percent_u"][key] = None
        else:
            out["rate_accuracy_percent"][key] = 100.0 * (abs(mean) - set_rate) / set_rate
            out["rate_accuracy_percent_u"][key] = 100.0 * abs(mean) * u_mean_rel / set_rate
        out["window_count"][key] = n
        out["window_pulses"][key] = ws.k
        out["window_angle_deg"][key] = angle
        out["window_noise_percent"][key] = 100.0 * sigma_w
        if abs(angle - ws.window_deg) > 1e-9 * ws.window_deg:
            notes.append(
                f"the {key}° window is {ws.k} whole pulse pitches, {angle:.6g}°: its rate is "
                "the mean over that angle."
            )
        if n < 10:
            notes.append(
                f"the {key}° figures come from {n} windows: their u holds the statistics of few "
                "windows."
            )
        spacing = float(np.spacing(max(abs(ws.first_t), abs(ws.last_t))))
        if spacing > _RESOLUTION_WARN * duration:
            warnings.append(
                f"timestamps near {max(abs(ws.first_t), abs(ws.last_t)):.4g} s are resolved to "
                f"{spacing:.2g} s in float64, {spacing / duration:.2g} of a {key}° window: store "
                "the times from a reference near the record's start."
            )
        traces[key] = WindowTrace(
            index=ws.trace.index.astype(np.float64),
            lo=ws.trace.lo * factor,
            hi=ws.trace.hi * factor,
            block=ws.trace.block,
            window_deg=angle,
        )
    if set_rate is None:
        notes.append("no set rate given: rate_accuracy_percent needs --set-rate-deg-s.")
    return RateWindows(
        **out,
        set_rate_deg_s=None if set_rate_deg_s is None else float(set_rate_deg_s),
        compensated=compensated,
        notes=notes,
        _traces=traces,
        warnings=tuple(warnings),
    )


def _noise_inputs(
    times_jitter_s: float | None,
    *,
    compensated: bool,
    heads_averaged: int,
    deviation_u_arcsec: float | None,
    specs: Any,
    timebase_correction: float,
    notes: list[str],
) -> _Noise:
    """σ_t, u_line and the timebase's u from what is given and the lab's specifications."""
    from rotacal.encoder.selfcal_uncertainty import undetectable_input
    from rotacal.uncertainty.specs import spec_input

    tb = spec_input(specs, "timebase.relative_error", name="timebase", unit="1")
    if compensated or heads_averaged > 1:
        und, _ = undetectable_input(specs)
        line = math.hypot(
            deviation_u_arcsec or 0.0, 0.0 if und is None else math.hypot(und.value, und.u)
        )
        if heads_averaged > 1:
            notes.append(
                f"head-averaged times: every order of the scale's deviation but the multiples of "
                f"{heads_averaged} cancels in the window angles"
                + (
                    "."
                    if und is not None
                    else "; those multiples count as 0 (state encoder.undetectable_harmonics_arcsec)."
                )
            )
        elif deviation_u_arcsec is None:
            notes.append(
                "the self-calibration states no point uncertainty: the compensated angle of "
                "windows shorter than 360° carries only the stated undetectable orders."
            )
    else:
        grad = spec_input(
            specs, "encoder.graduation_error_arcsec", name="graduation", unit="arcsec"
        )
        line = 0.0 if grad is None else math.hypot(grad.value, grad.u)
        if grad is None:
            notes.append(
                "not compensated and no encoder.graduation_error_arcsec stated: the stability "
                "over windows shorter than 360° holds the scale's graduation error as well as the "
                "table's rate (give --selfcal, or the specification)."
            )
    return _Noise(
        jitter_s=float(times_jitter_s or 0.0),
        line_arcsec=float(line),
        timebase_u=0.0 if tb is None else float(tb.u),
        timebase_correction=float(timebase_correction),
    )


def rate_windows_stream(
    chunks: Callable[[], Iterable[ArrayLike]] | Iterable[ArrayLike],
    *,
    pulses_per_rev: int,
    windows_deg: Sequence[float],
    set_rate_deg_s: float | None = None,
    deviation_arcsec: ArrayLike | None = None,
    line_offset: int = 0,
    deviation_u_arcsec: float | None = None,
    timing_jitter_s: float | None = None,
    pulses: int | None = None,
    timebase_correction: float = 0.0,
    heads_averaged: int = 1,
    specs: Any = None,
    check: bool = True,
    progress: Callable[[int], None] | None = None,
    readout_resolution_deg: float | None = None,
) -> RateWindows:
    """Rate accuracy and stability over angle windows from one head's pulse times in chunks.

    Parameters
    ----------
    chunks : iterable of array_like, or a callable returning one
        The pulse times (s) of one head in order, chunk by chunk (any sizes).
    pulses_per_rev : int
        m, pulses per revolution.
    windows_deg : sequence of float, deg
        The window sizes W (e.g. 1, 10, 360); each spans round(W·m/360) ≥ 2 pitches.
    set_rate_deg_s : float, deg/s, optional
        The commanded rate Ω_set (its magnitude: pulse times carry no sense of rotation).
    deviation_arcsec : array_like (m,), arcsec, optional
        The self-calibrated deviation to compensate the window angles with, ``line_offset`` the
        deviation index of the first pulse (as :func:`rotacal.encoder.pulses.pulse_angle_deg`).
    deviation_u_arcsec : float, arcsec, optional
        Standard uncertainty of each point of that deviation.
    timing_jitter_s : float, s, optional
        σ_t of the pulse times (the rate analysis's ``timing_jitter_s``); None: estimated from
        the train (:class:`rotacal.table.rate_jitter.JitterSums`), which needs ``pulses``.
    pulses : int, optional
        The train's length, when σ_t is to be estimated here.
    timebase_correction : float
        δ̂, the stated mean timebase error the rates are corrected for (rate·(1 + δ̂)).
    heads_averaged : int
        n when the times are the average of n equally spaced heads (``--head all``): the
        scale's orders that are not multiples of n cancel in them, as with compensation.
    specs : InstrumentSpecs, optional
        ``timebase.relative_error``, ``encoder.graduation_error_arcsec`` (uncompensated) and
        ``encoder.undetectable_harmonics_arcsec`` (compensated or head-averaged) enter the
        uncertainty.
    check : bool
        Check the pulse times as they come (finite, increasing, no missing or extra pulse:
        :func:`rotacal.encoder.pulses.check_pulse_times`, two pulses carried across chunks);
        False when they were checked already (the rate command's analysis of the same train).
    progress : callable, optional
        Called with the pulses of each chunk handled.
    readout_resolution_deg : float, deg, optional
        The quantum q of the angle readout or counter the pulse times were interpolated from
        (:mod:`rotacal.table.rate_angle`): each window end within a width q of its mark (JCGM
        100 F.2.2.1), so each window's angle within ±q, rectangular (§4.3.7), at every window,
        360° ones included. None: exact marks.

    Returns
    -------
    RateWindows

    Raises
    ------
    ConfigError
        A window that is not positive or spans fewer than 2 pulse pitches.
    CaptureError
        A record with fewer than 2 whole windows of a size (the message names the window); bad
        pulse times (``check``).

    References
    ----------
    See the module docstring: Kokuyama et al. (2015) §5; IEEE Std 1431-2004; JCGM 100:2008.
    """
    m = int(pulses_per_rev)
    if not windows_deg:
        raise ConfigError("--window-deg: give at least one window (deg), e.g. 1,10,360.")
    dev = None if deviation_arcsec is None else np.asarray(deviation_arcsec, dtype=np.float64)
    if dev is not None and dev.shape != (m,):
        raise ConfigError(f"the deviation has {dev.size} values, not m = {m}.")
    keys = [window_key(w) for w in windows_deg]
    if len(set(keys)) != len(keys):
        raise ConfigError(f"--window-deg lists a window twice: {','.join(keys)}.")
    sums = [WindowSums(w, m, deviation_arcsec=dev, line_offset=line_offset) for w in windows_deg]
    notes: list[str] = []
    jitter = None
    if timing_jitter_s is None:
        from rotacal.table.rate_jitter import JitterSums

        if pulses is None:
            raise ConfigError(
                "give timing_jitter_s, or pulses (the train's length) to estimate it."
            )
        try:
            jitter = JitterSums(int(pulses), m)
        except CaptureError:
            notes.append("the record is too short to estimate the timing jitter: taken as 0.")
    source: Iterable[ArrayLike] = chunks() if callable(chunks) else chunks
    tail, seen = np.zeros(0), 0
    for part in source:
        t = np.asarray(part, dtype=np.float64)
        if check:
            joined = np.concatenate((tail, t))
            if joined.size >= 3:
                check_pulse_times(joined, "head_0", first_index=seen - tail.size)
            tail = joined[-2:].copy()
            seen += t.size
        for ws in sums:
            ws.update(t)
        if jitter is not None:
            jitter.update(t)
        if progress is not None:
            progress(t.size)
    sigma_t = timing_jitter_s if jitter is None else jitter.result()[0]
    noise = _noise_inputs(
        sigma_t,
        compensated=dev is not None,
        heads_averaged=int(heads_averaged),
        deviation_u_arcsec=deviation_u_arcsec,
        specs=specs,
        timebase_correction=timebase_correction,
        notes=notes,
    )
    if readout_resolution_deg is not None:
        noise = dataclasses.replace(
            noise, resolution_deg=float(readout_resolution_deg) / math.sqrt(6.0)
        )
    return _finish(sums, set_rate_deg_s, noise, dev is not None, notes)


def rate_windows(
    times_s: ArrayLike,
    *,
    pulses_per_rev: int,
    windows_deg: Sequence[float],
    **kw: Any,
) -> RateWindows:
    """:func:`rate_windows_stream` of one head's whole array of pulse times (s), in chunks of
    4 M pulses (the same numbers for any chunking; keyword arguments as there)."""
    t = np.asarray(times_s, dtype=np.float64)

    def parts() -> Iterator[FloatArray]:
        for start in range(0, t.size, _ARRAY_CHUNK):
            yield t[start : start + _ARRAY_CHUNK]

    kw.setdefault("pulses", t.size)
    return rate_windows_stream(parts, pulses_per_rev=pulses_per_rev, windows_deg=windows_deg, **kw)
