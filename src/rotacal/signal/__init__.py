"""rotacal.signal — instrument-independent signal maths: IEEE 1057 sine fits, THD, SNR, the Allan
deviation and its family (MDEV, HDEV, TDEV, TOTDEV), IEEE 952 noise terms, and the detector of
clipped (saturated) signals."""

from typing import TYPE_CHECKING

from rotacal._lazy import attach

if TYPE_CHECKING:
    from rotacal.signal._checks import check_sampling
    from rotacal.signal.allan import (
        AllanDeviation,
        NoiseTerm,
        NoiseTerms,
        adev_confidence_interval,
        edf_overlapping_adev,
        noise_terms,
        overlapping_adev,
    )
    from rotacal.signal.clipping import (
        ClippedSignalError,
        Clipping,
        RailDetector,
        check_clipping,
        find_clipping,
        find_quadrature_clipping,
        quadrature_rail_detectors,
    )
    from rotacal.signal.counter import (
        CounterUnwrapper,
        counts_to_angle_deg,
        infer_register,
        unwrap_counts,
    )
    from rotacal.signal.daq_faults import DaqFaultFinder, DaqFaults, find_daq_faults
    from rotacal.signal.deviations import (
        DEVIATIONS,
        StabilityDeviation,
        deviation_keys,
        edf_deviation,
        longest_cluster,
        stability_deviation,
    )
    from rotacal.signal.deviations_stream import ChunkedDeviation
    from rotacal.signal.readings import CleanReadings, counter_register
    from rotacal.signal.sinefit import (
        DriftCheck,
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
    "DEVIATIONS",
    "AllanDeviation",
    "ChunkedDeviation",
    "CleanReadings",
    "ClippedSignalError",
    "Clipping",
    "CounterUnwrapper",
    "DaqFaultFinder",
    "DaqFaults",
    "DriftCheck",
    "HarmonicFitAccumulator",
    "NoiseTerm",
    "NoiseTerms",
    "RailDetector",
    "SineFit",
    "StabilityDeviation",
    "adev_confidence_interval",
    "check_clipping",
    "check_sampling",
    "counter_register",
    "counts_to_angle_deg",
    "deviation_keys",
    "displacement_amplitudes_from_rate",
    "edf_deviation",
    "edf_overlapping_adev",
    "estimate_frequency",
    "find_clipping",
    "find_daq_faults",
    "find_quadrature_clipping",
    "fit_harmonics",
    "fit_sine_3p",
    "fit_sine_4p",
    "infer_register",
    "longest_cluster",
    "noise_terms",
    "overlapping_adev",
    "quadrature_rail_detectors",
    "snr_db",
    "stability_deviation",
    "thd_percent",
    "thd_standard_uncertainty_percent",
    "unwrap_counts",
]

__getattr__, __dir__ = attach(__name__, __file__, __all__)
