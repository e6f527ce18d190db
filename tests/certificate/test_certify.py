"""``rotacal certify`` end to end: a plan of five measurements on twin captures gives a certificate
folder whose three documents agree with each other and with the twins' truth; reproducible;
failures leave nothing behind."""

from __future__ import annotations

import hashlib
import json
import shutil
from pathlib import Path
from typing import Any

import pytest
from click.testing import CliRunner
from lxml import etree

from rotacal.cli import cli

NS = {"dcc": "https://ptb.de/dcc", "si": "https://ptb.de/si"}
FILES = {"certificate.pdf", "certificate.xml", "results.json"}


def _certify(*args: str) -> Any:
    return CliRunner().invoke(cli, ["certify", *args], catch_exceptions=False)


@pytest.fixture(autouse=True)
def _records_of_this_test(
    tmp_path_factory: pytest.TempPathFactory, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Each test certifies into a records store of its own (plans here share numbers), outside
    the folder of its plan (whose contents the tests check)."""
    store = tmp_path_factory.mktemp("records") / "records.sqlite"
    monkeypatch.setenv("ROTACAL_DB", f"sqlite:///{store}")


@pytest.fixture(scope="module")
def issued(tmp_path_factory: pytest.TempPathFactory, make_plan) -> Path:
    folder = tmp_path_factory.mktemp("certify")
    plan = make_plan(folder)
    result = _certify(str(plan), "--db", f"sqlite:///{folder / 'records.sqlite'}")
    assert result.exit_code == 0, result.output
    return folder / "RC-2026-0042"


def _pdf_text(folder: Path) -> list[str]:
    from pypdf import PdfReader

    return [p.extract_text() for p in PdfReader(folder / "certificate.pdf").pages]


@pytest.fixture(scope="module")
def issued_text(issued: Path) -> list[str]:
    """The text of each page of the issued PDF (pypdf's extraction is slow: once per module)."""
    return _pdf_text(issued)


def test_the_folder_holds_the_certificate_and_its_figures_only(issued: Path) -> None:
    names = {p.name for p in issued.iterdir()}
    assert FILES <= names
    figures = names - FILES
    assert figures and all(n.startswith("figure-") and n.endswith(".svg") for n in figures)
    # nothing left beside the plan but the certificate folder (no staging folder)
    assert not [p for p in issued.parent.iterdir() if p.name.startswith(".")]


def test_results_json_has_the_interface_keys_and_the_expected_verdicts(issued: Path) -> None:
    doc = json.loads((issued / "results.json").read_text())
    assert doc["certificate_number"] == "RC-2026-0042"
    assert doc["item"]["serial"] == "SN-0001"
    assert [m["command"] for m in doc["measurements"]] == [
        "gyro scale-factor",
        "gyro triad",
        "allan",
        "selfcal",
        "motion encoder",
    ]
    verdicts = {k: v for m in doc["measurements"] for k, v in m["conformity"].items()}
    assert verdicts == {
        "nonlinearity_percent_fs": "pass",
        "scale_factor": "pass",
        "scale_misalignment[0][1]": "fail",  # 0.003060 ± 0.000054 above 0.003
        "arw_deg_rt_h": "pass",
        "bias_instability_deg_h": "indeterminate",  # 2.9 ± 1.0 straddles 3.5 (truth 3.0)
        "deviation_pp_arcsec": "pass",
        "thd_percent": "fail",  # 1.044 % above 1 %, simple acceptance
    }
    assert [m["decision_rule"] for m in doc["measurements"]] == ["guarded"] * 4 + ["simple"]
    for m in doc["measurements"]:
        # each measurement carries the command's own JSON, with warnings and provenance
        assert m["results"]["provenance"]["command"] == m["command"]
        assert isinstance(m["warnings"], list) and m["provenance"] == m["results"]["provenance"]


def test_plan_sha256_covers_the_plan_and_every_capture(issued: Path) -> None:
    doc = json.loads((issued / "results.json").read_text())
    folder = issued.parent
    h = hashlib.sha256((folder / "plan.toml").read_bytes())
    for m in doc["measurements"]:
        for capture in m["captures"]:
            digest = hashlib.sha256((folder / capture["path"]).read_bytes()).hexdigest()
            assert digest == capture["sha256"]
            h.update(b"\n" + digest.encode())
    assert doc["plan_sha256"] == h.hexdigest()


def test_the_reported_values_agree_with_the_twins_truth(issued: Path) -> None:
    doc = json.loads((issued / "results.json").read_text())
    reported = {q["quantity"]: q for m in doc["measurements"] for q in m["reported"]}
    truth = json.loads((issued.parent / "rates.npz.truth.json").read_text())
    sf = reported["scale_factor"]
    # the least-squares line through the twin's true point means, within U
    assert abs(sf["value"] - truth["ls_scale_factor"]) <= sf["U"]
    assert sf["unit"] == "V/(°/s)"
    noise = json.loads((issued.parent / "noise.npz.truth.json").read_text())
    arw = reported["arw_deg_rt_h"]
    assert abs(arw["value"] - noise["arw_deg_rt_h"]) <= 2 * arw["U"]


def test_every_number_of_the_dcc_is_the_one_in_results_json(issued: Path) -> None:
    doc = json.loads((issued / "results.json").read_text())
    root = etree.fromstring((issued / "certificate.xml").read_bytes())
    reals = {
        (real.findtext("si:label", namespaces=NS) or ""): real
        for real in root.iterfind(".//dcc:result//si:real", NS)
    }
    for m in doc["measurements"]:
        for q in m["reported"]:
            real = reals[q["quantity"]]
            assert float(real.findtext("si:value", namespaces=NS)) == q["value"], q
            assert real.findtext("si:unit", namespaces=NS) == q["dsi_unit"], q
            if q["interval"] is None:
                U = real.findtext("si:expandedUnc/si:uncertainty", namespaces=NS)
                assert float(U) == q["U"], q
                k = real.findtext("si:expandedUnc/si:coverageFactor", namespaces=NS)
                assert float(k) == q["k"], q
            else:
                low = real.findtext("si:coverageInterval/si:intervalMin", namespaces=NS)
                high = real.findtext("si:coverageInterval/si:intervalMax", namespaces=NS)
                assert [float(low), float(high)] == q["interval"], q


def test_the_dcc_is_valid(issued: Path, dcc_schema) -> None:
    dcc_schema.validate(str(issued / "certificate.xml"))


def test_the_same_plan_gives_the_same_certificate(
    issued: Path, issued_text: list[str], tmp_path: Path
) -> None:
    again = tmp_path / "again"
    # not recorded: the records refuse a second certificate of the same plan (test below)
    result = _certify(str(issued.parent / "plan.toml"), "--out", str(again), "--no-record")
    assert result.exit_code == 0, result.output
    for name in ("results.json", "certificate.xml"):
        assert (again / name).read_bytes() == (issued / name).read_bytes(), name
    assert _pdf_text(again) == issued_text


def test_an_existing_certificate_is_not_replaced_without_overwrite(issued: Path) -> None:
    before = (issued / "results.json").read_bytes()
    plan = str(issued.parent / "plan.toml")
    result = CliRunner().invoke(cli, ["certify", plan, "--no-record"])
    assert result.exit_code == 2
    assert "--overwrite" in result.output and result.output.count("\n") == 1
    assert (issued / "results.json").read_bytes() == before


def test_a_number_in_the_records_is_never_issued_again(issued: Path) -> None:
    before = (issued / "results.json").read_bytes()
    plan = str(issued.parent / "plan.toml")
    db = f"sqlite:///{issued.parent / 'records.sqlite'}"
    result = CliRunner().invoke(cli, ["certify", plan, "--overwrite", "--db", db])
    assert result.exit_code == 2 and result.output.count("\n") == 1
    assert "RC-2026-0042 is already in the records" in result.output
    assert "supersedes" in result.output
    assert (issued / "results.json").read_bytes() == before


def test_a_failing_plan_leaves_nothing_behind(tmp_path: Path, make_plan) -> None:
    plan = make_plan(tmp_path)
    (tmp_path / "noise.npz").write_bytes(b"not a capture")  # measurement 3's capture
    before = sorted(p.name for p in tmp_path.iterdir())
    result = CliRunner().invoke(cli, ["certify", str(plan)])
    assert result.exit_code == 2
    line = result.output.strip()
    assert "\n" not in line and "Traceback" not in result.output
    assert str(plan) in line and "measurement[3]" in line and "noise.npz" in line
    assert sorted(p.name for p in tmp_path.iterdir()) == before


def test_a_limit_on_a_result_the_command_does_not_report_is_named(
    tmp_path: Path, make_plan
) -> None:
    plan = make_plan(
        tmp_path,
        [{"name": "Noise", "command": "allan", "limits": {"arw_deg_h": {"max": 1.0}}}],
    )
    result = CliRunner().invoke(cli, ["certify", str(plan)])
    assert result.exit_code == 2
    assert "measurement[1].limits.arw_deg_h" in result.output and "arw_deg_rt_h" in result.output
    assert sorted(p.name for p in tmp_path.iterdir()) == [
        "noise.npz",
        "noise.npz.truth.json",
        "plan.toml",
    ]


def test_a_bad_option_value_is_named(tmp_path: Path, make_plan) -> None:
    plan = make_plan(tmp_path, [{"name": "SF", "command": "gyro scale-factor"}])
    text = plan.read_text().replace("full-scale-deg-s = 100", 'full-scale-deg-s = "lots"')
    plan.write_text(text)
    result = CliRunner().invoke(cli, ["certify", str(plan)])
    assert result.exit_code == 2 and "measurement[1].options" in result.output
    assert "lots" in result.output


def test_auto_numbers_follow_the_series_and_a_failure_consumes_none(
    tmp_path: Path, make_plan, monkeypatch: pytest.MonkeyPatch
) -> None:
    one = [{"name": "Noise", "command": "allan"}]
    plan = make_plan(tmp_path, one, certificate={"number": "auto", "date": "2026-11-25"})
    assert _certify(str(plan)).exit_code == 0
    again = CliRunner().invoke(cli, ["certify", str(plan)])  # the same calibration again
    assert again.exit_code == 2 and "certified already as RC-2026-0001" in again.output
    plan.write_text(plan.read_text() + "# the next calibration\n")
    (tmp_path / "noise.npz").rename(tmp_path / "kept.npz")
    assert CliRunner().invoke(cli, ["certify", str(plan)]).exit_code == 2  # no capture
    (tmp_path / "kept.npz").rename(tmp_path / "noise.npz")
    assert _certify(str(plan)).exit_code == 0
    assert sorted(p.name for p in tmp_path.glob("RC-*")) == ["RC-2026-0001", "RC-2026-0002"]


def test_auto_needs_the_records(tmp_path: Path, make_plan) -> None:
    one = [{"name": "Noise", "command": "allan"}]
    plan = make_plan(tmp_path, one, certificate={"number": "auto", "date": "2026-11-25"})
    result = CliRunner().invoke(cli, ["certify", str(plan), "--no-record"])
    assert result.exit_code == 2 and result.output.count("\n") == 1
    assert "certificate.number" in result.output and "--no-record" in result.output
    assert not list(tmp_path.glob("RC-*"))


def test_the_example_plan_works_as_it_is_on_simulated_captures(tmp_path: Path) -> None:
    runner = CliRunner()
    example = runner.invoke(cli, ["certify", "--example"]).output
    (tmp_path / "plan.toml").write_text(example)
    commands = [
        line.split("#", 1)[1].strip()
        for line in example.splitlines()
        if line.startswith("#   rotacal simulate")
    ]
    assert len(commands) == 3
    for command in commands:
        words = command.split()[1:]
        words[words.index("--out") + 1] = str(tmp_path / words[words.index("--out") + 1])
        assert runner.invoke(cli, words).exit_code == 0
    result = _certify(str(tmp_path / "plan.toml"))
    assert result.exit_code == 0, result.output
    assert FILES <= {p.name for p in (tmp_path / "RC-2026-0001").iterdir()}
    shutil.rmtree(tmp_path / "RC-2026-0001")


def test_the_end_marker_closes_the_last_page_and_never_stands_alone(issued_text: list[str]) -> None:
    pages = issued_text
    assert all("End of certificate" not in page for page in pages[:-1])
    last = pages[-1]
    assert "End of certificate" in last
    assert "SHA-256" in last  # the annex's table goes with it


def test_an_unknown_option_is_named_before_anything_runs(tmp_path: Path, make_plan) -> None:
    plan = make_plan(tmp_path)
    text = plan.read_text().replace('column = "rate_deg_s"', 'colum = "rate_deg_s"')
    plan.write_text(text)
    result = CliRunner().invoke(cli, ["certify", str(plan)])
    assert result.exit_code == 2
    line = result.output.strip()
    assert "measurement[3].options.colum" in line and "has no option --colum" in line
    assert "column" in line  # the options it has
    assert not [p for p in tmp_path.iterdir() if p.name.startswith((".", "RC-"))]
