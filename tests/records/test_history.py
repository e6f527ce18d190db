"""An item's history on both engines: the drift per year and its u against closed forms and an
independent solver, next_due against dates worked out by hand, supersession, ambiguous and
unknown serials, and the report.

Dates four years apart are 1461 days = exactly 4 years of 365.25 days, so points on such dates sit
exactly on a line in time and the closed forms below hold to rounding.
"""

from __future__ import annotations

import dataclasses
import datetime as dt
import json
import math
import re
from pathlib import Path

import numpy as np
import pytest
import sqlalchemy as sa
from tests.records.conftest import files_of, make_content
from tests.report.test_report_text import faults

from rotacal.certificate.content import ReportedQuantity
from rotacal.errors import ConfigError
from rotacal.plan.model import Item
from rotacal.records import open_store
from rotacal.records.history import item_history
from rotacal.records.trend import add_months, fit_drift, limit_crossing
from rotacal.report.history import history_report
from rotacal.report.html import write_html

D2012, D2016, D2020, D2024 = (dt.date(y, 1, 1) for y in (2012, 2016, 2020, 2024))


def _keep(store, content):
    """Keep ``content`` with the next number (as certify does)."""
    content = dataclasses.replace(content, number=store.draw_number(content.plan.issue_date))
    with store.keep(content, files_of(content)):
        pass
    return content


def _with_item(content, manufacturer="Gyro Maker Ltd", model="GM-300"):
    plan = dataclasses.replace(
        content.plan,
        item=Item("gyroscope", manufacturer, model, content.plan.item.serial),
        text=content.plan.text + f" {manufacturer} {model}".encode(),
    )
    return dataclasses.replace(content, plan=plan)


def _years(day: dt.date, origin: dt.date = D2024) -> float:
    return (day - origin).days / 365.25


# -- the fit -------------------------------------------------------------------------------------


def test_points_on_a_line_give_its_slope_and_the_weighted_u(store_url, issue) -> None:
    store = open_store(store_url)
    points = [(D2012, "10.0", "0.20"), (D2016, "12.0", "0.40"), (D2020, "14.0", "0.20")]
    points.append((D2024, "16.0", "0.80"))
    for day, value, U in points:
        issue(store, {"scale_factor": (value, U)}, number="auto", date=day)
    drift = item_history(store, "SN-0001", today=D2024).drift_per_year["scale_factor"]
    # closed form of a weighted straight line: u²(b) = 1 / (Σw t² − (Σw t)²/Σw), w = (k/U)²
    t = np.array([-12.0, -8.0, -4.0, 0.0])
    w = (2.0 / np.array([0.20, 0.40, 0.20, 0.80])) ** 2
    u_b = 1.0 / math.sqrt((w * t * t).sum() - (w * t).sum() ** 2 / w.sum())
    assert drift.value == pytest.approx(0.5, abs=1e-12)
    assert drift.u == pytest.approx(u_b, rel=1e-12)
    assert drift.birge_ratio == pytest.approx(0.0, abs=1e-6)  # on the line: no scatter
    assert (drift.n, drift.significant, drift.unit) == (4, True, "ppm/year")


def test_two_calibrations_give_the_difference_quotient(store_url, issue) -> None:
    store = open_store(store_url)
    issue(store, {"bias": ("10.0", "0.60")}, number="auto", date=D2020)
    issue(store, {"bias": ("12.0", "0.80")}, number="auto", date=D2024)
    drift = item_history(store, "SN-0001", today=D2024).drift_per_year["bias"]
    # b = Δy/Δt; u(b) = √(u₁² + u₂²)/Δt with u = U/2
    assert drift.value == pytest.approx(2.0 / 4.0, rel=1e-12)
    assert drift.u == pytest.approx(math.hypot(0.30, 0.40) / 4.0, rel=1e-12)
    assert drift.birge_ratio is None and drift.n == 2


