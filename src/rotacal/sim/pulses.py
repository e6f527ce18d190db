"""Digital twin of a multi-head pulse encoder on a rate table (Kokuyama et al. 2015).

The self-calibratable rotary encoder (SelfA) of Kokuyama et al. (2015), §3 is an incremental scale of m lines read
by n heads spaced equally around it; the DAQ records the time of every pulse edge at every head
(§5). :func:`simulate_pulses` makes that capture: columns ``head_0`` … ``head_{n-1}`` of pulse times
(s) as in INTERFACE.md's "multi-head pulse timestamps", and a truth dict whose scale deviation
follows INTERFACE.md's ``selfcal`` convention.

The model, all angles in degrees:

* **Scale.** Line j (0 ≤ j < m) sits at ``P_j = j·Δθ + e_j/3600``, ``Δθ = 360/m``, with the
  graduation error ``e_j = Σ_h A_h·cos(2π·h·j/m + φ_h) + g_j`` (arcsec) minus its mean; order 1 is
  the eccentricity, ``g_j`` iid Gaussian (``graduation_noise_arcsec``).
* **Heads.** Head i is fixed in space at ``h_i = i·360/n + ε_i/3600``, ``ε_0 = 0``, ``ε_i`` iid
  Gaussian (``head_placement_arcsec``).
* **Table.** ``θ(t) = θ0 + ω·t + Σ_k (a_k·ω/(2π·f_k))·sin(2π·f_k·t + ψ_k)``, so the rate is
  ``ω·(1 + Σ_k a_k·cos(2π·f_k·t + ψ_k))``.
* **Pulses.** Head i pulses whenever ``θ(t) = P_j − h_i + 360·w`` (any line j, any integer w). The
  crossing times are solved by a bracketed Newton iteration on θ(t) over whole arrays, then
  Gaussian timing jitter is added.
* **Timebase.** The DAQ's clock runs with a fractional error δ: it records ``(1 + δ)·t`` for an
  edge at true time t (a +1e-6 clock makes every time 1 ppm long, as the ``timebase.relative_error``
  specification of :mod:`rotacal.uncertainty.specs` says). δ is a stated offset plus, optionally,
  a rectangular draw per seed, so that a batch of runs samples the error a specification states.

The truth is computed from the model's own parameters (line errors, drawn placements, the closed
form θ(t)), never by a self-calibration method. The twin imports nothing of rotacal's methods.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from rotacal.errors import ConfigError
from rotacal.results import to_jsonable
from rotacal.sim.motion import _finite, _nonneg
from rotacal.sim.sensors import SimCapture, register_kind

__all__ = [
    "DEFAULT_HARMONICS",
    "MAX_TIMESTAMPS",
    "simulate_pulses",
    "table_angle_deg",
    "table_rate_deg_s",
]

FloatArray = NDArray[np.float64]

#: Scale harmonics (order, amplitude arcsec, phase rad) of the default twin: an eccentricity of
#: 3 arcsec (about 6 arcsec peak to peak, as in Kokuyama et al. 2015, Fig. 4) and a few small higher orders,
#: two of them (12, 24) multiples of the default 12 heads and so undetectable.
DEFAULT_HARMONICS: tuple[tuple[int, float, float], ...] = (
    (1, 3.0, 0.3),
    (2, 0.4, 1.1),
    (3, 0.15, 2.0),
    (12, 0.08, 0.5),
    (24, 0.03, 1.0),
)
#: Default fluctuation frequencies besides the revolution frequency (Hz).
DEFAULT_FLUCTUATION_HZ: tuple[float, ...] = (2.3, 7.9)
#: Largest number of timestamps (all heads together) the twin makes in one go.
MAX_TIMESTAMPS = 200_000_000
#: A head may sit at most this many pitches away from its nominal place.
MAX_PLACEMENT_PITCH = 0.4
#: Newton iterations before giving up (the bracket halves at least every iteration).
_MAX_NEWTON = 200
#: Timing jitter must stay below this fraction of the shortest pulse interval.
_JITTER_FRACTION = 1.0 / 50.0


# ---------------------------------------------------------------------- argument checks
def _int(name: str, value: Any, minimum: int) -> int:
    ok = isinstance(value, int | np.integer) and not isinstance(value, bool | np.bool_)
    if not ok and isinstance(value, float | np.floating) and float(value).is_integer():
        ok = True
    if not ok:
        raise ConfigError(f"{name} must be a whole number, got {value!r}.")
    v = int(value)
    if v < minimum:
        raise ConfigError(f"{name} must be at least {minimum}, got {v}.")
    return v


def _harmonics(harmonics: Any, m: int) -> list[tuple[int, float, float]]:
    if harmonics is None:
        return []
    if isinstance(harmonics, str | bytes | Mapping) or not isinstance(harmonics, Iterable):
        raise ConfigError(
            f"harmonics must be a sequence of (order, amplitude_arcsec, phase_rad) triples, "
            f"got {harmonics!r}."
        )
    out: list[tuple[int, float, float]] = []
    for k, item in enumerate(harmonics):
        try:
            order, amp, phase = item
        except (TypeError, ValueError):
            raise ConfigError(
                f"harmonics[{k}] must be an (order, amplitude_arcsec, phase_rad) triple, "
                f"got {item!r}."
            ) from None
        h = _int(f"harmonics[{k}] order", order, 1)
        if 2 * h >= m:
            raise ConfigError(
                f"harmonics[{k}] order {h} is not below half of pulses_per_rev={m}, so the "
                "lines cannot carry it; use an order below m/2."
            )
        out.append(
            (h, _nonneg(f"harmonics[{k}] amplitude", amp), _finite(f"harmonics[{k}] phase", phase))
        )
    return out


def _frequencies(fluctuation_hz: Any) -> list[float]:
    if isinstance(fluctuation_hz, str | bytes) or not isinstance(fluctuation_hz, Iterable):
        raise ConfigError(
            f"fluctuation_hz must be a sequence of frequencies (Hz) or None, got {fluctuation_hz!r}."
        )
    freqs = [_finite(f"fluctuation_hz[{k}]", f) for k, f in enumerate(fluctuation_hz)]
    for k, f in enumerate(freqs):
        if f <= 0:
            raise ConfigError(f"fluctuation_hz[{k}] must be > 0 Hz, got {f!r}.")
    if len(set(freqs)) != len(freqs):
        raise ConfigError(
            f"fluctuation_hz holds a frequency twice ({freqs}); give each frequency once."
        )
    return freqs


# ---------------------------------------------------------------------- table motion
def _fluct_angle(t: FloatArray, w_hz: FloatArray, c_deg: FloatArray, psi: FloatArray) -> FloatArray:
    """Σ_k c_k·sin(ω_k·t + ψ_k) (deg), one term at a time (K is small)."""
    out = np.zeros_like(t)
    for wk, ck, pk in zip(w_hz, c_deg, psi, strict=True):
        out += ck * np.sin(wk * t + pk)
    return out


def _fluct_rate(t: FloatArray, w_hz: FloatArray, a_rel: FloatArray, psi: FloatArray) -> FloatArray:
    """1 + Σ_k a_k·cos(ω_k·t + ψ_k) (-), the relative rate."""
    out = np.ones_like(t)
    for wk, ak, pk in zip(w_hz, a_rel, psi, strict=True):
        out += ak * np.cos(wk * t + pk)
    return out


def _solve_crossings(
    rhs: FloatArray,
    omega: float,
    w_hz: FloatArray,
    a_rel: FloatArray,
    psi: FloatArray,
    tol_s: float,
) -> tuple[FloatArray, int, float]:
    """Times t with ``ω·t + F(t) = rhs`` (rhs = target angle − θ0, deg) by bracketed Newton.

    ``|F| ≤ C = Σ|c_k|`` brackets every root in ``[(rhs − C)/ω, (rhs + C)/ω]``; a Newton step that
    leaves the (shrinking) bracket is replaced by bisection, so the iteration always converges.
    Returns the times (s), the iterations used and the largest last step (s).
    """
    c_deg = a_rel * omega / w_hz
    big_c = float(np.sum(np.abs(c_deg)))
    lo = (rhs - big_c) / omega
    hi = (rhs + big_c) / omega
    t = rhs / omega
    step = math.inf
    for it in range(1, _MAX_NEWTON + 1):
        f = omega * t + _fluct_angle(t, w_hz, c_deg, psi) - rhs
        above = f > 0
        hi = np.where(above, np.minimum(hi, t), hi)
        lo = np.where(above, lo, np.maximum(lo, t))
        t_new = t - f / (omega * _fluct_rate(t, w_hz, a_rel, psi))
        out = (t_new < lo) | (t_new > hi)
        if out.any():
            t_new = np.where(out, 0.5 * (lo + hi), t_new)
        step = float(np.max(np.abs(t_new - t))) if t.size else 0.0
        t = t_new
        if step <= tol_s:
            return t, it, step
    raise RuntimeError(  # unreachable: the bracket halves at least once per iteration
        f"pulse crossing times did not converge in {_MAX_NEWTON} iterations (last step {step} s)."
    )


# ---------------------------------------------------------------------- the twin
def simulate_pulses(
    *,
    heads: int = 12,
    pulses_per_rev: int = 18000,
    rate_deg_s: float = 300.0,
    revolutions: float = 3.0,
    harmonics: Iterable[tuple[int, float, float]] | None = DEFAULT_HARMONICS,
    graduation_noise_arcsec: float = 0.03,
    head_placement_arcsec: float = 5.0,
    rate_bias_percent: float = 0.0,
    rate_fluctuation_percent: float = 0.01,
    fluctuation_hz: Iterable[float] | None = None,
    jitter_s: float = 1e-9,
    start_spread_s: float | None = None,
    timebase_relative_error: float = 0.0,
    timebase_error_half_width: float = 0.0,
    seed: int = 0,
    noise_seed: int | None = None,
) -> SimCapture:
    """Pulse-edge times of an n-head self-calibratable encoder on a table turning at constant rate.

    See the module docstring for the model. Every random component (graduation noise, head
    placement, fluctuation phases, θ0, record delays, jitter, timebase error) has its own stream
    spawned from ``seed``, so switching one off leaves the others unchanged.

    Parameters
    ----------
    heads : int
        Number of read heads n (-), ≥ 2, equally spaced; head 0 is the reference.
    pulses_per_rev : int
        Lines (pulses per revolution) m of the scale (-), ≥ ``heads``; need not be divisible by n.
    rate_deg_s : float
        Set rate of the table (deg/s), > 0: the twin turns forward only.
    revolutions : float
        Length of the DAQ record in revolutions at the mean rate (-), > 0; the record lasts
        ``revolutions·360/ω`` s from t = 0.
    harmonics : sequence of (int, float, float) or None
        Scale error harmonics ``(order h ≥ 1 (-), amplitude A_h ≥ 0 (arcsec), phase φ_h (rad))``,
        each adding ``A_h·cos(2π·h·j/m + φ_h)`` to line j; order 1 is the eccentricity. Orders
        must stay below m/2.
    graduation_noise_arcsec : float
        Standard deviation of the iid random graduation error of each line (arcsec), ≥ 0.
    head_placement_arcsec : float
        Standard deviation of the placement error ε_i of heads 1 … n−1 (arcsec), ≥ 0. A head must
        sit within half a pitch of its nominal place i·360/n; a draw farther than 0.4 pitch from it
        is refused with a ConfigError.
    rate_bias_percent : float
        Mean rate error (%): ``ω = rate_deg_s·(1 + rate_bias_percent/100)``, which must stay > 0.
    rate_fluctuation_percent : float
        RMS of the relative rate fluctuation (%), ≥ 0, shared equally among the frequencies
        (``a_k = rate_fluctuation_percent/100·sqrt(2/K)``); ``Σ a_k`` must stay below 1 so the
        rate never reaches zero.
    fluctuation_hz : sequence of float or None
        Frequencies of the rate fluctuation (Hz), distinct, each > 0 and below half the pulse rate
        ``ω/Δθ``. None: the revolution frequency ω/360, 2.3 Hz and 7.9 Hz (none at all when
        ``rate_fluctuation_percent`` is 0).
    jitter_s : float
        Standard deviation of the Gaussian timing jitter added to every timestamp (s), ≥ 0 and at
        most 1/50 of the shortest pulse interval.
    start_spread_s : float or None
        Each head's record starts late by an independent uniform delay in ``[0, start_spread_s]``
        and ends early by another one (s). None: 5 % of a revolution (``0.05·360/ω``).
    seed : int
        Seed (≥ 0) of ``numpy.random.SeedSequence``; the same seed gives the same capture.
    noise_seed : int or None
        Seed (≥ 0) of the timing jitter alone; None: drawn from ``seed`` like every other
        component. With ``seed`` fixed and ``noise_seed`` varied, the table, scale and heads stay
        the same and only the measurement noise changes — repeated measurements of one truth.

    Returns
    -------
    SimCapture
        ``kind="pulses"``; columns ``head_0`` … ``head_{n-1}``: strictly increasing float64 pulse
        times (s), of different lengths. ``truth`` (JSON-able) holds every setting and drawn
        value and:

        - ``first_line_head0`` (L0): the scale line head 0 sees at its first recorded pulse;
        - ``first_pulse_time_head0_s`` (T0): that pulse's jitter-free time (s);
        - ``deviation_arcsec``: m values, ``deviation[J] = e_{(L0+J) mod m}`` minus the mean, so
          the true rotation from head 0's first recorded pulse to its J-th is
          ``J·360/m + (deviation[J] − deviation[0])/3600`` deg (INTERFACE.md ``selfcal``);
        - ``deviation_detectable_arcsec``: the same without the Fourier orders q (0 ≤ q ≤ m/2)
          that are multiples of n (order 0 included), the best an n-head equal-division-averaged
          self-calibration can recover;
        - ``mean_rate_deg_s`` (ω, deg/s); ``mean_rate_whole_revs_deg_s``: ``360·R/(T_R − T0)``
          with R = ``whole_revolutions_head0`` the whole revolutions head 0 recorded and T_R the
          jitter-free time it sees line L0 again after them (None when R = 0);
        - ``rate_fluctuation_rms_percent`` (%, as set);
        - ``newton_iterations`` and ``newton_max_step_s``: the last Newton step (s), ≤ 1e-13 s
          unless the record is so long that float64 times cannot resolve that (then ≤ 16·ε·t);
        - ``timebase_relative_error_drawn``: δ, the clock's fractional error in this capture.

        Every time in the truth (``first_pulse_time_head0_s``, ``record_start_s`` …) and the
        argument of :func:`table_angle_deg` are true times; divide a column by ``1 + δ`` first.

    Raises
    ------
    ConfigError
        Any invalid setting, naming it and what to change.

    References
    ----------
    Kokuyama, Watanabe, Nozato and Ota, "Development of angular velocity calibration facility
    using self-calibratable rotary encoder" (seed ``004_d33da54b56781293.txt``): §3, the head
    outputs ``s_i(k) = k·Δθ + 360·i/n + a_i(k)`` with ``m = 360/Δθ`` and ``a_i(k) = a(k + m·i/n)``,
    the undetectable multiples of n; §5, angular velocity from the times of the pulse edges.
    T. Watanabe, H. Fujimoto and T. Masuda, "Self-calibratable rotary encoder", J. Phys.: Conf.
    Ser. 13, 240 (2005) (Kokuyama et al. 2015, ref. [1]).
    """
    n = _int("heads", heads, 2)
    m = _int("pulses_per_rev", pulses_per_rev, 2)
    if m < n:
        raise ConfigError(
            f"pulses_per_rev={m} is less than heads={n}; give at least one line per head."
        )
    rate = _finite("rate_deg_s", rate_deg_s)
    if rate <= 0:
        raise ConfigError(
            f"rate_deg_s must be > 0 deg/s, got {rate_deg_s!r}: the pulse twin turns forward only."
        )
    bias = _finite("rate_bias_percent", rate_bias_percent)
    omega = rate * (1.0 + bias / 100.0)
    if omega <= 0:
        raise ConfigError(
            f"rate_bias_percent={bias!r} makes the mean rate {omega:.6g} deg/s, not > 0; "
            "keep it above -100 %."
        )
    revs = _finite("revolutions", revolutions)
    if revs <= 0:
        raise ConfigError(f"revolutions must be > 0, got {revolutions!r}.")
    harm = _harmonics(harmonics, m)
    grad_sd = _nonneg("graduation_noise_arcsec", graduation_noise_arcsec)
    place_sd = _nonneg("head_placement_arcsec", head_placement_arcsec)
    fluct_pct = _nonneg("rate_fluctuation_percent", rate_fluctuation_percent)
    jitter = _nonneg("jitter_s", jitter_s)
    tb_offset = _finite("timebase_relative_error", timebase_relative_error)
    tb_half = _nonneg("timebase_error_half_width", timebase_error_half_width)
    if abs(tb_offset) + tb_half >= 0.5:
        raise ConfigError(
            f"timebase_relative_error={tb_offset!r} ± {tb_half!r} lets the clock err by 50 % or "
            "more; a timebase error is a small fraction (e.g. 2e-6)."
        )
    seed_i = _int("seed", seed, 0)
    noise_i = None if noise_seed is None else _int("noise_seed", noise_seed, 0)

    pitch = 360.0 / m  # deg
    rev_s = 360.0 / omega  # s per revolution
    duration = revs * rev_s
    pulse_hz = omega / pitch
    expected = n * revs * m
    if expected > MAX_TIMESTAMPS:
        raise ConfigError(
            f"heads={n} × pulses_per_rev={m} × revolutions={revs:.6g} gives about "
            f"{expected:.3g} timestamps, more than the {MAX_TIMESTAMPS:.0e} the twin makes at "
            "once; lower revolutions, heads or pulses_per_rev."
        )
    spread = 0.05 * rev_s if start_spread_s is None else _nonneg("start_spread_s", start_spread_s)
    if 2.0 * spread >= duration:
        raise ConfigError(
            f"start_spread_s={spread:.6g} s leaves no record: twice it must stay below the "
            f"record length {duration:.6g} s; lower start_spread_s or raise revolutions."
        )

    if fluctuation_hz is None:
        freqs = [] if fluct_pct == 0 else [omega / 360.0, *DEFAULT_FLUCTUATION_HZ]
    else:
        freqs = _frequencies(fluctuation_hz)
    if fluct_pct > 0 and not freqs:
        raise ConfigError(
            f"rate_fluctuation_percent={fluct_pct!r} needs at least one frequency in "
            "fluctuation_hz; give one or set rate_fluctuation_percent=0."
        )
    for k, f in enumerate(freqs):
        if f >= pulse_hz / 2:
            raise ConfigError(
                f"fluctuation_hz[{k}]={f:.6g} Hz is at or above half the pulse rate "
                f"({pulse_hz / 2:.6g} Hz at {omega:.6g} deg/s and {m} pulses/rev); give lower "
                "fluctuation_hz, set rate_fluctuation_percent=0, or turn faster."
            )
    n_f = len(freqs)
    a_each = fluct_pct / 100.0 * math.sqrt(2.0 / n_f) if n_f else 0.0
    if n_f * a_each >= 1.0:
        raise ConfigError(
            f"rate_fluctuation_percent={fluct_pct!r} over {n_f} frequencies lets the rate reach "
            f"zero (Σ a_k = {n_f * a_each:.3g} ≥ 1); lower it below "
            f"{100.0 / math.sqrt(2.0 * n_f):.4g} %."
        )

    # independent streams: switching one component off leaves the others' draws unchanged
    # (SeedSequence.spawn gives the same first six children whatever their number)
    (s_grad, s_place, s_psi, s_theta0, s_delay, s_jitter, s_clock) = (
        np.random.default_rng(s) for s in np.random.SeedSequence(seed_i).spawn(7)
    )
    if noise_i is not None:
        s_jitter = np.random.default_rng(np.random.SeedSequence([noise_i, 0x7A5E]))
    delta = tb_offset + (float(s_clock.uniform(-tb_half, tb_half)) if tb_half > 0 else 0.0)

    # ---- scale: line errors (arcsec) in scale numbering
    j = np.arange(m, dtype=np.float64)
    e = np.zeros(m)
    for h, amp, phase in harm:
        e += amp * np.cos((2.0 * math.pi * h / m) * j + phase)
    e += s_grad.normal(0.0, 1.0, m) * grad_sd
    e -= e.mean()
    spacing = pitch + np.diff(np.append(e, e[0])) / 3600.0  # line j to j+1 (wrapping), deg
    if float(spacing.min()) <= 0.5 * pitch:
        worst = int(np.argmin(spacing))
        raise ConfigError(
            f"the scale errors move line {(worst + 1) % m} to within {spacing[worst] * 3600:.4g} "
            f"arcsec of line {worst} (pitch {pitch * 3600:.4g} arcsec), so lines would swap; "
            "lower the harmonic amplitudes or graduation_noise_arcsec."
        )

    # ---- heads (deg, fixed in space)
    eps = np.concatenate(([0.0], s_place.normal(0.0, 1.0, n - 1) * place_sd))  # arcsec
    limit = MAX_PLACEMENT_PITCH * pitch * 3600.0
    far = np.flatnonzero(np.abs(eps) > limit)
    if far.size:
        i = int(far[0])
        raise ConfigError(
            f"head_placement_arcsec={place_sd:.6g} put head {i} {eps[i]:.4g} arcsec from its "
            f"nominal place, more than 0.4 pitch ({limit:.4g} arcsec); heads must sit within "
            "half a pitch of nominal, so lower head_placement_arcsec."
        )
    head_deg = np.arange(n) * (360.0 / n) + eps / 3600.0

    # ---- table motion
    w_hz = 2.0 * math.pi * np.asarray(freqs, dtype=np.float64)  # rad/s
    a_rel = np.full(n_f, a_each)
    psi = s_psi.uniform(0.0, 2.0 * math.pi, n_f)
    theta0 = float(s_theta0.uniform(0.0, 360.0))
    c_deg = a_rel * omega / w_hz if n_f else np.zeros(0)
    big_c = float(np.sum(np.abs(c_deg)))

    def theta_rel(t: FloatArray) -> FloatArray:  # θ(t) − θ0 (deg)
        return omega * t + _fluct_angle(t, w_hz, c_deg, psi)

    start = s_delay.uniform(0.0, spread, n)
    stop = duration - s_delay.uniform(0.0, spread, n)
    tol = max(1e-13, 16.0 * np.finfo(float).eps * duration)

    # ---- crossings, head by head (memory stays one head's worth)
    cols: dict[str, FloatArray] = {}
    first_g: list[int] = []
    counts: list[int] = []
    iterations = 0
    max_step = 0.0
    t_head0 = np.zeros(0)
    min_interval = math.inf
    for i in range(n):
        edges = theta_rel(np.array([start[i], stop[i]]))  # window in θ − θ0 (deg)
        g_lo = math.floor((edges[0] + theta0 + head_deg[i] - big_c) / pitch) - 2
        g_hi = math.ceil((edges[1] + theta0 + head_deg[i] + big_c) / pitch) + 2
        g = np.arange(g_lo, g_hi + 1, dtype=np.int64)
        line = np.mod(g, m)
        # target θ − θ0 of each crossing: P_j + 360·w − h_i − θ0 with g = w·m + j
        rhs = g * pitch + e[line] / 3600.0 - head_deg[i] - theta0
        keep = (rhs >= edges[0]) & (rhs <= edges[1])
        g, line, rhs = g[keep], line[keep], rhs[keep]
        if g.size < 2:
            raise ConfigError(
                f"head {i} records fewer than 2 pulses; raise revolutions or lower start_spread_s."
            )
        t, its, step = _solve_crossings(rhs, omega, w_hz, a_rel, psi, tol)
        iterations = max(iterations, its)
        max_step = max(max_step, step)
        min_interval = min(min_interval, float(np.min(np.diff(t))))
        if i == 0:
            t_head0 = t.copy()
        first_g.append(int(g[0]))
        counts.append(int(g.size))
        cols[f"head_{i}"] = t
    if jitter > _JITTER_FRACTION * min_interval:
        raise ConfigError(
            f"jitter_s={jitter:.3g} s is too large for the shortest pulse interval "
            f"{min_interval:.3g} s; keep it below {_JITTER_FRACTION * min_interval:.3g} s."
        )
    for i in range(n):
        name = f"head_{i}"
        t = cols[name]
        if jitter > 0:
            t = t + s_jitter.normal(0.0, jitter, t.size)
            if not bool(np.all(np.diff(t) > 0)):  # beyond 30 σ: practically never
                raise ConfigError(
                    f"jitter_s={jitter:.3g} s reordered pulses of {name}; lower jitter_s."
                )
        cols[name] = t * (1.0 + delta) if delta != 0.0 else t

    # ---- truth
    l0 = first_g[0] % m
    t0 = float(t_head0[0])
    dev = np.roll(e, -l0)
    dev = dev - dev.mean()
    spec = np.fft.rfft(dev)
    q = np.arange(spec.size)
    undetectable = q % n == 0
    spec[undetectable] = 0.0
    dev_det = np.fft.irfft(spec, m)
    whole = (t_head0.size - 1) // m
    rate_whole = 360.0 * whole / (float(t_head0[whole * m]) - t0) if whole else None
    truth: dict[str, Any] = {
        "kind": "pulses",
        "heads": n,
        "pulses_per_rev": m,
        "pitch_deg": pitch,
        "set_rate_deg_s": rate,
        "rate_bias_percent": bias,
        "revolutions": revs,
        "duration_s": duration,
        "harmonics": [[h, a, p] for h, a, p in harm],
        "graduation_noise_arcsec": grad_sd,
        "head_placement_arcsec": place_sd,
        "head_placement_arcsec_values": eps,
        "head_positions_deg": head_deg,
        "rate_fluctuation_percent": fluct_pct,
        "fluctuation_hz": list(freqs),
        "fluctuation_relative_amplitudes": a_rel,
        "fluctuation_phases_rad": psi,
        "theta0_deg": theta0,
        "jitter_s": jitter,
        "start_spread_s": spread,
        "record_start_s": start,
        "record_stop_s": stop,
        "seed": seed_i,
        "noise_seed": noise_i,
        "pulses_per_head": counts,
        "first_line_per_head": [gg % m for gg in first_g],
        "first_line_head0": l0,
        "first_pulse_time_head0_s": t0,
        "deviation_pp_arcsec": float(np.ptp(dev)),
        "deviation_detectable_pp_arcsec": float(np.ptp(dev_det)),
        "deviation_undetectable_rms_arcsec": float(np.sqrt(np.mean((dev - dev_det) ** 2))),
        "undetectable_orders_note": (
            f"Fourier orders that are multiples of heads={n} (and order 0) are removed in "
            "deviation_detectable_arcsec: an equal-division-averaged self-calibration cannot "
            "see them."
        ),
        "mean_rate_deg_s": omega,
        "whole_revolutions_head0": whole,
        "mean_rate_whole_revs_deg_s": rate_whole,
        "rate_fluctuation_rms_percent": fluct_pct,
        "newton_iterations": iterations,
        "newton_max_step_s": max_step,
        "timebase_relative_error": tb_offset,
        "timebase_error_half_width": tb_half,
        "timebase_relative_error_drawn": delta,
    }
    truth = to_jsonable(truth)
    # long arrays of finite floats: plain lists directly (to_jsonable walks them per element)
    truth["deviation_arcsec"] = dev.tolist()
    truth["deviation_detectable_arcsec"] = dev_det.tolist()
    return SimCapture("pulses", cols, truth)


# ---------------------------------------------------------------------- truth helpers
def _motion_from_truth(
    truth: Mapping[str, Any],
) -> tuple[float, FloatArray, FloatArray, FloatArray, float]:
    if not isinstance(truth, Mapping) or truth.get("kind") != "pulses":
        raise ConfigError("truth must be the truth dict of a 'pulses' capture (kind 'pulses').")
    try:
        omega = float(truth["mean_rate_deg_s"])
        w_hz = 2.0 * math.pi * np.asarray(truth["fluctuation_hz"], dtype=np.float64)
        a_rel = np.asarray(truth["fluctuation_relative_amplitudes"], dtype=np.float64)
        psi = np.asarray(truth["fluctuation_phases_rad"], dtype=np.float64)
        t0 = float(truth["first_pulse_time_head0_s"])
    except KeyError as exc:
        raise ConfigError(
            f"the pulses truth lacks {exc.args[0]!r}; pass the whole truth dict."
        ) from None
    if not (w_hz.shape == a_rel.shape == psi.shape and w_hz.ndim == 1):
        raise ConfigError(
            "the pulses truth's fluctuation lists differ in length; pass it unchanged."
        )
    return omega, w_hz, a_rel, psi, t0


def table_angle_deg(truth: Mapping[str, Any], t: ArrayLike) -> FloatArray:
    """True table angle ``θ(t) − θ(T0)`` (deg) at times ``t`` (s), from a pulses truth dict alone.

    T0 is the jitter-free time of head 0's first recorded pulse (``first_pulse_time_head0_s``),
    so the angle is 0 there and ``J·360/m + (deviation[J] − deviation[0])/3600`` at head 0's J-th
    pulse (J < m).

    Parameters
    ----------
    truth : mapping
        ``SimCapture.truth`` of :func:`simulate_pulses` (or its JSON read back).
    t : array_like
        Times (s), any shape.

    Returns
    -------
    numpy.ndarray
        Angle (deg), the shape of ``t``.

    References
    ----------
    Kokuyama et al. (seed ``004_d33da54b56781293.txt``) §5: the table angle the pulse times sample.
    """
    omega, w_hz, a_rel, psi, t0 = _motion_from_truth(truth)
    tt = np.asarray(t, dtype=np.float64)
    c_deg = a_rel * omega / w_hz if w_hz.size else np.zeros(0)
    out = omega * (tt - t0)
    for wk, ck, pk in zip(w_hz, c_deg, psi, strict=True):
        out = out + ck * (np.sin(wk * tt + pk) - math.sin(wk * t0 + pk))
    return np.asarray(out, dtype=np.float64)


def table_rate_deg_s(truth: Mapping[str, Any], t: ArrayLike) -> FloatArray:
    """True table rate ``dθ/dt = ω·(1 + Σ_k a_k·cos(2π·f_k·t + ψ_k))`` (deg/s) at times ``t`` (s).

    Parameters
    ----------
    truth : mapping
        ``SimCapture.truth`` of :func:`simulate_pulses` (or its JSON read back).
    t : array_like
        Times (s), any shape.

    Returns
    -------
    numpy.ndarray
        Rate (deg/s), the shape of ``t``.

    References
    ----------
    Kokuyama et al. (seed ``004_d33da54b56781293.txt``) §5: the angular velocity and its
    fluctuation the facility measures.
    """
    omega, w_hz, a_rel, psi, _ = _motion_from_truth(truth)
    tt = np.asarray(t, dtype=np.float64)
    out = np.ones_like(tt)
    for wk, ak, pk in zip(w_hz, a_rel, psi, strict=True):
        out = out + ak * np.cos(wk * tt + pk)
    return np.asarray(omega * out, dtype=np.float64)


register_kind("pulses", simulate_pulses)
