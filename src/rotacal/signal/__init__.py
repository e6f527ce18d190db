"""rotacal.signal — instrument-independent signal maths: IEEE 1057 sine fits, THD, SNR."""

from rotacal.signal._checks import check_sampling
from rotacal.signal.sinefit import (
    HarmonicFitAccumulator,
    SineFit,
    displacement_amplitudes_from_rate,
    estimate_frequency,
    fit_harmonics,
    fit_sine_3p,
    fit_sine_4p,
    snr_db,
    thd_percent,
    thd_standard_uncertainty_percent,
)

__all__ = [
    "HarmonicFitAccumulator",
    "SineFit",
    "check_sampling",
    "displacement_amplitudes_from_rate",
    "estimate_frequency",
    "fit_harmonics",
    "fit_sine_3p",
    "fit_sine_4p",
    "snr_db",
    "thd_percent",
    "thd_standard_uncertainty_percent",
]
