"""Accelerometer-triad calibration from six static positions against gravity (Ferraris et al. 1995).

The DUT rests with each of its axes pointing up (``x_p``, ``y_p``, ``z_p``: the accelerometer on
that axis reads +g, the specific force at rest points up) and down (``x_a``, ``y_a``, ``z_a``).
With the model u = K_a·R_a·a + b_a (K_a diagonal, the rows of R_a unit sensitive axes) and U_p,
U_a the 3×3 matrices whose column j is the mean output in position j_p, j_a (Ferraris 1995 as
imucal numbers it)::

    b_a,i = (U_p + U_a)_ii / 2                                   (eqs. 19–20)
    K_a·R_a = (U_p − U_a) / (2g)                                  (eqs. 21–22)
    K_a,ii = ‖row i of (U_p − U_a)‖ / (2g),  R_a = K_a⁻¹·(U_p − U_a)/(2g)   (eq. 23)

Gravity g is the local value (m/s²): by default the normal gravity at the stated latitude on the
ellipsoid (WGS 84, Somigliana's closed form), else standard gravity 9.80665.

References
----------
Ferraris F., Grimaldi U., Parvis M. (1995), Procedure for effortless in-field calibration of
three-axial rate gyro and accelerometers, Sensors and Materials 7(5):311–330, eqs. (19)–(23).
Küderle A. et al. (2022), imucal — a Python library to calibrate 6 DOF IMUs, JOSS 7(73):4338.
NIMA TR8350.2 (2000), Department of Defense World Geodetic System 1984, eq. (4-1) (normal gravity).
"""

from __future__ import annotations

import dataclasses
import itertools
import math
from collections.abc import Callable, Mapping, Sequence
from typing import Any

import numpy as np

from rotacal.columns import ACCEL_OUTPUT_COLUMNS
from rotacal.errors import CaptureError, ConfigError
from rotacal.gyro.rotation_sections import FERRARIS_STATIC, _range
from rotacal.gyro.scale_factor_points import output_quantum
from rotacal.gyro.triad import apply_triad_calibration, decompose_scale_misalignment
from rotacal.gyro.uncertainty import element_key, linear_gum, uncertainty_json
from rotacal.results import Result, to_jsonable
from rotacal.signal._values import check_magnitudes, check_not_constant
from rotacal.signal.clipping import check_clipping
from rotacal.uncertainty.budget import UncertaintyBudget
from rotacal.uncertainty.gum import Input

__all__ = [
    "ACCEL_OUTPUT_COLUMNS",
    "STANDARD_GRAVITY",
    "AccelTriadCalibration",
    "calibrate_accel_triad",
    "normal_gravity",
]

#: Standard gravity (m/s², CGPM 1901), used when neither g nor the latitude is given.
STANDARD_GRAVITY = 9.80665
_AXES = "xyz"


def normal_gravity(latitude_deg: float) -> float:
    """Normal gravity on the WGS 84 ellipsoid at a geodetic latitude (m/s²), Somigliana's formula
    γ = γ_e(1 + k·sin²φ)/√(1 − e²·sin²φ) (NIMA TR8350.2, eq. 4-1); height 0.

    Parameters
    ----------
    latitude_deg : float
        Geodetic latitude (deg, −90…90).
    """
    s2 = math.sin(math.radians(float(latitude_deg))) ** 2
    return 9.7803253359 * (1.0 + 0.00193185265241 * s2) / math.sqrt(1.0 - 0.00669437999013 * s2)


