"""Twin of a gyro at rest: the IEEE Std 952 noise processes, with their true coefficients.

The rate record is the sum of white rate noise (angle random walk N), a rate random walk (K), a
bias instability B, angle quantization noise (Q), a rate ramp (R) and, optionally, quantization of
the output. The bias instability is either true flicker rate noise (``bias_model="flicker"``, the
default): its spectrum h/f with h = B²/π, aliased exactly as sampling an integrating gyro aliases
it, so that its Allan deviation is √(2 ln 2/π)·B at every τ (IEEE Std 952-1997, eq. C.21) up to
the record's longest periods; or (``"gauss-markov"``) a sum of first-order Gauss–Markov processes
whose corner frequencies are spread evenly in log frequency, flat only over the decades
``bias_band_s`` spans (σ_flat = 0.664·B at their geometric middle; it falls as √τ below the band
and as 1/√τ above it, where a five-term fit sees it as other terms). The truth holds N, K, B, Q, R
as set.
"""

from __future__ import annotations

import functools
import math
from typing import Any

import numpy as np
from scipy import signal as sps
from scipy.special import zeta

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


def _flicker(n: int, fs: float, b: float, rng: np.random.Generator) -> np.ndarray:
    """n rate samples of flicker rate noise of bias instability ``b`` (rate unit), by spectrum.

    The continuous rate has the one-sided spectrum h/f with h = B²/π, so that its Allan variance
    is 2 ln2·h = (2 ln 2/π)·B² (IEEE Std 952-1997, eq. C.21; NIST SP 1065, Table 5). The samples
    are the mean rate over each sampling interval (the angle differenced), whose spectrum is the
    aliased sum Σ_j h/|f + j·fs|·sinc²((f + j·fs)/fs); white Gaussian noise is shaped by its root
    in the frequency domain over twice the record (the first half kept, so that periods up to 2T
    are present), which leaves the Allan deviation at 0.664·B at every τ up to a fraction of T.
    """
    size = 2 * n
    white = np.fft.rfft(rng.standard_normal(size))
    white[0] = 0.0
    shape = _cached_shape(size, fs) if size <= _CACHE_SIZE else _flicker_shape(size, fs)
    white[1:] *= b * shape
    return np.fft.irfft(white, size)[:n]


#: Spectra of records up to this many samples (twice the record) are kept for the next seed.
_CACHE_SIZE = 1 << 21


def _flicker_shape(size: int, fs: float) -> np.ndarray:
    """√(fs·S(f)/2) of unit-B flicker at the rfft frequencies of ``size`` samples (DC left out),
    S the aliased spectrum of :func:`_flicker` (the same for every seed)."""
    f = np.fft.rfftfreq(size, 1.0 / fs)[1:]
    x = f / fs
    # Σ_{j≥1} 1/(j + x)³ + 1/(j − x)³ = −(ψ''(1 + x) + ψ''(1 − x))/2 = ζ(3, 1 + x) + ζ(3, 1 − x)
    # (Hurwitz zeta; ψ'' = −2ζ(3, ·), which is how SciPy's polygamma computes it, after a digamma
    # it discards: the same numbers in two thirds of the time), all aliases
    side = zeta(3, 1.0 + x) + zeta(3, 1.0 - x)
    s2 = np.sin(np.pi * x) ** 2
    spectrum = (np.sinc(x) ** 2 / f + s2 * side / (math.pi**2 * fs)) / math.pi
    shape = np.sqrt(fs * spectrum / 2.0)
    return shape


