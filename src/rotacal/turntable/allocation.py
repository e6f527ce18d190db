"""Error allocation of a turntable (GyroWheel study, §4) and its worst-case and Monte Carlo checks.

For every orientation component j ∈ (ψ, θ, γ) with requirement I_j the allocation solves the
generalised eqs. (31)–(33),

    minimise  J_j = Σ_i W_ji² / χ_i²    over the errors i that j is sensitive to (C_ji > 1e-12)
    subject to  max_φ Σ_i |c_ji(φ)|·χ_i ≤ I_j   and   χ_i ≥ LB_i   (eq. (29)),

where c(φ) = ∂(Δψ, Δθ, Δγ)/∂χ at χ = 0 is the table's linearised model (eq. (26) for the GyroWheel study's table;
``Turntable.linear_coefficients``), φ runs over every angle of the table on [0, 2π), and the weights
are W_ji = 1/C_ji, the inverse of the averaged sensitivities of eq. (28) — averaged as the table
chooses (``Turntable.sensitivity_grid``: by default the unbiased mean over a turn, the paper's
45° grid with both ends for the packaged table of the GyroWheel study) — or the error's ``weight`` override. For the GyroWheel study's table this is the paper's constraint on [0, π/2] (γ) and [3π/2, 2π] (ψ) —
the four cases of Lemma 1 fold every angle onto it. The upper bounds are then eq. (34),
UB_i = min_j χ*_ji, so that by Lemma 1 the linearised model meets every requirement for all
angles and all |χ_i| ≤ UB_i.

The constraint is semi-infinite (one inequality per angle). It is solved by an exchange method:
SLSQP with analytic gradients on the scaled variables x = χ/I_j against a finite set of angles
(start: every 45°); the worst angle of the solution on a fine grid, refined by Nelder–Mead, joins
the set; repeat until the fine-grid maximum is ≤ I_j·(1 + 1e-9); finally χ* is scaled so that the
refined worst case is ≤ I_j.

The full model of eqs. (17)–(25) (products of the small-angle matrices) adds second-order terms the
linear allocation does not see: for the GyroWheel study's table, the θ bound of a tight allocation
(φz2 + αz1 = I_θ) is exceeded by ~1e-4 relative at the worst corner of the box. With
``full_model_guard=True`` (the default) :func:`allocate` therefore checks the full model over every
sign vertex of the box (:func:`worst_case`) and shrinks the bounds of a component's errors by the
factor that brings the full model back to I_j (``optimiser["full_model_scale"]``). Every element of
ΔR is multilinear in χ (each error enters one matrix factor, linearly), so at fixed angles the
largest |Δ| over the box is at a vertex.

References
----------
Seed 001 (``../shared/seeds/001_4a387eb674e238f2.txt``), §3.2 eqs. (17)–(27), §4 eqs. (28)–(38),
Lemma 1, Table 4, Figures 8–9.
"""

from __future__ import annotations

import dataclasses
import itertools
import math
import time
from collections.abc import Callable, Mapping
from typing import Any

import numpy as np
from scipy.optimize import Bounds, minimize

from rotacal.errors import ConfigError
from rotacal.results import Result
from rotacal.turntable.chain import ANGLE_UNITS, ARCMIN_PER_RAD, COMPONENTS, SMALL_ANGLE_LIMIT_RAD
from rotacal.turntable.draws import QUANTILE, TopValues, quantile_interval, top_values_needed
from rotacal.turntable.fast import compiled_draws, compiled_tally, numba_enabled
from rotacal.turntable.geometry import Turntable
from rotacal.turntable.memo import LastResults, memo_key

__all__ = [
    "EVERY_ANGLE",
    "Allocation",
    "MonteCarloCheck",
    "allocate",
    "check_constraint_angles",
    "check_draws",
    "linear_allocation",
    "monte_carlo_check",
    "worst_case",
]

_UNIT_RAD = ANGLE_UNITS
#: An error with mean |∂Δ_j/∂χ_i| above this is one component j is sensitive to (eq. (28)).
_SENSITIVE = 1e-12
#: Relative tolerance of the worst cases (a worst case ≤ I_j·(1 + this) is within).
_EXCHANGE_RTOL = 1e-9
#: The exchange method stops when the refined worst angle exceeds I_j by no more than this
#: (relative): far below _EXCHANGE_RTOL because the polygonal (finite-angle) approximation of the
#: constraint moves χ* by ~√(excess), not by the excess.
_EXCHANGE_STOP = 1e-14
#: Largest fine angle grid of the exchange method and of the linear worst case (points).
_MAX_GRID_POINTS = 150_000
#: Largest number of full-model evaluations of the vertex × angle enumeration.
_MAX_FULL_EVALUATIONS = 4_000_000
#: Sign vertices are enumerated exhaustively up to this many errors (2¹⁰ vertices).
_MAX_VERTEX_ERRORS = 10
#: Rows per call of the fast model.
_EVAL_CHUNK = 262_144
_HIST_BINS = 60
#: The value of ``constraint_angles`` that enforces the allocation's constraint at every angle.
EVERY_ANGLE = "every"
_TWO_PI = 2.0 * math.pi


