"""The turntable report section (rotacal.report.turntable) for the seed table and a single axis.

Truth that does not come from the code under test: the digits printed in seed 001 (Table 4,
Figure 8) and the closed-form worst case of Table 4's bounds under the linearised model (eq. (26):
max over φ2 of |a cos φ2 + b sin φ2| + c = √(a² + b²) + c).
"""

from __future__ import annotations

import base64
import math
import re

import pytest

from rotacal.report.html import Report, render_html
from rotacal.report.turntable import (
    allocation_table,
    calibration_draws_figure,
    calibration_figure,
    seed_comparison_table,
    turntable_section,
)
from rotacal.turntable.budget import turntable_budget
from rotacal.turntable.model import load_turntable, seed_table

#: With the other budgets of the example table on the demo's xdist worker, whose process keeps
#: their allocations (tests/conftest.py).
pytestmark = pytest.mark.xdist_group("demo")

# Seed 001, Table 4 (arcmin), typed from the paper.
TABLE4 = {
    "phi_y1": 0.4235,
    "phi_z2": 0.7800,
    "alpha_x1": 0.4234,
    "alpha_z1": 0.7800,
    "alpha_x2": 0.2825,
    "alpha_y2": 0.2824,
    "eps_x": 0.4234,
    "eps_y": 0.4233,
}

SINGLE_AXIS = """
name = "single-axis rate table"
units = "arcsec"
[requirement]
psi = 20.0
theta = 30.0
gamma = 20.0
[[chain]]
axis = "z"
angle = "phi"
rotations = { e_z = "z", a_x = "x", a_y = "y" }
[errors]
e_z = { lower = 1.0, label = "Position error" }
a_x = { lower = 0.5, label = "Wobble about x" }
a_y = { lower = 0.5, label = "Wobble about y" }
"""


@pytest.fixture(scope="module")
def seed_budget():
    return turntable_budget(seed_table(), runs=20_000)


@pytest.fixture(scope="module")
def seed_section(seed_budget):
    return turntable_section(seed_budget)


@pytest.fixture(scope="module")
def single_budget():
    return turntable_budget(load_turntable(text=SINGLE_AXIS), runs=20_000)


@pytest.fixture(scope="module")
def single_section(single_budget):
    return turntable_section(single_budget)


def _is_png(fig) -> bool:
    return base64.b64decode(fig.png_base64)[:8] == b"\x89PNG\r\n\x1a\n"


def test_seed_section_has_every_part(seed_section) -> None:
    s = seed_section
    titles = [f.title for f in s.figures]
    assert len(s.figures) == 4, titles  # sensitivities, Monte Carlo, calibration map, draws
    assert all(_is_png(f) for f in s.figures)
    assert len(s.tables) == 2  # allocation, worst case
    assert "the study's Table 4 (′)" in s.tables[0].columns
    assert "rotacal / Table 4" in s.tables[0].columns
    # the side-by-side with the paper is folded away, cited by name
    assert len(s.details) == 1
    assert s.details[0].caption == "Reproducing the numbers of the GyroWheel study"
    assert s.details[0].note.startswith("What the paper's numbers rest on")
    assert {"gyrowheel", "clopper1934", "david2003"} <= set(s.references)
    html = render_html(Report("t", sections=[s]))
    assert s.title in html and html.count("<figure>") == 4 and html.count("<details>") == 1
    assert "seed 001" not in html.lower() and "seed 00" not in html.lower()


def _visible_text(html: str) -> str:
    body = re.sub(r"<(script|style)[^>]*>.*?</\1>", " ", html, flags=re.S)
    body = re.sub(r'src="data:[^"]*"', "", body)
    return re.sub(r"<[^>]+>", " ", body)


@pytest.mark.parametrize("which", ["seed_section", "single_section"])
def test_report_text_has_no_keys_no_e_notation_and_short_captions(which, request) -> None:
    s = request.getfixturevalue(which)
    text = _visible_text(render_html(Report("t", sections=[s])))
    assert not re.search(r"\d[eE][+-]?\d", text), re.findall(r"\S*\d[eE][+-]?\d\S*", text)
    keys = set(re.findall(r"\b[a-z]+_[a-z0-9_]+\b", text))
    # the single-axis table's own error names (e_z, a_x, a_y) are what its configuration calls
    # them; every name rotacal writes is plain words
    assert keys <= {"e_z", "a_x", "a_y"}, keys
    for f in s.figures:
        assert len(f.caption) <= 260, (f.title, len(f.caption))
    for t in [*s.tables, *s.details]:
        assert len(t.caption) <= 90, t.caption


def test_allocation_numbers_are_the_budgets(seed_budget) -> None:
    t = allocation_table(seed_budget)
    col_ub = t.columns.index("allocated upper bound (′)")
    col_t4 = t.columns.index("the study's Table 4 (′)")
    col_ratio = t.columns.index("rotacal / Table 4")
    assert len(t.rows) == len(seed_budget.error_names) == 9
    for name, row in zip(seed_budget.error_names, t.rows, strict=True):
        ub = seed_budget.upper_bounds_arcmin[name]
        if ub is None:
            assert name == "eta"
            assert row[col_ub] == "no effect on orientation"
            continue
        assert row[col_ub] == f"{ub:.4f}"
        assert float(row[col_t4]) == TABLE4[name]
        assert float(row[col_ratio]) == pytest.approx(ub / TABLE4[name], abs=6e-4)


