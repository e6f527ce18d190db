"""Position accuracy of an indexing (rotary) table against a reference: the acceptance test.

The table is sent to target positions θ_i, run after run, in one or both directions of approach;
at each stop a reference gives the actual angle, and the positional deviation is actual minus
target (ISO 230-2:2014, clause 3). Three kinds of reference:

* **a reference encoder** (column ``reference_deg``: its reading at each stop) — the deviation is
  (reference − target)·3600 arcsec, wrapped into ±180°;
* **the same, self-calibrated** (``selfcal``: a ``rotacal selfcal`` result, Kokuyama et al.
  2015): the reading is corrected by the encoder's graduation deviation first
  (:mod:`rotacal.position.reference`); the table's own encoder so calibrated serves as reference;
* **an autocollimator on an N-face polygon** (column ``error_arcsec``: the autocollimator reading,
  ``polygon_faces`` N): positions at k·360°/N; with runs in which the polygon was turned on the
  table by different numbers of faces the polygon's face errors are separated from the table's
  by closure (:mod:`rotacal.position.polygon`), otherwise they are flagged as inseparable.

Without a reference column the ``error_arcsec`` readings are taken as the deviations themselves.
The results: the error curve e(θ_i) (the mean bidirectional deviation, or the one direction's
mean), its peak-to-peak, its harmonics (:mod:`rotacal.position.harmonics`) and the ISO 230-2 values
of the axis (:mod:`rotacal.position.iso230`), each with its standard uncertainty.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from rotacal.errors import CaptureError, ConfigError
from rotacal.position.arrange import Approaches, arrange_approaches
from rotacal.position.harmonics import HarmonicFit, fit_harmonics
from rotacal.position.iso230 import (
    AXIS_VALUES,
    ISO_RUNS,
    AxisStatistics,
    axis_statistics,
    scatter_dof,
)
from rotacal.position.polygon import PolygonSeparation, separate_polygon
from rotacal.position.reference import selfcal_correction
from rotacal.results import Result
from rotacal.signal._values import check_magnitudes
from rotacal.uncertainty.coverage import coverage_factor

__all__ = ["DEFAULT_HARMONICS", "PositionAccuracy", "position_accuracy"]

#: One turn in arcsec: no deviation (or uncertainty of one) is larger.
TURN_ARCSEC = 1_296_000.0
#: Angles beyond this many degrees (2778 turns) are refused: not a table's position, and their
#: reduction modulo 360° would lose the arcsec digits in float64.
MAX_ANGLE_DEG = 1e6

#: Harmonics fitted by default (orders 1 … 4: eccentricity to the fourth-order lobing).
DEFAULT_HARMONICS = 4

FloatArray = NDArray[np.float64]


@dataclasses.dataclass(frozen=True)
class PositionAccuracy(Result):
    """The result of :func:`position_accuracy`; every angle in arcsec unless named ``_deg``.

    ``error_curve_arcsec`` is e(θ_i) at ``positions_deg``; ``error_forward_arcsec`` /
    ``error_reverse_arcsec`` and ``std_forward_arcsec`` / ``std_reverse_arcsec`` are x̄_i and
    s_i of each direction (None when absent); ``iso230_2`` maps each ISO 230-2 value (see
    :data:`rotacal.position.iso230.AXIS_VALUES`) to its value; the JSON flattens it as
    ``<name>_arcsec`` and ``<name>_arcsec_u``, with each one's effective degrees of freedom and
    coverage factor for p = 95 % in ``dof`` and ``k`` (keyed ``<name>_arcsec``, and
    ``error_pp_arcsec``; a ``dof`` of null beside a k is infinite: the u holds no scatter).
    ``polygon`` holds the cross-calibration (None without a polygon), ``harmonics`` the fit
    (None with ``harmonics=0``).
    """

    reference: str
    positions_deg: FloatArray
    directions: tuple[int, ...]
    runs: int
    run_labels: tuple[int, ...]
    error_curve_arcsec: FloatArray
    error_curve_arcsec_u: FloatArray
    error_pp_arcsec: float
    error_pp_arcsec_u: float
    reference_u_arcsec: float
    notes: tuple[str, ...]
    _stats: AxisStatistics = dataclasses.field(repr=False)
    _deviations: FloatArray = dataclasses.field(repr=False)
    _harmonics: HarmonicFit | None = dataclasses.field(repr=False)
    _polygon: PolygonSeparation | None = dataclasses.field(repr=False)
    _polygon_shifts: tuple[int, ...] = dataclasses.field(repr=False)
    _polygon_source: str = dataclasses.field(repr=False)
    _pooled: tuple[float, float] | None = dataclasses.field(repr=False)
    _selfcal: dict[str, Any] | None = dataclasses.field(repr=False)

    def by_direction(self, sign: int, what: str) -> FloatArray | None:
        """x̄_i (``what="mean"``), s_i (``"std"``) or their u (``"mean_u"``, ``"std_u"``) of the
        direction ``sign``, or None."""
        if sign not in self.directions:
            return None
        table = getattr(self._stats, what)
        return None if table is None else table[self.directions.index(sign)]

    def degrees_of_freedom(self) -> dict[str, float | None]:
        """ν_eff of each stated value's u (:func:`rotacal.position.iso230.scatter_dof`), keyed
        as in the JSON; None where the u is undefined."""
        st = self._stats
        out = {f"{name}_arcsec": st.values_dof[name] for name in AXIS_VALUES}
        hi, lo = int(np.argmax(st.curve)), int(np.argmin(st.curve))
        scatter = [*st.curve_scatter[:, hi].tolist(), *st.curve_scatter[:, lo].tolist()]
        out["error_pp_arcsec"] = scatter_dof(self.error_pp_arcsec_u, scatter, st.dof_scatter)
        return out

    def coverage_factors(self) -> dict[str, float | None]:
        """k = t₉₅(ν_eff) (GUM G.4) of each stated value, keyed as in the JSON."""
        return {
            key: None if dof is None else coverage_factor(dof)
            for key, dof in self.degrees_of_freedom().items()
        }

    def to_dict(self) -> dict[str, Any]:
        out = super().to_dict()
        out["dof"] = self.degrees_of_freedom()
        out["k"] = self.coverage_factors()
        for sign, word in ((1, "forward"), (-1, "reverse")):
            out[f"error_{word}_arcsec"] = _list(self.by_direction(sign, "mean"))
            out[f"error_{word}_arcsec_u"] = _list(self.by_direction(sign, "mean_u"))
            out[f"std_{word}_arcsec"] = _list(self.by_direction(sign, "std"))
            out[f"std_{word}_arcsec_u"] = _list(self.by_direction(sign, "std_u"))
        for name in AXIS_VALUES:
            out[f"{name}_arcsec"] = self._stats.values[name]
            out[f"{name}_arcsec_u"] = self._stats.values_u[name]
        pooled = self._pooled
        out["repeatability_pooled_std_arcsec"] = None if pooled is None else pooled[0]
        out["repeatability_pooled_std_arcsec_u"] = None if pooled is None else pooled[1]
        fit = self._harmonics
        out["harmonic_orders"] = [] if fit is None else list(fit.orders)
        for key, attr in (
            ("harmonic_amplitudes_arcsec", "amplitudes_arcsec"),
            ("harmonic_amplitudes_arcsec_u", "amplitudes_arcsec_u"),
            ("harmonic_phases_deg", "phases_deg"),
            ("harmonic_phases_deg_u", "phases_deg_u"),
            ("harmonic_cos_arcsec", "cos_arcsec"),
            ("harmonic_sin_arcsec", "sin_arcsec"),
        ):
            out[key] = [] if fit is None else _list(getattr(fit, attr))
        out["harmonic_residual_rms_arcsec"] = None if fit is None else fit.residual_rms_arcsec
        out["harmonic_dof"] = None if fit is None else fit.dof
        out["harmonic_effective_dof"] = None if fit is None else fit.effective_dof
        out["harmonic_k"] = None if fit is None else fit.coverage_k
        poly = self._polygon
        if poly is not None:
            out["polygon_faces"] = poly.face_errors_arcsec.size
            out["polygon_shifts"] = list(self._polygon_shifts)
            out["polygon_separated"] = self._polygon_source in ("closure", "stated")
            out["polygon_face_errors_source"] = self._polygon_source
            out["polygon_unresolved_orders"] = list(poly.unresolved)
            out["polygon_face_errors_arcsec"] = _list(poly.face_errors_arcsec)
            out["polygon_face_errors_arcsec_u"] = _list(poly.face_errors_arcsec_u)
            out["closure_residual_rms_arcsec"] = poly.residual_rms_arcsec
            out["polygon_dof"] = poly.dof
        if self._selfcal is not None:
            out["selfcal"] = dict(self._selfcal)
        return out

    def summary_lines(self) -> list[str]:
        """The headline numbers for the CLI, each ± U (p = 95 %, k = t₉₅(ν_eff) of each)."""
        from rotacal.numbers import format_quantity

        ks = self.coverage_factors()

        def q(value: float, u: float | None, key: str = "", k: float | None = None) -> str:
            k = k or ks.get(key) or 2.0
            return format_quantity(value, "arcsec", U=None if u is None else k * u, k=k, p=0.95)

        dirs = "both directions" if len(self.directions) == 2 else "one direction"
        lines = [
            f"reference {self.reference}: {self.positions_deg.size} positions, {self.runs} "
            f"run(s), {dirs}",
            f"{'error curve peak-to-peak':<34} "
            f"{q(self.error_pp_arcsec, self.error_pp_arcsec_u, 'error_pp_arcsec')}",
        ]
        v, vu = self._stats.values, self._stats.values_u
        for name, label in (
            ("positioning_accuracy_bidirectional", "accuracy A"),
            ("positioning_accuracy_forward", "accuracy A↑"),
            ("repeatability_bidirectional", "repeatability R"),
            ("repeatability_forward", "repeatability R↑ (4s)"),
            ("reversal_value", "reversal value B"),
            ("systematic_deviation_bidirectional", "systematic deviation E"),
        ):
            value = v[name]
            if value is not None:
                lines.append(f"{label + ' (ISO 230-2)':<34} {q(value, vu[name], name + '_arcsec')}")
        poly = self._polygon
        if poly is not None:
            how = {
                "closure": "separated by closure",
                "stated": "as stated (certificate)",
            }.get(self._polygon_source, f"{self._polygon_source} — in the error curve")
            rms = float(np.sqrt(np.mean(poly.face_errors_arcsec**2)))
            lines.append(
                f"polygon {poly.face_errors_arcsec.size} faces: face errors {how}, "
                f"rms {rms:.3g} arcsec"
            )
        fit = self._harmonics
        if fit is not None:
            for h, a, u, phi in zip(
                fit.orders,
                fit.amplitudes_arcsec,
                fit.amplitudes_arcsec_u,
                fit.phases_deg,
                strict=True,
            ):
                lines.append(
                    f"{f'harmonic {h} (phase {phi:.1f}°)':<34} "
                    f"{q(float(a), float(u), k=fit.coverage_k)}"
                )
        return lines


def _list(a: FloatArray | None) -> list[float] | None:
    return None if a is None else [float(v) for v in a]


def _polygon_shifts(
    app: Approaches, faces: int, face: ArrayLike | None, step: int | None
) -> NDArray[np.int64]:
    """How many faces the polygon was turned in each run, from the ``face`` column (face at the
    autocollimator at each reading) or a constant ``step`` per run (0 when neither is given)."""
    n_runs = len(app.runs)
    if face is None:
        return (np.arange(n_runs) * (step or 0)) % faces
    f = np.asarray(face, dtype=np.float64)[app.rows]  # (D, R, N)
    if np.any(f != np.round(f)) or np.any((f < 0) | (f >= faces)):
        raise CaptureError(f"column face: face numbers must be whole numbers 0 … {faces - 1}")
    k = np.rint(app.positions_deg / (360.0 / faces)).astype(np.int64) % faces
    shift = (f.astype(np.int64) - k[None, None, :]) % faces
    uniform = np.all(shift == shift[:1, :, :1], axis=(0, 2))
    if not np.all(uniform):
        r = int(np.flatnonzero(~uniform)[0])
        raise CaptureError(
            f"column face: in run {app.runs[r]} the face seen is not the position's index plus "
            "one constant turn of the polygon: the polygon must stay put within a run"
        )
    return shift[0, :, 0]


def _check_polygon_positions(positions_deg: FloatArray, faces: int) -> None:
    """The closure needs the N positions k·360°/N, each once."""
    pitch = 360.0 / faces
    k = positions_deg / pitch
    off = np.abs(k - np.rint(k)) * pitch
    idx = np.rint(k).astype(np.int64) % faces
    if np.any(off > 1e-4) or np.unique(idx).size != positions_deg.size or idx.size != faces:
        missing = sorted(set(range(faces)) - set(idx.tolist()))
        what = (
            f"misses {', '.join(f'{m * pitch:g}°' for m in missing[:4])}"
            + (" …" if len(missing) > 4 else "")
            if missing
            else "holds positions between the faces or one face twice (0° and 360°?)"
        )
        raise CaptureError(
            f"a {faces}-face polygon needs the {faces} positions k·{pitch:g}° covering 360° (the "
            f"closure of the cross-calibration); the capture {what}"
        )


def position_accuracy(
    position_deg: ArrayLike,
    *,
    reference_deg: ArrayLike | None = None,
    error_arcsec: ArrayLike | None = None,
    run: ArrayLike | None = None,
    direction: ArrayLike | None = None,
    face: ArrayLike | None = None,
    harmonics: int = DEFAULT_HARMONICS,
    polygon_faces: int | None = None,
    polygon_step_faces: int | None = None,
    polygon_face_errors_arcsec: ArrayLike | None = None,
    polygon_face_u_arcsec: float = 0.0,
    reference_u_arcsec: float = 0.0,
    selfcal: Mapping[str, Any] | None = None,
    selfcal_zero_deg: float = 0.0,
) -> PositionAccuracy:
    """Error curve, harmonics and ISO 230-2 values of a rotary axis from a position test.

    Parameters
    ----------
    position_deg : array_like, deg
        Target (commanded) position of each reading.
    reference_deg : array_like, deg, optional
        The reference encoder's reading at each stop (exclusive with ``error_arcsec``).
    error_arcsec : array_like, arcsec, optional
        The positional deviation at each stop, or with ``polygon_faces`` the autocollimator's
        reading on the polygon face in front of it.
    run, direction, face : array_like, optional
        Run number, sign of approach (+1/−1) and polygon face (0 … N−1) of each reading.
    harmonics : int
        Highest Fourier order fitted to the error curve (0: none).
    polygon_faces : int, optional
        N of the polygon (the readings are then autocollimator readings).
    polygon_step_faces : int, optional
        Faces the polygon was turned between consecutive runs, when there is no ``face`` column.
    polygon_face_errors_arcsec : array_like (N,), arcsec, optional
        The polygon's face errors as its calibration certificate states them (same sign
        convention as :mod:`rotacal.position.polygon`): the readings are corrected by them and
        no separation is attempted.
    polygon_face_u_arcsec : float, arcsec
        Their standard uncertainty (Type B).
    reference_u_arcsec : float, arcsec
        Standard uncertainty of the reference at a position (Type B, e.g. its certificate).
    selfcal : mapping, optional
        A ``rotacal selfcal`` result that corrects ``reference_deg``.
    selfcal_zero_deg : float, deg
        The reference's reading at line 0 of that self-calibration.

    Raises
    ------
    CaptureError, ConfigError
        Runs with different position sets, too few positions for the harmonics, polygon
        positions that do not cover 360°, inconsistent options (one line each).
    """
    if (reference_deg is None) == (error_arcsec is None):
        raise ConfigError(
            "give the reference's reading (column reference_deg) or the deviation (column "
            "error_arcsec), one of them"
        )
    if harmonics < 0:
        raise ConfigError(f"--harmonics {harmonics}: give 0 or more")
    if not (0 <= reference_u_arcsec <= TURN_ARCSEC):
        raise ConfigError(
            f"--reference-u-arcsec {reference_u_arcsec}: give a value from 0 to one turn "
            f"({TURN_ARCSEC:g} arcsec)"
        )
    pos = np.asarray(position_deg, dtype=np.float64)
    check_magnitudes("position_deg", pos, what="an angle in degrees", largest=MAX_ANGLE_DEG)
    if reference_deg is not None:
        check_magnitudes(
            "reference_deg", reference_deg, what="an angle in degrees", largest=MAX_ANGLE_DEG
        )
    if error_arcsec is not None:
        check_magnitudes(
            "error_arcsec", error_arcsec, what="a deviation in arcsec", largest=TURN_ARCSEC
        )
    notes: list[str] = []
    warnings: list[str] = []
    reference, values, u_ref2, selfcal_info = _deviations(
        pos, reference_deg, error_arcsec, polygon_faces, selfcal, selfcal_zero_deg, notes, warnings
    )
    app = arrange_approaches(pos, values, run=run, direction=direction)
    n_dir, n_runs, n_pos = app.values.shape
    u_ref = np.full(n_pos, math.sqrt(u_ref2 + reference_u_arcsec**2))
    poly, source = None, ""
    shifts: NDArray[np.int64] = np.zeros(0, dtype=np.int64)
    std_scale: float | None = 1.0
    x = app.values
    if polygon_faces is not None:
        _check_polygon_positions(app.positions_deg, polygon_faces)
        shifts = _polygon_shifts(app, polygon_faces, face, polygon_step_faces)
        poly, source, u_ref = _polygon(
            app, shifts, polygon_faces, polygon_face_errors_arcsec, polygon_face_u_arcsec, u_ref
        )
        x = poly.deviation
        nu_iso = n_dir * n_pos * (n_runs - 1)
        std_scale = math.sqrt(nu_iso / poly.dof) if poly.dof > 0 and nu_iso > 0 else None
        if source != "stated":
            warnings += _polygon_warnings(poly, polygon_faces, n_runs)
    stats = axis_statistics(x, u_ref, directions=app.directions, std_scale=std_scale)
    if n_runs == 1:
        warnings.append(
            "one run: no repeatability or accuracy A (ISO 230-2 approaches each position "
            f"{ISO_RUNS} times in each direction)"
        )
    elif n_runs < ISO_RUNS:
        warnings.append(
            f"{n_runs} runs: ISO 230-2's test cycle approaches each position {ISO_RUNS} times "
            "in each direction; the repeatability rests on fewer approaches"
        )
    if n_dir == 1:
        notes.append(
            "one direction of approach: no reversal value and no bidirectional values (ISO "
            "230-2 approaches in both directions)"
        )
    pooled = None
    if stats.std is not None:
        nu = poly.dof if poly is not None else n_dir * n_pos * (n_runs - 1)
        s = float(np.sqrt(np.mean(stats.std**2)))
        pooled = (s, s / math.sqrt(2.0 * nu))
    fit = None
    if harmonics:
        fit = fit_harmonics(app.positions_deg, stats.curve, harmonics, u_ref_arcsec=u_ref)
        weak = [
            h
            for h, a, u in zip(
                fit.orders, fit.amplitudes_arcsec, fit.amplitudes_arcsec_u, strict=True
            )
            if a < 2 * u
        ]
        if weak:
            notes.append(
                f"harmonic order(s) {', '.join(map(str, weak))} lie below twice their u: "
                "their amplitudes are raised by the noise and their phases not determined"
            )
    hi, lo = int(np.argmax(stats.curve)), int(np.argmin(stats.curve))
    return PositionAccuracy(
        reference=reference,
        positions_deg=app.positions_deg,
        directions=app.directions,
        runs=n_runs,
        run_labels=app.runs,
        error_curve_arcsec=stats.curve,
        error_curve_arcsec_u=stats.curve_u,
        error_pp_arcsec=float(stats.curve[hi] - stats.curve[lo]),
        error_pp_arcsec_u=float(math.hypot(stats.curve_u[hi], stats.curve_u[lo])),
        reference_u_arcsec=float(u_ref.max()),
        notes=tuple(notes),
        _stats=stats,
        _deviations=x,
        _harmonics=fit,
        _polygon=poly,
        _polygon_shifts=tuple(int(s) for s in shifts),
        _polygon_source=source,
        _pooled=pooled,
        _selfcal=selfcal_info,
        warnings=tuple(warnings),
    )


def _deviations(
    pos: FloatArray,
    reference_deg: ArrayLike | None,
    error_arcsec: ArrayLike | None,
    polygon_faces: int | None,
    selfcal: Mapping[str, Any] | None,
    selfcal_zero_deg: float,
    notes: list[str],
    warnings: list[str],
) -> tuple[str, FloatArray, float, dict[str, Any] | None]:
    """The reference's name, the readings as deviations (arcsec; a polygon's: autocollimator
    readings), the self-calibration's u² (arcsec²) and what the JSON says of it."""
    if polygon_faces is not None:
        if reference_deg is not None or selfcal is not None:
            raise ConfigError(
                "--polygon-faces reads autocollimator readings (column error_arcsec), not "
                "reference_deg or --selfcal"
            )
        if polygon_faces < 3:
            raise ConfigError(f"--polygon-faces {polygon_faces}: a polygon has 3 faces or more")
        return "polygon", np.asarray(error_arcsec, dtype=np.float64), 0.0, None
    if reference_deg is None:
        if selfcal is not None:
            raise ConfigError("--selfcal corrects a reference_deg column; the capture has none")
        return "deviation", np.asarray(error_arcsec, dtype=np.float64), 0.0, None
    reading = np.asarray(reference_deg, dtype=np.float64)
    reference, u2, info = "encoder", 0.0, None
    if selfcal is not None:
        corr = selfcal_correction(reading, selfcal, zero_deg=selfcal_zero_deg)
        reading = reading + corr.correction_arcsec / 3600.0
        reference = "self-calibrated encoder"
        if corr.u_arcsec is not None:
            u2 = corr.u_arcsec**2
        else:
            warnings.append(
                "the self-calibration states no uncertainty (deviation_u_arcsec): its "
                "correction counts as exact"
            )
        if corr.note:
            notes.append(corr.note)
        info = {
            "lines": corr.lines,
            "heads": corr.heads,
            "zero_deg": selfcal_zero_deg,
            "correction_pp_arcsec": float(np.ptp(corr.correction_arcsec)),
            "u_arcsec": corr.u_arcsec,
        }
    # actual minus target, within ±180° (a reading of 359.99° at target 0° is −36″)
    return reference, (np.mod(reading - pos + 180.0, 360.0) - 180.0) * 3600.0, u2, info


