"""Outputs on the command line: nothing the user gave is ever replaced, and no output is half-made.

Every file parameter of every command is found by walking the CLI, so a new input option is
covered (and one declared without INPUT_FILE fails here).
"""

from __future__ import annotations

import json
import multiprocessing
import os
import sys
import textwrap
from collections.abc import Iterator
from pathlib import Path

import click
import pytest
from click.testing import CliRunner

from rotacal.cli import cli
from rotacal.cli._common import INPUT_FILE
from rotacal.io import outputs, write_capture
from rotacal.sim import simulate_gyro_rates
from rotacal.uncertainty.specs import example_specs_toml


def run(*args: str):
    return CliRunner().invoke(cli, list(args), prog_name="rotacal")


def one_line_error(result, *needles: str) -> str:
    assert result.exit_code == 2, result.output
    err = result.stderr.strip()
    assert err.count("\n") == 0 and "Traceback" not in result.output, err
    for n in needles:
        assert n in err, err
    return err


def _commands(group: click.Group, prefix: tuple[str, ...] = ()) -> Iterator[tuple[str, ...]]:
    for name in group.list_commands(None):  # type: ignore[arg-type]  # (the lazy group's too)
        cmd = group.get_command(None, name)  # type: ignore[arg-type]
        if isinstance(cmd, click.Group):
            yield from _commands(cmd, (*prefix, name))
        else:
            yield (*prefix, name)


def _command(path: tuple[str, ...]) -> click.Command:
    cmd: click.Command = cli
    for name in path:
        assert isinstance(cmd, click.Group)
        sub = cmd.get_command(None, name)  # type: ignore[arg-type]
        assert sub is not None, path
        cmd = sub
    return cmd


def _inputs(path: tuple[str, ...]) -> list[click.Parameter]:
    return [p for p in _command(path).params if p.type is INPUT_FILE]


#: Every file a command reads, by command (the parameter names).
EXPECTED_INPUTS = {
    ("inspect",): {"capture"},
    ("allan",): {"capture", "specs"},
    ("gyro", "frequency-response"): {"capture", "more_captures", "specs"},
    ("gyro", "multiposition"): {"capture", "specs"},
    ("gyro", "resolution"): {"capture", "specs"},
    ("gyro", "accelerometer"): {"capture", "sections_path", "specs"},
    ("gyro", "rotations"): {"capture", "sections_path", "specs"},
    ("gyro", "scale-factor"): {"capture", "more_captures", "rates_path", "rest_from", "specs"},
    ("gyro", "triad"): {"capture", "specs"},
    ("motion", "encoder"): {"capture", "correction_from", "specs"},
    ("motion", "fog"): {"capture", "specs"},
    ("motion", "lts"): {"capture", "specs"},
    ("position",): {"capture", "selfcal_path", "specs"},
    ("motion", "angle"): {"capture", "specs"},
    ("rate",): {"capture", "selfcal_path", "specs"},
    ("selfcal",): {"capture", "specs"},
    ("turntable", "budget"): {"config"},
    ("turntable", "identify"): {"capture", "config_path", "budget_path", "specs"},
}

#: The options a command needs besides its files (to get as far as its outputs).
REQUIRED = {
    ("gyro", "multiposition"): ["--axis", "x"],
    ("motion", "encoder"): ["--lines", "36000"],
    ("motion", "lts"): ["--radius-mm", "100"],
    ("motion", "angle"): ["--counts-per-rev", "144000"],
    ("rate",): ["--pulses-per-rev", "18000"],
    ("selfcal",): ["--pulses-per-rev", "18000"],
}

#: File parameters that are outputs, not inputs.
OUTPUT_PARAMETERS = {("simulate", "out"), ("demo", "out"), ("turntable", "out"), ("specs", "out")}

