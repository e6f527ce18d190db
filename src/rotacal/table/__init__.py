"""Rotary-table calibrations: sinusoidal motion (Feng et al. 2023), constant rate (Kokuyama et al. 2015)."""

from typing import TYPE_CHECKING

from rotacal._lazy import attach

if TYPE_CHECKING:
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
    from rotacal.table.motion_angle import calibrate_angle_motion, calibrate_count_motion
    from rotacal.table.motion_angle_stream import calibrate_angle_motion_chunked
    from rotacal.table.rate import RateResult, align_deviation, allan_versus_angle, calibrate_rate
    from rotacal.table.rate_angle import calibrate_rate_from_angle, calibrate_rate_from_counts
    from rotacal.table.rate_file import calibrate_rate_file
    from rotacal.table.rate_windows import RateWindows, rate_windows, rate_windows_stream
    from rotacal.table.streaming import (
        calibrate_encoder_motion_chunked,
        calibrate_fog_motion_chunked,
        calibrate_lts_motion_chunked,
        encoder_chunks_from_file,
        fog_chunks_from_file,
        lts_chunks_from_file,
    )

__all__ = [
    "MotionResult",
    "RateResult",
    "RateWindows",
    "SchemeComparison",
    "align_deviation",
    "allan_versus_angle",
    "calibrate_angle_motion",
    "calibrate_angle_motion_chunked",
    "calibrate_count_motion",
    "calibrate_encoder_motion",
    "calibrate_encoder_motion_chunked",
    "calibrate_fog_motion",
    "calibrate_fog_motion_chunked",
    "calibrate_lts_motion",
    "calibrate_lts_motion_chunked",
    "calibrate_rate",
    "calibrate_rate_file",
    "calibrate_rate_from_angle",
    "calibrate_rate_from_counts",
    "compare_schemes",
    "encoder_chunks_from_file",
    "extreme_reversals",
    "fog_chunks_from_file",
    "lts_chunks_from_file",
    "position_error",
    "rate_windows",
    "rate_windows_stream",
]

__getattr__, __dir__ = attach(__name__, __file__, __all__)
