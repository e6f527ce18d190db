"""rotacal.encoder — angle from sensors: quadrature demodulation and reversals (seed 000)."""

from rotacal.encoder.quadrature import (
    Demodulation,
    PhaseState,
    QuadratureCorrection,
    Reversals,
    SubdivisionWarning,
    angle_deg,
    correct_quadrature,
    demodulate,
    find_reversals,
    fit_quadrature_correction,
    intercept_periods,
    reversing_subintervals,
    rotation_direction,
    subintervals,
    unwrapped_phase,
)

__all__ = [
    "Demodulation",
    "PhaseState",
    "QuadratureCorrection",
    "Reversals",
    "SubdivisionWarning",
    "angle_deg",
    "correct_quadrature",
    "demodulate",
    "find_reversals",
    "fit_quadrature_correction",
    "intercept_periods",
    "reversing_subintervals",
    "rotation_direction",
    "subintervals",
    "unwrapped_phase",
]
