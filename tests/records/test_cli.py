"""``rotacal records``: what certify issued is what the records show, list, export and import;
each mistake is one line and exit code 2."""

from __future__ import annotations

import hashlib
import json
from pathlib import Path

import pytest
from click.testing import CliRunner

from rotacal.cli import cli
from rotacal.records import open_store

PLAN = """\
[certificate]
number = "auto"
date = "2026-11-25"

[laboratory]
name = "Rate Lab"
address = "1 Test Road, Testville"

[customer]
name = "Gyro Maker Ltd"
address = "2 Sensor Street, Sensortown"

[[person]]
name = "A. Operator"
role = "performed"

[[person]]
name = "B. Manager"
role = "approved"

[item]
kind = "gyroscope"
manufacturer = "Gyro Maker Ltd"
model = "GM-300"
serial = "SN-0001"

[[standard]]
name = "Rate table encoder"
id = "STD-17"
certificate = "CAL-2026-123"
due = "2027-06-30"

[[measurement]]
name = "Noise"
command = "allan"
capture = "noise.npz"
limits = { arw_deg_rt_h = { max = 1.0 } }
"""


def run(*args: str):
    return CliRunner().invoke(cli, list(args))


def one_line(result, *needles: str) -> str:
    assert result.exit_code == 2, result.output
    line = result.output.strip()
    assert "\n" not in line and "Traceback" not in line, result.output
    for needle in needles:
        assert needle in line, line
    return line


@pytest.fixture(scope="module")
def certified(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, str]:
    """A certificate issued by `rotacal certify` into a store of this module: (folder, --db)."""
    folder = tmp_path_factory.mktemp("records-cli")
    db = f"sqlite:///{folder / 'records.sqlite'}"
    simulated = run(
        "simulate", "gyro-noise", "--duration-s", "60", "--out", str(folder / "noise.npz")
    )
    assert simulated.exit_code == 0, simulated.output
    (folder / "plan.toml").write_text(PLAN)
    issued = run("certify", str(folder / "plan.toml"), "--db", db)
    assert issued.exit_code == 0, issued.output
    assert "certificate RC-2026-0001" in issued.output and "recorded in sqlite:///" in issued.output
    return folder / "RC-2026-0001", db


def test_show_gives_back_what_certify_issued(certified, tmp_path: Path) -> None:
    folder, db = certified
    result = run("records", "show", "RC-2026-0001", "--db", db, "--json", str(tmp_path / "r.json"))
    assert result.exit_code == 0, result.output
    record = json.loads((tmp_path / "r.json").read_text())
    issued = json.loads((folder / "results.json").read_text())
    assert record["results"] == issued
    assert record["plan_sha256"] == issued["plan_sha256"]
    assert record["plan"]["text"] == (folder.parent / "plan.toml").read_text()
    assert {f["name"]: f["sha256"] for f in record["files"]} == {
        p.name: hashlib.sha256(p.read_bytes()).hexdigest() for p in folder.iterdir()
    }
    verdict = issued["measurements"][0]["conformity"]["arw_deg_rt_h"]
    assert record["conformity"][0]["verdict"] == verdict
    assert record["supersedes"] is None and record["superseded_by"] is None
    assert record["provenance"]["command"] == "records show"
    assert "certificate RC-2026-0001: Calibration certificate" in result.output
    restored = run("records", "show", "RC-2026-0001", "--db", db, "--files", str(tmp_path / "c"))
    assert restored.exit_code == 0, restored.output
    for path in folder.iterdir():
        assert (tmp_path / "c" / path.name).read_bytes() == path.read_bytes()
    again = run("records", "show", "RC-2026-0001", "--db", db, "--files", str(tmp_path / "c"))
    one_line(again, "--files", "exists")


def test_list_names_the_certificate_and_its_conformity(certified) -> None:
    _, db = certified
    result = run("records", "list", "--db", db)
    assert result.exit_code == 0, result.output
    header, row = result.output.splitlines()
    assert header.split()[:3] == ["number", "issued", "item"]
    assert row.startswith("RC-2026-0001  2026-11-25  Gyro Maker Ltd GM-300 SN-0001")
    data = json.loads(run("records", "list", "--db", db, "--json", "-").output)
    assert [c["number"] for c in data["certificates"]] == ["RC-2026-0001"]
    assert run("records", "list", "--db", db, "--serial", "SN-9").output.startswith(
        "no certificates of SN-9"
    )


def test_export_and_import_through_the_commands(certified, tmp_path: Path) -> None:
    _, db = certified
    to_stdout = run("records", "export", "--db", db)
    assert to_stdout.exit_code == 0
    written = run("records", "export", "--db", db, "--out", str(tmp_path / "b.jsonl"))
    assert written.exit_code == 0 and (tmp_path / "b.jsonl").read_text() == to_stdout.output
    other = f"sqlite:///{tmp_path / 'other.sqlite'}"
    imported = run("records", "import", str(tmp_path / "b.jsonl"), "--db", other)
    assert imported.exit_code == 0 and imported.output.startswith("imported 1 certificates")
    assert run("records", "export", "--db", other).output == to_stdout.output
    one_line(run("records", "export", "--db", db, "--out", str(tmp_path / "b.json")), ".jsonl")
    one_line(run("records", "export", "--db", db, "--out", str(tmp_path / "b.jsonl")), "b.jsonl")
    one_line(run("records", "import", str(tmp_path / "none.jsonl"), "--db", other), "none.jsonl")
    (tmp_path / "x.pdf").write_bytes(b"%PDF-1.7\n\xff\xfe\x00binary")
    one_line(run("records", "import", str(tmp_path / "x.pdf"), "--db", other), "not text (UTF-8)")
    one_line(run("records", "import", str(tmp_path), "--db", other), str(tmp_path))


