"""Digital twin of a single-axis gyro rate-table test (Kokuyama et al. 2015, §4): the "gyro-rates" capture.

The table holds each set rate Ω while the DUT's output is sampled. The DUT's analog response is

    V(Ω) = V0 + S·Ω + Σ_p c_p·Ω^p        (p ≥ 2: the nonlinearity, output units)

plus white Gaussian noise, then optionally quantised (mid-tread, ``q·round(v/q)``) and clipped at
the output rails. The truth reports the model's S and V0 and, because a nonlinear response has no
unique "scale factor", also the least-squares straight line of the noise-free analog response over
the set rates (each rate one point, equal weights: the line a perfect test would find) with its
residuals and nonlinearity in %FS (FS = the largest |set rate|). That line is computed here with
``numpy.polyfit``, which shares nothing with rotacal's estimator.

This module imports only numpy, rotacal.errors and rotacal.sim.sensors.SimCapture (twin rule).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from rotacal.errors import ConfigError
from rotacal.sim.motion import _finite
from rotacal.sim.sensors import SimCapture, register_kind

__all__ = ["DEFAULT_RATES_DEG_S", "simulate_gyro_rates"]

#: Eleven set rates from −100 to +100 °/s in steps of 20 °/s (Kokuyama et al. 2015 recommend ≥ 11 points;
#: ±100 °/s is the FMVSS 126 measurement range).
DEFAULT_RATES_DEG_S: tuple[float, ...] = tuple(float(r) for r in range(-100, 101, 20))

_MAX_ROWS = 50_000_000


def _powers(nonlinearity: Any) -> dict[int, float]:
    """``{p: c_p}`` from a mapping ``{p: c}`` or a sequence ``(c2, c3, …)``."""
    if nonlinearity is None:
        return {}
    if isinstance(nonlinearity, Mapping):
        items = list(nonlinearity.items())
    elif isinstance(nonlinearity, Sequence) and not isinstance(nonlinearity, str):
        items = [(i + 2, c) for i, c in enumerate(nonlinearity)]
    else:
        raise ConfigError(
            "nonlinearity must be a sequence (c2, c3, …) of the coefficients of Ω², Ω³, … or a "
            f"mapping {{power: coefficient}}, got {nonlinearity!r}."
        )
    out: dict[int, float] = {}
    for p, c in items:
        if isinstance(p, bool) or not float(p).is_integer() or int(p) < 2 or int(p) > 9:
            raise ConfigError(
                f"nonlinearity powers must be integers from 2 to 9, got {p!r}; the linear part "
                "is scale_factor and the constant is bias."
            )
        out[int(p)] = out.get(int(p), 0.0) + _finite(f"nonlinearity coefficient of Ω^{p}", c)
    return out


def set_rates(rates_deg_s: Any) -> np.ndarray:
    """The set rates (°/s) of a twin as a 1-D float array: at least 2 distinct, finite."""
    try:
        rates = np.asarray(rates_deg_s, dtype=float).reshape(-1)
    except (TypeError, ValueError):
        raise ConfigError(
            f"rates_deg_s must be a sequence of numbers, got {rates_deg_s!r}."
        ) from None
    if rates.size < 2 or np.unique(rates).size < 2:
        raise ConfigError(
            "rates_deg_s must hold at least 2 distinct set rates (Kokuyama et al. 2015: ≥ 11)."
        )
    if not np.all(np.isfinite(rates)):
        raise ConfigError("rates_deg_s must be finite numbers.")
    return rates


def static_response(s: float, v0: float, coeffs: Mapping[int, float]) -> Any:
    """The DUT's static response V(Ω) = V0 + S·Ω + Σ c_p·Ω^p (Ω in °/s, V in output units)."""

    def clean(w: np.ndarray) -> np.ndarray:
        v = v0 + s * w
        for p, c in coeffs.items():
            v = v + c * w**p
        return v

    return clean