def _polygon(
    app: Approaches,
    shifts: NDArray[np.int64],
    faces: int,
    stated_faces: ArrayLike | None,
    stated_u: float,
    u_ref: FloatArray,
) -> tuple[PolygonSeparation, str, FloatArray]:
    """The polygon's face errors separated by closure (or taken as stated), how, and the u of
    each position's reference grown by them."""
    if stated_faces is None:
        poly = separate_polygon(app.values, shifts)
        if not poly.unresolved:
            source = "closure"
        elif len(poly.unresolved) == faces // 2:
            source = "not separated"
        else:
            source = "partly separated"
    else:
        stated = _stated_faces(stated_faces, faces, stated_u)
        j = (np.arange(faces)[None, :] + shifts[:, None]) % faces
        poly = separate_polygon(app.values + stated[j][None], shifts, separate=False)
        poly = dataclasses.replace(
            poly,
            face_errors_arcsec=stated,
            face_errors_arcsec_u=np.full(faces, stated_u),
            unresolved=(),
        )
        u_ref = np.hypot(u_ref, stated_u)
        source = "stated"
    if poly.table_var_arcsec2 is not None and poly.sigma2 is not None:
        # the face errors' and zeros' estimates add to each position's mean (KKT covariance)
        n_runs = app.values.shape[1]
        extra = np.maximum(poly.table_var_arcsec2 - poly.sigma2 / n_runs, 0.0).mean(axis=0)
        u_ref = np.sqrt(u_ref**2 + extra)
    return poly, source, u_ref