def test_scatter_beyond_the_uncertainties_scales_u_by_the_birge_ratio(store_url, issue) -> None:
    store = open_store(store_url)
    for day, value in ((D2016, "10"), (D2020, "13"), (D2024, "14")):
        issue(store, {"scale_factor": (value, "0.20")}, number="auto", date=day)
    history = item_history(store, "SN-0001", today=D2024)
    drift = history.drift_per_year["scale_factor"]
    # by hand: t = −8, −4, 0 (t̄ = −4), y = 10, 13, 14: b = (−4·10 + 4·14)/32 = 0.5; residuals
    # −1/3, 2/3, −1/3 → χ² = (2/3)/0.1² = 200/3, R = √(200/3 / 1); u(b) = R·0.1/√32 = √(1/48)
    assert drift.value == pytest.approx(0.5, rel=1e-12)
    assert drift.birge_ratio == pytest.approx(math.sqrt(200.0 / 3.0), rel=1e-12)
    assert drift.u == pytest.approx(math.sqrt(1.0 / 48.0), rel=1e-12)
    assert any("Birge ratio 8.16" in w for w in history.warnings)


@pytest.mark.parametrize("spread", [0.05, 3.0], ids=["within-u", "beyond-u"])
def test_equal_weights_agree_with_numpy_polyfit(store_url, issue, spread) -> None:
    store = open_store(store_url)
    days = [dt.date(2017, 5, 3), dt.date(2018, 2, 11), dt.date(2019, 7, 30)]
    days += [dt.date(2020, 12, 1), dt.date(2022, 6, 15), dt.date(2023, 9, 9)]
    wiggle = np.array([0.3, -1.0, 0.6, 0.9, -0.7, 0.1]) * spread
    values = [round(50.0 - 1.3 * _years(d) + e, 3) for d, e in zip(days, wiggle, strict=True)]
    for day, value in zip(days, values, strict=True):
        issue(store, {"scale_factor": (f"{value:.3f}", "0.50")}, number="auto", date=day)
    drift = item_history(store, "SN-0001", today=D2024).drift_per_year["scale_factor"]
    t = np.array([_years(d, days[-1]) for d in days])
    scaled = drift.birge_ratio is not None and drift.birge_ratio > 1.0
    assert scaled == (spread > 1.0)
    coef, cov = np.polyfit(t, values, 1, w=np.full(6, 1 / 0.25), cov=True if scaled else "unscaled")
    assert drift.value == pytest.approx(coef[0], rel=1e-9)
    assert drift.u == pytest.approx(math.sqrt(cov[0, 0]), rel=1e-9)


def test_iso_ts_28037_example_as_a_peer_program_gives_it() -> None:
    """The example of ISO/TS 28037:2010 clause 6 (uncertainties in y only, equal weights), as
    GTC's line_fit_wls prints it: intercept 1.87 (u 0.47), slope 1.76 (u 0.12), Σ w r² = 1.66476."""
    line = fit_drift(np.arange(1.0, 7.0), [3.3, 5.6, 7.1, 9.3, 10.7, 12.1], np.full(6, 0.5))
    intercept, u_intercept = line.predict(0.0)
    assert round(line.slope, 2) == 1.76 and round(line.u_slope, 2) == 0.12
    assert round(float(intercept), 2) == 1.87 and round(float(u_intercept), 2) == 0.47
    assert line.chi2 == pytest.approx(1.66476, abs=5e-6)
    assert not line.scaled  # R = √(1.66/4) < 1: the stated u are kept


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_the_crossing_agrees_with_bisection_on_the_full_covariance(seed: int) -> None:
    """The band ŷ + 2u(ŷ) from numpy.polyfit's parameters and covariance at t = 0 (intercept and
    slope correlated, scaled as the fit scales) reaches the limit where limit_crossing says."""
    rng = np.random.default_rng(seed)
    t = np.sort(rng.uniform(-9.0, 0.0, 7))
    u = rng.uniform(0.2, 0.6, 7)
    y = 5.0 + 0.8 * t + rng.normal(0.0, 1.0, 7) * u * (3.0 if seed == 3 else 1.0)
    line = fit_drift(t, y, u)
    (slope, intercept), cov = np.polyfit(t, y, 1, w=1 / u, cov=True if line.scaled else "unscaled")

    def edge(x: float) -> float:
        g = np.array([x, 1.0])
        return intercept + slope * x + 2.0 * math.sqrt(g @ cov @ g) - 12.0

    low, high = 0.0, 100.0
    assert edge(low) < 0 < edge(high)
    for _ in range(200):
        mid = 0.5 * (low + high)
        low, high = (mid, high) if edge(mid) < 0 else (low, mid)
    assert limit_crossing(line, 12.0, upper=True) == pytest.approx(low, abs=1e-9)
    assert line.scaled == (seed == 3)


