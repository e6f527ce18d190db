"""Gyro-triad calibration from rotations through known angles (Ferraris et al. 1994/1995).
The DUT is turned through a known angle φ_l (typically 360°, by hand or on a table) about each of
its axes; the rate is integrated over each rotation section. With the bias b taken from static
sections, the integrated output of rotation l is::

    Θ_l = Σ (u_k − b) / fs  =  K · φ_l·e_l       (output unit · s)

so the 3×3 matrix K of u = K·ω + b follows from the angle vectors: K = Θ·Φᵀ(Φ·Φᵀ)⁻¹ (Θ: 3×m
integrated outputs, Φ: 3×m true angle vectors in deg). With three rotations about x, y and z this
is Θ·Φ⁻¹, the Ferraris/imucal solution; more rotations (both directions, repeats) are combined by
least squares. The recording's sections (static and rotations, imucal's names or row ranges) are
read by :mod:`rotacal.gyro.rotation_sections`.

Conventions (imucal's, the common one): angles follow the right-hand rule about the named axis
of the DUT — a positive angle turns counter-clockwise seen from the tip of the +axis, and a
correctly signed gyro reads positive during it. The Ferraris protocol (Ferraris et al. 1995;
imucal's guide and its ``FerrarisCalibration(expected_angle=-360)``) turns each axis clockwise
seen from that tip, the gyro reading negative: hence the default ``angle_deg=-360``; give +360
for counter-clockwise turns. A turn done the other way, or an axis mounted reversed, flips the
sign of that column or row of K: a negative diagonal element is named in ``warnings``
(:func:`rotacal.gyro.plausibility.negative_diagonal_warnings`). K here equals imucal's
``K_g @ R_g``; :attr:`RotationCalibration.scale_factors` and ``sensitive_axes`` are its ``K_g``
diagonal and ``R_g``. imucal also removes a g-sensitivity term ``K_ga·a`` (accelerometer-derived)
from the rate before integrating; pass that per-sample offset as ``bias`` (n, 3) to do the same.

References
----------
Ferraris F., Gorini I., Grimaldi U., Parvis M. (1994), Calibration of three-axial rate gyros
without angular velocity standards, Sensors and Actuators A 42:446–449.
Ferraris F., Grimaldi U., Parvis M. (1995), Procedure for effortless in-field calibration of
three-axial rate gyro and accelerometers, Sensors and Materials 7(5):311–330, eqs. (12)–(15).
Küderle A. et al. (2022), imucal — a Python library to calibrate 6 DOF IMUs, JOSS 7(73):4338.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from rotacal.errors import CaptureError, ConfigError
from rotacal.gyro.plausibility import negative_diagonal_warnings, rotation_warnings
from rotacal.gyro.rotation_sections import (
    FERRARIS_ANGLE_DEG,
    FERRARIS_ROTATIONS,
    FERRARIS_STATIC,
    _parse_rotations,
    _parse_static,
    ferraris_sections,
)
from rotacal.gyro.triad import (
    TRIAD_OUTPUT_COLUMNS,
    apply_triad_calibration,
    decompose_scale_misalignment,
)
from rotacal.gyro.uncertainty import (
    as_specs,
    element_key,
    linear_gum,
    uncertainty_json,
)
from rotacal.results import Result, to_jsonable
from rotacal.signal._values import (
    check_magnitudes,
    check_not_constant,
    check_not_copies,
    check_setting,
)
from rotacal.signal.clipping import check_clipping
from rotacal.uncertainty.budget import UncertaintyBudget
from rotacal.uncertainty.gum import Input
from rotacal.uncertainty.specs import (
    TYPE_A_ONLY_NOTE,
    InstrumentSpecs,
    spec_input,
    type_a_note,
)

__all__ = [
    "FERRARIS_ANGLE_DEG",
    "FERRARIS_ROTATIONS",
    "FERRARIS_STATIC",
    "NOMINAL_ANGLE_TOLERANCE",
    "RotationCalibration",
    "calibrate_triad_rotations",
    "ferraris_sections",
]

_AXES = "xyz"
#: Largest relative difference between a rotation's angle seen with the nominal sensitivity and
#: its set angle: MEMS gyros' scale factors are within a few % of nominal, a quarter turn short
#: of 360° is 25 % off.
NOMINAL_ANGLE_TOLERANCE = 0.1


@dataclasses.dataclass(frozen=True)
class RotationCalibration(Result):
    """Gyro-triad calibration from rotations through known angles.

    Output quantities are in the output unit of the rate ("u", e.g. °/s or counts).

    Attributes
    ----------
    scale_misalignment : ndarray (3, 3)
        K in u = K·ω + b (u per °/s); equals imucal's K_g·R_g.
    bias : ndarray (3,)
        b (u): the mean of the static sections (or the ``bias`` given; its mean if per-sample).
    scale_factors, sensitive_axes, misalignment_deg
        :func:`~rotacal.gyro.triad.decompose_scale_misalignment` of K (imucal's K_g diagonal,
        R_g; deg).
    scale_misalignment_u, bias_u : ndarray
        Combined standard uncertainties (u per °/s, u) of the budgets in ``_budgets`` (one per
        element, keys ``scale_misalignment[i][j]`` and ``bias[i]``). K: white noise of the static
        sections integrated over each rotation; the bias subtracted (its white-noise uncertainty,
        common to every rotation); the offset change during each rotation (the spread of the
        static-section means beyond what their noise explains: g-sensitivity, Earth rate);
        the realised angles (``table.set_angle_arcsec`` or ``angle_u_deg``); the DAQ timebase
        (``timebase.relative_error``). b: the white noise of the static mean. The JSON adds
        ``scale_misalignment_U``, ``bias_U``, ``k``, ``coverage_probability`` and
        ``uncertainty_budgets``.
    noise_std : ndarray (3,)
        Per-sample noise of the static sections about their own means (u), pooled.
    static_mean_spread : ndarray (3,)
        Standard deviation of the static-section means (u); 0 with fewer than two sections.
    rotations : tuple of dict
        Per rotation: ``axis``, ``start``, ``stop`` (half-open sample range), ``samples``,
        ``duration_s``, ``angle_deg`` (set), ``integrated_output`` (u·s, bias removed),
        ``angle_measured_deg`` (K⁻¹·Θ: what the calibrated gyro integrates) and
        ``angle_residual_deg`` (its difference from the set angle vector; 0 for three rotations).
    residual_rms : float
        rms of all components of ``angle_residual_deg`` (deg).
    fs_hz : float
        Sampling rate (Hz).
    static_samples : int
        Samples in the static sections.
    angle_u_deg : float
        Standard uncertainty of each realised rotation angle (deg) used in the uncertainties
        (from ``angle_u_deg``, or the standard deviation of ``table.set_angle_arcsec``).
    output_unit : str
        Name of the output unit (for budgets and reports; "" when not given).
    """

    scale_misalignment: np.ndarray
    bias: np.ndarray
    scale_factors: np.ndarray
    sensitive_axes: np.ndarray
    misalignment_deg: np.ndarray
    scale_misalignment_u: np.ndarray
    bias_u: np.ndarray
    noise_std: np.ndarray
    static_mean_spread: np.ndarray
    rotations: tuple[dict[str, Any], ...]
    residual_rms: float
    fs_hz: float
    static_samples: int
    angle_u_deg: float
    notes: tuple[str, ...] = ()
    output_unit: str = ""
    _plot: dict[str, Any] = dataclasses.field(default_factory=dict, repr=False, compare=False)
    _budgets: dict[str, UncertaintyBudget] = dataclasses.field(
        default_factory=dict, repr=False, compare=False
    )

    def calibrate(self, u: Any) -> np.ndarray:
        """ω̂ = K⁻¹(u − b) (°/s) for raw outputs ``u`` (n, 3)."""
        return apply_triad_calibration(u, self.scale_misalignment, self.bias)

    def to_dict(self) -> dict[str, Any]:
        """The JSON fields plus the uncertainty keys (arrays shaped like K and b)."""
        out = super().to_dict()
        if self._budgets:
            shapes = {"scale_misalignment": (3, 3), "bias": (3,)}
            if element_key("g_sensitivity", (0, 0)) in self._budgets:  # gyro.ferraris's K_ga
                shapes["g_sensitivity"] = (3, 3)
            keys = uncertainty_json(self._budgets, shapes)
            out.update(to_jsonable(keys))
        return out


# ------------------------------------------------------------------------------------ checks
def _clipping(
    u: np.ndarray,
    rots: Sequence[tuple],
    stats_: Sequence[tuple[str, int, int]],
    columns: Sequence[str],
    allow_clipped: bool,
) -> tuple[str, ...]:
    """The rails of each output over the rows the calibration uses (the one detector of
    :mod:`rotacal.signal.clipping`); the static sections are where the gyro rests, so the level
    it shows there is not a rail (a one-way rotation starts from it)."""
    used = np.zeros(u.shape[0], dtype=bool)
    rest = np.zeros(u.shape[0], dtype=bool)
    for *_, s, e, _ in rots:
        used[s:e] = True
    for _, s, e in stats_:
        used[s:e] = rest[s:e] = True
    return check_clipping(
        {name: np.where(used, u[:, c], np.nan) for c, name in enumerate(columns)},
        allow_clipped=allow_clipped,
        rest=rest if rest.any() else None,
    )


def _check_sections(
    rate: np.ndarray, ranges: Sequence[tuple[int, int]], columns: Sequence[str]
) -> None:
    """The samples the method uses: finite, within float64's range, varying, not copies."""
    for s, e in ranges:
        seg = rate[s:e]
        bad = ~np.isfinite(seg)
        if bad.any():
            row, col = (int(i) for i in np.argwhere(bad)[0])
            raise CaptureError(
                f"column {columns[col]} has a non-finite value at row {s + row} (in section "
                f"[{s}, {e})); remove or repair that sample."
            )
    used = np.concatenate([rate[s:e] for s, e in ranges])
    for j, name in enumerate(columns):
        check_magnitudes(name, used[:, j], what="a gyro output")
        check_not_constant(name, used[:, j], "the output does not respond to the rotations")
    check_not_copies(
        {name: used[:, j] for j, name in enumerate(columns)},
        "each column must hold its own axis's output",
    )


