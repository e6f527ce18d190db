"""Twin of a gyro at rest: the IEEE Std 952 noise processes, with their true coefficients.

The rate record is the sum of white rate noise (angle random walk N), a rate random walk (K), a
bias-instability process made of first-order Gauss–Markov processes whose corner frequencies are
spread evenly in log frequency (their sum has a flat Allan deviation over the decades they span,
the usual stand-in for flicker noise) and, optionally, quantization of the output. The truth holds
N, K and B as set; B is the plateau level σ_flat/0.664 that the Gauss–Markov sum is scaled to.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from scipy import signal as sps

from rotacal.errors import ConfigError
from rotacal.sim.motion import _nonneg
from rotacal.sim.sensors import SimCapture, register_kind

__all__ = ["simulate_gyro_noise"]

#: Flat-plateau Allan deviation of a sum of Gauss–Markov processes, one per 1/3 decade of
#: correlation time, each of variance q²: σ_flat ≈ _GM_PLATEAU·q (closed form of the sum's
#: Allan variance, evaluated once numerically at mid-band; see the test of this twin).
_GM_PER_DECADE = 3
_MAX_SAMPLES = 50_000_000


def _gm_allan_plateau(taus_c: np.ndarray, tau: float) -> float:
    """Allan deviation at τ of a sum of unit-variance Gauss–Markov processes (closed form).

    For one process of correlation time T and variance q²: σ²(τ) = (q²T²/τ²)·(4e^{−τ/T} −
    e^{−2τ/T} + 2τ/T − 3) (IEEE Std 952, Annex C, the exponentially correlated process).
    """
    x = tau / taus_c
    total = np.sum(taus_c**2 / tau**2 * (4 * np.exp(-x) - np.exp(-2 * x) + 2 * x - 3))
    return math.sqrt(total)


def simulate_gyro_noise(
    *,
    duration_s: float = 3600.0,
    fs_hz: float = 100.0,
    arw_deg_rt_h: float = 0.3,
    bias_instability_deg_h: float = 3.0,
    rrw_deg_h_rt_h: float = 0.0,
    bias_band_s: tuple[float, float] = (1.0, 1000.0),
    bias_deg_s: float = 0.0,
    quantum_deg_s: float | None = None,
    timebase_relative_error: float = 0.0,
    seed: int = 0,
    range_deg_s: float | None = None,
) -> SimCapture:
    """A static gyro record ``time_s, rate_deg_s`` with known noise coefficients.

    Parameters
    ----------
    duration_s : float, s
    fs_hz : float, Hz
    arw_deg_rt_h : float, °/√h
        Angle random walk N: white rate noise of std N/60·√fs (°/s).
    bias_instability_deg_h : float, °/h
        B: the flat Allan deviation is 0.664·B between ``bias_band_s`` (correlation times).
    rrw_deg_h_rt_h : float, °/h/√h
        Rate random walk K: σ(τ) = K·√(τ/3).
    bias_band_s : (float, float), s
        Shortest and longest correlation time of the bias-instability processes.
    bias_deg_s : float, °/s
        Constant bias (does not change the Allan deviation).
    quantum_deg_s : float, °/s, optional
        Quantise the output to this step.
    range_deg_s : float, °/s, optional
        Measuring range: an output beyond ±range_deg_s is reported as ±range_deg_s (a saturated
        gyro; the truth then holds ``range_deg_s`` and ``clipped_samples``).
    timebase_relative_error : float
        Fractional error e of the DAQ clock that stamps ``time_s``: every recorded time is
        (1 + e) times the true one (a +1e-6 clock makes every time 1 ppm long). The noise
        coefficients of the truth are those of true time. Default 0.
    seed : int

    Returns
    -------
    SimCapture
        ``kind="gyro-noise"``; truth: the coefficients as set, and ``flat_adev_deg_s``.

    References
    ----------
    IEEE Std 952-1997, Annex C (noise terms; the exponentially correlated process).
    """
    fs = _nonneg("fs_hz", fs_hz)
    dur = _nonneg("duration_s", duration_s)
    n = round(dur * fs)
    if fs <= 0 or n < 100:
        raise ConfigError(f"duration_s·fs_hz gives {n} samples; give at least 100.")
    if n > _MAX_SAMPLES:
        raise ConfigError(f"{n} samples is more than the twin's {_MAX_SAMPLES}; shorten it.")
    arw = _nonneg("arw_deg_rt_h", arw_deg_rt_h)
    b = _nonneg("bias_instability_deg_h", bias_instability_deg_h)
    k = _nonneg("rrw_deg_h_rt_h", rrw_deg_h_rt_h)
    t_lo, t_hi = (float(x) for x in bias_band_s)
    if not 0 < t_lo < t_hi or t_lo < 2.0 / fs:
        raise ConfigError(
            "bias_band_s must be (shortest, longest) correlation times, 2/fs ≤ shortest < longest."
        )
    try:
        clock = float(timebase_relative_error)
    except (TypeError, ValueError):
        raise ConfigError(
            f"timebase_relative_error must be a number, got {timebase_relative_error!r}."
        ) from None
    if not math.isfinite(clock) or clock <= -1.0:
        raise ConfigError(
            f"timebase_relative_error must be finite and > −1, got {timebase_relative_error!r}."
        )
    rng = np.random.default_rng(seed)
    dt = 1.0 / fs
    rate = np.full(n, float(bias_deg_s))
    # white rate noise: N (°/√h) = 60·N (°/s·√s); sample std = N·√fs
    rate += (arw / 60.0) * math.sqrt(fs) * rng.standard_normal(n)
    # rate random walk: K (°/h/√h) → °/s/√s is K/216000; increments of std K·√dt
    if k > 0:
        rate += np.cumsum((k / 216000.0) * math.sqrt(dt) * rng.standard_normal(n))
    flat = 0.0
    if b > 0:
        decades = math.log10(t_hi / t_lo)
        taus_c = np.logspace(math.log10(t_lo), math.log10(t_hi), int(decades * _GM_PER_DECADE) + 1)
        mid = math.sqrt(t_lo * t_hi)
        flat = 0.664 * b / 3600.0  # °/s
        q = flat / _gm_allan_plateau(taus_c, mid)
        for tc in taus_c:
            phi = math.exp(-dt / tc)
            drive = q * math.sqrt(1 - phi**2) * rng.standard_normal(n)
            drive[0] = q * rng.standard_normal()
            rate += sps.lfilter([1.0], [1.0, -phi], drive)
    if quantum_deg_s is not None:
        step = _nonneg("quantum_deg_s", quantum_deg_s)
        if step > 0:
            rate = np.round(rate / step) * step
    clipped: dict[str, Any] = {}
    if range_deg_s is not None:
        lim = _nonneg("range_deg_s", range_deg_s)
        if lim <= 0:
            raise ConfigError(f"range_deg_s must be > 0 °/s, got {range_deg_s!r}.")
        clipped = {"range_deg_s": lim, "clipped_samples": int(np.count_nonzero(abs(rate) > lim))}
        rate = np.clip(rate, -lim, lim)
    truth: dict[str, Any] = {
        "kind": "gyro-noise",
        "arw_deg_rt_h": arw,
        "bias_instability_deg_h": b,
        "rrw_deg_h_rt_h": k,
        "flat_adev_deg_s": flat,
        "bias_band_s": [t_lo, t_hi],
        "bias_deg_s": float(bias_deg_s),
        "quantum_deg_s": quantum_deg_s,
        "timebase_relative_error": clock,
        "fs_hz": fs,
        "samples": n,
        "seed": seed,
        **clipped,
    }
    return SimCapture(
        kind="gyro-noise",
        columns={"time_s": np.arange(n) * (dt * (1.0 + clock)), "rate_deg_s": rate},
        truth=truth,
    )


register_kind("gyro-noise", simulate_gyro_noise)
