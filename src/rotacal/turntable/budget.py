"""A turntable's accuracy budget end to end: model, sensitivities, allocation, Monte Carlo check,
and what the allocated table does to a gyro calibration (GyroWheel study, §§2–4).

:func:`turntable_budget` is what ``rotacal turntable budget CONFIG.toml`` runs. From the table's
description (a TOML file, see :mod:`rotacal.turntable.config`) it

1. takes the orientation requirement as stated, or derives it from a required calibration accuracy
   of a multiposition drift test (eqs. (7)–(16); only for a table of the GyroWheel study's geometry) — by
   default so that the tables the allocation admits pass the calibration check of step 4, or by
   the paper's Earth-rate reading of eq. (16) (:mod:`rotacal.turntable.requirement`);
2. averages the sensitivities (eq. (28)) and allocates upper bounds to the error sources
   (eqs. (29)–(34)) — the constraint at every angle, or on the paper's grid — checking the worst
   case over all angles (Lemma 1);
3. checks the allocation by Monte Carlo with the full nonlinear model (eqs. (17)–(25));
4. for a table of the GyroWheel study's geometry, draws tables within the allocation and computes the
   rate-sensing error of the multiposition calibration run on them (eqs. (7)–(14) with the
   orientation error of each test position from eq. (23)), and the worst such table.

References
----------
Seed 001 (``../shared/seeds/001_4a387eb674e238f2.txt``): GyroWheel calibration tests, error
analysis and turntable error allocation — eqs. (7)–(16), (17)–(34), Lemma 1, Tables 1–4, Figures 4–9.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

import numpy as np

from rotacal.errors import ConfigError
from rotacal.results import Result, with_warnings
from rotacal.sim.multiposition import DEFAULT_LATITUDE_DEG
from rotacal.turntable.allocation import (
    EVERY_ANGLE,
    Allocation,
    MonteCarloCheck,
    allocate,
    check_constraint_angles,
    check_draws,
    monte_carlo_check,
)
from rotacal.turntable.calibration import (
    OrientationRequirement,
    orientation_requirement,
    rate_sensing_error_from_rotation,
)
from rotacal.turntable.chain import ARCMIN_PER_RAD, COMPONENTS
from rotacal.turntable.config import load_turntable
from rotacal.turntable.draws import COVERAGE, fraction_interval, quantile_interval
from rotacal.turntable.geometry import Turntable
from rotacal.turntable.plausibility import budget_warnings
from rotacal.turntable.requirement import (
    DEFAULT_DERIVATION,
    DerivedRequirement,
    calibration_worst_case,
    check_derivation,
    derive_requirement,
)
from rotacal.turntable.seed001 import is_seed_table, reproduce_seed001

__all__ = ["TurntableBudget", "budget_allocation", "calibration_check", "turntable_budget"]


def _arcmin(values: Mapping[str, float | None]) -> dict[str, float | None]:
    return {k: (None if v is None else float(v) * ARCMIN_PER_RAD) for k, v in values.items()}


@dataclasses.dataclass(frozen=True)
class TurntableBudget(Result):
    """The budget of one turntable (JSON keys of INTERFACE.md, ``turntable budget``).

    ``sensitivities`` maps ``psi``/``theta``/``gamma`` to {error: mean |∂Δ/∂χ|} (eq. (28));
    ``upper_bounds_arcmin`` maps each error to its allocated upper bound (eq. (34); ``None`` for
    translations, which cannot change the orientation); ``monte_carlo`` holds ``runs``,
    ``max_abs_arcmin`` (per component), ``all_within``, the draw settings and what the check
    states with a 95 % coverage interval (``fraction_outside`` with ``fraction_outside_interval``;
    ``quantile_abs_arcmin`` with ``quantile_abs_interval_arcmin``, the 99.9 % quantile of each
    |Δ|; :mod:`rotacal.turntable.draws`); ``calibration`` adds the intervals of its 95th
    percentile and of its fraction above the required accuracy. ``options`` holds
    the two choices of the budget (``requirement_derivation``, ``constraint_angles``);
    ``derivation`` how a calibration accuracy became the requirement (``None`` when stated).
    """

    table: str
    error_names: tuple[str, ...]
    labels: dict[str, str]
    requirement_arcmin: dict[str, float]
    requirement_source: str
    options: dict[str, Any]
    derivation: dict[str, Any] | None
    sensitivities: dict[str, dict[str, float]]
    lower_bounds_arcmin: dict[str, float]
    upper_bounds_arcmin: dict[str, float | None]
    binding: dict[str, str]
    worst_case: dict[str, dict[str, Any]]
    allocation_within: bool
    monte_carlo: dict[str, Any]
    calibration: dict[str, Any] | None
    reproduction: dict[str, Any] | None
    _table: Turntable = dataclasses.field(repr=False)
    _allocation: Allocation = dataclasses.field(repr=False)
    _monte_carlo: MonteCarloCheck = dataclasses.field(repr=False)
    _requirement: OrientationRequirement | None = dataclasses.field(repr=False)
    _calibration_draws: dict[str, np.ndarray] | None = dataclasses.field(repr=False)
    _plan_deg: tuple[np.ndarray, np.ndarray] | None = dataclasses.field(repr=False)


#: Tables drawn for the calibration check (the paper's Monte Carlo size).
_CALIBRATION_RUNS = 10_000


def _worst_case_arcmin(worst: Mapping[str, Mapping[str, Any]]) -> dict[str, dict[str, Any]]:
    """The allocation's worst cases with every ``*_rad`` value also in arcmin (as the JSON is)."""
    out: dict[str, dict[str, Any]] = {}
    for comp, entry in worst.items():
        out[comp] = {}
        for key, value in entry.items():
            if key.endswith("_rad"):
                out[comp][key[: -len("_rad")] + "_arcmin"] = float(value) * ARCMIN_PER_RAD
            else:
                out[comp][key] = value
    return out


