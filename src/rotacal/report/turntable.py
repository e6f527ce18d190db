"""Report section for a turntable's accuracy budget (the GyroWheel study, §§2.2–2.3 and §4).

:func:`turntable_section` renders a :class:`~rotacal.turntable.budget.TurntableBudget`: the
results a lab signs first (:mod:`rotacal.report.turntable_results`: the Monte Carlo and
calibration checks with their coverage intervals), then the sensitivities of the orientation error
to each error source (the study's Figure 8), the allocated upper bounds (Table 4), the worst case
over all angles (Lemma 1), the Monte Carlo check with the full model (Figure 9), what an
orientation error does to a multiposition gyro calibration (Figures 4–5) and, for the study's own
table, a side-by-side of the paper's numbers and rotacal's, folded away
(:mod:`rotacal.report.turntable_seed001`).

References
----------
The GyroWheel study (Int. J. Aerospace Eng., article 6524782): eqs. (7)–(16), (26), (28)–(34),
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

from rotacal.numbers import fixed
from rotacal.references import cite
from rotacal.report.html import Figure, Section, Table, figure_from_matplotlib
from rotacal.report.turntable_common import COMP_SYMBOL, angle_symbol, is_seed_budget, symbol
from rotacal.report.turntable_results import RESULT_REFERENCES, turntable_results
from rotacal.report.turntable_seed001 import (
    seed_comparison_table,
    seed_paragraph,
    table4_worst_case,
)
from rotacal.report.wording import readable
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
    "table_name",
    "turntable_section",
    "worst_case_table",
]

#: How the text cites the paper the method comes from.
_PAPER = cite("gyrowheel")
#: How the text names it in running words ("the GyroWheel study's Table 4").
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
    """Averaged sensitivities of Δψ, Δθ, Δγ to every angular error (the study's Figure 8).

    References
    ----------
    The GyroWheel study, eq. (28) and Figure 8.
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
        ax.set_title(COMP_SYMBOL[comp], fontsize=10)
        ax.set_xlabel("mean |∂Δ/∂χ| (rad/rad)")
        _style(ax)
        ax.grid(False, axis="y")
    axes[0].set_yticks(y)
    axes[0].set_yticklabels(labels, fontsize=8.5)
    fig.tight_layout()
    step, endpoint = budget._table.sensitivity_grid
    grid = (
        f"every {fixed(step)}° from 0° to 360°, both ends"
        if endpoint
        else f"every {fixed(step)}° over a turn"
    )
    return figure_from_matplotlib(
        fig,
        "Sensitivity of the orientation error to each error source",
        f"Mean |∂Δ/∂χᵢ| of the linearised model over the table's angles ({grid}; {_PAPER}, "
        "eq. (28)); a longer bar needs a tighter tolerance. Offsets do not turn the instrument.",
    )


# ----------------------------------------------------------------------------------------------
# 2. Allocation (Table 4)
# ----------------------------------------------------------------------------------------------


def allocation_table(budget: TurntableBudget) -> Table:
    """Lower and allocated upper bounds per error source, the binding component, Table 4.

    References
    ----------
    The GyroWheel study, eqs. (29)–(34) and Table 4.
    """
    seed = is_seed_budget(budget)
    cols = ["error source", "symbol", "ISO 230-7", "lower bound (′)", "allocated upper bound (′)"]
    cols.append("set by")
    if seed:
        cols += ["the study's Table 4 (′)", "rotacal / Table 4"]
    specs = _specs(budget)
    rows = []
    for name in budget.error_names:
        ub = budget.upper_bounds_arcmin.get(name)
        spec = specs.get(name)
        if ub is None:
            lower = spec.lower if spec is not None else 0.0
            row = [
                budget.labels.get(name, "") or symbol(name),
                symbol(name),
                _iso(budget, name),
                f"{fixed(lower * 1e3)} mm",
                "no effect on orientation",
                "—",
            ]
            if seed:
                row += ["—", "—"]
        else:
            binding = budget.binding.get(name, "")
            row = [
                budget.labels.get(name, "") or symbol(name),
                symbol(name),
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
        caption="Tolerances allocated to the error sources",
        note=f"Allocation by {_PAPER}, eqs. (29)–(34). 'Set by' names the orientation component "
        "whose requirement limits the source; the lower bound is what manufacturing achieves."
        + (" Table 4 is the study's printed allocation, for its own requirement." if seed else ""),
    )


# ----------------------------------------------------------------------------------------------
# 3. Worst case (Lemma 1)
# ----------------------------------------------------------------------------------------------


def _angles_text(angles: Any, names: tuple[str, ...]) -> str:
    if angles is None:
        return "—"
    if isinstance(angles, Mapping):
        return ", ".join(f"{angle_symbol(k)} = {float(v):.1f}°" for k, v in angles.items())
    arr = np.atleast_1d(np.asarray(angles, dtype=float))
    return ", ".join(f"{angle_symbol(n)} = {v:.1f}°" for n, v in zip(names, arr, strict=False))


def worst_case_table(budget: TurntableBudget) -> Table:
    """Per component: requirement, Lemma-1 linear bound, full model worst case, where, within.

    The last column, the largest error among the Monte Carlo draws, is a diagnostic: it grows with
    the number of draws and stays below the worst case.

    References
    ----------
    The GyroWheel study, Lemma 1 (eqs. (35)–(38)) and eqs. (17)–(25).
    """
    names = tuple(budget._table.angle_names)
    drawn = budget.monte_carlo["max_abs_arcmin"]
    rows = []
    for comp in COMPONENTS:
        wc = budget.worst_case.get(comp)
        req = budget.requirement_arcmin[comp]
        if not wc:
            rows.append([COMP_SYMBOL[comp], _f4(req), "—", "—", "—", "—", _f4(drawn[comp])])
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
                _f4(drawn[comp]),
            ]
        )
    runs = int(budget.monte_carlo["runs"])
    return Table(
        [
            "component",
            "requirement (′)",
            "linear bound (′)",
            "full model (′)",
            "worst at",
            "within",
            f"largest of {runs:,} draws (′)",
        ],
        rows,
        caption="Worst case over all angles, every error at its allocated bound",
        note=f"Design values of the model, not measurements: the linear bound is what Lemma 1 of "
        f"{_PAPER} guarantees, the full model multiplies the error matrices of eqs. (17)–(22). "
        "The largest error among the Monte Carlo draws is a diagnostic; it grows with the number "
        "of draws and stays below the worst case.",
    )


