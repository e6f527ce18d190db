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
import math
from collections.abc import Mapping
from typing import Any

import numpy as np
from scipy.optimize import Bounds, minimize

from rotacal.errors import ConfigError
from rotacal.results import Result
from rotacal.turntable.chain import COMPONENTS
from rotacal.turntable.geometry import Turntable
from rotacal.turntable.memo import LastResults, memo_key
from rotacal.turntable.montecarlo import MonteCarloCheck, check_draws, monte_carlo_check
from rotacal.turntable.worstcase import (
    _EXCHANGE_RTOL,
    _MAX_FULL_EVALUATIONS,
    _MAX_GRID_POINTS,
    _TWO_PI,
    _check_step,
    _coefficients,
    _display,
    _fast,
    _grid,
    _grid_m,
    _LinearMax,
    _require_angular,
    _requirement,
    _source,
    _unit_factor,
    _worst_case_arrays,
    worst_case,
)

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

#: An error with mean |∂Δ_j/∂χ_i| above this is one component j is sensitive to (eq. (28)).
_SENSITIVE = 1e-12
#: The exchange method stops when the refined worst angle exceeds I_j by no more than this
#: (relative): far below _EXCHANGE_RTOL because the polygonal (finite-angle) approximation of the
#: constraint moves χ* by ~√(excess), not by the excess.
_EXCHANGE_STOP = 1e-14
#: The value of ``constraint_angles`` that enforces the allocation's constraint at every angle.
EVERY_ANGLE = "every"
#: The last allocations made in this process, by their inputs (the table as it compares and the
#: options). An allocation is deterministic in these, and a repeat with the same ones is common —
#: the requirement's derivation tries scales it tried before, a batch of one table design, a
#: command run twice in one session — while one costs 5–15 s.
_ALLOCATIONS: LastResults[Allocation] = LastResults(8)


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


class _Infeasible(Exception):
    def __init__(self, value: float, angles: np.ndarray) -> None:
        super().__init__(value)
        self.value = value
        self.angles = angles


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