def _monte_carlo_statistics(mc: MonteCarloCheck) -> dict[str, Any]:
    """What the Monte Carlo check states with a 95 % coverage interval (:mod:`.draws`): the
    fraction of tables outside the requirement, and the 99.9 % quantile of each |Δ| (arcmin)."""
    fraction, low, high = fraction_interval(mc.outside, mc.runs)
    out: dict[str, Any] = {
        "coverage_probability": COVERAGE,
        "fraction_outside": fraction,
        "fraction_outside_interval": [low, high],
    }
    if mc.quantile_abs_rad is not None:
        out["quantile"] = mc.quantile
        out["quantile_abs_arcmin"] = {
            c: v[0] * ARCMIN_PER_RAD for c, v in mc.quantile_abs_rad.items()
        }
        out["quantile_abs_interval_arcmin"] = {
            c: [v[1] * ARCMIN_PER_RAD, v[2] * ARCMIN_PER_RAD]
            for c, v in mc.quantile_abs_rad.items()
        }
    return out


def _calibration_statistics(draws: Mapping[str, np.ndarray], required: float) -> dict[str, Any]:
    """95 % coverage intervals of the calibration check's 95th percentile (order statistics) and
    of the fraction of tables above the required accuracy (Clopper–Pearson), per gyro axis."""
    p95: dict[str, list[float]] = {}
    above: dict[str, list[float]] = {}
    for axis, values in draws.items():
        v = np.asarray(values, dtype=float)
        stated = quantile_interval(v, v.size, 0.95)
        if stated is not None:
            p95[axis] = [stated[1], stated[2]]
        _, low, high = fraction_interval(int(np.count_nonzero(v > required)), v.size)
        above[axis] = [low, high]
    return {"p95_rate_error_interval_deg_h": p95, "fraction_above_required_interval": above}


def _seed_geometry(table: Turntable) -> bool:
    """True when the chain is the GyroWheel study's: an outer axis about y, then an inner axis about z."""
    axes = [link.axis for link in table.links if link.axis is not None]
    return axes == ["y", "z"]


def _calibration_settings(table: Turntable) -> dict[str, Any]:
    cal = dict(table.settings.get("calibration", {}))
    return {
        "latitude_deg": float(cal.get("latitude_deg", DEFAULT_LATITUDE_DEG)),
        "outer_steps": int(cal.get("outer_steps", 8)),
        "inner_steps": int(cal.get("inner_steps", 8)),
    }


