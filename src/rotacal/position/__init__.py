"""rotacal.position — position accuracy of an indexing table against a reference (ISO 230-2):
the error curve, its harmonics, repeatability and reversal, with a reference encoder (optionally
self-calibrated, Kokuyama et al. 2015) or an autocollimator on a polygon (closure
cross-calibration)."""

from typing import TYPE_CHECKING

from rotacal._lazy import attach

if TYPE_CHECKING:
    from rotacal.position.accuracy import DEFAULT_HARMONICS, PositionAccuracy, position_accuracy
    from rotacal.position.arrange import Approaches, arrange_approaches
    from rotacal.position.harmonics import HarmonicFit, fit_harmonics
    from rotacal.position.iso230 import AXIS_VALUES, AxisStatistics, axis_statistics
    from rotacal.position.polygon import PolygonSeparation, separate_polygon, unresolved_orders
    from rotacal.position.reference import SelfcalCorrection, selfcal_correction

__all__ = [
    "AXIS_VALUES",
    "DEFAULT_HARMONICS",
    "Approaches",
    "AxisStatistics",
    "HarmonicFit",
    "PolygonSeparation",
    "PositionAccuracy",
    "SelfcalCorrection",
    "arrange_approaches",
    "axis_statistics",
    "fit_harmonics",
    "position_accuracy",
    "selfcal_correction",
    "separate_polygon",
    "unresolved_orders",
]

__getattr__, __dir__ = attach(__name__, __file__, __all__)