# ------------------------------------------------------------------------------------ method
def calibrate_triad_rotations(
    rate: Any,
    fs_hz: float,
    rotations: Any,
    *,
    static: Any = None,
    bias: Any = None,
    bias_u: Any = None,
    offset_change_u: Any = None,
    earth_angle_deg: Any = None,
    earth_angle_u_deg: Any = None,
    angle_deg: float = FERRARIS_ANGLE_DEG,
    angle_u_deg: float = 0.0,
    nominal_scale: float | None = None,
    rounding_u: Any = None,
    columns: Sequence[str] = TRIAD_OUTPUT_COLUMNS,
    specs: InstrumentSpecs | None = None,
    output_unit: str = "",
    allow_clipped: bool = False,
) -> RotationCalibration:
    """K and b of a gyro triad from rotations through known angles (Ferraris-style).

    The bias is the mean of all static samples (pooled, as imucal does) unless ``bias`` is given;
    each rotation section's rate minus the bias is summed and divided by fs (the rectangle rule:
    exact for sections that start and end at rest, whose rate and its slope vanish at the ends);
    K solves Θ = K·Φ by least squares over the rotations.

    Parameters
    ----------
    rate : array_like, (n, 3)
        Raw gyro outputs ``ux, uy, uz`` (output unit, e.g. °/s or counts), uniformly sampled.
    fs_hz : float
        Sampling rate (Hz).
    rotations : mapping or sequence
        ``{"x": (start, stop), "y": …, "z": …}`` — one rotation about each DUT axis, half-open
        sample ranges [start, stop) that begin and end at rest (``{"start": …, "end": …}``
        values accepted, as in imucal's section lists) — or a list of ``(axis, start, stop)`` /
        ``(axis, start, stop, angle_deg)`` with axis ``"x"``, ``"-y"``, … or a 3-vector, for more
        than three rotations (both directions, repeats). Together they must span all three axes.
    static : mapping or sequence, optional
        Sample ranges at rest (name → (start, stop), or a list of pairs): the bias and the noise.
    bias : array_like, (3,) or (n, 3), optional
        The offset to remove instead of the static mean (output unit): a constant, or one row per
        sample (for example b + K_ga·a with the g-sensitivity and the calibrated acceleration).
    bias_u : array_like (3,), optional
        Standard uncertainty of a given ``bias`` (output unit), common to every rotation; without
        it the given bias counts as exact.
    offset_change_u : array_like (m, 3), optional
        Standard uncertainty of the mean offset during each rotation beyond ``bias_u`` (output
        unit; one row per rotation, independent between rotations): e.g. K_ga's uncertainty
        times g along the rotation's axis. Replaces the spread of the static means.
    earth_angle_deg : array_like (m, 3), optional
        The angle vector the Earth turns the DUT through during each rotation, in the DUT's axes
        (deg): added to the set angle vector (Θ_l = K·(φ_l·e_l + E_l)).
    earth_angle_u_deg : array_like (m, 3), optional
        Its standard uncertainty per component (deg), Type B (the part of the Earth rate whose
        projection is unknown without the heading).
    angle_deg : float
        Set angle of each rotation given without its own (deg, right-hand rule about the named
        axis). Default −360: one clockwise turn seen from the tip of the +axis, the Ferraris
        protocol as imucal records it (the gyro reads negative); +360 for a counter-clockwise
        turn.
    angle_u_deg : float
        Standard uncertainty of each realised rotation angle (deg, normal, independent between
        rotations), for the uncertainties; leave it 0 when ``specs`` states
        ``table.set_angle_arcsec``.
    nominal_scale : float, optional
        The gyro's nominal sensitivity (output unit per °/s; 1 for outputs in °/s). With it, each
        rotation's integrated output along its own axis, divided by it, must come within
        :data:`NOMINAL_ANGLE_TOLERANCE` of the set angle: three rotations determine K exactly, so
        a turn that was not the angle set (a partial turn, a section cut short, the wrong sign)
        would otherwise pass into K unseen.
    rounding_u : array_like (3,), optional
        Per-sample rounding of a quantised output that its noise does not dither (output unit;
        :func:`rotacal.gyro.accel_triad.rounding_u`): added to the noise of each integrated
        rotation, whose samples sweep the grid and round independently.
    columns : sequence of 3 str
        Names of the rate columns, for messages.
    specs : InstrumentSpecs or None
        The lab's instrument specifications (Type B; a TOML path or a mapping also work). Used:
        ``table.set_angle_arcsec`` (error of each realised angle, realised = set + e, independent
        between rotations) and ``timebase.relative_error`` (a clock ε long makes the sampling
        interval 1/(fs·(1 + ε)), so K = K₀/(1 + ε)); stated means correct the result. None: the
        budgets hold the capture's Type A part (and ``angle_u_deg``).
    output_unit : str
        Name of the output unit, for the budgets and reports.
    allow_clipped : bool
        Calibrate from outputs with samples at the rails anyway (``--allow-clipped``);
        ``warnings`` name the clipping. Refused by default.

    Returns
    -------
    RotationCalibration
        K (output unit per °/s), b (output unit), uncertainties, per-rotation angles.

    Raises
    ------
    ConfigError
        Bad sections (out of range, overlapping a static with a rotation, axes that do not span
        3-D), neither ``static`` nor ``bias``, a bad setting.
    CaptureError
        NaN/inf in a section used; in the sections used, values beyond float64's working range,
        an output that is constant or copies another (or its negative), an output at its rails
        (:mod:`rotacal.signal.clipping`).

    References
    ----------
    Ferraris F., Gorini I., Grimaldi U., Parvis M. (1994), Sensors and Actuators A 42:446–449;
    Ferraris F., Grimaldi U., Parvis M. (1995), Sensors and Materials 7(5):311–330, eqs. (12)–(15)
    (integrated rotations, K = W·Φ⁻¹; numbering as in imucal's implementation).
    JCGM 100:2008 (GUM) §4.2, §4.3, §5.1.2, G.4.1 (the budgets).
    """
    spec = as_specs(specs)
    cols = tuple(columns)
    if len(cols) != 3:
        raise ConfigError(f"columns must name the 3 rate columns, got {columns!r}.")
    u = np.asarray(rate, dtype=float)
    if u.ndim != 2 or u.shape[1] != 3:
        raise CaptureError(
            f"rate must be an (n, 3) array ({', '.join(cols)}); got shape {u.shape}."
        )
    n = u.shape[0]
    try:
        fs = float(fs_hz)
    except (TypeError, ValueError):
        raise ConfigError(f"fs_hz must be a number, got {fs_hz!r}.") from None
    if not math.isfinite(fs) or fs <= 0:
        raise ConfigError(f"fs_hz must be a positive sampling rate (Hz), got {fs_hz!r}.")
    check_setting("--fs-hz", fs, unit="Hz")
    try:
        ang_u = float(angle_u_deg)
    except (TypeError, ValueError):
        raise ConfigError(f"angle_u_deg must be a number, got {angle_u_deg!r}.") from None
    if not math.isfinite(ang_u) or ang_u < 0:
        raise ConfigError(f"angle_u_deg must be ≥ 0 deg, got {angle_u_deg!r}.")
    ang_in = spec_input(spec, "table.set_angle_arcsec", name="angle error")
    if ang_in is not None and ang_u > 0:
        raise ConfigError(
            "give the angle uncertainty once: either angle_u_deg or table.set_angle_arcsec in the "
            "specifications, not both."
        )
    if ang_in is None and ang_u > 0:
        ang_in = Input(
            "angle error",
            0.0,
            ang_u * 3600.0,
            distribution="normal",
            unit="arcsec",
            source="angle_u_deg",
            description=f"normal u={ang_u:g}°",
        )
    tb_in = spec_input(spec, "timebase.relative_error", name="timebase error ε_t")
    ang_mean_deg = 0.0 if ang_in is None else ang_in.value / 3600.0
    eps_t = 0.0 if tb_in is None else tb_in.value
    rots = _parse_rotations(rotations, angle_deg, n)
    stats_ = _parse_static(static, n)
    if not stats_ and bias is None:
        raise ConfigError(
            "give static sections (static=) or the bias (bias=): the bias must be removed before "
            "the rotations are integrated."
        )
    for name, _, _, s, e, _ in rots:
        for sname, ss, se in stats_:
            if s < se and ss < e:
                raise ConfigError(
                    f"static section {sname} [{ss}, {se}) overlaps rotation {name} [{s}, {e}); "
                    "fix the section list."
                )
    # 3×m true angle vectors (deg): the set angles plus the stated mean angle error
    phi = np.column_stack([v * (a + ang_mean_deg) for _, _, v, _, _, a in rots])
    m_rot = len(rots)
    earth, earth_u, change_u = (
        np.zeros((m_rot, 3)) if x is None else _per_rotation(name, x, m_rot)
        for name, x in (
            ("earth_angle_deg", earth_angle_deg),
            ("earth_angle_u_deg", earth_angle_u_deg),
            ("offset_change_u", offset_change_u),
        )
    )
    phi = phi + earth.T
    if np.linalg.matrix_rank(phi, tol=1e-9 * np.abs(phi).max()) < 3:
        have = ", ".join(label for _, label, _, _, _, _ in rots)
        raise ConfigError(
            f"the rotations (about {have}) do not span three axes: add a rotation about each of "
            "x, y and z."
        )
    _check_sections(u, [(s, e) for *_, s, e, _ in rots] + [(s, e) for _, s, e in stats_], cols)
    clipped = _clipping(u, rots, stats_, cols, allow_clipped)

    # --- static sections: bias, noise, spread of the section means
    if stats_:
        idx = np.concatenate([np.arange(s, e) for _, s, e in stats_])
        static_samples = int(idx.size)
        b_static = u[idx].mean(axis=0)
        means = np.array([u[s:e].mean(axis=0) for _, s, e in stats_])
        dev = np.concatenate([u[s:e] - means[i] for i, (_, s, e) in enumerate(stats_)])
        dof = max(static_samples - len(stats_), 1)
        noise = np.sqrt(np.sum(dev**2, axis=0) / dof)
        spread = means.std(axis=0, ddof=1) if len(stats_) > 1 else np.zeros(3)
        # the part of the spread the white noise does not explain (each mean scatters by σ²/N_i)
        inv_n = float(np.mean([1.0 / (e - s) for _, s, e in stats_]))
        excess = np.sqrt(np.maximum(spread**2 - noise**2 * inv_n, 0.0))
        u_b_white = noise / math.sqrt(static_samples)
    else:
        static_samples = 0
        b_static = None
        noise = np.zeros(3)
        spread = np.zeros(3)
        excess = np.zeros(3)
        u_b_white = np.zeros(3)

    noise_theta = noise  # the noise of each integrated rotation's samples
    if rounding_u is not None:
        noise_theta = np.sqrt(noise**2 + _per_rotation("rounding_u", rounding_u, 1)[0] ** 2)
    notes: list[str] = []
    if bias is None:
        assert b_static is not None
        offset: np.ndarray = np.broadcast_to(b_static, u.shape)
        b_out = b_static
        u_b = u_b_white
    else:
        bb = np.asarray(bias, dtype=float)
        if bb.shape == (3,):
            offset = np.broadcast_to(bb, u.shape)
            b_out = bb.copy()
        elif bb.shape == u.shape:
            offset = bb
            b_out = bb.mean(axis=0)
            notes.append("per-sample offsets given (bias of shape (n, 3)); bias is their mean")
        else:
            raise ConfigError(
                f"bias must have shape (3,) or ({n}, 3) like the rate; got {bb.shape}."
            )
        if not np.isfinite(bb).all():
            raise ConfigError("bias has a non-finite value (NaN or inf); give finite offsets.")
        u_b = np.zeros(3) if bias_u is None else _per_rotation("bias_u", bias_u, 1)[0]
        if bias_u is None:
            notes.append("bias given by the caller: its uncertainty is not included")

    # --- integrate each rotation: Θ_l = Σ (u − offset)/fs; a clock ε_t long samples at fs·(1 + ε_t)
    theta = np.column_stack([np.sum(u[s:e] - offset[s:e], axis=0) / fs for *_, s, e, _ in rots])
    if nominal_scale is not None:
        _check_angles(theta, rots, nominal_scale)
    pinv = phi.T @ np.linalg.inv(phi @ phi.T)  # m×3: K = Θ·pinv
    kmat = theta @ pinv / (1.0 + eps_t)
    if not np.isfinite(kmat).all() or abs(np.linalg.det(kmat)) <= 1e-12 * np.abs(kmat).max() ** 3:
        raise CaptureError(
            "the integrated rotations give a singular scale/misalignment matrix: check that the "
            "rotation sections hold the rotations about x, y and z."
        )
    budgets = _rotation_budgets(
        kmat=kmat,
        theta=theta,
        pinv=pinv,
        axes=np.column_stack([v for _, _, v, _, _, _ in rots]),
        labels=[label for _, label, _, _, _, _ in rots],
        samples=np.array([e - s for *_, s, e, _ in rots], dtype=float),
        fs=fs,
        noise=noise_theta,
        noise_dof=float(max(static_samples - len(stats_), 1)),
        b_out=np.asarray(b_out, dtype=float),
        u_b=u_b,
        excess=np.broadcast_to(excess if bias is None else np.zeros(3), (m_rot, 3))
        if offset_change_u is None
        else change_u,
        earth_u=earth_u,
        sections=len(stats_),
        bias_given=bias is not None and bias_u is None,
        bias_source=("static mean", "Type A: white noise of the static samples")
        if bias is None
        else ("the offset given", "bias_u, as stated by the caller"),
        ang_in=ang_in,
        tb_in=tb_in,
        spec=spec,
        output_unit=output_unit,
    )
    u_k = np.array(
        [[budgets[element_key("scale_misalignment", (i, j))].u for j in range(3)] for i in range(3)]
    )
    u_b = np.array([budgets[element_key("bias", (i,))].u for i in range(3)])
    if ang_mean_deg != 0.0 or eps_t != 0.0:
        notes.append(
            f"stated mean errors correct K: realised angles = set + {ang_mean_deg * 3600:.3g}″, "
            f"K = K₀/(1 + {eps_t:.3g}) for the timebase"
        )

    # m×3 (deg): what the calibrated gyro integrates, less the Earth's turn
    measured = apply_triad_calibration(theta.T / (1.0 + eps_t), kmat, np.zeros(3)) - earth
    phi = phi - earth.T
    resid = measured - phi.T
    scale, axes_r, mis = decompose_scale_misalignment(kmat)
    diag_dom = np.all(np.abs(np.diag(kmat)) > np.sum(np.abs(kmat), axis=1) - np.abs(np.diag(kmat)))
    if not diag_dom:
        notes.append(
            "K is not diagonally dominant: check that each rotation section is labelled with the "
            "axis it turns about"
        )
    rot_rows = tuple(
        {
            "name": name,
            "axis": label,
            "start": s,
            "stop": e,
            "samples": e - s,
            "duration_s": (e - s) / fs,
            "angle_deg": a,
            "integrated_output": theta[:, i],
            "angle_measured_deg": measured[i],
            "angle_residual_deg": resid[i],
        }
        for i, (name, label, _, s, e, a) in enumerate(rots)
    )
    plot = {
        "rate": u,
        "offset": b_out,
        "rotations": [(label, s, e) for _, label, _, s, e, _ in rots],
        "static": [(name, s, e) for name, s, e in stats_],
    }
    return RotationCalibration(
        scale_misalignment=kmat,
        bias=np.asarray(b_out, dtype=float),
        scale_factors=scale,
        sensitive_axes=axes_r,
        misalignment_deg=mis,
        scale_misalignment_u=u_k,
        bias_u=u_b,
        noise_std=noise,
        static_mean_spread=spread,
        rotations=rot_rows,
        residual_rms=float(np.sqrt(np.mean(resid**2))),
        fs_hz=fs,
        static_samples=static_samples,
        angle_u_deg=0.0 if ang_in is None else ang_in.u / 3600.0,
        notes=tuple(notes),
        output_unit=output_unit,
        _plot=plot,
        _budgets=budgets,
        warnings=(
            *clipped,
            *negative_diagonal_warnings(
                kmat,
                cols,
                "the turn went the other way: --angle-deg is −360 for a clockwise turn seen from "
                "the tip of the +axis (the Ferraris protocol), +360 for a counter-clockwise one",
            ),
            *rotation_warnings(
                u,
                offset,
                [(label, s, e) for _, label, _, s, e, _ in rots],
                resid,
                _angle_u(noise_theta, kmat, [e - s for *_, s, e, _ in rots], fs),
            ),
        ),
    )


