"""Plans of turntable positions for the multiposition drift test, and whether they identify β.

β (the seven drift coefficients) is unique only when the design matrix A has rank 7 (seed 001,
eqs. (4)–(6)): with φ1 and φ2 both multiples of 90° the column ax·ay is zero everywhere, and with
inner angles only at odd multiples of 45° ax² = ay² makes 1, ax² and az² collinear.
:func:`check_multiposition_plan` names what a plan leaves unidentifiable and why;
:func:`multiposition_plan` makes full-factorial plans.

References
----------
Seed 001 (GyroWheel calibration tests), §2.1, eqs. (2)–(6).
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import numpy as np

from rotacal.errors import ConfigError
from rotacal.gyro.multiposition_model import (
    _NAMES,
    _POSITION_DECIMALS,
    _RANK_RTOL,
    _angles,
    _axis,
    drift_design_matrix,
)
from rotacal.results import Result

__all__ = ["MultipositionPlan", "check_multiposition_plan", "multiposition_plan"]


@dataclasses.dataclass(frozen=True)
class MultipositionPlan(Result):
    """A set of turntable positions and how well it identifies the drift coefficients.

    ``condition_number`` is that of A (its columns are dimensionless gravity terms);
    ``u_factors`` are √diag((AᵀA)⁻¹): a coefficient's standard uncertainty per unit noise of one
    reading (deg/h per deg/h), for one reading per position.
    """

    axis: str
    phi1_deg: np.ndarray
    phi2_deg: np.ndarray
    positions: int
    rank: int
    condition_number: float
    u_factors: dict[str, float]
    identifiable: bool
    unidentifiable: tuple[str, ...]


def _distinct_positions(p1: np.ndarray, p2: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Index of the first row of each distinct position (angles mod 360°, to 10⁻⁶°) and the
    position of each row, numbered in the order the positions first appear."""
    scale = 10.0**_POSITION_DECIMALS
    full = round(360.0 * scale)
    k1 = np.round(np.mod(p1, 360.0) * scale).astype(np.int64) % full
    k2 = np.round(np.mod(p2, 360.0) * scale).astype(np.int64) % full
    _, first, inverse = np.unique(k1 * full + k2, return_index=True, return_inverse=True)
    order = np.argsort(first)  # positions in the order they first appear
    rank_of = np.empty_like(order)
    rank_of[order] = np.arange(order.size)
    return first[order], rank_of[np.asarray(inverse).reshape(-1)]


def _analyse(
    a: np.ndarray, names: tuple[str, ...]
) -> tuple[int, float, tuple[str, ...], list[str]]:
    """Rank, condition number, unidentifiable coefficients and a reason for each fault."""
    # A = QR: R (7 × 7) has A's singular values and right singular vectors, at a fraction of
    # the cost of an SVD of the tall A.
    sv, vt = np.linalg.svd(np.linalg.qr(a, mode="r"), full_matrices=False)[1:]
    tol = _RANK_RTOL * sv[0] if sv.size else 0.0
    rank = int(np.count_nonzero(sv > tol))
    cond = float(sv[0] / sv[-1]) if sv[-1] > tol else math.inf
    if rank == len(names):
        return rank, cond, (), []
    null = vt[rank:]  # rows spanning the null space of A
    weight = np.sqrt(np.sum(null * null, axis=0))
    bad = tuple(n for n, wgt in zip(names, weight, strict=True) if wgt > 1e-6)
    reasons = []
    col_norm = np.sqrt(np.sum(a * a, axis=0))
    zero = [names[j] for j in range(len(names)) if col_norm[j] <= 1e-9 * max(col_norm.max(), 1.0)]
    if zero:
        reasons.append(
            f"the column{'s' if len(zero) > 1 else ''} of {', '.join(zero)} "
            f"{'are' if len(zero) > 1 else 'is'} zero at every position"
        )
    rest = [n for n in bad if n not in zero]
    if rest:
        reasons.append(f"only a combination of {', '.join(rest)} is determined")
    return rank, cond, bad, reasons


def check_multiposition_plan(
    phi1_deg: np.ndarray, phi2_deg: np.ndarray, *, axis: str = "x"
) -> MultipositionPlan:
    """Check that a plan of turntable positions identifies every drift coefficient.

    Parameters
    ----------
    phi1_deg, phi2_deg : array
        Outer and inner angles of the planned positions (deg).
    axis : {"x", "y"}
        The gyro axis the plan is for.

    Returns
    -------
    MultipositionPlan
        Rank 7, the condition number of A and the uncertainty factors.

    Raises
    ------
    ConfigError
        Fewer than 7 distinct positions, non-finite angles, or a plan that leaves coefficients
        unidentifiable (named in the message, with the reason).

    References
    ----------
    Seed 001, eqs. (4)–(6): β is unique only when AᵀA is invertible (rank A = 7).
    """
    return _plan(phi1_deg, phi2_deg, axis, ConfigError, "the plan")


