"""Report section and figure for the gyro scale factor and nonlinearity (Kokuyama et al. 2015, §4)."""

from __future__ import annotations

from typing import Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

from rotacal.gyro.scale_factor import ScaleFactorResult
from rotacal.numbers import fixed
from rotacal.references import cite
from rotacal.report.gyro_sf_items import sf_item_figures, sf_item_rows, sf_item_tables
from rotacal.report.html import Figure, ResultRow, Section, Table, figure_from_matplotlib
from rotacal.report.uncertainty import budget_details, budget_results, result_row
from rotacal.report.wording import (
    diagnostics_table,
    paragraph,
    readable_rows,
    readable_tables,
)

__all__ = ["requirement_rows", "scale_factor_figure", "scale_factor_section"]

_C = {"pt": "#1f5f99", "fit": "#d2691e", "band": "#f2e3c6", "limit": "#b22222", "grid": "#e3e7eb"}


def _style(ax: Any) -> None:
    ax.grid(True, color=_C["grid"], linewidth=0.7)
    ax.spines[["top", "right"]].set_visible(False)


def _g(x: float | None, digits: int = 6) -> str:
    return fixed(x, digits) if x is not None else "—"


def _unit(r: ScaleFactorResult) -> str:
    """The output unit the user gave, or "output units" in words."""
    return r.output_unit or "output units"


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
        return [["resolution", f"{_g(r.resolution_deg_s, 3)} °/s ({r.resolution_basis})"]]
    q = r.output_quantum
    noise = res.noise_deg_s
    bandwidth = (
        "the recorded samples' (sample rate not given)"
        if res.bandwidth_hz is None
        else f"{_g(res.bandwidth_hz, 4)} Hz ({res.bandwidth_source})"
    )
    return [
        [
            "resolution (smallest rate change resolved)",
            f"{_g(r.resolution_deg_s, 3)} °/s, set by the "
            + (res.set_by or "— (neither the quantum nor the noise is visible)"),
        ],
        [
            "output quantum / |S|",
            "not visible"
            if q is None
            else f"{_g(res.quantum_deg_s, 3)} °/s ({_g(q, 4)} {_unit(r)})",
        ],
        [
            "noise of one reading / |S|",
            "not visible" if noise is None else f"{_g(noise, 3)} °/s rms (largest rate point)",
        ],
        ["bandwidth of the reading", bandwidth],
    ]


def scale_factor_figure(r: ScaleFactorResult) -> Figure:
    """Output against rate with the fitted line (top) and residuals in %FS (bottom)."""
    unit = _unit(r)
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
        label=f"least-squares line: S = {_g(r.scale_factor, 7)} {unit}/(°/s), "
        f"V0 = {_g(r.bias, 5)} {unit}",
    )
    ax1.plot(rates, means, "o", ms=5, color=_C["pt"], label=f"point means ({r.n_points} rates)")
    ax1.set_ylabel(f"output ({unit})")
    ax1.legend(fontsize=8, loc="upper left", frameon=False)
    _style(ax1)

    nl = r.nonlinearity_percent_fs
    ax2.axhspan(-nl, nl, color=_C["band"], zorder=0, label=f"±NL = ±{_g(nl, 3)} % FS")
    lim = _accuracy_limit(r)
    if lim is not None:
        for sgn in (1, -1):
            ax2.axhline(
                sgn * lim,
                color=_C["limit"],
                ls="--",
                lw=1.1,
                label=f"requirement ±{_g(lim)} % FS ({r.requirement.title})"
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
        f"max |δ| = {_g(abs(r.residuals_percent_fs[worst]), 3)} % FS",
        (rates[worst], r.residuals_percent_fs[worst]),
        xytext=(0, 12 if r.residuals_percent_fs[worst] >= 0 else -16),
        textcoords="offset points",
        ha="left" if worst == 0 else ("right" if worst == rates.size - 1 else "center"),
        fontsize=8,
    )
    top = max(nl, lim or 0.0) * 1.45
    ax2.set_ylim(-top, top)
    ax2.set_xlabel("set rate Ω (°/s)")
    ax2.set_ylabel(f"residual (% of FS = {_g(r.full_scale_deg_s)} °/s)")
    ax2.legend(fontsize=8, loc="upper center", bbox_to_anchor=(0.5, -0.2), ncols=3, frameon=False)
    _style(ax2)
    fig.align_ylabels((ax1, ax2))
    fig.tight_layout()
    return figure_from_matplotlib(
        fig,
        "Output against rate, and the residuals of the straight line",
        f"Top: point means and the least-squares line V = S·Ω + V0 ({cite('kokuyama2015')}, §4). "
        "Bottom: residuals in % of full scale; band ±NL, dashed: the requirement.",
    )


