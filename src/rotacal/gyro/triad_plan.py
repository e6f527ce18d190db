"""The test plan of the 3-axis gyro calibration: reference rates, and whether they identify K and b.

The modified six-position test (robot-manipulator study 2023, Table 2 and Fig. 5) rotates the DUT
about each axis at several rates in both directions; the model u = K·ω + b is identifiable when
the design matrix A of eq. (5) (the reference rates and a row of ones) has full rank 4. This
module makes such a plan (:func:`triad_plan`) and checks one (:func:`triad_plan_check`) before
any capture is taken; :mod:`rotacal.gyro.triad` fits the capture.

References
----------
Calibration Method of MEMS Gyroscopes Using a Robot Manipulator. IEEE Aerospace and Electronic
Systems Magazine, March 2023: eqs. (4), (5), Table 2, Fig. 5.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from rotacal.columns import RATE_COLUMNS
from rotacal.errors import CaptureError, ConfigError
from rotacal.results import Result

__all__ = [
    "SEED_RATES_DEG_S",
    "TriadPlanCheck",
    "triad_plan",
    "triad_plan_check",
]

#: The rates of the robot-manipulator study (2023), Table 2 (°/s).
SEED_RATES_DEG_S = (6.0, 18.0, 30.0, 60.0, 90.0)

_AXES = "xyz"
_COEF_NAMES = ("wx", "wy", "wz", "bias")
#: Relative tolerance of the numerical rank of the column-equilibrated design.
_RANK_RTOL = 1e-9


def _as_triplet(name: str, columns: Sequence[str], values: Any) -> np.ndarray:
    """(n, 3) float64 array; CaptureError on a wrong shape or a non-finite value."""
    arr = np.asarray(values, dtype=np.float64)
    if arr.ndim != 2 or arr.shape[1] != 3:
        raise CaptureError(
            f"{name} must be an (n, 3) array (columns {', '.join(columns)}); got shape {arr.shape}."
        )
    finite = np.isfinite(arr)
    if not finite.all():
        row, col = (int(i) for i in np.argwhere(~finite)[0])
        raise CaptureError(
            f"column {columns[col]} has a non-finite value ({arr[row, col]!r}) at row {row}; "
            "remove or repair that row."
        )
    return arr


def _design(omega: np.ndarray) -> np.ndarray:
    """Aᵀ of the robot-manipulator study's eq. (5): rows [ωx, ωy, ωz, 1] (°/s, °/s, °/s, 1)."""
    return np.column_stack([omega, np.ones(omega.shape[0])])


def triad_plan(
    rates_deg_s: Sequence[float] = SEED_RATES_DEG_S,
    *,
    axes: str = "xyz",
    both_directions: bool = True,
    samples_per_point: int = 1,
    include_static: bool = False,
) -> np.ndarray:
    """Reference rates of the modified six-position test: rates × axes × both directions.

    Parameters
    ----------
    rates_deg_s : sequence of float
        Rate magnitudes (°/s); the robot-manipulator study's Table 2 uses 6, 18, 30, 60, 90.
    axes : str
        Rotation axes in order, any of ``"xyz"`` (robot-manipulator study 2023, Fig. 5: all three).
    both_directions : bool
        Add each rate with a negative sign too (the robot-manipulator study's six positions: ± each axis).
    samples_per_point : int
        Rows per rate point (repeat each point, as a capture of that many samples would).
    include_static : bool
        Add one point at rest (0 °/s) at the start.

    Returns
    -------
    ndarray, (n, 3)
        Reference rate ω in the DUT's nominal axes (°/s), one row per sample, in test order: for
        each axis, each rate, +rate then −rate.

    References
    ----------
    Calibration Method of MEMS Gyroscopes Using a Robot Manipulator, IEEE A&E Systems Magazine,
    March 2023, Table 2, Fig. 5.
    """
    rates = np.asarray(rates_deg_s, dtype=float).ravel()
    if rates.size == 0 or not np.isfinite(rates).all() or np.any(rates <= 0):
        raise ConfigError(
            f"rates_deg_s must be positive, finite rate magnitudes (°/s); got {rates_deg_s!r}."
        )
    if not axes or any(a not in _AXES for a in axes) or len(set(axes)) != len(axes):
        raise ConfigError(f"axes must be distinct letters from 'xyz', got {axes!r}.")
    if isinstance(samples_per_point, bool) or int(samples_per_point) != samples_per_point:
        raise ConfigError(
            f"samples_per_point must be a positive integer, got {samples_per_point!r}."
        )
    if samples_per_point < 1:
        raise ConfigError(
            f"samples_per_point must be a positive integer, got {samples_per_point!r}."
        )
    signs = np.array([1.0, -1.0]) if both_directions else np.array([1.0])
    mags = (rates[:, None] * signs[None, :]).ravel()  # +r1, −r1, +r2, …
    blocks = []
    if include_static:
        blocks.append(np.zeros((1, 3)))
    for a in axes:
        pts = np.zeros((mags.size, 3))
        pts[:, _AXES.index(a)] = mags
        blocks.append(pts)
    points = np.vstack(blocks)
    return np.repeat(points, int(samples_per_point), axis=0)


