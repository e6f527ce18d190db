"""Report section for gyro noise: the Allan deviation with its fitted IEEE 952 slopes."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

from rotacal.gyro.noise import GyroNoise
from rotacal.numbers import fixed, format_plain, format_quantity
from rotacal.references import cite
from rotacal.report.html import Figure, Section, Table, figure_from_matplotlib
from rotacal.report.uncertainty import budget_details, budget_results
from rotacal.report.wording import paragraph, readable_rows, readable_tables

__all__ = ["noise_section"]

_LABELS = {
    "quantization": ("quantization Q", "−1", "°", 1.0),
    "angle_random_walk": ("angle random walk N", "−½", "°/√h", 60.0),
    "bias_instability": ("bias instability B", "0", "°/h", 3600.0),
    "rate_random_walk": ("rate random walk K", "+½", "°/h/√h", 3600.0 * 60.0),
    "rate_ramp": ("rate ramp R", "+1", "°/h²", 3600.0**2),
}
_COLORS = {
    "quantization": "#6a3d9a",
    "angle_random_walk": "#d2691e",
    "bias_instability": "#2e8b57",
    "rate_random_walk": "#b22222",
    "rate_ramp": "#555555",
}


def _figure(r: GyroNoise) -> Figure:
    tau = np.asarray(r.tau_s)
    fig, ax = plt.subplots(figsize=(7.8, 4.8))
    ax.fill_between(
        tau,
        r.adev_low_deg_s,
        r.adev_high_deg_s,
        color="#9fb7cf",
        alpha=0.45,
        lw=0,
        label="68 % interval",
    )
    ax.loglog(tau, r.adev_deg_s, color="#1f5f99", lw=1.4, label="overlapping Allan deviation")
    for name, term in r.terms.terms.items():
        label = _LABELS.get(name, (name, "", "", 1.0))[0]
        # draw the line a decade beyond the points it was fitted through
        t0, t1 = np.asarray(term.line_tau_s, dtype=float)[[0, -1]]
        a0 = float(np.asarray(term.line_adev)[0])
        tt = np.array([max(tau[0], t0 / 10), min(tau[-1], t1 * 10)])
        ax.loglog(
            tt,
            a0 * (tt / t0) ** term.slope,
            "--",
            lw=1.1,
            color=_COLORS.get(name, "#333"),
            label=f"{label} (slope {_LABELS.get(name, ('', '?'))[1]})",
        )
    ax.set_xlabel("averaging time τ (s)")
    ax.set_ylabel("σ(τ) (°/s)")
    ax.grid(True, which="both", color="#e3e7eb", linewidth=0.6)
    ax.spines[["top", "right"]].set_visible(False)
    ax.legend(loc="best", fontsize=8, frameon=False)
    return figure_from_matplotlib(
        fig,
        "Allan deviation and noise terms",
        f"Column “{r.column}” of the capture, {r.samples} samples at {fixed(r.fs_hz)} Hz "
        f"({fixed(r.duration_s / 3600, 3)} h). Dashed: the {cite('ieee952')} lines where each "
        "slope dominates.",
    )


def noise_section(r: GyroNoise, title: str = "Gyro noise") -> Section:
    """The noise terms with U in the summary, IEEE Std 952's rule-of-thumb intervals as
    diagnostics, the Allan deviation figure and the budgets folded."""
    rows = []
    for name, term in r.terms.terms.items():
        label, slope, unit, scale = _LABELS.get(name, (name, "", term.unit, 1.0))
        rows.append(
            [
                label,
                slope,
                f"{fixed(term.coefficient * scale, 4)} {unit}",
                f"{fixed(term.low * scale, 3)} … {fixed(term.high * scale, 3)} {unit}",
                _time_text(term.tau_ref_s),
            ]
        )
    if not rows:
        rows.append(["no term identified", "", "", "", ""])
    table = Table(
        ["term", "slope", "value", "interval ±1/√(2(N/m − 1))", "read at τ"],
        rows,
        caption=f"Noise terms by the slope method ({cite('ieee952')}, Annex C)",
        note="The intervals are IEEE Std 952 C.4's rule of thumb (diagnostics, not results); the "
        "summary states each term with the U of its budget.",
    )
    paragraphs = [paragraph(n) for n in r.notes]
    if r._budgets:
        paragraphs.append(
            "Uncertainty budgets: each term's Type A standard uncertainty is the ±1σ χ² interval "
            "of the reading it comes from — the level of the line fitted through correlated "
            "points of the curve (equivalent degrees of freedom for the term's own noise type), "
            "or the one point of the flat minimum for B. The slope method's own bias (other terms "
            "adding to the fitted points) is not in u; each budget's notes estimate it."
        )
    return Section(
        title=title,
        paragraphs=paragraphs,
        tables=[table],
        figures=[_figure(r)],
        results=readable_rows(budget_results(r._budgets)),
        details=readable_tables(budget_details(r._budgets)),
        references=["ieee952", "greenhall2003", "gum"],
        anchor="gyro-noise",
    )


def _time_text(seconds: float) -> str:
    """A time for a table cell, with the SI prefix that keeps its digits readable."""
    return (
        format_plain(seconds, "s", digits=3)
        if seconds >= 0.01
        else format_quantity(seconds, "s", si_prefix=True, digits=3)
    )