def test_a_drift_away_from_the_limit_never_reaches_it() -> None:
    line = fit_drift([-8.0, 0.0], [14.0, 6.0], [0.4, 0.4])
    assert limit_crossing(line, 20.0, upper=True) is None
    assert limit_crossing(line, 0.0, upper=False) is not None


@pytest.mark.parametrize(
    ("day", "months", "due"),
    [
        (dt.date(2024, 1, 31), 1, dt.date(2024, 2, 29)),
        (dt.date(2023, 1, 31), 1, dt.date(2023, 2, 28)),
        (dt.date(2023, 11, 30), 3, dt.date(2024, 2, 29)),
        (dt.date(2025, 12, 15), 12, dt.date(2026, 12, 15)),
        (dt.date(2025, 5, 31), 18, dt.date(2026, 11, 30)),
    ],
)
def test_months_are_calendar_months(day, months, due) -> None:
    assert add_months(day, months) == due


# -- next due ------------------------------------------------------------------------------------

#: Two calibrations on 2016-01-01 and two on 2024-01-01, each with U = 1.6 (k = 2, u = 0.8):
#: t̄ = −4 years, the value there â = 10 with u(â) = 0.8/√4 = 0.4, |b| = 8/8 = 1 per year with
#: u(b) = 0.8/√(4·4²) = 0.1. The band's edge â ± (b·s + 2√(0.4² + (0.1 s)²)) at s = 7.5 years is
#: 10 ± (7.5 + 2·0.85) = 10 ± 9.2, so a limit of 19.2 (rising) or 0.8 (falling) is reached at
#: t = −4 + 7.5 = 3.5 years = 1278.375 days after 2024-01-01: on 2027-07-02. With limits 14 and
#: 6 the edge is there at s = 3 (10 ± (3 + 2·0.5)): t = −1 year = −365.25 days → 2022-12-31.
_DRIFTING = {"rising": ("6.0", "14.0", 1), "falling": ("14.0", "6.0", 0)}


def _drifting(store, issue, direction: str, limit: str) -> None:
    first, last, side = _DRIFTING[direction]
    limits = ("", limit) if side else (limit, "")
    for day, value in ((D2016, first), (D2016, first), (D2024, last), (D2024, last)):
        issue(
            store,
            {"scale_factor": (value, "1.6"), "bias": ("0.5", "0.2")},
            number="auto",
            date=day,
            limits={"scale_factor": limits, "bias": ("-1", "1")},
        )


@pytest.mark.parametrize(("direction", "limit"), [("rising", "19.2"), ("falling", "0.8")])
def test_a_drift_sets_next_due_where_its_band_reaches_the_limit(
    store_url, issue, direction, limit
) -> None:
    store = open_store(store_url)
    store.set_settings(interval_months="60")  # fixed interval: 2029-01-01
    _drifting(store, issue, direction, limit)
    history = item_history(store, "SN-0001", today=dt.date(2026, 1, 1))
    assert history.next_due.date == dt.date(2027, 7, 2)
    assert history.next_due.quantity == "scale_factor"
    assert "on 2027-07-02" in history.next_due.method
    assert f"limit {limit} ppm" in history.next_due.method
    assert "2029-01-01" in history.next_due.method
    assert history.warnings == ()
    assert history.drift_per_year["bias"].significant is False