def _required_deg_h(table: Turntable) -> float | None:
    """The calibration accuracy the table must allow, if the configuration states one."""
    if table.calibration_requirement_deg_h is not None:
        return float(table.calibration_requirement_deg_h)
    value = table.settings.get("calibration", {}).get("required_deg_h")
    return None if value is None else float(value)


def _plan_angles(settings: Mapping[str, Any]) -> tuple[np.ndarray, np.ndarray]:
    from rotacal.gyro.multiposition import multiposition_plan

    plan = multiposition_plan(
        outer_steps=settings["outer_steps"], inner_steps=settings["inner_steps"]
    )
    return np.asarray(plan.phi1_deg, dtype=float), np.asarray(plan.phi2_deg, dtype=float)


def calibration_check(
    table: Turntable,
    upper_bounds_rad: Mapping[str, float | None],
    *,
    lower_bounds_rad: Mapping[str, float] | None = None,
    runs: int = 10_000,
    seed: int = 2026,
    latitude_deg: float = DEFAULT_LATITUDE_DEG,
    outer_steps: int = 8,
    inner_steps: int = 8,
) -> dict[str, np.ndarray]:
    """Rate-sensing errors of multiposition calibrations run on tables drawn within the bounds.

    Each draw is a table whose errors have magnitudes uniform between the lower and upper bounds
    and random signs; at every test position of the plan its orientation error ΔR (eq. (23), full
    model) perturbs the Earth rate and gravity the gyro sees (eq. (8)), the drift coefficients are
    fitted with the nominal inputs (eq. (6)) and the rate-sensing errors Δω_x, Δω_y (eqs. (12)–(14))
    follow. Unlike eqs. (15)–(16), the orientation error here varies from position to position,
    as eq. (26) says it does.

    Parameters
    ----------
    table : Turntable
        A table of the GyroWheel study's geometry (outer axis about y, inner about z).
    upper_bounds_rad, lower_bounds_rad : mapping
        Bounds of each error (rad; translations are ignored: they cannot change the orientation).
    runs : int
        Number of tables drawn.
    seed : int
        Seed of the random generator.
    latitude_deg : float
        Latitude of the laboratory (deg).
    outer_steps, inner_steps : int
        The plan: φ1 every 360°/outer_steps, φ2 every 360°/inner_steps.

    Returns
    -------
    dict
        ``"x"`` and ``"y"``: arrays of Δω (°/h), one per draw.

    References
    ----------
    Seed 001, eqs. (7)–(14), (23).
    """
    if not _seed_geometry(table):
        raise ConfigError(
            "the calibration check needs a table of the GyroWheel study's geometry (an outer axis about y, "
            "then an inner axis about z): the multiposition kinematics of eq. (3) assume it."
        )
    names = table.angular_error_names
    lb = dict.fromkeys(names, 0.0) | dict(lower_bounds_rad or {})
    ub = {n: upper_bounds_rad.get(n) for n in names}
    lo = np.array([lb[n] for n in names])
    hi = np.array([0.0 if ub[n] is None else float(ub[n]) for n in names])  # type: ignore[arg-type]
    rng = np.random.default_rng(seed)
    mag = rng.uniform(lo, hi, size=(runs, len(names)))
    chi = np.where(rng.random((runs, len(names))) < 0.5, -mag, mag)
    p1, p2 = _plan_angles(
        {"outer_steps": outer_steps, "inner_steps": inner_steps, "latitude_deg": latitude_deg}
    )
    errors = {n: chi[:, i, None] for i, n in enumerate(names)}  # (runs, 1) against (positions,)
    delta_r = table.rotation_error([np.radians(p1), np.radians(p2)], errors)
    dwx, dwy = rate_sensing_error_from_rotation(
        delta_r, phi1_deg=p1, phi2_deg=p2, latitude_deg=latitude_deg
    )
    return {"x": np.asarray(dwx), "y": np.asarray(dwy)}


