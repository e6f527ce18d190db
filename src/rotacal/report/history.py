"""The report of an item's calibration history (``rotacal records history SERIAL --report``).

Per reported quantity one figure: each calibration's value with its U bar against the calibration
date (superseded certificates hollow and grey: listed, not fitted), the acceptance limits of the
latest certificate, the drift line with its expanded-uncertainty band (k = 2) and the date the
item is next due. Then the table of the calibrations as their certificates printed them.
"""

from __future__ import annotations

import datetime as dt
from collections.abc import Sequence

import matplotlib

matplotlib.use("Agg")
import matplotlib.dates as mdates
import matplotlib.pyplot as plt
import numpy as np

from rotacal.numbers import fixed
from rotacal.records.history import Calibration, Drift, ItemHistory, ReportedResult
from rotacal.records.trend import SIGNIFICANCE_K, years_since
from rotacal.references import cite
from rotacal.report.html import Figure, Report, ResultRow, Section, Table, figure_from_matplotlib
from rotacal.report.uncertainty import result_row

__all__ = ["history_report"]

_FITTED = "#1f5f99"
_SUPERSEDED = "#9aa3ad"
_LIMIT = "#a4161a"
_DUE = "#b8860b"
#: More calibrations than this: smaller markers without caps, and the table folded away.
_MANY = 40


def _points(
    key: str, calibrations: Sequence[Calibration], unit: str
) -> tuple[list[tuple[dt.date, ReportedResult]], list[tuple[dt.date, ReportedResult]]]:
    """The plotted values of ``key`` in ``unit``: (fitted, superseded)."""
    fitted: list[tuple[dt.date, ReportedResult]] = []
    superseded: list[tuple[dt.date, ReportedResult]] = []
    for c in calibrations:
        r = c.results.get(key)
        if r is None or r.value is None or r.unit != unit:
            continue
        (superseded if c.superseded_by is not None else fitted).append((c.date, r))
    return fitted, superseded


def _bars(points: Sequence[tuple[dt.date, ReportedResult]]) -> np.ndarray:
    """The U bars (below, above) of each point: ± U, or the stated coverage interval."""
    below, above = [], []
    for _, r in points:
        assert r.value is not None
        if r.interval is not None:
            below.append(r.value - r.interval[0])
            above.append(r.interval[1] - r.value)
        else:
            below.append(r.U or 0.0)
            above.append(r.U or 0.0)
    return np.array([below, above])


def _days(dates: Sequence[dt.date]) -> np.ndarray:
    return np.array(dates, dtype="datetime64[D]")


def _plot_values(
    ax: plt.Axes, points: Sequence[tuple[dt.date, ReportedResult]], **style: object
) -> None:
    if points:
        ax.errorbar(
            _days([d for d, _ in points]),
            np.array([r.value for _, r in points], dtype=float),
            yerr=_bars(points),
            fmt="o",
            ms=4 if len(points) <= _MANY else 2,
            capsize=3 if len(points) <= _MANY else 0,  # caps on hundreds of bars make a blur
            elinewidth=1,
            **style,  # type: ignore[arg-type]
        )


def _plot_drift(ax: plt.Axes, drift: Drift, start: dt.date, end: dt.date) -> None:
    """The fitted line and its band ŷ ± 2 u(ŷ) from ``start`` to ``end``."""
    days = np.linspace(0, (end - start).days, 240).round().astype("timedelta64[D]")
    dates = np.datetime64(start, "D") + days
    predicted, u_predicted = drift.line.predict(years_since(dates, drift.origin))
    style = "-" if drift.significant else "--"
    value, u = drift.rounded()
    label = (
        f"drift {value} {drift.unit} (u = {u}), "
        f"{'significant' if drift.significant else 'not significant'}"
    )
    ax.fill_between(
        dates,
        predicted - SIGNIFICANCE_K * u_predicted,
        predicted + SIGNIFICANCE_K * u_predicted,
        color="#9fb7cf",
        alpha=0.4,
        lw=0,
        label="predicted value ± 2 u",
    )
    # above the points: with hundreds of calibrations their bars would hide it
    ax.plot(dates, predicted, style, color=_FITTED, lw=1.4, label=label, zorder=4)


