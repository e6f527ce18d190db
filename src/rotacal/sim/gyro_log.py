"""Digital twin of a continuous rate-table log: the "gyro-log" capture.

The table holds each set rate for ``plateau_s`` seconds and ramps to the next at a constant
angular acceleration. Its rate column is the table's true rate plus white noise (a measured
rate; ``rate_noise_deg_s=0`` gives the exact profile). The DUT's static response is that of
:mod:`rotacal.sim.gyro_rates`,

    V(Ω) = V0 + S·Ω + Σ_p c_p·Ω^p,

driven by the true rate through a first-order lag (time constant τ) in series with an
underdamped second-order section (natural frequency f_n, damping ζ) of unit DC gain, so the
output lags and rings after each step; white Gaussian output noise is added. The dynamics are
discretised with the bilinear transform (``scipy.signal.bilinear``) and run by
``scipy.signal.lfilter`` from rest at the first rate.

The truth holds the plateaus (``start_s``/``end_s``: where the table reaches its set rate and
where it leaves it), the model's S and V0, and the least-squares line through the noise-free
static response at the distinct set rates (``numpy.polyfit``, sharing nothing with rotacal's
estimator) with its NL in %FS. ``settle_time_s`` is when the step response's envelope,
exp(−ζ·2πf_n·t) and exp(−t/τ), has decayed to 10⁻⁴ of the step.

This module imports only numpy, scipy, rotacal.errors and rotacal.sim (twin rule).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from rotacal.errors import ConfigError
from rotacal.sim.gyro_rates import _powers, set_rates, static_response
from rotacal.sim.motion import _finite
from rotacal.sim.sensors import SimCapture, register_kind

__all__ = ["DEFAULT_LOG_RATES_DEG_S", "simulate_gyro_log"]

#: Eleven plateaus from rest out to ±100 °/s, alternating in sign (as a test engineer runs them).
DEFAULT_LOG_RATES_DEG_S: tuple[float, ...] = (0.0, 20, -20, 40, -40, 60, -60, 80, -80, 100, -100)
_MAX_ROWS = 50_000_000


def _profile(
    rates: np.ndarray, plateau_s: float, accel: float, fs_hz: float
) -> tuple[np.ndarray, np.ndarray, list[dict[str, float]]]:
    """Time (s), the true table rate (°/s) and the plateaus' true spans."""
    ramps = np.r_[0.0, np.abs(np.diff(rates)) / accel]  # ramp before each plateau (s)
    starts = np.cumsum(ramps + np.r_[0.0, np.full(rates.size - 1, plateau_s)])
    ends = starts + plateau_s
    n = math.floor(ends[-1] * fs_hz) + 1
    if n > _MAX_ROWS:
        raise ConfigError(f"the log would have {n} rows, more than {_MAX_ROWS}; shorten it")
    t = np.arange(n) / fs_hz
    # the rate is piecewise linear through the corners (start, rate) and (end, rate)
    knots_t = np.column_stack([starts, ends]).reshape(-1)
    knots_r = np.repeat(rates, 2)
    omega = np.interp(t, knots_t, knots_r)
    spans = [
        {"start_s": float(a), "end_s": float(b), "rate_deg_s": float(r)}
        for a, b, r in zip(starts, ends, rates, strict=True)
    ]
    return t, omega, spans


def _dynamics(u: np.ndarray, fs_hz: float, lag_s: float, fn_hz: float, zeta: float) -> np.ndarray:
    """``u`` through 1/(τs + 1) · ωn²/(s² + 2ζωn·s + ωn²), bilinear, from rest at ``u[0]``."""
    from scipy import signal

    out = u - u[0]
    if fn_hz > 0:
        wn = 2.0 * math.pi * fn_hz
        b, a = signal.bilinear([wn * wn], [1.0, 2.0 * zeta * wn, wn * wn], fs=fs_hz)
        out = signal.lfilter(b, a, out)
    if lag_s > 0:
        b, a = signal.bilinear([1.0], [lag_s, 1.0], fs=fs_hz)
        out = signal.lfilter(b, a, out)
    return out + u[0]