@dataclasses.dataclass(frozen=True)
class AccelTriadCalibration(Result):
    """Accelerometer triad from six static positions (Ferraris et al. 1995).

    Attributes
    ----------
    scale_misalignment : ndarray (3, 3)
        K_a·R_a in u = K_a·R_a·a + b_a (output unit per m/s²).
    scale_factors : ndarray (3,)
        imucal's K_a diagonal (output unit per m/s²): row norms of K_a·R_a.
    sensitive_axes : ndarray (3, 3)
        imucal's R_a: unit rows, the sensitive axis of each accelerometer in the DUT's axes.
    misalignment_deg : ndarray (3,)
        Angle of each sensitive axis from its nominal axis (deg).
    bias : ndarray (3,)
        b_a (output unit).
    scale_misalignment_u, scale_factors_u, bias_u : ndarray
        Standard uncertainties (budgets in ``_budgets``: the white noise of each position mean,
        Type A, and the stated u of g; the JSON adds ``_U``, ``k``, ``uncertainty_budgets``).
    gravity_m_s2 : float
        g used (m/s²).
    noise_std : ndarray (3,)
        Per-sample noise about each position's mean (output unit), pooled.
    positions : tuple of dict
        Per position: ``name``, ``start``, ``stop``, ``samples``, ``mean`` (output unit),
        ``acceleration_m_s2`` (the calibrated mean) and ``gravity_error_m_s2`` (its norm − g: how
        far the position was from the model — a tilted position, a nonlinear output).
    """

    scale_misalignment: np.ndarray
    scale_factors: np.ndarray
    sensitive_axes: np.ndarray
    misalignment_deg: np.ndarray
    bias: np.ndarray
    scale_misalignment_u: np.ndarray
    scale_factors_u: np.ndarray
    bias_u: np.ndarray
    gravity_m_s2: float
    noise_std: np.ndarray
    positions: tuple[dict[str, Any], ...]
    notes: tuple[str, ...] = ()
    output_unit: str = ""
    _budgets: dict[str, UncertaintyBudget] = dataclasses.field(
        default_factory=dict, repr=False, compare=False
    )

    def calibrate(self, u: Any) -> np.ndarray:
        """a = (K_a·R_a)⁻¹·(u − b_a) (m/s²) for raw outputs ``u`` (n, 3)."""
        return apply_triad_calibration(u, self.scale_misalignment, self.bias)

    def to_dict(self) -> dict[str, Any]:
        """The JSON fields plus the uncertainty keys."""
        out = super().to_dict()
        shapes = {"scale_misalignment": (3, 3), "scale_factors": (3,), "bias": (3,)}
        out.update(to_jsonable(uncertainty_json(self._budgets, shapes)))
        return out


def check_disjoint(sections: Mapping[str, tuple[int, int]]) -> None:
    """Refuse two named sample ranges [start, stop) that overlap, with one line."""
    order = sorted(sections.items(), key=lambda kv: kv[1][0])
    for (a, (_, ea)), (b, (sb, _)) in itertools.pairwise(order):
        if sb < ea:
            raise ConfigError(f"sections {a} and {b} overlap; fix the section list.")


def static_positions(static: Any, n: int) -> dict[str, tuple[int, int]]:
    """The six named static positions (``x_p`` … ``z_a``) as half-open sample ranges, refused with
    one line when one is missing or two overlap."""
    if not isinstance(static, Mapping):
        raise ConfigError(
            f"the static positions must be named {', '.join(FERRARIS_STATIC)} (a mapping)."
        )
    missing = [k for k in FERRARIS_STATIC if k not in static]
    if missing:
        raise ConfigError(
            f"static position {', '.join(missing)} is missing: the six-position method needs "
            f"each axis up and down ({', '.join(FERRARIS_STATIC)})."
        )
    out = {k: _range(f"static {k}", static[k], n) for k in FERRARIS_STATIC}
    check_disjoint(out)
    return out


def _six_means(u: np.ndarray, pos: Mapping[str, tuple[int, int]]) -> tuple[np.ndarray, ...]:
    """(U_p, U_a, counts (2, 3), pooled noise (3,)): column j of U_p/U_a is the mean output in
    position j_p/j_a."""
    means = {k: u[s:e].mean(axis=0) for k, (s, e) in pos.items()}
    up = np.column_stack([means[f"{a}_p"] for a in _AXES])
    ua = np.column_stack([means[f"{a}_a"] for a in _AXES])
    counts = np.array([[pos[f"{a}_{t}"][1] - pos[f"{a}_{t}"][0] for a in _AXES] for t in "pa"])
    sq = sum(np.sum((u[s:e] - means[k]) ** 2, axis=0) for k, (s, e) in pos.items())
    noise = np.sqrt(sq / max(int(counts.sum()) - 6, 1))
    return up, ua, counts, noise


def _solve(up: np.ndarray, ua: np.ndarray, g: float) -> tuple[np.ndarray, np.ndarray]:
    """K_a·R_a and b_a of eqs. (19)–(22)."""
    return (up - ua) / (2.0 * g), np.diag(up + ua) / 2.0


