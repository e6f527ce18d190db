"""Plausibility check of a multi-head self-calibration (Kokuyama et al. 2015, equal-division averaging).

The heads must tell one story: the deviation curve fitted to the head differences leaves a closure
residual (noise, rate changes within a pitch) that the revolution-to-revolution repeatability of
the curve accounts for. A residual far beyond it means the heads disagree — a head column
misnumbered or swapped, a head that misses pulses.
"""

from __future__ import annotations

import math

__all__ = ["HEAD_DISAGREEMENT_LIMIT", "selfcal_warnings"]

#: Closure residual over repeatability·√n beyond which the heads disagree. On the twin (12 and 4
#: heads, 2 … 5 revolutions) the ratio is 1.6–2.0; two swapped heads make it several hundred.
HEAD_DISAGREEMENT_LIMIT = 10.0


def selfcal_warnings(
    *, closure_residual_rms_arcsec: float, repeatability_rms_arcsec: float | None, heads: int
) -> list[str]:
    """The warning for heads that disagree beyond their repeatability (empty otherwise).

    Each point of a single-revolution curve averages the n head differences, so its scatter
    between revolutions (the repeatability, arcsec) is about the closure residual per head
    difference over √n; the ratio closure/(repeatability·√n) is of order 1 when the heads agree.

    Parameters
    ----------
    closure_residual_rms_arcsec : float
        rms of what the fitted curve leaves in the head differences (arcsec).
    repeatability_rms_arcsec : float or None
        Spread of the single-revolution curves about their mean (arcsec); None with one
        revolution (no check then).
    heads : int
        Number of heads n.

    References
    ----------
    Seed 004 §2 (equal-division averaged self-calibration; the head differences).
    """
    rep = repeatability_rms_arcsec
    if rep is None or not rep > 0 or heads < 2 or not math.isfinite(closure_residual_rms_arcsec):
        return []
    ratio = closure_residual_rms_arcsec / (rep * math.sqrt(heads))
    if ratio <= HEAD_DISAGREEMENT_LIMIT:
        return []
    return [
        f"the heads disagree: the closure residual {closure_residual_rms_arcsec:.3g}″ rms is "
        f"{ratio:.3g} times what the revolution-to-revolution repeatability ({rep:.3g}″ over "
        f"√{heads} heads) explains (limit {HEAD_DISAGREEMENT_LIMIT:g}) — a head column "
        "misnumbered or swapped, or a head that misses pulses; check the order of head_0 … "
        f"head_{heads - 1} (equally spaced, in the sense of rotation)"
    ]