def simulate_gyro_log(
    *,
    rates_deg_s: Sequence[float] = DEFAULT_LOG_RATES_DEG_S,
    plateau_s: float = 30.0,
    acceleration_deg_s2: float = 50.0,
    fs_hz: float = 100.0,
    scale_factor: float = 0.0125,
    bias: float = 2.5,
    nonlinearity: Sequence[float] | Mapping[int, float] | None = (4e-8, -1.5e-11),
    noise_std: float = 6.25e-4,
    rate_noise_deg_s: float = 0.02,
    lag_s: float = 0.05,
    natural_frequency_hz: float = 2.0,
    damping_ratio: float = 0.15,
    seed: int = 0,
) -> SimCapture:
    """A continuous rate-table log: plateaus, ramps, a noisy table rate, a lagging, ringing DUT.

    Parameters
    ----------
    rates_deg_s : sequence of float
        Set rates in the order run (°/s); at least 2 distinct.
    plateau_s : float
        Time the table holds each rate (s, > 0).
    acceleration_deg_s2 : float
        Angular acceleration of the ramps between plateaus (°/s², > 0).
    fs_hz : float
        Sample rate of the log (Hz, > 0).
    scale_factor, bias, nonlinearity
        S (output units per °/s, nonzero), V0 (output units) and the coefficients c_p of Ω^p
        (``(c2, c3, …)`` or ``{p: c_p}``), as in :func:`rotacal.sim.simulate_gyro_rates`.
    noise_std : float
        White output noise (output units rms, ≥ 0).
    rate_noise_deg_s : float
        White noise of the recorded table rate (°/s rms, ≥ 0).
    lag_s : float
        Time constant τ of the DUT's first-order lag (s, ≥ 0; 0: none).
    natural_frequency_hz, damping_ratio : float
        f_n (Hz, ≥ 0; 0: no ringing, below fs/4) and ζ (0 < ζ) of the ringing section.
    seed : int
        Seed of ``numpy.random.default_rng``.

    Returns
    -------
    SimCapture
        ``kind="gyro-log"``, columns ``time_s``, ``rate_deg_s`` (the recorded table rate) and
        ``output``; ``truth``: ``plateaus`` (each ``start_s``, ``end_s``, ``rate_deg_s``),
        ``scale_factor``, ``bias``, ``ls_scale_factor``, ``ls_bias``,
        ``nonlinearity_percent_fs`` (FS: the largest |set rate|), ``settle_time_s`` and every
        setting under ``sensor``.
    """
    rates = set_rates(rates_deg_s)
    plateau = _finite("plateau_s", plateau_s)
    accel = _finite("acceleration_deg_s2", acceleration_deg_s2)
    fs = _finite("fs_hz", fs_hz)
    s, v0 = _finite("scale_factor", scale_factor), _finite("bias", bias)
    sigma, rate_sigma = (
        _finite("noise_std", noise_std),
        _finite("rate_noise_deg_s", rate_noise_deg_s),
    )
    tau, fn = _finite("lag_s", lag_s), _finite("natural_frequency_hz", natural_frequency_hz)
    zeta = _finite("damping_ratio", damping_ratio)
    if min(plateau, accel, fs) <= 0 or s == 0:
        raise ConfigError("plateau_s, acceleration_deg_s2 and fs_hz must be > 0, scale_factor ≠ 0.")
    if min(sigma, rate_sigma, tau, fn) < 0 or zeta <= 0 or fn >= fs / 4:
        raise ConfigError(
            "noise_std, rate_noise_deg_s, lag_s, natural_frequency_hz must be ≥ 0, "
            "damping_ratio > 0 and natural_frequency_hz below fs_hz/4."
        )
    coeffs = _powers(nonlinearity)
    static = static_response(s, v0, coeffs)

    t, omega, spans = _profile(rates, plateau, accel, fs)
    rng = np.random.default_rng(seed)
    out = _dynamics(static(omega), fs, tau, fn, zeta) + rng.normal(0.0, sigma, t.size)
    recorded = omega + rng.normal(0.0, rate_sigma, t.size) if rate_sigma > 0 else omega
    uniq = np.unique(rates)
    ls_s, ls_v0 = np.polyfit(uniq, static(uniq), 1)
    ls_res = static(uniq) - (ls_s * uniq + ls_v0)
    full_scale = float(np.max(np.abs(uniq)))
    decay = max(tau, 1.0 / (zeta * 2.0 * math.pi * fn) if fn > 0 else 0.0)
    truth: dict[str, Any] = {
        "kind": "gyro-log",
        "plateaus": spans,
        "scale_factor": s,
        "bias": v0,
        "nonlinearity_coefficients": {str(p): c for p, c in sorted(coeffs.items())},
        "ls_scale_factor": float(ls_s),
        "ls_bias": float(ls_v0),
        "ls_residuals": ls_res,
        "rates_deg_s": uniq,
        "full_scale_deg_s": full_scale,
        "nonlinearity_percent_fs": 100.0 * float(np.max(np.abs(ls_res))) / (abs(ls_s) * full_scale),
        "settle_time_s": decay * math.log(1e4),
        "samples": int(t.size),
        "sensor": {
            "noise_std": sigma,
            "rate_noise_deg_s": rate_sigma,
            "lag_s": tau,
            "natural_frequency_hz": fn,
            "damping_ratio": zeta,
            "plateau_s": plateau,
            "acceleration_deg_s2": accel,
            "fs_hz": fs,
            "seed": int(seed),
            "run_order_deg_s": rates,
        },
    }
    return SimCapture("gyro-log", {"time_s": t, "rate_deg_s": recorded, "output": out}, truth)


register_kind("gyro-log", simulate_gyro_log)
