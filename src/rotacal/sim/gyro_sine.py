"""The twin of a gyro's dynamic test: a second-order DUT on a sinusoidal table read by an encoder.

The table turns ``θ(t) = A·[sin u + Σ_h r_h·sin(h·u + ψ_h)]``, ``u = 2πf·t + phase`` (a
:class:`~rotacal.sim.motion.SineMotion` without stagnation, play or creep), read by the shaft
encoder of :func:`~rotacal.sim.sensors.simulate_encoder` (or given as an angle column). The DUT is
the unit-gain second-order low-pass ``H(s) = ωn²/(s² + 2ζωn·s + ωn²)`` times ``exp(−s·τ)``, in
its settled (steady) state: each line h·f of the table's rate comes out multiplied by |H(j·2πhf)|
and shifted by arg H(j·2πhf), plus white noise. The truth holds H at the fundamental, fn, ζ, τ
and the −3 dB bandwidth found by root search on |H|² = ½ (not from a closed form).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np
from scipy.optimize import brentq

from rotacal.errors import ConfigError
from rotacal.sim.motion import SineMotion, _finite, _nonneg
from rotacal.sim.sensors import SimCapture, _truth, simulate_encoder

__all__ = ["dut_response", "simulate_gyro_sine"]

_TWO_PI = 2.0 * math.pi


def dut_response(
    frequency_hz: Any, natural_frequency_hz: float, damping_ratio: float, delay_s: float = 0.0
) -> np.ndarray:
    """The twin DUT's H(j·2πf) (-), complex: ``1/(1 − (f/fn)² + 2jζ·f/fn)·exp(−j·2πf·τ)``."""
    f = np.asarray(frequency_hz, dtype=np.float64)
    x = f / natural_frequency_hz
    return np.exp(-1j * _TWO_PI * f * delay_s) / (1.0 - x * x + 2j * damping_ratio * x)


def _bandwidth_by_search(fn: float, zeta: float) -> float:
    """The frequency (Hz) above which |H| stays below 1/√2, by bracketing and ``brentq``."""

    def excess(f: float) -> float:
        return float(abs(dut_response(f, fn, zeta)) ** 2) - 0.5

    hi = fn
    while excess(hi) > 0:
        hi *= 2.0
    return float(brentq(excess, hi / 2.0 if hi > fn else 1e-9 * fn, hi, xtol=1e-15 * fn))


