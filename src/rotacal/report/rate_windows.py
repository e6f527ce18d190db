"""Report section of the rate over angle windows: accuracy, stability and the window rates.

The definitions (consecutive, non-overlapping windows; mean rate against the set rate; spread and
largest departure of the window rates) are those of :mod:`rotacal.table.rate_windows`.
"""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt

from rotacal.numbers import coverage, fixed, format_quantity
from rotacal.references import cite
from rotacal.report.html import Figure, ResultRow, Section, Table, figure_from_matplotlib
from rotacal.report.motion import _style
from rotacal.table.rate_windows import RateWindows, window_coverage_factor

__all__ = ["rate_windows_figure", "rate_windows_section"]

_RATE = "#1f5f99"
_BAND = "#d2691e"


def rate_windows_figure(w: RateWindows) -> Figure:
    """One panel per window size: each window's rate about the mean (% of rate) against the
    angle turned (revolutions) — the least and largest of each block when the windows are many
    — with ±1 standard deviation (the stability) as a band."""
    keys = list(w.traces)
    fig, axes = plt.subplots(len(keys), 1, figsize=(9.5, 1.2 + 2.1 * len(keys)), squeeze=False)
    for ax, key in zip(axes[:, 0], keys, strict=True):
        tr = w.traces[key]
        mean = w.window_mean_rate_deg_s[key]
        rev = (tr.index + 0.5 * tr.block) * tr.window_deg / 360.0
        lo = 100.0 * (tr.lo - mean) / mean
        hi = 100.0 * (tr.hi - mean) / mean
        if tr.block == 1:
            ax.plot(rev, lo, ".-" if lo.size < 200 else "-", color=_RATE, lw=0.7, ms=3)
        else:
            ax.fill_between(rev, lo, hi, facecolor=_RATE, edgecolor=_RATE, lw=0.5, alpha=0.8)
        s = w.rate_stability_percent[key]
        ax.axhspan(-s, s, color=_BAND, alpha=0.15, lw=0)
        ax.axhline(0.0, color="#333", lw=0.6)
        ax.set_ylabel("rate − mean (%)", fontsize=8)
        ax.set_title(
            f"over {key}°: {w.window_count[key]} windows, stability {s:#.3g} %, "
            f"peak {w.rate_stability_peak_percent[key]:#.3g} %"
            + ("" if tr.block == 1 else f" (least and largest of each {tr.block} windows)"),
            fontsize=9,
            loc="left",
        )
        ax.set_xlim(0, max(float(rev[-1] + 0.5 * tr.block * tr.window_deg / 360.0), 1e-12))
        _style(ax)
        secondary = ax.secondary_xaxis(
            "top",
            functions=(lambda r, m=mean: r * 360.0 / m, lambda s_, m=mean: s_ * m / 360.0),
        )
        secondary.tick_params(labelsize=7)
    axes[-1, 0].set_xlabel("angle turned (revolutions); time (s) on top")
    fig.tight_layout()
    return figure_from_matplotlib(
        fig,
        "Rate over angle windows",
        "Mean rate of each consecutive window about the mean of all, in % of it; the band is "
        "± the rate stability (one standard deviation of the window rates)"
        + (", windows compensated with the self-calibrated deviation." if w.compensated else "."),
    )


def _table(w: RateWindows) -> Table:
    def pm(value: float | None, u: float | None) -> str:  # value ± u, rounded as u
        return "—" if value is None or u is None else format_quantity(value, "%", U=u)

    rows = [
        [
            f"{key}° ({w.window_pulses[key]} pitches)",
            str(w.window_count[key]),
            pm(w.rate_accuracy_percent[key], w.rate_accuracy_percent_u[key]),
            pm(w.rate_stability_percent[key], w.rate_stability_percent_u[key]),
            pm(w.rate_stability_peak_percent[key], w.rate_stability_peak_percent_u[key]),
            f"{fixed(w.window_noise_percent[key], 2)} %",
        ]
        for key in w.window_count
    ]
    return Table(
        ["window", "windows", "rate accuracy", "rate stability", "largest departure", "noise σ_w"],
        rows,
        caption="Rate accuracy and stability over angle windows (value ± standard uncertainty)",
        note=(
            "Accuracy: 100·(mean window rate − set rate)/set rate. Stability: 100·standard "
            "deviation of the window rates/their mean. Largest departure: 100·max|window rate − "
            "mean|/mean. σ_w: the measurement noise of one window rate (timing of its two end "
            "pulses, the angle error of its two end lines; none over 360°)."
        ),
    )


def rate_windows_section(w: RateWindows, title: str = "Rate over angle windows") -> Section:
    """The windows' table, figure and notes; each window's figures in the summary."""
    results = []
    for key in w.window_count:
        for name, value, u in (
            ("stability", w.rate_stability_percent[key], w.rate_stability_percent_u[key]),
            ("accuracy", w.rate_accuracy_percent[key], w.rate_accuracy_percent_u[key]),
        ):
            if value is None or u is None:
                continue
            # U = t₉₅(N − 1)·u over the N windows, as the certificate states it
            k = window_coverage_factor(w.window_count[key])
            text = format_quantity(value, "%", U=k * u, k=k, p=0.95)
            results.append(
                ResultRow(
                    f"rate {name} over {key}°",
                    text.split(" (k", 1)[0],
                    coverage=coverage(k, 0.95).strip("()"),
                )
            )
    return Section(
        title=title,
        paragraphs=[
            "The record cut into consecutive, non-overlapping windows of each angle; the mean rate "
            "of each is the window's angle over the time between its end pulses, the rate-table "
            f"test of elapsed time through a known angle ({cite('kokuyama2015')}, §5). Over 360° "
            "a window starts and ends on the same line, so the graduation error cancels.",
            *w.notes,
        ],
        tables=[_table(w)],
        figures=[rate_windows_figure(w)] if w.traces else [],
        results=results,
        references=["kokuyama2015", "ieee1431", "gum"],
        anchor="rate-windows",
    )