# ------------------------------------------------------------------------------------- results
@dataclasses.dataclass(frozen=True)
class Allocation(Result):
    """Upper bounds of a turntable's errors (GyroWheel study, eqs. (29)–(34)) and their Lemma 1 check.

    Attributes
    ----------
    error_names : tuple of str
        Every error of the table in χ order (translations included).
    units : str
        The table's display units (values here are radians whatever it is).
    upper_bounds_rad : dict
        UB_i (rad, eq. (34)); ``None`` for an error with no effect on the orientation (a
        translation such as the GyroWheel study's intersection error η).
    lower_bounds_rad : dict
        LB_i (rad, eq. (29)) of every angular error.
    per_component : dict
        ``{j: {error: χ*_ji}}`` (rad): the optimum of eq. (31), (32) or (33) for component j, over
        the errors j is sensitive to.
    binding : dict
        ``{error: j}``: the component whose χ*_ji is the minimum in eq. (34).
    weights : dict
        ``{j: {error: W_ji}}``: 1/C_ji, or the error's ``weight`` override.
    sensitivities : dict
        ``{j: {error: C_ji}}``: averaged sensitivities (eq. (28)) of every angular error.
    requirement_rad : dict
        I_j (rad, eq. (15)).
    worst_case : dict
        Per component, from :func:`worst_case`: ``linear_rad`` (Lemma 1 bound), ``full_rad`` (full
        model over the box's vertices × angles), ``angles_deg`` where, ``within``.
    within : bool
        Both worst cases of every component are ≤ I_j.
    optimiser : dict
        Method, per-component iterations, success, the constraint angles used, notes.
    """

    error_names: tuple[str, ...]
    units: str
    upper_bounds_rad: dict[str, float | None]
    lower_bounds_rad: dict[str, float]
    per_component: dict[str, dict[str, float]]
    binding: dict[str, str]
    weights: dict[str, dict[str, float]]
    sensitivities: dict[str, dict[str, float]]
    requirement_rad: dict[str, float]
    worst_case: dict[str, dict[str, Any]]
    within: bool
    optimiser: dict[str, Any]

    def upper_bounds_in(self, units: str = "arcmin") -> dict[str, float | None]:
        """The upper bounds in ``units`` (rad, mrad, urad, deg, arcmin, arcsec)."""
        f = _unit_factor(units)
        return {k: (None if v is None else v / f) for k, v in self.upper_bounds_rad.items()}


@dataclasses.dataclass(frozen=True)
class MonteCarloCheck(Result):
    """Monte Carlo check of an allocation with the full model (GyroWheel study, §4.3, Figure 9).

    Attributes
    ----------
    runs, seed : int
        Number of draws and the seed of ``numpy.random.Generator(PCG64(seed))``.
    signs : str
        ``"random"`` (χ_i = ±U(LB_i, UB_i)) or ``"positive"`` (the paper's literal Ω_χ).
    max_abs_rad, max_abs_arcmin : dict
        Largest |Δψ|, |Δθ|, |Δγ| over the draws.
    requirement_rad : dict
        I_j (rad).
    all_within : bool
        No draw exceeds any requirement.
    outside : int
        Draws with at least one component beyond its requirement.
    draws_per_second : float
        Throughput of this run (wall clock; not reproducible, unlike everything else).
    histograms : dict
        ``{j: {"edges_rad": [61 edges over ±I_j], "counts": [60]}}`` (values beyond ±I_j are not
        counted; see ``outside``).
    quantile : float
        The quantile q of |Δ_j| stated in ``quantile_abs_rad`` (0.999).
    quantile_abs_rad : dict or None
        ``{j: (value, low, high)}``: the q-quantile of |Δ_j| over the draws and its
        distribution-free 95 % coverage interval (:func:`rotacal.turntable.draws.quantile_interval`);
        ``None`` when there are too few draws for one.
    """

    runs: int
    seed: int
    signs: str
    max_abs_rad: dict[str, float]
    max_abs_arcmin: dict[str, float]
    requirement_rad: dict[str, float]
    all_within: bool
    outside: int
    draws_per_second: float
    histograms: dict[str, dict[str, list[float]]]
    quantile: float = QUANTILE
    quantile_abs_rad: dict[str, tuple[float, float, float]] | None = None


# ------------------------------------------------------------------------------------- helpers
class _Infeasible(Exception):
    def __init__(self, value: float, angles: np.ndarray) -> None:
        super().__init__(value)
        self.value = value
        self.angles = angles


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


