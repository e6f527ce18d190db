"""Report section for a turntable's accuracy budget (seed 001, §§2.2–2.3 and §4).

:func:`turntable_section` renders a :class:`~rotacal.turntable.budget.TurntableBudget`: the
sensitivities of the orientation error to each error source (the seed's Figure 8), the allocated
upper bounds (Table 4), the worst case over all angles (Lemma 1), the Monte Carlo check with the
full model (Figure 9), what an orientation error does to a multiposition gyro calibration
(Figures 4–5) and, for the seed's own table, a side-by-side of the paper's numbers and rotacal's
(:mod:`rotacal.report.turntable_seed001`).

References
----------
Seed 001 (``../shared/seeds/001_4a387eb674e238f2.txt``): eqs. (7)–(16), (26), (28)–(34),
Lemma 1, Tables 2 and 4, Figures 4, 5, 8 and 9.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
from matplotlib.lines import Line2D
from matplotlib.patches import Rectangle
from matplotlib.ticker import MaxNLocator

from rotacal.report.html import Figure, Section, Table, figure_from_matplotlib
from rotacal.report.turntable_common import COMP_SYMBOL, is_seed_budget, symbol
from rotacal.report.turntable_seed001 import (
    seed_comparison_table,
    seed_paragraph,
    table4_worst_case,
)
from rotacal.turntable.budget import TurntableBudget
from rotacal.turntable.model import ARCMIN_PER_RAD, COMPONENTS
from rotacal.turntable.seed001 import (
    EQ16_DEG,
    FIGURE8,
    TABLE4_ARCMIN,
)

__all__ = [
    "EQ16_DEG",
    "FIGURE8",
    "TABLE4_ARCMIN",
    "allocation_table",
    "calibration_draws_figure",
    "calibration_figure",
    "monte_carlo_figure",
    "seed_comparison_table",
    "sensitivity_figure",
    "turntable_section",
    "worst_case_table",
]

_COMP_COLOR = {"psi": "#1f5f99", "theta": "#2e8b57", "gamma": "#d2691e"}
_REQ = "#b22222"


def _style(ax: Any) -> None:
    ax.grid(True, color="#e3e7eb", linewidth=0.7)
    ax.set_axisbelow(True)  # grid lines behind bars
    ax.spines[["top", "right"]].set_visible(False)


def _specs(budget: TurntableBudget) -> dict[str, Any]:
    return {e.name: e for e in budget._table.errors}


def _iso(budget: TurntableBudget, name: str) -> str:
    iso = getattr(_specs(budget).get(name), "iso", None)
    return str(iso) if iso else "—"


def _bar_label(budget: TurntableBudget, name: str) -> str:
    """``Position error of outer axis (Δφy1, EBB)``: label, then symbol and ISO symbol."""
    label = budget.labels.get(name) or name
    tags = [t for t in (symbol(name), _iso(budget, name)) if t not in ("—", label)]
    return f"{label} ({', '.join(tags)})" if tags else label


def _f4(x: float | None) -> str:
    return "—" if x is None or not np.isfinite(x) else f"{x:.4f}"


# ----------------------------------------------------------------------------------------------
# 1. Sensitivities (Figure 8)
# ----------------------------------------------------------------------------------------------


def sensitivity_figure(budget: TurntableBudget) -> Figure:
    """Averaged sensitivities of Δψ, Δθ, Δγ to every angular error (the seed's Figure 8).

    References
    ----------
    Seed 001, eq. (28) and Figure 8.
    """
    names = list(budget._table.angular_error_names)
    labels = [_bar_label(budget, n) for n in names]
    y = np.arange(len(names))[::-1]
    height = 0.45 * len(names) + 1.3
    fig, axes = plt.subplots(1, 3, figsize=(12.0, height), sharey=True)
    vmax = max(
        [float(budget.sensitivities[c].get(n, 0.0)) for c in COMPONENTS for n in names] + [1e-12]
    )
    for ax, comp in zip(axes, COMPONENTS, strict=True):
        vals = np.array([float(budget.sensitivities[comp].get(n, 0.0)) for n in names])
        ax.barh(y, vals, color=_COMP_COLOR[comp], height=0.6)
        for yi, v in zip(y, vals, strict=True):
            text = "0" if v == 0.0 else f"{v:.4f}"
            ax.text(v + 0.02 * vmax, yi, text, va="center", ha="left", fontsize=8)
        ax.set_xlim(0, vmax * 1.32)
        ax.set_title(f"{COMP_SYMBOL[comp]} ({comp})", fontsize=10)
        ax.set_xlabel("mean |∂Δ/∂χ| (rad/rad)")
        _style(ax)
        ax.grid(False, axis="y")
    axes[0].set_yticks(y)
    axes[0].set_yticklabels(labels, fontsize=8.5)
    fig.tight_layout()
    step, endpoint = budget._table.sensitivity_grid
    grid = (
        f"on the grid 0°, {step:g}°, …, 360° with both ends (the paper's averaging: 0° and 360° "
        "count twice)"
        if endpoint
        else f"over a full turn, every {step:g}°"
    )
    return figure_from_matplotlib(
        fig,
        "Sensitivity of the orientation error to each error source",
        "Each bar is |∂Δ/∂χᵢ| of the linearised model at zero error (seed 001, eqs. (26), (28)), "
        f"averaged over every rotation angle of the table ({', '.join(budget._table.angle_names)})"
        f" {grid}. "
        "A larger value means the error source must be held tighter. Translations (offsets) have "
        "no effect on orientation and are not shown.",
    )


# ----------------------------------------------------------------------------------------------
# 2. Allocation (Table 4)
# ----------------------------------------------------------------------------------------------


def allocation_table(budget: TurntableBudget) -> Table:
    """Lower and allocated upper bounds per error source, the binding component, Table 4.

    References
    ----------
    Seed 001, eqs. (29)–(34) and Table 4.
    """
    seed = is_seed_budget(budget)
    cols = ["error", "label", "ISO", "lower bound (′)", "allocated upper bound (′)", "set by"]
    if seed:
        cols += ["seed Table 4 (′)", "rotacal / Table 4"]
    specs = _specs(budget)
    rows = []
    for name in budget.error_names:
        ub = budget.upper_bounds_arcmin.get(name)
        spec = specs.get(name)
        if ub is None:
            lower = spec.lower if spec is not None else 0.0
            row = [
                symbol(name),
                budget.labels.get(name, ""),
                _iso(budget, name),
                f"{lower * 1e3:g} mm",
                "no effect on orientation",
                "—",
            ]
            if seed:
                row += ["—", "—"]
        else:
            binding = budget.binding.get(name, "")
            row = [
                symbol(name),
                budget.labels.get(name, ""),
                _iso(budget, name),
                _f4(budget.lower_bounds_arcmin.get(name, 0.0)),
                _f4(ub),
                f"{COMP_SYMBOL.get(binding, binding)}" if binding else "—",
            ]
            if seed:
                t4 = TABLE4_ARCMIN.get(name)
                row += [_f4(t4), f"{ub / t4:.3f}" if t4 else "—"]
        rows.append(row)
    return Table(
        cols,
        rows,
        caption="Allocated upper bounds of the error sources (seed 001, eqs. (29)–(34))",
    )


# ----------------------------------------------------------------------------------------------
# 3. Worst case (Lemma 1)
# ----------------------------------------------------------------------------------------------


def _angles_text(angles: Any, names: tuple[str, ...]) -> str:
    if angles is None:
        return "—"
    if isinstance(angles, Mapping):
        return ", ".join(f"{k} = {float(v):.1f}°" for k, v in angles.items())
    arr = np.atleast_1d(np.asarray(angles, dtype=float))
    return ", ".join(f"{n} = {v:.1f}°" for n, v in zip(names, arr, strict=False))


def worst_case_table(budget: TurntableBudget) -> Table:
    """Per component: requirement, Lemma-1 linear bound, full model worst case, where, within.

    References
    ----------
    Seed 001, Lemma 1 (eqs. (35)–(38)) and eqs. (17)–(25).
    """
    names = tuple(budget._table.angle_names)
    rows = []
    for comp in COMPONENTS:
        wc = budget.worst_case.get(comp)
        req = budget.requirement_arcmin[comp]
        if not wc:
            rows.append([COMP_SYMBOL[comp], _f4(req), "—", "—", "—", "—"])
            continue
        lin = wc.get("linear_arcmin")
        full = wc.get("full_arcmin")
        rows.append(
            [
                COMP_SYMBOL[comp],
                _f4(req),
                _f4(None if lin is None else float(lin)),
                _f4(None if full is None else float(full)),
                _angles_text(wc.get("angles_deg"), names),
                "yes" if wc.get("within") else "NO",
            ]
        )
    return Table(
        [
            "component",
            "requirement (′)",
            "linear bound (′)",
            "full model (′)",
            "worst at",
            "within",
        ],
        rows,
        caption="Worst case over all angles with every error at its allocated bound (Lemma 1)",
    )


# ----------------------------------------------------------------------------------------------
# 4. Monte Carlo (Figure 9)
# ----------------------------------------------------------------------------------------------


def monte_carlo_figure(budget: TurntableBudget) -> Figure:
    """Histograms of Δψ, Δθ, Δγ over the Monte Carlo draws, with ±requirement (Figure 9).

    References
    ----------
    Seed 001, §4.3 and Figure 9.
    """
    mc = budget._monte_carlo
    fig, axes = plt.subplots(1, 3, figsize=(12.0, 3.8), constrained_layout=True)
    for ax, comp in zip(axes, COMPONENTS, strict=True):
        h = mc.histograms[comp]
        edges = np.asarray(h["edges_rad"], dtype=float) * ARCMIN_PER_RAD
        counts = np.asarray(h["counts"], dtype=float)
        req = budget.requirement_arcmin[comp]
        ax.stairs(counts, edges, fill=True, color=_COMP_COLOR[comp], alpha=0.8)
        for sign in (-1.0, 1.0):
            ax.axvline(sign * req, color=_REQ, ls="--", lw=1.3)
        ax.set_xlim(-1.2 * req, 1.2 * req)
        ax.set_title(
            f"{COMP_SYMBOL[comp]}: max |Δ| = {mc.max_abs_arcmin[comp]:.4f}′ of {req:.4f}′",
            fontsize=9.5,
        )
        ax.set_xlabel(f"{COMP_SYMBOL[comp]} (arcmin)")
        ax.ticklabel_format(axis="y", style="sci", scilimits=(-3, 4))
        _style(ax)
    axes[0].set_ylabel("draws per bin")
    fig.legend(
        handles=[Line2D([], [], color=_REQ, ls="--", lw=1.3, label="requirement ±I")],
        loc="outside lower center",
        fontsize=8.5,
        frameon=False,
    )
    within = "all within the requirement" if mc.all_within else f"{mc.outside} outside"
    return figure_from_matplotlib(
        fig,
        "Monte Carlo check with the full model",
        f"{mc.runs:,} tables drawn with every error uniform between its lower and allocated upper "
        f"bound ({mc.signs} signs) and the angles uniform over a turn; orientation error from the "
        "full nonlinear model (seed 001, eqs. (17)–(25)). Red dashed: the requirement ±I. "
        "Max |Δ|: "
        + ", ".join(f"{COMP_SYMBOL[c]} {mc.max_abs_arcmin[c]:.4f}′" for c in COMPONENTS)
        + f" — {within}.",
    )


# ----------------------------------------------------------------------------------------------
# 5. Effect on the calibration (Figures 4–5)
# ----------------------------------------------------------------------------------------------


def _plan(budget: TurntableBudget) -> tuple[np.ndarray, np.ndarray, float]:
    """The multiposition plan (φ1, φ2 in deg) and latitude (deg) the budget used."""
    assert budget._plan_deg is not None and budget.calibration is not None
    p1, p2 = budget._plan_deg
    return p1, p2, float(budget.calibration["latitude_deg"])


def _box(ax: Any, half_x: float, half_y: float, **kw: Any) -> None:
    ax.add_patch(Rectangle((-half_x, -half_y), 2 * half_x, 2 * half_y, fill=False, **kw))


def _label_top(ax: Any, line: Any, text: str) -> None:
    """Write ``text`` just above the highest point of a contour line (on a white ground)."""
    paths = [p.vertices for p in line.get_paths() if len(p.vertices)]
    if not paths:
        return
    v = np.concatenate(paths)
    top = v[np.argmax(v[:, 1])]
    ax.annotate(
        text,
        (0.0, top[1]),
        xytext=(0, 4),
        textcoords="offset points",
        ha="center",
        va="bottom",
        fontsize=8.5,
        color=_REQ,
        bbox={"boxstyle": "round,pad=0.15", "fc": "white", "ec": "none", "alpha": 0.85},
    )


def calibration_figure(budget: TurntableBudget, *, n: int = 101) -> Figure | None:
    """Rate-sensing errors over orientation errors, with ωm and the requirement box (Figs. 4–5).

    Left: Δωx over (Δψ, Δθ) at Δγ = 0; right: Δωy over (Δθ, Δγ) at Δψ = 0 (°/h, axes in degrees).
    The contour Δω = ωm, rotacal's requirement box (largest volume, all corners within ωm), the
    equal limit and (when it differs) the requirement the allocation used are drawn. ``None``
    when ``budget._requirement`` is None (a table not of the seed's geometry).

    Parameters
    ----------
    budget : TurntableBudget
        The budget (its ``_requirement`` and table's ``[calibration]`` settings are used).
    n : int
        Grid points per axis.

    Returns
    -------
    Figure or None

    References
    ----------
    Seed 001, eqs. (7)–(16), Figures 4 and 5.
    """
    from rotacal.turntable.calibration import rate_error_surfaces

    req = budget._requirement
    if req is None or budget._plan_deg is None:
        return None
    p1, p2, lat = _plan(budget)
    wm = float(req.required_deg_h)
    box = {c: math.degrees(float(req.limits_rad[c])) for c in COMPONENTS}
    eq = float(req.equal_limit_deg)
    stated = {c: budget.requirement_arcmin[c] / 60.0 for c in COMPONENTS}
    lim_deg = 1.3 * max(max(box.values()), max(stated.values()), eq)
    lim_rad = min(math.radians(lim_deg), 0.1)
    s = rate_error_surfaces(lim_rad, n=n, phi1_deg=p1, phi2_deg=p2, latitude_deg=lat)
    # widen once if the ωm contour reaches the edge (room for the contour and its label)
    g = np.asarray(s["grid_rad"])
    inside = np.concatenate(
        [
            np.abs(g[np.any(np.asarray(s[a][k]) <= wm, axis=ax)])
            for a, k in (("x", "psi_theta"), ("y", "theta_gamma"))
            for ax in (0, 1)
        ]
    )
    extent = float(np.max(inside)) if inside.size else 0.0
    if extent > 0.8 * lim_rad and lim_rad < 0.1:
        lim_rad = min(1.3 * extent, 0.1)
        s = rate_error_surfaces(lim_rad, n=n, phi1_deg=p1, phi2_deg=p2, latitude_deg=lat)
    g = np.degrees(np.asarray(s["grid_rad"]))
    panels = [
        ("x", "psi_theta", ("psi", "theta")),
        ("y", "theta_gamma", ("theta", "gamma")),
    ]
    zmax = max(float(np.max(s[a][k])) for a, k, _ in panels)
    levels = MaxNLocator(nbins=12).tick_values(0.0, zmax)
    fig, axes = plt.subplots(1, 2, figsize=(11.5, 5.0), constrained_layout=True)
    show_stated = any(abs(stated[c] - box[c]) > 1e-9 * box[c] for c in COMPONENTS)
    cs = None
    for ax, (axis, key, (cx, cy)) in zip(axes, panels, strict=True):
        z = np.asarray(s[axis][key]).T  # first index is the first-named component → x axis
        cs = ax.contourf(g, g, z, levels=levels, cmap="Blues")
        line = ax.contour(g, g, z, levels=[wm], colors=_REQ, linewidths=1.6)
        _label_top(ax, line, f"Δω{axis} = ωm = {wm:g} °/h")
        _box(ax, box[cx], box[cy], ec="black", lw=1.8)
        _box(ax, eq, eq, ec="black", lw=1.0, ls=":")
        if show_stated:
            _box(ax, stated[cx], stated[cy], ec="#666", lw=1.2, ls="--")
        ax.set_xlabel(f"{COMP_SYMBOL[cx]} (°)")
        ax.set_ylabel(f"{COMP_SYMBOL[cy]} (°)")
        other = next(c for c in COMPONENTS if c not in (cx, cy))
        ax.set_title(
            f"Δω{axis} over ({COMP_SYMBOL[cx]}, {COMP_SYMBOL[cy]}), {COMP_SYMBOL[other]} = 0",
            fontsize=10,
        )
        ax.set_aspect("equal")
    assert cs is not None
    fig.colorbar(cs, ax=axes, shrink=0.85, label="rate-sensing error Δω (°/h)")
    handles = [
        Line2D([], [], color=_REQ, lw=1.6, label=f"Δω = ωm = {wm:g} °/h"),
        Line2D([], [], color="black", lw=1.8, label="rotacal's requirement box"),
        Line2D([], [], color="black", lw=1.0, ls=":", label="equal limit"),
    ]
    if show_stated:
        handles.append(
            Line2D([], [], color="#666", lw=1.2, ls="--", label="the requirement allocated to")
        )
    fig.legend(
        handles=handles, loc="outside lower center", ncols=len(handles), fontsize=8.5, frameon=False
    )
    return figure_from_matplotlib(
        fig,
        "What an orientation error does to the gyro calibration",
        f"Rate-sensing error of a multiposition drift calibration ({req.positions} positions, "
        f"latitude {lat:g}°, Table 1 coefficients, method {req.method!r}) when the table tilts the "
        "gyro by a constant orientation error (seed 001, eqs. (7)–(14), Figure 4). Red: the "
        f"accuracy ωm = {wm:g} °/h; inside it the calibration is good enough. Solid box: rotacal's "
        "requirement (the box of largest volume whose every corner (±Iψ, ±Iθ, ±Iγ) stays within "
        "ωm, Figure 5 and eq. (15)); dotted: equal limits (the form of eq. (16))"
        + ("; dashed: the requirement the allocation used" if show_stated else "")
        + ". The boxes' corners are checked with the third component "
        "at its limit too, so they sit inside the red line drawn at zero third component."
        + _allocated_box_note(budget),
    )


def _allocated_box_note(budget: TurntableBudget) -> str:
    """Why the requirement the allocation used differs from the box (for the figure's caption)."""
    derivation = budget.derivation or {}
    if derivation.get("derivation") == "calibration-check":
        return (
            f" The allocation's requirement is the box × {derivation['scale_of_box']:.4f}: a real "
            "table's orientation error varies from position to position (eq. (26)), so the box's "
            "corner is never reached at every position at once; every table within the allocated "
            "bounds keeps the calibration within ωm (worst table below)."
        )
    if derivation.get("derivation") == "earth-rate-only":
        return (
            " The allocation's requirement is the Earth-rate reading alone (seed 001's eq. (16)): "
            "it ignores what the drift fit does with gravity and lies outside ωm."
        )
    return ""


def calibration_draws_figure(budget: TurntableBudget) -> Figure | None:
    """Histograms of Δωx, Δωy of calibrations run on tables drawn within the allocation.

    Returns ``None`` when the budget has no such draws (a table not of the seed's geometry).

    References
    ----------
    Seed 001, eqs. (7)–(14) with the position-dependent orientation error of eq. (23).
    """
    draws = budget._calibration_draws
    if draws is None:
        return None
    req = budget._requirement
    wm = float(req.required_deg_h) if req is not None else None
    fig, axes = plt.subplots(1, 2, figsize=(11.0, 3.4), sharey=True)
    hi = max(float(np.max(draws[a])) for a in ("x", "y"))
    if wm is not None:
        hi = max(hi, wm)
    bins = np.linspace(0.0, 1.05 * hi, 61)
    for ax, axis in zip(axes, ("x", "y"), strict=True):
        v = np.asarray(draws[axis], dtype=float)
        ax.hist(v, bins=bins, color="#1f5f99", alpha=0.85)
        title = f"Δω{axis}: max {np.max(v):.4f} °/h"
        if wm is not None:
            ax.axvline(wm, color=_REQ, ls="--", lw=1.4, label=f"ωm = {wm:g} °/h")
            ax.legend(loc="upper right", fontsize=8, frameon=False)
            title += f", {np.mean(v > wm) * 100:.1f} % above ωm"
        ax.set_title(title, fontsize=9.5)
        ax.set_xlabel(f"Δω{axis} (°/h)")
        _style(ax)
    axes[0].set_ylabel("tables drawn")
    fig.tight_layout()
    cal = budget.calibration or {}
    return figure_from_matplotlib(
        fig,
        "Calibrations on tables built to the allocation",
        f"{len(draws['x']):,} tables drawn with every error uniform between its lower and "
        "allocated upper bound (random signs); on each, the multiposition calibration "
        f"({cal.get('plan', '?')} positions, latitude {cal.get('latitude_deg', '?')}°) sees the "
        "orientation error of every position from the full model (eq. (23)), and the rate-sensing "
        "errors of eqs. (12)–(14) follow."
        + (f" Red dashed: ωm = {wm:g} °/h." if wm is not None else ""),
    )


# ----------------------------------------------------------------------------------------------
# 6. The calibration verdict's remedy
# ----------------------------------------------------------------------------------------------


def _remedy(budget: TurntableBudget, wm: float) -> str:
    """What to do when tables built to the allocation fail the calibration accuracy."""
    if (budget.derivation or {}).get("derivation") == "earth-rate-only":
        return (
            "the Earth-rate reading of eq. (16) leaves out what the drift fit does with gravity. "
            'Derive the requirement with derivation = "calibration-check" (the default) and '
            "run the budget again."
        )
    return (
        "the stated orientation requirement is looser than this calibration needs. Give "
        f'[requirement] calibration_deg_h = {wm:g} instead (derivation "calibration-check") and '
        "run the budget again."
    )


# ----------------------------------------------------------------------------------------------
# The section
# ----------------------------------------------------------------------------------------------


def turntable_section(budget: TurntableBudget, title: str | None = None) -> Section:
    """The turntable's accuracy budget as one report section (seed 001, §§2.2–2.3 and §4).

    Figures: sensitivities, Monte Carlo histograms and — for a table of the seed's geometry —
    the calibration maps and the calibration draws. Tables: allocation, worst case and — for the
    seed's own error names — the side-by-side with the paper.

    Parameters
    ----------
    budget : TurntableBudget
        From :func:`rotacal.turntable.budget.turntable_budget`.
    title : str, optional
        Section title (default: "Turntable accuracy budget — <table name>").

    Returns
    -------
    Section

    References
    ----------
    Seed 001, eqs. (7)–(16), (26), (28)–(34), Lemma 1, Tables 2 and 4, Figures 4, 5, 8, 9.
    """
    reqs = budget.requirement_arcmin
    req_text = ", ".join(f"{COMP_SYMBOL[c]} ≤ {reqs[c]:.4f}′" for c in COMPONENTS)
    n_ang = len(budget._table.angular_error_names)
    n_off = len(budget.error_names) - n_ang
    mc = budget.monte_carlo
    paragraphs = [
        f"{budget.table}: {n_ang} angular error source{'s' if n_ang != 1 else ''}"
        + (f" and {n_off} offset{'s' if n_off != 1 else ''}" if n_off else "")
        + f". The instrument's orientation must stay within {req_text} "
        f"(requirement {budget.requirement_source}) at every angle of the table.",
        "Sensitivities. How much one arc-minute of each error source moves the instrument's "
        "orientation, averaged over the table's angles. An error the orientation is more "
        "sensitive to gets a tighter tolerance; an error that does not appear in a panel does not "
        "affect that component at all.",
        "Allocation. For each orientation component, the tolerances minimise the weighted cost "
        "Σ W²/χ² (W = 1/sensitivity: an error the component is less sensitive to gets a looser "
        "tolerance) while every error at its tolerance, at the worst angles, keeps that component "
        "within its requirement; an error shared by several components takes the smallest of "
        "their tolerances (seed 001, eqs. (29)–(34)), which can leave a component some margin. "
        "'Set by' names the component whose budget limits that source. "
        "The lower bounds are what manufacturing can achieve; a tolerance below them would make "
        "the table unbuildable.",
        "Worst case. Every error at its allocated bound and the worst angles: the linear bound "
        "(every term at its worst sign) is what Lemma 1 of the seed proves; the full model "
        "multiplies the error matrices of eqs. (17)–(22) over "
        + "; ".join(
            sorted({str(budget.worst_case[c].get("vertices", "")) for c in COMPONENTS} - {""})
        )
        + ". Both must stay within the requirement.",
        f"Monte Carlo. {mc['runs']:,} tables built anywhere within the tolerances, each turned to "
        "random angles, with the full model: "
        + (
            "every one stays within the requirement."
            if mc["all_within"]
            else f"{mc['outside']} exceed the requirement — the allocation is not safe."
        ),
    ]
    tables = [allocation_table(budget), worst_case_table(budget)]
    figures = [sensitivity_figure(budget), monte_carlo_figure(budget)]
    cal_fig = calibration_figure(budget)
    if cal_fig is not None and budget._requirement is not None:
        req = budget._requirement
        paragraphs.append(
            "Calibration. A tilted gyro sees slightly wrong Earth rate and gravity at every "
            "position, so the drift coefficients it is calibrated with come out wrong. For a "
            f"calibration accurate to {req.required_deg_h:g} °/h an orientation error that is the "
            f"same at every position must stay within Δψ {req.limits_deg['psi']:.4f}°, Δθ "
            f"{req.limits_deg['theta']:.4f}°, Δγ {req.limits_deg['gamma']:.4f}° (or "
            f"{req.equal_limit_deg:.4f}° on every component) for rotacal's plan of "
            f"{req.positions} positions at latitude {req.latitude_deg:g}°."
            + _allocated_box_note(budget)
        )
        figures.append(cal_fig)
        draws_fig = calibration_draws_figure(budget)
        if draws_fig is not None and budget.calibration is not None:
            mx = budget.calibration["max_rate_error_deg_h"]
            p95 = budget.calibration["p95_rate_error_deg_h"]
            wm = req.required_deg_h
            worst = budget.calibration.get("worst_table_rate_error_deg_h", {})
            # the worst table decides when it is known; the draws alone can miss it
            within = (worst["worst_deg_h"] if worst else max(mx.values())) <= wm
            worst_text = (
                f"; the worst table within the bounds reaches {worst['worst_deg_h']:.4f} °/h"
                if worst
                else ""
            )
            verdict = (
                f"all within {wm:g} °/h{worst_text}."
                if within
                else f"more than the {wm:g} °/h the calibration needs{worst_text}: "
                + _remedy(budget, wm)
            )
            paragraphs.append(
                "Tables built to the allocated tolerances and used for that calibration give rate "
                f"errors up to Δωx {mx['x']:.4f} °/h and Δωy {mx['y']:.4f} °/h (95 % of tables "
                f"below {p95['x']:.4f} and {p95['y']:.4f} °/h): {verdict}"
            )
            figures.append(draws_fig)
    t4 = table4_worst_case(budget) if is_seed_budget(budget) else None
    seed_tab = seed_comparison_table(budget, table4_worst=t4)
    if seed_tab is not None and t4 is not None:
        tables.append(seed_tab)
        paragraphs.append(
            "Reproducing seed 001. The paper's printed numbers beside rotacal's. "
            + seed_paragraph(budget, t4)
        )
    return Section(
        title=title or f"Turntable accuracy budget — {budget.table}",
        paragraphs=paragraphs,
        tables=tables,
        figures=figures,
        anchor="turntable-budget",
    )