def _plan(
    phi1_deg: Any, phi2_deg: Any, axis: str, error: type[Exception], what: str
) -> MultipositionPlan:
    return _plan_core(phi1_deg, phi2_deg, axis, error, what)[0]


def _plan_core(
    phi1_deg: Any, phi2_deg: Any, axis: str, error: type[Exception], what: str
) -> tuple[MultipositionPlan, np.ndarray, np.ndarray, np.ndarray]:
    """The plan's checks; also A, the first row of each position and each row's position."""
    ax_ = _axis(axis)
    names = _NAMES[ax_]
    p1, p2 = _angles(phi1_deg, phi2_deg, error)
    first, pos_of_row = _distinct_positions(p1, p2)
    if first.size < len(names):
        raise error(
            f"{what} has {first.size} distinct turntable position(s): the {len(names)} drift "
            f"coefficients of the {ax_} axis need at least {len(names)}: turn both axes in 45° steps (8 × 8 positions)."
        )
    a = drift_design_matrix(p1, p2, axis=ax_)
    rank, cond, bad, reasons = _analyse(a, names)
    if bad:
        held = [(n, v) for n, v in (("phi1_deg", p1), ("phi2_deg", p2)) if np.ptp(v) == 0]
        reasons = [*(f"{n} is {float(v[0]):g}° in every row" for n, v in held), *reasons]
        raise error(
            f"{what} leaves {', '.join(bad)} of the {ax_} axis unidentifiable ({'; '.join(reasons)}; "
            f"rank {rank} of {len(names)}): add or change positions: both axes in 45° steps "
            "(8 × 8 positions) identify all seven."
        )
    a1 = a[first]
    u = np.sqrt(np.diag(np.linalg.inv(a1.T @ a1)))
    plan = MultipositionPlan(
        axis=ax_,
        phi1_deg=p1,
        phi2_deg=p2,
        positions=int(first.size),
        rank=rank,
        condition_number=cond,
        u_factors=dict(zip(names, (float(v) for v in u), strict=True)),
        identifiable=True,
        unidentifiable=(),
    )
    return plan, a, first, pos_of_row


def multiposition_plan(
    *,
    outer_steps: int = 8,
    inner_steps: int = 8,
    outer_offset_deg: float = 0.0,
    inner_offset_deg: float = 0.0,
    axis: str = "x",
) -> MultipositionPlan:
    """A full-factorial plan: φ1 every 360°/outer_steps, φ2 every 360°/inner_steps.

    The default, both axes every 45° (64 positions), identifies all seven coefficients of either
    axis with a condition number of A of 6.9 (the smallest a uniform grid gives: the columns 1,
    a₁² and az² are correlated by geometry). Coarser grids can fail: 90° steps make ax·ay vanish;
    four inner angles at 45° + k·90° make a₁² and az² collinear with 1. Those raise ConfigError.

    Parameters
    ----------
    outer_steps, inner_steps : int
        Number of equally spaced outer and inner angles (≥ 1).
    outer_offset_deg, inner_offset_deg : float
        Angle of the first position on each axis (deg).
    axis : {"x", "y"}
        The gyro axis to check the plan for.

    Returns
    -------
    MultipositionPlan
        Angles in the order outer-major (the inner axis steps fastest), rank and conditioning.

    References
    ----------
    Seed 001, §2.1 (multiposition tests on a two-axis turntable, eqs. (2)–(6)).
    """
    steps = []
    for name, v in (("outer_steps", outer_steps), ("inner_steps", inner_steps)):
        if isinstance(v, bool) or not float(v).is_integer() or not 1 <= int(v) <= 360:
            raise ConfigError(f"{name} must be an integer from 1 to 360, got {v!r}.")
        steps.append(int(v))
    offs = []
    for name, off in (
        ("outer_offset_deg", outer_offset_deg),
        ("inner_offset_deg", inner_offset_deg),
    ):
        try:
            f = float(off)
        except (TypeError, ValueError):
            raise ConfigError(f"{name} must be a number of degrees, got {off!r}.") from None
        if not math.isfinite(f):
            raise ConfigError(f"{name} must be finite, got {off!r}.")
        offs.append(f)
    outer = offs[0] + np.arange(steps[0]) * (360.0 / steps[0])
    inner = offs[1] + np.arange(steps[1]) * (360.0 / steps[1])
    p1, p2 = np.meshgrid(outer, inner, indexing="ij")
    return _plan(
        p1.ravel(),
        p2.ravel(),
        axis,
        ConfigError,
        f"the plan of {steps[0]} outer × {steps[1]} inner angles",
    )