#: The file each input parameter gets in these tests (contents never read: the refusal comes first).
FILES = {
    "capture": "cap.npz",
    "config": "table.toml",
    "config_path": "table.toml",
    "budget_path": "budget.json",
    "correction_from": "ref.npz",
    "more_captures": "more.npz",
    "rates_path": "rates.csv",
    "rest_from": "rest.npz",
    "selfcal_path": "sc.json",
    "sections_path": "sec.json",
    "specs": "specs.toml",
}


def test_every_file_a_command_reads_is_declared_as_an_input():
    declared = {path: {p.name for p in _inputs(path)} for path in _commands(cli)}
    assert {path: names for path, names in declared.items() if names} == EXPECTED_INPUTS
    for path in _commands(cli):
        for p in _command(path).params:
            if isinstance(p.type, click.Path) and p.type is not INPUT_FILE:
                assert (path[0], p.name) in OUTPUT_PARAMETERS, (path, p.name)


@pytest.fixture
def given(tmp_path: Path) -> dict[str, Path]:
    """The files a user gave: dummy bytes, except the specs, which are parsed while options are."""
    files = {name: tmp_path / file for name, file in FILES.items()}
    for name, path in files.items():
        path.write_bytes(f"precious {name}\n".encode())
    files["specs"].write_text(example_specs_toml())
    return files


def _argv(path: tuple[str, ...], files: dict[str, Path]) -> list[str]:
    argv = [*path, *REQUIRED.get(path, [])]
    arguments = 0
    for p in _inputs(path):
        if isinstance(p, click.Argument):
            argv.insert(len(path) + arguments, str(files[p.name or ""]))
            arguments += 1
        else:
            argv += [p.opts[0], str(files[p.name or ""])]
    return argv


CASES = [
    pytest.param(path, p.name, id=f"{' '.join(path)} {p.name}")
    for path in _commands(cli)
    for p in _inputs(path)
]


@pytest.mark.parametrize(("path", "name"), CASES)
@pytest.mark.parametrize("option", ["--json", "--report"])
@pytest.mark.parametrize("way", ["same path", "symlink", "hard link"])
def test_no_output_replaces_an_input(tmp_path, given, path, name, option, way):
    """Refused with --overwrite (and before anything is read: the dummy files are no captures)."""
    source = given[name]
    target = {"same path": source, "symlink": tmp_path / "link", "hard link": tmp_path / "hard"}
    if way == "symlink":
        target[way].symlink_to(source)
    elif way == "hard link":
        os.link(source, target[way])
    before = {p.name: p.read_bytes() for p in tmp_path.iterdir()}
    param = next(p for p in _inputs(path) if p.name == name)
    label = param.opts[0] if isinstance(param, click.Option) else param.human_readable_name
    r = run(*_argv(path, given), option, str(target[way]), "--overwrite")
    one_line_error(r, f"{option} {target[way]} would overwrite the input {label} {source}")
    assert {p.name: p.read_bytes() for p in tmp_path.iterdir()} == before


@pytest.mark.parametrize(("path", "name"), CASES)
def test_an_input_is_refused_without_overwrite_too(given, path, name):
    r = run(*_argv(path, given), "--json", str(given[name]))
    one_line_error(r, "would overwrite the input")


# ---------------------------------------------------------------------------- real analyses
@pytest.fixture(scope="module")
def capture(tmp_path_factory) -> Path:
    """A small gyro rate-table capture (11 rates × 200 samples)."""
    cap = simulate_gyro_rates(samples_per_point=200, seed=7)
    return write_capture(tmp_path_factory.mktemp("cap") / "rates.npz", cap.columns)


def _scale_factor(capture: Path, *more: str):
    return run("gyro", "scale-factor", str(capture), *more)


