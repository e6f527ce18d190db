"""Report section for gyro noise: the Allan deviation with its five fitted IEEE 952 terms."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

from rotacal.gyro.noise import GyroNoise
from rotacal.gyro.noise_fit import NOISE_TERM_NAMES
from rotacal.numbers import fixed
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
_KEYS = {
    "quantization": "quantization_arcsec",
    "angle_random_walk": "arw_deg_rt_h",
    "bias_instability": "bias_instability_deg_h",
    "rate_random_walk": "rrw_deg_h_rt_h",
    "rate_ramp": "rate_ramp_deg_h2",
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
    fit = r.fit
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
    ax.loglog(
        fit.tau_s,
        np.sqrt(fit.avar),
        "o",
        ms=3.5,
        mfc="none",
        color="#1f5f99",
        label="points fitted",
    )
    lines = fit.term_adev(tau)
    floor = 1e-3 * float(np.min(r.adev_deg_s))
    for j, name in enumerate(NOISE_TERM_NAMES):
        if not fit.c[j] > 0:
            continue
        label, slope, _, _ = _LABELS[name]
        resolved = fit.coefficients[j] > fit.expanded[j]  # its 95 % interval excludes 0
        ax.loglog(
            tau,
            np.maximum(lines[j], floor),
            "--" if resolved else ":",
            lw=1.1,
            color=_COLORS[name],
            label=f"{label} (slope {slope})" + ("" if resolved else ", not resolved"),
        )
    ax.loglog(tau, fit.total_adev(tau), color="#222", lw=1.0, label="sum of the fitted terms")
    lo = 0.3 * float(np.min(r.adev_low_deg_s))
    hi = 3.0 * float(np.max(r.adev_high_deg_s))
    ax.set_ylim(lo, hi)
    ax.set_xlabel("averaging time τ (s)")
    ax.set_ylabel("σ(τ) (°/s)")
    ax.grid(True, which="both", color="#e3e7eb", linewidth=0.6)
    ax.spines[["top", "right"]].set_visible(False)
    ax.legend(loc="best", fontsize=8, frameon=False)
    return figure_from_matplotlib(
        fig,
        "Allan deviation and the fitted noise terms",
        f"Column “{r.column}” of the capture, {r.samples} samples at {fixed(r.fs_hz)} Hz "
        f"({fixed(r.duration_s / 3600, 3)} h). Dashed: each {cite('ieee952')} term of the "
        "five-term fit alone; solid black: their sum; circles: the points fitted.",
    )


def noise_section(r: GyroNoise, title: str = "Gyro noise") -> Section:
    """The five fitted terms with their 95 % intervals, the Allan deviation figure with each
    term's line and their sum, and the budgets folded."""
    rows = []
    terms = r.noise_terms
    for name in NOISE_TERM_NAMES:
        label, slope, unit, _ = _LABELS[name]
        key = _KEYS[name]
        value = terms.get(key)
        if value is None:
            continue
        interval = terms[f"{key}_interval"]
        shown = "arcsec" if key == "quantization_arcsec" else unit
        rows.append(
            [
                label,
                slope,
                f"{fixed(value, 4)} {shown}",
                f"{fixed(interval[0], 4)} … {fixed(interval[1], 4)} {shown}",
            ]
        )
    if not rows:
        rows.append(["no term identified (record unit without a factor to °)", "", "", ""])
    fit = r.fit
    table = Table(
        ["term", "slope", "value", "95 % interval"],
        rows,
        caption=f"Noise terms by the five-term fit ({cite('ieee952')}, Annex C)",
        note=f"Generalised least squares on {fit.tau_s.size} points of the Allan variance, "
        f"model discrepancy {fixed(100 * fit.discrepancy, 2)} % per point; an interval that "
        "holds 0 means the term is not resolved by this record.",
    )
    paragraphs = [paragraph(n) for n in r.notes]
    if r._budgets:
        paragraphs.append(
            "The five terms come from one fit of 3Q²/τ² + N²/τ + (2 ln 2/π)B² + K²τ/3 + R²τ²/2 to "
            "the whole Allan variance curve, with non-negative coefficients and weights from the "
            "covariance of the overlapping estimator for the fitted mixture (its points are "
            "correlated). Each term's Type A uncertainty is its 95 % interval from that fit "
            "(widened by the model discrepancy when the curve departs from the model)."
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
