"""Report section and figure for the multiposition drift calibration (seed 001, eqs. 1–6)."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

from rotacal.gyro.multiposition import MultipositionResult
from rotacal.report.html import Figure, Section, Table, figure_from_matplotlib
from rotacal.report.uncertainty import budget_tables

__all__ = ["multiposition_figure", "multiposition_section"]


def _style(ax: Any) -> None:
    ax.grid(True, color="#e3e7eb", linewidth=0.7)
    ax.spines[["top", "right"]].set_visible(False)


def multiposition_figure(r: MultipositionResult) -> Figure:
    """Mean residual at each turntable position, coloured by the outer angle φ1."""
    p = r._plot
    p1 = np.asarray(p["phi1_deg"])
    p2 = np.asarray(p["phi2_deg"])
    res = np.asarray(p["mean_residual_deg_h"]) * 1e3  # mdeg/h
    resid_rows = np.asarray(r.residuals_deg_h) * 1e3
    idx = np.arange(res.size)
    fig, ax = plt.subplots(figsize=(10.0, 3.8))
    outer = np.unique(np.round(np.mod(p1, 360.0), 6))
    cmap = plt.get_cmap("viridis", max(outer.size, 2))
    color_of = {float(v): cmap(i) for i, v in enumerate(outer)}
    colors = [color_of[float(v)] for v in np.round(np.mod(p1, 360.0), 6)]
    pos_row = np.asarray(p["row_position"])
    ax.plot(pos_row, resid_rows, ".", ms=3, color="#9aa4ae", zorder=1, label="each reading")
    ax.bar(idx, res, color=colors, width=0.75, zorder=2, label="mean at the position")
    if np.isfinite(r.residual_std_deg_h):
        s = r.residual_std_deg_h * 1e3
        ax.axhspan(-s, s, color="#f2e3c6", zorder=0, label=f"±s = ±{s:.3g} mdeg/h")
    ax.axhline(0.0, color="#555", lw=0.7)
    # Label the start of each outer angle's block of positions.
    starts = [0] + [i for i in range(1, p1.size) if p1[i] != p1[i - 1]]
    if len(starts) <= 24:
        ax.set_xticks(starts)
        ax.set_xticklabels([f"φ1={p1[i]:g}°" for i in starts], rotation=0, fontsize=7.5)
    ax.set_xlim(-0.8, res.size - 0.2)
    ax.set_xlabel(
        "turntable position (in the order of the capture; φ2 steps within each φ1 block)"
        if len(starts) <= 24
        else "turntable position index"
    )
    ax.set_ylabel("residual (mdeg/h)")
    ax.legend(fontsize=8, loc="upper center", bbox_to_anchor=(0.5, -0.22), ncols=3, frameon=False)
    _style(ax)
    if p2.size <= 16:
        for i in idx:
            ax.annotate(f"{p2[i]:g}°", (i, 0), fontsize=6, ha="center", va="bottom", color="#555")
    return figure_from_matplotlib(
        fig,
        "Residuals per turntable position",
        f"Output minus Earth rate minus the fitted drift model ({r.axis} axis), in 10⁻³ °/h: bars "
        "the mean at each position (colour: outer angle φ1), dots each reading. A systematic "
        "pattern over φ1 or φ2 would show a term the model lacks or an orientation error (seed 001, "
        "§2.2).",
    )


def multiposition_section(
    r: MultipositionResult,
    title: str | None = None,
    *,
    figures: bool = True,
    truth: Mapping[str, float] | None = None,
) -> Section:
    """Coefficient table with standard uncertainties, the design's conditioning and the figure.

    ``truth`` maps coefficient names to true values (a twin's) and adds them with the errors.
    """
    cols = ["coefficient", "value", "standard uncertainty", "unit"]
    if truth is not None:
        cols += ["twin truth", "error", "error / u"]
    rows = []
    for name, value in r.drift_coefficients.items():
        u = r.drift_coefficients_u[name]
        unit = r.drift_coefficient_units[name].replace("^2", "²")
        row = [name, f"{value:+.5f}", f"{u:.2g}" if np.isfinite(u) else "—", unit]
        if truth is not None:
            t = float(truth[name])
            err = value - t
            row += [f"{t:+.5g}", f"{err:+.2g}", f"{err / u:+.2f}" if u > 0 else "—"]
        rows.append(row)
    design = Table(
        ["design", "value"],
        [
            ["axis", r.axis],
            ["distinct positions", str(r.positions)],
            ["readings (rows)", str(r.rows)],
            ["rank of A", f"{r.rank} of {len(r.drift_coefficients)}"],
            ["condition number of A", f"{r.condition_number:.3g}"],
            ["residual std s", f"{r.residual_std_deg_h:.3g} °/h"],
            ["latitude", f"{r.latitude_deg:g}°"],
            ["Earth rate (sidereal)", f"{r.earth_rate_deg_h:.8g} °/h"],
        ],
        caption="Regression design (seed 001, eqs. (4)–(6))",
    )
    return Section(
        title=title or f"Multiposition drift coefficients, {r.axis} axis",
        paragraphs=[
            "Least squares of k·i − ω on the gravity terms at each turntable position (seed 001, "
            "eqs. (1)–(6)). Each coefficient's uncertainty budget holds the fit's residual "
            "variance s²·(AᵀA)⁻¹ (Type A) and, where the lab states them, the latitude and the "
            "turntable's orientation error (seed 001 eqs. (7)–(11)), with sensitivities from the "
            "derivative of the least-squares solution.",
            *r.notes,
        ],
        tables=[
            Table(cols, rows, caption="Drift coefficients"),
            design,
            *budget_tables(r._budgets),
        ],
        figures=[multiposition_figure(r)] if figures else [],
        anchor=f"multiposition-{r.axis}",
    )
