"""Plausibility checks of a turntable error budget (GyroWheel study).

The error allocation (eqs. (29)–(34)) bounds each geometric error so that the orientation errors
stay within the requirement; its Monte Carlo check draws tables built to those bounds. Draws
outside the requirement, or an allocation that does not meet it, mean the bounds are not the
conservative ones the proof promises — a sensitivity or requirement entered wrong.
"""

from __future__ import annotations

from collections.abc import Mapping

__all__ = ["budget_warnings"]


def budget_warnings(
    *,
    allocation_within: bool,
    runs: int,
    outside: int,
    max_abs_arcmin: Mapping[str, float],
    requirement_arcmin: Mapping[str, float],
) -> list[str]:
    """Warnings of a turntable budget whose allocation or Monte Carlo check misses the requirement.

    Parameters
    ----------
    allocation_within : bool
        The worst case of the allocated bounds stays within the requirement.
    runs, outside : int
        Monte Carlo draws, and draws with an orientation error beyond the requirement.
    max_abs_arcmin, requirement_arcmin : mapping
        Per component (dpsi, dtheta, dgamma): the largest |error| drawn and the requirement
        (arcmin).

    References
    ----------
    Seed 001 eqs. (29)–(34) (error allocation and its proof) and §5 (Monte Carlo check).
    """
    out = []
    if not allocation_within:
        out.append(
            "the allocated upper bounds do not keep the worst-case orientation error within the "
            "requirement: check the [requirement] values and the error model of the table file"
        )
    if outside > 0:
        over = ", ".join(
            f"{c} {max_abs_arcmin[c]:.4g} > {requirement_arcmin[c]:.4g}′"
            for c in requirement_arcmin
            if c in max_abs_arcmin and max_abs_arcmin[c] > requirement_arcmin[c]
        )
        out.append(
            f"the Monte Carlo check finds {outside} of {runs} tables built to the allocation "
            f"outside the requirement ({over}): the bounds are not conservative — check the "
            "requirement and the errors' distributions in the table file"
        )
    return out