def test_a_later_drift_date_never_lengthens_the_fixed_interval(store_url, issue) -> None:
    store = open_store(store_url)
    _drifting(store, issue, "rising", "19.2")
    history = item_history(store, "SN-0001", today=dt.date(2024, 6, 1))
    assert history.next_due.date == dt.date(2025, 1, 1)  # 12 months after 2024-01-01
    assert history.next_due.quantity is None
    assert "fixed interval of 12 months" in history.next_due.method
    assert "only on 2027-07-02" in history.next_due.method
    assert "never lengthen" in history.next_due.method
    later = item_history(store, "SN-0001", today=dt.date(2025, 1, 2))
    assert "the item is overdue for calibration since 2025-01-01" in later.warnings


def test_a_band_already_past_its_limit_is_due_then_and_warns(store_url, issue) -> None:
    store = open_store(store_url)
    _drifting(store, issue, "rising", "14")
    history = item_history(store, "SN-0001", today=dt.date(2024, 2, 1))
    assert history.next_due.date == dt.date(2022, 12, 31)
    assert history.next_due.quantity == "scale_factor"
    assert any("predicted out of tolerance since 2022-12-31" in w for w in history.warnings)


def test_no_significant_drift_leaves_the_fixed_interval(store_url, issue) -> None:
    store = open_store(store_url)
    store.set_settings(interval_months="1")
    days = [dt.date(2021, 3, 15), dt.date(2022, 3, 20), dt.date(2023, 3, 10), dt.date(2024, 1, 31)]
    for day, value in zip(days, ["10.0", "10.1", "9.9", "10.0"], strict=True):
        issue(
            store,
            {"scale_factor": (value, "1.0")},
            number="auto",
            date=day,
            limits={"scale_factor": ("9", "11")},
        )
    history = item_history(store, "SN-0001", today=dt.date(2024, 2, 1))
    drift = history.drift_per_year["scale_factor"]
    assert not drift.significant and abs(drift.value) <= 2 * drift.u
    assert history.next_due.date == dt.date(2024, 2, 29)  # a month after 31 January
    assert history.next_due.quantity is None
    assert "no quantity with a limit drifts significantly" in history.next_due.method


# -- what enters the fit, and what the history lists -----------------------------------------------


def test_a_superseded_certificate_is_listed_but_not_fitted(store_url, issue) -> None:
    store = open_store(store_url)
    issue(store, {"scale_factor": ("10.0", "0.20")}, number="auto", date=D2016)
    wrong = issue(store, {"scale_factor": ("30.0", "0.20")}, number="auto", date=D2020)
    issue(store, {"scale_factor": ("14.0", "0.20")}, number="auto", date=D2024)
    fix = issue(
        store,
        {"scale_factor": ("12.0", "0.20")},
        number="auto",
        date=D2020,
        supersedes=wrong.number,
    )
    history = item_history(store, "SN-0001", today=D2024)
    listed = {c.number: c for c in history.calibrations}
    assert listed[wrong.number].superseded_by == fix.number
    assert listed[wrong.number].results["scale_factor"].value == 30.0
    assert listed[fix.number].supersedes == wrong.number
    drift = history.drift_per_year["scale_factor"]
    assert drift.n == 3 and drift.value == pytest.approx(0.5, abs=1e-12)  # 10, 12, 14 in 8 years


def test_a_correction_under_another_serial_still_marks_the_original(store_url, issue) -> None:
    store = open_store(store_url)
    wrong = issue(store, {"bias": ("1.0", "0.2")}, number="auto", date=D2020, serial="SN-0001")
    fix = issue(
        store,
        {"bias": ("1.0", "0.2")},
        number="auto",
        date=D2020,
        serial="SN-0002",
        supersedes=wrong.number,
    )
    history = item_history(store, "SN-0001", today=D2024)
    assert [c.superseded_by for c in history.calibrations] == [fix.number]
    assert history.drift_per_year == {}


