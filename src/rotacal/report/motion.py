"""Report sections and figures for the sinusoidal-motion calibration (Feng et al. 2023).

:func:`motion_section` states one calibration: its results (each value ± U with k and p, from the
uncertainty budgets) go to the report's summary; the section holds what was analysed, the figures,
the harmonic amplitudes with their U, the diagnostics of the fit (not results) and the budgets,
folded. :func:`comparison_section` lays two schemes on the same runs out as the paper's Table 1.
"""

from __future__ import annotations

import math
import re
from collections.abc import Sequence
from typing import Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

from rotacal.glossary import GLOSSARY
from rotacal.numbers import coverage, fixed, format_plain, format_quantity
from rotacal.references import cite
from rotacal.report.html import Figure, ResultRow, Section, Table, figure_from_matplotlib
from rotacal.report.uncertainty import budget_details, budget_results, plain_name, result_row
from rotacal.report.wording import readable
from rotacal.table.motion import MotionResult, SchemeComparison
from rotacal.uncertainty import UncertaintyBudget, coverage_factor, round_ilac

__all__ = ["comparison_section", "motion_figures", "motion_section"]

_SCHEME_NAMES = {"encoder": "OSE", "lts": "LTS", "fog": "FOG", "angle": "angle readout"}
_COLORS = {"meas": "#1f5f99", "fit": "#d2691e", "rev_max": "#b22222", "rev_min": "#2e8b57"}


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
                label="multi-harmonic fit",
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
        f"{_SCHEME_NAMES[r.scheme]} scheme; the shaded span holds the {r.periods_used} whole periods "
        "the fit uses.",
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
        f"{format_plain(r.residual_rms_deg * 3600, 'arcsec', digits=3)} of displacement.",
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
    ax.set_ylabel(r"$A_h / A_1$ (%)")
    ax.set_ylim(max(1e-4, 0.3 * rel[rel > 0].min()), 200)
    ax.set_title(f"THD = {r.thd_percent:.3f} %", fontsize=10)
    _style(ax)
    return figure_from_matplotlib(
        fig,
        "Harmonic spectrum of the angular displacement",
        f"Relative to the fundamental; THD over h = 2…{r.harmonics}."
        + (" Displacement amplitudes from the rate fit." if r.scheme == "fog" else ""),
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
        f"Correction ({_correction_name(c.method)}): offsets {fixed(c.offset_a, 4)}, "
        f"{fixed(c.offset_b, 4)}; amplitude ratio {fixed(c.amplitude_b / c.amplitude_a, 6)}; "
        f"phase error {fixed(np.degrees(c.phase_error_rad), 4)}°.",
    )


def _position_error_figure(r: MotionResult) -> Figure | None:
    err = r._plot.get("position_error_deg")
    if err is None:
        return None
    t = np.linspace(r.analysis_start_s, r.analysis_stop_s, np.asarray(err).size)
    fig, ax = plt.subplots(figsize=(9.5, 2.6))
    ax.plot(t, np.asarray(err) * 3600, lw=0.8, color="#7a3b8f")
    ax.set_xlabel("time (s)")
    ax.set_ylabel("position error (arcsec)")
    _style(ax)
    return figure_from_matplotlib(
        fig,
        "Angular position error",
        "Measured displacement minus the ideal sinusoid of the set amplitude and frequency "
        f"({cite('feng2023')}, eq. 2).",
    )


def motion_figures(r: MotionResult, *, position_error: bool = True) -> list[Figure]:
    """Every figure of one motion calibration, in reading order; ``position_error=False`` leaves
    out the angular position error (a page that shows it for another scheme of the same run need
    not draw it twice: each figure costs a few tenths of a second)."""
    figs = [
        _motion_figure(r),
        _zoom_figure(r),
        _residual_figure(r),
        _spectrum_figure(r),
        _lissajous_figure(r),
        _position_error_figure(r) if position_error else None,
    ]
    return [f for f in figs if f is not None]