def test_overwrite_replaces_the_output_atomically(capture, tmp_path, unrendered_figures):
    """--overwrite puts a new file in place (a hard link to the old one keeps the old bytes)."""
    # one-pixel figures: this test never looks at them (tests/report draws and looks at them)
    out = tmp_path / "r.json"
    out.write_text("old")
    os.link(out, tmp_path / "keep.json")
    inode = out.stat().st_ino
    assert _scale_factor(capture, "--json", str(out), "--overwrite").exit_code == 0
    assert json.loads(out.read_text())["scale_factor"] > 0 and out.stat().st_ino != inode
    assert (tmp_path / "keep.json").read_text() == "old"
    (tmp_path / "real.html").write_text("old")
    (tmp_path / "link.html").symlink_to("real.html")
    assert (
        _scale_factor(capture, "--report", str(tmp_path / "link.html"), "--overwrite").exit_code
        == 0
    )
    assert (tmp_path / "link.html").is_symlink()
    assert "<html" in (tmp_path / "real.html").read_text().lower()
    assert sorted(p.name for p in tmp_path.iterdir()) == [
        "keep.json",
        "link.html",
        "r.json",
        "real.html",
    ]


def test_an_analysis_that_fails_after_the_checks_leaves_no_file(tmp_path):
    cap = write_capture(tmp_path / "enc.npz", {"time_s": [0.0, 1.0], "a": [0.0, 1.0]})
    r = run(
        "gyro",
        "scale-factor",
        str(cap),
        "--json",
        str(tmp_path / "out" / "r.json"),
        "--report",
        str(tmp_path / "r.html"),
    )
    one_line_error(r, "rate_deg_s")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["enc.npz"]  # no output, folder or temp


def _cli_in_a_process(argv: list[str], log: str) -> None:
    fd = os.open(log, os.O_WRONLY | os.O_CREAT | os.O_TRUNC)
    os.dup2(fd, 2)
    sys.stderr = os.fdopen(2, "w", buffering=1)
    from rotacal.cli import main

    main(argv)


def test_ten_processes_writing_one_json_exactly_one_wins(capture, tmp_path, monkeypatch):
    """Ten real processes run the command at once; all get past the checks before any names
    its file (a barrier after the temporary file is written), so nine must lose the race.
    The command is ``inspect``: every command writes through the same ``write_outputs``, and
    inspect's work is a tenth of a second where the scale factor's 200 000-trial Monte Carlo
    took a second in each of the ten processes."""
    ctx = multiprocessing.get_context("fork")  # the children start with rotacal imported
    barrier = ctx.Barrier(10)
    real = outputs._write_temporary

    def write_then_wait(*args, **kwargs):  # type: ignore[no-untyped-def]
        tmp = real(*args, **kwargs)
        barrier.wait(timeout=120)
        return tmp

    monkeypatch.setattr(outputs, "_write_temporary", write_then_wait)
    out = tmp_path / "out" / "r.json"
    argv = ["inspect", str(capture), "--json", str(out)]
    logs = [str(tmp_path / f"{i}.log") for i in range(10)]
    procs = [ctx.Process(target=_cli_in_a_process, args=(argv, log)) for log in logs]
    for p in procs:
        p.start()
    for p in procs:
        p.join(timeout=300)
    codes = [p.exitcode for p in procs]
    assert sorted(codes) == [0] + [2] * 9, codes
    for code, log in zip(codes, logs, strict=True):
        err = Path(log).read_text()
        if code == 2:
            assert err == (
                f"rotacal: error: --json {out} was created by another process meanwhile; "
                "choose another name or pass --overwrite\n"
            )
    assert json.loads(out.read_text())["provenance"]["command"] == "inspect"
    assert [p.name for p in out.parent.iterdir()] == ["r.json"]  # no temporary left


