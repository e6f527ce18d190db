"""Digital twin of angle and counter readings: a table's angle logged by a readout or a counter card.

The table moves sinusoidally (:class:`~rotacal.sim.SineMotion`, for ``motion angle``) or turns at a
constant rate with a sinusoidal rate fluctuation (for ``rate``):
``θ(t) = ω·t + (a·ω/(2π·f_w))·sin(2π·f_w·t)``, so that ``dθ/dt = ω·(1 + a·cos(2π·f_w·t))``.
White noise of ``noise_deg`` rms is added to θ (the table's jitter; it dithers the readout).

The reading is either

- ``angle_deg``: θ rounded to the readout's quantum ``resolution_deg`` (0: not rounded), or
- ``count``: an up/down counter, ``floor(θ·N/360) + start_count`` held in a register of
  ``counter_bits`` bits, signed (two's complement) or not, so that it wraps around.

DAQ faults: ``drop_rows`` single samples are left out and ``repeat_rows`` rows written twice, at
random places; the truth lists where (``sensor.dropped_samples`` as true sample numbers,
``sensor.repeated_rows`` as row numbers of the written record).

References
----------
Feng et al. 2023, Sensors 23:4876 (sinusoidal motion); Kokuyama et al. (seed 004) §5 (constant
rate with fluctuation); two's complement: IEEE Std 1754-1994 §2.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from rotacal.errors import ConfigError
from rotacal.sim.motion import SineMotion
from rotacal.sim.sensors import SimCapture, _finite, _nonneg, _time_axis, _truth, register_kind

__all__ = ["constant_rate_angle_deg", "constant_rate_deg_s", "simulate_angle"]

_BITS = (8, 16, 24, 32, 64)


def constant_rate_angle_deg(
    t: Any, rate_deg_s: float, fluctuation: float, fluctuation_hz: float
) -> np.ndarray:
    """θ(t) (deg) of the constant-rate motion (module docstring), θ(0) = 0."""
    tt = np.asarray(t, dtype=np.float64)
    out = rate_deg_s * tt
    if fluctuation and fluctuation_hz:
        w = 2 * math.pi * fluctuation_hz
        out = out + fluctuation * rate_deg_s / w * np.sin(w * tt)
    return np.asarray(out)


def constant_rate_deg_s(
    t: Any, rate_deg_s: float, fluctuation: float, fluctuation_hz: float
) -> np.ndarray:
    """dθ/dt (deg/s) of the constant-rate motion."""
    tt = np.asarray(t, dtype=np.float64)
    return np.asarray(rate_deg_s * (1.0 + fluctuation * np.cos(2 * math.pi * fluctuation_hz * tt)))


def _register(true: np.ndarray, bits: int, signed: bool) -> np.ndarray:
    """The register's readings of the true counts (wrapped)."""
    if bits == 64:
        return true
    m = np.int64(1) << np.int64(bits)
    if signed:
        half = m >> np.int64(1)
        return ((true + half) % m) - half
    return true % m


