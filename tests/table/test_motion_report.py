"""The sinusoidal-motion report (rotacal.report.motion) reads plainly and states what it must.

Each check is against something the report does not make: the twin's truth (the fitted drift and
the THD inside the intervals the report prints), the result's own JSON keys (none may reach the
reader), and the rules of the issue (every summary row carries its U; no E notation; diagnostics
are not results).
"""

from __future__ import annotations

import re
from html.parser import HTMLParser

import numpy as np
import pytest

from rotacal import sim
from rotacal.report.html import Report, render_html
from rotacal.report.motion import comparison_section, motion_section
from rotacal.table import (
    calibrate_encoder_motion,
    calibrate_fog_motion,
    calibrate_lts_motion,
    compare_schemes,
)
from rotacal.uncertainty import load_specs

MOTION = sim.SineMotion(
    amplitude_deg=0.5, frequency_hz=2.0, harmonics={2: (0.010, 0.4), 3: (0.008, 1.1)}
)
SMALL = sim.SineMotion(amplitude_deg=0.025, frequency_hz=10.0, harmonics={2: (0.002, 0.4)})
TRUE_DRIFT = 0.002  # deg/s
SNAKE = re.compile(r"\b[a-z][a-z0-9]*(?:_[a-z0-9]+)+\b")
E_NOTATION = re.compile(r"\d[eE][-+]?\d")
NUMBER = r"(-?\d+(?:\.\d+)?)"


class _Text(HTMLParser):
    """The text a reader sees: everything but styles, scripts and the machine's name."""

    def __init__(self) -> None:
        super().__init__()
        self.parts: list[str] = []
        self._hidden = 0

    def handle_starttag(self, tag: str, attrs: object) -> None:
        self._hidden += tag in ("style", "script")

    def handle_endtag(self, tag: str) -> None:
        self._hidden -= tag in ("style", "script")

    def handle_data(self, data: str) -> None:
        if not self._hidden:
            self.parts.append(data)


def _visible(html: str) -> str:
    parser = _Text()
    parser.feed(html)
    return " ".join(parser.parts)


def _keys(data: object) -> set[str]:
    """Every key of a JSON document, at any depth."""
    if isinstance(data, dict):
        return set(data) | {k for v in data.values() for k in _keys(v)}
    if isinstance(data, list):
        return {k for v in data for k in _keys(v)}
    return set()


def _specs():
    rect = {"distribution": "rectangular", "half_width": 2e-6}
    return load_specs({"timebase": {"relative_error": rect}})


@pytest.fixture(scope="module")
def results():
    enc = sim.simulate_encoder(MOTION, noise_rms=0.01, fs_hz=20_000.0, duration_s=2.6, seed=3)
    c = enc.columns
    encoder = calibrate_encoder_motion(
        c["time_s"],
        c["a"],
        c["b"],
        lines=36000,
        set_amplitude_deg=0.5,
        set_frequency_hz=2.0,
        specs=_specs(),
    )
    lts = sim.simulate_lts(SMALL, seed=2).columns
    lts_r = calibrate_lts_motion(lts["time_s"], lts["displacement_mm"], radius_mm=100.0)
    drifting = sim.SineMotion(amplitude_deg=0.5, frequency_hz=2.0, drift_deg_s=TRUE_DRIFT)
    fog = sim.simulate_fog(drifting, snr_db=30.0, fs_hz=2000.0, duration_s=10.125 / 2, seed=1)
    fog_r = calibrate_fog_motion(
        fog.columns["time_s"],
        fog.columns["rate_deg_s"],
        set_amplitude_deg=0.5,
        set_frequency_hz=2.0,
        drift=True,
    )
    same_run = sim.simulate_fog(MOTION, snr_db=30.0, fs_hz=2000.0, duration_s=10.125 / 2, seed=4)
    fog_same = calibrate_fog_motion(same_run.columns["time_s"], same_run.columns["rate_deg_s"])
    return {"encoder": encoder, "lts": lts_r, "fog": fog_r, "fog_same_run": fog_same}


def _summary(section):
    return {row.quantity: row for row in section.results}


@pytest.mark.parametrize("kind", ["encoder", "lts", "fog"])
def test_every_result_states_its_u_and_no_key_or_e_notation_reaches_the_reader(results, kind):
    r = results[kind]
    section = motion_section(r, figures=False)
    assert section.results
    for row in section.results:
        assert "±" in row.value or "true value in" in row.value, row
        assert "k = " in row.coverage and "p = 95 %" in row.coverage, row
    text = _visible(render_html(Report("t", sections=[section])))
    leaked = set(SNAKE.findall(text)) & _keys(r.to_dict())
    assert not leaked
    assert not E_NOTATION.search(text), E_NOTATION.search(text)
    assert "seed 0" not in text.lower() and "output unit" not in text
    assert "Feng et al. (2023)" in text and "References" in text


