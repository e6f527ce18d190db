"""Ferraris calibration of a 6-DOF IMU with gravity and the Earth's rotation separated.

The session (Ferraris et al. 1995; imucal's names) holds six static positions, each axis up and
down, and a turn through a known angle about each axis. The gyro model (imucal's, with the Earth
rate added)::

    u_g = K·(ω + Ω_E) + b + K_ga·a        (output unit; ω, Ω_E in °/s, a in m/s²)

with a the specific force measured by the accelerometer triad, calibrated first from the same six
positions (:mod:`rotacal.gyro.accel_triad`). Steps:

1. The accelerometer: K_a, R_a, b_a; a(t) = (K_a·R_a)⁻¹·(u_a − b_a) for every sample.
2. The Earth rate in the DUT's axes: its vertical component Ω_E·sin L lies along the measured
   "up" a/|a| whatever the heading, so it is removed exactly at the stated latitude L. The
   horizontal component Ω_E·cos L points North, and the heading of each position is not
   recorded: it is not removed, and its projection enters the uncertainty as a heading uniform
   over the circle (u = Ω_E·cos L·√((1 − û_k²)/2) on axis k, û the up unit vector). Without a
   latitude nothing is removed and each component is u = Ω_E/√3 (a random direction).
3. The g-sensitivity from the positions' gyro means (Ferraris eq. 9, imucal):
   K_ga[:, j] = (U_p − U_a − K·(E_p − E_a))[:, j]/(2g), E the Earth rate vector (vertical part)
   of each position; the bias b is the mean over the static samples of u − K_ga·a − K·E.
4. The rotations (:func:`~rotacal.gyro.rotations.calibrate_triad_rotations`): b + K_ga·a(t) is
   removed sample by sample before integrating, and the angle the Earth turned the DUT through
   during each rotation (its vertical part) is added to the set angle vector. K enters steps 3 and
   4 only through the Earth's terms (10⁻⁴ of the output), so three passes settle it to rounding.

Compared with imucal (which ignores the Earth rate and uses g = 9.81): with ``latitude_deg=None``
and ``gravity_m_s2=9.81`` this is imucal's computation (b_g then differs by the mean of K_ga·a over
the static samples, which imucal leaves in b_g).

References
----------
Ferraris F., Grimaldi U., Parvis M. (1995), Procedure for effortless in-field calibration of
three-axial rate gyro and accelerometers, Sensors and Materials 7(5):311–330, eqs. (9), (12)–(15).
Küderle A. et al. (2022), imucal — a Python library to calibrate 6 DOF IMUs, JOSS 7(73):4338.
Titterton D. H., Weston J. L. (2004), Strapdown Inertial Navigation Technology, 2nd ed., §3.4.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from rotacal.errors import CaptureError
from rotacal.gyro.accel_triad import (
    ACCEL_OUTPUT_COLUMNS,
    AccelTriadCalibration,
    calibrate_accel_triad,
    check_disjoint,
    check_latitude,
    jacobian_budgets,
    rounding_inputs,
    rounding_u,
    static_positions,
    with_rounding,
)
from rotacal.gyro.multiposition_model import EARTH_RATE_DEG_H
from rotacal.gyro.rotation_sections import FERRARIS_ANGLE_DEG, _range, ferraris_sections
from rotacal.gyro.rotations import RotationCalibration, calibrate_triad_rotations
from rotacal.gyro.triad import TRIAD_OUTPUT_COLUMNS
from rotacal.gyro.uncertainty import element_key
from rotacal.uncertainty.gum import Input
from rotacal.uncertainty.specs import InstrumentSpecs

__all__ = ["FerrarisGyroCalibration", "calibrate_ferraris"]

_AXES = "xyz"
_PASSES = 3


@dataclasses.dataclass(frozen=True)
class FerrarisGyroCalibration(RotationCalibration):
    """A :class:`~rotacal.gyro.rotations.RotationCalibration` with gravity and the Earth rate
    separated (see :mod:`rotacal.gyro.ferraris`).

    Attributes (besides those of RotationCalibration)
    -------------------------------------------------
    g_sensitivity, g_sensitivity_u : ndarray (3, 3)
        K_ga (output unit per m/s²) and its standard uncertainty (budgets under
        ``g_sensitivity[i][j]``: the noise of the position means, the Earth rate's horizontal
        projection).
    latitude_deg : float or None
        The latitude whose Earth rate was removed (None: not removed, in the uncertainty).
    earth_rate_vertical_deg_s : float
        Ω_E·sin L removed along the measured vertical (°/s); 0 without a latitude.
    gravity_m_s2 : float
        g of the accelerometer calibration and of K_ga (m/s²).
    accelerometer : AccelTriadCalibration or None
        The accelerometer triad's calibration of the same positions.
    """

    g_sensitivity: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros((3, 3)))
    g_sensitivity_u: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros((3, 3)))
    latitude_deg: float | None = None
    earth_rate_vertical_deg_s: float = 0.0
    gravity_m_s2: float = 0.0
    accelerometer: AccelTriadCalibration | None = None


def _up(a: np.ndarray) -> np.ndarray:
    norm = np.linalg.norm(a, axis=-1, keepdims=True)
    return a / np.where(norm > 0, norm, 1.0)


def calibrate_ferraris(
    gyro: Any,
    acc: Any,
    fs_hz: float,
    sections: Mapping[str, Any],
    *,
    latitude_deg: float | None = None,
    gravity_m_s2: float | None = None,
    angle_deg: float = FERRARIS_ANGLE_DEG,
    position_u_deg: float = 0.0,
    nominal_scale: float | None = None,
    columns: Sequence[str] = TRIAD_OUTPUT_COLUMNS,
    acc_columns: Sequence[str] = ACCEL_OUTPUT_COLUMNS,
    specs: InstrumentSpecs | None = None,
    output_unit: str = "",
    acc_unit: str = "",
    allow_clipped: bool = False,
) -> FerrarisGyroCalibration:
    """Gyro triad K, b, K_ga (and the accelerometer triad) from a Ferraris session.

    Parameters
    ----------
    gyro, acc : array_like, (n, 3)
        Raw gyro outputs (output unit, e.g. °/s or counts) and raw accelerometer outputs (output
        unit, e.g. m/s² or counts), the same rows, uniformly sampled.
    fs_hz : float
        Sampling rate (Hz).
    sections : mapping
        imucal's section list: ``x_p, x_a, y_p, y_a, z_p, z_a`` (static, each axis up and down)
        and ``x_rot, y_rot, z_rot`` (each turn, from rest to rest), half-open sample ranges.
    latitude_deg : float, optional
        Geodetic latitude of the session (deg): the vertical Earth rate is removed, and g is the
        normal gravity there unless ``gravity_m_s2`` is given.
    gravity_m_s2 : float, optional
        Local gravity (m/s²); default the normal gravity at the latitude, else 9.80665.
    angle_deg : float
        Set angle of each turn (deg, right-hand rule; −360 is the Ferraris protocol's clockwise
        turn).
    position_u_deg : float
        Standard uncertainty of each static position's tilt (deg), for the accelerometer.
    nominal_scale : float, optional
        The gyro's nominal sensitivity (output unit per °/s): each turn must come within 10 % of
        the set angle with it (see :func:`~rotacal.gyro.rotations.calibrate_triad_rotations`).
    columns, acc_columns : sequence of 3 str
        Names of the gyro and accelerometer columns, for messages.
    specs : InstrumentSpecs or None
        As in :func:`~rotacal.gyro.rotations.calibrate_triad_rotations`.
    output_unit, acc_unit : str
        Names of the gyro and accelerometer output units.
    allow_clipped : bool
        Calibrate from outputs at their rails anyway (``warnings`` name them).

    Returns
    -------
    FerrarisGyroCalibration

    Raises
    ------
    ConfigError
        A section missing or overlapping another, a bad latitude or g, bad settings.
    CaptureError
        As for the accelerometer and the rotations; NaN/inf in an accelerometer column during a
        rotation.

    References
    ----------
    Ferraris F., Grimaldi U., Parvis M. (1995), Sensors and Materials 7(5):311–330, eqs. (9),
    (12)–(23); imucal (Küderle et al. 2022) for the section names and conventions.
    """
    rotations, static = ferraris_sections(sections)
    ug = np.asarray(gyro, dtype=float)
    ua = np.asarray(acc, dtype=float)
    if ug.ndim != 2 or ug.shape[1] != 3 or ua.shape != ug.shape:
        raise CaptureError(
            f"gyro and acc must be (n, 3) arrays of the same rows; got {ug.shape} and {ua.shape}."
        )
    n = ug.shape[0]
    pos = static_positions(static, n)
    check_disjoint({**pos, **{f"{k}_rot": _range(f"{k}_rot", v, n) for k, v in rotations.items()}})
    lat = None if latitude_deg is None else check_latitude(latitude_deg)
    accel = calibrate_accel_triad(
        ua,
        pos,
        gravity_m_s2=gravity_m_s2,
        latitude_deg=lat,
        position_u_deg=position_u_deg,
        columns=acc_columns,
        output_unit=acc_unit,
        allow_clipped=allow_clipped,
    )
    g = accel.gravity_m_s2
    rot_rows = [rotations[a] for a in _AXES]
    for s, e in rot_rows:
        if not np.isfinite(ua[s:e]).all():
            raise CaptureError(
                f"an accelerometer column has a non-finite value in the rotation [{s}, {e}); "
                "remove or repair that sample."
            )
    a = accel.calibrate(np.nan_to_num(ua))  # m/s²; rows outside the sections are not used
    up = _up(a)
    we = EARTH_RATE_DEG_H / 3600.0
    sin_l = 0.0 if lat is None else math.sin(math.radians(lat))
    cos_l = 1.0 if lat is None else math.cos(math.radians(lat))

    def horizontal_u(u_hat: np.ndarray) -> np.ndarray:
        """u of the Earth rate's unknown part on each axis (°/s), for an up unit vector."""
        if lat is None:
            return np.full(3, we / math.sqrt(3.0))
        return we * cos_l * np.sqrt(np.clip(1.0 - u_hat**2, 0.0, 1.0) / 2.0)

    # --- static positions: gyro means, calibrated accelerations, up vectors, Earth terms
    names = [f"{ax}_{t}" for t in "pa" for ax in _AXES]
    counts = np.array([pos[k][1] - pos[k][0] for k in names], dtype=float)
    gm = np.array([ug[slice(*pos[k])].mean(axis=0) for k in names])  # (6, 3) output unit
    am = np.array([a[slice(*pos[k])].mean(axis=0) for k in names])  # (6, 3) m/s²
    em = we * sin_l * np.array([up[slice(*pos[k])].mean(axis=0) for k in names])  # (6, 3) °/s
    eu = np.array([horizontal_u(v) for v in _up(am)])  # (6, 3) °/s
    w = counts / counts.sum()
    dev = np.concatenate([ug[slice(*pos[k])] - gm[i] for i, k in enumerate(names)])
    noise = np.sqrt(np.sum(dev**2, axis=0) / max(dev.shape[0] - 6, 1))

    def static_model(gmeans: np.ndarray, e: np.ndarray, kmat: np.ndarray) -> tuple:
        """K_ga (Ferraris eq. 9 less the Earth's part) and b (the pooled static mean of
        u − K_ga·a − K·E), from the position means."""
        kga = (gmeans[:3] - gmeans[3:] - (e[:3] - e[3:]) @ kmat.T).T / (2.0 * g)
        b = w @ (gmeans - am @ kga.T - e @ kmat.T)
        return kga, b

    # Earth's turn during each rotation (its vertical part) and the unknown part's u (deg)
    dur = np.array([(e - s) / fs_hz for s, e in rot_rows])
    earth_rot = np.array([we * sin_l * up[s:e].sum(axis=0) / fs_hz for s, e in rot_rows])
    earth_rot_u = np.array(
        [dur[i] * horizontal_u(_up(a[s:e].mean(axis=0))) for i, (s, e) in enumerate(rot_rows)]
    )
    a_rot = np.array([a[s:e].mean(axis=0) for s, e in rot_rows])  # (3, 3) m/s²

    uq = rounding_u(ug[np.concatenate([np.arange(*pos[k]) for k in names])], ug, noise)
    rounding = rounding_inputs(uq, columns, names, output_unit or "output unit")
    kmat = np.eye(3)  # K enters only the Earth's terms: the first pass starts from unity
    budgets: dict[str, Any] = {}
    result: RotationCalibration | None = None
    for _ in range(_PASSES):
        kga, b = static_model(gm, em, kmat)
        inputs = [
            Input(
                f"mean of {columns[c]} in {names[p]}",
                float(gm[p, c]),
                float(noise[c] / math.sqrt(counts[p])),
                float(max(dev.shape[0] - 6, 1)),
                "normal",
                output_unit or "output unit",
                "Type A: white noise of the position",
            )
            for p in range(6)
            for c in range(3)
        ] + [
            Input(
                f"Earth rate about {_AXES[c]} in {names[p]} (heading unknown)",
                0.0,
                float(eu[p, c]),
                unit="°/s",
                source="earth rate",
                description="Type B: the heading uniform over the circle"
                if lat is not None
                else "Type B: no latitude given, a random direction",
            )
            for p in range(6)
            for c in range(3)
        ]
        inputs += rounding
        km = kmat

        def model(x: np.ndarray, km: np.ndarray = km) -> dict[str, np.ndarray]:
            kk, bb = static_model(with_rounding(x, 36), em + x[18:36].reshape(6, 3), km)
            return {"g_sensitivity": kk, "bias": bb}

        unit = output_unit or "output unit"
        budgets = jacobian_budgets(
            model,
            inputs,
            {"g_sensitivity": f"{unit}/(m/s²)", "bias": unit},
            ("Type A assumes white noise in each static position.",),
        )
        u_kga = np.reshape(
            [budgets[element_key("g_sensitivity", i)].u for i in np.ndindex(3, 3)], (3, 3)
        )
        u_b = np.array([budgets[element_key("bias", (i,))].u for i in range(3)])
        offset = b + a @ kga.T
        result = calibrate_triad_rotations(
            ug,
            fs_hz,
            rotations,
            static=static,
            bias=offset,
            bias_u=u_b,
            offset_change_u=np.sqrt((a_rot**2) @ (u_kga**2).T),
            earth_angle_deg=earth_rot,
            earth_angle_u_deg=earth_rot_u,
            angle_deg=angle_deg,
            nominal_scale=nominal_scale,
            rounding_u=uq,
            columns=columns,
            specs=specs,
            output_unit=output_unit,
            allow_clipped=allow_clipped,
        )
        kmat = result.scale_misalignment
    assert result is not None
    all_budgets = {**result._budgets, **budgets}
    notes = [x for x in result.notes if not x.startswith(("per-sample offsets", "bias given"))]
    notes += list(accel.notes)
    if lat is None:
        notes.append(
            "no latitude given: the Earth rate (15.04 °/h) is not removed and enters the "
            "uncertainty as a rate of unknown direction"
        )
    else:
        notes.append(
            f"Earth rate: Ω_E·sin L = {we * sin_l * 3600:.4g} °/h removed along the measured "
            f"vertical; the horizontal Ω_E·cos L = {we * cos_l * 3600:.4g} °/h (heading not "
            "recorded) is in the uncertainty"
        )
    fields = {f.name: getattr(result, f.name) for f in dataclasses.fields(RotationCalibration)}
    fields.update(
        bias=b,
        bias_u=u_b,
        notes=tuple(notes),
        _budgets=all_budgets,
        warnings=(*accel.warnings, *result.warnings),
    )
    return FerrarisGyroCalibration(
        **fields,
        g_sensitivity=kga,
        g_sensitivity_u=u_kga,
        latitude_deg=lat,
        earth_rate_vertical_deg_s=we * sin_l,
        gravity_m_s2=g,
        accelerometer=accel,
    )
