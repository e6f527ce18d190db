"""The encoder and gyro reports read as a metrologist expects: every result with its U, plain
names, fixed notation, papers by author and year, the user's output unit."""

from __future__ import annotations

import html
import re
from pathlib import Path

import pytest
from click.testing import CliRunner

from rotacal.cli import cli
from rotacal.report.wording import readable

#: Column names of the captures and GUM's subscripted symbols (t_p, e_j) may be shown as they are.
_ALLOWED = re.compile(r"^(?:[a-z]_[a-z0-9]+|time_s|rate_deg_s|head_\d+)$")
_SNAKE = re.compile(r"(?<![\w.])([a-z][a-z0-9]*(?:_[a-z0-9]+)+)(?![\w.])")
_E_NOTATION = re.compile(r"\b\d(?:\.\d+)?[eE][-+]?\d+\b")


def _run(*args: str) -> None:
    r = CliRunner().invoke(cli, list(args))
    assert r.exit_code == 0, r.output


def _visible(path: Path) -> str:
    text = path.read_text(encoding="utf-8")
    for pattern in (r"<style>.*?</style>", r"<script>.*?</script>", r"<img[^>]*>"):
        text = re.sub(pattern, " ", text, flags=re.S)
    return re.sub(r"\s+", " ", html.unescape(re.sub(r"<[^>]+>", " ", text)))


def _summary_rows(path: Path) -> list[str]:
    text = path.read_text(encoding="utf-8")
    summary = text[text.index('id="summary"') : text.index("</table>", text.index('id="summary"'))]
    body = summary[summary.index("<tbody>") :]
    rows = re.findall(r"<tr>(.*?)</tr>", body, flags=re.S)
    return [re.sub(r"\s+", " ", html.unescape(re.sub(r"<[^>]+>", " | ", r))) for r in rows]


@pytest.fixture(scope="module")
def reports(tmp_path_factory, unrendered_figures_in_module) -> dict[str, Path]:
    """Every report of this part, each from a twin capture through the command line (its
    figures one pixel each: these tests read the text; tests/report looks at the figures)."""
    d = tmp_path_factory.mktemp("reports")
    out = {
        name: d / f"{name}.html"
        for name in (
            "selfcal",
            "rate",
            "scale",
            "scale_mv",
            "triad",
            "rotations",
            "allan",
            "multiposition",
            "inspect",
        )
    }
    pulses, rates, triad, rot, noise, mp = (
        str(d / n) for n in ("p.npz", "g.csv", "t.csv", "r.csv", "n.csv", "m.csv")
    )
    _run(
        "simulate",
        "pulses",
        "--out",
        pulses,
        "--heads",
        "4",
        "--pulses-per-rev",
        "3600",
        "--revolutions",
        "4.2",
    )
    _run("selfcal", pulses, "--pulses-per-rev", "3600", "--report", str(out["selfcal"]))
    _run(
        "rate",
        pulses,
        "--pulses-per-rev",
        "3600",
        "--set-rate-deg-s",
        "300",
        "--report",
        str(out["rate"]),
    )
    _run("simulate", "gyro-rates", "--out", rates)
    _run("gyro", "scale-factor", rates, "--requirement", "fmvss126", "--report", str(out["scale"]))
    _run("gyro", "scale-factor", rates, "--output-unit", "mV", "--report", str(out["scale_mv"]))
    _run("simulate", "gyro-triad", "--out", triad)
    _run("gyro", "triad", triad, "--report", str(out["triad"]))
    _run("simulate", "gyro-rotations", "--out", rot)
    _run(
        "gyro",
        "rotations",
        rot,
        "--sections",
        rot + ".truth.json",
        "--report",
        str(out["rotations"]),
    )
    _run("simulate", "gyro-noise", "--out", noise, "--duration-s", "600")
    _run("allan", noise, "--report", str(out["allan"]))
    _run("simulate", "multiposition", "--out", mp)
    _run(
        "gyro",
        "multiposition",
        mp,
        "--axis",
        "x",
        "--latitude-deg",
        "45.75",
        "--report",
        str(out["multiposition"]),
    )
    _run("inspect", noise, "--report", str(out["inspect"]))
    return out


NAMES = [
    "selfcal",
    "rate",
    "scale",
    "scale_mv",
    "triad",
    "rotations",
    "allan",
    "multiposition",
    "inspect",
]


@pytest.mark.parametrize("name", NAMES)
def test_visible_text_has_no_keys_no_e_notation_no_seed_numbers(reports, name):
    text = _visible(reports[name]).split("About this report")[0]  # not the machine's name
    keys = {k for k in _SNAKE.findall(text) if not _ALLOWED.match(k)}
    assert not keys, f"{name}: {sorted(keys)}"
    assert not _E_NOTATION.findall(text), name
    assert "seed 00" not in text.lower(), name
    assert not re.search(r"\boutput unit\b(?!s)", text), name


@pytest.mark.parametrize("name", [n for n in NAMES if n != "inspect"])
def test_every_result_in_the_summary_states_its_U(reports, name):
    rows = _summary_rows(reports[name])
    assert rows, name
    for row in rows:
        assert "±" in row or "true value in" in row or "no uncertainty" in row, f"{name}: {row}"


def test_selfcal_states_the_head_placements_with_U(reports):
    text = _visible(reports["selfcal"])
    placements = re.findall(r"head (\d) [\d.]+ ([-\d.]+ ± [\d.]+ arcsec)", text)
    assert [h for h, _ in placements] == ["1", "2", "3"]
    assert "Kokuyama et al. (2015)" in text and "References" in text


def test_triad_states_scale_factors_and_misalignment_with_U(reports):
    rows = _summary_rows(reports["triad"])
    for axis in ("ux", "uy", "uz"):
        assert any(f"misalignment of {axis}" in r and "±" in r and "°" in r for r in rows)
        assert any(f"scale factor |K| of {axis}" in r and "±" in r for r in rows)


def test_scale_factor_states_the_users_unit_or_says_output_units(reports):
    assert "mV/(°/s)" in _visible(reports["scale_mv"])
    text = _visible(reports["scale"])
    assert "output units/(°/s)" in text
    rows = _summary_rows(reports["scale"])
    judged = [r for r in rows if "FMVSS 126" in r]
    assert len(judged) == 3 and all(" pass " in r or " fail " in r for r in judged)


def test_rate_judges_the_stability_against_fmvss_126(reports):
    rows = _summary_rows(reports["rate"])
    assert any("relative root Allan variance" in r and "< 0.05 %" in r for r in rows)


@pytest.mark.parametrize(
    ("text", "expected"),
    [
        ("within 7.5e-10.", "within 7.5 × 10⁻¹⁰."),
        ("ν = 1.563e+04 from", "ν = 15630 from"),
        ("bias +2.17e-06 arcsec", "bias +2.17 × 10⁻⁶ arcsec"),
        ("head_8 stops", "head 8 stops"),
        ("(seed 004 §4)", "(Kokuyama et al. (2015) §4)"),
        ("scale_factor_u and bias_u", "u(scale factor) and u(bias)"),
        ("1.2 output unit/(°/s)", "1.2 output units/(°/s)"),
        ("deg/h/g^2", "°/h/g²"),
        ("s(1 deg)", "s(1 deg)"),
        ("(see timing_jitter)", "(see the timing-noise estimate)"),
        ("a1e5b and 3.2", "a1e5b and 3.2"),
    ],
)
def test_readable_rewrites_for_a_person(text, expected):
    assert readable(text) == expected
