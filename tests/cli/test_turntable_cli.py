"""`rotacal turntable budget|example`: INTERFACE keys, a closed form, one-line errors."""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest
from click.testing import CliRunner

from rotacal.cli import cli


def run(*args: str):
    return CliRunner().invoke(cli, list(args), prog_name="rotacal")


def one_line_error(result, *needles):
    assert result.exit_code == 2, result.output
    err = result.stderr.strip()
    assert err.count("\n") == 0 and "Traceback" not in result.output, err
    for n in needles:
        assert n.lower() in err.lower(), err


@pytest.fixture()
def example(tmp_path: Path) -> Path:
    path = tmp_path / "table.toml"
    r = run("turntable", "example", "--out", str(path))
    assert r.exit_code == 0, r.output
    return path


@pytest.mark.xdist_group("demo")  # the example table's allocations: tests/conftest.py
def test_budget_json_has_the_interface_keys_and_the_closed_form(example, tmp_path):
    out = tmp_path / "budget.json"
    report = tmp_path / "budget.html"
    r = run(
        "turntable",
        "budget",
        str(example),
        "--runs",
        "20000",
        "--json",
        str(out),
        "--report",
        str(report),
    )
    assert r.exit_code == 0, r.output
    d = json.loads(out.read_text())
    for key in ("sensitivities", "upper_bounds_arcmin", "monte_carlo"):
        assert key in d
    for key in ("runs", "max_abs_arcmin", "all_within"):
        assert key in d["monte_carlo"]
    assert d["monte_carlo"]["runs"] == 20000 and d["monte_carlo"]["all_within"] is True
    ub = d["upper_bounds_arcmin"]
    # Δθ = φz2 + αz1 with equal weights: each gets half the θ requirement; the full-model guard
    # may shave the second-order excess off it, which is below (Σ|UB|)²/Iθ (all in rad).
    arcmin = math.pi / 10_800
    i_theta = d["requirement_arcmin"]["theta"]
    second = (sum(v for v in ub.values() if v) * arcmin) ** 2 / (i_theta * arcmin)
    assert ub["phi_z2"] == pytest.approx(ub["alpha_z1"], rel=1e-6)  # SLSQP: ~√ftol
    assert i_theta / 2 * (1 - second) <= ub["phi_z2"] <= i_theta / 2
    assert ub["eta"] is None
    # the example derives its requirement so that its own calibration check passes
    assert d["options"] == {
        "requirement_derivation": "calibration-check",
        "constraint_angles": "every",
    }
    assert d["calibration"]["fraction_above_required"] == {"x": 0.0, "y": 0.0}
    assert d["calibration"]["worst_table_rate_error_deg_h"]["worst_deg_h"] <= 0.01
    assert d["warnings"] == []
    # Figure 8: mean |cos| over 0:45:360.
    cos_mean = sum(abs(math.cos(math.radians(a))) for a in range(0, 361, 45)) / 9
    assert d["sensitivities"]["psi"]["phi_y1"] == pytest.approx(cos_mean, abs=1e-12)
    assert report.stat().st_size > 50_000


@pytest.mark.xdist_group("demo")  # the example table's budgets: tests/conftest.py
def test_budget_text_summary_with_the_papers_reading(example):
    r = run(
        "turntable",
        "budget",
        str(example),
        "--runs",
        "5000",
        "--requirement-derivation",
        "earth-rate-only",
        "--constraint-angles",
        "45",
    )
    assert r.exit_code == 0, r.output
    assert "all within" in r.output and "alpha_x2" in r.output
    # eq. (16): ωm/(√2·Ωe) per component (typed here); Δθ's pair splits it
    limit = math.degrees(0.01 / (math.sqrt(2.0) * 15.041067)) * 60.0
    assert "psi 1.616  theta 1.616  gamma 1.616" in r.output
    row = next(line for line in r.stdout.splitlines() if line.startswith("phi_z2"))
    assert float(row.split()[2]) == pytest.approx(limit / 2, rel=3e-4)
    # … and the calibration check says what that reading does to a 0.01 °/h calibration
    assert "NOT MET" in r.stdout
    assert "tables built to this allocation can miss the calibration accuracy" in r.stderr


@pytest.mark.parametrize(
    ("args", "needles"),
    [
        (("--constraint-angles", "7"), ("--constraint-angles", "divides 360")),
        (("--requirement-derivation", "paper"), ("invalid value", "earth-rate-only")),
    ],
)
def test_bad_budget_options_are_one_line(example, args, needles):
    one_line_error(run("turntable", "budget", str(example), "--runs", "10", *args), *needles)


def test_derivation_for_a_stated_requirement_is_one_line(example):
    stated = _edit(
        example,
        'calibration_deg_h = 0.01\nderivation = "calibration-check"',
        "psi = 1.62\ntheta = 1.62\ngamma = 1.62",
    )
    r = run("turntable", "budget", str(stated), "--requirement-derivation", "earth-rate-only")
    one_line_error(r, "applies to a requirement derived from", "calibration_deg_h")


def test_example_refuses_to_overwrite(example):
    one_line_error(run("turntable", "example", "--out", str(example)), "exists")


def _edit(example: Path, old: str, new: str) -> Path:
    text = example.read_text()
    assert old in text
    example.write_text(text.replace(old, new, 1))
    return example


def test_unknown_error_name_is_one_line(example):
    one_line_error(
        run("turntable", "budget", str(_edit(example, "phi_y1 = {", "phi_q1 = {"))), "phi_q1"
    )


def test_negative_bound_is_one_line(example):
    bad = _edit(example, "phi_y1 = { lower = 0.05", "phi_y1 = { lower = -0.05")
    one_line_error(run("turntable", "budget", str(bad)), "phi_y1", "negative")


def test_infeasible_allocation_is_one_line(example):
    bad = _edit(example, "alpha_y2 = { lower = 0.05", "alpha_y2 = { lower = 1.7")
    one_line_error(run("turntable", "budget", str(bad)), "infeasible", "psi")


def test_missing_config_is_one_line(tmp_path):
    one_line_error(run("turntable", "budget", str(tmp_path / "nope.toml")), "nope.toml")
