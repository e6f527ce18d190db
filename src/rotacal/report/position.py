"""Report section and figure of a position test: error curve, ±2s band, harmonics, ISO 230-2."""

from __future__ import annotations

import math
from typing import Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

from rotacal.position.accuracy import PositionAccuracy
from rotacal.report.gyro_steps import standard_u_row
from rotacal.report.html import Figure, Section, Table, figure_from_matplotlib
from rotacal.report.wording import paragraph

__all__ = ["position_figure", "position_plot", "position_section"]

_C = {
    1: "#1f5f99",
    -1: "#b5651d",
    "curve": "#222222",
    "fit": "#2e8b57",
    "grid": "#e3e7eb",
    "face": "#6a3d9a",
}
_WORD = {1: "↑ positive approach", -1: "↓ negative approach"}


def position_plot(r: PositionAccuracy) -> Any:
    """Runs, each direction's mean with its ±2s band, the error curve and its harmonic fit; the
    harmonics' amplitudes (± 2u); a polygon's face errors when separated."""
    poly = r._polygon
    # constrained layout runs when the figure is drawn (not when it is built)
    fig = plt.figure(figsize=(10.0, 6.8), layout="constrained")
    grid = fig.add_gridspec(2, 2 if poly is not None else 1, height_ratios=[1.35, 1.0])
    ax = fig.add_subplot(grid[0, :])
    # a full circle is drawn closed: the reading at 0° is drawn again at 360°
    closed = r.positions_deg[0] == 0.0 and r.positions_deg[-1] < 360.0
    pos = np.r_[r.positions_deg, 360.0] if closed else r.positions_deg

    def wrap(a: Any) -> Any:
        return None if a is None else (np.r_[a, a[0]] if closed else a)

    for d, sign in enumerate(r.directions):
        colour = _C[sign]
        for run in r._deviations[d]:
            ax.plot(pos, wrap(run), color=colour, lw=0.6, alpha=0.35)
        mean = wrap(r.by_direction(sign, "mean"))
        std = wrap(r.by_direction(sign, "std"))
        if std is not None and mean is not None:
            ax.fill_between(pos, mean - 2 * std, mean + 2 * std, color=colour, alpha=0.15)
        if mean is not None:
            ax.plot(pos, mean, "o-", color=colour, ms=3, lw=1.2, label=f"{_WORD[sign]}: mean ± 2s")
    ax.plot(pos, wrap(r.error_curve_arcsec), color=_C["curve"], lw=1.8, label="error curve e(θ)")
    fit = r._harmonics
    if fit is not None:
        th = np.linspace(0.0, 360.0, 721)
        ang = np.deg2rad(th)[:, None] * np.asarray(fit.orders)[None, :]
        model = fit.mean_arcsec + np.cos(ang) @ fit.cos_arcsec + np.sin(ang) @ fit.sin_arcsec
        ax.plot(th, model, color=_C["fit"], lw=1.0, ls="--", label=f"harmonics 1…{fit.orders[-1]}")
    ax.set_xlabel("target position θ (°)")
    ax.set_ylabel("positional deviation (arcsec)")
    ax.set_xlim(min(0.0, pos.min()), max(360.0, pos.max()))
    ax.set_xticks(np.arange(0, 361, 45))
    ax.grid(True, color=_C["grid"], lw=0.7)
    ax.spines[["top", "right"]].set_visible(False)
    ax.legend(fontsize=7, loc="best", frameon=False, ncol=2)
    ax.set_title("thin lines: single runs", fontsize=8, loc="right", color="#666")
    ax2 = fig.add_subplot(grid[1, 0])
    if fit is not None:
        ax2.bar(fit.orders, fit.amplitudes_arcsec, color=_C["fit"], width=0.6)
        ax2.errorbar(
            fit.orders, fit.amplitudes_arcsec, yerr=2 * fit.amplitudes_arcsec_u, fmt="none",
            ecolor="#333", capsize=3,
        )  # fmt: skip
        ax2.set_xticks(fit.orders)
    ax2.set_xlabel("harmonic order (per revolution)")
    ax2.set_ylabel("amplitude (arcsec) ± 2u")
    ax2.grid(True, axis="y", color=_C["grid"], lw=0.7)
    ax2.set_axisbelow(True)
    ax2.spines[["top", "right"]].set_visible(False)
    if poly is not None:
        ax3 = fig.add_subplot(grid[1, 1])
        faces = np.arange(poly.face_errors_arcsec.size)
        u = poly.face_errors_arcsec_u
        ax3.bar(faces, poly.face_errors_arcsec, color=_C["face"], width=0.6)
        if u is not None:
            ax3.errorbar(
                faces, poly.face_errors_arcsec, yerr=2 * u, fmt="none", ecolor="#333", capsize=2
            )
        ax3.set_xlabel("polygon face")
        ax3.set_ylabel("face error (arcsec) ± 2u")
        ax3.set_title(
            "separated by closure" if not poly.unresolved else "NOT fully separated",
            fontsize=8,
            color="#666" if not poly.unresolved else "#b22222",
        )
        ax3.grid(True, axis="y", color=_C["grid"], lw=0.7)
        ax3.set_axisbelow(True)
        ax3.spines[["top", "right"]].set_visible(False)
    return fig


