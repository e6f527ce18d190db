"""The result of a sine / multi-harmonic fit (re-exported from :mod:`rotacal.signal.sinefit`)."""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from rotacal.results import Result

_EVAL_CHUNK = 1 << 16


@dataclass(frozen=True, eq=False)
class SineFit(Result):
    """A fitted sine with harmonics, ``y ≈ C + Σ_h A_h·sin(2π·h·f·(t − t_ref) + φ_h)``.

    Equivalently ``y ≈ C + Σ_h a_h·cos(2π·h·f·(t − t_ref)) + b_h·sin(2π·h·f·(t − t_ref))`` with
    ``a_h = A_h·sin φ_h`` and ``b_h = A_h·cos φ_h`` (Feng et al. 2023, Sensors 23:4876,
    eqs. (9)–(10); IEEE Std 1057-2017, §4.1.3).

    Attributes
    ----------
    frequency_hz : fundamental frequency f (Hz).
    offset : constant term C (unit of y).
    amplitudes : A_h for h = 1..H (unit of y).
    phases_rad : φ_h for h = 1..H (rad), relative to ``t_ref_s``.
    cos_coefs, sin_coefs : a_h and b_h (unit of y).
    t_ref_s : time origin of the phases (s); the middle of the record.
    residual_rms : rms of y − model (unit of y). With the block-moment method it comes from the
        normal equations (yᵀy − bᵀp); when that is too small to trust (below ~3e-5·rms(y)) the
        in-memory fits sum it from the samples, and a :class:`HarmonicFitAccumulator` fed in
        chunks, which no longer has them, gives it as computed (rounding, clamped at 0).
    n_samples : number of samples fitted.
    iterations : Gauss–Newton iterations of the frequency refinement (0 when f was fixed).
    amplitudes_u : standard uncertainty of A_h (unit of y) from the residual variance, assuming
        white noise; includes the correlation with f when f was fitted.
    frequency_u_hz : standard uncertainty of f (Hz), idem; 0 when f was fixed.
    offset_u : standard uncertainty of C (unit of y), idem.
    drift : the linear term D of a fit with drift, ``y ≈ C + D·(t − t_ref) + Σ_h …`` (unit of y
        per s); None when the model has no drift term (the IEEE 1057 model).
    drift_u : standard uncertainty of D (unit of y per s), as ``amplitudes_u``; None without drift.
    drift_check : the same data refitted with a drift term at the fitted frequency (a fit without
        drift asked for it with ``drift_check=True``), to judge whether an unfitted drift matters;
        None otherwise.
    phases_u_rad : standard uncertainty of φ_h (rad), as ``amplitudes_u`` (GUM first-order
        propagation of the covariance of a_h, b_h through φ = atan2(a, b)); not in the JSON.
    """

    frequency_hz: float
    offset: float
    amplitudes: np.ndarray
    phases_rad: np.ndarray
    cos_coefs: np.ndarray
    sin_coefs: np.ndarray
    t_ref_s: float
    residual_rms: float
    n_samples: int
    iterations: int
    amplitudes_u: np.ndarray
    frequency_u_hz: float
    offset_u: float = math.nan
    drift: float | None = None
    drift_u: float | None = None
    drift_check: DriftCheck | None = dataclasses.field(default=None, repr=False)
    phases_u_rad: np.ndarray | None = dataclasses.field(default=None, repr=False)

    @property
    def harmonics(self) -> int:
        """Number of harmonics H in the model (1 = the fundamental only)."""
        return int(self.amplitudes.size)

    @property
    def n_parameters(self) -> int:
        """Parameters of the refined model: offset, H pairs, frequency (and the drift term)."""
        return 2 * self.harmonics + 2 + (0 if self.drift is None else 1)

    def periodic(self) -> SineFit:
        """The same fit without its drift term (itself when it has none): the periodic model."""
        if self.drift is None:
            return self
        return dataclasses.replace(self, drift=None, drift_u=None)

    def evaluate(self, t: Any) -> np.ndarray:
        """The fitted model at times ``t`` (s), in the unit of y; same shape as ``t``."""
        return self._series(t, derivative=False)

    def evaluate_derivative(self, t: Any) -> np.ndarray:
        """The time derivative of the fitted model at ``t`` (s), in unit of y per second."""
        return self._series(t, derivative=True)

    def trend(self, t: Any) -> np.ndarray:
        """The model's non-periodic part at ``t`` (s): ``C + D·(t − t_ref)``, or C without drift."""
        ta = np.asarray(t, dtype=np.float64)
        if self.drift is None:
            return np.full(ta.shape, self.offset)
        return self.offset + self.drift * (ta - self.t_ref_s)

    def _series(self, t: Any, *, derivative: bool) -> np.ndarray:
        ta = np.asarray(t, dtype=np.float64)
        flat = ta.ravel()
        out = np.empty(flat.size)
        w = 2.0 * math.pi * self.frequency_hz
        h = np.arange(1, self.harmonics + 1, dtype=np.float64)
        if derivative:  # d/dt [a cos(hwτ) + b sin(hwτ)] = hw·(b cos − a sin)
            ca = h * w * self.sin_coefs
            cb = -h * w * self.cos_coefs
            const = 0.0
        else:
            ca = np.asarray(self.cos_coefs, dtype=np.float64)
            cb = np.asarray(self.sin_coefs, dtype=np.float64)
            const = self.offset
        for s in range(0, flat.size, _EVAL_CHUNK):
            e = min(flat.size, s + _EVAL_CHUNK)
            out[s:e] = harmonic_series(w * (flat[s:e] - self.t_ref_s), ca, cb, const)
            if self.drift is not None:
                out[s:e] += self.drift if derivative else self.drift * (flat[s:e] - self.t_ref_s)
        return out.reshape(ta.shape)


