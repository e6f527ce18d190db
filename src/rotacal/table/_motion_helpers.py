"""Small helpers shared by the motion calibration's budgets (private): the fit's ν and s, the
model's curvature, the notes on instrument specifications."""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence

import numpy as np

from rotacal.signal import SineFit
from rotacal.uncertainty import (
    InstrumentSpecs,
)
from rotacal.uncertainty.specs import type_a_note

_P = 0.95
_DEG = "°"
_TIMEBASE = ("timebase.relative_error",)


def fit_dof(fit: SineFit) -> float:
    """ν = N − p of a refined multi-harmonic fit (p = 2H + 2: offset, H pairs, frequency; one
    more with a drift term)."""
    return float(max(fit.n_samples - fit.n_parameters, 1))


def _fit_sigma(fit: SineFit) -> float:
    """s = √(RSS/(N − p)), the residual's standard deviation (unit of the fitted signal)."""
    n = fit.n_samples
    return float(fit.residual_rms * math.sqrt(n / fit_dof(fit)))


def _second_derivative(fit: SineFit, t: np.ndarray) -> np.ndarray:
    """d²y/dt² of the fitted model (unit of y per s²): coefficients −(hω)²·(a_h, b_h) (a drift
    term has none)."""
    w = 2.0 * math.pi * fit.frequency_hz
    hw2 = (w * np.arange(1, fit.harmonics + 1)) ** 2
    d2 = dataclasses.replace(
        fit.periodic(), offset=0.0, cos_coefs=-hw2 * fit.cos_coefs, sin_coefs=-hw2 * fit.sin_coefs
    )
    return np.asarray(d2.evaluate(t))


def _one_period(fit: SineFit, points: int = 4096) -> tuple[np.ndarray, np.ndarray]:
    """(τ, periodic model) over one period of the fundamental, uniformly (τ from t_ref, s)."""
    tau = np.arange(points) / (points * fit.frequency_hz)
    return tau, np.asarray(fit.periodic().evaluate(fit.t_ref_s + tau))


def _stated_mean(specs: InstrumentSpecs | None, key: str) -> float:
    """The stated mean of a specification (0 when not stated): a recognised systematic effect
    the result is corrected for (GUM §3.2.4, the integrator's policy A)."""
    return 0.0 if specs is None else specs.mean(key)


def _spec_notes(specs: InstrumentSpecs | None, keys: Sequence[str]) -> tuple[str, ...]:
    """The "Type A only" note when none of ``keys`` is stated, else the keys not stated."""
    note = type_a_note(specs, keys)
    if note is not None or specs is None:
        return (note,) if note else ()
    missing = [k for k in keys if specs.get(k) is None]
    if not missing:
        return ()
    return (
        f"not stated in {specs.source}: {', '.join(missing)} — its effect is not in this budget.",
    )


def _correction_notes(specs: InstrumentSpecs | None, keys: Sequence[str]) -> tuple[str, ...]:
    """The standard "corrected for the stated mean …" note of every key with a non-zero mean."""
    if specs is None:
        return ()
    out = []
    for key in keys:
        note = specs.correction_note(key)
        if note is None:
            continue
        if key == "encoder.graduation_error_arcsec":
            note += (
                " A reading error common to both extremes cancels in the amplitude (half the "
                "stroke): the correction is 0."
            )
        out.append(note)
    return tuple(out)
