"""Report section and figure of a small-step test: threshold and resolution (IEEE Std 528 / 1431)."""

from __future__ import annotations

from typing import Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

from rotacal.gyro.threshold import K_RECTANGULAR_95, SmallStepResult
from rotacal.numbers import fixed
from rotacal.report.html import Figure, ResultRow, Section, Table, figure_from_matplotlib
from rotacal.report.uncertainty import result_row
from rotacal.report.wording import paragraph

__all__ = ["small_step_figure", "small_step_plot", "small_step_section", "standard_u_row"]

_C = {"met": "#1f5f99", "not": "#b22222", "band": "#f2e3c6", "grid": "#e3e7eb"}


def standard_u_row(
    quantity: str, value: float | None, u: float | None, unit: str, note: str = "", k: float = 2.0
) -> ResultRow:
    """A result row from a value and its standard uncertainty: U = k·u, p ≈ 95 % (k = 2 for a
    normal distribution, 1.65 for a rectangular one)."""
    if value is None or u is None or not np.isfinite(u):
        return result_row(quantity, value, unit, note=note or "no uncertainty")
    return result_row(quantity, value, unit, U=k * u, k=k, p=0.95, note=note)


def small_step_plot(r: SmallStepResult) -> Any:
    """The matplotlib figure of :func:`small_step_figure` (also drawn for the method page)."""
    fig, axes = plt.subplots(1, 2, figsize=(10.0, 4.2), sharey=True)
    for ax, kind in zip(axes, ("threshold", "resolution"), strict=True):
        steps = [s for s in r.steps if s.kind == kind]
        bracket = getattr(r, f"{kind}_bracket_deg_s")
        if bracket is not None:
            lo, hi = bracket
            ax.axvspan(max(lo, 1e-12), hi, color=_C["band"], zorder=0, label=f"{kind} lies here")
        if steps:
            x = np.array([s.input_deg_s for s in steps])
            y = np.array([s.ratio for s in steps])
            u = np.array([s.ratio_u for s in steps])
            met = y >= r.criterion
            for mask, colour, label in ((met, _C["met"], "≥ 50 %"), (~met, _C["not"], "< 50 %")):
                if mask.any():
                    ax.errorbar(
                        x[mask],
                        y[mask],
                        yerr=u[mask],
                        fmt="o",
                        ms=4,
                        capsize=2,
                        color=colour,
                        label=f"steps {label} (± u)",
                    )
            ax.set_xscale("log")
        ax.axhline(r.criterion, color="#555", ls="--", lw=1.0, label="50 % of expected")
        ax.axhline(1.0, color="#999", lw=0.7)
        ax.set_xlabel(
            "input from rest |Ω| (°/s)" if kind == "threshold" else "input change |ΔΩ| (°/s)"
        )
        ax.set_title(kind, fontsize=10)
        ax.grid(True, color=_C["grid"], linewidth=0.7)
        ax.spines[["top", "right"]].set_visible(False)
        ax.legend(fontsize=7, loc="lower right", frameon=False)
    axes[0].set_ylabel("output change / (S·input change)")
    fig.tight_layout()
    return fig


def small_step_figure(r: SmallStepResult) -> Figure:
    """Ratio of each step's output change to the expected one, against its input, per item."""
    return figure_from_matplotlib(
        small_step_plot(r),
        "Output change of each step against its input",
        "Each point is one step between dwells: its output change over what the scale factor "
        "predicts (1: the gyro follows; 0: it does not). Shaded: the interval in which the "
        "threshold (left) and the resolution (right) lie (IEEE Std 528-2001 definitions).",
    )


def small_step_section(r: SmallStepResult, title: str | None = None) -> Section:
    """Results with U (k = 2), the levels' table and the figure."""
    results = [
        standard_u_row(
            "threshold",
            r.threshold_deg_s,
            r.threshold_deg_s_u,
            "°/s",
            note="middle of its bracket, rectangular u",
            k=K_RECTANGULAR_95,
        ),
        standard_u_row(
            "resolution (small-step test)",
            r.resolution_deg_s,
            r.resolution_deg_s_u,
            "°/s",
            note="middle of its bracket, rectangular u",
            k=K_RECTANGULAR_95,
        ),
    ]
    own = r.output_resolution
    rows: list[list[str]] = [
        ["scale factor used", f"{fixed(r.scale_factor, 8)} ({r.scale_factor_source})"],
        ["dwells / steps", f"{r.dwells} / {len(r.steps)}"],
    ]
    for name in ("threshold", "resolution"):
        b = getattr(r, f"{name}_bracket_deg_s")
        rows.append([f"{name} bracket", "—" if b is None else f"({b[0]:.4g}, {b[1]:.4g}] °/s"])
    if own is not None:
        rows.append(["one reading resolves (quantum or noise)", own.basis])
    paragraphs: list[Any] = [
        "The table stepped the rate by small increments around rest (threshold) and around "
        "operating rates (resolution). A step is met when its output change reaches 50 % of "
        "what the scale factor predicts; the threshold (resolution) is the smallest input "
        "(input change) from which every larger one is met, stated as the middle of the "
        "interval between the largest failing and that level (IEEE Std 528-2001, IEEE Std "
        "1431-2004).",
        *(paragraph(n) for n in r.notes),
    ]
    return Section(
        title=title or "Gyro threshold and resolution (small-step test)",
        paragraphs=paragraphs,
        tables=[Table(["quantity", "value"], rows, caption="Test and diagnostics")],
        figures=[small_step_figure(r)],
        anchor="gyro-steps",
        results=results,
        references=["ieee1431", "gum"],
    )