def _check_angles(theta: np.ndarray, rots: Sequence[tuple], nominal_scale: float) -> None:
    """Refuse a rotation whose integrated output along its axis, over the nominal sensitivity,
    is not within :data:`NOMINAL_ANGLE_TOLERANCE` of its set angle."""
    try:
        s0 = float(nominal_scale)
    except (TypeError, ValueError):
        raise ConfigError(f"nominal_scale must be a number, got {nominal_scale!r}.") from None
    if not (math.isfinite(s0) and s0 != 0):
        raise ConfigError(f"nominal_scale must be finite and non-zero, got {nominal_scale!r}.")
    for i, (name, label, axis, _, _, a) in enumerate(rots):
        seen = float(axis @ theta[:, i]) / s0
        if abs(seen / a - 1.0) > NOMINAL_ANGLE_TOLERANCE:
            raise CaptureError(
                f"the rotation about {label} (section {name}) integrates to {seen:.4g}° with the "
                f"nominal sensitivity {s0:g} per °/s, not the set {a:g}° (±"
                f"{100 * NOMINAL_ANGLE_TOLERANCE:g} %): not a full turn, a section that misses "
                "part of it, or the other sense of rotation; fix the section list or --angle-deg."
            )


def _per_rotation(name: str, value: Any, m: int) -> np.ndarray:
    """An (m, 3) array of per-rotation values (a (3,) value is the same for every rotation)."""
    try:
        arr = np.broadcast_to(np.asarray(value, dtype=float), (m, 3)).copy()
    except (TypeError, ValueError):
        raise ConfigError(f"{name} must have shape (3,) or ({m}, 3), got {value!r}.") from None
    if not np.isfinite(arr).all() or ("_u" in name and np.any(arr < 0)):
        raise ConfigError(f"{name} must be finite (and ≥ 0 for an uncertainty), got {value!r}.")
    return arr


