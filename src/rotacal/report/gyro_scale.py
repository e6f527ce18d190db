"""Report section and figure for the gyro scale factor and nonlinearity (seed 004, §4)."""

from __future__ import annotations

from typing import Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

from rotacal.gyro.scale_factor import ScaleFactorResult
from rotacal.report.html import Figure, Section, Table, figure_from_matplotlib
from rotacal.report.uncertainty import budget_tables

__all__ = ["scale_factor_figure", "scale_factor_section"]

_C = {"pt": "#1f5f99", "fit": "#d2691e", "band": "#f2e3c6", "limit": "#b22222", "grid": "#e3e7eb"}


def _style(ax: Any) -> None:
    ax.grid(True, color=_C["grid"], linewidth=0.7)
    ax.spines[["top", "right"]].set_visible(False)


def _g(x: float | None, digits: int = 6) -> str:
    if x is None or not np.isfinite(x):
        return "—"
    return f"{x:.{digits}g}"


def _interval(r: ScaleFactorResult) -> str:
    """The 95 % interval for the true NL, rounded to the decimal place of U (ILAC-P14 §5.4)."""
    b = r._budgets.get("nonlinearity_percent_fs")
    if b is None or b.interval is None:
        return "—"
    if b.U <= 0:
        return f"[{b.interval[0]:.4g}, {b.interval[1]:.4g}] %FS"
    _, u_str = b.rounded()
    decimals = len(u_str.split(".")[1]) if "." in u_str else 0
    lo, hi = b.interval
    return f"[{lo:.{decimals}f}, {hi:.{decimals}f}] %FS"


def _accuracy_limit(r: ScaleFactorResult) -> float | None:
    if r.requirement is None:
        return None
    for c in r.requirement.checks:
        if c.quantity == "accuracy":
            return float(c.limit)
    return None


def _resolution_rows(r: ScaleFactorResult) -> list[list[str]]:
    """The resolution, what set it, both limits and the bandwidth with its source."""
    res = r.resolution
    if res is None:
        return [["resolution", f"{_g(r.resolution_deg_s, 3)} °/s ({r.resolution_basis})", "", ""]]
    unit = f" {r.output_unit}" if r.output_unit else ""
    q = r.output_quantum
    noise = res.noise_deg_s
    bandwidth = (
        "the recorded samples' (sample rate not given)"
        if res.bandwidth_hz is None
        else f"{res.bandwidth_hz:.4g} Hz ({res.bandwidth_source})"
    )
    return [
        [
            "resolution (smallest rate change resolved)",
            f"{_g(r.resolution_deg_s, 3)} °/s, set by the "
            + (res.set_by or "— (neither the quantum nor the noise is visible)"),
            "",
            "",
        ],
        [
            "  output quantum / |S|",
            "not visible" if q is None else f"{_g(res.quantum_deg_s, 3)} °/s ({q:.4g}{unit})",
            "",
            "",
        ],
        [
            "  noise of one reading / |S|",
            "not visible" if noise is None else f"{_g(noise, 3)} °/s rms (largest rate point)",
            "",
            "",
        ],
        ["  bandwidth of the reading", bandwidth, "", ""],
    ]


def scale_factor_figure(r: ScaleFactorResult) -> Figure:
    """Output against rate with the fitted line (top) and residuals in %FS (bottom)."""
    unit = r.output_unit or "output unit"
    rates = np.asarray(r.rates_deg_s)
    means = np.array([p.mean for p in r.points])
    se_pct = (
        np.array([p.standard_error for p in r.points])
        * 100.0
        / (abs(r.scale_factor) * r.full_scale_deg_s)
    )
    fig, (ax1, ax2) = plt.subplots(
        2, 1, figsize=(9.0, 6.4), sharex=True, gridspec_kw={"height_ratios": [1.15, 1]}
    )
    span = float(np.ptp(rates))
    xx = np.linspace(rates.min() - 0.03 * span, rates.max() + 0.03 * span, 2)
    ax1.plot(
        xx,
        r.scale_factor * xx + r.bias,
        color=_C["fit"],
        lw=1.3,
        label=f"least-squares line: S = {r.scale_factor:.7g} {unit}/(°/s), "
        f"V0 = {r.bias:.5g} {unit}",
    )
    ax1.plot(rates, means, "o", ms=5, color=_C["pt"], label=f"point means ({r.n_points} rates)")
    ax1.set_ylabel(f"output ({unit})")
    ax1.legend(fontsize=8, loc="upper left", frameon=False)
    _style(ax1)

    nl = r.nonlinearity_percent_fs
    ax2.axhspan(-nl, nl, color=_C["band"], zorder=0, label=f"±NL = ±{nl:.3g} %FS")
    lim = _accuracy_limit(r)
    if lim is not None:
        for sgn in (1, -1):
            ax2.axhline(
                sgn * lim,
                color=_C["limit"],
                ls="--",
                lw=1.1,
                label=f"requirement ±{lim:g} %FS ({r.requirement.title})"
                if sgn == 1 and r.requirement is not None
                else None,
            )
    ax2.axhline(0.0, color="#777", lw=0.7)
    ax2.errorbar(
        rates,
        r.residuals_percent_fs,
        yerr=np.where(np.isfinite(se_pct), se_pct, 0.0),
        fmt="o-",
        ms=5,
        lw=0.8,
        capsize=3,
        color=_C["pt"],
        label="residual δ of each point (± its standard error)",
    )
    worst = int(np.argmax(np.abs(r.residuals_percent_fs)))
    ax2.annotate(
        f"max |δ| = {abs(r.residuals_percent_fs[worst]):.3g} %FS",
        (rates[worst], r.residuals_percent_fs[worst]),
        xytext=(0, 12 if r.residuals_percent_fs[worst] >= 0 else -16),
        textcoords="offset points",
        ha="left" if worst == 0 else ("right" if worst == rates.size - 1 else "center"),
        fontsize=8,
    )
    top = max(nl, lim or 0.0) * 1.45
    ax2.set_ylim(-top, top)
    ax2.set_xlabel("set rate Ω (°/s)")
    ax2.set_ylabel(f"residual (% of FS = {r.full_scale_deg_s:g} °/s)")
    ax2.legend(fontsize=8, loc="upper center", bbox_to_anchor=(0.5, -0.2), ncols=3, frameon=False)
    _style(ax2)
    fig.align_ylabels((ax1, ax2))
    fig.tight_layout()
    return figure_from_matplotlib(
        fig,
        "Output against rate, and the residuals of the straight line",
        "Top: the mean output of each rate point and the unweighted least-squares line "
        "V = S·Ω + V0 (seed 004 §4). Bottom: residuals δ in % of full scale (δ/(|S|·FS)); the band "
        "is ±NL, the dashed lines the requirement's accuracy limit.",
    )