def _slsqp(
    w: np.ndarray, lo: np.ndarray, rows: np.ndarray, x0: np.ndarray
) -> tuple[np.ndarray, Any]:
    """min Σ w²/x² s.t. rows·x ≤ 1, x ≥ lo (SLSQP, analytic gradients), from x0 made feasible."""
    w2 = w * w
    # start on the feasible side: shrink x0 toward the lower bounds until every row holds
    d = np.maximum(x0, lo) - lo
    ad = rows @ d
    room = (1.0 - rows @ lo)[ad > 0] / ad[ad > 0]
    start = lo + min(1.0, float(room.min()) if room.size else 1.0) * d
    j0 = float(np.sum(w2 / (start * start)))

    def objective(x: np.ndarray) -> tuple[float, np.ndarray]:
        return float(np.sum(w2 / (x * x))) / j0, -2.0 * w2 / (x * x * x) / j0

    res = minimize(
        objective,
        start,
        jac=True,
        method="SLSQP",
        bounds=Bounds(lo, np.full(lo.size, np.inf)),
        constraints=[{"type": "ineq", "fun": lambda x: 1.0 - rows @ x, "jac": lambda x: -rows}],
        options={"ftol": 1e-14, "maxiter": 1000},
    )
    return np.maximum(np.asarray(res.x, dtype=float), lo), res


def _solve_component(
    lmax: _LinearMax, w: np.ndarray, xl: np.ndarray
) -> tuple[np.ndarray, dict[str, Any]]:
    """The scaled optimum x = χ*/I_j of one component (exchange method); raises _Infeasible."""
    peaks_lb = lmax(xl, peaks=1)
    g_lb, ang_lb = peaks_lb[0]
    if g_lb > 1.0 + _EXCHANGE_RTOL:
        raise _Infeasible(g_lb, ang_lb)
    if g_lb >= 1.0 - 1e-12:
        return xl.copy(), {
            "iterations": 0,
            "success": True,
            "message": "the lower bounds alone meet the requirement exactly: χ* = LB",
            "objective": float(np.sum((w / xl) ** 2)),
            "constraint_angles": 1,
            "exchange_angles_deg": [],
            "worst_linear": float(g_lb),
            "active_angles_deg": [np.degrees(ang_lb).round(9).tolist()],
        }
    lo = np.maximum(xl, 1e-9)
    # start from every 45°; on a constraint grid, from the part of it common with every 45°
    per_axis = 8 if lmax.refine else math.gcd(8, round(_TWO_PI / lmax.step))
    coarse = _grid_m(lmax.grid.shape[1], per_axis)
    angles = list(coarse)
    rows = lmax.rows(coarse)
    # start: the KKT shape χ_i³ ∝ W_i²/mean|c_i| on top of the lower bounds, halfway to the limit
    mean_abs = np.maximum(lmax.grid_abs.mean(axis=0), 1e-12)
    d = np.cbrt(w * w / mean_abs)
    ad = rows @ d
    room = (0.5 * (1.0 + g_lb) - rows @ xl)[ad > 0] / ad[ad > 0]
    x = xl + (float(room.min()) if room.size else 1.0) * d
    iterations, res, worst = 0, None, (math.inf, np.zeros(0))
    for iterations in range(1, 61):  # noqa: B007 - the count is reported
        keep = np.unique(np.round(rows, 15), axis=0, return_index=True)[1]
        x, res = _slsqp(w, lo, rows[np.sort(keep)], x)
        peaks = lmax(x)
        worst = peaks[0]
        if worst[0] <= 1.0 + _EXCHANGE_STOP:
            break
        new = [a for v, a in peaks if v > 1.0 + _EXCHANGE_STOP]
        angles.extend(new)
        rows = np.vstack([rows, lmax.rows(np.asarray(new))])
    # scale the free variables so the refined worst case is ≤ 1 (i.e. ≤ I_j)
    for _ in range(8):
        worst = lmax(x)[0]
        if worst[0] <= 1.0:
            break
        row = lmax.rows(worst[1])[0]
        free = x > xl
        g_pin = float(row[~free] @ x[~free])
        g_free = float(row[free] @ x[free])
        if g_free <= 0.0:
            break
        x = np.where(free, x * ((1.0 - g_pin) / g_free) * (1.0 - 4e-16), x)
        x = np.maximum(x, xl)
    all_angles = np.asarray(angles)
    slack = 1.0 - lmax.rows(all_angles) @ x
    active = all_angles[slack <= 1e-7]
    info = {
        "iterations": iterations,
        "success": bool(res is not None and res.success and worst[0] <= 1.0 + _EXCHANGE_RTOL),
        "message": str(res.message) if res is not None else "",
        "objective": float(np.sum((w / x) ** 2)),
        "constraint_angles": len(angles),
        "exchange_angles_deg": np.degrees(all_angles[coarse.shape[0] :]).round(9).tolist(),
        "worst_linear": float(worst[0]),
        "active_angles_deg": np.degrees(active).round(9).tolist(),
    }
    return x, info


# ----------------------------------------------------------------------------- worst case
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


