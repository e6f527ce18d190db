"""Report section and figures of a turntable identification (GyroWheel study, eqs. 17–26)."""

from __future__ import annotations

from typing import Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

from rotacal.numbers import fixed
from rotacal.references import cite
from rotacal.report.html import Figure, ResultRow, Section, Table, figure_from_matplotlib
from rotacal.report.wording import diagnostics_table, paragraph
from rotacal.turntable.identify import TurntableIdentification

__all__ = ["estimates_figure", "identify_section", "residuals_figure"]

_COLOURS = {"psi": "#1f6fb2", "theta": "#c2571a", "gamma": "#2e8b57"}
_SYMBOLS = {"psi": "Δψ", "theta": "Δθ", "gamma": "Δγ"}


def _style(ax: Any) -> None:
    ax.grid(True, color="#e3e7eb", linewidth=0.7)
    ax.spines[["top", "right"]].set_visible(False)


def residuals_figure(r: TurntableIdentification) -> Figure:
    """Residual of each component at each position, with the band ±s."""
    fig, ax = plt.subplots(figsize=(10.0, 3.6))
    idx = np.arange(r.positions)
    for k, (c, values) in enumerate(r.residuals_arcsec.items()):
        ax.plot(idx + (k - 1) * 0.2, values, "o", ms=3.5, color=_COLOURS[c], label=_SYMBOLS[c])
    s = r.s_arcsec
    ax.axhspan(-s, s, color="#f2e3c6", zorder=0, label=f"±s = ±{fixed(s, 3)} arcsec")
    ax.axhline(0.0, color="#555", lw=0.7)
    ax.set_xlabel("position (in the order of the capture)")
    ax.set_ylabel("measured − model (arcsec)")
    ax.set_xlim(-0.8, r.positions - 0.2)
    ax.legend(fontsize=8, loc="upper center", bbox_to_anchor=(0.5, -0.2), ncols=4, frameon=False)
    _style(ax)
    fig.tight_layout()
    return figure_from_matplotlib(
        fig,
        "Residuals per position",
        "Measured orientation error minus the identified model at each position (arcsec); a "
        "pattern over the positions shows an error the model lacks (e.g. a wobble that varies "
        "with the angle).",
    )


def estimates_figure(r: TurntableIdentification) -> Figure:
    """Each separable combination ± U, with the allocation's bound for it (when given)."""
    combos = list(r.combinations)
    bounds: dict[str, Any] = {}
    if r.allocation is not None:
        bounds = {e["name"]: e for e in r.allocation["combinations"]}
    fig, ax = plt.subplots(figsize=(8.0, 0.55 * len(combos) + 1.4))
    ys = np.arange(len(combos))[::-1]
    for y, combo in zip(ys, combos, strict=True):
        entry = bounds.get(combo["name"])
        bound = entry["bound_arcsec"] if entry else None
        if bound is not None:
            ax.plot([-bound, bound], [y, y], color="#d9dee3", lw=9, solid_capstyle="butt", zorder=0)
            ax.plot([-bound, bound], [y, y], "|", color="#b03a2e", ms=14, mew=1.6, zorder=1)
        colour = {"outside": "#b03a2e", "undecided": "#c2871a"}.get(
            entry["decision"] if entry else "", "#1f6fb2"
        )
        ax.errorbar(
            combo["value_arcsec"],
            y,
            xerr=combo["U_arcsec"],
            fmt="o",
            color=colour,
            ms=5,
            capsize=4,
            zorder=2,
        )
    ax.set_yticks(ys)
    ax.set_yticklabels([c["name"] for c in combos], fontsize=8.5)
    ax.axvline(0.0, color="#555", lw=0.7)
    ax.set_xlabel(f"arcsec (estimate ± U, k = {fixed(r.k, 3)})")
    _style(ax)
    fig.tight_layout()
    caption = "The separable combinations of the table's errors with their expanded uncertainty"
    if r.allocation is not None:
        caption += (
            "; grey bars end in red ticks at ± the bound the allocation implies for each "
            f"(Σ|aᵢ|·UBᵢ, {r.allocation['source']})"
        )
    return figure_from_matplotlib(fig, "Identified errors against the allocation", caption + ".")


def _tables(r: TurntableIdentification) -> list[Table]:
    decisions = {}
    if r.allocation is not None:
        decisions = {e["name"]: e for e in r.allocation["combinations"]}
    rows = []
    for c in r.combinations:
        entry = decisions.get(c["name"], {})
        bound = entry.get("bound_arcsec")
        rows.append(
            [
                c["name"],
                fixed(c["value_arcsec"], 3),
                fixed(c["u_arcsec"], 3),
                fixed(c["U_arcsec"], 3),
                "—" if bound is None else fixed(bound, 3),
                entry.get("decision", "—"),
            ]
        )
    tables = [
        Table(
            ["combination", "value (arcsec)", "u", "U", "bound", "decision"],
            rows,
            caption="Separable combinations of the errors (each error with coefficient 1 unless "
            "stated)",
        )
    ]
    if r.inseparable:
        tables.append(
            Table(
                ["errors", "what separates them"],
                [[", ".join(g["names"]), " ".join(g["separate_by"])] for g in r.inseparable],
                caption="What the positions cannot separate",
            )
        )
    tables.append(
        diagnostics_table(
            [
                ["positions", str(r.positions)],
                ["separable combinations (rank)", str(r.rank)],
                ["degrees of freedom ν = 3n − r", str(r.dof)],
                ["residual standard deviation s", f"{fixed(r.s_arcsec, 3)} arcsec"],
                *(
                    [f"residual rms {_SYMBOLS[c]}", f"{fixed(v, 3)} arcsec"]
                    for c, v in r.residual_rms_arcsec.items()
                ),
                ["model / iterations", f"{r.model} / {r.iterations}"],
                ["σ_i/σ_max", ", ".join(f"{v:.2g}" for v in r.singular_values_relative)],
                [
                    "measure next (φ1, φ2)",
                    ", ".join(f"({a:g}°, {b:g}°)" for a, b in r.next_positions_deg) or "—",
                ],
                ["design criterion", r.design.get("criterion", "—")],
            ],
            f"least squares on the full model ({cite('gyrowheel')}, eqs. 17–25)",
        )
    )
    return tables


def identify_section(r: TurntableIdentification, title: str | None = None) -> Section:
    """The identified combinations with U, the inseparable groups, the figures, the diagnostics."""
    results = [
        ResultRow(
            quantity=c["name"],
            value=f"{fixed(c['value_arcsec'], 3)} arcsec",
            coverage=f"U = {fixed(c['U_arcsec'], 3)} arcsec (k = {fixed(r.k, 3)})",
        )
        for c in r.combinations
    ]
    verdict = []
    if r.allocation is not None:
        verdict.append(
            f"Against {r.allocation['source']}: {r.allocation['verdict']} ({r.allocation['rule']})."
        )
    return Section(
        title=title or f"Geometric errors of {r.table}",
        paragraphs=[
            f"Nonlinear least squares of the measured orientation errors on the full model of "
            f"{cite('gyrowheel')} (eqs. 17–25), u from the residuals (s²·(JᵀJ)⁺, ν = {r.dof}). "
            "Orientation errors alone see only the separable combinations listed; "
            + (
                f"{', '.join(r.unidentifiable)} cannot be estimated alone."
                if r.unidentifiable
                else "every error is separable."
            ),
            *(paragraph(v) for v in verdict),
        ],
        tables=_tables(r),
        figures=[estimates_figure(r), residuals_figure(r)],
        anchor="turntable-identify",
        results=results,
        references=["gyrowheel", "gum"],
    )