def _figure(history: ItemHistory, key: str, title: str) -> Figure | None:
    latest = [c.results[key] for c in history.calibrations if key in c.results][-1]
    unit = latest.unit
    fitted, superseded = _points(key, history.calibrations, unit)
    if not fitted and not superseded:
        return None
    drift = history.drift_per_year.get(key)
    due = history.next_due
    dates = [d for d, _ in (*fitted, *superseded)]
    start = min(dates)
    end = max(max(dates), due.date, history._fixed_due)
    reaches = drift.reaches if drift is not None else None
    if reaches is not None and start <= reaches <= end + (end - start):
        end = max(end, reaches)  # show where the drift reaches its limit, if not far beyond
    else:
        reaches = None
    margin = dt.timedelta(days=max(30, (end - start).days // 25))
    fig, ax = plt.subplots(figsize=(7.8, 4.4))
    if drift is not None:
        _plot_drift(ax, drift, start, end)
    _plot_values(ax, fitted, color=_FITTED, label="calibration: value ± U (as printed)")
    _plot_values(ax, superseded, color=_SUPERSEDED, mfc="white", label="superseded (not fitted)")
    low, high = drift.limits if drift is not None else (latest.limit_min, latest.limit_max)
    unit_text = f" {unit}" if unit else ""
    for limit, side in ((low, "lower"), (high, "upper")):
        if limit is not None:
            ax.axhline(
                limit,
                color=_LIMIT,
                ls="--",
                lw=1.1,
                label=f"{side} limit {fixed(limit)}{unit_text}",
            )
    what = (
        "fixed interval"
        if due.quantity is None
        else "drift"
        if due.quantity == key
        else f"drift of “{due.quantity}”"
    )
    ax.axvline(mdates.date2num(due.date), color=_DUE, lw=1.4, label=f"next due {due.date} ({what})")
    if reaches is not None and reaches != due.date:
        ax.axvline(
            mdates.date2num(reaches),
            color=_LIMIT,
            ls=":",
            lw=1.2,
            label=f"prediction ± 2 u reaches the limit {reaches}",
        )
    ax.set_xlim(mdates.date2num(start - margin), mdates.date2num(end + margin))
    locator = mdates.AutoDateLocator(minticks=4, maxticks=9)
    ax.xaxis.set_major_locator(locator)
    ax.xaxis.set_major_formatter(mdates.ConciseDateFormatter(locator))
    ax.set_xlabel("calibration date")
    ax.set_ylabel(f"{latest.name} ({unit})" if unit else latest.name)
    ax.grid(True, color="#e3e7eb", linewidth=0.6)
    ax.spines[["top", "right"]].set_visible(False)
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8, frameon=False)
    caption = [
        _count(len(fitted), "calibration")
        + (f" and {len(superseded)} superseded (not fitted)" if superseded else "")
        + ". Bars: the expanded uncertainty U each certificate states."
    ]
    if drift is not None:
        caption.append(
            "Line: the straight-line drift fitted by weighted least squares (weights 1/u²) to "
            "the calibrations that were not superseded; band: its prediction ± 2 u."
        )
    if low is not None or high is not None:
        caption.append("Limits: those of the latest certificate.")
    return figure_from_matplotlib(fig, title, " ".join(caption))


def _count(n: int, noun: str) -> str:
    return f"{n} {noun}" if n == 1 else f"{n} {noun}s"


def _title(history: ItemHistory, key: str) -> str:
    latest = [c.results[key] for c in history.calibrations if key in c.results][-1]
    name = latest.name or key
    if name == key:  # the certificate names it by its key
        return f"“{key}”" if "_" in key else key
    return f"{name} (“{key}”)"


def _drift_text(key: str, drift: Drift | None) -> str:
    if drift is None:
        return (
            f"“{key}”: no drift — it needs values from at least two calibrations on different "
            "dates that were not superseded."
        )
    birge = (
        f"Birge ratio R = {drift.birge_ratio:.2f}"
        + ("; u is multiplied by R because R > 1" if drift.line.scaled else "")
        if drift.birge_ratio is not None
        else "two calibrations leave no residual to judge the scatter by"
    )
    verdict = "significant" if drift.significant else "not significant"
    value, u = drift.rounded()
    return (
        f"Drift: {value} {drift.unit} with standard uncertainty {u} {drift.unit} over {drift.n} calibrations ({birge}); "
        f"{verdict} (|b| {'>' if drift.significant else '≤'} 2 u(b))."
    )


def _printed(r: ReportedResult | None) -> str:
    if r is None:
        return ""
    value, U = r.printed
    unit = f" {r.unit}" if r.unit else ""
    verdict = f" ({r.verdict})" if r.verdict else ""
    k = f" (k = {fixed(r.k, 3)})" if r.k is not None and r.k != 2.0 else ""
    return f"{value} ± {U}{unit}{k}{verdict}"


def _calibrations_table(history: ItemHistory, keys: Sequence[str]) -> Table:
    rows = [
        [
            c.number,
            c.date.isoformat(),
            c.issue_date.isoformat(),
            c.supersedes or "",
            c.superseded_by or "",
            *(_printed(c.results.get(key)) for key in keys),
        ]
        for c in history.calibrations
    ]
    return Table(
        ["certificate", "calibrated", "issued", "supersedes", "superseded by"]
        + [f"“{key}”" for key in keys],
        rows,
        caption=f"The {len(rows)} calibrations, oldest first: each value ± U as its certificate "
        "printed it",
        note="U is the expanded uncertainty the certificate states, for k = 2 unless another k "
        "is given; the verdict is the certificate's conformity statement where its plan set a limit. A "
        "superseded certificate stays in the records; its correction replaces it in the drift.",
    )


def _summary(history: ItemHistory) -> list[ResultRow]:
    due = history.next_due
    rows = [
        ResultRow(
            "next calibration due",
            due.date.isoformat(),
            note=f"set by the drift of {due.quantity}" if due.quantity else "fixed interval",
        )
    ]
    for key, drift in history.drift_per_year.items():
        rows.append(
            result_row(
                f"drift of {_title(history, key)}",
                drift.value,
                drift.unit,
                U=SIGNIFICANCE_K * drift.u,
                k=SIGNIFICANCE_K,
                note="significant" if drift.significant else "not significant",
            )
        )
    return rows


def history_report(history: ItemHistory, store: str) -> Report:
    """The HTML report of an item's calibration history.

    Parameters
    ----------
    history : ItemHistory
        What :func:`rotacal.records.history.item_history` found.
    store : str
        The records store as messages show it (its URL without a password).
    """
    item = history.item
    keys = list(dict.fromkeys(key for c in history.calibrations for key in c.results))
    due = history.next_due
    intro = Section(
        title="Next calibration due",
        anchor="next-due",
        paragraphs=[
            f"Next due: {due.date}. {due.method}",
            "Method: each quantity's values of the certificates that were not superseded are "
            "fitted with a straight line against the calibration date by weighted least squares "
            "(weights 1/u², u = U/k as printed); u of the drift comes from the fit's covariance "
            "and, with more than two calibrations, is multiplied by the Birge ratio "
            "R = √(χ²/(n − 2)) when R > 1. A drift is significant when |b| > 2 u(b). For each "
            "quantity with a significant drift and an acceptance limit on its latest certificate, "
            "the date at which the predicted value plus (minus, for a lower limit) its expanded "
            "uncertainty (k = 2) reaches the limit is found; the earliest such date is the next "
            f"due date when it comes before the laboratory's fixed interval of "
            f"{history._interval_months} months after the last calibration. Drift may shorten "
            "that interval, never lengthen it: lengthening it is for the laboratory's interval "
            f"review ({cite('ilac_g24')}, method 2 uses drift this way; {cite('ncsl_rp1')}, "
            f"variables data). The straight line follows {cite('gum')} H.3 and "
            f"{cite('iso_ts28037')} §6; the Birge ratio {cite('birge1932')}.",
        ],
        results=_summary(history),
        references=["ilac_g24", "ncsl_rp1", "gum", "iso_ts28037", "birge1932"],
    )
    sections = [intro]
    for key in keys:
        title = _title(history, key)
        figure = _figure(history, key, title)
        sections.append(
            Section(
                title=title,
                anchor=f"q-{len(sections)}",
                paragraphs=[_drift_text(key, history.drift_per_year.get(key))],
                figures=[figure] if figure is not None else [],
            )
        )
    table = _calibrations_table(history, keys)
    sections.append(
        Section(
            title="Calibrations",
            anchor="calibrations",
            tables=[] if len(history.calibrations) > _MANY else [table],
            details=[table] if len(history.calibrations) > _MANY else [],
        )
    )
    return Report(
        title=f"Calibration history of {item['manufacturer']} {item['model']}, serial "
        f"{history.serial}",
        subtitle=f"{item['kind']} · {len(history.calibrations)} certificates in the records "
        f"store {store}",
        sections=sections,
        inputs={"records store": store, "serial": history.serial},
        warnings=list(history.warnings),
    )