@dataclass(frozen=True)
class DriftCheck:
    """A fit refitted with a linear drift term at the same frequency (see ``drift_check``).

    Attributes
    ----------
    drift, drift_u : the drift D and its standard uncertainty (unit of y per s).
    offset : C of the refit (unit of y).
    amplitudes, amplitudes_u : A_h and u(A_h) of the refit (unit of y), h = 1..H.
    cos_coefs, sin_coefs : a_h, b_h of the refit (unit of y).
    residual_rms : rms of y − refit (unit of y).
    """

    drift: float
    drift_u: float
    offset: float
    amplitudes: np.ndarray
    amplitudes_u: np.ndarray
    cos_coefs: np.ndarray
    sin_coefs: np.ndarray
    residual_rms: float


def harmonic_series(theta: np.ndarray, ca: np.ndarray, cb: np.ndarray, const: float) -> np.ndarray:
    """``const + Σ_h ca[h-1]·cos(hθ) + cb[h-1]·sin(hθ)`` by the angle-addition recurrence.

    The exact cos/sin are recomputed every 8 harmonics so rounding cannot build up.
    """
    return harmonic_series_many(theta, [(ca, cb, const)])[0]


def harmonic_series_many(
    theta: np.ndarray, series: Sequence[tuple[np.ndarray, np.ndarray, float]]
) -> list[np.ndarray]:
    """:func:`harmonic_series` for several ``(ca, cb, const)`` of one length at the same θ: the
    cos/sin of each harmonic are formed once, each series summed as :func:`harmonic_series` sums
    it (the same numbers to the bit)."""
    c1 = np.cos(theta)
    s1 = np.sin(theta)
    outs = [np.full(theta.shape, const, dtype=np.float64) for _, _, const in series]
    ch, sh = c1, s1
    for k in range(series[0][0].size):
        hk = k + 1
        if hk > 1:
            if hk % 8 == 0:
                ch, sh = np.cos(hk * theta), np.sin(hk * theta)
            else:
                ch, sh = ch * c1 - sh * s1, sh * c1 + ch * s1
        for out, (ca, cb, _) in zip(outs, series, strict=True):
            out += ca[k] * ch
            out += cb[k] * sh
    return outs