# ------------------------------------------------------------------- paths refused before the work
@pytest.mark.parametrize(
    "argv",
    [
        ["gyro", "scale-factor", "{cap}", "--json", "{cap}/r.json"],
        ["gyro", "scale-factor", "{cap}", "--report", "{cap}/sub/r.html"],
        ["turntable", "budget", "{cap}", "--json", "{cap}/r.json"],
        ["simulate", "gyro-rates", "--out", "{cap}/x.npz", "--noise-std", "-1"],
        ["turntable", "example", "--out", "{cap}/t.toml"],
        ["specs", "example", "--out", "{cap}/s.toml"],
        ["demo", "--out", "{cap}/demo"],
    ],
    ids=lambda argv: " ".join(argv[:2]),
)
def test_an_output_under_a_regular_file_fails_before_the_work(tmp_path, argv):
    """The capture is no capture and the simulation's noise is negative: the output is named."""
    cap = tmp_path / "cap.csv"
    cap.write_text("not a capture")
    r = run(*[a.format(cap=cap) for a in argv])
    one_line_error(r, f"{cap} is a file, not a folder")
    assert [p.name for p in tmp_path.iterdir()] == ["cap.csv"]


@pytest.mark.parametrize("overwrite", [[], ["--overwrite"]])
def test_a_dangling_symlink_is_not_followed(tmp_path, overwrite):
    target = tmp_path / "elsewhere"
    for name in ("r.json", "x.npz", "s.toml", "x.npz.truth.json"):
        (tmp_path / name).symlink_to(target / name)
    cap = tmp_path / "cap.csv"
    cap.write_text("not a capture")
    for argv in (
        ["gyro", "scale-factor", str(cap), "--json", str(tmp_path / "r.json")],
        ["simulate", "gyro-rates", "--out", str(tmp_path / "x.npz")],
        ["specs", "example", "--out", str(tmp_path / "s.toml")],
    ):
        one_line_error(run(*argv, *overwrite), "is a dangling symbolic link")
    assert not target.exists()


def test_simulate_checks_the_extension_before_simulating(tmp_path):
    r = run("simulate", "gyro-rates", "--out", str(tmp_path / "x.xlsx"), "--noise-std", "-1")
    one_line_error(r, "unknown capture extension '.xlsx'")
    assert list(tmp_path.iterdir()) == []


def test_simulate_writes_the_capture_and_its_truth_or_neither(tmp_path):
    (tmp_path / "x.npz.truth.json").write_text("keep")
    r = run("simulate", "gyro-rates", "--out", str(tmp_path / "x.npz"))
    one_line_error(r, "x.npz.truth.json (the truth beside --out) already exists")
    assert [p.name for p in tmp_path.iterdir()] == ["x.npz.truth.json"]


def test_an_unwritable_folder_fails_before_the_work(tmp_path, bound_by_permissions):
    """In a process the permission bits bind (the tests run as root, whom they do not)."""
    ro = tmp_path / "ro"
    ro.mkdir()
    cap = tmp_path / "cap.csv"
    cap.write_text("not a capture")
    commands = [
        ["gyro", "scale-factor", str(cap), "--json", str(ro / "r.json")],
        ["gyro", "scale-factor", str(cap), "--report", str(ro / "new" / "r.html")],
        ["simulate", "gyro-rates", "--out", str(ro / "x.npz")],
        ["turntable", "example", "--out", str(ro / "t.toml")],
        ["demo", "--out", str(ro / "demo")],
    ]
    code = textwrap.dedent(
        f"""
        import sys
        from rotacal.cli import main
        for argv in {commands!r}:
            try:
                main(argv)
            except SystemExit as e:
                print(e.code)
            sys.stderr.flush()
        """
    )
    os.chmod(ro, 0o555)
    try:
        p = bound_by_permissions(["-c", code], unwritable=ro)
    finally:
        os.chmod(ro, 0o755)
    assert p.stdout.split() == ["2"] * len(commands), (p.stdout, p.stderr)
    errors = p.stderr.splitlines()
    assert len(errors) == len(commands), p.stderr
    for line in errors:
        assert (
            f"no permission to write in folder {ro} (or it is on a read-only file system)" in line
        )
    assert list(ro.iterdir()) == []