@dataclasses.dataclass(frozen=True)
class TriadPlanCheck(Result):
    """Whether a plan of reference rates makes every coefficient of u = K·ω + b identifiable.

    Attributes
    ----------
    rows : int
        Rows of the plan (samples).
    points : int
        Distinct reference-rate vectors.
    rank : int
        Numerical rank of A (robot-manipulator study 2023, eq. (5), 4×n); 4 is full.
    condition_number : float
        σ_max/σ_min of A as the robot-manipulator study (2023) builds it (rates in °/s, a row of ones); inf when rank < 4.
    condition_number_scaled : float
        The same after scaling each row of A to unit rms: what limits the precision, independent
        of units; inf when rank < 4.
    identifiable : bool
        All 12 coefficients (9 of K, 3 of b) are determined by the plan.
    unidentifiable : tuple of str
        Coefficients the plan leaves undetermined (``K_xy``: output x per rate about y; ``b_x``).
    noise_gain : dict of str to float
        u(coefficient) per unit noise of one row: u(K_iy) = σ_i·noise_gain["wy"] (1/(°/s)),
        u(b_i) = σ_i·noise_gain["bias"] (1), for white noise σ_i of output i; None when not
        identifiable.
    advice : str
        What to add to the plan when it is not identifiable; empty otherwise.
    """

    rows: int
    points: int
    rank: int
    condition_number: float
    condition_number_scaled: float
    identifiable: bool
    unidentifiable: tuple[str, ...]
    noise_gain: dict[str, float] | None
    advice: str = ""


def _plan_advice(omega: np.ndarray, bias_lost: bool) -> str:
    tips = []
    for j, a in enumerate(_AXES):
        col = omega[:, j]
        if not np.any(col):
            tips.append(f"there is no rotation about {a}")
        elif np.ptp(col) == 0:
            tips.append(f"every row has the same rate about {a} ({col[0]:g} °/s)")
    if tips:
        return (
            "; ".join(tips) + ": add rotations about every axis at two or more rates (both signs)"
        )
    if bias_lost:
        return (
            "the rates and the constant term are linearly dependent, so the biases cannot be "
            "told from the scale factors: add each rate in both directions, or a point at rest"
        )
    return (
        "the reference rates are linearly dependent (for example rotations about one oblique "
        "axis only): rotate about each of x, y and z separately"
    )


def _small_r(x: np.ndarray) -> np.ndarray:
    """The 4×4 triangular factor of x (n×4; zero rows added when n < 4)."""
    if x.shape[0] < x.shape[1]:
        x = np.vstack([x, np.zeros((x.shape[1] - x.shape[0], x.shape[1]))])
    return np.asarray(np.linalg.qr(x, mode="r"))