def scale_factor_section(
    r: ScaleFactorResult,
    title: str | None = None,
    *,
    figures: bool = True,
    truth: dict[str, Any] | None = None,
) -> Section:
    """A report section: results, pass/fail lines, the table of points and the figure.

    ``truth`` (a twin's truth dict) adds the true values beside the results.
    """
    unit = r.output_unit or "output unit"
    has_truth = truth is not None
    cols = ["quantity", "value", "standard uncertainty"] + (["twin truth"] if has_truth else [])
    rows = [
        [
            "scale factor S",
            f"{r.scale_factor:.8g} {unit}/(°/s)",
            _g(r.scale_factor_u, 3),
            _g(truth["ls_scale_factor"], 8) if truth else "",
        ],
        [
            "bias V0",
            f"{r.bias:.6g} {unit}",
            _g(r.bias_u, 3),
            _g(truth["ls_bias"], 6) if truth else "",
        ],
        [
            "nonlinearity NL",
            f"{r.nonlinearity_percent_fs:.4g} %FS",
            _g(r._budgets["nonlinearity_percent_fs"].u, 3) if r._budgets else "",
            _g(truth["nonlinearity_percent_fs"], 4) if truth else "",
        ],
        [
            "true NL, 95 % interval",
            _interval(r),
            "",
            "",
        ],
        [
            "NL bias-corrected",
            (
                f"{_g(r.nonlinearity_percent_fs_bias_corrected, 4)} %FS "
                f"(noise bias {_g(r.nonlinearity_percent_fs_bias, 2)} %FS)"
                if np.isfinite(r.nonlinearity_percent_fs_bias)
                else "— (noise level not known apart from the NL: not corrected)"
                if "nonlinearity_percent_fs" in r._budgets
                else "—"
            ),
            "",
            "",
        ],
        ["full scale FS", f"{r.full_scale_deg_s:g} °/s", "", ""],
        ["rate points / samples", f"{r.n_points} / {r.samples_used}", "", ""],
        *_resolution_rows(r),
    ]
    if not has_truth:
        rows = [row[:3] for row in rows]
    tables = [Table(cols, rows, caption="Scale factor and nonlinearity")]
    paragraphs = list(r.notes)
    if r.requirement is not None:
        v = r.requirement
        verdict = {True: "PASS", False: "FAIL", None: "NOT ASSESSED"}
        d = r.decision_with_uncertainty

        def with_u(quantity: str) -> str:
            if quantity == "accuracy" and d is not None:
                if d.interval is not None:
                    return f"{d.verdict.upper()} (true NL in {_interval(r)})"
                return f"{d.verdict.upper()} (NL ± U = {d.value:.4g} ± {d.U:.2g} %FS)"
            return "— (no U)"

        tables.append(
            Table(
                ["check", "limit", "measured", "margin", "verdict", "verdict with U (ILAC-G8)"],
                [
                    [
                        c.quantity,
                        f"{'±' if c.quantity == 'range' else '< '}{c.limit:g} "
                        f"{'°/s' if c.unit == 'deg/s' else '%FS'}",
                        _g(c.value, 4),
                        _g(c.margin, 3),
                        verdict[c.passed],
                        with_u(c.quantity),
                    ]
                    for c in v.checks
                ],
                caption=f"Requirement: {v.title} — {verdict[v.passed]} ({v.source})",
            )
        )
        paragraphs.append(v.note)
        if d is not None:
            paragraphs.append(
                f"Decision rule: {d.rule}. {d.line[0].upper()}{d.line[1:]}. The range and "
                "resolution checks carry no uncertainty here (set rates, and the resolution: the "
                "larger of the output quantum and the noise of one reading, divided by |S|)."
            )
    tables.append(
        Table(
            [
                "set rate (°/s)",
                "n",
                f"mean ({unit})",
                f"std ({unit})",
                f"std. error ({unit})",
                f"residual δ ({unit})",
                "δ (%FS)",
            ],
            [
                [
                    f"{p.rate_deg_s:+g}",
                    str(p.n),
                    f"{p.mean:.7g}",
                    _g(p.std, 4),
                    _g(p.standard_error, 3),
                    f"{p.residual:+.4g}",
                    f"{p.residual_percent_fs:+.4f}",
                ]
                for p in r.points
            ],
            caption="Rate points",
        )
    )
    tables += budget_tables(r._budgets)
    return Section(
        title=title or "Gyro scale factor and nonlinearity",
        paragraphs=paragraphs,
        tables=tables,
        figures=[scale_factor_figure(r)] if figures else [],
        anchor="gyro-scale",
    )
