"""Noise terms of a gyro from a static or constant-rate record (IEEE Std 952-1997, Annex C).

A thin calibration layer over :mod:`rotacal.signal.allan`: it takes a rate column (and its time
column, or a sampling rate), checks the sampling, computes the overlapping Allan deviation on a
dense log-spaced τ grid and reads the noise terms off it, giving the JSON of INTERFACE.md's
``allan`` command.

Every noise term found gets an uncertainty budget (GUM): its Type A standard uncertainty is the
±1σ χ² interval of the Allan deviation it is read from, with the degrees of freedom of *that*
reading — for a term read off a line fitted through several (correlated) points of the curve, the
variance of the fitted line's level, computed exactly from the overlapping estimator's quadratic
form for the term's own noise type (:func:`line_level_variance`); for the bias instability, the
edf of the one point it is read at. A stated DAQ timebase error (``timebase.relative_error``)
rescales τ and enters as a Type B row. The slope method's own bias (other noise terms adding to
the points a line is fitted through; the minimum of noisy points for B) is not in u — each budget
says so and gives an upper estimate of the first part.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from rotacal.errors import CaptureError, ConfigError
from rotacal.gyro.plausibility import allan_warnings
from rotacal.results import Result
from rotacal.signal import check_sampling
from rotacal.signal._values import check_magnitudes, check_not_constant, check_setting
from rotacal.signal.allan import (
    BIAS_INSTABILITY_FACTOR,
    FIT_HALF_DECADES,
    ONE_SIGMA,
    SLOPE_CORE,
    AllanDeviation,
    NoiseTerm,
    NoiseTerms,
    adev_confidence_interval,
    edf_overlapping_adev,
    noise_terms,
    overlapping_adev,
)
from rotacal.signal.clipping import check_clipping
from rotacal.uncertainty.budget import UncertaintyBudget, uncertainty_keys
from rotacal.uncertainty.gum import Input, propagate
from rotacal.uncertainty.specs import TYPE_A_ONLY_NOTE, InstrumentSpecs, spec_input

__all__ = ["GyroNoise", "gyro_noise", "line_level_variance", "noise_of_deviation"]

#: Relative spread of the sampling steps above which a time column is not a constant rate.
_MAX_STEP_SPREAD = 1e-3
#: Coverage probability of the expanded uncertainties.
COVERAGE_PROBABILITY = 0.95
#: Named JSON key and unit of each term (IEEE Std 952-1997, Table C.1).
_NAMED_UNITS = {
    "arw_deg_rt_h": "°/√h",
    "bias_instability_deg_h": "°/h",
    "rrw_deg_h_rt_h": "°/h/√h",
    "quantization_deg": "°",
    "rate_ramp_deg_h2": "°/h²",
}
_TERM_KEY = {
    "angle_random_walk": "arw_deg_rt_h",
    "bias_instability": "bias_instability_deg_h",
    "rate_random_walk": "rrw_deg_h_rt_h",
    "quantization": "quantization_deg",
    "rate_ramp": "rate_ramp_deg_h2",
}
#: Noise type α (S_y ∝ f^α) each term's reading is assumed to see: white PM for Q, white FM for
#: N, flicker FM for B, random-walk FM for K; the rate ramp (deterministic) is treated as K.
_TERM_ALPHA = {
    "quantization": 2,
    "angle_random_walk": 0,
    "bias_instability": -1,
    "rate_random_walk": -2,
    "rate_ramp": -2,
}
_ALPHA_TEXT = {2: "white PM", 0: "white FM", -1: "flicker FM", -2: "random-walk FM"}
_TERM_LABEL = {
    "quantization": "quantization Q",
    "angle_random_walk": "angle random walk N",
    "bias_instability": "bias instability B",
    "rate_random_walk": "rate random walk K",
    "rate_ramp": "rate ramp R",
}
#: Lags at which a kernel correlation is evaluated at most (coarser steps for large clusters).
_MAX_LAGS = 2048
#: Conversion of the record's rate unit to °/s (the named values need it).
_RATE_UNIT_TEXT = {"deg/s": "°/s", "rad/s": "rad/s", "deg/h": "°/h"}


@dataclasses.dataclass(frozen=True)
class GyroNoise(Result):
    """Allan deviation and IEEE 952 noise terms of one gyro channel (INTERFACE.md ``allan``).

    Attributes
    ----------
    tau_s : list of float, s
    adev_deg_s : list of float, deg/s
        Overlapping Allan deviation at ``tau_s`` (in the record's unit when it is not °/s).
    adev_low_deg_s, adev_high_deg_s : list of float
        Its 68.3 % chi-squared interval (equivalent degrees of freedom for white rate noise).
    arw_deg_rt_h, bias_instability_deg_h, rrw_deg_h_rt_h : float or None
        Angle random walk (°/√h), bias instability (°/h, with the 0.664 factor), rate random
        walk (°/h/√h); None where the curve shows no such slope.
    quantization_deg, rate_ramp_deg_h2 : float or None
    intervals : dict
        ``{name: [low, high]}`` of every term found, in the units above: IEEE 952 C.4's rule of
        thumb ±1/√(2(N/m − 1)) at one point. The standard uncertainties ``<name>_u`` of the JSON
        (and the budgets) are the χ² evaluation of the reading actually made (see the module).
    fs_hz : float, Hz
    samples : int
    duration_s : float, s
    column : str
    notes : list of str
    """

    tau_s: list[float]
    adev_deg_s: list[float]
    adev_low_deg_s: list[float]
    adev_high_deg_s: list[float]
    arw_deg_rt_h: float | None
    bias_instability_deg_h: float | None
    rrw_deg_h_rt_h: float | None
    quantization_deg: float | None
    rate_ramp_deg_h2: float | None
    intervals: dict[str, list[float]]
    fs_hz: float
    samples: int
    duration_s: float
    column: str
    notes: list[str]
    _adev: AllanDeviation = dataclasses.field(repr=False)
    _terms: NoiseTerms = dataclasses.field(repr=False)
    _budgets: dict[str, UncertaintyBudget] = dataclasses.field(
        default_factory=dict, repr=False, compare=False
    )
    _slope_bias: dict[str, float] = dataclasses.field(
        default_factory=dict, repr=False, compare=False
    )

    @property
    def allan(self) -> AllanDeviation:
        return self._adev

    @property
    def terms(self) -> NoiseTerms:
        return self._terms

    def to_dict(self) -> dict[str, Any]:
        """INTERFACE.md ``allan`` keys plus ``<term>_u``/``<term>_U`` (None where the term is not
        seen), ``k`` ({term: k}), ``coverage_probability`` and ``uncertainty_budgets``."""
        out = super().to_dict()
        for key in _NAMED_UNITS:
            out[f"{key}_u"] = None
            out[f"{key}_U"] = None
        out.update(uncertainty_keys(self._budgets))
        if not self._budgets:
            out["coverage_probability"] = None
        return out


# ====================================================================== uncertainty of a reading
def _box_corr(a: float, b: float, d: np.ndarray) -> np.ndarray:
    """Σ_j box_a(j)·box_b(j − d): the overlap of [0, a) and [d, d + b) (samples)."""
    return np.maximum(0.0, np.minimum(a, d + b) - np.maximum(0.0, d))


def _lag_sum(a: int, b: int, n_phase: int, lags: np.ndarray, c: np.ndarray, step: int) -> float:
    """Σ_δ #{(k, l): l − k = δ}·C(δ)² over the second differences k < N − 2a, l < N − 2b."""
    ka, kb = n_phase - 2 * a, n_phase - 2 * b
    count = np.maximum(0.0, np.minimum(ka, kb - lags) - np.maximum(0.0, -lags))
    return step * float(np.sum(count * c * c))


def _pair_sum(a: int, b: int, n_phase: int, alpha: int) -> float:
    """Σ_{k,l} C_ab(l − k)² for the second-difference kernels of cluster sizes a and b.

    The second difference d_k(m) = x_{k+2m} − 2x_{k+m} + x_k is a linear filter of unit white
    noise: white PM (α = 2) the spikes (1, −2, 1) at 0, m, 2m; white FM (α = 0) the rate through
    −box_m + box_m shifted by m; random-walk FM (α = −2) the rate's increments through the
    triangle box_m * box_m. C_ab(δ) = Σ_j h_a(j)·h_b(j − δ) in closed form (box overlaps; for the
    triangle the self-convolution of the box overlap). Large clusters are evaluated on every q-th
    lag (q·Σ, q ≥ 1 so that ≤ 2048 lags): the error is O((q/m)²) of a smooth sum.
    """
    if alpha == 2:
        acc: dict[int, float] = {}
        for p_, cp in ((0, 1.0), (a, -2.0), (2 * a, 1.0)):
            for r_, cr in ((0, 1.0), (b, -2.0), (2 * b, 1.0)):
                acc[p_ - r_] = acc.get(p_ - r_, 0.0) + cp * cr
        lags = np.array(list(acc), dtype=np.float64)
        return _lag_sum(a, b, n_phase, lags, np.array(list(acc.values())), 1)
    if alpha == 0:
        lo, hi = -(2 * b - 1), 2 * a - 1
        q = max(1, (hi - lo) // _MAX_LAGS)
        d = np.arange(lo, hi + 1, q, dtype=np.float64)
        c = (
            _box_corr(a, b, d)
            - _box_corr(a, b, d + b)
            - _box_corr(a, b, d - a)
            + _box_corr(a, b, d - a + b)
        )
        return _lag_sum(a, b, n_phase, d, c, q)
    lo, hi = -(b - 1), a - 1
    q = max(1, (hi - lo) // _MAX_LAGS)
    t = _box_corr(a, b, np.arange(lo, hi + 1, q, dtype=np.float64))
    c = q * np.convolve(t, t)
    d = 2 * lo + q * np.arange(c.size, dtype=np.float64)
    return _lag_sum(a, b, n_phase, d, c, q)


def _kernel_energy(m: int, alpha: int) -> float:
    """C_mm(0) = Σ_j h_m(j)²: 6 (white PM), 2m (white FM), (2m³ + m)/3 (random-walk FM)."""
    if alpha == 2:
        return 6.0
    if alpha == 0:
        return 2.0 * m
    return (2.0 * m**3 + m) / 3.0


def line_level_variance(cluster_sizes: Any, n_phase: int, noise_alpha: int) -> float:
    """Variance of the level of a fixed-slope line fitted through several Allan deviation points.

    The line of slope p through the points (log τ_i, log σ̂_i) has the level
    ``ln C = mean_i(ln σ̂_i) − p·mean_i(ln τ_i)``; the σ̂_i of one record are correlated (they use
    the same samples), so ``var(ln C) = (1/n²)·Σ_ij cov(ln σ̂_i, ln σ̂_j)``. For Gaussian noise of
    one power-law type every σ̂²(m) is a quadratic form of the noise, and
    ``cov(σ̂²_a, σ̂²_b)/(σ²_a·σ²_b) = 2·Σ_{k,l} C_ab(l − k)² / (K_a·K_b·C_aa(0)·C_bb(0))`` with
    K_m = N − 2m second differences and C_ab the correlation of their filter kernels; then
    cov(ln σ̂_a, ln σ̂_b) ≈ ¼ of that. For one point this is 1/(2·edf) with the exact edf of the
    overlapping estimator (it equals Greenhall's edf where that is exact: every m for white PM,
    m ≳ 50 for white and random-walk FM).

    Parameters
    ----------
    cluster_sizes : array_like of int
        The cluster sizes m_i (samples) of the points the line is fitted through.
    n_phase : int
        Phase points N of the record (rate samples + 1).
    noise_alpha : {2, 0, -2}
        The noise type of the term: 2 white PM (quantization), 0 white FM (angle random walk),
        −2 random-walk FM (rate random walk).

    Returns
    -------
    float
        var(ln C), dimensionless (relative variance of the coefficient; ν = 1/(2·var) is the
        equivalent degrees of freedom of the fitted level).

    References
    ----------
    IEEE Std 952-1997, Annex C (§C.1 overlapping Allan variance, the slope method); C. A. Greenhall
    and W. J. Riley, "Uncertainty of stability variances based on finite differences", Proc. 35th
    PTTI (2003), §2 (the variance estimator as a quadratic form; edf = 2·E²/var); NIST SP 1065
    (Riley 2008), §5.3 (edf and χ² intervals).
    """
    ms = np.asarray(cluster_sizes, dtype=np.int64).ravel()
    if noise_alpha not in (2, 0, -2):
        raise ConfigError(f"noise_alpha must be 2, 0 or −2 for a fitted line; got {noise_alpha!r}.")
    if ms.size == 0 or (ms < 1).any() or (n_phase - 2 * ms < 1).any():
        raise ConfigError(
            f"cluster sizes must satisfy 1 ≤ m ≤ (N − 1)/2 = {(n_phase - 1) // 2}; got {ms}."
        )
    total = 0.0
    for i in range(ms.size):
        a = int(ms[i])
        ea = _kernel_energy(a, noise_alpha) * (n_phase - 2 * a)
        for j in range(i, ms.size):
            b = int(ms[j])
            eb = _kernel_energy(b, noise_alpha) * (n_phase - 2 * b)
            rel = 2.0 * _pair_sum(a, b, n_phase, noise_alpha) / (ea * eb)
            total += rel if i == j else 2.0 * rel
    return 0.25 * total / (ms.size * ms.size)


def _fit_points(terms: NoiseTerms, term: NoiseTerm) -> np.ndarray | None:
    """Indices (into ``terms.slope_tau_s``) of the points ``term``'s line was fitted through."""
    t = np.asarray(terms.slope_tau_s, dtype=np.float64)
    slope = np.asarray(terms.local_slope, dtype=np.float64)
    lo, hi = term.fit_tau_s
    cand = np.flatnonzero((t >= lo * (1 - 1e-9)) & (t <= hi * (1 + 1e-9)))
    core = cand[np.abs(slope[cand] - term.slope) <= SLOPE_CORE]
    ref = math.log10(term.tau_ref_s)
    for pts in (cand, core):
        for sel in (pts, pts[np.abs(np.log10(t[pts]) - ref) <= FIT_HALF_DECADES]):
            if (
                sel.size == term.n_points
                and sel.size
                and math.isclose(t[sel[0]], lo, rel_tol=1e-9)
                and math.isclose(t[sel[-1]], hi, rel_tol=1e-9)
            ):
                return sel
    return None


def _term_variance(name: str, coefficient: float, tau: np.ndarray) -> np.ndarray:
    """σ²(τ) of one IEEE 952 term of native coefficient C (record unit based; Table C.1)."""
    if name == "quantization":
        return 3.0 * coefficient**2 / tau**2
    if name == "angle_random_walk":
        return coefficient**2 / tau
    if name == "bias_instability":
        return np.full_like(tau, (BIAS_INSTABILITY_FACTOR * coefficient) ** 2)
    if name == "rate_random_walk":
        return coefficient**2 * tau / 3.0
    return coefficient**2 * tau**2 / 2.0  # rate ramp


def _leak_fraction(
    terms: NoiseTerms, name: str, tau: np.ndarray, sigma: np.ndarray
) -> tuple[float, list[str], list[str]]:
    """How much too high a reading is from the *other* terms found, at its points τ_i.

    σ̂²(τ_i) = σ²_term(τ_i) + Σ_other σ²_o(τ_i), so the term's own level is σ̂·√(1 − ρ_i) with
    ρ_i = Σ_other σ²_o/σ̂²; over the points the level is high by 1 − exp(mean ½·ln(1 − ρ_i)).
    A term whose line would exceed the measured deviation at one of these points contradicts the
    curve there (a slope read off a few noisy points at long τ) and is left out.

    Returns the fraction, the terms used and the terms left out.
    """
    other = np.zeros_like(tau)
    used: list[str] = []
    dropped: list[str] = []
    for o_name, o_term in terms.terms.items():
        if o_name == name:
            continue
        var = _term_variance(o_name, o_term.coefficient, tau)
        if np.any(var >= sigma**2):
            dropped.append(o_name)
            continue
        used.append(o_name)
        other += var
    if not used:
        return 0.0, used, dropped
    rho = np.minimum(other / sigma**2, 0.99)
    return float(1.0 - math.exp(float(np.mean(0.5 * np.log1p(-rho))))), used, dropped


def _noise_budgets(
    adev: AllanDeviation,
    terms: NoiseTerms,
    unit: str,
    specs: InstrumentSpecs | None,
) -> tuple[dict[str, UncertaintyBudget], dict[str, float]]:
    """One GUM budget per named noise term found (see :func:`gyro_noise`), and the estimated
    slope-method bias (fraction by which each reading may be high; not in u)."""
    budgets: dict[str, UncertaintyBudget] = {}
    leaks: dict[str, float] = {}
    if unit not in _RATE_UNIT_TEXT:
        return budgets, leaks
    rate_unit = _RATE_UNIT_TEXT[unit]
    fs = adev.fs_hz
    n_phase = adev.n_phase
    sizes = np.asarray(adev.cluster_sizes)  # sorted, unique
    deviations = np.asarray(adev.adev, dtype=np.float64)

    def adev_at(ms: np.ndarray) -> np.ndarray:
        """σ at cluster sizes ``ms``, NaN where the curve has no such size (a lookup table of
        every τ would cost seconds for 5·10⁶ of them)."""
        idx = np.minimum(np.searchsorted(sizes, ms), sizes.size - 1)
        return np.where(sizes[idx] == ms, deviations[idx], np.nan)

    timebase = spec_input(specs, "timebase.relative_error", name="DAQ timebase relative error")
    for name, term in terms.terms.items():
        key = _TERM_KEY[name]
        value = getattr(terms, key)
        if value is None:
            continue
        alpha = _TERM_ALPHA[name]
        notes: list[str] = []
        if name == "bias_instability":
            ms = np.array([round(term.tau_used_s * fs)])
            edf = float(edf_overlapping_adev(n_phase, ms, alpha)[0])
            level = term.coefficient * BIAS_INSTABILITY_FACTOR  # the plateau σ_min
            what = f"Allan deviation minimum at τ = {term.tau_used_s:.3g} s"
            how = f"χ², edf {edf:.4g} ({_ALPHA_TEXT[alpha]}, one point)"
            notes.append(
                "B = σ_min/0.664 from the smallest of noisy points: picking the minimum biases B "
                "down; that part of the slope method's bias is not in u."
            )
        else:
            pts = _fit_points(terms, term)
            if pts is None:
                ms = np.array([round(term.tau_used_s * fs)])
                notes.append(
                    "the fitted points could not be recovered: u is that of the one point nearest "
                    "the reading (conservative)."
                )
            else:
                ms = np.rint(np.asarray(terms.slope_tau_s)[pts] * fs).astype(np.int64)
            var_ln = line_level_variance(ms, n_phase, alpha)
            edf = 1.0 / (2.0 * var_ln)
            level = term.coefficient  # σ of the fitted line at τ_ref
            lo_t, hi_t = term.fit_tau_s
            what = (
                f"line of slope {term.slope:+g} through σ(τ), τ = {lo_t:.3g}…{hi_t:.3g} s, read "
                f"at {term.tau_ref_s:.3g} s"
            )
            how = f"χ², edf {edf:.4g} ({_ALPHA_TEXT[alpha]}, {ms.size} correlated points)"
            notes.append(
                f"u of the reading is the χ² (±1σ) interval of the fitted line's level for "
                f"{_ALPHA_TEXT[alpha]} noise, the points' correlation included."
            )
        lo, hi = adev_confidence_interval(1.0, np.array([edf]), ONE_SIGMA)
        u_rel = 0.5 * float(hi[0] - lo[0])
        factor = float(value) / level  # named unit per record unit
        inputs = [
            Input(
                name=what,
                value=level,
                u=level * u_rel,
                dof=edf,
                distribution="chi-squared",
                unit=rate_unit,
                source=f"Type A, {adev.n_samples} samples at {fs:.6g} Hz",
                description=how,
            )
        ]
        sigma_pts = adev_at(ms)
        leak = 0.0
        used: list[str] = []
        dropped: list[str] = []
        if np.all(np.isfinite(sigma_pts)) and len(terms.terms) > 1:
            leak, used, dropped = _leak_fraction(terms, name, ms / fs, sigma_pts)
        if dropped:
            notes.append(
                f"{', '.join(_TERM_LABEL[o] for o in dropped)} would exceed the measured "
                "deviation at these points (a line read off few points elsewhere): left out of "
                "the slope-method bias estimate."
            )
        leaks[key] = leak
        if leak > 0.0:
            notes.append(
                f"{', '.join(_TERM_LABEL[o] for o in used)}, extended into these points, would "
                f"make the reading up to {100.0 * leak:.2g} % high (an upper estimate; this bias "
                "of the slope method is not in u and not corrected)."
            )
        else:
            notes.append("the slope method's own bias is not in u.")
        slope = 0.0 if name == "bias_instability" else term.slope
        has_e = False
        if specs is None:
            notes.append(TYPE_A_ONLY_NOTE)
        elif timebase is not None and slope != 0.0:
            inputs.append(timebase)
            has_e = True
        elif slope != 0.0:
            notes.append("timebase.relative_error not stated: τ taken as exact.")
        e0 = inputs[-1].value if has_e else 0.0

        def model(sigma: float, *e: float, _f: float = factor, _p: float = slope) -> float:
            # τ of the record = τ_true·(1 + e): the true coefficient is C·(1 + e)^p (p = slope)
            return _f * sigma * (1.0 + (e[0] if e else 0.0)) ** _p

        def jac(sigma: float, *e: float, _f: float = factor, _p: float = slope) -> np.ndarray:
            g = 1.0 + (e[0] if e else 0.0)
            row = [_f * g**_p]
            if e:
                row.append(_f * sigma * _p * g ** (_p - 1.0))
            return np.array([row])

        if e0 != 0.0 and specs is not None:
            notes.append(str(specs.correction_note("timebase.relative_error")))
        res = propagate(
            model,
            inputs,
            jacobian=jac,
            p=COVERAGE_PROBABILITY,
            names_out=[_TERM_LABEL[name]],
            units_out=[_NAMED_UNITS[key]],
        )
        b = res.budget(0)
        budgets[key] = dataclasses.replace(b, notes=(*b.notes, *notes))
    return budgets, leaks


def _gap_free_record(values: ArrayLike, column: str) -> np.ndarray:
    """The column as a 1-D float64 array, refused when not 1-D or holding NaN/inf."""
    y = np.asarray(values, dtype=np.float64)
    if y.ndim != 1:
        raise CaptureError(f"column '{column}' must be 1-D, got shape {y.shape}.")
    bad = np.flatnonzero(~np.isfinite(y))
    if bad.size:
        raise CaptureError(
            f"column '{column}' has {bad.size} NaN/inf value(s), the first at sample {bad[0]}; "
            "the Allan deviation needs a gap-free record."
        )
    return y


def _check_fs_hz(fs_hz: float | None) -> None:
    if fs_hz is not None:
        fs = float(fs_hz)
        if not math.isfinite(fs) or fs <= 0:
            raise ConfigError(f"fs_hz must be > 0, got {fs_hz!r}.")
        check_setting("--fs-hz", fs, unit="Hz")


def _constant_rate(
    first: float, last: float, n: int, min_step: float, max_step: float, fs_hz: float | None
) -> float:
    """The sampling rate of ``n`` time stamps from ``first`` to ``last`` (s), their mean step,
    refused when a step differs from it by more than 10 % (not a constant rate) or when it
    contradicts ``fs_hz``. The mean step, not the median: a record read in chunks gets the same
    number (:mod:`rotacal.gyro.noise_stream`), and it is the less rounded of the two."""
    step = (last - first) / (n - 1)
    spread = max(max_step - step, step - min_step) / step
    if spread > _MAX_STEP_SPREAD * 100:
        raise CaptureError(
            f"time_s is not sampled at a constant rate (steps vary by {100 * spread:.3g} %): the "
            "Allan deviation needs equally spaced samples; resample the record first."
        )
    fs = 1.0 / step
    if fs_hz is not None and not math.isclose(fs, float(fs_hz), rel_tol=1e-3):
        raise ConfigError(
            f"--fs-hz {fs_hz:g} contradicts the time column ({fs:.6g} Hz); give one of them."
        )
    return fs


def _sampling_rate(time_s: ArrayLike | None, fs_hz: float | None, n: int) -> float:
    _check_fs_hz(fs_hz)
    if time_s is None:
        if fs_hz is None:
            raise ConfigError("give the sampling rate (fs_hz, --fs-hz) or a time_s column.")
        return float(fs_hz)
    t = np.asarray(time_s, dtype=np.float64)
    if t.shape != (n,):
        raise CaptureError(f"time_s has {t.size} values, the rate column {n}; they must match.")
    check_sampling(t, "time_s")
    if n < 2:
        raise CaptureError(f"the record holds {n} sample(s): too short for an Allan deviation.")
    steps = np.diff(t)
    return _constant_rate(
        float(t[0]), float(t[-1]), n, float(steps.min()), float(steps.max()), fs_hz
    )


def gyro_noise(
    rate: ArrayLike,
    *,
    fs_hz: float | None = None,
    time_s: ArrayLike | None = None,
    unit: str = "deg/s",
    taus: Any = "log",
    column: str = "rate_deg_s",
    specs: InstrumentSpecs | None = None,
    allow_clipped: bool = False,
) -> GyroNoise:
    """Overlapping Allan deviation and IEEE 952 noise terms of a gyro's rate record, each term
    with its uncertainty budget.

    Parameters
    ----------
    rate : array_like
        Rate samples, in ``unit`` (°/s by default; "rad/s", "deg/h" are converted for the named
        terms).
    fs_hz : float, Hz, optional
        Sampling rate; or give ``time_s``.
    time_s : array_like, s, optional
        Sample times (equally spaced; gaps are refused).
    unit : str
        Unit of ``rate``.
    taus : None, str or array_like
        τ grid (see :func:`rotacal.signal.allan.overlapping_adev`); default ``"log"``.
    column : str
        The column's name, for messages and the report.
    specs : InstrumentSpecs, optional
        The lab's instrument specifications; ``timebase.relative_error`` (fractional error of the
        DAQ clock, which scales every τ) is used, the others do not apply. None: Type A only.
    allow_clipped : bool
        Analyse a record with samples at the rails (:mod:`rotacal.signal.clipping`) anyway
        (``--allow-clipped``); ``warnings`` name the clipping. Refused by default.

    Returns
    -------
    GyroNoise
        With ``_budgets`` (one per named term found) and, in the JSON, ``<term>_u``,
        ``<term>_U``, ``k``, ``coverage_probability`` and ``uncertainty_budgets``.

    Notes
    -----
    Type A: u of a term is the ±1σ χ² interval of its reading, with ν the equivalent degrees of
    freedom of that reading: for Q, N, K (and R) the level of the fixed-slope line through its
    fitted points (:func:`line_level_variance`, for the term's noise type, the points'
    correlation included); for B the edf (flicker FM, Greenhall) of the one point at the minimum.
    Type B: a timebase error e makes the record's τ = (1 + e)·τ_true, so the true coefficient is
    C·(1 + e)^p with p the term's slope (sensitivity p·C). k = t_0.975(ν_eff).

    The slope method's own bias is not in u and not corrected; each budget says so and, where
    other terms were found, states an upper estimate of it: the other terms' lines extended into
    the points the reading uses (``_slope_bias``: the fraction by which the reading may be high).
    On the static twin (0.3 °/√h, 3 °/h, correlation times from 1 s) the mean ARW of 300 records
    of 600 s is 0.3 % (±0.1 %) above the truth, a sixth of its u; with correlation times from
    0.5 s (0.1 °/√h, 2 °/h, 2 h at 20 Hz) it is 2.2 % (±0.1 %) high and the estimate says 2.6 %.

    References
    ----------
    IEEE Std 952-1997, Annex C (Allan variance, Table C.1 slopes, §C.4 confidence);
    IEEE Std 1139 / NIST SP 1065 (overlapping ADEV; §5.3 edf and χ² intervals); JCGM 100:2008
    (GUM) §4.2, §4.3, §5.1.2, G.4 (budgets, ν_eff, k).
    """
    y = _gap_free_record(rate, column)
    check_magnitudes(column, y, what="a rate signal")
    check_not_constant(
        column, y, "the sensor is stuck, or the column is a set value; supply the sensor output"
    )
    fs = _sampling_rate(time_s, fs_hz, y.size)
    clipped = check_clipping({column: y}, allow_clipped=allow_clipped)
    # clipping is judged above, under the column's name
    adev = overlapping_adev(y, fs=fs, taus=taus, data_type="rate", allow_clipped=True)
    return noise_of_deviation(adev, unit=unit, column=column, specs=specs, warnings=clipped)


def noise_of_deviation(
    adev: AllanDeviation,
    *,
    unit: str,
    column: str,
    specs: InstrumentSpecs | None,
    warnings: tuple[str, ...] = (),
) -> GyroNoise:
    """The :class:`GyroNoise` of an Allan deviation of a rate record (the part of
    :func:`gyro_noise` after the deviation: noise terms, budgets, plausibility warnings), for a
    deviation computed in memory or from a record read in chunks."""
    terms = noise_terms(adev, unit=unit)
    named = {
        "angle_random_walk": "arw_deg_rt_h",
        "bias_instability": "bias_instability_deg_h",
        "rate_random_walk": "rrw_deg_h_rt_h",
        "quantization": "quantization_deg",
        "rate_ramp": "rate_ramp_deg_h2",
    }
    budgets, leaks = _noise_budgets(adev, terms, unit, specs)
    values: dict[str, float | None] = {}
    intervals = {}
    for name, key in named.items():
        plain = getattr(terms, key)
        # one truth: a stated mean timebase error corrects the value as its budget does
        scale = budgets[key].value / plain if key in budgets and plain else 1.0
        values[key] = None if plain is None else float(plain) * scale
        low, high = getattr(terms, key + "_low"), getattr(terms, key + "_high")
        if low is not None and high is not None:
            intervals[name] = [float(low) * scale, float(high) * scale]
    return GyroNoise(
        tau_s=np.asarray(adev.tau_s, dtype=np.float64).tolist(),
        adev_deg_s=np.asarray(adev.adev, dtype=np.float64).tolist(),
        adev_low_deg_s=np.asarray(adev.adev_low, dtype=np.float64).tolist(),
        adev_high_deg_s=np.asarray(adev.adev_high, dtype=np.float64).tolist(),
        arw_deg_rt_h=values["arw_deg_rt_h"],
        bias_instability_deg_h=values["bias_instability_deg_h"],
        rrw_deg_h_rt_h=values["rrw_deg_h_rt_h"],
        quantization_deg=values["quantization_deg"],
        rate_ramp_deg_h2=values["rate_ramp_deg_h2"],
        intervals=intervals,
        fs_hz=adev.fs_hz,
        samples=int(adev.n_samples),
        duration_s=float(adev.n_samples / adev.fs_hz),
        column=column,
        notes=[*adev.notes, *terms.notes],
        _adev=adev,
        _terms=terms,
        _budgets=budgets,
        _slope_bias=leaks,
        warnings=(
            *warnings,
            *allan_warnings(
                bias_instability=values["bias_instability_deg_h"],
                local_slope=terms.local_slope,
                tau_s=terms.slope_tau_s,
            ),
        ),
    )


def gyro_noise_from_angle(
    angle: ArrayLike,
    *,
    fs_hz: float | None = None,
    time_s: ArrayLike | None = None,
    column: str = "angle_deg",
    **options: Any,
) -> GyroNoise:
    """:func:`gyro_noise` of a record of angle (or phase) samples instead of rate samples.

    An integrating gyro (a ring-laser gyro's or an angle readout's counts), or frequency-
    stability phase data (time error), gives the running integral of the rate. The N angle samples
    θ_i are differenced to N − 1 rate samples ω_i = (θ_{i+1} − θ_i)·fs; their running integral is
    θ_i − θ_0, so the overlapping Allan deviation is that of the angle record as phase data
    (IEEE Std 952-1997 Annex C; NIST SP 1065 §5.2.4, phase form), to rounding.

    Parameters
    ----------
    angle : array_like
        Angle samples in the unit of the rate's integral: ° for ``unit="deg/s"``, rad for
        "rad/s", or the column's own (time error in s for phase data, with ``unit="other"``).
    fs_hz : float, Hz, optional
        Sampling rate; or give ``time_s``.
    time_s : array_like, s, optional
        Sample times of the angles (equally spaced; gaps are refused).
    column : str
        The column's name, for messages and the report.
    **options
        ``unit`` ("deg/s": angle in °, "rad/s": angle in rad, "other": the column's own unit per
        s), ``taus``, ``specs``, ``allow_clipped`` as for :func:`gyro_noise`.

    Raises
    ------
    CaptureError
        An angle in ° or rad that steps by half a turn or more between two samples (an angle
        kept modulo 360°, or motion the sampling does not resolve); NaN/inf; fewer than 3 samples.
    ConfigError
        ``unit="deg/h"`` (the differenced rate is per second).

    Returns
    -------
    GyroNoise
        As :func:`gyro_noise`, with a note that the rate was differenced from the angle.
    """
    theta = _gap_free_record(angle, column)
    if theta.size < 3:
        raise CaptureError(
            f"column '{column}' holds {theta.size} angle sample(s): too short for an Allan "
            "deviation."
        )
    unit = options.get("unit", "deg/s")
    if unit == "deg/h":
        raise ConfigError(
            f"column '{column}' is an angle (--angle): its rate comes out per second; give "
            "--unit deg/s (angle in deg) or rad/s (angle in rad)"
        )
    fs = _sampling_rate(time_s, fs_hz, theta.size)
    steps = np.diff(theta)
    half_turn = {"deg/s": 180.0, "rad/s": math.pi}.get(unit)
    if half_turn is not None:
        # a step of half a turn or more between samples is a wrap-around (an angle kept modulo
        # a turn) or motion the sampling cannot resolve: either way the rate would be wrong
        jumps = np.flatnonzero(np.abs(steps) >= half_turn)
        if jumps.size:
            i = int(jumps[0])
            raise CaptureError(
                f"column '{column}' jumps by {steps[i]:+.6g} {unit.split('/')[0]} from sample "
                f"{i} to {i + 1} ({jumps.size} such step(s)): an angle that wraps around a turn "
                "(unwrap it, e.g. count whole turns, before the analysis) or motion faster than "
                "the sampling resolves"
            )
    result = gyro_noise(steps * fs, fs_hz=fs, column=column, **options)
    note = (
        f"the rate is the angle column '{column}' differenced ({theta.size} angle samples, "
        f"{theta.size - 1} rate samples)"
    )
    return dataclasses.replace(result, notes=[note, *result.notes])