def _options(
    table: Turntable, requirement_derivation: str | None, constraint_angles: Any
) -> tuple[str | None, float | None]:
    """The derivation (None for a stated requirement) and the constraint step (None: every angle).

    An argument overrides the configuration's ``[requirement] derivation`` and ``[allocation]
    constraint_angles``; a derivation for a table that states its orientation requirement is a
    ConfigError.
    """
    derivation = None
    if requirement_derivation is not None:
        derivation = check_derivation(requirement_derivation, "--requirement-derivation")
        if table.calibration_requirement_deg_h is None:
            raise ConfigError(
                f"--requirement-derivation {derivation} applies to a requirement derived from "
                "[requirement] calibration_deg_h; this configuration states psi, theta, gamma: "
                "drop the option or state calibration_deg_h instead."
            )
    elif table.calibration_requirement_deg_h is not None:
        given = table.settings.get("requirement", {}).get("derivation", DEFAULT_DERIVATION)
        derivation = check_derivation(given, "[requirement] derivation")
    if constraint_angles is not None:
        step = check_constraint_angles(constraint_angles, "--constraint-angles")
    else:
        given = table.settings.get("allocation", {}).get("constraint_angles", EVERY_ANGLE)
        step = check_constraint_angles(given, "[allocation] constraint_angles")
    return derivation, step


def _derivation_text(derived: DerivedRequirement) -> str:
    """How the requirement followed from the calibration accuracy, for ``requirement_source``."""
    wm = derived.required_deg_h
    if derived.scale is None:
        limit = derived.earth_rate.equal_limit_deg if derived.earth_rate is not None else math.nan
        return (
            f"derived from a calibration accuracy of {wm:g} °/h by the Earth-rate reading alone: "
            f"{limit:.5f}° on each component (derivation 'earth-rate-only', the GyroWheel study's eq. (16); "
            "gravity terms and the drift fit are left out)"
        )
    return (
        f"derived from a calibration accuracy of {wm:g} °/h: the box of eqs. (15)–(16) × "
        f"{derived.scale:.4f}, so that every table within the allocated bounds keeps Δωx and Δωy "
        f"≤ {wm:g} °/h at every test position (derivation 'calibration-check')"
    )


def _paper_reading_calibration(
    table: Turntable,
    reproduction: Mapping[str, Any],
    required: float,
    seed: int,
    cal_settings: Mapping[str, Any],
) -> dict[str, Any]:
    """The calibration check of the paper's reading end to end: the grid allocation at eq. (16)'s
    Earth-rate limit (arcmin bounds from the reproduction), its worst table and its draws."""
    ub = {
        n: v / ARCMIN_PER_RAD
        for n, v in reproduction["table4"]["upper_bounds_at_eq16_arcmin"].items()
    }
    lb = {e.name: float(e.lower) for e in table.errors if e.name in ub}
    p1, p2 = _plan_angles(cal_settings)
    worst = calibration_worst_case(
        table, ub, phi1_deg=p1, phi2_deg=p2, latitude_deg=cal_settings["latitude_deg"]
    )
    draws = calibration_check(
        table, ub, lower_bounds_rad=lb, runs=_CALIBRATION_RUNS, seed=seed, **cal_settings
    )
    return {
        "required_deg_h": required,
        "requirement_arcmin": reproduction["table4"]["eq16_requirement_arcmin"],
        "worst_table_rate_error_deg_h": worst,
        "runs": _CALIBRATION_RUNS,
        "fraction_above_required": {k: float(np.mean(v > required)) for k, v in draws.items()},
    }


def _allocation_step(
    table: Turntable,
    derivation: str | None,
    constraint_step: float | None,
    cal_settings: Mapping[str, Any],
) -> tuple[
    dict[str, float], str, Allocation, DerivedRequirement | None, OrientationRequirement | None
]:
    """Steps 1–2 of :func:`turntable_budget`: the requirement (stated or derived), its source
    text, the allocation, and the derivation's record (None for a stated requirement)."""
    requirement_obj: OrientationRequirement | None = None
    derived: DerivedRequirement | None = None
    if table.requirement is not None:
        requirement = dict(table.requirement)
        source = "stated in the configuration"
        alloc = allocate(table, requirement, constraint_step_deg=constraint_step)
    elif table.calibration_requirement_deg_h is not None:
        if not _seed_geometry(table):
            raise ConfigError(
                "calibration_deg_h needs a table of the GyroWheel study's geometry (outer axis about y, inner "
                "about z); state [requirement] psi, theta, gamma for this table instead."
            )
        p1, p2 = _plan_angles(cal_settings)
        derived = derive_requirement(
            table,
            table.calibration_requirement_deg_h,
            derivation or DEFAULT_DERIVATION,
            phi1_deg=p1,
            phi2_deg=p2,
            latitude_deg=cal_settings["latitude_deg"],
            constraint_step_deg=constraint_step,
        )
        requirement_obj = derived.box
        requirement = dict(derived.requirement_rad)
        alloc = derived.allocation
        source = _derivation_text(derived)
    else:
        raise ConfigError(
            "the configuration states no requirement: add [requirement] psi, theta, gamma or "
            "calibration_deg_h."
        )
    return requirement, source, alloc, derived, requirement_obj