def rounding_u(static: np.ndarray, whole: np.ndarray, noise: np.ndarray) -> np.ndarray:
    """Standard uncertainty of the rounding left in a mean of each column (output unit):
    (q/√12)·exp(−2π²σ²/q²), σ the column's noise and q its step — the grid
    :func:`~rotacal.gyro.scale_factor_points.output_quantum` sees in the static rows (densely
    used) or in the whole column (every gap between its values a multiple of the smallest, however
    sparse), else, for a column without any noise, the smallest gap between its values (an upper
    bound). Without noise a mean keeps up to ±q/2 of rounding, uniform (GUM
    F.2.2.1); noise dithers it away as the quantised Gaussian's characteristic function at 2π/q,
    exp(−2π²σ²/q²) (Widrow & Kollár 2008, Quantization Noise, ch. 4). 0 for a noisy column
    without a visible grid."""
    out = np.zeros(static.shape[1])
    for c in range(static.shape[1]):
        col = whole[np.isfinite(whole[:, c]), c]
        # a grid used sparsely (few levels, a coarse step) still counts: every gap a multiple
        q = output_quantum(static[:, c]) or output_quantum(col, max_median_steps=math.inf) or 0.0
        if not q and noise[c] <= 1e-12 * float(np.max(np.abs(col), initial=0.0)):
            gaps = np.diff(np.unique(col))  # no noise at all: the smallest gap bounds the step
            q = float(gaps.min()) if gaps.size else 0.0
        if q:
            out[c] = q / math.sqrt(12.0) * math.exp(-2.0 * math.pi**2 * (noise[c] / q) ** 2)
    return out


def rounding_inputs(
    uq: np.ndarray, cols: Sequence[str], names: Sequence[str], unit: str
) -> list[Input]:
    """Type B inputs of the rounding of each position mean (:func:`rounding_u`): one per position
    and column (positions far apart on the grid round independently), then one per column common
    to all positions (positions at nearly the same level round alike); the model adds both."""

    def one(name: str, u: float) -> Input:
        return Input(
            name,
            0.0,
            float(u),
            unit=unit,
            source="output quantum",
            description="Type B: rectangular, the output's step not dithered by its noise",
        )

    return [
        one(f"rounding of the mean of {cols[c]} in {names[p]}", uq[c])
        for p in range(len(names))
        for c in range(len(cols))
    ] + [one(f"rounding of {cols[c]} common to the positions", uq[c]) for c in range(len(cols))]


def with_rounding(x: np.ndarray, start: int) -> np.ndarray:
    """The 18 position means of ``x`` (first 18 entries) plus their rounding inputs at
    ``start`` (18 per position and column, then 3 common), as (6, 3)."""
    return (x[:18] + x[start : start + 18]).reshape(6, 3) + x[start + 18 : start + 21]


def jacobian_budgets(
    func: Callable[[np.ndarray], dict[str, np.ndarray]],
    inputs: Sequence[Input],
    units: Mapping[str, str],
    notes: Sequence[str] = (),
) -> dict[str, UncertaintyBudget]:
    """One GUM budget per element of each output of ``func`` (x ↦ {name: array}), the inputs
    independent, the sensitivities by central differences (step 10⁻⁴·u of each input; the
    closed forms here are smooth, so the first-order GUM of JCGM 100:2008 §5.1.2 applies)."""
    x0 = np.array([i.value for i in inputs], dtype=float)
    y0 = func(x0)
    jac = {name: np.zeros((*np.shape(v), x0.size)) for name, v in y0.items()}
    for k, inp in enumerate(inputs):
        h = 1e-4 * inp.u if inp.u > 0 else 0.0
        if h == 0.0:
            continue
        dx = np.zeros_like(x0)
        dx[k] = h
        yp, ym = func(x0 + dx), func(x0 - dx)
        for name in y0:
            jac[name][..., k] = (np.asarray(yp[name]) - np.asarray(ym[name])) / (2.0 * h)
    budgets = {}
    for name, value in y0.items():
        for idx in np.ndindex(*np.shape(value)):
            sens = jac[name][idx]
            used = [i for i in range(x0.size) if sens[i] != 0.0] or [0]  # a noise-free twin
            b = linear_gum(
                element_key(name, idx),
                units[name],
                float(np.asarray(value)[idx]),
                [inputs[i] for i in used],
                [float(sens[i]) for i in used],
            ).budget(0)
            budgets[element_key(name, idx)] = dataclasses.replace(b, notes=(*b.notes, *notes))
    return budgets