def build_sine_fit(
    *,
    frequency_hz: float,
    offset: float,
    cos_coefs: np.ndarray,
    sin_coefs: np.ndarray,
    t_ref_s: float,
    rss: float,
    n_samples: int,
    iterations: int,
    cov_unit: np.ndarray,
    refined: bool,
    drift: float | None = None,
    drift_check: DriftCheck | None = None,
) -> SineFit:
    """Assemble a :class:`SineFit` from the fitted coefficients.

    ``cov_unit`` is ``(JᵀJ)⁻¹`` in the parameter order ``[C, a_1..a_H, b_1..b_H(, D)(, f)]``
    (D when ``drift`` is given); it is scaled by the residual variance ``s² = RSS/(N − p)``
    (IEEE Std 1057-2017, §4.1.3).
    """
    a = np.asarray(cos_coefs, dtype=np.float64)
    b = np.asarray(sin_coefs, dtype=np.float64)
    nh = a.size
    n_par = 2 * nh + 1 + (1 if refined else 0) + (0 if drift is None else 1)
    rss = max(float(rss), 0.0)
    s2 = rss / (n_samples - n_par)
    cov = s2 * cov_unit
    amp = np.hypot(a, b)
    ia = np.arange(1, nh + 1)
    ib = ia + nh
    vaa = cov[ia, ia]
    vbb = cov[ib, ib]
    vab = cov[ia, ib]
    with np.errstate(invalid="ignore", divide="ignore"):
        var_amp = (a * a * vaa + b * b * vbb + 2.0 * a * b * vab) / (amp * amp)
    var_amp = np.where(amp > 0, var_amp, 0.5 * (vaa + vbb))
    amp_u = np.sqrt(np.maximum(var_amp, 0.0))
    # φ = atan2(a, b): ∂φ/∂a = b/A², ∂φ/∂b = −a/A²
    with np.errstate(invalid="ignore", divide="ignore"):
        var_phase = (b * b * vaa + a * a * vbb - 2.0 * a * b * vab) / (amp * amp) ** 2
    phase_u = np.sqrt(np.maximum(np.where(amp > 0, var_phase, np.inf), 0.0))
    f_u = math.sqrt(max(float(cov[-1, -1]), 0.0)) if refined else 0.0
    extra: dict[str, Any] = {}
    if drift is not None:
        i_d = 2 * nh + 1
        extra.update(drift=float(drift), drift_u=math.sqrt(max(float(cov[i_d, i_d]), 0.0)))
    if drift_check is not None:
        extra.update(drift_check=drift_check)
    return SineFit(
        frequency_hz=float(frequency_hz),
        offset=float(offset),
        amplitudes=amp,
        phases_rad=np.arctan2(a, b),
        cos_coefs=a.copy(),
        sin_coefs=b.copy(),
        t_ref_s=float(t_ref_s),
        residual_rms=math.sqrt(rss / n_samples),
        n_samples=int(n_samples),
        iterations=int(iterations),
        amplitudes_u=amp_u,
        frequency_u_hz=f_u,
        offset_u=math.sqrt(max(float(cov[0, 0]), 0.0)),
        phases_u_rad=phase_u,
        **extra,
    )


def build_drift_check(
    *,
    params: np.ndarray,
    offset: float,
    rss: float,
    n_samples: int,
    cov_unit: np.ndarray,
) -> DriftCheck:
    """Assemble a :class:`DriftCheck` from a linear refit ``[C, a_1..a_H, b_1..b_H, D]`` at a fixed
    frequency: ``cov_unit`` = (ΦᵀΦ)⁻¹ of that refit, scaled by ``s² = RSS/(N − 2H − 2)``."""
    nh = (params.size - 2) // 2
    fit = build_sine_fit(
        frequency_hz=1.0,
        offset=offset,
        cos_coefs=params[1 : nh + 1],
        sin_coefs=params[nh + 1 : 2 * nh + 1],
        t_ref_s=0.0,
        rss=rss,
        n_samples=n_samples,
        iterations=0,
        cov_unit=cov_unit,
        refined=False,
        drift=float(params[-1]),
    )
    assert fit.drift is not None and fit.drift_u is not None
    return DriftCheck(
        drift=fit.drift,
        drift_u=fit.drift_u,
        offset=fit.offset,
        amplitudes=fit.amplitudes,
        amplitudes_u=fit.amplitudes_u,
        cos_coefs=fit.cos_coefs,
        sin_coefs=fit.sin_coefs,
        residual_rms=fit.residual_rms,
    )
