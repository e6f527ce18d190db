"""Measurement uncertainty shared by every calibration: the GUM law of propagation (JCGM 100),
the Monte Carlo method (JCGM 101), distributions of input quantities, uncertainty budgets and the
rounding of reported results (ILAC-P14).

Validated on the worked examples of JCGM 100 Annex H, JCGM 101 §9 and JCGM 102 (see the tests and
``../shared/UNCERTAINTY-EXAMPLES.md``).
"""

from typing import TYPE_CHECKING

from rotacal._lazy import attach

if TYPE_CHECKING:
    from rotacal.uncertainty.budget import (
        BudgetRow,
        UncertaintyBudget,
        result_keys,
        round_ilac,
        uncertainty_keys,
    )
    from rotacal.uncertainty.correlation import correlation_matrix
    from rotacal.uncertainty.coverage import (
        coverage_factor,
        prefetch_quantiles,
        welch_satterthwaite,
    )
    from rotacal.uncertainty.distributions import (
        Arcsine,
        Constant,
        CurvilinearTrapezoid,
        Distribution,
        MultivariateNormal,
        Normal,
        Rectangular,
        StudentT,
        Trapezoidal,
        Triangular,
        distribution_from_spec,
    )
    from rotacal.uncertainty.gum import GUMResult, Input, propagate
    from rotacal.uncertainty.linear_fit import LinearFit, linear_fit_uncertainty
    from rotacal.uncertainty.montecarlo import (
        MonteCarloResult,
        coverage_interval,
        monte_carlo,
        numerical_tolerance,
        validate_gum,
    )
    from rotacal.uncertainty.specs import KNOWN_SPECS, InstrumentSpecs, load_specs

__all__ = [
    "KNOWN_SPECS",
    "Arcsine",
    "BudgetRow",
    "Constant",
    "CurvilinearTrapezoid",
    "Distribution",
    "GUMResult",
    "Input",
    "InstrumentSpecs",
    "LinearFit",
    "MonteCarloResult",
    "MultivariateNormal",
    "Normal",
    "Rectangular",
    "StudentT",
    "Trapezoidal",
    "Triangular",
    "UncertaintyBudget",
    "correlation_matrix",
    "coverage_factor",
    "coverage_interval",
    "distribution_from_spec",
    "linear_fit_uncertainty",
    "load_specs",
    "monte_carlo",
    "numerical_tolerance",
    "prefetch_quantiles",
    "propagate",
    "result_keys",
    "round_ilac",
    "uncertainty_keys",
    "validate_gum",
    "welch_satterthwaite",
]

__getattr__, __dir__ = attach(__name__, __file__, __all__)
