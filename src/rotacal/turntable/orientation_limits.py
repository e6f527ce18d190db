"""The orientation error a turntable may have for a required gyro calibration accuracy (eqs. (15)–(16)).

:func:`orientation_requirement` finds the box (Iψ, Iθ, Iγ) of largest volume whose every corner
keeps both rate-sensing errors of the multiposition test (eqs. (12)–(14), the readings of
:mod:`rotacal.turntable.calibration`) within the required accuracy ωm, and the largest equal limit
I (the form of the paper's eq. (16)); :func:`equal_orientation_limit_rad` the equal limit alone.
The rate errors at a box's corners come from the exact quadratic form of the error model, so a
search over boxes costs a few small products per step.

References
----------
Seed 001 (GyroWheel calibration tests: error analysis and turntable error allocation), §2.3,
eqs. (15)–(16).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from typing import Any

import numpy as np
from scipy.optimize import brentq, minimize

from rotacal.errors import ConfigError
from rotacal.gyro.multiposition import (
    EARTH_RATE_DEG_H,
)
from rotacal.results import Result
from rotacal.sim.multiposition import DEFAULT_LATITUDE_DEG
from rotacal.turntable.calibration_setup import (
    _AXES,
    _CORNERS,
    _METHOD_TEXT,
    MAX_ORIENTATION_ERROR_RAD,
    _features,
    _finite_number,
    _Setup,
    _setup,
)
from rotacal.turntable.chain import COMPONENTS

__all__ = ["OrientationRequirement", "equal_orientation_limit_rad", "orientation_requirement"]


# ------------------------------------------------------------------------- the requirement


@dataclasses.dataclass(frozen=True)
class OrientationRequirement(Result):
    """The allowed orientation error for a required calibration accuracy (eqs. (15)–(16)).

    ``limits_rad`` is the box (Iψ, Iθ, Iγ) of largest volume such that at every corner
    (±Iψ, ±Iθ, ±Iγ) both Δωx and Δωy are ≤ ``required_deg_h``; ``equal_limit_rad`` the largest
    I with Iψ = Iθ = Iγ = I (the form of the paper's eq. (16)). ``rate_error_at_limits_deg_h`` is
    the largest Δωx, Δωy over the box's corners (°/h).
    """

    required_deg_h: float
    limits_rad: dict[str, float]
    limits_deg: dict[str, float]
    equal_limit_rad: float
    equal_limit_deg: float
    rate_error_at_limits_deg_h: dict[str, float]
    rate_error_at_equal_limit_deg_h: dict[str, float]
    method: str
    positions: int
    latitude_deg: float
    notes: tuple[str, ...] = ()


def _corner_vectors(s: _Setup, limits: np.ndarray) -> np.ndarray:
    """Δω_vec of both axes at the 8 corners of the box ``limits`` (3,): shape (2, 8, n)."""
    c = _CORNERS * limits
    f = _features(c[:, 0], c[:, 1], c[:, 2])
    return np.stack([f @ s.quadratic[axis][1] for axis in _AXES])


def _corner_max(s: _Setup, limits: np.ndarray) -> np.ndarray:
    """Largest Δωx and Δωy over the corners of the box (°/h), shape (2,)."""
    return np.asarray(np.max(np.abs(_corner_vectors(s, limits)), axis=(1, 2)))


def _scale_to_boundary(s: _Setup, shape: np.ndarray, wm: float) -> tuple[float, bool]:
    """Largest t with max corner error of the box t·shape ≤ wm; (t, capped at the 0.1 rad limit)."""
    t_cap = MAX_ORIENTATION_ERROR_RAD / float(np.max(shape))

    def excess(t: float) -> float:
        return float(np.max(_corner_max(s, t * shape))) - wm

    if excess(t_cap) <= 0.0:
        return t_cap, True
    # near-linear response: a small probe gives a good first bracket
    probe = 1e-6 * t_cap
    m = excess(probe) + wm
    lo = min(0.5 * probe * wm / m, t_cap) if m > 0 else probe
    while excess(lo) > 0.0:
        lo *= 0.5
    hi = min(2.0 * lo, t_cap)
    while excess(hi) <= 0.0:
        lo, hi = hi, min(2.0 * hi, t_cap)
    t = brentq(excess, lo, hi, xtol=1e-15 * hi, rtol=4 * np.finfo(float).eps, maxiter=200)
    shrink = 1e-13
    while excess(t) > 0.0:  # brentq may land a hair outside: step to the feasible side
        t = max(t * (1.0 - shrink), lo)
        shrink *= 4.0
    return float(t), False


def _required(required_deg_h: Any) -> float:
    """ωm (°/h) as a float; a non-positive or non-finite one is one ConfigError line."""
    wm = _finite_number("required_deg_h", required_deg_h)
    if wm <= 0:
        raise ConfigError(
            f"required_deg_h must be a positive accuracy in °/h, got {required_deg_h!r}."
        )
    return wm


def equal_orientation_limit_rad(
    required_deg_h: float = 0.01,
    *,
    phi1_deg: Any = None,
    phi2_deg: Any = None,
    latitude_deg: float = DEFAULT_LATITUDE_DEG,
    coefficients: Mapping[str, Mapping[str, float]] | None = None,
    method: str = "coefficients",
    earth_rate_deg_h: float = EARTH_RATE_DEG_H,
) -> float:
    """The equal limit I = Iψ = Iθ = Iγ (rad) of :func:`orientation_requirement` alone.

    The same root (the largest I at which every corner (±I, ±I, ±I) keeps Δωx, Δωy ≤ ωm), hence
    the same number as its ``equal_limit_rad``, without the box of largest volume that SLSQP
    finds there — most of its time, and not needed where only the form of eq. (16) is asked
    (the latitude and plan scan of :func:`rotacal.turntable.seed001.reproduce_seed001`).

    Parameters
    ----------
    required_deg_h : float
        Required calibration accuracy ωm (°/h, > 0).
    phi1_deg, phi2_deg, latitude_deg, coefficients, method, earth_rate_deg_h
        As in :func:`rate_sensing_error`.

    Returns
    -------
    float
        I (rad).

    Raises
    ------
    ConfigError
        As :func:`orientation_requirement`.

    References
    ----------
    Seed 001, §2.2–2.3, eqs. (13)–(16).
    """
    wm = _required(required_deg_h)
    s = _setup(phi1_deg, phi2_deg, latitude_deg, coefficients, method, earth_rate_deg_h)
    return _scale_to_boundary(s, np.ones(3), wm)[0]


def orientation_requirement(
    required_deg_h: float = 0.01,
    *,
    phi1_deg: Any = None,
    phi2_deg: Any = None,
    latitude_deg: float = DEFAULT_LATITUDE_DEG,
    coefficients: Mapping[str, Mapping[str, float]] | None = None,
    method: str = "coefficients",
    earth_rate_deg_h: float = EARTH_RATE_DEG_H,
) -> OrientationRequirement:
    """Allowed orientation error (Iψ, Iθ, Iγ) for a required calibration accuracy ωm (eq. (15)).

    The paper (Figure 5) draws the rectangles of largest area inside Δωx ≤ ωm over (Δψ, Δθ) and
    Δωy ≤ ωm over (Δθ, Δγ). rotacal takes the box of largest volume — maximising
    log Iψ + log Iθ + log Iγ, since the two rectangles share Iθ — such that at every corner
    (±Iψ, ±Iθ, ±Iγ) the full model gives Δωx ≤ ωm and Δωy ≤ ωm (Δω is the ∞-norm of a
    near-linear function of the errors, so the corners are the worst points of the box). It is
    solved by SLSQP in log variables with one smooth constraint ``±Δω_i ≤ ωm`` per corner, axis and
    test position, then scaled so that the worst corner meets ωm (root-finding). The equal limit
    (Iψ = Iθ = Iγ, the form of eq. (16)) is a 1-D root.

    Parameters
    ----------
    required_deg_h : float
        Required calibration accuracy ωm (°/h, > 0); default 0.01 (the GyroWheel study's example, §2.3).
    phi1_deg, phi2_deg, latitude_deg, coefficients, method, earth_rate_deg_h
        As in :func:`rate_sensing_error`.

    Returns
    -------
    OrientationRequirement
        The box and the equal limit (rad and deg), the worst Δωx, Δωy at each (°/h), notes.

    Raises
    ------
    ConfigError
        A non-positive or non-finite ωm; the faults of :func:`rate_sensing_error`.

    References
    ----------
    Seed 001, §2.2–2.3, eqs. (13)–(16), Figures 4–5.
    """
    wm = _required(required_deg_h)
    s = _setup(phi1_deg, phi2_deg, latitude_deg, coefficients, method, earth_rate_deg_h)
    notes: list[str] = [
        f"plan of {s.positions} positions, latitude {s.latitude_deg:g}°, Earth rate "
        f"{s.earth_rate_deg_h:.8g} °/h; Δω by method {s.method!r} " + _METHOD_TEXT[s.method],
        "the paper's 0.027° (eq. (16)) states neither its plan nor its latitude; it is the Earth-rate "
        "reading alone (method 'earth-rate'), ωm/(√2·Ωe) = 0.02694°; rotacal's values are not "
        "tuned toward it.",
    ]
    ones = np.ones(3)
    i_eq, capped_eq = _scale_to_boundary(s, ones, wm)
    if capped_eq:
        notes.append(
            f"the equal limit reaches the small-angle cap {MAX_ORIENTATION_ERROR_RAD} rad: the "
            "requirement is not binding there."
        )
    lo_b = math.log(i_eq) - math.log(1e3)
    hi_b = math.log(MAX_ORIENTATION_ERROR_RAD)

    def cons(x: np.ndarray) -> np.ndarray:
        v = _corner_vectors(s, np.exp(x)).ravel() / wm
        return np.concatenate([1.0 - v, 1.0 + v])

    x0 = np.full(3, math.log(i_eq) - 1e-6)
    res = minimize(
        lambda x: -float(np.sum(x)),
        x0,
        jac=lambda x: -np.ones(3),
        method="SLSQP",
        bounds=[(lo_b, hi_b)] * 3,
        constraints=[{"type": "ineq", "fun": cons}],
        options={"ftol": 1e-13, "maxiter": 500},
    )
    shape = np.exp(np.clip(res.x, lo_b, hi_b)) if np.all(np.isfinite(res.x)) else ones
    t, capped = _scale_to_boundary(s, shape / np.max(shape), wm)
    box = t * shape / np.max(shape)
    if not res.success:
        notes.append(f"SLSQP did not report convergence ({res.message}); the box was verified.")
    if float(np.sum(np.log(box))) < 3.0 * math.log(i_eq):
        box = np.full(3, i_eq)
        notes.append(
            "the optimiser found no box larger than the equal one; the equal box is given."
        )
    if capped:
        notes.append(
            f"a limit reaches the small-angle cap {MAX_ORIENTATION_ERROR_RAD} rad: that component "
            "is not bounded by the requirement."
        )
    at_box = _corner_max(s, box)
    at_eq = _corner_max(s, np.full(3, i_eq))
    if float(np.max(at_box)) > wm * (1 + 1e-9) or float(np.max(at_eq)) > wm * (1 + 1e-9):
        raise RuntimeError("orientation_requirement: the verified box exceeds ωm (a bug).")
    return OrientationRequirement(
        required_deg_h=wm,
        limits_rad=dict(zip(COMPONENTS, (float(v) for v in box), strict=True)),
        limits_deg=dict(zip(COMPONENTS, (math.degrees(float(v)) for v in box), strict=True)),
        equal_limit_rad=float(i_eq),
        equal_limit_deg=math.degrees(i_eq),
        rate_error_at_limits_deg_h={"x": float(at_box[0]), "y": float(at_box[1])},
        rate_error_at_equal_limit_deg_h={"x": float(at_eq[0]), "y": float(at_eq[1])},
        method=s.method,
        positions=s.positions,
        latitude_deg=s.latitude_deg,
        notes=tuple(notes),
    )
