"""What an orientation error of the turntable does to a multiposition gyro calibration (GyroWheel study).

A multiposition test (GyroWheel study, §2.1, :mod:`rotacal.gyro.multiposition`) estimates the seven drift
coefficients of each gyro axis from ``b1 − b2 = A·β`` (eqs. (5)–(6)), with b2 the Earth-rate
component and A the gravity terms of eq. (3) at the *intended* positions. A turntable whose
instrument frame is off by the small rotation

    ΔR = [[1, −Δθ, Δψ], [Δθ, 1, −Δγ], [−Δψ, Δγ, 1]]                         (eq. (7))

(Δψ about the gyro's y axis, Δθ about z, Δγ about x; ΔR = R_dᵀ·R_t of eqs. (23)–(24)) makes the
gyro feel the row vectors ``ω' = ω·ΔR`` and ``a' = a·ΔR`` (eq. (8)) instead. rotacal's reading of
eqs. (9)–(14):

* the physical outputs are ``b1 = b2' + A'·β_T`` with β_T the true coefficients (default the GyroWheel study
  Table 1) and b2', A' built from ω', a' (eqs. (9)–(10));
* the lab, unaware of the error, solves eq. (6) with the nominal A and b2:
  ``β1 = (AᵀA)⁻¹Aᵀ(b1 − b2)``; eq. (11) gives ``β2 = (A'ᵀA')⁻¹A'ᵀ(b1 − b2') = β_T``, so
  ``Δβ = β1 − β2 = (AᵀA)⁻¹Aᵀ[(b2' − b2) + (A' − A)·β_T]`` (eq. (12));
* eq. (13) as printed, ``Δω = b1 − A·β2 − b2'``, does not contain Δβ although the text says "the
  deviation Δβ results in the rate-sensing error". The default ``method="coefficients"`` follows the
  text: the rate error the wrong coefficients cause at the test positions, ``Δω_vec = A·Δβ``.
  ``method="eq13"`` evaluates the printed formula with the physical b1, which is
  ``(A' − A)·β_T`` (the Earth rate drops out). ``method="earth-rate"`` keeps the Earth-rate
  reading alone, ``Δω_vec = b2' − b2`` (no gravity terms, no fit): the reading behind the paper's
  eq. (16) — for equal limits I its worst case over every orientation is √2·Ωe·I (the Earth rate
  at 45° between two gyro axes), so I = ωm/(√2·Ωe) = 0.02694° for ωm = 0.01 °/h, which the
  paper prints as 0.027°;
* eq. (14): the rate-sensing error of the axis is ``‖Δω_vec‖∞`` (°/h).

The nominal A, its least-squares projector and the hat matrix are fixed per plan, and the changes
``a' − a = a·(ΔR − I)`` are formed directly from the small quantities (no difference of large
numbers), so a whole grid of orientation errors costs a few array products.

The paper does not state its test positions or latitude; rotacal's defaults are
:func:`rotacal.gyro.multiposition.multiposition_plan` (both axes every 45°, 64 positions) and the
twin's latitude 45.75° (:data:`rotacal.sim.multiposition.DEFAULT_LATITUDE_DEG`).

References
----------
Seed 001 (GyroWheel calibration tests: error analysis and turntable error allocation), §2.2–2.3,
eqs. (7)–(16), Table 1, Figures 4–5.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from rotacal.errors import ConfigError
from rotacal.gyro.multiposition import (
    EARTH_RATE_DEG_H,
)
from rotacal.sim.multiposition import DEFAULT_LATITUDE_DEG
from rotacal.turntable.calibration_setup import (
    MAX_ORIENTATION_ERROR_RAD,
    METHODS,
    _deviations,
    _errors,
    _finite_number,
    _from_errors,
    _input_changes,
    _norms,
    _setup,
    _uniform_delta,
)
from rotacal.turntable.chain import COMPONENTS
from rotacal.turntable.orientation_limits import (
    OrientationRequirement,
    equal_orientation_limit_rad,
    orientation_requirement,
)

__all__ = [
    "COMPONENTS",
    "MAX_ORIENTATION_ERROR_RAD",
    "METHODS",
    "OrientationRequirement",
    "actual_inputs",
    "coefficient_deviation",
    "equal_orientation_limit_rad",
    "orientation_matrix",
    "orientation_requirement",
    "rate_error_surfaces",
    "rate_error_vectors",
    "rate_error_vectors_from_rotation",
    "rate_sensing_error",
    "rate_sensing_error_from_rotation",
]

# ----------------------------------------------------------------------------------- public


def orientation_matrix(dpsi: Any, dtheta: Any, dgamma: Any) -> np.ndarray:
    """The small-angle orientation-error matrix ΔR of the GyroWheel study, eq. (7).

    ``ΔR = [[1, −Δθ, Δψ], [Δθ, 1, −Δγ], [−Δψ, Δγ, 1]]`` (= I + skew(Δγ, Δψ, Δθ)).

    Parameters
    ----------
    dpsi, dtheta, dgamma : float or array
        Orientation errors Δψ (about the gyro's y axis), Δθ (about z), Δγ (about x), rad;
        broadcast together.

    Returns
    -------
    ndarray, shape (..., 3, 3)
        ΔR (dimensionless), one per broadcast element.

    References
    ----------
    Seed 001, §2.2, eq. (7).
    """
    p, t, g = _errors(dpsi, dtheta, dgamma, limit=False)
    return _uniform_delta(p, t, g) + np.eye(3)


def actual_inputs(
    dpsi: Any,
    dtheta: Any,
    dgamma: Any,
    *,
    phi1_deg: Any = None,
    phi2_deg: Any = None,
    latitude_deg: float = DEFAULT_LATITUDE_DEG,
    earth_rate_deg_h: float = EARTH_RATE_DEG_H,
) -> tuple[np.ndarray, np.ndarray]:
    """Earth rate and gravity the gyro really senses with an orientation error (eq. (8)).

    ``ω' = ω·ΔR``, ``a' = a·ΔR`` (row vectors) with ω, a of eq. (3) at each planned position.

    Parameters
    ----------
    dpsi, dtheta, dgamma : float or array
        Orientation errors (rad), broadcast together; |error| ≤ 0.1 rad.
    phi1_deg, phi2_deg : array or None
        Outer and inner angles of the plan (deg); None: both axes every 45° (64 positions).
    latitude_deg : float
        Latitude of the laboratory (deg).
    earth_rate_deg_h : float
        Earth rate Ωe (°/h).

    Returns
    -------
    (omega_deg_h, gravity_g) : (ndarray, ndarray)
        Each of shape (..., n, 3): (ωx', ωy', ωz') in °/h and (ax', ay', az') in g.

    References
    ----------
    Seed 001, §2.1–2.2, eqs. (3), (7) and (8).
    """
    s = _setup(phi1_deg, phi2_deg, latitude_deg, None, "coefficients", earth_rate_deg_h)
    p, t, g = _errors(dpsi, dtheta, dgamma)
    dw, da = _input_changes(s, _uniform_delta(p, t, g), per_position=False)
    return s.omega + dw, s.gravity + da


def coefficient_deviation(
    dpsi: Any,
    dtheta: Any,
    dgamma: Any,
    *,
    phi1_deg: Any = None,
    phi2_deg: Any = None,
    latitude_deg: float = DEFAULT_LATITUDE_DEG,
    coefficients: Mapping[str, Mapping[str, float]] | None = None,
    earth_rate_deg_h: float = EARTH_RATE_DEG_H,
) -> tuple[np.ndarray, np.ndarray]:
    """Deviation Δβ = β1 − β2 of the calibrated drift coefficients (eq. (12)).

    ``Δβ = (AᵀA)⁻¹Aᵀ[(b2' − b2) + (A' − A)·β_T]``: eq. (6) applied by a lab unaware of the
    orientation error, minus the truth β2 = β_T of eq. (11).

    Parameters
    ----------
    dpsi, dtheta, dgamma : float or array
        Orientation errors (rad), broadcast together; |error| ≤ 0.1 rad.
    phi1_deg, phi2_deg : array or None
        The plan (deg); None: both axes every 45° (64 positions).
    latitude_deg : float
        Latitude (deg).
    coefficients : mapping or None
        True drift coefficients β_T, ``{"x": {...}, "y": {...}}`` by the names of
        :func:`rotacal.gyro.multiposition.coefficient_names` (deg/h, deg/h/g, deg/h/g²);
        missing axes or names take the GyroWheel study's Table 1 values.
    earth_rate_deg_h : float
        Earth rate Ωe (°/h).

    Returns
    -------
    (dbeta_x, dbeta_y) : (ndarray, ndarray)
        Each of shape (..., 7), in the order of ``coefficient_names(axis)`` (deg/h, deg/h/g,
        deg/h/g²).

    References
    ----------
    Seed 001, §2.2, eqs. (6), (9)–(12).
    """
    s = _setup(phi1_deg, phi2_deg, latitude_deg, coefficients, "coefficients", earth_rate_deg_h)
    dev = _from_errors(s, dpsi, dtheta, dgamma)
    return dev["x"][0], dev["y"][0]


def rate_error_vectors(
    dpsi: Any,
    dtheta: Any,
    dgamma: Any,
    *,
    phi1_deg: Any = None,
    phi2_deg: Any = None,
    latitude_deg: float = DEFAULT_LATITUDE_DEG,
    coefficients: Mapping[str, Mapping[str, float]] | None = None,
    method: str = "coefficients",
    earth_rate_deg_h: float = EARTH_RATE_DEG_H,
) -> tuple[np.ndarray, np.ndarray]:
    """Rate-sensing error vectors at the test positions (eq. (13), rotacal's reading).

    ``method="coefficients"``: ``A·Δβ`` (the error the deviated coefficients cause);
    ``method="eq13"``: ``b1 − A·β2 − b2' = (A' − A)·β_T`` (the formula as printed);
    ``method="earth-rate"``: ``b2' − b2`` (the Earth-rate reading alone).

    Parameters
    ----------
    dpsi, dtheta, dgamma : float or array
        Orientation errors (rad), broadcast together; |error| ≤ 0.1 rad.
    phi1_deg, phi2_deg, latitude_deg, coefficients, earth_rate_deg_h
        As in :func:`rate_sensing_error`.
    method : {"coefficients", "eq13", "earth-rate"}
        The reading of eq. (13).

    Returns
    -------
    (dw_x, dw_y) : (ndarray, ndarray)
        Each of shape (..., n) (°/h), one value per test position.

    References
    ----------
    Seed 001, §2.2, eqs. (12)–(13).
    """
    s = _setup(phi1_deg, phi2_deg, latitude_deg, coefficients, method, earth_rate_deg_h)
    dev = _from_errors(s, dpsi, dtheta, dgamma)
    return dev["x"][1], dev["y"][1]


def rate_sensing_error(
    dpsi: Any,
    dtheta: Any,
    dgamma: Any,
    *,
    phi1_deg: Any = None,
    phi2_deg: Any = None,
    latitude_deg: float = DEFAULT_LATITUDE_DEG,
    coefficients: Mapping[str, Mapping[str, float]] | None = None,
    method: str = "coefficients",
    earth_rate_deg_h: float = EARTH_RATE_DEG_H,
) -> tuple[np.ndarray, np.ndarray]:
    """Rate-sensing errors Δωx, Δωy caused by an orientation error (eqs. (7)–(14)).

    Whole-array: the nominal design matrices and projectors are built once per call, then any
    grid of orientation errors costs a few array products.

    Parameters
    ----------
    dpsi, dtheta, dgamma : float or array
        Orientation errors Δψ (about y), Δθ (about z), Δγ (about x), rad, broadcast together;
        |error| ≤ 0.1 rad (eq. (7) is a small-angle model).
    phi1_deg, phi2_deg : array or None
        Outer and inner angles of the multiposition plan (deg); both or neither. None: both axes
        every 45° (64 positions). The plan must identify the seven coefficients of both axes.
    latitude_deg : float
        Latitude of the laboratory (deg); default 45.75° (the paper states none).
    coefficients : mapping or None
        True drift coefficients β_T, ``{"x": {...}, "y": {...}}`` (deg/h, deg/h/g, deg/h/g²);
        missing axes or names take the GyroWheel study's Table 1 values.
    method : {"coefficients", "eq13", "earth-rate"}
        ``"coefficients"``: ‖A·Δβ‖∞ (the text's meaning); ``"eq13"``: ‖(A' − A)·β_T‖∞ (eq. (13)
        as printed); ``"earth-rate"``: ‖b2' − b2‖∞ (the Earth-rate reading alone, eq. (16)'s).
        See the module docstring.
    earth_rate_deg_h : float
        Earth rate Ωe (°/h); default sidereal 15.041067.

    Returns
    -------
    (dw_x, dw_y) : (ndarray, ndarray)
        Δωx and Δωy (°/h), of the broadcast shape of the orientation errors.

    Raises
    ------
    ConfigError
        Non-finite or too large orientation errors, shapes that do not broadcast, an unknown
        method or coefficient, a latitude beyond ±90°, a plan that leaves coefficients
        unidentifiable.

    References
    ----------
    Seed 001, §2.2, eqs. (7)–(14) and Table 1.
    """
    s = _setup(phi1_deg, phi2_deg, latitude_deg, coefficients, method, earth_rate_deg_h)
    return _norms(_from_errors(s, dpsi, dtheta, dgamma))


def rate_sensing_error_from_rotation(
    delta_r: Any,
    *,
    phi1_deg: Any,
    phi2_deg: Any,
    latitude_deg: float = DEFAULT_LATITUDE_DEG,
    coefficients: Mapping[str, Mapping[str, float]] | None = None,
    method: str = "coefficients",
    earth_rate_deg_h: float = EARTH_RATE_DEG_H,
) -> tuple[np.ndarray, np.ndarray]:
    """Rate-sensing errors Δωx, Δωy for an orientation error that differs from position to position.

    Same as :func:`rate_sensing_error`, but ΔR is given per test position — e.g. ``ΔR = R_dᵀR_t`` of
    the turntable model (eqs. (23)–(24)) at each (φ1, φ2) of the plan, whose orientation error
    varies with φ2 (eq. (26)). ΔR may be the small-angle matrix or a proper rotation; the inputs
    are ``ω·ΔR`` and ``a·ΔR`` (eq. (8)).

    Parameters
    ----------
    delta_r : array, shape (..., n, 3, 3)
        ΔR at each of the n test positions (dimensionless), in the order of the plan's angles; a
        leading batch shape is allowed. n = 1 applies one ΔR to every position.
    phi1_deg, phi2_deg : array
        Outer and inner angles of the plan (deg), n each.
    latitude_deg, coefficients, method, earth_rate_deg_h
        As in :func:`rate_sensing_error`.

    Returns
    -------
    (dw_x, dw_y) : (ndarray, ndarray)
        Δωx and Δωy (°/h), of shape ``delta_r.shape[:-3]``.

    Raises
    ------
    ConfigError
        A ΔR of the wrong shape, non-finite, or more than 0.1 from the identity in any element;
        the faults of :func:`rate_sensing_error`.

    References
    ----------
    Seed 001, §2.2, eqs. (8)–(14); §3.2, eqs. (23)–(24).
    """
    return _norms(
        _rotation_deviations(
            delta_r, phi1_deg, phi2_deg, latitude_deg, coefficients, method, earth_rate_deg_h
        )
    )


def _rotation_deviations(
    delta_r: Any,
    phi1_deg: Any,
    phi2_deg: Any,
    latitude_deg: Any,
    coefficients: Any,
    method: Any,
    earth_rate_deg_h: Any,
) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """Per axis (Δβ, Δω_vec) for a ΔR per test position, checked (see the public functions)."""
    s = _setup(phi1_deg, phi2_deg, latitude_deg, coefficients, method, earth_rate_deg_h)
    try:
        r = np.asarray(delta_r, dtype=float)
    except (TypeError, ValueError):
        raise ConfigError("delta_r must be an array of 3 × 3 matrices.") from None
    n = s.positions
    if r.ndim < 3 or r.shape[-2:] != (3, 3) or r.shape[-3] not in (1, n):
        raise ConfigError(
            f"delta_r must have shape (..., {n}, 3, 3) (one ΔR per test position of the plan), "
            f"got {r.shape}."
        )
    if not np.all(np.isfinite(r)):
        raise ConfigError("delta_r has non-finite values (NaN or inf): give finite matrices.")
    d = r - np.eye(3)
    if d.size and float(np.max(np.abs(d))) > MAX_ORIENTATION_ERROR_RAD:
        raise ConfigError(
            f"delta_r differs from the identity by up to {float(np.max(np.abs(d))):.4g}, beyond "
            f"the small orientation errors of the GyroWheel study (≤ {MAX_ORIENTATION_ERROR_RAD} rad): pass "
            "ΔR = R_dᵀ·R_t, not R_t."
        )
    return _deviations(s, d, per_position=True)


def rate_error_vectors_from_rotation(
    delta_r: Any,
    *,
    phi1_deg: Any,
    phi2_deg: Any,
    latitude_deg: float = DEFAULT_LATITUDE_DEG,
    coefficients: Mapping[str, Mapping[str, float]] | None = None,
    method: str = "coefficients",
    earth_rate_deg_h: float = EARTH_RATE_DEG_H,
) -> tuple[np.ndarray, np.ndarray]:
    """Rate-sensing error vectors at the test positions for a ΔR per position (eqs. (8)–(13)).

    The vectors whose ∞-norms :func:`rate_sensing_error_from_rotation` returns (eq. (14)).

    Parameters
    ----------
    delta_r, phi1_deg, phi2_deg, latitude_deg, coefficients, method, earth_rate_deg_h
        As in :func:`rate_sensing_error_from_rotation`.

    Returns
    -------
    (dw_x, dw_y) : (ndarray, ndarray)
        Each of shape ``delta_r.shape[:-3] + (n,)`` (°/h), one value per test position.

    References
    ----------
    Seed 001, §2.2, eqs. (8)–(13); §3.2, eqs. (23)–(24).
    """
    dev = _rotation_deviations(
        delta_r, phi1_deg, phi2_deg, latitude_deg, coefficients, method, earth_rate_deg_h
    )
    return dev["x"][1], dev["y"][1]


def rate_error_surfaces(
    limit_rad: float,
    *,
    n: int = 41,
    phi1_deg: Any = None,
    phi2_deg: Any = None,
    latitude_deg: float = DEFAULT_LATITUDE_DEG,
    coefficients: Mapping[str, Mapping[str, float]] | None = None,
    method: str = "coefficients",
    earth_rate_deg_h: float = EARTH_RATE_DEG_H,
) -> dict[str, Any]:
    """Δωx and Δωy over planes of orientation errors, the data of the GyroWheel study's Figure 4.

    Each plane varies two components over ``[−limit_rad, +limit_rad]`` (n points each) with the
    third at zero; each curve varies one component with the other two at zero.

    Parameters
    ----------
    limit_rad : float
        Half-width of the grid (rad, 0 < limit ≤ 0.1).
    n : int
        Points per grid axis (≥ 2).
    phi1_deg, phi2_deg, latitude_deg, coefficients, method, earth_rate_deg_h
        As in :func:`rate_sensing_error`.

    Returns
    -------
    dict
        ``grid_rad`` (n,); ``x`` and ``y``: for each plane ``"psi_theta"``, ``"theta_gamma"``,
        ``"psi_gamma"`` an (n, n) array of Δω (°/h), first index the first-named component;
        ``curves``: ``{"x": {"psi": (n,), "theta": ..., "gamma": ...}, "y": {...}}``; ``method``,
        ``latitude_deg``, ``positions``, ``units`` ("deg/h").

    References
    ----------
    Seed 001, §2.2, eqs. (7)–(14), Figure 4.
    """
    lim = _finite_number("limit_rad", limit_rad)
    if not 0 < lim <= MAX_ORIENTATION_ERROR_RAD:
        raise ConfigError(
            f"limit_rad must be in (0, {MAX_ORIENTATION_ERROR_RAD}] rad, got {limit_rad!r}."
        )
    if isinstance(n, bool) or not float(n).is_integer() or int(n) < 2:
        raise ConfigError(f"n must be an integer ≥ 2, got {n!r}.")
    s = _setup(phi1_deg, phi2_deg, latitude_deg, coefficients, method, earth_rate_deg_h)
    g = np.linspace(-lim, lim, int(n))
    u, v = np.meshgrid(g, g, indexing="ij")
    z2 = np.zeros_like(u)
    planes = {
        "psi_theta": (u, v, z2),
        "theta_gamma": (z2, u, v),
        "psi_gamma": (u, z2, v),
    }
    out: dict[str, Any] = {"grid_rad": g, "x": {}, "y": {}, "curves": {"x": {}, "y": {}}}
    for name, (p, t, gm) in planes.items():
        wx, wy = _norms(_from_errors(s, p, t, gm))
        out["x"][name], out["y"][name] = wx, wy
    z1 = np.zeros_like(g)
    for k, comp in enumerate(COMPONENTS):
        args = [z1, z1, z1]
        args[k] = g
        wx, wy = _norms(_from_errors(s, *args))
        out["curves"]["x"][comp], out["curves"]["y"][comp] = wx, wy
    out.update(method=s.method, latitude_deg=s.latitude_deg, positions=s.positions, units="deg/h")
    return out