def check_constraint_angles(value: Any, where: str) -> float | None:
    """Where the allocation's constraint holds: ``None`` for every angle, else a grid step (deg).

    ``value`` is ``None`` or ``"every"`` (every angle) or a number of degrees > 0 that divides 360°
    into whole steps (45: the paper's grid). ``where`` names the setting in the one-line
    :class:`~rotacal.errors.ConfigError` (e.g. ``"[allocation] constraint_angles"``).
    """
    if value is None or value == EVERY_ANGLE:
        return None
    number = value
    if isinstance(value, str):
        try:
            number = float(value)
        except ValueError:
            number = math.nan
    ok = not isinstance(number, (bool, np.bool_)) and isinstance(
        number, (int, float, np.integer, np.floating)
    )
    step = float(number) if ok else math.nan
    count = 360.0 / step if math.isfinite(step) and step > 0 else math.nan
    if not (math.isfinite(count) and abs(count - round(count)) < 1e-9):
        shown = str(value).lower() if isinstance(value, bool) else repr(value)
        raise ConfigError(
            f"{where} = {shown} must be {EVERY_ANGLE!r} (the constraint at every angle) or a "
            "step in degrees that divides 360° into whole steps (45: the paper's grid φ2 ∈ "
            "{0°, 45°, 90°})."
        )
    return step


def _constraint_grid(n_angles: int, step_deg: float | None) -> tuple[np.ndarray, float] | None:
    """The angles (rad) of a constraint grid of ``step_deg`` and its step (rad); None: every angle."""
    step = check_constraint_angles(step_deg, "constraint_step_deg")
    if step is None:
        return None
    per_axis = round(360.0 / step)
    if n_angles and per_axis**n_angles > _MAX_GRID_POINTS:
        raise ConfigError(
            f"constraint_step_deg = {step:g}° gives {per_axis}^{n_angles} constraint angles, more "
            f"than {_MAX_GRID_POINTS}: use a coarser step or every angle."
        )
    return _grid_m(n_angles, per_axis), _TWO_PI / per_axis


def _check_step(angle_step_deg: Any) -> float:
    try:
        step = float(angle_step_deg)
    except (TypeError, ValueError):
        step = math.nan
    if not (math.isfinite(step) and 0.0 < step <= 90.0):
        raise ConfigError(f"angle_step_deg must be in (0, 90] degrees, got {angle_step_deg!r}.")
    return step


@dataclasses.dataclass
class _Linear:
    """The linear allocation of eqs. (31)–(34) and what the rest of :func:`allocate` reuses."""

    names: tuple[str, ...]
    lower: np.ndarray
    sensitivities: np.ndarray
    grid: np.ndarray
    step: float
    coef_abs: np.ndarray
    per_component: dict[str, dict[str, float]]
    weights: dict[str, dict[str, float]]
    info: dict[str, Any]
    notes: list[str]
    upper: np.ndarray
    affected: np.ndarray
    binding: dict[str, str]


def _linear_allocation(
    table: Turntable, req: dict[str, float], step_deg: float, constraint_step_deg: float | None
) -> _Linear:
    """Per-component optima of eqs. (31)–(33) and their eq. (34) minimum (linearised model)."""
    names = tuple(table.angular_error_names)
    specs = {e.name: e for e in table.errors}
    angle_names = tuple(table.angle_names)
    units, ufac = _display(table)
    lb = np.array([float(specs[n].lower) for n in names])
    sens_step, sens_endpoint = table.sensitivity_grid
    sens = np.asarray(
        table.sensitivities(step_deg=sens_step, endpoint=sens_endpoint), dtype=float
    ).reshape(3, len(names))
    grid, step = _grid(len(angle_names), step_deg, _MAX_GRID_POINTS)
    coef_abs = np.abs(_coefficients(table, grid))
    constraint = _constraint_grid(len(angle_names), constraint_step_deg)
    if constraint is not None:
        c_grid, c_step = constraint
        c_abs = np.abs(_coefficients(table, c_grid))
    per_axis = round(_TWO_PI / step)
    mesh_abs = coef_abs.reshape((per_axis,) * len(angle_names) + coef_abs.shape[1:])
    reach = coef_abs.max(axis=0)  # (3, n): largest |c_ji| on the grid
    per_component: dict[str, dict[str, float]] = {}
    weights: dict[str, dict[str, float]] = {}
    comp_info: dict[str, Any] = {}
    notes: list[str] = []
    chi_star = np.full((3, len(names)), np.inf)
    for j, comp in enumerate(COMPONENTS):
        cols = np.flatnonzero((sens[j] > _SENSITIVE) | (reach[j] > _SENSITIVE))
        if cols.size == 0:
            per_component[comp], weights[comp] = {}, {}
            comp_info[comp] = {"iterations": 0, "success": True, "note": "no error affects it"}
            notes.append(f"{comp}: no error of the table affects it; nothing to allocate.")
            continue
        w_abs = np.array([_weight(specs[names[i]].weight, sens[j, i], reach[j, i]) for i in cols])
        weights[comp] = {names[i]: float(v) for i, v in zip(cols, w_abs, strict=True)}
        if constraint is None:
            lmax = _LinearMax(table, j, cols, grid, coef_abs[:, j, :][:, cols], step)
        else:
            lmax = _LinearMax(table, j, cols, c_grid, c_abs[:, j, :][:, cols], c_step, False)
        try:
            x, info = _solve_component(lmax, w_abs / w_abs.max(), lb[cols] / req[comp])
        except _Infeasible as e:
            contrib = lmax.rows(e.angles)[0] * lb[cols]
            order = np.argsort(-contrib)[:3]
            largest = ", ".join(
                f"{names[cols[i]]} {contrib[i] / ufac:.4g}" for i in order if contrib[i] > 0
            )
            # only the angles the component's coefficients depend on (ψ of the GyroWheel study's table: φ2, not φ1)
            comp_mesh = mesh_abs[..., j, :][..., cols]
            where = ", ".join(
                f"{a} = {v:.2f}°"
                for k, (a, v) in enumerate(zip(angle_names, np.degrees(e.angles), strict=True))
                if float(np.ptp(comp_mesh, axis=k).max()) > _SENSITIVE
            )
            raise ConfigError(
                f"{_source(table)}: the allocation of {comp} is infeasible: "
                + (f"at {where} " if where else "at every angle ")
                + f"the lower bounds alone give {e.value * req[comp] / ufac:.4g} {units} against "
                f"the requirement {req[comp] / ufac:.4g} {units} (largest contributions, "
                f"{units}: {largest}); lower those bounds or relax the requirement."
            ) from None
        chi = x * req[comp]
        chi_star[j, cols] = chi
        per_component[comp] = {names[i]: float(v) for i, v in zip(cols, chi, strict=True)}
        comp_info[comp] = info

    ub = chi_star.min(axis=0)
    bind_idx = chi_star.argmin(axis=0)
    affected = np.isfinite(ub)
    binding: dict[str, str] = {}
    for i, n in enumerate(names):
        if affected[i]:
            binding[n] = COMPONENTS[int(bind_idx[i])]
    ub = np.where(affected, ub, 0.0)
    for i, n in enumerate(names):
        if not affected[i]:
            notes.append(f"{n} has no effect on the orientation: no upper bound.")

    return _Linear(
        names=names,
        lower=lb,
        sensitivities=sens,
        grid=grid,
        step=step,
        coef_abs=coef_abs,
        per_component=per_component,
        weights=weights,
        info=comp_info,
        notes=notes,
        upper=ub,
        affected=affected,
        binding=binding,
    )