def test_counts_and_diagnostics_are_not_results(results):
    r = results["encoder"]
    section = motion_section(r, figures=False)
    names = " ".join(_summary(section))
    for word in ("periods", "reversing", "residual", "position error", "signal-to-noise"):
        assert word not in names
    captions = {t.caption: t for t in section.tables}
    diagnostics = captions["Diagnostics, not results"]
    assert [row[0] for row in diagnostics.rows] == [
        "fit residual, rms (of the displacement)",
        "angular position error, largest",
        "angular position error, rms",
    ]
    # the largest position error in arcsec is the result's, rounded to 4 significant digits
    shown = float(diagnostics.rows[1][1].split()[0])
    assert shown == pytest.approx(r.position_error_max_deg * 3600.0, rel=5e-4)
    analysis = {row[0]: row[1] for row in captions["What was analysed"].rows}
    assert analysis["periods analysed"].startswith(f"{r.periods_used} whole periods")
    assert analysis["reversing moments found"].startswith(f"{r.reversal_times_s.size}, each")


def test_thd_is_one_result_whose_interval_holds_the_twins_truth(results):
    r = results["encoder"]
    row = _summary(motion_section(r, figures=False))["total harmonic distortion"]
    lo, hi = (float(x) for x in re.search(rf"\[{NUMBER}, {NUMBER}\]", row.value).groups())
    truth = MOTION.truth(r.analysis_start_s, r.analysis_stop_s)["thd_percent"]
    assert lo <= truth <= hi
    assert "bias-corrected" in row.note and "noise bias" in row.note


def test_errors_against_the_set_motion_hold_the_twins_truth(results):
    """The twin moves exactly at the set values: every error's interval must hold 0."""
    rows = _summary(motion_section(results["encoder"], figures=False))
    for name in ("amplitude error", "frequency error", "angular-acceleration amplitude error"):
        value, big_u = (
            float(x) for x in re.match(rf"{NUMBER} ± {NUMBER}", rows[name].value).groups()
        )
        assert abs(value) <= big_u, (name, rows[name].value)
        assert "set motion, 0.5° at 2 Hz" in rows[name].note


def test_the_fitted_drift_is_a_result_whose_u_holds_the_twins_drift(results):
    """FOG with --drift: D0 is the table's drift (the twin's gyro has no bias), D1 is 0."""
    rows = _summary(motion_section(results["fog"], figures=False))
    for name, truth in (("rate offset D0 (drift and gyro bias)", TRUE_DRIFT), ("rate drift", 0.0)):
        value, big_u = (
            float(x) for x in re.match(rf"{NUMBER} ± {NUMBER}", rows[name].value).groups()
        )
        assert abs(value - truth) <= big_u, (name, rows[name].value)


def test_harmonic_table_states_a_u_per_harmonic_and_flags_the_noise_level(results):
    r = results["encoder"]
    table = next(t for t in motion_section(r, figures=False).tables if "Harmonic" in t.caption)
    assert len(table.rows) == r.harmonics
    assert all("±" in row[1] for row in table.rows)
    truth = MOTION.truth(r.analysis_start_s, r.analysis_stop_s)["harmonic_amplitudes_deg"]
    for row, true_h in zip(table.rows, truth, strict=True):
        # the twin has harmonics 1–3 only: 4…N must be flagged, 1–3 must not
        assert (row[3] == "at the noise level") == (true_h < 1e-9), row


def test_comparison_names_the_paper_and_states_each_difference_with_u(results):
    enc, fog = results["encoder"], results["fog_same_run"]
    truth = MOTION.truth(enc.analysis_start_s, enc.analysis_stop_s)
    c = compare_schemes(enc, fog)
    section = comparison_section([("0.5° / 2 Hz", c, truth)], paper=[(1.28, 1.30, -0.02)])
    table = section.tables[0]
    assert any(col.startswith("Feng et al. (2023) Table 1") for col in table.columns)
    assert [row.quantity for row in section.results] == [
        "0.5° / 2 Hz: THD difference of two schemes"
    ]
    assert "±" in section.results[0].value
    # each THD cell's interval holds the twin's true THD
    for cell in (table.rows[0][1], table.rows[0][3]):
        lo, hi = (float(x) for x in re.search(rf"\[{NUMBER}, {NUMBER}\]", cell).groups())
        assert lo <= truth["thd_percent"] <= hi, cell
    text = _visible(render_html(Report("t", sections=[section])))
    assert not set(SNAKE.findall(text)) & _keys(c.to_dict())
    assert not E_NOTATION.search(text)
    assert np.isfinite(c.thd_difference_percent_u)