@functools.lru_cache(maxsize=4)
def _cached_shape(size: int, fs: float) -> np.ndarray:
    shape = _flicker_shape(size, fs)
    shape.flags.writeable = False
    return shape


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
    quantization_arcsec: float = 0.0,
    rate_ramp_deg_h2: float = 0.0,
    bias_model: str = "flicker",
) -> SimCapture:
    """A static gyro record ``time_s, rate_deg_s`` with known noise coefficients.

    Parameters
    ----------
    duration_s : float, s
    fs_hz : float, Hz
    arw_deg_rt_h : float, °/√h
        Angle random walk N: white rate noise of std N/60·√fs (°/s).
    bias_instability_deg_h : float, °/h
        B: the flat Allan deviation 0.664·B (at every τ for ``bias_model="flicker"``, between
        ``bias_band_s`` for ``"gauss-markov"``).
    rrw_deg_h_rt_h : float, °/h/√h
        Rate random walk K: σ(τ) = K·√(τ/3).
    bias_band_s : (float, float), s
        Shortest and longest correlation time of the Gauss–Markov processes (``"gauss-markov"``).
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
    quantization_arcsec : float, arcsec
        Angle quantization noise Q (IEEE Std 952, eq. C.5: σ² = 3Q²/τ²): white angle noise of
        std Q added to the integrated angle (a quantizer of step Δ gives Q = Δ/√12).
    rate_ramp_deg_h2 : float, °/h²
        Rate ramp R: the rate grows by R·t (σ = R·τ/√2, eq. C.29).
    bias_model : "flicker" or "gauss-markov"
        How the bias instability is made (see the module).

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
    q_angle = _nonneg("quantization_arcsec", quantization_arcsec) / 3600.0  # °
    ramp = float(rate_ramp_deg_h2) / 3600.0**2  # °/s²
    if not math.isfinite(ramp):
        raise ConfigError(f"rate_ramp_deg_h2 must be finite, got {rate_ramp_deg_h2!r}.")
    if bias_model not in ("flicker", "gauss-markov"):
        raise ConfigError(f"bias_model must be 'flicker' or 'gauss-markov', got {bias_model!r}.")
    rng = np.random.default_rng(seed)
    dt = 1.0 / fs
    rate = np.full(n, float(bias_deg_s))
    # white rate noise: N (°/√h) = 60·N (°/s·√s); sample std = N·√fs
    rate += (arw / 60.0) * math.sqrt(fs) * rng.standard_normal(n)
    # rate random walk: K (°/h/√h) → °/s/√s is K/216000. Each sample is the mean over its
    # interval of a Brownian rate W: W at the start, half the interval's increment, and the
    # bridge's mean (variance K²dt/12), so that σ²(τ) = K²τ/3 at every τ (a plain cumulative
    # sum would add K²·dt/(6τ), a white-rate part, at the shortest τ)
    if k > 0:
        kk = (k / 216000.0) * math.sqrt(dt)
        steps = kk * rng.standard_normal(n)
        start = np.concatenate(([0.0], np.cumsum(steps[:-1])))
        rate += start + 0.5 * steps + (kk / math.sqrt(12.0)) * rng.standard_normal(n)
    flat = 0.664 * b / 3600.0 if b > 0 else 0.0  # °/s
    if b > 0 and bias_model == "flicker":
        rate += _flicker(n, fs, b / 3600.0, rng)
    elif b > 0:
        decades = math.log10(t_hi / t_lo)
        taus_c = np.logspace(math.log10(t_lo), math.log10(t_hi), int(decades * _GM_PER_DECADE) + 1)
        mid = math.sqrt(t_lo * t_hi)
        q = flat / _gm_allan_plateau(taus_c, mid)
        for tc in taus_c:
            phi = math.exp(-dt / tc)
            drive = q * math.sqrt(1 - phi**2) * rng.standard_normal(n)
            drive[0] = q * rng.standard_normal()
            rate += sps.lfilter([1.0], [1.0, -phi], drive)
    if q_angle > 0:
        # white angle noise e: the rate of the angle θ + e is ω + (e_{i+1} − e_i)·fs
        rate += np.diff(q_angle * rng.standard_normal(n + 1)) * fs
    if ramp:
        rate += ramp * (np.arange(n) + 0.5) * dt
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
        "quantization_arcsec": q_angle * 3600.0,
        "rate_ramp_deg_h2": ramp * 3600.0**2,
        "bias_model": bias_model,
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