def linear_allocation(
    table: Turntable,
    requirement: Mapping[str, float] | float | None = None,
    *,
    angle_step_deg: float = 1.0,
    constraint_step_deg: float | None = None,
) -> dict[str, float | None]:
    """The upper bounds of eqs. (31)–(34) for the linearised model (26) alone (rad).

    What the paper's allocation is: the per-component optima and their minimum (eq. (34)),
    without rotacal's full-model guard and worst-case check (:func:`allocate` adds both).

    Parameters
    ----------
    table : Turntable
        The table.
    requirement : mapping or float, optional
        I_j (rad) for psi, theta, gamma (or one value for all); default ``table.requirement``.
    angle_step_deg, constraint_step_deg
        As in :func:`allocate`.

    Returns
    -------
    dict
        UB_i (rad) per error, ``None`` for errors with no effect on the orientation.

    References
    ----------
    Seed 001, §4.2, eqs. (31)–(34), Table 4.
    """
    _require_angular(table)
    req = _requirement(table, requirement)
    lin = _linear_allocation(table, req, _check_step(angle_step_deg), constraint_step_deg)
    out: dict[str, float | None] = dict.fromkeys(table.error_names)
    for i, n in enumerate(lin.names):
        out[n] = float(lin.upper[i]) if lin.affected[i] else None
    return out


