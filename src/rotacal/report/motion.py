"""Report sections and figures for the sinusoidal-motion calibration (seed 000)."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

from rotacal.report.html import Figure, Section, Table, figure_from_matplotlib
from rotacal.report.uncertainty import budget_tables, results_table
from rotacal.table.motion import MotionResult, SchemeComparison
from rotacal.uncertainty import round_ilac

__all__ = ["comparison_section", "motion_figures", "motion_section"]

_SCHEME_NAMES = {"encoder": "OSE", "lts": "LTS", "fog": "FOG"}
_COLORS = {"meas": "#1f5f99", "fit": "#d2691e", "rev_max": "#b22222", "rev_min": "#2e8b57"}


def _fmt(x: float | None, digits: int = 6) -> str:
    if x is None or not np.isfinite(x):
        return "—"
    return f"{x:.{digits}g}"


def _style(ax: Any) -> None:
    ax.grid(True, color="#e3e7eb", linewidth=0.7)
    ax.spines[["top", "right"]].set_visible(False)


def _motion_figure(r: MotionResult) -> Figure:
    p = r._plot
    fit = r._fit
    fig, ax = plt.subplots(figsize=(9.5, 3.6))
    t = p["t"]
    if r.scheme == "fog":
        ax.plot(
            t, p["rate_deg_s"], ".", ms=1.5, color=_COLORS["meas"], alpha=0.5, label="measured rate"
        )
        tt = np.linspace(r.analysis_start_s, r.analysis_stop_s, 4000)
        if fit is not None:
            ax.plot(
                tt,
                fit.evaluate(tt),
                color=_COLORS["fit"],
                lw=1.4,
                label="multi-harmonic fit (eq. 9)",
            )
        ax.set_ylabel("angular rate (°/s)")
        rev_y = np.zeros_like(r.reversal_times_s)
    else:
        ax.plot(t, p["angle_deg"], color=_COLORS["meas"], lw=1.0, label="measured θ")
        tt = np.linspace(r.analysis_start_s, r.analysis_stop_s, 4000)
        if fit is not None:
            ax.plot(
                tt, fit.evaluate(tt), "--", color=_COLORS["fit"], lw=1.2, label="multi-harmonic fit"
            )
        ax.set_ylabel("angular displacement (°)")
        rev_y = np.interp(r.reversal_times_s, t, p["angle_deg"])
    if r.scheme == "fog":  # zero crossings of the rate: a falling one is a maximum of θ
        is_max = fit.evaluate_derivative(r.reversal_times_s) < 0 if fit is not None else rev_y >= 0
    else:
        is_max = rev_y >= float(np.mean(p["angle_deg"]))
    for sel, marker, color, what in (
        (is_max, "v", "rev_max", "max"),
        (~is_max, "^", "rev_min", "min"),
    ):
        ax.plot(
            r.reversal_times_s[sel],
            rev_y[sel],
            marker,
            color=_COLORS[color],
            ms=6,
            label=f"reversing moments ({what} θ)",
        )
    ax.axvspan(
        r.analysis_start_s,
        r.analysis_stop_s,
        color="#f2f5d8",
        zorder=0,
        label=f"{r.periods_used} whole periods analysed",
    )
    ax.set_xlabel("time (s)")
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.18), fontsize=8, ncols=5, frameon=False)
    _style(ax)
    return figure_from_matplotlib(
        fig,
        "Motion, fitted curve and reversing moments",
        f"{_SCHEME_NAMES[r.scheme]} scheme. The shaded span holds the {r.periods_used} whole periods "
        f"bounded by {2 * r.periods_used + 1} reversing moments (seed §3.3) that the fit uses.",
    )


def _zoom_figure(r: MotionResult) -> Figure | None:
    """One reversing moment close up: the precise point of eqs. (7)–(8) on the samples."""
    p = r._plot
    if r.scheme == "fog" or r.reversal_times_s.size < 2:
        return None
    t, y = p["t"], p["angle_deg"]
    tr = r.reversal_times_s[r.reversal_times_s.size // 2]
    half = 0.04 / max(r.frequency_hz, 1e-9)
    m = (t > tr - half) & (t < tr + half)
    if m.sum() < 5:
        return None
    fig, ax = plt.subplots(figsize=(5.2, 3.2))
    ax.plot((t[m] - tr) * 1e3, y[m], ".-", ms=2, lw=0.6, color=_COLORS["meas"], label="measured θ")
    ax.axvline(0.0, color=_COLORS["rev_max"], lw=1, label="reversing moment")
    ax.set_xlabel(f"time from the reversing moment at {tr:.5f} s (ms)")
    ax.set_ylabel("θ (°)")
    ax.legend(fontsize=8)
    _style(ax)
    return figure_from_matplotlib(fig, "A reversing moment close up", "±4 % of a period around it.")


def _residual_figure(r: MotionResult) -> Figure:
    p = r._plot
    fig, ax = plt.subplots(figsize=(9.5, 2.8))
    if r.scheme == "fog":
        ax.plot(p["t_used"], p["residual_deg_s"], ".", ms=1.2, color="#555", alpha=0.6)
        ax.set_ylabel("rate residual (°/s)")
    else:
        ax.plot(p["t_used"], np.asarray(p["residual_deg"]) * 3600, lw=0.7, color="#555")
        ax.set_ylabel("θ residual (arcsec)")
    ax.set_xlabel("time (s)")
    _style(ax)
    return figure_from_matplotlib(
        fig,
        "Residuals of the fit",
        f"Measurement minus the {r.harmonics}-harmonic fit; rms "
        f"{r.residual_rms_deg * 3600:.3g} arcsec of displacement equivalent.",
    )


def _spectrum_figure(r: MotionResult) -> Figure:
    amps = np.asarray(r.harmonic_amplitudes_deg)
    h = np.arange(1, amps.size + 1)
    rel = 100 * amps / amps[0]
    fig, ax = plt.subplots(figsize=(6.2, 3.2))
    ax.bar(h, np.maximum(rel, 1e-6), color=["#1f5f99"] + ["#d2691e"] * (amps.size - 1))
    ax.set_yscale("log")
    ax.set_xticks(h)
    ax.set_xlabel("harmonic order h")
    ax.set_ylabel("A_h / A_1 (%)")
    ax.set_ylim(max(1e-4, 0.3 * rel[rel > 0].min()), 200)
    ax.set_title(f"THD = {r.thd_percent:.3f} %", fontsize=10)
    _style(ax)
    return figure_from_matplotlib(
        fig,
        "Harmonic spectrum of the angular displacement",
        "Amplitudes relative to the fundamental; THD over h = 2…N (eq. 1)."
        + (
            " Displacement amplitudes A'_h/(2πhf) from the rate fit (eq. 14)."
            if r.scheme == "fog"
            else ""
        ),
    )


def _lissajous_figure(r: MotionResult) -> Figure | None:
    p = r._plot
    if r.scheme != "encoder":
        return None
    a, b = p["lissajous_raw"]
    u, v = p["lissajous_corrected"]
    fig, axes = plt.subplots(1, 3, figsize=(12.5, 3.7), gridspec_kw={"width_ratios": [1, 1, 1.6]})
    th = np.linspace(0, 2 * np.pi, 400)
    pairs = ((a, b, "before correction (a, b)"), (u, v, "after correction (u, v)"))
    for ax, (x, y, title) in zip(axes[:2], pairs, strict=True):
        ax.plot(x, y, ".", ms=0.8, alpha=0.4, color=_COLORS["meas"])
        ax.plot(np.cos(th), np.sin(th), color=_COLORS["fit"], lw=0.6)
        ax.set_aspect("equal")
        ax.set_title(title, fontsize=10)
        _style(ax)
    # The errors Heydemann removes are small on a circle plot: show the radius against phase.
    ax = axes[2]
    # Raw signals as recorded (their mean is not their offset: the motion dwells at its reversals).
    for x, y, color, label in ((a, b, "#9a9a9a", "before"), (u, v, _COLORS["meas"], "after")):
        radius = np.hypot(x, y)
        ax.plot(
            np.degrees(np.arctan2(y, x)),
            100 * (radius / np.median(radius) - 1),
            ".",
            ms=0.8,
            color=color,
            label=label,
        )
    ax.set_xlabel("signal phase (°)")
    ax.set_ylabel("radius deviation (%)")
    ax.set_xticks(np.arange(-180, 181, 90))
    ax.legend(fontsize=8, markerscale=8)
    ax.set_title("radius against phase: what the correction removed", fontsize=10)
    _style(ax)
    c = p["correction"]
    return figure_from_matplotlib(
        fig,
        "Lissajous figure of the quadrature signals",
        f"Correction ({c.method}): offsets {c.offset_a:.4g}, {c.offset_b:.4g}; amplitude ratio "
        f"{c.amplitude_b / c.amplitude_a:.5f}; phase error {np.degrees(c.phase_error_rad):.3f}°.",
    )


def _position_error_figure(r: MotionResult) -> Figure | None:
    err = r._plot.get("position_error_deg")
    if err is None:
        return None
    t = np.linspace(r.analysis_start_s, r.analysis_stop_s, np.asarray(err).size)
    fig, ax = plt.subplots(figsize=(9.5, 2.6))
    ax.plot(t, np.asarray(err) * 3600, lw=0.8, color="#7a3b8f")
    ax.set_xlabel("time (s)")
    ax.set_ylabel("ap_err (arcsec)")
    _style(ax)
    return figure_from_matplotlib(
        fig,
        "Angular position error (eq. 2)",
        "Measured displacement minus the ideal sinusoid of set amplitude and frequency (phase and mean "
        f"from a 3-parameter fit at the set frequency); max {_fmt(r.position_error_max_deg, 4)}°, "
        f"rms {_fmt(r.position_error_rms_deg, 4)}°.",
    )


def motion_figures(r: MotionResult) -> list[Figure]:
    """Every figure of one motion calibration, in reading order."""
    figs = [
        _motion_figure(r),
        _zoom_figure(r),
        _residual_figure(r),
        _spectrum_figure(r),
        _lissajous_figure(r),
        _position_error_figure(r),
    ]
    return [f for f in figs if f is not None]


def _u(r: MotionResult, key: str, unit: str) -> str:
    b = r._budgets.get(key)
    return f"{b.u:.2g} {unit}" if b is not None else ""


def _thd_rows(r: MotionResult) -> list[list[str]]:
    """The THD as one statement: the plain value with its u, its noise bias, the bias-corrected
    value and the 95 % interval for the true THD — every number from the THD's budget, rounded
    to the decimal place of U (ILAC-P14 §5.4)."""
    b = r._budgets.get("thd_percent")
    plain = [f"THD (h = 2…{r.harmonics}), plain (eq. 1)", f"{r.thd_percent:.4f} %"]
    if b is None or b.interval is None or not b.U > 0:
        return [[*plain, f"{r.thd_percent_u:.2g} %"]]
    _, u_str = round_ilac(b.value, b.U)
    dec = len(u_str.split(".")[1]) if "." in u_str else 0
    lo, hi = b.interval
    if lo <= 0.0:
        where = f"[0, {hi:.{dec}f}] % (consistent with noise: an upper limit)"
    else:
        where = f"[{lo:.{dec}f}, {hi:.{dec}f}] %"
    return [
        [f"THD (h = 2…{r.harmonics}), plain (eq. 1)", f"{b.value:.{dec}f} %", f"{b.u:.2g} %"],
        ["THD, noise bias of the plain value (Monte Carlo)", f"{r.thd_percent_bias:+.2g} pp", ""],
        [
            "THD, bias-corrected (noise power removed)",
            f"{r.thd_percent_bias_corrected:.{dec}f} %",
            "",
        ],
        ["true THD, 95 % coverage interval", where, f"U = {u_str} % (half-width)"],
    ]


def motion_section(r: MotionResult, title: str | None = None, *, figures: bool = True) -> Section:
    """A report section for one motion calibration: results, errors against set values, figures,
    then the results with their expanded uncertainties and one uncertainty budget per quantity."""
    name = _SCHEME_NAMES.get(r.scheme, r.scheme)
    rows = [
        ["amplitude (fundamental)", f"{r.amplitude_deg:.7g} °", f"{r.amplitude_deg_u:.2g} °"],
        ["frequency", f"{r.frequency_hz:.9g} Hz", f"{r.frequency_hz_u:.2g} Hz"],
        [
            "angular-acceleration amplitude",
            f"{r.angular_acceleration_amplitude_deg_s2:.6g} °/s²",
            _u(r, "angular_acceleration_amplitude_deg_s2", "°/s²"),
        ],
        *_thd_rows(r),
        ["periods analysed", str(r.periods_used), ""],
        [
            "reversing moments found",
            str(r.reversal_times_s.size),
            _u(r, "reversal_times_s", "s") + (" each" if r._budgets else ""),
        ],
        ["fit residual (rms)", f"{r.residual_rms_deg * 3600:.3g} arcsec", ""],
    ]
    if r.snr_db is not None:
        rows.append(["SNR of the rate signal", f"{r.snr_db:.2f} dB", ""])
    if r.drift_deg_s is not None:  # --drift (rotacal.table.motion_drift)
        what = "rate offset D0 (drift + gyro bias)" if r.scheme == "fog" else "drift (fitted)"
        rows.append([what, f"{r.drift_deg_s:.6g} °/s", f"{r.drift_deg_s_u:.2g} °/s"])
    if r.rate_drift_deg_s2 is not None:
        rows.append(
            [
                "rate drift D1 (fitted)",
                f"{r.rate_drift_deg_s2:.6g} °/s²",
                f"{r.rate_drift_deg_s2_u:.2g} °/s²",
            ]
        )
    tables = [
        Table(
            ["quantity", "value", "standard uncertainty u (see the budgets)"],
            rows,
            caption="Results",
        )
    ]
    if r.set_amplitude_deg is not None:
        tables.append(
            Table(
                ["index", "error"],
                [
                    ["amplitude error", f"{_fmt(r.amplitude_error_percent, 4)} %"],
                    ["frequency error", f"{_fmt(r.frequency_error_percent, 4)} %"],
                    [
                        "angular-acceleration amplitude error",
                        f"{_fmt(r.angular_acceleration_error_percent, 4)} %",
                    ],
                    [
                        "angular position error, max |ap_err|",
                        f"{_fmt(r.position_error_max_deg, 4)} °",
                    ],
                    ["angular position error, rms", f"{_fmt(r.position_error_rms_deg, 4)} °"],
                ],
                caption=f"Against the set motion: {r.set_amplitude_deg:g}° at {r.set_frequency_hz:g} Hz",
            )
        )
    amps = np.asarray(r.harmonic_amplitudes_deg)
    tables.append(
        Table(
            ["h", "A_h (°)", "A_h / A_1 (%)"],
            [[str(h), f"{a:.4e}", f"{100 * a / amps[0]:.4f}"] for h, a in enumerate(amps, 1)],
            caption="Harmonic amplitudes of the angular displacement",
        )
    )
    tables.extend(budget_tables(r._budgets))
    return Section(
        title=title or f"Sinusoidal motion by {name}",
        paragraphs=list(r.notes),
        tables=tables,
        figures=motion_figures(r) if figures else [],
    )


def comparison_section(
    rows: Sequence[tuple[str, SchemeComparison, dict[str, Any] | None]],
    *,
    paper: Sequence[tuple[float, float, float]] | None = None,
) -> Section:
    """The comparison of schemes on the same runs, laid out like Feng et al. (2023) Table 1.

    ``rows``: (scenario label, comparison, truth or None). ``paper``: the seed's own
    (OSE-or-LTS, FOG, difference) THD values for the same scenarios, shown beside rotacal's.
    """
    cols = ["scenario", "OSE (%)", "LTS (%)", "FOG (%)", "difference (pp)", "FOG SNR (dB)"]
    has_truth = any(t is not None for _, _, t in rows)
    if has_truth:
        cols.append("twin truth (%)")
    if paper is not None:
        cols += ["paper: OSE/LTS", "paper: FOG", "paper: diff."]
    body = []
    for i, (label, c, truth) in enumerate(rows):
        ose = f"{c.thd_reference_percent:.3f}" if c.reference_scheme == "encoder" else "—"
        lts = f"{c.thd_reference_percent:.3f}" if c.reference_scheme == "lts" else "—"
        row = [
            label,
            ose,
            lts,
            f"{c.thd_other_percent:.3f}",
            f"{c.thd_difference_percent:+.3f} ± {c.thd_difference_percent_u:.2g}"
            + (f" (U = {c._budgets['thd_difference_percent'].U:.2g})" if c._budgets else ""),
            _fmt(c.snr_db, 3),
        ]
        if has_truth:
            row.append(f"{truth['thd_percent']:.3f}" if truth else "—")
        if paper is not None:
            row += [f"{paper[i][0]:.2f}", f"{paper[i][1]:.2f}", f"{paper[i][2]:+.2f}"]
        body.append(row)
    return Section(
        title="THD by two schemes on the same runs (as the seed's Table 1)",
        paragraphs=[
            "Each run is measured by the combined scheme (OSE for large amplitudes, LTS for the "
            "smallest) and by the FOG at the same time. The difference is combined minus FOG, in "
            "percentage points, ± its standard uncertainty (each THD's by Monte Carlo, the two "
            "taken as independent) and the expanded uncertainty U at 95 % (a difference beyond U "
            "is not explained by noise). The paper's own values are shown for comparison; the "
            "twin's motion was chosen to resemble them, so agreement with the twin's truth, not "
            "with the paper's digits, is what validates the methods."
        ],
        tables=[
            Table(cols, body, caption="THD of the angular displacement"),
            *(
                results_table(c._budgets, caption=f"{label}: differences with their U (ILAC-P14)")
                for label, c, _ in rows
                if c._budgets
            ),
        ],
        anchor="table1",
    )