def test_the_json_has_the_printed_numbers_and_u_from_k(store_url) -> None:
    store = open_store(store_url)
    content = make_content({"bias": ("0.5", "0.1")}, date=D2024)
    measurement = content.measurements[0]
    q = ReportedQuantity("bias", "bias", "°/h", "\\degree\\per\\hour", "-0.000125", "0.000040",
                         "1.96", "0.95")  # fmt: skip
    content = dataclasses.replace(
        content, measurements=(dataclasses.replace(measurement, quantities=(q,)),)
    )
    kept = _keep(store, content)
    out = json.loads(json.dumps(item_history(store, "SN-0001", today=D2024).to_dict()))
    assert set(out) == {"serial", "item", "calibrations", "drift_per_year", "next_due", "warnings"}
    assert out["item"] == {
        "kind": "gyroscope",
        "manufacturer": "Gyro Maker Ltd",
        "model": "GM-300",
        "serial": "SN-0001",
    }
    (calibration,) = out["calibrations"]
    assert calibration["number"] == kept.number and calibration["date"] == "2024-01-01"
    assert calibration["superseded_by"] is None
    assert calibration["results"] == {
        "bias": {"value": -0.000125, "u": 0.00004 / 1.96, "U": 0.00004, "k": 1.96, "unit": "°/h"}
    }
    assert out["next_due"] == {
        "date": "2025-01-01",
        "method": out["next_due"]["method"],
        "quantity": None,
    }


def test_a_key_reported_twice_is_named_by_its_measurement(store_url) -> None:
    store = open_store(store_url)
    for day, cold, hot in ((D2020, "10.0", "11.0"), (D2024, "12.0", "15.0")):
        content = make_content({"scale_factor": (cold, "0.2")}, date=day)
        at20 = dataclasses.replace(content.measurements[0], name="Scale factor at 20 °C")
        at50 = dataclasses.replace(
            at20,
            index=2,
            name="Scale factor at 50 °C",
            quantities=(dataclasses.replace(at20.quantities[0], value=hot),),
        )
        _keep(store, dataclasses.replace(content, measurements=(at20, at50)))
    once = make_content({"scale_factor": ("8.0", "0.2")}, date=D2016)  # reports it once
    only20 = dataclasses.replace(once.measurements[0], name="Scale factor at 20 °C")
    _keep(store, dataclasses.replace(once, measurements=(only20,)))
    drifts = item_history(store, "SN-0001", today=D2024).drift_per_year
    cold, hot = "scale_factor@Scale factor at 20 °C", "scale_factor@Scale factor at 50 °C"
    assert set(drifts) == {cold, hot}
    assert drifts[hot].value == pytest.approx(1.0, abs=1e-12)  # 11 → 15 in 4 years
    assert (drifts[cold].n, drifts[cold].value) == (3, pytest.approx(0.5, abs=1e-12))  # 8, 10, 12


def test_values_in_another_unit_are_left_out_with_a_warning(store_url) -> None:
    store = open_store(store_url)
    for day, value, unit in ((D2016, "1.0", "%"), (D2020, "10.0", "ppm"), (D2024, "12.0", "ppm")):
        content = make_content({"scale_factor": (value, "0.2")}, date=day)
        m = content.measurements[0]
        q = dataclasses.replace(m.quantities[0], unit=unit)
        _keep(
            store,
            dataclasses.replace(content, measurements=(dataclasses.replace(m, quantities=(q,)),)),
        )
    history = item_history(store, "SN-0001", today=D2024)
    drift = history.drift_per_year["scale_factor"]
    assert drift.n == 2 and drift.value == pytest.approx(0.5, abs=1e-12)
    assert any("the drift uses only the values in ppm" in w for w in history.warnings)


# -- the user's mistakes ---------------------------------------------------------------------------


def test_a_serial_of_several_models_asks_which(store_url) -> None:
    store = open_store(store_url)
    _keep(store, _with_item(make_content({"bias": ("1.0", "0.2")}, date=D2020), model="GM-300"))
    _keep(store, _with_item(make_content({"bias": ("2.0", "0.2")}, date=D2020), model="GM-400"))
    with pytest.raises(ConfigError) as e:
        item_history(store, "SN-0001")
    message = str(e.value)
    assert "\n" not in message and store.shown in message and "'SN-0001'" in message
    assert "Gyro Maker Ltd GM-300 (--model GM-300)" in message
    assert "Gyro Maker Ltd GM-400 (--model GM-400)" in message
    history = item_history(store, "SN-0001", model="GM-400", today=D2024)
    assert history.item["model"] == "GM-400"
    assert [c.results["bias"].value for c in history.calibrations] == [2.0]
    with pytest.raises(ConfigError, match=r"no item of model 'GM-500'; its items: .*GM-300"):
        item_history(store, "SN-0001", model="GM-500")