def simulate_gyro_sine(
    frequency_hz: float = 2.0,
    *,
    rate_amplitude_deg_s: float = 30.0,
    natural_frequency_hz: float = 8.0,
    damping_ratio: float = 0.5,
    delay_s: float = 0.0,
    noise_deg_s: float = 0.05,
    reference: str = "encoder",
    lines: int = 3600,
    encoder_noise_rms: float = 0.01,
    angle_noise_deg: float = 0.0,
    fs_hz: float = 5000.0,
    periods: float = 8.0,
    phase_rad: float = 0.3,
    harmonics: Mapping[int, tuple[float, float]] | None = None,
    seed: int = 0,
) -> SimCapture:
    """One capture of a gyro's dynamic test at one frequency (module docstring).

    Parameters
    ----------
    frequency_hz : float — table frequency f (Hz).
    rate_amplitude_deg_s : float — amplitude of the table's fundamental rate (deg/s); the angle
        amplitude is that over 2πf.
    natural_frequency_hz, damping_ratio, delay_s : the DUT's fn (Hz), ζ (-) and delay τ (s).
    noise_deg_s : float — white noise of the DUT's rate (deg/s rms per sample).
    reference : {'encoder', 'angle'} — columns ``a``, ``b`` of an encoder of ``lines`` lines with
        ``encoder_noise_rms`` (signal units), or ``angle_deg`` with ``angle_noise_deg`` (deg).
    fs_hz : float — sampling rate of every column (Hz).
    periods : float — capture length in motion periods.
    phase_rad : float — phase of the fundamental at t = 0 (rad).
    harmonics : mapping, optional — the table's distortion ``h → (r_h, ψ_h)`` as in SineMotion.
    seed : int — seed of the noise.

    Returns
    -------
    SimCapture
        Kind ``"gyro-sine"``; columns ``time_s``, the reference, ``rate_deg_s``; truth with
        ``amplitude_ratio``, ``phase_deg``, ``natural_frequency_hz``, ``damping_ratio``,
        ``delay_s``, ``bandwidth_hz``.
    """
    f = _finite("frequency_hz", frequency_hz)
    rate_amp = _finite("rate_amplitude_deg_s", rate_amplitude_deg_s)
    fn = _finite("natural_frequency_hz", natural_frequency_hz)
    zeta = _finite("damping_ratio", damping_ratio)
    tau = _finite("delay_s", delay_s)
    if f <= 0 or rate_amp <= 0 or fn <= 0 or zeta <= 0:
        raise ConfigError(
            "frequency_hz, rate_amplitude_deg_s, natural_frequency_hz and damping_ratio must be > 0"
        )
    if reference not in ("encoder", "angle"):
        raise ConfigError(f"reference must be 'encoder' or 'angle', got {reference!r}")
    n_periods = _finite("periods", periods)
    if n_periods < 1:
        raise ConfigError(f"periods must be ≥ 1, got {periods!r}")
    motion = SineMotion(
        amplitude_deg=rate_amp / (_TWO_PI * f),
        frequency_hz=f,
        harmonics=dict(harmonics or {}),
        phase_rad=phase_rad,
    )
    duration = n_periods / f
    if reference == "encoder":
        enc = simulate_encoder(
            motion,
            lines=lines,
            fs_hz=fs_hz,
            duration_s=duration,
            noise_rms=encoder_noise_rms,
            seed=seed + 1,
        )
        columns = dict(enc.columns)
        t = columns["time_s"]
        sensor = dict(enc.truth["sensor"])
    else:
        t = np.arange(round(duration * fs_hz)) / fs_hz
        noise = _nonneg("angle_noise_deg", angle_noise_deg)
        rng_a = np.random.default_rng(seed + 1)
        columns = {"time_s": t, "angle_deg": motion.angle_deg(t) + rng_a.normal(0, noise, t.size)}
        sensor = {"fs_hz": fs_hz, "angle_noise_deg": noise, "duration_s": duration}
    # every line of the table's rate through H, in steady state
    u = _TWO_PI * f * t + motion.phase_rad
    lines_h = [(1, 1.0, 0.0)] + [(h, r, psi) for h, (r, psi) in motion.harmonics.items()]
    rate = np.zeros(t.size)
    for h, r, psi in lines_h:
        resp = complex(dut_response(h * f, fn, zeta, tau))
        rate += (
            abs(resp) * r * h * rate_amp * np.cos(h * u + psi + math.atan2(resp.imag, resp.real))
        )
    noise_dut = _nonneg("noise_deg_s", noise_deg_s)
    rate += np.random.default_rng(seed).normal(0.0, noise_dut, t.size)
    columns["rate_deg_s"] = rate
    h1 = complex(dut_response(f, fn, zeta, tau))
    # the phase of H continuous from 0 at f = 0: the low-pass part lies in (−180°, 0]
    low = complex(dut_response(f, fn, zeta))
    phase_deg = math.degrees(math.atan2(low.imag, low.real)) - 360.0 * f * tau
    sensor.update(
        natural_frequency_hz=fn,
        damping_ratio=zeta,
        delay_s=tau,
        noise_deg_s=noise_dut,
        reference=reference,
        rate_amplitude_deg_s=rate_amp,
        seed=int(seed),
    )
    truth = _truth(motion, "gyro-sine", t, sensor, 10)
    truth.update(
        amplitude_ratio=abs(h1),
        amplitude_ratio_db=20.0 * math.log10(abs(h1)),
        phase_deg=phase_deg,
        natural_frequency_hz=fn,
        damping_ratio=zeta,
        delay_s=tau,
        bandwidth_hz=_bandwidth_by_search(fn, zeta),
    )
    return SimCapture("gyro-sine", columns, truth)