# ----------------------------------------------------------------------------------- allocation
def allocate(
    table: Turntable,
    requirement: Mapping[str, float] | float | None = None,
    *,
    angle_step_deg: float = 1.0,
    full_model_guard: bool = True,
    max_evaluations: int = _MAX_FULL_EVALUATIONS,
    constraint_step_deg: float | None = None,
) -> Allocation:
    """Upper bounds of a turntable's errors from its orientation requirement (eqs. (29)–(34)).

    One problem per orientation component j (generalised eqs. (31)–(33)): minimise
    Σ_i W_ji²/χ_i² over the errors j is sensitive to, subject to max over every angle of
    Σ_i |c_ji(φ)|·χ_i ≤ I_j and χ_i ≥ LB_i; then UB_i = min_j χ*_ji (eq. (34)). Solved by SLSQP with
    analytic gradients in the scaled variables χ/I_j and an exchange method for the semi-infinite
    constraint (see the module docstring). With ``full_model_guard`` the full model is checked
    over the box's sign vertices and, where it exceeds I_j (second-order terms), the bounds of
    component j's errors are shrunk until it does not; ``per_component`` keeps the linear optimum.

    Parameters
    ----------
    table : Turntable
        The table; its ``errors`` give LB_i (rad) and optional weight overrides.
    requirement : mapping or float, optional
        I_j (rad) for psi, theta, gamma (or one value for all); default ``table.requirement``.
    angle_step_deg : float
        Step of the fine angle grid (deg) on which the worst angle is sought; coarsened for tables
        of three angles so that the grid stays ≤ 1.5·10⁵ points.
    full_model_guard : bool
        Shrink bounds where the full model exceeds a requirement (default True).
    max_evaluations : int
        Cap of the full-model enumeration of :func:`worst_case`.
    constraint_step_deg : float, optional
        Enforce the constraint of eqs. (31)–(33) only at the angles that are multiples of this
        step (deg, dividing 360°), unrefined: 45 is the paper's grid — its constraint on φ2 ∈
        [0, π/2] (eq. (31)) evaluated at φ2 ∈ {0°, 45°, 90°}, the points of its averaging, which
        Lemma 1's folding extends to every multiple of 45°; with it, Table 4 comes out (see
        :mod:`rotacal.turntable.seed001`). ``None`` (default): every angle (a fine grid refined
        between its points). The worst case reported (Lemma 1 check) and the full-model guard
        always look at every angle, so a grid allocation that exceeds the requirement between
        its points is shown (``within``) and, with the guard, shrunk.

    Returns
    -------
    Allocation
        Upper bounds (rad), the per-component optima, weights, sensitivities, the Lemma 1 worst
        cases and the optimiser's record.

    Raises
    ------
    ConfigError
        No requirement; a bad requirement or step; a table none of whose errors changes the
        orientation; lower bounds that alone exceed a requirement at some angle (one line starting
        with the table's source, naming the component, the angles that component depends on, the
        value and the largest bounds).

    References
    ----------
    Seed 001, §4.1–4.2, eqs. (28)–(34), Lemma 1 (eqs. (35)–(38)), Table 4.
    """
    key = memo_key(
        table, requirement, angle_step_deg, full_model_guard, max_evaluations, constraint_step_deg
    )
    return _ALLOCATIONS.get(
        key,
        lambda: _allocate(
            table,
            requirement,
            angle_step_deg=angle_step_deg,
            full_model_guard=full_model_guard,
            max_evaluations=max_evaluations,
            constraint_step_deg=constraint_step_deg,
        ),
    )


#: The last allocations made in this process, by their inputs (the table as it compares and the
#: options). An allocation is deterministic in these, and a repeat with the same ones is common —
#: the requirement's derivation tries scales it tried before, a batch of one table design, a
#: command run twice in one session — while one costs 5–15 s.
_ALLOCATIONS: LastResults[Allocation] = LastResults(8)


def _allocate(
    table: Turntable,
    requirement: Mapping[str, float] | float | None,
    *,
    angle_step_deg: float,
    full_model_guard: bool,
    max_evaluations: int,
    constraint_step_deg: float | None,
) -> Allocation:
    """:func:`allocate` without its memo."""
    _require_angular(table)
    req = _requirement(table, requirement)
    step_deg = _check_step(angle_step_deg)
    lin = _linear_allocation(table, req, step_deg, constraint_step_deg)
    names, lb, grid, step = lin.names, lin.lower, lin.grid, lin.step
    per_component, notes, angle_names = lin.per_component, lin.notes, tuple(table.angle_names)
    ub, affected = lin.upper.copy(), lin.affected
    upper: dict[str, float | None] = {}
    cache = {"grid": grid, "step": step, "coef_abs": lin.coef_abs}
    scale = dict.fromkeys(COMPONENTS, 1.0)
    wc = _worst_case_arrays(table, ub, req, step_deg, int(max_evaluations), cache)
    if full_model_guard:
        for _ in range(6):
            over = [j for j, c in enumerate(COMPONENTS) if wc[c]["full_rad"] > req[c]]
            if not over:
                break
            for j in over:
                comp = COMPONENTS[j]
                cols = np.array([names.index(n) for n in per_component[comp]], dtype=int)
                free = cols[ub[cols] > lb[cols]]
                s = _guard_scale(table, wc[comp], ub, free, j, req[comp], angle_names, names)
                ub[free] = np.maximum(ub[free] * s, lb[free])
                scale[comp] *= s
            wc = _worst_case_arrays(table, ub, req, step_deg, int(max_evaluations), cache)
        for comp, s in scale.items():
            if s < 1.0:
                notes.append(
                    f"{comp}: the full model exceeded the requirement at the worst vertex of the "
                    f"linear allocation; its errors' bounds were scaled by {s:.9f}."
                )
    for i, n in enumerate(names):
        upper[n] = float(ub[i]) if affected[i] else None
    for n in table.error_names:
        if n not in upper:
            upper[n] = None
            notes.append(f"{n} is a translation: no effect on the orientation, no upper bound.")
    upper = {n: upper[n] for n in table.error_names}
    sensitivities = {
        c: {n: float(lin.sensitivities[j, i]) for i, n in enumerate(names)}
        for j, c in enumerate(COMPONENTS)
    }
    sens_step, sens_endpoint = table.sensitivity_grid
    optimiser = {
        "method": "SLSQP (analytic gradients, variables χ/I_j) with an exchange method for the "
        "semi-infinite angle constraint",
        "sensitivity_grid": {"step_deg": float(sens_step), "endpoint": bool(sens_endpoint)},
        "constraint_angles": "every angle"
        if constraint_step_deg is None
        else f"multiples of {float(constraint_step_deg):g}° only",
        "grid_step_deg": math.degrees(step),
        "grid_points": int(grid.shape[0]),
        "components": lin.info,
        "full_model_guard": bool(full_model_guard),
        "full_model_scale": scale,
        "notes": notes,
    }
    return Allocation(
        error_names=tuple(table.error_names),
        units=_display(table)[0],
        upper_bounds_rad=upper,
        lower_bounds_rad={n: float(v) for n, v in zip(names, lb, strict=True)},
        per_component=per_component,
        binding=lin.binding,
        weights=lin.weights,
        sensitivities=sensitivities,
        requirement_rad=req,
        worst_case=wc,
        within=all(v["within"] for v in wc.values()),
        optimiser=optimiser,
    )


