"""Turntable budget plausibility: Monte Carlo draws outside the requirement are named."""

from __future__ import annotations

from rotacal.turntable.plausibility import budget_warnings

REQ = {"dpsi": 1.0, "dtheta": 0.4, "dgamma": 1.5}


def test_draws_within_say_nothing() -> None:
    maxima = {"dpsi": 0.9, "dtheta": 0.39, "dgamma": 1.0}
    assert (
        budget_warnings(
            allocation_within=True,
            runs=1000,
            outside=0,
            max_abs_arcmin=maxima,
            requirement_arcmin=REQ,
        )
        == []
    )


def test_draws_outside_and_an_allocation_beyond_the_requirement_are_named() -> None:
    maxima = {"dpsi": 0.9, "dtheta": 0.45, "dgamma": 1.0}
    lines = budget_warnings(
        allocation_within=False,
        runs=1000,
        outside=7,
        max_abs_arcmin=maxima,
        requirement_arcmin=REQ,
    )
    assert len(lines) == 2
    assert "worst-case" in lines[0]
    assert "7 of 1000" in lines[1] and "dtheta 0.45 > 0.4′" in lines[1] and "dpsi" not in lines[1]
