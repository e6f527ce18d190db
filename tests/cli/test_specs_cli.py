"""`--specs FILE.toml` on the analyses and `rotacal specs example`: Type B inputs reach the budgets."""

from __future__ import annotations

import json
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
def specs(tmp_path: Path) -> Path:
    path = tmp_path / "specs.toml"
    r = run("specs", "example", "--out", str(path))
    assert r.exit_code == 0, r.output
    return path


def _sim(tmp_path: Path, kind: str, name: str) -> Path:
    path = tmp_path / name
    r = run("simulate", kind, "--out", str(path))
    assert r.exit_code == 0, r.output
    return path


def _rows(d: dict, name: str) -> list[str]:
    """Each row's source with its origin (the specification's name lives in the origin)."""
    return [f"{row['source']} ({row['origin']})" for row in d["uncertainty_budgets"][name]["rows"]]


def test_encoder_motion_budget_takes_the_specs(tmp_path, specs):
    cap = _sim(tmp_path, "encoder", "enc.npz")
    out_plain, out_specs = tmp_path / "plain.json", tmp_path / "specs.json"
    r = run("motion", "encoder", str(cap), "--lines", "36000", "--json", str(out_plain))
    assert r.exit_code == 0, r.output
    r = run(
        "motion",
        "encoder",
        str(cap),
        "--lines",
        "36000",
        "--specs",
        str(specs),
        "--json",
        str(out_specs),
    )
    assert r.exit_code == 0, r.output
    plain, with_specs = json.loads(out_plain.read_text()), json.loads(out_specs.read_text())
    for name in ("amplitude_deg", "frequency_hz", "thd_percent"):
        assert f"{name}_u" in with_specs and f"{name}_U" in with_specs and name in with_specs["k"]
    # the ±1″ graduation (rectangular, u = 1/√3 ″ at each of the two extremes, sensitivity
    # 1/7200 °/″) adds in quadrature to the fit's Type A part
    grad_u = (1 / 3**0.5) / 7200
    expected = (plain["amplitude_deg_u"] ** 2 + 2 * grad_u**2) ** 0.5
    assert with_specs["amplitude_deg_u"] == pytest.approx(expected, rel=1e-6)
    assert any("graduation" in s for s in _rows(with_specs, "amplitude_deg"))
    # ±2 ppm timebase on the frequency: u = f·2e-6/√3 added in quadrature
    f = with_specs["frequency_hz"]
    expected_f = (plain["frequency_hz_u"] ** 2 + (f * 2e-6 / 3**0.5) ** 2) ** 0.5
    assert with_specs["frequency_hz_u"] == pytest.approx(expected_f, rel=1e-6)


def test_multiposition_latitude_from_the_specs(tmp_path, specs):
    cap = _sim(tmp_path, "multiposition", "mp.csv")
    out = tmp_path / "mp.json"
    r = run(
        "gyro", "multiposition", str(cap), "--axis", "x", "--specs", str(specs), "--json", str(out)
    )
    assert r.exit_code == 0, r.output
    d = json.loads(out.read_text())
    assert set(d["drift_coefficients_U"]) == set(d["drift_coefficients"])
    one_line_error(run("gyro", "multiposition", str(cap), "--axis", "x"), "latitude")


@pytest.mark.parametrize(
    ("old", "new", "needle"),
    [
        ("u = 0.01 }", "u = -0.01 }", "≥ 0"),
        (
            'relative_error = { distribution = "rectangular"',
            'relative_error = { distribution = "squarish"',
            "squarish",
        ),
        ("relative_error =", "relative_eror =", "relative_eror"),
    ],
)
def test_bad_specs_are_one_line(tmp_path, specs, old, new, needle):
    cap = _sim(tmp_path, "encoder", "enc.npz")
    text = specs.read_text()
    assert old in text
    specs.write_text(text.replace(old, new, 1))
    one_line_error(
        run("motion", "encoder", str(cap), "--lines", "36000", "--specs", str(specs)), needle
    )


def test_missing_specs_file_is_one_line(tmp_path):
    cap = _sim(tmp_path, "encoder", "enc.npz")
    one_line_error(
        run(
            "motion", "encoder", str(cap), "--lines", "36000", "--specs", str(tmp_path / "no.toml")
        ),
        "no.toml",
    )


def test_example_refuses_to_overwrite(specs):
    one_line_error(run("specs", "example", "--out", str(specs)), "exists")