#: Coverage probability of every U this section states (that of the budgets).
_P = 0.95
_CORRECTIONS = {"heydemann": "Heydemann's ellipse fit"}
#: A snake_case token: a JSON key, replaced by its plain name where the glossary has one.
_KEY = re.compile(r"\b[a-z][a-z0-9]*(?:_[a-z0-9]+)+\b")


def _correction_name(method: str) -> str:
    return _CORRECTIONS.get(method, method)


def _plain_text(text: str) -> str:
    """``text`` for a reader: every JSON key the glossary knows written as its plain name, every
    number in fixed notation (:func:`~rotacal.report.wording.readable`; the JSON keeps the budgets'
    text as it is)."""
    text = readable(text)
    return _KEY.sub(
        lambda m: GLOSSARY[m.group()].name if m.group() in GLOSSARY else m.group(), text
    )


def _plain_table(t: Table) -> Table:
    """A budget table whose source names and notes say plain names, not JSON keys (the budgets'
    rows keep the keys in the JSON)."""
    return Table(
        t.columns,
        [[_plain_text(c) for c in row] for row in t.rows],
        caption=_plain_text(t.caption),
        first_column_header=t.first_column_header,
        note=_plain_text(t.note),
    )


def _fit_k(r: MotionResult) -> float:
    """Coverage factor for p = 95 % at the fit's ν = N − p (Type A quantities of the fit)."""
    return coverage_factor(float(r._plot.get("fit_dof", math.inf)), _P)


def _decimals(b: UncertaintyBudget) -> int:
    """Decimal places of the budget's value as ILAC-P14 rounds it (those of U to 2 digits)."""
    _, u_text = round_ilac(b.value, b.U)
    return len(u_text.split(".")[1]) if "." in u_text else 0


def _thd_note(r: MotionResult) -> str:
    """The THD's noise bias and bias-corrected value, to the decimal place of its U."""
    b = r._budgets.get("thd_percent")
    if b is None or not b.U > 0 or not math.isfinite(r.thd_percent_bias_corrected):
        return f"h = 2…{r.harmonics}"
    dec = _decimals(b)
    consistent = b.interval is not None and b.interval[0] <= 0.0
    return (
        f"h = 2…{r.harmonics}; bias-corrected: {r.thd_percent_bias_corrected:.{dec}f} %; noise "
        f"bias: {fixed(r.thd_percent_bias, 2)} percentage points"
        + ("; consistent with noise: the interval is an upper limit" if consistent else "")
    )


def _drift_rows(r: MotionResult) -> list[ResultRow]:
    """The fitted drift (--drift) as results: ± U with k for the fit's ν (Type A)."""
    k = _fit_k(r)
    rows = []
    if r.drift_deg_s is not None and r.drift_deg_s_u is not None:
        name = "rate offset D0 (drift and gyro bias)" if r.scheme == "fog" else "drift_deg_s"
        rows.append(
            result_row(name, r.drift_deg_s, "°/s", U=k * r.drift_deg_s_u, k=k, p=_P, note="fitted")
        )
    if r.rate_drift_deg_s2 is not None and r.rate_drift_deg_s2_u is not None:
        rows.append(
            result_row(
                "rate_drift_deg_s2",
                r.rate_drift_deg_s2,
                "°/s²",
                U=k * r.rate_drift_deg_s2_u,
                k=k,
                p=_P,
                note="fitted",
            )
        )
    return rows


def motion_results(r: MotionResult) -> list[ResultRow]:
    """The summary rows of one motion calibration: every budget's quantity as value ± U (the THD
    as its interval for the true value, with its bias as a note), then a fitted drift. The
    reversing moments are not a result: their count and U are in the section's analysis table."""
    budgets = {k: b for k, b in r._budgets.items() if k != "reversal_times_s"}
    notes = {"thd_percent": _thd_note(r)}
    if r.set_amplitude_deg is not None:
        against = f"against the set motion, {fixed(r.set_amplitude_deg)}° at "
        against += f"{fixed(r.set_frequency_hz)} Hz"
        for key in ("amplitude_error_percent", "frequency_error_percent"):
            notes[key] = against
        notes["angular_acceleration_error_percent"] = against
    return [*budget_results(budgets, notes=notes), *_drift_rows(r)]