def simulate_gyro_rates(
    *,
    rates_deg_s: Sequence[float] = DEFAULT_RATES_DEG_S,
    scale_factor: float = 0.0125,
    bias: float = 2.5,
    nonlinearity: Sequence[float] | Mapping[int, float] | None = (4e-8, -1.5e-11),
    noise_std: float = 6.25e-4,
    samples_per_point: int | Sequence[int] = 5000,
    quantum: float | None = None,
    saturation: tuple[float, float] | None = None,
    rate_relative_error: float = 0.0,
    seed: int = 0,
) -> SimCapture:
    """A rate-table test of a single-axis gyro: ``samples_per_point`` outputs at each set rate.

    The defaults describe an analog automotive yaw-rate sensor: 12.5 mV/(°/s) about a 2.5 V
    null, a small quadratic and cubic nonlinearity (0.0195 %FS after the straight-line fit
    over ±100 °/s), 0.05 °/s rms noise (0.625 mV) and 5000 samples (50 s at 100 Hz) per point.

    Parameters
    ----------
    rates_deg_s : sequence of float
        Set rates of the table (°/s), in the order they are run; at least 2 distinct.
    scale_factor : float
        S, output units per °/s (nonzero).
    bias : float
        V0, output at zero rate (output units).
    nonlinearity : sequence or mapping or None
        Coefficients c_p of Ω^p (output units per (°/s)^p): ``(c2, c3, …)`` or ``{p: c_p}``.
    noise_std : float
        White Gaussian output noise per sample (output units rms, ≥ 0).
    samples_per_point : int or sequence of int
        Samples at each rate (one number, or one per rate), each ≥ 1.
    quantum : float or None
        Output quantum (output units): values are rounded to ``quantum·round(v/quantum)``.
    saturation : (float, float) or None
        Output rails (low, high) in output units: the output is clipped to them (the truth's
        ``sensor`` then holds ``clipped_samples``, the outputs that were beyond them).
    rate_relative_error : float
        Relative error ε of the table's rate (dimensionless, > −1): the table turns at
        Ω·(1 + ε) while the capture records the set rate Ω (the systematic effect behind the
        specification ``table.set_rate_relative``; draw it per run to check a budget).
    seed : int
        Seed of ``numpy.random.default_rng``.

    Returns
    -------
    SimCapture
        ``kind="gyro-rates"``, columns ``rate_deg_s`` (°/s, the set rate of each row) and ``output``
        (output units). ``truth`` holds ``scale_factor``/``bias`` of the model, ``ls_scale_factor``,
        ``ls_bias``, ``ls_residuals`` and ``nonlinearity_percent_fs`` (= 100·max|δ|/(|S_ls|·FS)) of
        the least-squares line through the noise-free analog response against the rates the table
        realised (``true_rates_deg_s``; the set rates when ``rate_relative_error`` is 0; FS is the
        largest |set rate|), ``full_scale_deg_s``,
        ``clean_output`` per rate, ``saturated_rates_deg_s`` (rates whose clean output lies beyond a
        rail) and every setting.

    References
    ----------
    Kokuyama et al., "Development of angular velocity calibration facility using self-calibratable
    rotary encoder", §4 (V(Ω) = S·Ω + V0 + δ(Ω), ≥ 11 points, NL in %FS).
    """
    rates = set_rates(rates_deg_s)
    s = _finite("scale_factor", scale_factor)
    if s == 0:
        raise ConfigError("scale_factor must be nonzero.")
    v0 = _finite("bias", bias)
    coeffs = _powers(nonlinearity)
    sigma = _finite("noise_std", noise_std)
    if sigma < 0:
        raise ConfigError(f"noise_std must be ≥ 0, got {noise_std!r}.")
    counts = np.broadcast_to(np.asarray(samples_per_point), rates.shape)
    if counts.dtype.kind not in "iu" or np.any(counts < 1):
        raise ConfigError(
            "samples_per_point must be a positive integer or one positive integer per rate, got "
            f"{samples_per_point!r}."
        )
    counts = counts.astype(np.int64)
    if int(counts.sum()) > _MAX_ROWS:
        raise ConfigError(
            f"the test would have {int(counts.sum())} rows, more than {_MAX_ROWS}; lower "
            "samples_per_point."
        )
    eps = _finite("rate_relative_error", rate_relative_error)
    if eps <= -1.0:
        raise ConfigError(f"rate_relative_error must be > −1, got {rate_relative_error!r}.")
    q = None if quantum is None else _finite("quantum", quantum)
    if q is not None and q <= 0:
        raise ConfigError(f"quantum must be > 0 output units, got {quantum!r}.")
    rails: tuple[float, float] | None = None
    if saturation is not None:
        try:
            lo, hi = (
                _finite("saturation[0]", saturation[0]),
                _finite("saturation[1]", saturation[1]),
            )
        except (TypeError, IndexError):
            raise ConfigError(
                f"saturation must be (low, high) output rails, got {saturation!r}."
            ) from None
        if hi <= lo:
            raise ConfigError(
                f"saturation must be (low, high) with low < high, got {saturation!r}."
            )
        rails = (lo, hi)

    clean = static_response(s, v0, coeffs)
    clean_pts = clean(rates * (1.0 + eps))
    # Truth of the fit: least-squares line of the noise-free analog response against the realised
    # rates, one point per distinct set rate (a rate run twice is still one point: the method
    # groups equal set rates).
    uniq = np.unique(rates)
    true_uniq = uniq * (1.0 + eps)
    clean_uniq = clean(true_uniq)
    ls_s, ls_v0 = np.polyfit(true_uniq, clean_uniq, 1)
    ls_res = clean_uniq - (ls_s * true_uniq + ls_v0)
    fs = float(np.max(np.abs(uniq)))
    nl = 100.0 * float(np.max(np.abs(ls_res))) / (abs(ls_s) * fs)

    rate_col = np.repeat(rates, counts)
    out = np.repeat(clean_pts, counts)
    if sigma > 0:
        out = out + np.random.default_rng(seed).normal(0.0, sigma, out.size)
    if q is not None:
        out = q * np.round(out / q)
    saturated: list[float] = []
    clipped: dict[str, Any] = {}
    if rails is not None:
        clipped["clipped_samples"] = int(np.count_nonzero((out < rails[0]) | (out > rails[1])))
        out = np.clip(out, rails[0], rails[1])
        beyond = (clean_uniq <= rails[0]) | (clean_uniq >= rails[1])
        saturated = [float(r) for r in uniq[beyond]]

    truth: dict[str, Any] = {
        "kind": "gyro-rates",
        "scale_factor": s,
        "bias": v0,
        "nonlinearity_coefficients": {str(p): c for p, c in sorted(coeffs.items())},
        "ls_scale_factor": float(ls_s),
        "ls_bias": float(ls_v0),
        "rates_deg_s": uniq,
        "true_rates_deg_s": true_uniq,
        "rate_relative_error": eps,
        "clean_output": clean_uniq,
        "ls_residuals": ls_res,
        "full_scale_deg_s": fs,
        "nonlinearity_percent_fs": nl,
        "saturated_rates_deg_s": saturated,
        "samples": int(out.size),
        "sensor": {
            "noise_std": sigma,
            "samples_per_point": counts.tolist(),
            "quantum": q,
            "saturation": None if rails is None else list(rails),
            **clipped,
            "seed": int(seed),
            "run_order_deg_s": rates,
        },
    }
    return SimCapture("gyro-rates", {"rate_deg_s": rate_col, "output": out}, truth)


register_kind("gyro-rates", simulate_gyro_rates)