def _weight(override: float | None, sensitivity: float, reach: float) -> float:
    """W_ji: the override, else 1/C_ji (1/max|c_ji| for an error with a zero grid mean)."""
    if override is not None:
        return float(override)
    return 1.0 / float(sensitivity if sensitivity > _SENSITIVE else reach)


def _guard_scale(
    table: Turntable,
    wc: Mapping[str, Any],
    ub: np.ndarray,
    free: np.ndarray,
    j: int,
    req: float,
    angle_names: tuple[str, ...],
    names: tuple[str, ...],
) -> float:
    """Factor on the free errors of component j that brings the full model at its worst point to I_j."""
    if free.size == 0:
        raise ConfigError(
            f"the full model exceeds the {COMPONENTS[j]} requirement and none of the errors that "
            f"{COMPONENTS[j]} is sensitive to can shrink further (none, or all at their lower "
            "bounds): lower those bounds or relax the requirement."
        )
    angles = np.radians([[wc["angles_deg"][a] for a in angle_names]])
    chi = np.array([[wc["signs"].get(n, 1) * u for n, u in zip(names, ub, strict=True)]])
    chi_fixed = chi.copy()
    chi_fixed[0, free] = 0.0
    full = float(_fast(table, angles, chi)[0, j])
    rest = float(_fast(table, angles, chi_fixed)[0, j])
    sign = 1.0 if full >= 0 else -1.0
    part = sign * (full - rest)
    if part <= 0:
        return 1.0 - 1e-9
    return max(0.0, min(1.0, (req * (1.0 - 1e-12) - sign * rest) / part))


