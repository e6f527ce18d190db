"""rotacal.gyro — gyroscope calibrations on the table: scale factor and nonlinearity (Kokuyama et al. 2015),
3-axis calibration (robot-manipulator study 2023) and calibration from rotations through a known angle (Ferraris),
multiposition drift coefficients (GyroWheel study), noise terms (IEEE Std 952), frequency response on a
sinusoidal table (IEEE Std 1057 sine fits, second-order model)."""

from typing import TYPE_CHECKING

from rotacal._lazy import attach

if TYPE_CHECKING:
    from rotacal.gyro.accel_triad import (
        ACCEL_OUTPUT_COLUMNS,
        AccelTriadCalibration,
        calibrate_accel_triad,
        normal_gravity,
    )
    from rotacal.gyro.ferraris import FerrarisGyroCalibration, calibrate_ferraris
    from rotacal.gyro.frequency_model import (
        SecondOrderFit,
        bandwidth_from_model,
        fit_second_order,
        second_order_response,
    )
    from rotacal.gyro.frequency_response import (
        FrequencyPoint,
        FrequencyResponse,
        calibrate_frequency_response,
        response_at_frequency,
    )
    from rotacal.gyro.multiposition import (
        EARTH_RATE_DEG_H,
        MultipositionPlan,
        MultipositionResult,
        calibrate_multiposition,
        check_multiposition_plan,
        coefficient_names,
        drift_design_matrix,
        earth_rate_and_gravity,
        multiposition_plan,
    )
    from rotacal.gyro.noise import GyroNoise, gyro_noise, gyro_noise_from_angle
    from rotacal.gyro.noise_fit import NoiseFit, avar_covariance, fit_noise_terms
    from rotacal.gyro.plateaus import Plateau, PlateauSearch, find_plateaus
    from rotacal.gyro.plateaus_stream import find_plateaus_chunked, log_chunks
    from rotacal.gyro.rotation_sections import sections_from_labels
    from rotacal.gyro.rotations import (
        RotationCalibration,
        calibrate_triad_rotations,
        ferraris_sections,
    )
    from rotacal.gyro.scale_factor import (
        REQUIREMENTS,
        ScaleFactorResult,
        calibrate_scale_factor,
        evaluate_requirement,
        resolve_requirement,
    )
    from rotacal.gyro.scale_factor_log import (
        LogScaleFactorResult,
        calibrate_scale_factor_log,
        calibrate_scale_factor_log_chunked,
    )
    from rotacal.gyro.scale_factor_stream import (
        calibrate_scale_factor_chunked,
        scale_factor_chunks,
    )
    from rotacal.gyro.sf_items import scale_factor_repeatability, signed_scale_factors
    from rotacal.gyro.sf_temperature import temperature_coefficients
    from rotacal.gyro.threshold import SmallStepResult, small_step_test
    from rotacal.gyro.triad import (
        RATE_COLUMNS,
        TRIAD_OUTPUT_COLUMNS,
        TriadPlanCheck,
        TriadResult,
        apply_triad_calibration,
        calibrate_triad,
        calibrate_triad_columns,
        decompose_scale_misalignment,
        triad_plan,
        triad_plan_check,
    )
    from rotacal.gyro.triad_log import TriadLogResult, TriadRun, calibrate_triad_log, split_runs

__all__ = [
    "ACCEL_OUTPUT_COLUMNS",
    "EARTH_RATE_DEG_H",
    "RATE_COLUMNS",
    "REQUIREMENTS",
    "TRIAD_OUTPUT_COLUMNS",
    "AccelTriadCalibration",
    "FerrarisGyroCalibration",
    "FrequencyPoint",
    "FrequencyResponse",
    "GyroNoise",
    "LogScaleFactorResult",
    "MultipositionPlan",
    "MultipositionResult",
    "NoiseFit",
    "Plateau",
    "PlateauSearch",
    "RotationCalibration",
    "ScaleFactorResult",
    "SecondOrderFit",
    "SmallStepResult",
    "TriadLogResult",
    "TriadPlanCheck",
    "TriadResult",
    "TriadRun",
    "apply_triad_calibration",
    "avar_covariance",
    "bandwidth_from_model",
    "calibrate_accel_triad",
    "calibrate_ferraris",
    "calibrate_frequency_response",
    "calibrate_multiposition",
    "calibrate_scale_factor",
    "calibrate_scale_factor_chunked",
    "calibrate_scale_factor_log",
    "calibrate_scale_factor_log_chunked",
    "calibrate_triad",
    "calibrate_triad_columns",
    "calibrate_triad_log",
    "calibrate_triad_rotations",
    "check_multiposition_plan",
    "coefficient_names",
    "decompose_scale_misalignment",
    "drift_design_matrix",
    "earth_rate_and_gravity",
    "evaluate_requirement",
    "ferraris_sections",
    "find_plateaus",
    "find_plateaus_chunked",
    "fit_noise_terms",
    "fit_second_order",
    "gyro_noise",
    "gyro_noise_from_angle",
    "log_chunks",
    "multiposition_plan",
    "normal_gravity",
    "resolve_requirement",
    "response_at_frequency",
    "scale_factor_chunks",
    "scale_factor_repeatability",
    "second_order_response",
    "sections_from_labels",
    "signed_scale_factors",
    "small_step_test",
    "split_runs",
    "temperature_coefficients",
    "triad_plan",
    "triad_plan_check",
]

__getattr__, __dir__ = attach(__name__, __file__, __all__)
