"""Report section and figure for the multiposition drift calibration (GyroWheel study, eqs. 1–6)."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

from rotacal.gyro.multiposition import MultipositionResult
from rotacal.numbers import fixed
from rotacal.references import cite
from rotacal.report.html import Figure, Section, Table, figure_from_matplotlib
from rotacal.report.uncertainty import budget_details, budget_results
from rotacal.report.wording import (
    diagnostics_table,
    paragraph,
    readable_rows,
    readable_tables,
)

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
        ax.axhspan(-s, s, color="#f2e3c6", zorder=0, label=f"±s = ±{fixed(s, 3)} mdeg/h")
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
        f"Output − Earth rate − drift model ({r.axis} axis), 10⁻³ °/h: bars the mean per position "
        "(colour: φ1), dots each reading; a pattern shows a missing term or an orientation error.",
    )


def multiposition_section(
    r: MultipositionResult,
    title: str | None = None,
    *,
    figures: bool = True,
    truth: Mapping[str, float] | None = None,
) -> Section:
    """Drift coefficients with U in the summary, the design's conditioning, the figure, the budgets.

    ``truth`` maps coefficient names to true values (a twin's) and adds them with the errors.
    """
    results = readable_rows(
        budget_results(
            r._budgets,
            names={
                f"drift_coefficients.{name}": f"drift coefficient {name}"
                for name in r.drift_coefficients
            },
        )
    )
    tables = []
    if truth is not None:
        rows = []
        for name, value in r.drift_coefficients.items():
            u = r.drift_coefficients_u[name]
            t = float(truth[name])
            err = value - t
            rows.append(
                [
                    name,
                    fixed(value, 5),
                    fixed(t, 5),
                    fixed(err, 2),
                    fixed(err / u, 3) if u > 0 else "—",
                ]
            )
        tables.append(
            Table(
                ["coefficient", "measured", "twin truth", "error", "error / u"],
                rows,
                caption="Against the twin's truth",
            )
        )
    tables.append(
        diagnostics_table(
            [
                ["axis", r.axis],
                ["distinct positions", str(r.positions)],
                ["readings (rows)", str(r.rows)],
                ["rank of A", f"{r.rank} of {len(r.drift_coefficients)}"],
                ["condition number of A", fixed(r.condition_number, 3)],
                ["residual standard deviation s", f"{fixed(r.residual_std_deg_h, 3)} °/h"],
                ["latitude", f"{fixed(r.latitude_deg)}°"],
                ["Earth rate (sidereal)", f"{fixed(r.earth_rate_deg_h, 8)} °/h"],
            ],
            f"regression design ({cite('gyrowheel')}, eqs. 4–6)",
        )
    )
    return Section(
        title=title or f"Multiposition drift coefficients, {r.axis} axis",
        paragraphs=[
            f"Least squares of k·i − ω on the gravity terms at each turntable position "
            f"({cite('gyrowheel')}, eqs. 1–6). Each coefficient's uncertainty budget holds the "
            "fit's residual variance s²·(AᵀA)⁻¹ (Type A) and, where the lab states them, the "
            "latitude and the turntable's orientation error (eqs. 7–11), with sensitivities from "
            "the derivative of the least-squares solution.",
            *(paragraph(n) for n in r.notes),
        ],
        tables=tables,
        figures=[multiposition_figure(r)] if figures else [],
        anchor=f"multiposition-{r.axis}",
        results=results,
        details=readable_tables(budget_details(r._budgets)),
        references=["gyrowheel", "gum"],
    )
