"""Reading a calibration plan: every key checked, every fault one line naming the plan file, the
key and its line (INTERFACE.md, "Calibration plans and certificates")."""

from __future__ import annotations

import datetime as dt
import re
from pathlib import Path

import pytest

from rotacal.cli.certify import example_plan
from rotacal.errors import ConfigError
from rotacal.plan.read import MEASUREMENT_COMMANDS, read_plan
from rotacal.plan.run import command_of


@pytest.fixture
def folder(tmp_path: Path) -> Path:
    """A folder with the example plan and (empty, for reading only) captures it names."""
    for name in ("rates.npz", "triad.npz", "noise.npz"):
        (tmp_path / name).write_bytes(b"")
    (tmp_path / "plan.toml").write_text(example_plan(), encoding="utf-8")
    return tmp_path


def _edit(folder: Path, old: str, new: str) -> Path:
    path = folder / "plan.toml"
    text = path.read_text(encoding="utf-8")
    assert old in text, old
    path.write_text(text.replace(old, new, 1), encoding="utf-8")
    return path


def _line_of(path: Path, fragment: str, occurrence: int = 1) -> int:
    lines = [i + 1 for i, line in enumerate(path.read_text().splitlines()) if fragment in line]
    return lines[occurrence - 1]


def test_the_example_plan_reads_as_it_is(folder: Path) -> None:
    plan = read_plan(folder / "plan.toml")
    assert plan.number == "RC-2026-0001"
    assert plan.start_date == plan.end_date == plan.issue_date == dt.date(2026, 11, 25)
    assert [m.command for m in plan.measurements] == ["gyro scale-factor", "gyro triad", "allan"]
    first = plan.measurements[0]
    assert first.captures == ((folder / "rates.npz").resolve(),)
    assert dict(first.options) == {"full-scale-deg-s": 100, "output-unit": "V"}
    assert {(lim.key, lim.min, lim.max) for lim in first.limits} == {
        ("nonlinearity_percent_fs", None, 0.5),
        ("scale_factor", 0.0124, 0.0126),
    }
    assert first.decision_rule == "guarded"
    assert plan.measurements[2].decision_rule == "guarded"  # the default
    assert {p.role for p in plan.persons} == {"performed", "approved"}
    assert plan.laboratory.country == "DE"
    assert plan.conditions.temperature_c == 23.0 and plan.conditions.humidity_percent == 45


def test_every_measurement_command_exists_in_the_cli() -> None:
    for name in MEASUREMENT_COMMANDS:
        assert command_of(name).name == name.split()[-1]


# (old text, new text, the key the message must name, words it must hold, line to point at)
BAD = [
    (
        'number = "RC-2026-0001"',
        'number = "RC/2026"',
        "certificate.number",
        "folder",
        'number = "RC/2026"',
    ),
    ("date = 2026-11-25 ", 'date = "25.11.2026" ', "certificate.date", "2026-11-25", "date = "),
    (
        "date = 2026-11-25 ",
        "start_date = 2026-11-26\nend_date = 2026-11-25\n",
        "certificate.end_date",
        "before",
        "end_date = 2026",
    ),
    ('name = "Rate Lab"', "name = 42", "laboratory.name", "non-empty text", "name = 42"),
    (
        'country = "DE"',
        'country = "Germany"',
        "laboratory.country",
        "ISO 3166",
        'country = "Germany"',
    ),
    (
        'email = "lab@example.org"',
        'emial = "lab@example.org"',
        "laboratory.emial",
        "unknown key",
        "emial",
    ),
    (
        'role = "approved"',
        'role = "boss"',
        "person[2].role",
        "performed, approved",
        'role = "boss"',
    ),
    ('kind = "gyroscope"', 'kind = "gyro"', "item.kind", "gyroscope", 'kind = "gyro"'),
    ('serial = "SN-0001"', 'serial = ""', "item.serial", "non-empty", 'serial = ""'),
    ("due = 2027-06-30", "due = 2026-11-01", "standard[1].due", "recalibrate", "due = 2026-11-01"),
    ("due = 2027-06-30", "due = 2027-13-01", "", "not valid TOML", None),
    (
        "humidity_percent = 45",
        "humidity_percent = 145",
        "conditions.humidity_percent",
        "0…100",
        "humidity",
    ),
    (
        'capture = "triad.npz"',
        'capture = "triads.npz"',
        "measurement[2].capture",
        "no such file: triads.npz",
        'capture = "triads.npz"',
    ),
    (
        'command = "allan"',
        'command = "allen"',
        "measurement[3].command",
        "not a measurement command",
        'command = "allen"',
    ),
    (
        'command = "allan"',
        'command = "demo"',
        "measurement[3].command",
        "not a measurement command",
        'command = "demo"',
    ),
    (
        'decision_rule = "guarded"',
        'decision_rule = "strict"',
        "measurement[1].decision_rule",
        "simple or guarded",
        "strict",
    ),
    (
        "{ max = 0.5 } }",
        "{ max = 0.5, typ = 0.1 } }",
        "measurement[3].limits.arw_deg_rt_h.typ",
        "unknown key",
        "typ = 0.1",
    ),
    (
        "min = 0.0124, max = 0.0126",
        "min = 0.0126, max = 0.0124",
        "measurement[1].limits.scale_factor",
        "above max",
        "limits",
    ),
    (
        'options = { column = "rate_deg_s" }',
        'options = { column = "rate_deg_s", json = "x.json" }',
        "measurement[3].options.json",
        "leave this option out",
        "x.json",
    ),
    ("[conditions]", "[condition]", "condition", "unknown table", "[condition]"),
]


@pytest.mark.parametrize(
    ("old", "new", "key", "words", "line_text"), BAD, ids=[b[2] or b[3] for b in BAD]
)
def test_a_bad_plan_names_the_file_the_key_and_its_line(
    folder: Path, old: str, new: str, key: str, words: str, line_text: str | None
) -> None:
    path = _edit(folder, old, new)
    with pytest.raises(ConfigError) as err:
        read_plan(path)
    message = str(err.value)
    assert "\n" not in message
    assert message.startswith(f"{path}: {key}"), message
    assert words in message, message
    if line_text is not None:
        assert f"(line {_line_of(path, line_text)})" in message, message
    else:  # the TOML parser's own line
        assert re.search(r"line \d+", message), message


def test_a_missing_table_and_a_missing_person_role_are_named(folder: Path) -> None:
    path = folder / "plan.toml"
    text = path.read_text()
    start = text.index("[customer]")
    path.write_text(text[:start] + text[text.index("[[person]]") :])
    with pytest.raises(ConfigError, match=r"plan.toml: customer: is missing"):
        read_plan(path)
    path.write_text(text.replace('role = "approved"', 'role = "performed"'))
    with pytest.raises(
        ConfigError,
        match=r'plan.toml: person \(line \d+\): needs a \[\[person\]\] with role = "approved"',
    ):
        read_plan(path)
    # the approver reviews another person's work: the performer (any case or spacing) may not
    path.write_text(text.replace('name = "B. Manager"', 'name = "a.  OPERATOR"'))
    with pytest.raises(
        ConfigError, match=r"person\[2\] \(line \d+\): a.  OPERATOR both performed .* approves it"
    ):
        read_plan(path)


def test_a_plan_that_is_not_there_or_not_text(tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match="no such plan file"):
        read_plan(tmp_path / "nothing.toml")
    (tmp_path / "bin.toml").write_bytes(b"\xff\xfe\x00")
    with pytest.raises(ConfigError, match="not UTF-8"):
        read_plan(tmp_path / "bin.toml")