def _analysis_table(r: MotionResult) -> Table:
    """What was analysed: counts and the span, the reversing moments' U — not results."""
    rows = [
        ["periods analysed", f"{r.periods_used} whole periods"],
        [
            "analysed span",
            f"{fixed(r.analysis_start_s)} s to {fixed(r.analysis_stop_s)} s, "
            f"{r.samples_used} samples",
        ],
        ["harmonics fitted", str(r.harmonics)],
    ]
    b = r._budgets.get("reversal_times_s")
    found = f"{r.reversal_times_s.size}"
    if b is not None and b.U > 0:
        each = format_quantity(b.U, "s", si_prefix=True, digits=2)  # 0.00012 s → 120 µs
        found += f", each located to ± {each} {coverage(b.k, b.p)}"
    rows.append(["reversing moments found", found])
    if r.set_amplitude_deg is not None:
        rows.append(
            [
                "set motion (the reference of the errors)",
                f"{fixed(r.set_amplitude_deg)}° at {fixed(r.set_frequency_hz)} Hz",
            ]
        )
    return Table(["", "value"], rows, caption="What was analysed")


def _harmonics_table(r: MotionResult) -> Table:
    """A_h ± U of every harmonic: h = 1 from the amplitude's budget, h ≥ 2 from the fit (Type A)."""
    amps = np.asarray(r.harmonic_amplitudes_deg, dtype=float)
    us = r._plot.get("harmonic_amplitudes_u_deg")
    k = _fit_k(r)
    big_u = np.full(amps.size, np.nan) if us is None else k * np.asarray(us, dtype=float)
    amp_budget = r._budgets.get("amplitude_deg")
    if amp_budget is not None:
        big_u[0] = amp_budget.U
    rows = []
    for h, (a, u_h) in enumerate(zip(amps, big_u, strict=True), 1):
        rel = 100.0 * a / amps[0]
        rel_u = 100.0 * u_h / amps[0] if h > 1 else None
        low = h > 1 and np.isfinite(u_h) and a < u_h
        rows.append(
            [
                str(h),
                format_quantity(a, U=u_h),
                format_quantity(rel, U=rel_u) if h > 1 else "100",
                "at the noise level" if low else "",
            ]
        )
    fog = " (displacement, from the rate fit)" if r.scheme == "fog" else ""
    return Table(
        ["h", "Aₕ ± U (°)", "Aₕ / A₁ ± U (%)", "remark"],
        rows,
        caption=f"Harmonic amplitudes of the angular displacement{fog}",
        note=f"U for k = {k:.2f}, p = 95 %. h = 1: the amplitude's full budget; h ≥ 2: the fit's "
        f"noise only (in-phase and quadrature components, {cite('ieee1057')}). An amplitude below "
        "its U is at the noise level: noise pushes it up, so read it as an upper limit.",
    )


def _diagnostics_table(r: MotionResult) -> Table:
    """The fit's residual, the SNR and the position error: what the capture looks like."""
    rows = [
        [
            "fit residual, rms (of the displacement)",
            format_plain(r.residual_rms_deg * 3600.0, "arcsec", digits=3),
        ]
    ]
    if r.snr_db is not None:
        rows.append(["signal-to-noise ratio of the rate", format_plain(r.snr_db, "dB", digits=3)])
    if r.position_error_max_deg is not None and r.position_error_rms_deg is not None:
        rows += [
            [
                "angular position error, largest",
                format_plain(r.position_error_max_deg * 3600.0, "arcsec", digits=4),
            ],
            [
                "angular position error, rms",
                format_plain(r.position_error_rms_deg * 3600.0, "arcsec", digits=4),
            ],
        ]
    return Table(
        ["", "value"],
        rows,
        caption="Diagnostics, not results",
        note="These describe the capture and the fit; they carry no uncertainty and are not "
        "calibration results. The residual holds the sensor's noise and what the fit does not "
        "model. The position error is the measured displacement minus the ideal sinusoid of the "
        f"set amplitude and frequency ({cite('feng2023')}, eq. 2): it holds the motion's harmonics "
        "and the sensor's noise and errors alike.",
    )