def position_figure(r: PositionAccuracy) -> Figure:
    """The error-curve figure of :func:`position_plot`, with its caption."""
    return figure_from_matplotlib(
        position_plot(r),
        "Error curve of the table",
        "Positional deviation (actual − target) at each target position: each run (thin lines), "
        "each direction's mean with its ±2s band (ISO 230-2), the error curve (mean "
        "bidirectional deviation) and its least-squares harmonics; below, the harmonics' "
        "amplitudes with 2u" + (" and the polygon's face errors." if r._polygon else "."),
    )


def _reference_phrase(reference: str) -> str:
    """The reference (``PositionAccuracy.reference``) as the report's sentence names it."""
    if reference == "polygon":
        return "an autocollimator on a polygon"
    if reference == "deviation":
        return "the instrument whose deviations the capture holds (column error_arcsec)"
    return ("an " if reference[:1] in "aeiou" else "a ") + reference


def position_section(r: PositionAccuracy, title: str | None = None) -> Section:
    """Results with U (k = t₉₅(ν_eff)), the ISO 230-2 table (with ν_eff), the harmonics table and
    the figure."""
    d = r.to_dict()
    ks = d["k"]
    results = [
        standard_u_row(
            "error curve peak-to-peak",
            r.error_pp_arcsec,
            r.error_pp_arcsec_u,
            "″",
            k=ks["error_pp_arcsec"] or 2.0,
        )
    ]
    iso_rows = []
    for key, label in (
        ("positioning_accuracy_bidirectional", "accuracy A"),
        ("positioning_accuracy_forward", "accuracy A↑"),
        ("positioning_accuracy_reverse", "accuracy A↓"),
        ("repeatability_bidirectional", "repeatability R"),
        ("repeatability_forward", "repeatability R↑ (4s)"),
        ("repeatability_reverse", "repeatability R↓ (4s)"),
        ("reversal_value", "reversal value B"),
        ("reversal_value_mean", "mean reversal value B̄"),
        ("systematic_deviation_bidirectional", "systematic deviation E"),
        ("systematic_deviation_forward", "systematic deviation E↑"),
        ("systematic_deviation_reverse", "systematic deviation E↓"),
        ("mean_deviation_range", "range of mean deviation M"),
    ):
        v, u = d[f"{key}_arcsec"], d[f"{key}_arcsec_u"]
        if v is None:
            continue
        dof, k = d["dof"][f"{key}_arcsec"], ks[f"{key}_arcsec"]
        iso_rows.append(
            [
                label,
                f"{v:.3f}",
                "—" if u is None else f"{u:.3f}",
                "—" if u is None else ("∞" if dof is None else f"{dof:.1f}"),
                "—" if k is None else f"{k:.2f}",
            ]
        )
        if key in ("positioning_accuracy_bidirectional", "repeatability_bidirectional"):
            k = ks[f"{key}_arcsec"] or 2.0
            results.append(standard_u_row(label, v, u, "″", note="ISO 230-2", k=k))
    tables = [
        Table(
            ["ISO 230-2 value", "arcsec", "u (arcsec)", "ν_eff", "k (95 %)"],
            iso_rows,
            caption="ISO 230-2 values, with the effective degrees of freedom of each u "
            "(Welch–Satterthwaite: the readings' scatter has n − 1) and its coverage factor",
        )
    ]
    fit = r._harmonics
    if fit is not None:
        tables.append(
            Table(
                ["order", "amplitude (″)", "u (″)", "phase (°)", "u (°)"],
                [
                    [str(h), f"{a:.3f}", f"{ua:.3f}", f"{p:.1f}", f"{up:.1f}"]
                    for h, a, ua, p, up in zip(
                        fit.orders,
                        fit.amplitudes_arcsec,
                        fit.amplitudes_arcsec_u,
                        fit.phases_deg,
                        fit.phases_deg_u,
                        strict=True,
                    )
                ],
                caption=f"Harmonics c·cos(hθ − φ) (residual rms {fit.residual_rms_arcsec:.3f}″, "
                f"{fit.dof} dof; the u's effective dof "
                + ("∞" if math.isinf(fit.effective_dof) else f"{fit.effective_dof:.1f}")
                + f", k = {fit.coverage_k:.2f} for 95 %)",
            )
        )
    paragraphs: list[Any] = [
        f"The table was sent to {r.positions_deg.size} target positions in {r.runs} run(s), "
        + ("in both directions of approach" if len(r.directions) == 2 else "in one direction")
        + f"; the reference was {_reference_phrase(r.reference)}. "
        "The positional deviation is actual minus target position; the values of the axis follow "
        "ISO 230-2:2014 (repeatability 4s, accuracy from the ±2s bands).",
        *(paragraph(n) for n in r.notes),
    ]
    return Section(
        title=title or "Position accuracy of the table",
        paragraphs=paragraphs,
        tables=tables,
        figures=[position_figure(r)],
        anchor="position",
        results=results,
        references=["iso230_2", "evans1996"] + (["kokuyama2015"] if r._selfcal else []),
    )