def _check_plan(omega: np.ndarray) -> TriadPlanCheck:
    x = _design(omega)
    n = x.shape[0]
    points = int(np.unique(omega, axis=0).shape[0]) if n else 0
    scale = np.sqrt(np.mean(x**2, axis=0))
    scale[scale == 0] = 1.0
    xs = x / scale
    # The SVD of the 4×4 R of a QR has the singular values and right vectors of the n×4 matrix.
    _, pad, vt = np.linalg.svd(_small_r(xs))
    sv = np.linalg.svd(_small_r(x), compute_uv=False)
    tol = _RANK_RTOL * max(float(pad[0]), 1.0)
    rank = int(np.count_nonzero(pad > tol))
    if rank < 4:
        null = vt[rank:]
        dead = np.linalg.norm(null, axis=0) > 1e-6  # coefficient j touches the null space
        names = []
        for j in np.flatnonzero(dead):
            if j < 3:
                names += [f"K_{i}{_AXES[j]}" for i in _AXES]
            else:
                names += [f"b_{i}" for i in _AXES]
        names_sorted = tuple(sorted(names, key=lambda s: (s[0] == "b", s[-1], s)))
        return TriadPlanCheck(
            rows=n,
            points=points,
            rank=rank,
            condition_number=math.inf,
            condition_number_scaled=math.inf,
            identifiable=False,
            unidentifiable=names_sorted,
            noise_gain=None,
            advice=_plan_advice(omega, bool(dead[3])),
        )
    gain = np.sqrt(np.diag(np.linalg.inv(x.T @ x)))
    return TriadPlanCheck(
        rows=n,
        points=points,
        rank=rank,
        condition_number=float(sv[0] / sv[-1]),
        condition_number_scaled=float(pad[0] / pad[-1]),
        identifiable=True,
        unidentifiable=(),
        noise_gain={name: float(g) for name, g in zip(_COEF_NAMES, gain, strict=True)},
    )


def triad_plan_check(omega_deg_s: Any, *, strict: bool = True) -> TriadPlanCheck:
    """Rank and condition number of A for a plan; are all 9 + 3 coefficients identifiable?

    The model's design matrix A (robot-manipulator study 2023, eq. (5)) has the reference rates and a row of ones. A
    coefficient is identifiable when its unit vector lies in the row space of Aᵀ (orthogonal to
    the null space): rotations about x only, for instance, leave every K_iy and K_iz undetermined,
    and a single rate about an axis (without the opposite sign or a second rate) confounds that
    axis's scale factors with the biases.

    Parameters
    ----------
    omega_deg_s : array_like, (n, 3)
        Reference rates (°/s) of the planned rows, columns ωx, ωy, ωz in the DUT's nominal axes.
    strict : bool
        Raise :class:`ConfigError` naming the unidentifiable coefficients (default); with False
        return the check with ``identifiable=False`` instead.

    Returns
    -------
    TriadPlanCheck
        Rank, condition numbers (dimensionless), identifiability, noise gains (see the class).

    Raises
    ------
    ConfigError
        The plan leaves coefficients undetermined (``strict``), or it is not an (n, 3) array of
        finite rates.

    References
    ----------
    Calibration Method of MEMS Gyroscopes Using a Robot Manipulator, IEEE A&E Systems Magazine,
    March 2023, eqs. (4)–(5).
    """
    try:
        omega = _as_triplet("omega_deg_s", RATE_COLUMNS, omega_deg_s)
    except CaptureError as e:
        raise ConfigError(str(e)) from None
    if omega.shape[0] == 0:
        raise ConfigError("the plan is empty: give at least one row of reference rates.")
    check = _check_plan(omega)
    if strict and not check.identifiable:
        raise ConfigError(
            f"the plan leaves {', '.join(check.unidentifiable)} unidentifiable (rank "
            f"{check.rank} of 4): {check.advice}."
        )
    return check
