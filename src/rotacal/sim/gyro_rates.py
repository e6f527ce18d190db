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


def static_response(
    s: float,
    v0: float,
    coeffs: Mapping[int, float],
    half_asymmetry: float = 0.0,
    scale_tc_ppm_per_c: float = 0.0,
    bias_tc_per_c: float = 0.0,
) -> Any:
    """The DUT's static response ``clean(Ω, ΔT)`` = V0 + k_b·ΔT + S·(1 + 1e-6·k_S·ΔT)·Ω·(1 ± a/2)
    + Σ c_p·Ω^p (Ω in °/s, V in output units, ΔT in °C from the reference temperature; the sign
    of Ω picks ±: ``half_asymmetry`` = a/2, dimensionless; k_S in ppm/°C, k_b in output units/°C).
    """

    def clean(w: np.ndarray, dt: np.ndarray | float = 0.0) -> np.ndarray:
        v = v0 + bias_tc_per_c * dt
        v = v + s * (1.0 + 1e-6 * scale_tc_ppm_per_c * dt) * w * (1.0 + np.sign(w) * half_asymmetry)
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
    asymmetry_ppm: float = 0.0,
    run_scale_factor_std_ppm: float = 0.0,
    temperature_c: float | Sequence[float] | None = None,
    temperature_ref_c: float = 25.0,
    scale_factor_tc_ppm_per_c: float = 0.0,
    bias_tc_per_c: float = 0.0,
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
    asymmetry_ppm : float
        Scale-factor asymmetry A (ppm): the linear slope is S·(1 + A/2·1e-6) for Ω > 0 and
        S·(1 − A/2·1e-6) for Ω < 0 (IEEE Std 528's asymmetry, S₊ − S₋ = A·S).
    run_scale_factor_std_ppm : float
        Run-to-run standard deviation of S (ppm, ≥ 0): this run's S is S·(1 + σ·z·1e-6), z a
        standard normal drawn from ``seed`` (truth ``run_scale_factor``); several seeds make
        several runs of one gyro.
    temperature_c : float or sequence of float or None
        Temperature of the test (°C; one number, or one per rate): writes a ``temperature_c``
        column and makes S and V0 depend on it: S(T) = S·(1 + k_S·1e-6·(T − T_ref)),
        V0(T) = V0 + k_B·(T − T_ref).
    temperature_ref_c : float
        T_ref (°C), where S and V0 hold.
    scale_factor_tc_ppm_per_c : float
        k_S (ppm/°C).
    bias_tc_per_c : float
        k_B (output units per °C); the truth states it as (°/h)/°C, 3600·k_B/S.
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

    rng = np.random.default_rng(seed)
    run_std = _finite("run_scale_factor_std_ppm", run_scale_factor_std_ppm)
    if run_std < 0:
        raise ConfigError(
            f"run_scale_factor_std_ppm must be ≥ 0, got {run_scale_factor_std_ppm!r}."
        )
    # drawn only when asked, so that the noise of a capture without it stays as it was
    s = s * (1.0 + 1e-6 * run_std * float(rng.standard_normal())) if run_std > 0 else s
    half_a = 0.5e-6 * _finite("asymmetry_ppm", asymmetry_ppm)
    temps, t_ref, k_s, k_b = _temperatures(
        temperature_c, rates, temperature_ref_c, scale_factor_tc_ppm_per_c, bias_tc_per_c
    )
    clean = static_response(s, v0, coeffs, half_a, k_s, k_b)
    clean_pts = clean(rates * (1.0 + eps), 0.0 if temps is None else temps - t_ref)
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
        out = out + (rng if run_std > 0 else np.random.default_rng(seed)).normal(
            0.0, sigma, out.size
        )
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
        "run_scale_factor": s,
        **_signed_truth(true_uniq, clean_uniq, float(ls_s)),
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
    columns = {"rate_deg_s": rate_col, "output": out}
    if temps is not None:
        columns["temperature_c"] = np.repeat(temps, counts)
        truth.update(
            temperature_c=temps,
            temperature_ref_c=t_ref,
            scale_factor_temperature_coefficient_ppm_per_c=k_s,
            bias_temperature_coefficient_deg_h_per_c=3600.0 * k_b / s,
        )
    return SimCapture("gyro-rates", columns, truth)


def _temperatures(
    temperature_c: Any, rates: np.ndarray, ref: Any, k_s: Any, k_b: Any
) -> tuple[np.ndarray | None, float, float, float]:
    """(temperature of each run point in °C or None, T_ref, k_S ppm/°C, k_B output/°C)."""
    t_ref = _finite("temperature_ref_c", ref)
    ks, kb = _finite("scale_factor_tc_ppm_per_c", k_s), _finite("bias_tc_per_c", k_b)
    if temperature_c is None:
        if ks or kb:
            raise ConfigError("temperature coefficients need temperature_c (the test's °C).")
        return None, t_ref, 0.0, 0.0
    try:
        temps = np.broadcast_to(np.asarray(temperature_c, dtype=float), rates.shape).copy()
    except (TypeError, ValueError):
        raise ConfigError(
            f"temperature_c must be a number or one number per rate (°C), got {temperature_c!r}."
        ) from None
    if not np.all(np.isfinite(temps)):
        raise ConfigError("temperature_c must be finite (°C).")
    return temps, t_ref, ks, kb


def _signed_truth(true_rates: np.ndarray, clean: np.ndarray, ls_s: float) -> dict[str, float]:
    """S₊, S₋ (two slopes, one intercept) of the noise-free response and 1e6·(S₊ − S₋)/S_ls,
    by numpy.linalg.lstsq (shares nothing with rotacal.gyro.sf_items); NaN below 2 per sign."""
    if min(np.count_nonzero(true_rates > 0), np.count_nonzero(true_rates < 0)) < 2:
        nan = float("nan")
        return {"scale_factor_positive": nan, "scale_factor_negative": nan, "asymmetry_ppm": nan}
    design = np.column_stack(
        [np.where(true_rates > 0, true_rates, 0.0), np.where(true_rates < 0, true_rates, 0.0)]
    )
    design = np.column_stack([design, np.ones(true_rates.size)])
    (sp, sn, _), *_ = np.linalg.lstsq(design, clean, rcond=None)
    return {
        "scale_factor_positive": float(sp),
        "scale_factor_negative": float(sn),
        "asymmetry_ppm": 1e6 * float(sp - sn) / ls_s,
    }


register_kind("gyro-rates", simulate_gyro_rates)