# ----------------------------------------------------------------------------------------------
# 4. Monte Carlo (Figure 9)
# ----------------------------------------------------------------------------------------------


def monte_carlo_figure(budget: TurntableBudget) -> Figure:
    """Histograms of Δψ, Δθ, Δγ over the Monte Carlo draws, with ±requirement (Figure 9).

    References
    ----------
    The GyroWheel study, §4.3 and Figure 9.
    """
    mc = budget._monte_carlo
    # counts in thousands when large: plain tick labels, no "1e4" offset on the axis
    most = max(max(mc.histograms[c]["counts"]) for c in COMPONENTS)
    per_unit, y_label = (
        (1000.0, "draws per bin (thousands)") if most >= 10_000 else (1.0, "draws per bin")
    )
    fig, axes = plt.subplots(1, 3, figsize=(12.0, 3.8), constrained_layout=True)
    for ax, comp in zip(axes, COMPONENTS, strict=True):
        h = mc.histograms[comp]
        edges = np.asarray(h["edges_rad"], dtype=float) * ARCMIN_PER_RAD
        counts = np.asarray(h["counts"], dtype=float) / per_unit
        req = budget.requirement_arcmin[comp]
        ax.stairs(counts, edges, fill=True, color=_COMP_COLOR[comp], alpha=0.8)
        for sign in (-1.0, 1.0):
            ax.axvline(sign * req, color=_REQ, ls="--", lw=1.3)
        ax.set_xlim(-1.2 * req, 1.2 * req)
        ax.set_title(
            f"{COMP_SYMBOL[comp]}: largest |Δ| {mc.max_abs_arcmin[comp]:.4f}′ of {req:.4f}′",
            fontsize=9.5,
        )
        ax.set_xlabel(f"{COMP_SYMBOL[comp]} (arcmin)")
        _style(ax)
    axes[0].set_ylabel(y_label)
    fig.legend(
        handles=[Line2D([], [], color=_REQ, ls="--", lw=1.3, label="requirement ±I")],
        loc="outside lower center",
        fontsize=8.5,
        frameon=False,
    )
    within = "all within the requirement" if mc.all_within else f"{mc.outside:,} outside"
    return figure_from_matplotlib(
        fig,
        "Monte Carlo check with the full model",
        f"{mc.runs:,} tables drawn within their tolerances at random angles (full model, "
        f"{_PAPER}, eqs. (17)–(25)): {within}. Red dashed: the requirement ±I.",
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
    when ``budget._requirement`` is None (a table not of the study's geometry).

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
    The GyroWheel study, eqs. (7)–(16), Figures 4 and 5.
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
        _label_top(ax, line, f"Δω{axis} = ωm = {fixed(wm)} °/h")
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
        Line2D([], [], color=_REQ, lw=1.6, label=f"Δω = ωm = {fixed(wm)} °/h"),
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
        f"Rate-sensing error of a {req.positions}-position drift calibration at latitude "
        f"{fixed(lat)}° under a constant orientation error ({_PAPER}, eqs. (7)–(14), Figures 4–5)."
        " The lines and boxes are named in the legend.",
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
            f" The allocation's requirement is the Earth-rate reading alone ({_PAPER}, eq. (16)): "
            "it ignores what the drift fit does with gravity and lies outside ωm."
        )
    return ""


def calibration_draws_figure(budget: TurntableBudget) -> Figure | None:
    """Histograms of Δωx, Δωy of calibrations run on tables drawn within the allocation.

    Returns ``None`` when the budget has no such draws (a table not of the study's geometry).

    References
    ----------
    The GyroWheel study, eqs. (7)–(14) with the position-dependent orientation error of eq. (23).
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
            ax.axvline(wm, color=_REQ, ls="--", lw=1.4, label=f"ωm = {fixed(wm)} °/h")
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
        f"Rate-sensing error of the {cal.get('plan', '')} position calibration on each of "
        f"{len(draws['x']):,} tables drawn within the allocation (eqs. (12)–(14), (23))."
        + (f" Red dashed: ωm = {fixed(wm)} °/h." if wm is not None else ""),
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
        f'[requirement] calibration_deg_h = {fixed(wm)} instead (derivation "calibration-check") and '
        "run the budget again."
    )


# ----------------------------------------------------------------------------------------------
# The section
# ----------------------------------------------------------------------------------------------


def _cited(text: str) -> str:
    """``text`` (a table's name, the requirement's source: JSON text that may name a paper by the
    project's file name) as a reader reads it (:func:`~rotacal.report.wording.readable`)."""
    return readable(text)


def table_name(budget: TurntableBudget) -> str:
    """The table's name as a report titles it (the paper cited by name, not by our file's)."""
    return _cited(budget.table)


def _requirement_source(budget: TurntableBudget) -> str:
    """The budget's note on where the requirement came from, citing the paper by name."""
    return _cited(budget.requirement_source)


def _calibration_paragraphs(budget: TurntableBudget) -> list[str]:
    """What the calibration map and the calibration draws show, and the verdict."""
    req = budget._requirement
    cal = budget.calibration
    if req is None:
        return []
    wm = req.required_deg_h
    out = [
        "Calibration. A tilted gyro sees slightly wrong Earth rate and gravity at every "
        "position, so the drift coefficients it is calibrated with come out wrong. For a "
        f"calibration accurate to {fixed(wm)} °/h an orientation error that is the same at every "
        f"position must stay within Δψ {req.limits_deg['psi']:.4f}°, Δθ "
        f"{req.limits_deg['theta']:.4f}°, Δγ {req.limits_deg['gamma']:.4f}° (the box of largest "
        "volume whose every corner keeps the rate-sensing error within ωm, eq. (15) and Figure 5; "
        f"or {req.equal_limit_deg:.4f}° on every component, the form of eq. (16)) for rotacal's "
        f"plan of {req.positions} positions at latitude {fixed(req.latitude_deg)}° (drift "
        f"coefficients of Table 1, method '{req.method}'). The map draws the third component at "
        "zero; the boxes' corners are checked with it at its limit too, so they sit inside the "
        "red line." + _allocated_box_note(budget)
    ]
    if cal is None or budget._calibration_draws is None:
        return out
    mx = cal["max_rate_error_deg_h"]
    worst = cal.get("worst_table_rate_error_deg_h", {})
    # the worst table decides when it is known; the draws alone can miss it
    within = (worst["worst_deg_h"] if worst else max(mx.values())) <= wm
    worst_text = (
        f"; the worst table within the bounds reaches {worst['worst_deg_h']:.4f} °/h"
        if worst
        else ""
    )
    verdict = (
        f"all within {fixed(wm)} °/h{worst_text}."
        if within
        else f"more than the {fixed(wm)} °/h the calibration needs{worst_text}: "
        + _remedy(budget, wm)
    )
    out.append(
        f"Tables built to the allocated tolerances ({cal['runs']:,} drawn, the orientation error "
        "of every test position from the full model) give calibrations with rate-sensing errors up "
        f"to Δωx {mx['x']:.4f} °/h and Δωy {mx['y']:.4f} °/h: {verdict} The summary states the "
        "error 95 % of such calibrations stay within, with its coverage interval."
    )
    return out


def turntable_section(budget: TurntableBudget, title: str | None = None) -> Section:
    """The turntable's accuracy budget as one report section (the GyroWheel study, §§2.2–2.3, §4).

    Results (the summary): the Monte Carlo and calibration checks with their coverage intervals
    (:func:`rotacal.report.turntable_results.turntable_results`). Figures: sensitivities, Monte
    Carlo histograms and — for a table of the study's geometry — the calibration map and the
    calibration draws. Tables: allocation and worst case; folded: for the study's own error
    names, the side-by-side with the paper.

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
    The GyroWheel study, eqs. (7)–(16), (26), (28)–(34), Lemma 1, Tables 2 and 4, Figures 4, 5,
    8, 9.
    """
    reqs = budget.requirement_arcmin
    req_text = ", ".join(f"{COMP_SYMBOL[c]} ≤ {reqs[c]:.4f}′" for c in COMPONENTS)
    n_ang = len(budget._table.angular_error_names)
    n_off = len(budget.error_names) - n_ang
    mc = budget.monte_carlo
    paragraphs = [
        f"{_cited(budget.table)}: {n_ang} angular error source{'s' if n_ang != 1 else ''}"
        + (f" and {n_off} offset{'s' if n_off != 1 else ''}" if n_off else "")
        + f". The instrument's orientation must stay within {req_text} "
        f"(requirement {_requirement_source(budget)}) at every angle of the table. The method is "
        f"that of {_PAPER}: sensitivities, allocation of tolerances, worst case and a Monte Carlo "
        "check with the full model.",
        "Sensitivities. How much one arc-minute of each error source moves the instrument's "
        "orientation, averaged over the table's angles. An error the orientation is more "
        "sensitive to gets a tighter tolerance; an error that does not appear in a panel does not "
        "affect that component at all.",
        "Allocation. For each orientation component, the tolerances minimise the weighted cost "
        "Σ W²/χ² (W = 1/sensitivity: an error the component is less sensitive to gets a looser "
        "tolerance) while every error at its tolerance, at the worst angles, keeps that component "
        "within its requirement; an error shared by several components takes the smallest of "
        "their tolerances (eqs. (29)–(34)), which can leave a component some margin. "
        "The lower bounds are what manufacturing can achieve; a tolerance below them would make "
        "the table unbuildable.",
        "Worst case. Every error at its allocated bound and the worst angles: the linear bound "
        "(every term at its worst sign) is what Lemma 1 proves; the full model "
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
            else f"{mc['outside']:,} exceed the requirement — the allocation is not safe."
        )
        + " The summary states the orientation error 99.9 % of such tables stay within (its "
        f"interval from the order statistics of the draws, {cite('david2003')}) and the fraction "
        f"outside the requirement (exact binomial interval, {cite('clopper1934')}); a verdict is "
        "given only when the whole interval lies on one side of the limit.",
    ]
    tables = [allocation_table(budget), worst_case_table(budget)]
    figures = [sensitivity_figure(budget), monte_carlo_figure(budget)]
    cal_fig = calibration_figure(budget)
    if cal_fig is not None:
        paragraphs += _calibration_paragraphs(budget)
        figures.append(cal_fig)
        draws_fig = calibration_draws_figure(budget)
        if draws_fig is not None:
            figures.append(draws_fig)
    details = []
    t4 = table4_worst_case(budget) if is_seed_budget(budget) else None
    seed_tab = seed_comparison_table(budget, table4_worst=t4)
    if seed_tab is not None and t4 is not None:
        seed_tab.note = seed_paragraph(budget, t4)
        details.append(seed_tab)
        paragraphs.append(
            f"Reproducing {_PAPER}: the paper's printed numbers beside rotacal's are in the "
            "folded table below, with what they rest on."
        )
    return Section(
        title=title or f"Turntable accuracy budget — {_cited(budget.table)}",
        paragraphs=paragraphs,
        tables=tables,
        figures=figures,
        anchor="turntable-budget",
        results=turntable_results(budget),
        details=details,
        references=["gyrowheel", "iso230_7", *RESULT_REFERENCES],
    )