# ---------------------------------------------------------------------------------- Monte Carlo
def monte_carlo_check(
    table: Turntable,
    allocation: Allocation,
    *,
    runs: int = 1_000_000,
    seed: int = 2026,
    signs: str = "random",
    chunk: int = 262_144,
    progress: Callable[[int, int], None] | None = None,
) -> MonteCarloCheck:
    """Monte Carlo check of an allocation with the full orientation-error model (Figure 9).

    Each draw takes every angle uniform on [0, 2π) and every angular error χ_i = s_i·U(LB_i, UB_i)
    (s_i = ±1 with equal odds for ``signs="random"``; +1 for ``"positive"``, the paper's literal
    Ω_χ), and evaluates the full model ``table.fast_orientation_error`` (eqs. (17)–(24)). The draws
    come from ``numpy.random.Generator(PCG64(seed))``, one row of uniforms per draw (errors first,
    then angles; for random signs one uniform v on [−1, 1) gives both sign and magnitude |v|), in
    chunks of ``chunk`` rows: memory stays flat and the result is the same for any chunk size.

    Parameters
    ----------
    table : Turntable
        The table.
    allocation : Allocation
        Its ``upper_bounds_rad`` and ``lower_bounds_rad`` (rad) and ``requirement_rad`` are used
        (``None`` bounds: the error is held at 0).
    runs : int
        Number of draws (the paper used 10 000); an integer ≥ 1.
    seed : int
        Seed of the generator; an integer ≥ 0.
    signs : {"random", "positive"}
        Sign of the errors.
    chunk : int
        Draws per chunk.
    progress : callable, optional
        ``progress(done, total)`` after every chunk.

    Returns
    -------
    MonteCarloCheck
        Largest |Δψ|, |Δθ|, |Δγ| (rad and arcmin), whether all draws are within the requirement,
        how many are not, the throughput, 60-bin histograms over ±I_j, and the 99.9 % quantile
        of each |Δ_j| with its 95 % coverage interval (from the largest draws, kept chunk by chunk).

    Raises
    ------
    ConfigError
        runs or chunk not an integer ≥ 1, seed not an integer ≥ 0 (booleans and floats such as
        1.5 are refused, not truncated), an unknown ``signs``, LB_i > UB_i.

    References
    ----------
    Seed 001, §4.3 (Monte Carlo verification, 10 000 runs), Figure 9; eqs. (17)–(25).
    """
    _require_angular(table)
    runs_i, seed_i = check_draws(runs, seed)
    chunk_i = _integer("chunk", chunk, 1)
    if signs not in ("random", "positive"):
        raise ConfigError(f"signs must be 'random' or 'positive', got {signs!r}.")
    names = tuple(table.angular_error_names)
    ub = _bounds_vector(table, allocation.upper_bounds_rad, "the upper bound")
    lb = _bounds_vector(table, allocation.lower_bounds_rad, "the lower bound")
    lb = np.where(ub > 0, lb, 0.0)
    bad = np.flatnonzero(lb > ub)
    if bad.size:
        raise ConfigError(
            f"the lower bound of {names[int(bad[0])]} exceeds its upper bound: fix the allocation."
        )
    req = _requirement(table, allocation.requirement_rad)
    req_v = np.array([req[c] for c in COMPONENTS])
    n_err = len(names)
    n_angles = len(tuple(table.angle_names))
    width = ub - lb
    rng = np.random.Generator(np.random.PCG64(seed_i))
    max_abs = np.zeros(3)
    counts = np.zeros((3, _HIST_BINS), dtype=np.int64)
    outside = 0
    bins_per_rad = _HIST_BINS / (2.0 * req_v)
    largest = TopValues(top_values_needed(runs_i), 3)  # for the 99.9 % quantile of |Δ|
    t0 = time.perf_counter()
    done = 0
    if numba_enabled():  # the same numbers, each chunk's draws and tallies in one pass
        draws, tally = compiled_draws(), compiled_tally()
        chi_buffer, angle_buffer = np.empty((chunk_i, n_err)), np.empty((chunk_i, n_angles))
    while done < runs_i:
        m = min(chunk_i, runs_i - done)
        u = rng.random((m, n_err + n_angles))
        if numba_enabled():
            chi, angles = chi_buffer[:m], angle_buffer[:m]
            draws(u, lb, width, signs == "random", chi, angles)
            d = _fast(table, angles, chi)
            outside += tally(d, req_v, bins_per_rad, max_abs, counts)
            largest.add(np.abs(d))
            done += m
            if progress is not None:
                progress(done, runs_i)
            continue
        if signs == "random":
            v = 2.0 * u[:, :n_err] - 1.0
            chi = np.copysign(lb + width * np.abs(v), v)
        else:
            chi = lb + width * u[:, :n_err]
        angles = _TWO_PI * u[:, n_err:]
        d = _fast(table, angles, chi)
        a = np.abs(d)
        np.maximum(max_abs, a.max(axis=0), out=max_abs)
        largest.add(a)
        out_mask = a > req_v
        outside += int(np.count_nonzero(out_mask.any(axis=1)))
        idx = np.floor((d + req_v) * bins_per_rad).astype(np.int64)
        idx = np.minimum(idx, _HIST_BINS - 1)  # +I_j exactly falls in the last bin
        for j in range(3):
            keep = idx[~out_mask[:, j], j]
            counts[j] += np.bincount(keep, minlength=_HIST_BINS)[:_HIST_BINS]
        done += m
        if progress is not None:
            progress(done, runs_i)
    elapsed = time.perf_counter() - t0
    histograms = {
        c: {
            "edges_rad": np.linspace(-req_v[j], req_v[j], _HIST_BINS + 1).tolist(),
            "counts": counts[j].tolist(),
        }
        for j, c in enumerate(COMPONENTS)
    }
    quantiles = {
        c: quantile_interval(largest.values[:, j], runs_i) for j, c in enumerate(COMPONENTS)
    }
    return MonteCarloCheck(
        runs=runs_i,
        seed=seed_i,
        signs=signs,
        max_abs_rad={c: float(max_abs[j]) for j, c in enumerate(COMPONENTS)},
        max_abs_arcmin={c: float(max_abs[j] * ARCMIN_PER_RAD) for j, c in enumerate(COMPONENTS)},
        requirement_rad=req,
        all_within=outside == 0,
        outside=outside,
        draws_per_second=runs_i / elapsed if elapsed > 0 else math.inf,
        histograms=histograms,
        quantile_abs_rad=(
            None if any(v is None for v in quantiles.values()) else quantiles  # type: ignore[arg-type]
        ),
    )


def check_draws(runs: Any, seed: Any) -> tuple[int, int]:
    """``runs`` (an integer ≥ 1) and ``seed`` (an integer ≥ 0) of :func:`monte_carlo_check` as
    ints; anything else is one ConfigError line naming it. A caller that allocates first checks
    them before the allocation's seconds of work."""
    return _integer("runs", runs, 1), _integer("seed", seed, 0)


def _integer(name: str, value: Any, minimum: int) -> int:
    """``value`` as an int ≥ ``minimum``; bools, floats and strings are one ConfigError line."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)):
        raise ConfigError(f"{name} must be an integer ≥ {minimum}, got {value!r}.")
    if int(value) < minimum:
        raise ConfigError(f"{name} must be an integer ≥ {minimum}, got {value!r}.")
    return int(value)
