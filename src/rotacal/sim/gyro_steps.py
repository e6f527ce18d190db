"""Digital twin of a gyro's small-step test (threshold and resolution, IEEE Std 528 / 1431): "gyro-steps".

The table dwells on a sequence of set rates: at each base rate Ω₀ of ``base_rates_deg_s`` it
runs, for each increment δ (in increasing order), Ω₀ → Ω₀ + δ → Ω₀ → Ω₀ − δ → Ω₀. The gyro senses
the rate through two imperfections with a known effect:

* **stick–slip of size r** (``resolution_deg_s``): the sensed rate keeps its last value until the
  input differs from it by r or more, then takes the input's value;
* **dead zone of half-width d** (``dead_zone_deg_s``): a sensed rate below d in magnitude gives
  the output at rest.

Its output is V0 + S·(sensed rate, or 0 in the dead zone) plus white Gaussian noise. So a step of
input change δ between non-zero rates (|Ω| ≥ d) moves the output fully when δ ≥ r and not at all
when δ < r: the resolution (IEEE Std 528, the smallest change producing ≥ 50 % of the expected
output) is r. From rest, an input Ω moves it fully when |Ω| ≥ max(r, d), so the threshold is
max(r, d). These closed forms are the truth; the twin does not apply the 50 % rule.

This module imports only numpy, rotacal.errors and rotacal.sim (twin rule).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from rotacal.errors import ConfigError
from rotacal.sim.motion import _finite
from rotacal.sim.sensors import SimCapture, register_kind

__all__ = ["DEFAULT_INCREMENTS_DEG_S", "simulate_gyro_steps"]

#: Increments of the default test (°/s), from below to above the default r and d.
DEFAULT_INCREMENTS_DEG_S: tuple[float, ...] = (0.001, 0.002, 0.003, 0.005, 0.008, 0.012, 0.02)


def _rates(bases: np.ndarray, increments: np.ndarray) -> np.ndarray:
    """The dwells' set rates, in the order they are run."""
    seq: list[float] = []
    for b in bases:
        seq.append(float(b))
        for d in increments:
            seq += [b + d, b, b - d, b]
    return np.asarray(seq)


def _sensed(rates: np.ndarray, r: float, d: float) -> np.ndarray:
    """The rate the gyro senses at each dwell (a loop over dwells, not samples: a few hundred)."""
    out = np.empty_like(rates)
    last = rates[0]
    for i, w in enumerate(rates):
        if abs(w - last) >= r:
            last = w
        out[i] = last if abs(last) >= d else 0.0
    return out


def simulate_gyro_steps(
    *,
    base_rates_deg_s: Sequence[float] = (0.0, 10.0, -10.0),
    increments_deg_s: Sequence[float] = DEFAULT_INCREMENTS_DEG_S,
    resolution_deg_s: float = 0.0042,
    dead_zone_deg_s: float = 0.007,
    scale_factor: float = 0.0125,
    bias: float = 2.5,
    noise_std: float = 2.5e-5,
    samples_per_dwell: int = 2000,
    seed: int = 0,
) -> SimCapture:
    """A small-step test of a gyro with known threshold and resolution.

    Parameters
    ----------
    base_rates_deg_s : sequence of float
        Rates (°/s) around which the increments are stepped; 0 tests the threshold.
    increments_deg_s : sequence of float
        Increments δ (°/s, > 0).
    resolution_deg_s : float
        r, the stick–slip size (°/s, ≥ 0).
    dead_zone_deg_s : float
        d, the dead zone's half-width (°/s, ≥ 0).
    scale_factor : float
        S (output units per °/s, nonzero).
    bias : float
        V0 (output units).
    noise_std : float
        White output noise per sample (output units rms, ≥ 0); the default is 0.002 °/s.
    samples_per_dwell : int
        Samples at each dwell (≥ 2).
    seed : int
        Seed of ``numpy.random.default_rng``.

    Returns
    -------
    SimCapture
        ``kind="gyro-steps"``, columns ``rate_deg_s`` and ``output``; truth ``threshold_deg_s`` =
        max(r, d), ``resolution_deg_s`` = r, the sensed rate of each dwell and every setting.
    """
    bases = np.asarray(base_rates_deg_s, dtype=float).reshape(-1)
    inc = np.sort(np.asarray(increments_deg_s, dtype=float).reshape(-1))
    if bases.size == 0 or inc.size == 0 or not np.all(np.isfinite(np.r_[bases, inc])):
        raise ConfigError("base_rates_deg_s and increments_deg_s must be non-empty finite numbers.")
    if np.any(inc <= 0):
        raise ConfigError("increments_deg_s must be > 0 °/s.")
    r = _finite("resolution_deg_s", resolution_deg_s)
    d = _finite("dead_zone_deg_s", dead_zone_deg_s)
    s = _finite("scale_factor", scale_factor)
    v0 = _finite("bias", bias)
    sigma = _finite("noise_std", noise_std)
    if r < 0 or d < 0 or sigma < 0 or s == 0:
        raise ConfigError(
            "resolution_deg_s, dead_zone_deg_s and noise_std must be ≥ 0 and scale_factor nonzero."
        )
    if isinstance(samples_per_dwell, bool) or int(samples_per_dwell) != samples_per_dwell:
        raise ConfigError(f"samples_per_dwell must be an integer ≥ 2, got {samples_per_dwell!r}.")
    n = int(samples_per_dwell)
    if n < 2:
        raise ConfigError(f"samples_per_dwell must be ≥ 2, got {samples_per_dwell!r}.")
    rates = _rates(bases, inc)
    sensed = _sensed(rates, r, d)
    out = np.repeat(v0 + s * sensed, n)
    if sigma > 0:
        out = out + np.random.default_rng(seed).normal(0.0, sigma, out.size)
    truth: dict[str, Any] = {
        "kind": "gyro-steps",
        "threshold_deg_s": max(r, d),
        "resolution_deg_s": r,
        "scale_factor": s,
        "bias": v0,
        "dwell_rates_deg_s": rates,
        "sensed_rates_deg_s": sensed,
        "sensor": {
            "stick_slip_deg_s": r,
            "dead_zone_deg_s": d,
            "noise_std": sigma,
            "samples_per_dwell": n,
            "seed": int(seed),
        },
        "samples": int(out.size),
    }
    return SimCapture("gyro-steps", {"rate_deg_s": np.repeat(rates, n), "output": out}, truth)


register_kind("gyro-steps", simulate_gyro_steps)
