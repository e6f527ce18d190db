"""Batches: many calibration plans certified as tasks on Dask distributed, resumable, into the
records store (INTERFACE.md "Batches"). See :func:`run_batch`."""

from __future__ import annotations

from typing import TYPE_CHECKING

from rotacal._lazy import attach

if TYPE_CHECKING:
    from .plans import expected_plan_sha256, find_plans
    from .run import BatchInterruptedError, BatchResult, PlanOutcome, run_batch

__all__ = [
    "BatchInterruptedError",
    "BatchResult",
    "PlanOutcome",
    "expected_plan_sha256",
    "find_plans",
    "run_batch",
]

__getattr__, __dir__ = attach(__name__, __file__, __all__)