def _paragraphs(r: MotionResult) -> list[str]:
    """How the motion was measured, in words: the method, then the scheme's own steps."""
    fitted = (
        "The gyro's angular rate is fitted, and integrated analytically to the displacement,"
        if r.scheme == "fog"
        else "The angular displacement is fitted"
    )
    text = [
        f"{fitted} with {r.harmonics} harmonics of one frequency over {r.periods_used} whole "
        f"periods between reversing moments ({cite('feng2023')}, eqs. 7–14; the sine fit of "
        f"{cite('ieee1057')}). Every result is stated as value ± U with its "
        f"coverage factor k and probability p ({cite('gum')}); the THD's interval is evaluated by "
        f"Monte Carlo ({cite('gum_s1')}) because noise biases it upward."
    ]
    fit = r._fit
    for note in r.notes:
        if note.startswith("quadrature correction:"):
            method = note.split(":", 1)[1].strip()
            text.append(
                "The encoder's quadrature signals were corrected for offsets, amplitude ratio and "
                f"phase error ({_correction_name(method)}, {cite('heydemann1981')})."
                if method == "heydemann"
                else f"The encoder's quadrature signals were corrected: {method}."
            )
        elif note.startswith("rate bias D0"):
            if fit is not None and r.drift_deg_s is None:  # with --drift D0 is a result
                k = _fit_k(r)
                d0 = format_quantity(fit.offset, "°/s", U=k * fit.offset_u, k=k, p=_P)
                text.append(f"The gyro's rate bias D0 = {d0} was fitted and removed.")
        elif note.startswith("drift fitted"):
            text.append(
                "A linear drift was fitted beside the motion (--drift) and removed from it; it "
                "is stated with the results."
            )
        elif note.startswith("θ = arctan(D/R)"):
            radius = note.split("R =", 1)[1].strip()
            text.append(
                "The angle is θ = arctan(D/R) of the displacement D the laser triangulation sensor "
                f"reads at the radius R = {radius} from the table's axis ({cite('feng2023')}, "
                "eq. 15)."
            )
        else:
            text.append(_plain_text(note))
    return text


def motion_section(r: MotionResult, title: str | None = None, *, figures: bool = True) -> Section:
    """A report section for one motion calibration (Feng et al. 2023): the results as value ± U
    for the report's summary, what was analysed, the figures, the harmonic amplitudes with their
    U, the fit's diagnostics (not results), and one uncertainty budget per quantity, folded."""
    name = _SCHEME_NAMES.get(r.scheme, r.scheme)
    references = ["feng2023", "ieee1057", "gum", "gum_s1", "ilac_p14"]
    if r.scheme == "encoder":
        references.append("heydemann1981")
    return Section(
        title=title or f"Sinusoidal motion by {name}",
        paragraphs=_paragraphs(r),
        tables=[_analysis_table(r), _harmonics_table(r), _diagnostics_table(r)],
        figures=motion_figures(r) if figures else [],
        results=motion_results(r),
        details=[_plain_table(t) for t in budget_details(r._budgets)],
        references=references,
    )


def _thd_cell(value: float, budget: UncertaintyBudget | None) -> str:
    """A THD in a table cell: the value to the decimal place of its U, then its 95 % interval."""
    if budget is None or not budget.U > 0:
        return fixed(value, 4)
    text = format_quantity(value, U=budget.U, interval=budget.interval)
    return text.replace(", true value in ", " ")


