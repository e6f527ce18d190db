"""The numbers seed 001 prints, and rotacal's computations that stand beside them.

One place for the paper's Table 4, eq. (16) and Figure 8 (the report, the benchmark and the budget
import them from here; tests keep their own typed copies as independent truth), and
:func:`reproduce_seed001`, which computes what rotacal gets for the same questions.

References
----------
Seed 001 (``../shared/seeds/001_4a387eb674e238f2.txt``): eq. (16), Figure 8, Table 4, Lemma 1.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from rotacal.turntable.model import ARCMIN_PER_RAD, COMPONENTS, SEED_ERROR_NAMES, Turntable

__all__ = [
    "CHI",
    "EQ16_DEG",
    "EQ16_DEG_H",
    "FIGURE8",
    "TABLE4_ARCMIN",
    "is_seed_table",
    "reproduce_seed001",
]

#: The seed's error vector χ of eq. (25) (the angular errors; η, a translation, is left out).
CHI: tuple[str, ...] = tuple(n for n in SEED_ERROR_NAMES if n != "eta")
#: Seed 001, Table 4: the paper's allocated upper bounds (arcmin), χ order of eq. (25).
TABLE4_ARCMIN: dict[str, float] = {
    "phi_y1": 0.4235,
    "phi_z2": 0.7800,
    "alpha_x1": 0.4234,
    "alpha_z1": 0.7800,
    "alpha_x2": 0.2825,
    "alpha_y2": 0.2824,
    "eps_x": 0.4234,
    "eps_y": 0.4233,
}
#: Seed 001, eq. (16): the orientation requirement (deg, each component) ...
EQ16_DEG = 0.027
#: ... for a calibration accuracy of 0.01 °/h.
EQ16_DEG_H = 0.01
#: Seed 001, Figure 8: the averaged sensitivities of the |cos φ2| and |sin φ2| terms, and the
#: slightly larger values it also prints for some of the same terms.
FIGURE8: dict[str, float] = {"cos": 0.6476, "sin": 0.5365, "cos_alt": 0.6481, "sin_alt": 0.5372}

#: Latitudes (deg) and plans (outer × inner steps) over which eq. (16) is recomputed.
_SCAN_LATITUDES = (0.0, 15.0, 30.0, 45.0, 60.0, 75.0, 89.0)
_SCAN_PLANS = ((8, 8), (12, 12))


def is_seed_table(table: Turntable) -> bool:
    """True when the table's angular errors are seed 001's χ (the paper's numbers then apply)."""
    return tuple(table.angular_error_names) == CHI


def reproduce_seed001(
    table: Turntable, requirement_rad: Mapping[str, float], *, required_deg_h: float = EQ16_DEG_H
) -> dict[str, Any]:
    """rotacal's answers to the questions behind eq. (16) and Table 4.

    - ``table4_worst_case``: Table 4's bounds under rotacal's Lemma 1 check (linear bound and full
      model, arcmin): does the paper's allocation meet its own requirement, and with what margin?
    - ``eq16_scan``: the equal orientation limit for ``required_deg_h`` recomputed over latitudes
      0–89° and two plans (8 × 8 and 12 × 12 positions), for both readings of eq. (13) — the paper
      states neither plan nor latitude, so the scan shows whether they could explain its 0.027°.

    Parameters
    ----------
    table : Turntable
        The seed's table (see :func:`is_seed_table`).
    requirement_rad : mapping
        The orientation requirement (rad) per component, for the Table 4 check.
    required_deg_h : float
        Calibration accuracy of eq. (16) (°/h).

    Returns
    -------
    dict
        ``table4_worst_case`` {component: {"linear_arcmin", "full_arcmin", "requirement_arcmin"}},
        ``eq16_scan`` {method: {"min_deg", "max_deg", "latitudes_deg", "plans"}}.

    References
    ----------
    Seed 001, eq. (16), Table 4, Lemma 1.
    """
    from rotacal.gyro.multiposition import multiposition_plan
    from rotacal.turntable.allocation import worst_case
    from rotacal.turntable.calibration import METHODS, orientation_requirement

    t4 = {n: v / ARCMIN_PER_RAD for n, v in TABLE4_ARCMIN.items()}
    wc = worst_case(table, t4, dict(requirement_rad))
    table4 = {
        c: {
            "linear_arcmin": float(wc[c]["linear_rad"]) * ARCMIN_PER_RAD,
            "full_arcmin": float(wc[c]["full_rad"]) * ARCMIN_PER_RAD,
            "requirement_arcmin": float(requirement_rad[c]) * ARCMIN_PER_RAD,
        }
        for c in COMPONENTS
    }
    scan: dict[str, Any] = {}
    for method in METHODS:
        limits = []
        for outer, inner in _SCAN_PLANS:
            plan = multiposition_plan(outer_steps=outer, inner_steps=inner)
            for lat in _SCAN_LATITUDES:
                req = orientation_requirement(
                    required_deg_h,
                    phi1_deg=plan.phi1_deg,
                    phi2_deg=plan.phi2_deg,
                    latitude_deg=lat,
                    method=method,
                )
                limits.append(req.equal_limit_deg)
        scan[method] = {
            "min_deg": float(np.min(limits)),
            "max_deg": float(np.max(limits)),
            "latitudes_deg": list(_SCAN_LATITUDES),
            "plans": [f"{o} × {i}" for o, i in _SCAN_PLANS],
        }
    return {"table4_worst_case": table4, "eq16_scan": scan}
