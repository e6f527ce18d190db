"""Turntable geometric errors (GyroWheel study): the error model by homogeneous transforms, sensitivities,
error allocation with its Monte Carlo check, and what orientation errors do to a multiposition
gyro calibration.

Start from :func:`seed_table` (the paper's two-axis table) or :func:`load_turntable` (a TOML
description of any serial table) and :func:`turntable_budget` (what ``rotacal turntable budget``
runs). :func:`identify_turntable` is the inverse (``rotacal turntable identify``): the errors
from orientation errors measured at many positions. :func:`orientation_error` is the model of the GyroWheel study's table, eqs. (17)–(24), radians in and out.
"""

from rotacal.turntable.allocation import (
    Allocation,
    MonteCarloCheck,
    allocate,
    monte_carlo_check,
    worst_case,
)
from rotacal.turntable.budget import (
    TurntableBudget,
    budget_allocation,
    calibration_check,
    turntable_budget,
)
from rotacal.turntable.calibration import (
    OrientationRequirement,
    orientation_matrix,
    orientation_requirement,
    rate_error_surfaces,
    rate_sensing_error,
    rate_sensing_error_from_rotation,
)
from rotacal.turntable.config import load_turntable, seed_table, seed_table_toml
from rotacal.turntable.identify import TurntableIdentification, identify_turntable
from rotacal.turntable.model import (
    COMPONENTS,
    ErrorSpec,
    Link,
    Turntable,
    orientation_error,
)

__all__ = [
    "COMPONENTS",
    "Allocation",
    "ErrorSpec",
    "Link",
    "MonteCarloCheck",
    "OrientationRequirement",
    "Turntable",
    "TurntableBudget",
    "TurntableIdentification",
    "allocate",
    "budget_allocation",
    "calibration_check",
    "identify_turntable",
    "load_turntable",
    "monte_carlo_check",
    "orientation_error",
    "orientation_matrix",
    "orientation_requirement",
    "rate_error_surfaces",
    "rate_sensing_error",
    "rate_sensing_error_from_rotation",
    "seed_table",
    "seed_table_toml",
    "turntable_budget",
    "worst_case",
]