def requirement_rows(r: ScaleFactorResult) -> list[ResultRow]:
    """One summary row per check of the requirement, with its limit and verdict.

    The accuracy check is judged with the uncertainty of NL (ILAC-G8: a pass when the whole 95 %
    interval lies below the limit, inconclusive when the limit lies within it); range and
    resolution carry no uncertainty (set rates; the larger of the output quantum and one
    reading's noise, divided by |S|).
    """
    v = r.requirement
    if v is None:
        return []
    d = r.decision_with_uncertainty
    b = r._budgets.get("nonlinearity_percent_fs")
    rows = []
    for c in v.checks:
        unit = "°/s" if c.unit == "deg/s" else "% FS"
        limit = f"{'±' if c.quantity == 'range' else '< '}{_g(c.limit)} {unit} ({v.title})"
        if c.quantity == "accuracy" and d is not None and b is not None:
            passed = {"pass with U": True, "fail with U": False}.get(d.verdict)
            rows.append(
                result_row(
                    "nonlinearity against the requirement",
                    b.value,
                    "% FS",
                    U=b.U,
                    k=b.k,
                    p=b.p,
                    interval=b.interval,
                    limit=limit,
                    passed=passed,
                    note=f"{d.verdict} ({cite('ilac_g8')})",
                )
            )
            continue
        rows.append(
            result_row(
                f"{c.quantity} against the requirement",
                c.value,
                unit if c.quantity != "range" else "°/s",
                limit=limit,
                passed=c.passed,
                note="no uncertainty: "
                + ("the set rates" if c.quantity == "range" else "a bound, not a measurement"),
            )
        )
    return rows


def scale_factor_section(
    r: ScaleFactorResult,
    title: str | None = None,
    *,
    figures: bool = True,
    truth: dict[str, Any] | None = None,
) -> Section:
    """A report section: results with U, the requirement's verdicts, the rate points, the figure.

    ``truth`` (a twin's truth dict) adds the true values in a table beside the results.
    """
    unit = _unit(r)
    names = {
        "scale_factor": "scale factor S",
        "bias": "bias V0",
        "nonlinearity_percent_fs": "nonlinearity NL",
    }
    judged = requirement_rows(r)
    budgets = dict(r._budgets)
    if any(row.quantity.startswith("nonlinearity") for row in judged):
        budgets.pop("nonlinearity_percent_fs", None)  # stated once, with its limit and verdict
    results = readable_rows(budget_results(budgets, names=names)) + judged + sf_item_rows(r)
    tables = []
    if truth is not None:
        tables.append(
            Table(
                ["quantity", "measured", "twin truth"],
                [
                    ["scale factor S", _g(r.scale_factor, 8), _g(truth["ls_scale_factor"], 8)],
                    ["bias V0", _g(r.bias, 6), _g(truth["ls_bias"], 6)],
                    [
                        "nonlinearity NL (% FS)",
                        _g(r.nonlinearity_percent_fs, 4),
                        _g(truth["nonlinearity_percent_fs"], 4),
                    ],
                ],
                caption="Against the twin's truth",
            )
        )
    nl_bias = (
        f"{_g(r.nonlinearity_percent_fs_bias, 2)} % FS; less that bias "
        f"{_g(r.nonlinearity_percent_fs_bias_corrected, 4)} % FS"
        if np.isfinite(r.nonlinearity_percent_fs_bias)
        else "not known apart from the NL: not corrected"
    )
    tables.append(
        diagnostics_table(
            [
                ["full scale FS", f"{_g(r.full_scale_deg_s)} °/s"],
                ["rate points / samples", f"{r.n_points} / {r.samples_used}"],
                ["noise bias of NL", nl_bias],
                *_resolution_rows(r),
            ]
        )
    )
    paragraphs = [
        f"Unweighted least-squares line of the gyro's output against the set rate "
        f"({cite('kokuyama2015')}, §4); NL is the largest residual in % of full scale.",
        *(paragraph(n) for n in r.notes),
    ]
    if r.requirement is not None:
        paragraphs.append(paragraph(r.requirement.note))
    tables.append(
        Table(
            [
                "set rate (°/s)",
                "n",
                f"mean ({unit})",
                f"standard deviation ({unit})",
                f"standard error ({unit})",
                f"residual δ ({unit})",
                "δ (% FS)",
            ],
            [
                [
                    _g(p.rate_deg_s),
                    str(p.n),
                    _g(p.mean, 7),
                    _g(p.std, 4),
                    _g(p.standard_error, 3),
                    _g(p.residual, 4),
                    _g(p.residual_percent_fs, 4),
                ]
                for p in r.points
            ],
            caption="Rate points (diagnostics, not results)",
        )
    )
    tables += sf_item_tables(r)  # sign, runs, temperature (IEEE Std 952/1431)
    references = ["kokuyama2015", "ieee952", "ieee1431", "gum", "ilac_p14"]
    if r.requirement is not None:
        references += ["fmvss126", "ilac_g8"]
    return Section(
        title=title or "Gyro scale factor and nonlinearity",
        paragraphs=paragraphs,
        tables=tables,
        figures=[scale_factor_figure(r), *sf_item_figures(r)] if figures else [],
        anchor="gyro-scale",
        results=results,
        details=readable_tables(budget_details(r._budgets)),
        references=references,
    )