def test_seed_comparison_prints_the_papers_numbers(seed_budget, seed_section) -> None:
    t = seed_comparison_table(seed_budget)
    assert t is not None
    rows = {r[0]: r for r in t.rows}
    cos_row = next(r for k, r in rows.items() if "|cos" in k)
    sin_row = next(r for k, r in rows.items() if "|sin" in k)
    # Figure 8's printed digits, and rotacal's own value printed beside them
    assert cos_row[1].startswith("0.6476") and cos_row[2] == "0.6476"
    assert sin_row[1].startswith("0.5365") and sin_row[2] == "0.5365"
    eq16 = next(r for k, r in rows.items() if "eq. (16)" in k)
    assert eq16[1] == "0.027° each"
    # eq. (16) is the Earth-rate reading alone: ωm/(√2·Ωe), typed here, and the plan's value,
    # which rounds to the printed 0.027°
    closed = math.degrees(0.01 / (math.sqrt(2.0) * 15.041067))
    assert f"ωm/(√2·Ωe) = {closed:.5f}°" in eq16[2]
    assert eq16[2].startswith("0.0269") and "the Earth-rate reading alone" in eq16[2]
    assert "it rounds to the printed value" in eq16[3]
    # the fit's reading stays far below it, over every scanned plan and latitude
    scan = seed_budget.reproduction["eq16_scan"]
    assert 0.0 < scan["coefficients"]["max_deg"] < 0.027 / 2
    assert round(scan["earth-rate"]["min_deg"], 3) == 0.027
    # Table 4: the paper's allocation recomputed on its grid, and what it rests on
    t4 = next(r for k, r in rows.items() if "(Table 4)" in k)
    assert t4[1].startswith("Δφy1 0.4235′, Δφz2 0.7800′")
    assert "Δφz2 0.7800′" in t4[2] and "Δαx1 0.4234′" in t4[2]
    assert "Iθ = Δφz2 + Δαz1 of Table 4 = 1.56′ = 0.026°" in t4[3]
    assert "5 of 8 are equal; Δφy1, Δαx2, Δεy differ by one unit of the last digit" in t4[3]
    assert "rounded down to 0.001°" in t4[3]
    # nothing is left "unexplained"
    # (the module's section of this budget: building it again would draw its four figures again)
    text = " ".join(" ".join(r) for r in t.rows) + " ".join(seed_section.paragraphs)
    assert "explained" not in text


def test_table4_worst_case_matches_the_closed_form(seed_budget) -> None:
    t = seed_comparison_table(seed_budget)
    assert t is not None
    row = next(r for r in t.rows if r[0].startswith("worst case"))
    table4_part = row[2].split("; this budget:")[0]
    assert table4_part.startswith("Table 4 (of 1.56′): ")
    got = {
        c: float(re.search(rf"{sym} ([0-9.]+)′", table4_part).group(1))  # type: ignore[union-attr]
        for c, sym in (("psi", "Δψ"), ("theta", "Δθ"), ("gamma", "Δγ"))
    }
    t4 = TABLE4
    # eq. (26): Δψ = (φy1 + εy) cos φ2 − (αx1 + εx) sin φ2 + αy2 at the worst signs
    psi = math.hypot(t4["phi_y1"] + t4["eps_y"], t4["alpha_x1"] + t4["eps_x"]) + t4["alpha_y2"]
    gamma = math.hypot(t4["phi_y1"] + t4["eps_y"], t4["alpha_x1"] + t4["eps_x"]) + t4["alpha_x2"]
    theta = t4["phi_z2"] + t4["alpha_z1"]
    # full model = linear + O(|χ|²): (1.6′ ≈ 4.7e-4 rad)² is ~1e-4 of the value
    assert got["psi"] == pytest.approx(psi, abs=5e-4)
    assert got["gamma"] == pytest.approx(gamma, abs=5e-4)
    assert got["theta"] == pytest.approx(theta, abs=5e-4)


def test_single_axis_table_builds_without_seed_parts(single_budget) -> None:
    assert calibration_figure(single_budget) is None
    assert calibration_draws_figure(single_budget) is None
    assert seed_comparison_table(single_budget) is None
    s = turntable_section(single_budget)
    assert len(s.figures) == 2 and all(_is_png(f) for f in s.figures)
    assert len(s.tables) == 2
    alloc = s.tables[0]
    assert "the study's Table 4 (′)" not in alloc.columns
    col = alloc.columns.index("allocated upper bound (′)")
    for name, row in zip(single_budget.error_names, alloc.rows, strict=True):
        assert row[col] == f"{single_budget.upper_bounds_arcmin[name]:.4f}"
    assert "Reproducing" not in " ".join(s.paragraphs)
    assert not s.details
    assert "all within" in s.figures[1].caption or "outside" in s.figures[1].caption