def calibrate_accel_triad(
    acc: Any,
    static: Any,
    *,
    gravity_m_s2: float | None = None,
    gravity_u_m_s2: float = 0.0,
    latitude_deg: float | None = None,
    position_u_deg: float = 0.0,
    columns: Sequence[str] = ACCEL_OUTPUT_COLUMNS,
    output_unit: str = "",
    allow_clipped: bool = False,
) -> AccelTriadCalibration:
    """K_a, R_a and b_a of an accelerometer triad from its six static positions (Ferraris 1995).

    Parameters
    ----------
    acc : array_like, (n, 3)
        Raw accelerometer outputs (output unit: m/s², g or counts).
    static : mapping
        ``x_p, x_a, y_p, y_a, z_p, z_a`` → half-open sample ranges [start, stop) (pairs or
        ``{"start", "end"}``): each axis pointing up (reads +g) and down.
    gravity_m_s2 : float, optional
        Local gravity (m/s²). Default: :func:`normal_gravity` at ``latitude_deg``, else 9.80665.
    gravity_u_m_s2 : float
        Standard uncertainty of g (m/s²), Type B.
    latitude_deg : float, optional
        Geodetic latitude (deg), for the normal gravity.
    position_u_deg : float
        Standard uncertainty of each position's tilt from the vertical (deg), Type B, about each
        of the two horizontal axes, independent between positions: a tilt δ moves the other
        outputs' means by K_a·R_a·g·δ and so R_a's off-diagonal elements by δ. 0 (the default,
        imucal's assumption): positions exact, and a note says so.
    columns : sequence of 3 str
        The output columns' names, for messages.
    output_unit : str
        Name of the output unit.
    allow_clipped : bool
        Calibrate from outputs at their rails anyway (``warnings`` name them).

    Returns
    -------
    AccelTriadCalibration

    Raises
    ------
    ConfigError
        A position missing, overlapping another, out of range; a bad g or latitude.
    CaptureError
        NaN/inf in a position, a constant output, an output at its rails, two positions of one
        axis that give the same reading (no sensitivity), a singular K_a·R_a.

    References
    ----------
    Ferraris F., Grimaldi U., Parvis M. (1995), Sensors and Materials 7(5):311–330, eqs.
    (19)–(23); JCGM 100:2008 (GUM) §5.1.2 (the budgets).
    """
    u = np.asarray(acc, dtype=float)
    cols = tuple(columns)
    if u.ndim != 2 or u.shape[1] != 3:
        raise CaptureError(f"acc must be an (n, 3) array ({', '.join(cols)}); got {u.shape}.")
    g = gravity_for(gravity_m_s2, latitude_deg)
    gu = _nonnegative("gravity_u_m_s2", gravity_u_m_s2)
    pos = static_positions(static, u.shape[0])
    rows = np.concatenate([np.arange(s, e) for s, e in pos.values()])
    used = u[rows]
    if not np.isfinite(used).all():
        r, c = (int(i) for i in np.argwhere(~np.isfinite(used))[0])
        raise CaptureError(
            f"column {cols[c]} has a non-finite value at row {int(rows[r])} (a static position); "
            "remove or repair that sample."
        )
    for j, name in enumerate(cols):
        check_magnitudes(name, used[:, j], what="an accelerometer output")
        check_not_constant(name, used[:, j], "the output does not respond to gravity")
    # every position rests: a level it holds is not a rail; clipping shows as the rail level
    # of a position whose noise is cut off (the groups of the detector are the positions)
    groups = np.repeat(np.arange(6), [e - s for s, e in pos.values()])
    clipped = check_clipping(
        {name: used[:, j] for j, name in enumerate(cols)},
        allow_clipped=allow_clipped,
        groups=groups,
    )
    up, ua, counts, noise = _six_means(u, pos)
    for j, name in enumerate(cols):
        if not abs(up[j, j] - ua[j, j]) > 4.0 * noise[j] * math.sqrt(2.0 / counts.min()):
            raise CaptureError(
                f"column {name} reads the same with its axis up ({up[j, j]:.6g}) and down "
                f"({ua[j, j]:.6g}): it does not sense gravity — a wrong column or the positions "
                "of another axis; check the section list."
            )
    m, b = _solve(up, ua, g)
    if not abs(np.linalg.det(m)) > 1e-9 * np.abs(m).max() ** 3:
        raise CaptureError(
            "the six positions give a singular K_a·R_a: two positions hold the same attitude; "
            "check the section list."
        )
    scale, axes, mis = decompose_scale_misalignment(m)
    ou = output_unit or "output unit"
    names = [f"{a}_{t}" for t in "pa" for a in _AXES]
    inputs = [
        Input(
            f"mean of {cols[c]} in {names[p]}",
            float((up if p < 3 else ua)[c, p % 3]),
            float(noise[c] / math.sqrt(counts[p // 3, p % 3])),
            float(max(int(counts.sum()) - 6, 1)),
            "normal",
            ou,
            f"Type A: white noise, {int(counts[p // 3, p % 3])} samples",
        )
        for p in range(6)
        for c in range(3)
    ]
    inputs += rounding_inputs(rounding_u(used, u, noise), cols, names, ou)
    tilt_u = math.radians(_nonnegative("position_u_deg", position_u_deg))
    tilts = [(p, k) for p in range(6) for k in range(3) if k != p % 3] if tilt_u > 0 else []
    inputs += [
        Input(
            f"tilt of {names[p]} towards {_AXES[k]}",
            0.0,
            tilt_u,
            unit="rad",
            source="position_u_deg",
            description=f"Type B: u = {position_u_deg:g}°",
        )
        for p, k in tilts
    ]
    inputs.append(Input("gravity g", g, gu, unit="m/s²", source="gravity_u_m_s2"))

    def model(x: np.ndarray) -> dict[str, np.ndarray]:
        v = with_rounding(x, 18)
        for i, (p, k) in enumerate(tilts):  # the tilt adds g·δ along axis k to the reading
            v[p] -= m[:, k] * g * x[39 + i]
        mm, bb = _solve(v[:3].T, v[3:].T, x[-1])
        return {
            "scale_misalignment": mm,
            "scale_factors": np.linalg.norm(mm, axis=1),
            "bias": bb,
        }

    unit_k = f"{ou}/(m/s²)"
    budgets = jacobian_budgets(
        model,
        inputs,
        {"scale_misalignment": unit_k, "scale_factors": unit_k, "bias": ou},
        ("Type A assumes white noise in each position and positions aligned with gravity.",),
    )

    def arr(name: str, shape: tuple[int, ...]) -> np.ndarray:
        return np.reshape([budgets[element_key(name, i)].u for i in np.ndindex(*shape)], shape)

    a_cal = apply_triad_calibration(np.column_stack([up, ua]).T, m, b)
    positions = tuple(
        {
            "name": k,
            "start": s,
            "stop": e,
            "samples": e - s,
            "mean": (up if k.endswith("_p") else ua)[:, _AXES.index(k[0])],
            "acceleration_m_s2": a_cal[names.index(k)],
            "gravity_error_m_s2": float(np.linalg.norm(a_cal[names.index(k)]) - g),
        }
        for k, (s, e) in pos.items()
    )
    notes = [] if gravity_m_s2 is not None else [_gravity_note(g, latitude_deg)]
    if tilt_u == 0:
        notes.append(
            "positions taken as exactly vertical (position_u_deg = 0): a tilt δ of a position "
            "moves R_a's off-diagonal elements by δ (rad) and is not in the uncertainty"
        )
    return AccelTriadCalibration(
        scale_misalignment=m,
        scale_factors=scale,
        sensitive_axes=axes,
        misalignment_deg=mis,
        bias=b,
        scale_misalignment_u=arr("scale_misalignment", (3, 3)),
        scale_factors_u=arr("scale_factors", (3,)),
        bias_u=arr("bias", (3,)),
        gravity_m_s2=g,
        noise_std=noise,
        positions=positions,
        notes=tuple(notes),
        output_unit=output_unit,
        _budgets=budgets,
        warnings=clipped,
    )


def gravity_for(gravity_m_s2: float | None, latitude_deg: float | None) -> float:
    """g (m/s²): the one given, else the normal gravity at the latitude, else 9.80665."""
    if latitude_deg is not None:
        check_latitude(latitude_deg)
    if gravity_m_s2 is None:
        return STANDARD_GRAVITY if latitude_deg is None else normal_gravity(latitude_deg)
    try:
        g = float(gravity_m_s2)
    except (TypeError, ValueError):
        raise ConfigError(f"gravity must be a number (m/s²), got {gravity_m_s2!r}.") from None
    if not 9.7 <= g <= 9.9:
        raise ConfigError(
            f"gravity {gravity_m_s2!r} m/s² is no value on the Earth's surface (9.78…9.84); give "
            "g in m/s²."
        )
    return g


def check_latitude(latitude_deg: Any) -> float:
    """The latitude (deg) as a float, refused with one line outside −90…90."""
    try:
        lat = float(latitude_deg)
    except (TypeError, ValueError):
        raise ConfigError(f"--latitude-deg must be a number, got {latitude_deg!r}.") from None
    if not -90.0 <= lat <= 90.0:
        raise ConfigError(f"--latitude-deg must lie in −90…90°, got {latitude_deg!r}.")
    return lat


def _nonnegative(name: str, value: Any) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ConfigError(f"{name} must be a number, got {value!r}.") from None
    if not (math.isfinite(v) and v >= 0):
        raise ConfigError(f"{name} must be finite and ≥ 0, got {value!r}.")
    return v


def _gravity_note(g: float, latitude_deg: float | None) -> str:
    if latitude_deg is None:
        return f"g = {g:.5f} m/s² (standard gravity: no latitude or g given)"
    return (
        f"g = {g:.6f} m/s²: normal gravity (WGS 84) at {float(latitude_deg):g}° latitude, height 0"
    )