def budget_allocation(
    table: Turntable,
    *,
    requirement_derivation: str | None = None,
    constraint_angles: float | str | None = None,
) -> Allocation:
    """The allocation :func:`turntable_budget` makes for ``table`` (its steps 1–2: the
    requirement stated or derived, eqs. (7)–(16); the upper bounds, eqs. (29)–(34)), without
    the Monte Carlo and calibration checks — what ``rotacal turntable identify --config``
    compares the identified errors with.

    References
    ----------
    Seed 001, eqs. (7)–(16), (29)–(34).
    """
    derivation, constraint_step = _options(table, requirement_derivation, constraint_angles)
    return _allocation_step(table, derivation, constraint_step, _calibration_settings(table))[2]


def turntable_budget(
    config: Turntable | str | Path,
    *,
    runs: int | None = None,
    seed: int | None = None,
    progress: Callable[[int, int], None] | None = None,
    requirement_derivation: str | None = None,
    constraint_angles: float | str | None = None,
) -> TurntableBudget:
    """Model, sensitivities, allocation, Monte Carlo check and calibration effect of a turntable.

    Parameters
    ----------
    config : Turntable, str or Path
        The table, or the path of its TOML description.
    runs : int, optional
        Monte Carlo draws (default: the config's ``[monte_carlo] runs``, else 10⁶).
    seed : int, optional
        Seed of the Monte Carlo draws (default: the config's, else 2026).
    progress : callable, optional
        ``progress(done, total)`` during the Monte Carlo.
    requirement_derivation : {"calibration-check", "earth-rate-only"}, optional
        How ``[requirement] calibration_deg_h`` becomes the orientation requirement
        (:mod:`rotacal.turntable.requirement`); default: the config's ``[requirement]
        derivation``, else ``"calibration-check"``. Refused for a stated requirement.
    constraint_angles : "every" or float, optional
        Where the allocation's constraint holds: ``"every"`` angle or a grid step (deg, dividing
        360°; 45 = the paper's grid); default: the config's ``[allocation] constraint_angles``,
        else every angle.

    Returns
    -------
    TurntableBudget

    References
    ----------
    Seed 001, eqs. (7)–(16), (17)–(34), Lemma 1, Figure 9.
    """
    table = config if isinstance(config, Turntable) else load_turntable(Path(config))
    mc_settings = dict(table.settings.get("monte_carlo", {}))
    runs = runs if runs is not None else mc_settings.get("runs", 1_000_000)
    seed = seed if seed is not None else mc_settings.get("seed", 2026)
    check_draws(runs, seed)  # a refusal before the allocation's seconds of work, not after
    cal_settings = _calibration_settings(table)
    derivation, constraint_step = _options(table, requirement_derivation, constraint_angles)
    step = _allocation_step(table, derivation, constraint_step, cal_settings)
    requirement, source, alloc, derived, requirement_obj = step

    mc = monte_carlo_check(
        table,
        alloc,
        runs=runs,
        seed=seed,
        signs=str(mc_settings.get("signs", "random")),
        progress=progress,
        stream=str(mc_settings.get("stream", "philox")),
    )

    calibration: dict[str, Any] | None = None
    draws: dict[str, np.ndarray] | None = None
    plan: tuple[np.ndarray, np.ndarray] | None = None
    required = _required_deg_h(table)
    if _seed_geometry(table) and required is not None:
        plan = _plan_angles(cal_settings)
        if requirement_obj is None:
            requirement_obj = orientation_requirement(
                required,
                phi1_deg=plan[0],
                phi2_deg=plan[1],
                latitude_deg=cal_settings["latitude_deg"],
            )
        draws = calibration_check(
            table,
            alloc.upper_bounds_rad,
            lower_bounds_rad=alloc.lower_bounds_rad,
            runs=_CALIBRATION_RUNS,
            seed=seed,
            **cal_settings,
        )
        worst = (
            derived.worst
            if derived is not None
            else calibration_worst_case(
                table,
                alloc.upper_bounds_rad,
                phi1_deg=plan[0],
                phi2_deg=plan[1],
                latitude_deg=cal_settings["latitude_deg"],
            )
        )
        calibration = {
            "required_deg_h": required,
            "plan": f"{cal_settings['outer_steps']} outer × {cal_settings['inner_steps']} inner",
            "latitude_deg": cal_settings["latitude_deg"],
            "runs": _CALIBRATION_RUNS,
            "max_rate_error_deg_h": {k: float(np.max(v)) for k, v in draws.items()},
            "p95_rate_error_deg_h": {k: float(np.percentile(v, 95)) for k, v in draws.items()},
            "fraction_above_required": {k: float(np.mean(v > required)) for k, v in draws.items()},
            **_calibration_statistics(draws, required),
            "worst_table_rate_error_deg_h": worst,
            "orientation_requirement": requirement_obj.to_dict(),
        }
    reproduction = None
    if is_seed_table(table):
        p1, p2 = _plan_angles(cal_settings)
        reproduction = reproduce_seed001(
            table, phi1_deg=p1, phi2_deg=p2, latitude_deg=cal_settings["latitude_deg"]
        )
        if required is not None:
            reproduction["paper_reading_calibration"] = _paper_reading_calibration(
                table, reproduction, required, seed, cal_settings
            )

    lower = {n: float(alloc.lower_bounds_rad.get(n, 0.0)) for n in table.angular_error_names}
    budget = TurntableBudget(
        table=table.name,
        error_names=table.error_names,
        labels={e.name: e.label for e in table.errors},
        requirement_arcmin={c: float(requirement[c]) * ARCMIN_PER_RAD for c in COMPONENTS},
        requirement_source=source,
        options={
            "requirement_derivation": derivation,
            "constraint_angles": EVERY_ANGLE if constraint_step is None else constraint_step,
        },
        derivation=None if derived is None else derived.to_dict(),
        sensitivities=alloc.sensitivities,
        lower_bounds_arcmin={k: float(v) * ARCMIN_PER_RAD for k, v in lower.items()},
        upper_bounds_arcmin=_arcmin(alloc.upper_bounds_rad),
        binding=dict(alloc.binding),
        worst_case=_worst_case_arcmin(alloc.worst_case),
        allocation_within=bool(alloc.within),
        monte_carlo={
            "runs": mc.runs,
            "seed": mc.seed,
            "signs": mc.signs,
            "stream": mc.stream,
            "max_abs_arcmin": dict(mc.max_abs_arcmin),
            "all_within": bool(mc.all_within),
            "outside": int(mc.outside),
            **_monte_carlo_statistics(mc),
        },
        calibration=calibration,
        reproduction=reproduction,
        _table=table,
        _allocation=alloc,
        _monte_carlo=mc,
        _requirement=requirement_obj,
        _calibration_draws=draws,
        _plan_deg=plan,
    )
    checks = budget_warnings(
        allocation_within=bool(alloc.within),
        runs=int(mc.runs),
        outside=int(mc.outside),
        max_abs_arcmin=dict(mc.max_abs_arcmin),
        requirement_arcmin=budget.requirement_arcmin,
    )
    return with_warnings(budget, [*_calibration_warnings(calibration), *checks])


def _calibration_warnings(calibration: Mapping[str, Any] | None) -> list[str]:
    """A warning when tables built to the allocation can exceed the calibration accuracy."""
    if calibration is None:
        return []
    worst = calibration["worst_table_rate_error_deg_h"]["worst_deg_h"]
    required = calibration["required_deg_h"]
    if worst <= required:
        return []
    frac = calibration["fraction_above_required"]
    return [
        f"tables built to this allocation can miss the calibration accuracy of {required:g} °/h: "
        f"the worst reaches {worst:.4g} °/h, and {frac['x'] * 100:.1f} % (x) and "
        f"{frac['y'] * 100:.1f} % (y) of {calibration['runs']} tables drawn exceed it; derive the "
        'requirement from [requirement] calibration_deg_h with derivation "calibration-check".'
    ]
