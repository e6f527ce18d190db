"""The worst case of a turntable's orientation error over its angles and its error box (GyroWheel study, §4).

The searches :func:`rotacal.turntable.allocation.allocate` and :func:`worst_case` share: the
largest Σ_i |c_ji(φ)|·χ_i of the linearised model (eq. (26)) over every angle (a grid, its peaks
refined by Nelder–Mead: :class:`_LinearMax`), and the largest |Δ_j| of the full model
(eqs. (17)–(25)) over the sign vertices of the box χ = ±UB at those angles — every element of ΔR
is multilinear in χ, so at fixed angles the largest |Δ| over the box is at a vertex. Also the
checks of a requirement and of bounds that the allocation and the Monte Carlo share.

References
----------
Seed 001 (``../shared/seeds/001_4a387eb674e238f2.txt``), §3.2 eqs. (17)–(27), §4 eqs. (28)–(34),
Lemma 1.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable, Mapping
from typing import Any

import numpy as np
from scipy.optimize import minimize

from rotacal.errors import ConfigError
from rotacal.turntable.chain import ANGLE_UNITS, COMPONENTS, SMALL_ANGLE_LIMIT_RAD
from rotacal.turntable.geometry import Turntable

__all__ = ["worst_case"]

_UNIT_RAD = ANGLE_UNITS
#: Relative tolerance of the worst cases (a worst case ≤ I_j·(1 + this) is within).
_EXCHANGE_RTOL = 1e-9
#: Largest fine angle grid of the exchange method and of the linear worst case (points).
_MAX_GRID_POINTS = 150_000
#: Largest number of full-model evaluations of the vertex × angle enumeration.
_MAX_FULL_EVALUATIONS = 4_000_000
#: Sign vertices are enumerated exhaustively up to this many errors (2¹⁰ vertices).
_MAX_VERTEX_ERRORS = 10
#: Rows per call of the fast model.
_EVAL_CHUNK = 262_144
_TWO_PI = 2.0 * math.pi


def _unit_factor(units: str) -> float:
    try:
        return _UNIT_RAD[units]
    except KeyError:
        raise ConfigError(
            f"unknown angular units {units!r}: use one of {', '.join(_UNIT_RAD)}."
        ) from None


def _display(table: Turntable) -> tuple[str, float]:
    units = str(getattr(table, "units", "arcmin"))
    return (units, _UNIT_RAD[units]) if units in _UNIT_RAD else ("arcmin", _UNIT_RAD["arcmin"])


def _source(table: Turntable) -> str:
    """How messages about ``table`` start: its file (or text), else its name."""
    source = str(getattr(table, "source", "") or "")
    return source or f"turntable {table.name!r}"


def _require_angular(table: Turntable) -> None:
    """Refuse a table none of whose errors changes the orientation (one ConfigError line)."""
    if not table.angular_error_names:
        raise ConfigError(
            f"{_source(table)}: no error of the chain changes the orientation (only "
            f"translations: {', '.join(table.error_names) or 'none'}), nothing to allocate or "
            "check; add the links' error rotations."
        )


def _requirement(table: Turntable, requirement: Any) -> dict[str, float]:
    if requirement is None:
        requirement = table.requirement
        if requirement is None:
            raise ConfigError(
                f"table {table.name!r} states no [requirement] psi/theta/gamma: pass requirement= "
                "(rad), e.g. the limits rotacal.turntable.calibration.orientation_requirement "
                "derives from calibration_deg_h."
            )
    if isinstance(requirement, Mapping):
        missing = [c for c in COMPONENTS if c not in requirement]
        extra = [str(k) for k in requirement if k not in COMPONENTS]
        if missing or extra:
            raise ConfigError(
                "the requirement must give psi, theta and gamma (rad)"
                + (f"; missing {', '.join(missing)}" if missing else "")
                + (f"; unknown {', '.join(extra)}" if extra else "")
                + "."
            )
        values = {c: requirement[c] for c in COMPONENTS}
    else:
        values = dict.fromkeys(COMPONENTS, requirement)
    out: dict[str, float] = {}
    for c, v in values.items():
        try:
            f = float(v)
        except (TypeError, ValueError):
            raise ConfigError(f"requirement {c} must be a number in rad, got {v!r}.") from None
        if not (math.isfinite(f) and f > 0.0):
            raise ConfigError(f"requirement {c} must be a positive angle in rad, got {v!r}.")
        if f > SMALL_ANGLE_LIMIT_RAD:
            raise ConfigError(
                f"requirement {c} = {f:.6g} rad ({math.degrees(f):.4g}°) is beyond "
                f"{SMALL_ANGLE_LIMIT_RAD:g} rad: the small-angle error model needs errors ≪ 1 rad; "
                "give radians."
            )
        out[c] = f
    return out


def _angles_list(angles: np.ndarray) -> list[np.ndarray]:
    return [angles[:, k] for k in range(angles.shape[1])]


def _coefficients(table: Turntable, angles: np.ndarray) -> np.ndarray:
    """∂(Δψ, Δθ, Δγ)/∂χ at χ = 0, shape (k, 3, n_angular), for angles (k, n_angles) in rad."""
    c = np.asarray(table.linear_coefficients(_angles_list(angles)), dtype=float)
    return c.reshape(angles.shape[0], 3, -1)


def _grid(n_angles: int, step_deg: float, max_points: int) -> tuple[np.ndarray, float]:
    """Every combination of angles on [0, 2π) at ``step_deg`` (coarser if > max_points): (M, n), rad."""
    per_axis = max(1, round(360.0 / step_deg))
    if n_angles > 0 and per_axis**n_angles > max_points:
        per_axis = max(4, math.floor(max_points ** (1.0 / n_angles)))
    return _grid_m(n_angles, per_axis), _TWO_PI / per_axis


def _grid_m(n_angles: int, per_axis: int) -> np.ndarray:
    if n_angles == 0:
        return np.zeros((1, 0))
    axis = np.arange(per_axis) * (_TWO_PI / per_axis)
    mesh = np.meshgrid(*([axis] * n_angles), indexing="ij")
    return np.stack([m.ravel() for m in mesh], axis=1)


def _top_peaks(values: np.ndarray, grid: np.ndarray, step: float, k: int) -> list[int]:
    """Indices of up to ``k`` largest values that lie more than 2 grid steps apart."""
    n_top = min(values.size, 4096)
    top = np.argpartition(-values, n_top - 1)[:n_top] if n_top < values.size else np.arange(n_top)
    top = top[np.argsort(-values[top], kind="stable")]
    chosen: list[int] = []
    for idx in top:
        if grid.shape[1]:
            d = [np.abs(np.angle(np.exp(1j * (grid[idx] - grid[c])))).max() for c in chosen]
            if any(di <= 2.0 * step for di in d):
                continue
        chosen.append(int(idx))
        if len(chosen) == k:
            break
    return chosen


def _refine(
    fun: Callable[[np.ndarray], float], start: np.ndarray, step: float
) -> tuple[float, np.ndarray]:
    """A local maximum of ``fun`` (angles in rad) near ``start`` by Nelder–Mead: (value, angles)."""
    start = np.asarray(start, dtype=float)
    best = (fun(start), start)
    n = start.size
    if n == 0:
        return best
    simplex = np.vstack([start - 0.25 * step, start - 0.25 * step + 0.5 * step * np.eye(n)])
    res = minimize(
        lambda a: -fun(a),
        start,
        method="Nelder-Mead",
        options={
            "initial_simplex": simplex,
            "xatol": 1e-10,
            "fatol": 1e-15,
            "maxiter": 400 * n,
            "maxfev": 800 * n,
        },
    )
    if -float(res.fun) > best[0]:
        best = (-float(res.fun), np.mod(np.asarray(res.x, dtype=float), _TWO_PI))
    return best


class _LinearMax:
    """max over φ of Σ_i a_i(φ)·x_i for a_i = |c_ji(φ)| of one component, on a grid then refined."""

    def __init__(
        self,
        table: Turntable,
        component: int,
        columns: np.ndarray,
        grid: np.ndarray,
        grid_abs: np.ndarray,
        step: float,
        refine: bool = True,
    ) -> None:
        self.table = table
        self.component = component
        self.columns = columns
        self.grid = grid
        self.grid_abs = grid_abs
        self.step = step
        #: False: the constraint holds on the grid only (the paper's φ2 ∈ {0°, 45°, 90°}), so
        #: the maxima are the grid's own, not refined between its points.
        self.refine = refine

    def rows(self, angles: np.ndarray) -> np.ndarray:
        angles = np.asarray(angles, dtype=float)
        if angles.ndim == 1:  # one point of the local search: the fast path, the same numbers
            c = self.table.point_coefficients(angles)[None]
        else:
            c = _coefficients(self.table, angles)
        return np.abs(c[:, self.component, :][:, self.columns])

    def __call__(self, x: np.ndarray, peaks: int = 3) -> list[tuple[float, np.ndarray]]:
        """Refined local maxima, largest first: [(value, angles rad)]."""
        vals = self.grid_abs @ x
        out = []
        if not self.refine:
            top = _top_peaks(vals, self.grid, 0.0, peaks)
            return [(float(vals[i]), self.grid[i].copy()) for i in top]
        for idx in _top_peaks(vals, self.grid, self.step, peaks):
            v, a = _refine(lambda a: float(self.rows(a)[0] @ x), self.grid[idx], self.step)
            out.append((max(v, float(vals[idx])), a if v >= vals[idx] else self.grid[idx]))
        out.sort(key=lambda t: -t[0])
        return out


def _bounds_vector(table: Turntable, bounds: Mapping[str, Any] | None, what: str) -> np.ndarray:
    names = tuple(table.angular_error_names)
    out = np.zeros(len(names))
    for key, value in (bounds or {}).items():
        name = table.resolve(str(key))
        if name not in names:
            continue  # a translation: no effect on the orientation
        if value is None:
            continue
        try:
            v = float(value)
        except (TypeError, ValueError):
            raise ConfigError(f"{what} of {name} must be a number in rad, got {value!r}.") from None
        if not (math.isfinite(v) and v >= 0.0):
            raise ConfigError(f"{what} of {name} must be ≥ 0 rad and finite, got {value!r}.")
        if v > SMALL_ANGLE_LIMIT_RAD:
            raise ConfigError(
                f"{what} of {name} = {v:.6g} rad ({math.degrees(v):.4g}°) is beyond "
                f"{SMALL_ANGLE_LIMIT_RAD:g} rad: the small-angle error model needs errors ≪ 1 rad; "
                "give radians."
            )
        out[names.index(name)] = v
    return out


def _fast(table: Turntable, angles: np.ndarray, chi: np.ndarray) -> np.ndarray:
    return np.asarray(table.fast_orientation_error(angles, chi), dtype=float)


def _linear_worst(
    table: Turntable,
    ub: np.ndarray,
    req: np.ndarray,
    grid: np.ndarray,
    step: float,
    coef_abs: np.ndarray,
) -> list[tuple[float, np.ndarray]]:
    """max over φ of Σ_i |c_ji(φ)|·UB_i / I_j per component: [(value, angles rad)]."""
    out = []
    cols = np.arange(ub.size)
    for j in range(3):
        lmax = _LinearMax(table, j, cols, grid, coef_abs[:, j, :], step)
        out.append(lmax(ub / req[j], peaks=3)[0])
    return out


def _full_worst(
    table: Turntable,
    ub: np.ndarray,
    req: np.ndarray,
    grid_lin: np.ndarray,
    max_evaluations: int,
) -> list[dict[str, Any]]:
    """Largest |Δ_j| of the full model over sign vertices χ = ±UB × angles, per component."""
    n_ang = ub.size
    n_angles = grid_lin.shape[1]
    active = np.flatnonzero(ub > 0)
    nv = active.size
    top = 6
    cands: list[list[tuple[float, np.ndarray, np.ndarray]]] = [[], [], []]
    evaluations = 0

    def consider(vals: np.ndarray, point: Callable[[int], tuple[np.ndarray, np.ndarray]]) -> None:
        """Keep the ``top`` largest values of each component; ``point(i)``: row i's angles, χ."""
        for j in range(3):
            v = vals[:, j]
            k = min(top, v.size)
            idx = np.argpartition(-v, k - 1)[:k]
            cands[j].extend((float(v[i]), *point(int(i))) for i in idx)
            cands[j].sort(key=lambda t: -t[0])
            del cands[j][top:]

    if nv <= _MAX_VERTEX_ERRORS:
        signs = np.array(list(itertools.product((1.0, -1.0), repeat=nv))).reshape(-1, nv)
        chi_v = np.zeros((signs.shape[0], n_ang))
        chi_v[:, active] = signs * ub[active]
        per_angle = max(1, max_evaluations // chi_v.shape[0])
        per_axis = min(360, max(4, math.floor(per_angle ** (1.0 / max(n_angles, 1)))))
        grid = _grid_m(n_angles, per_axis)
        step = _TWO_PI / per_axis
        strategy = f"all {chi_v.shape[0]} sign vertices × {grid.shape[0]} angle points"
        g = grid.shape[0]
        total = chi_v.shape[0] * g
        trig = table.fast_angle_trig(grid)  # once: every vertex sees the same angles
        for start in range(0, total, _EVAL_CHUNK):
            stop = min(start + _EVAL_CHUNK, total)
            vals = np.empty((stop - start, 3))  # point p: vertex p // g at angle point p % g
            for v in range(start // g, (stop - 1) // g + 1):
                lo, hi = max(start, v * g) - v * g, min(stop, (v + 1) * g) - v * g
                part = {k: (cos[lo:hi], sin[lo:hi]) for k, (cos, sin) in trig.items()}
                at = v * g + lo - start
                vals[at : at + hi - lo] = table.fast_orientation_error_at(part, chi_v[v], hi - lo)

            def point(i: int, start: int = start) -> tuple[np.ndarray, np.ndarray]:
                return grid[(start + i) % g].copy(), chi_v[(start + i) // g].copy()

            consider(np.abs(vals) / req, point)
            evaluations += stop - start
    else:
        step = _TWO_PI / max(round(grid_lin.shape[0] ** (1.0 / max(n_angles, 1))), 1)
        strategy = (
            f"{nv} errors (> {_MAX_VERTEX_ERRORS}): at each of {grid_lin.shape[0]} angle points the "
            "vertices of the linear worst signs of each component, then single sign flips"
        )
        chunk = max(1, _EVAL_CHUNK // 6)
        for start in range(0, grid_lin.shape[0], chunk):
            angles = grid_lin[start : start + chunk]
            c = _coefficients(table, angles)[:, :, active]
            s = np.where(c >= 0.0, 1.0, -1.0)  # (k, 3, nv)
            s = np.concatenate([s, -s], axis=1).reshape(-1, nv)
            chi_s = np.zeros((s.shape[0], n_ang))
            chi_s[:, active] = s * ub[active]
            ang = np.repeat(angles, 6, axis=0)

            def row(
                i: int, a: np.ndarray = ang, c: np.ndarray = chi_s
            ) -> tuple[np.ndarray, np.ndarray]:
                return a[i].copy(), c[i].copy()

            consider(np.abs(_fast(table, ang, chi_s)) / req, row)
            evaluations += chi_s.shape[0]
    enumerated = evaluations
    out = []
    for j in range(3):
        best = (-1.0, np.zeros(n_angles), np.zeros(n_ang))
        for v0, a0, chi0 in cands[j][:3]:
            value, a, chi = v0, a0, chi0
            for _ in range(2):
                value, a = _refine(_component_of(table, chi, j, float(req[j])), a, step)
                # single sign flips at these angles (multilinear: a vertex stays best)
                while nv:
                    flips = np.repeat(chi[None, :], nv, axis=0)
                    flips[np.arange(nv), active] *= -1.0
                    vals = np.abs(_fast(table, np.repeat(a[None, :], nv, axis=0), flips)[:, j])
                    i = int(np.argmax(vals))
                    if vals[i] / req[j] <= value * (1.0 + 1e-15):
                        break
                    value, chi = float(vals[i] / req[j]), flips[i]
            if value > best[0]:
                best = (value, a, chi)
        out.append(
            {
                "value_rad": best[0] * req[j],
                "angles": best[1],
                "chi": best[2],
                "strategy": strategy,
                "evaluations": enumerated,
            }
        )
    return out


def _component_of(
    table: Turntable, chi: np.ndarray, j: int, req: float
) -> Callable[[np.ndarray], float]:
    """|Δ_j|/I_j of the full model at fixed errors χ, as a function of the angles (rad)."""

    def f(angles: np.ndarray) -> float:
        return float(abs(_fast(table, angles[None, :], chi[None, :])[0, j])) / req

    return f


def _worst_case_arrays(
    table: Turntable,
    ub: np.ndarray,
    req: dict[str, float],
    angle_step_deg: float,
    max_evaluations: int,
    cache: dict[str, Any] | None = None,
) -> dict[str, dict[str, Any]]:
    angle_names = tuple(table.angle_names)
    if cache is not None and "grid" in cache:
        grid, step, coef_abs = cache["grid"], cache["step"], cache["coef_abs"]
    else:
        grid, step = _grid(len(angle_names), angle_step_deg, _MAX_GRID_POINTS)
        coef_abs = np.abs(_coefficients(table, grid))
    req_v = np.array([req[c] for c in COMPONENTS])
    lin = _linear_worst(table, ub, req_v, grid, step, coef_abs)
    full = _full_worst(table, ub, req_v, grid, max_evaluations)
    names = tuple(table.angular_error_names)
    out: dict[str, dict[str, Any]] = {}
    for j, comp in enumerate(COMPONENTS):
        lin_rad = lin[j][0] * req_v[j]
        full_rad = float(full[j]["value_rad"])
        tol = req_v[j] * (1.0 + _EXCHANGE_RTOL)
        out[comp] = {
            "linear_rad": float(lin_rad),
            "linear_angles_deg": dict(
                zip(angle_names, np.degrees(lin[j][1]).round(9).tolist(), strict=True)
            ),
            "full_rad": full_rad,
            "angles_deg": dict(
                zip(angle_names, np.degrees(full[j]["angles"]).round(9).tolist(), strict=True)
            ),
            "signs": {
                n: (1 if s > 0 else -1)
                for n, s, u in zip(names, full[j]["chi"], ub, strict=True)
                if u > 0
            },
            "requirement_rad": float(req_v[j]),
            "within": bool(lin_rad <= tol and full_rad <= tol),
            "vertices": full[j]["strategy"],
            "evaluations": int(full[j]["evaluations"]),
        }
    return out


def worst_case(
    table: Turntable,
    upper_bounds: Mapping[str, float | None],
    requirement: Mapping[str, float] | float | None = None,
    *,
    lower_bounds: Mapping[str, float] | None = None,
    angle_step_deg: float = 1.0,
    max_evaluations: int = _MAX_FULL_EVALUATIONS,
) -> dict[str, dict[str, Any]]:
    """Lemma 1 check: the worst orientation error of every table whose errors satisfy |χ_i| ≤ UB_i.

    Two worst cases per component j:

    * ``linear_rad`` — max over all angles of Σ_i |c_ji(φ)|·UB_i, the bound Lemma 1 proves for the
      linearised model (26) (fine grid of ``angle_step_deg`` per angle, coarser for tables of three
      angles so the grid stays ≤ 1.5·10⁵ points, then Nelder–Mead from the 3 best peaks);
    * ``full_rad`` — max of |Δ_j| of the full model (``table.fast_orientation_error``, eqs.
      (17)–(24)) over every sign vertex χ = ±UB of the box × a grid of angles (at most
      ``max_evaluations`` evaluations), then from the 3 best points Nelder–Mead over the angles
      alternated with single sign flips. ΔR is multilinear in χ, so at fixed angles the largest
      |Δ_j| over the box is at a vertex. Tables of more than 10 errors are not enumerated: at each
      angle the linear worst sign vertex of each component (and its negative) is taken instead.

    Parameters
    ----------
    table : Turntable
        The table (``rotacal.turntable.model``).
    upper_bounds : mapping
        UB_i per error name (rad; ``None`` or a missing angular error = 0, i.e. exact; aliases
        accepted; translations ignored).
    requirement : mapping or float, optional
        I_j (rad) for psi, theta, gamma, or one value for all; default the table's.
    lower_bounds : mapping, optional
        LB_i (rad). The vertices ±UB bound the box {LB ≤ |χ| ≤ UB} from outside; the lower bounds
        are only checked (LB_i ≤ UB_i).
    angle_step_deg : float
        Fine-grid step of the linear worst case (deg).
    max_evaluations : int
        Cap of the full-model vertex × angle enumeration.

    Returns
    -------
    dict
        ``{j: {"linear_rad", "linear_angles_deg", "full_rad", "angles_deg", "signs",
        "requirement_rad", "within", "vertices", "evaluations"}}``; angles in degrees by angle
        name, ``signs`` the worst vertex (±1 per error), ``within`` both ≤ I_j·(1 + 1e-9).

    Raises
    ------
    ConfigError
        A negative, non-numeric or too large (> 0.1 rad) bound, an unknown error name,
        LB_i > UB_i, a bad requirement, a table with no angular error.

    References
    ----------
    Seed 001, eq. (30), Lemma 1 (eqs. (35)–(38)); eqs. (17)–(26).
    """
    _require_angular(table)
    req = _requirement(table, requirement)
    ub = _bounds_vector(table, upper_bounds, "the upper bound")
    if lower_bounds is not None:
        lb = _bounds_vector(table, lower_bounds, "the lower bound")
        bad = np.flatnonzero(lb > ub * (1.0 + 1e-12))
        if bad.size:
            n = table.angular_error_names[int(bad[0])]
            raise ConfigError(
                f"the lower bound of {n} ({lb[bad[0]]:.6g} rad) exceeds its upper bound "
                f"({ub[bad[0]]:.6g} rad): raise the upper bound or lower the lower bound."
            )
    step = _check_step(angle_step_deg)
    if int(max_evaluations) < 1:
        raise ConfigError(f"max_evaluations must be ≥ 1, got {max_evaluations!r}.")
    return _worst_case_arrays(table, ub, req, step, int(max_evaluations))


def _check_step(angle_step_deg: Any) -> float:
    try:
        step = float(angle_step_deg)
    except (TypeError, ValueError):
        step = math.nan
    if not (math.isfinite(step) and 0.0 < step <= 90.0):
        raise ConfigError(f"angle_step_deg must be in (0, 90] degrees, got {angle_step_deg!r}.")
    return step