def test_the_same_model_of_two_makers_is_picked_by_maker_and_model(store_url) -> None:
    store = open_store(store_url)
    _keep(store, _with_item(make_content({"bias": ("1.0", "0.2")}, date=D2020)))
    other = make_content({"bias": ("3.0", "0.2")}, date=D2020)
    _keep(store, _with_item(other, manufacturer="Other Gyro Co"))
    with pytest.raises(ConfigError, match=re.escape('(--model "Other Gyro Co GM-300")')):
        item_history(store, "SN-0001", model="GM-300")
    history = item_history(store, "SN-0001", model="Other Gyro Co GM-300", today=D2024)
    assert [c.results["bias"].value for c in history.calibrations] == [3.0]


def test_an_unknown_serial_says_where_to_look(store_url, issue) -> None:
    store = open_store(store_url)
    issue(store, {"bias": ("1.0", "0.2")}, number="auto", date=D2020)
    with pytest.raises(ConfigError) as e:
        item_history(store, "SN-9999")
    message = str(e.value)
    assert "no certificate of an item with serial 'SN-9999'" in message
    assert store.shown in message and "rotacal records list" in message
    with pytest.raises(ConfigError, match="differing only in case or spaces: 'SN-0001'"):
        item_history(store, "sn-0001 ")


# -- the report ------------------------------------------------------------------------------------


# the history it draws is read alike from each engine (test_a_drift_sets_next_due_where_…): the
# figures are drawn once, from SQLite
@pytest.mark.parametrize("store_url", ["sqlite"], indirect=True)
def test_the_report_has_one_figure_per_quantity(store_url, issue, tmp_path: Path) -> None:
    store = open_store(store_url)
    _drifting(store, issue, "rising", "19.2")
    history = item_history(store, "SN-0001", today=dt.date(2024, 6, 1))
    report = history_report(history, "sqlite:///lab/records.sqlite")
    html = write_html(report, tmp_path / "history.html").read_text(encoding="utf-8")
    assert faults(html) == []  # plain words: keys quoted as a plan names them, no E notation
    assert html.count("<figure>") == 2 == len(history.drift_per_year)
    assert html.count('src="data:image/png;base64,') == 2
    assert "serial SN-0001" in html and "2025-01-01" in html and "2027-07-02" in html
    assert html.count("<tr>") >= 1 + len(history.calibrations)  # the calibrations table


def test_a_certificate_without_values_is_listed_and_dates_the_interval(store_url, issue) -> None:
    store = open_store(store_url)
    issue(store, {"bias": ("1.0", "0.2")}, number="auto", date=D2020)
    issue(store, {}, number="auto", date=dt.date(2023, 8, 31))
    history = item_history(store, "SN-0001", today=D2020)
    assert [len(c.results) for c in history.calibrations] == [1, 0]
    assert history.drift_per_year == {}
    assert history.next_due.date == dt.date(2024, 8, 31)
    assert history.next_due.method.startswith(
        "The laboratory's fixed interval of 12 months after the last calibration on 2023-08-31;"
    )


def test_an_interval_setting_broken_outside_rotacal_is_named(store_url, issue) -> None:
    store = open_store(store_url)
    issue(store, {"bias": ("1.0", "0.2")}, number="auto", date=D2020)
    store.set_settings(interval_months="12")
    with store.begin() as connection:
        connection.execute(
            sa.text("UPDATE settings SET value = 'abc' WHERE key = 'interval_months'")
        )
    with pytest.raises(
        ConfigError, match="interval_months = 'abc' is not a whole number of months"
    ):
        item_history(store, "SN-0001")