def comparison_section(
    rows: Sequence[tuple[str, SchemeComparison, dict[str, Any] | None]],
    *,
    paper: Sequence[tuple[float, float, float]] | None = None,
) -> Section:
    """The comparison of schemes on the same runs, laid out like Feng et al. (2023) Table 1.

    ``rows``: (scenario label, comparison, truth or None). ``paper``: the paper's own
    (OSE-or-LTS, FOG, difference) THD values for the same scenarios, in %, shown beside rotacal's.
    Each THD is stated with its 95 % interval for the true THD; the difference of the two THDs is each
    row's result (± U, k, p); the amplitude and frequency differences are in the details.
    """
    feng = cite("feng2023")
    cols = ["scenario", "OSE (%)", "LTS (%)", "FOG (%)", "difference (pp)", "FOG SNR (dB)"]
    has_truth = any(t is not None for _, _, t in rows)
    if has_truth:
        cols.append("twin truth (%)")
    if paper is not None:
        cols += [f"{feng} Table 1: {s}" for s in ("OSE or LTS (%)", "FOG (%)", "difference (pp)")]
    body = []
    results = []
    others = []
    budgets = []
    for i, (label, c, truth) in enumerate(rows):
        b_ref, b_fog = c._thd_budgets if c._thd_budgets is not None else (None, None)
        combined = _thd_cell(c.thd_reference_percent, b_ref)
        diff = c._budgets.get("thd_difference_percent")
        row = [
            label,
            combined if c.reference_scheme == "encoder" else "—",
            combined if c.reference_scheme == "lts" else "—",
            _thd_cell(c.thd_other_percent, b_fog),
            format_quantity(c.thd_difference_percent, U=diff.U if diff else None),
            format_plain(c.snr_db, digits=3) if c.snr_db is not None else "—",
        ]
        if has_truth:
            row.append(fixed(truth["thd_percent"], 4) if truth else "—")
        if paper is not None:
            # as the paper prints them: two decimals
            row += [f"{paper[i][0]:.2f}", f"{paper[i][1]:.2f}", f"{paper[i][2]:+.2f}"]
        body.append(row)
        names = {key: f"{label}: {plain_name(key)}" for key in c._budgets}
        thd_only = {k: b for k, b in c._budgets.items() if k == "thd_difference_percent"}
        rest = {k: b for k, b in c._budgets.items() if k != "thd_difference_percent"}
        results += budget_results(thd_only, names=names)
        others += [[r.quantity, r.value, r.coverage] for r in budget_results(rest, names=names)]
        for t in budget_details(thd_only):
            t.caption = f"{label}: {t.caption[:1].lower()}{t.caption[1:]}"
            budgets.append(_plain_table(t))
    details = (
        [
            Table(
                ["quantity", "value ± U", "coverage"],
                others,
                caption="Amplitude and frequency differences of the two schemes",
            )
        ]
        if others
        else []
    ) + budgets
    return Section(
        title=f"THD by two schemes on the same runs (as {feng}, Table 1)",
        paragraphs=[
            "Each run is measured by the combined scheme (OSE for large amplitudes, LTS for the "
            "smallest) and by the FOG at the same time. The difference is combined minus FOG, in "
            "percentage points, ± its expanded uncertainty U at 95 % (the two THDs taken as "
            "independent): a difference beyond U is not explained by noise. The paper's own "
            "values are shown for comparison; the twin's motion was chosen to resemble them, so "
            "agreement with the twin's truth, not with the paper's digits, is what validates the "
            "methods."
        ],
        tables=[
            Table(
                cols,
                body,
                caption="THD of the angular displacement",
                note="A THD reads value [interval]: the 95 % coverage interval for the true THD "
                "(it is biased upward by noise, so the interval is not centred on the value).",
            )
        ],
        anchor="table1",
        results=results,
        details=details,
        references=["feng2023", "gum", "gum_s1", "ilac_p14"],
    )
