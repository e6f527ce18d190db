"""Rotary-table calibrations: sinusoidal motion (seed 000)."""

from rotacal.table.motion import (
    MotionResult,
    SchemeComparison,
    calibrate_encoder_motion,
    calibrate_fog_motion,
    calibrate_lts_motion,
    compare_schemes,
    extreme_reversals,
    position_error,
)

__all__ = [
    "MotionResult",
    "SchemeComparison",
    "calibrate_encoder_motion",
    "calibrate_fog_motion",
    "calibrate_lts_motion",
    "compare_schemes",
    "extreme_reversals",
    "position_error",
]