def simulate_angle(
    motion: SineMotion | None = None,
    *,
    rate_deg_s: float | None = None,
    fluctuation: float = 0.0,
    fluctuation_hz: float = 1.0,
    reading: str = "count",
    counts_per_rev: int = 144_000,
    counter_bits: int = 16,
    signed: bool = False,
    start_count: int | None = None,
    resolution_deg: float = 0.0,
    noise_deg: float = 0.0,
    fs_hz: float = 2_000.0,
    duration_s: float | None = None,
    drop_rows: int = 0,
    repeat_rows: int = 0,
    seed: int = 0,
    harmonics: int = 10,
) -> SimCapture:
    """A table's angle as an angle readout or an up/down counter logs it (module docstring).

    Parameters
    ----------
    motion : SineMotion, optional — sinusoidal motion; None with ``rate_deg_s``: constant rate.
    rate_deg_s : float, optional — constant rate ω (deg/s), instead of ``motion``.
    fluctuation : float — relative rate fluctuation a (-), e.g. 1e-4.
    fluctuation_hz : float — its frequency f_w (Hz).
    reading : ``"count"`` or ``"angle"`` — the column written.
    counts_per_rev : int — N, counts per revolution.
    counter_bits : int — register width (8, 16, 24, 32, 64).
    signed : bool — two's complement register.
    start_count : int, optional — the count at θ = 0; default: 40 counts below the end of the
        register's positive range, so that the record wraps.
    resolution_deg : float, deg — quantum of an angle readout (0: unrounded).
    noise_deg : float, deg — white noise on θ (rms).
    fs_hz : float, Hz; duration_s : float, s (default: 6⅛ periods, or 10 s at constant rate).
    drop_rows, repeat_rows : int — samples lost and rows written twice.
    seed : int — random seed.
    harmonics : int — N_H of the truth's THD.

    Returns
    -------
    SimCapture — ``time_s`` and ``count`` or ``angle_deg``; truth: the motion's (sinusoidal) or
    ``rate_deg_s``, ``fluctuation``, ``fluctuation_hz`` (constant rate), and ``sensor``.
    """
    if (motion is None) == (rate_deg_s is None):
        raise ConfigError("give either a sinusoidal motion or rate_deg_s (constant rate)")
    if reading not in ("count", "angle"):
        raise ConfigError(f"reading must be 'count' or 'angle', got {reading!r}")
    if counter_bits not in _BITS:
        raise ConfigError(f"counter_bits must be one of {_BITS}, got {counter_bits}")
    cpr = int(counts_per_rev)
    if cpr < 1:
        raise ConfigError(f"counts_per_rev must be ≥ 1, got {counts_per_rev}")
    noise = _nonneg("noise_deg", noise_deg)
    q = _nonneg("resolution_deg", resolution_deg)
    rng = np.random.default_rng(seed)
    if motion is not None:
        t, fs, dur, _ = _time_axis(motion, fs_hz, duration_s, 0.0)
        theta = motion.angle_deg(t)
    else:
        w = _finite("rate_deg_s", rate_deg_s)
        fs = _finite("fs_hz", fs_hz)
        dur = 10.0 if duration_s is None else _finite("duration_s", duration_s)
        if not (fs > 0 and dur > 0 and w != 0):
            raise ConfigError("fs_hz, duration_s and rate_deg_s must be non-zero (fs, T > 0)")
        t = np.arange(round(dur * fs)) / fs
        theta = constant_rate_angle_deg(t, w, fluctuation, fluctuation_hz)
    if noise > 0:
        theta = theta + rng.normal(0.0, noise, t.size)
    sensor: dict[str, Any] = {"reading": reading, "fs_hz": fs, "duration_s": dur, "seed": seed}
    sensor["noise_deg"] = noise
    if reading == "count":
        if start_count is None:
            start_count = (1 << (counter_bits - (1 if signed else 0))) - 40
        true = np.floor(theta * (cpr / 360.0)).astype(np.int64) + np.int64(start_count)
        values: np.ndarray = _register(true, counter_bits, signed)
        sensor.update(
            counts_per_rev=cpr, counter_bits=counter_bits, signed=signed, start_count=start_count
        )
        sensor["wraps"] = int(np.count_nonzero(np.diff(values) != np.diff(true)))
        name = "count"
    else:
        values = np.round(theta / q) * q if q > 0 else theta
        sensor["resolution_deg"] = q
        name = "angle_deg"
    keep = np.ones(t.size, dtype=bool)
    if drop_rows:
        dropped = np.sort(rng.choice(np.arange(1, t.size - 1), int(drop_rows), replace=False))
        keep[dropped] = False
        sensor["dropped_samples"] = dropped.tolist()
    tt, vv = t[keep], values[keep]
    if repeat_rows:
        rows = np.sort(rng.choice(np.arange(1, tt.size), int(repeat_rows), replace=False))
        tt = np.insert(tt, rows, tt[rows - 1])
        vv = np.insert(vv, rows, vv[rows - 1])
        sensor["repeated_rows"] = (rows + np.arange(rows.size)).tolist()
    if motion is not None:
        truth = _truth(motion, "angle", t, sensor, harmonics)
    else:
        truth = {
            "kind": "angle",
            "samples": int(t.size),
            "rate_deg_s": float(rate_deg_s),  # type: ignore[arg-type]
            "fluctuation": float(fluctuation),
            "fluctuation_hz": float(fluctuation_hz),
            "sensor": sensor,
        }
    return SimCapture("angle", {"time_s": tt, name: vv}, truth)


register_kind("angle", simulate_angle)