def test_settings_shown_and_changed(tmp_path: Path) -> None:
    db = f"sqlite:///{tmp_path / 's.sqlite'}"
    shown = run("records", "settings", "--db", db)
    assert shown.output == "number_format = RC-{year}-{count:04d}\ninterval_months = 12\n"
    changed = run("records", "settings", "--db", db, "--number-format", "CAL{year}/{count:03d}")
    assert "number_format = CAL{year}/{count:03d}" in changed.output
    one_line(run("records", "settings", "--db", db, "--number-format", "X"), "{count}")
    one_line(run("records", "settings", "--db", db, "--interval-months", "0"), "months")
    assert open_store(db).settings()["number_format"] == "CAL{year}/{count:03d}"


def test_an_unknown_number_is_one_line(certified) -> None:
    _, db = certified
    one_line(run("records", "show", "RC-1999-0001", "--db", db), "no certificate RC-1999-0001")


def test_a_superseding_certificate_is_linked_both_ways(certified, tmp_path: Path) -> None:
    folder, module_db = certified
    db = f"sqlite:///{tmp_path / 'copy.sqlite'}"  # a copy: the module's store stays as it is
    (tmp_path / "b.jsonl").write_text(run("records", "export", "--db", module_db).output)
    assert run("records", "import", str(tmp_path / "b.jsonl"), "--db", db).exit_code == 0
    plan = tmp_path / "plan.toml"
    plan.write_text(PLAN.replace('number = "auto"', 'number = "auto"\nsupersedes = "RC-2026-0001"'))
    (tmp_path / "noise.npz").write_bytes((folder.parent / "noise.npz").read_bytes())
    issued = run("certify", str(plan), "--db", db)
    assert issued.exit_code == 0, issued.output
    shown = run("records", "show", "RC-2026-0001", "--db", db)
    assert "SUPERSEDED by RC-2026-0002" in shown.output
    listed = run("records", "list", "--db", db).output
    assert "superseded by RC-2026-0002" in listed
    twice = run("certify", str(plan), "--db", db)
    one_line(twice, "RC-2026-0001 is already superseded by RC-2026-0002")
    # the trail: the supersession and the new issue; a certify that fails after its number was
    # drawn leaves that number's draft and voiding, never an issued event
    bad = tmp_path / "bad.toml"
    bad.write_text(
        PLAN.replace('name = "Gyro Maker Ltd"\naddress', 'name = "Gyro\\u0001"\naddress')
    )
    one_line(run("certify", str(bad), "--db", db), "control character U+0001")
    audit = run("records", "audit", "--db", db, "--json", "-")
    assert audit.exit_code == 0, audit.output
    trail = json.loads(audit.output)
    assert trail["intact"] is True and trail["problems"] == []
    assert [(e["number"], e["to_state"], e["who"]) for e in trail["events"]] == [
        ("RC-2026-0001", "draft", "A. Operator"),
        ("RC-2026-0001", "issued", "B. Manager"),
        ("RC-2026-0001", "superseded", "B. Manager"),
        ("RC-2026-0002", "draft", "A. Operator"),
        ("RC-2026-0002", "issued", "B. Manager"),
        ("RC-2026-0003", "draft", "A. Operator"),
        ("RC-2026-0003", "voided", trail["events"][-1]["station"]),
    ]
    assert "control character U+0001" in trail["events"][-1]["reason"]
    text = run("records", "audit", "RC-2026-0001", "--db", db).output.splitlines()
    assert text[-1] == "audit trail of RC-2026-0001: intact, 3 events"
    assert text[2].endswith("issued → superseded  by B. Manager: superseded by RC-2026-0002")
    assert "  approved    by B. Manager at 20" in shown.output
    assert "issued → superseded  by B. Manager" in shown.output
    one_line(run("records", "audit", "RC-1999-0001", "--db", db), "no certificate RC-1999-0001")


def test_a_password_in_the_url_never_reaches_the_json(postgres, tmp_path: Path) -> None:
    # the test server trusts loopback, so a password in the URL is accepted and ignored
    db = postgres.new_database().replace("rotacal@", "rotacal:s3cret@")
    result = run("records", "list", "--db", db, "--json", "-")
    assert result.exit_code == 0, result.output
    assert "s3cret" not in result.output
    data = json.loads(result.output)
    assert data["provenance"]["options"]["db"].startswith("postgresql+psycopg://rotacal:***@")
    assert data["store"].startswith("postgresql+psycopg://rotacal:***@")
    one_line(
        run("records", "list", "--db", f"sqlite://u:pw@/{tmp_path / 'r.sqlite'}"),
        "takes no user, password or host",
    )