def _stated_faces(values: ArrayLike, faces: int, u: float) -> FloatArray:
    """A certificate's face errors (arcsec): N finite values; their mean is removed (closure)."""
    f = np.asarray(values, dtype=np.float64).ravel()
    if f.size != faces or not np.all(np.abs(f) < TURN_ARCSEC):
        raise ConfigError(
            f"--polygon-face-errors-arcsec: give {faces} finite values below one turn, one per face 0 … "
            f"{faces - 1} (got {f.size})"
        )
    if not (0 <= u <= TURN_ARCSEC):
        raise ConfigError(f"--polygon-face-u-arcsec {u}: give a value from 0 to one turn")
    return f - f.mean()


def _polygon_warnings(poly: PolygonSeparation, faces: int, n_runs: int) -> list[str]:
    out = []
    if len(poly.unresolved) == faces // 2:
        out.append(
            "the polygon sat in the same position on the table in every run: its face errors "
            "cannot be separated from the table's, and the error curve is the table's deviation "
            "less the face errors (turn the polygon by one face between runs, column face or "
            "--polygon-step-faces; or give its certificate's --polygon-face-errors-arcsec)"
        )
    elif poly.unresolved:
        out.append(
            f"the polygon's turns between runs leave order(s) "
            f"{', '.join(map(str, poly.unresolved))} of its face errors inseparable from the "
            "table's: they are counted as the table's (turn it by one face in some run)"
        )
    if poly.dof <= 0 and n_runs > 1:
        out.append(
            "the runs determine the face errors exactly, with no residual left: no "
            "uncertainty of the face errors and no repeatability (measure more runs)"
        )
    return out