def _angle_u(noise: np.ndarray, kmat: np.ndarray, samples: Sequence[int], fs: float) -> np.ndarray:
    """White-noise standard uncertainty (deg) of each rotation's measured angle vector K⁻¹·Θ:
    Θ_c of a section of N samples scatters by σ_c·√N/fs (output unit·s)."""
    kinv = np.linalg.inv(kmat)
    cov_unit = (kinv * noise[None, :] ** 2) @ kinv.T  # K⁻¹·diag(σ²)·K⁻ᵀ per (sample/fs)²
    return np.array([np.sqrt(np.diag(cov_unit) * n) / fs for n in samples])


def _rotation_budgets(
    *,
    kmat: np.ndarray,
    theta: np.ndarray,
    pinv: np.ndarray,
    axes: np.ndarray,
    labels: Sequence[str],
    samples: np.ndarray,
    fs: float,
    noise: np.ndarray,
    noise_dof: float,
    b_out: np.ndarray,
    u_b: np.ndarray,
    excess: np.ndarray,
    earth_u: np.ndarray,
    sections: int,
    bias_given: bool,
    bias_source: tuple[str, str],
    ang_in: Input | None,
    tb_in: Input | None,
    spec: InstrumentSpecs | None,
    output_unit: str,
) -> dict[str, UncertaintyBudget]:
    """One GUM budget per element of K (9) and b (3), all inputs independent.

    K_cj = Σ_l Θ_cl·P_lj/(1 + ε_t) (P = Φᵀ(ΦΦᵀ)⁻¹) with Θ_cl = Σ(u_c − b_c)/fs. Inputs of K_cj,
    for each rotation l with P_lj ≠ 0: Θ_cl (white noise σ_c·√N_l/fs, c = P_lj/(1 + ε_t)), the
    offset change during it (u = the excess spread of the static means, c = −T_l·P_lj/(1 + ε_t)),
    its angle error e_l (c = −(K·a_l)_c·P_lj/3600 per arcsec, a_l the axis); once: the bias
    subtracted (c = −Σ_l T_l·P_lj/(1 + ε_t), common to every rotation) and ε_t
    (c = −K_cj/(1 + ε_t)). b_c: the static mean (σ_c/√N).

    References
    ----------
    Ferraris et al. (1995), eqs. (12)–(15); JCGM 100:2008 (GUM) §4.2, §4.3, §5.1.2 eq. (10),
    G.4.1.
    """
    ou = output_unit or "output unit"
    unit_k = f"{ou}/(°/s)"
    g = 1.0 + (0.0 if tb_in is None else tb_in.value)
    dur = samples / fs
    m = len(labels)
    common = []
    if (
        note := type_a_note(spec, ("table.set_angle_arcsec", "timebase.relative_error"))
    ) is not None:
        common.append(
            note if ang_in is None else note.replace("Type A only", "Type A and angle_u_deg")
        )
    if spec is not None:  # stated means correct K (GUM §3.2.4): angles set + ā, K = K₀/(1 + ε̄_t)
        for key in ("table.set_angle_arcsec", "timebase.relative_error"):
            if (fix := spec.correction_note(key)) is not None:
                common.append(fix)
    common.append(
        "Type A assumes white noise (from the static sections) during the rotations and the "
        "linear model u = K·ω + b."
    )
    budgets: dict[str, UncertaintyBudget] = {}
    for c in range(3):
        for j in range(3):
            name = f"K_{_AXES[c]}{_AXES[j]}"
            ins: list[Input] = []
            sens: list[float] = []
            for ln in range(m):
                p = float(pinv[ln, j])
                if p == 0.0:
                    continue
                rot = f"rotation about {labels[ln]}" + (f" #{ln}" if m > 3 else "")
                ins.append(
                    Input(
                        f"Θ_{_AXES[c]} over the {rot}",
                        float(theta[c, ln]),
                        float(noise[c]) * math.sqrt(samples[ln]) / fs,
                        noise_dof,
                        "normal",
                        f"{ou}·s",
                        f"Type A: white noise of the static sections, {int(samples[ln])} samples",
                    )
                )
                sens.append(p / g)
                if excess[ln, c] > 0:
                    ins.append(
                        Input(
                            f"offset change during the {rot}",
                            0.0,
                            float(excess[ln, c]),
                            float(max(sections - 1, 1)),
                            "normal",
                            ou,
                            "Type A: spread of the static-section means beyond their noise",
                        )
                    )
                    sens.append(-dur[ln] * p / g)
                if ang_in is not None:
                    ins.append(dataclasses.replace(ang_in, name=f"angle error of the {rot}"))
                    sens.append(-float(kmat[c] @ axes[:, ln]) * p / 3600.0)
                for k in np.flatnonzero(earth_u[ln] > 0):
                    ins.append(
                        Input(
                            f"Earth's turn about {_AXES[k]} during the {rot}",
                            0.0,
                            float(earth_u[ln, k]),
                            unit="deg",
                            source="earth rate",
                            description="Type B: the projection unknown without the heading",
                        )
                    )
                    sens.append(-float(kmat[c, k]) * p)
            if not bias_given:
                ins.append(
                    Input(
                        f"bias b_{_AXES[c]} subtracted ({bias_source[0]})",
                        float(b_out[c]),
                        float(u_b[c]),
                        noise_dof,
                        "normal",
                        ou,
                        f"{bias_source[1]}, common to every rotation",
                    )
                )
                sens.append(-float(dur @ pinv[:, j]) / g)
            if tb_in is not None:
                ins.append(tb_in)
                sens.append(-float(kmat[c, j]) / g)
            b = linear_gum(name, unit_k, float(kmat[c, j]), ins, sens).budget(0)
            budgets[element_key("scale_misalignment", (c, j))] = dataclasses.replace(
                b, notes=b.notes + tuple(common)
            )
    for c in range(3):
        name = f"b_{_AXES[c]}"
        if bias_given:
            b0 = Input(f"{name} given by the caller", float(b_out[c]), 0.0, unit=ou, source="bias=")
            extra = ["bias given by the caller: its uncertainty is not included."]
        else:
            b0 = Input(
                f"{name}: {bias_source[0]}",
                float(b_out[c]),
                float(u_b[c]),
                noise_dof,
                "normal",
                ou,
                bias_source[1],
            )
            extra = []
        b = linear_gum(name, ou, float(b_out[c]), [b0], [1.0]).budget(0)
        extra.append(
            TYPE_A_ONLY_NOTE
            if spec is None
            else "no instrument specification applies to the static mean: Type A only."
        )
        budgets[element_key("bias", (c,))] = dataclasses.replace(b, notes=b.notes + tuple(extra))
    return budgets
