"""rotacal.encoder — angle from sensors: quadrature demodulation and reversals (Feng et al. 2023), pulse
timing and the self-calibration of a multi-head encoder (Kokuyama et al. 2015)."""

from typing import TYPE_CHECKING

from rotacal._lazy import attach

if TYPE_CHECKING:
    from rotacal.encoder.pulses import (
        HeadPairing,
        check_pulse_times,
        head_columns,
        pair_heads,
        pulse_angle_deg,
        pulse_rate,
        whole_revolution_rate,
    )
    from rotacal.encoder.quadrature import (
        Demodulation,
        HysteresisRule,
        PhaseState,
        QuadratureCorrection,
        ReversalPlan,
        Reversals,
        SubdivisionWarning,
        angle_deg,
        correct_quadrature,
        demodulate,
        find_reversals,
        fit_quadrature_correction,
        hysteresis_stride,
        intercept_periods,
        plan_reversals,
        reversal_point_in_window,
        reversal_window,
        reversing_subintervals,
        rotation_direction,
        subinterval_transitions,
        subintervals,
        unwrapped_phase,
    )
    from rotacal.encoder.selfcal import (
        SelfCalibration,
        head_shifts,
        self_calibrate,
        undetectable_orders,
    )
    from rotacal.encoder.selfcal_stream import self_calibrate_chunked

__all__ = [
    "Demodulation",
    "HeadPairing",
    "HysteresisRule",
    "PhaseState",
    "QuadratureCorrection",
    "ReversalPlan",
    "Reversals",
    "SelfCalibration",
    "SubdivisionWarning",
    "angle_deg",
    "check_pulse_times",
    "correct_quadrature",
    "demodulate",
    "find_reversals",
    "fit_quadrature_correction",
    "head_columns",
    "head_shifts",
    "hysteresis_stride",
    "intercept_periods",
    "pair_heads",
    "plan_reversals",
    "pulse_angle_deg",
    "pulse_rate",
    "reversal_point_in_window",
    "reversal_window",
    "reversing_subintervals",
    "rotation_direction",
    "self_calibrate",
    "self_calibrate_chunked",
    "subinterval_transitions",
    "subintervals",
    "undetectable_orders",
    "unwrapped_phase",
    "whole_revolution_rate",
]

__getattr__, __dir__ = attach(__name__, __file__, __all__)
