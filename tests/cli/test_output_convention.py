"""One output convention for every command: ``wrote PATH`` lines, --overwrite, output extensions,
``provenance`` and ``warnings`` in every JSON, byte-identical JSON run to run.

Every command is found by walking the CLI: a new command without a recipe here fails
``test_every_command_has_a_recipe``, so it cannot miss the convention.
"""

from __future__ import annotations

import hashlib
import json
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

import rotacal
from rotacal.cli import cli
from rotacal.demo import demo_files
from rotacal.io.outputs import Output, write_outputs
from rotacal.uncertainty.specs import example_specs_toml

from .test_outputs import _commands


def run(*args: str):
    return CliRunner().invoke(cli, list(args), prog_name="rotacal")


def wrote_lines(result) -> list[str]:
    """The ``wrote`` lines on stderr, and none on stdout."""
    assert "wrote " not in result.stdout, result.stdout
    return [line for line in result.stderr.splitlines() if line.startswith("wrote ")]


def one_line_error(result, *needles: str) -> str:
    assert result.exit_code == 2, (result.stdout, result.stderr)
    err = result.stderr.strip()
    assert err.count("\n") == 0 and "Traceback" not in result.output, err
    for needle in needles:
        assert needle in err, err
    return err


# ------------------------------------------------------------------------------ small captures
@pytest.fixture(scope="module")
def captures(tmp_path_factory) -> dict[str, Path]:
    """Small twin captures of every kind, made with `rotacal simulate` (and the example files)."""
    folder = tmp_path_factory.mktemp("captures")
    small = {
        "encoder": ["--duration-s", "3"],
        "lts": ["--duration-s", "3"],
        "fog": ["--duration-s", "3"],
        "angle": ["--duration-s", "3"],
        "pulses": ["--heads", "4", "--pulses-per-rev", "360", "--revolutions", "3"],
        "gyro-rates": ["--samples-per-point", "50"],
        "gyro-triad": ["--samples-per-point", "20"],
        "gyro-noise": ["--duration-s", "600"],
        "gyro-rotations": [],
        "gyro-steps": ["--samples-per-dwell", "20"],
        "ferraris": [],
        "multiposition": [],
        "orientation": [],
        "gyro-sine": ["--frequency-hz", "2", "--periods", "3"],
        "gyro-sine-6": ["--frequency-hz", "6", "--periods", "3"],
        "position": ["--positions", "12", "--runs", "2"],
    }
    out = {}
    for kind, more in small.items():
        path = folder / f"{kind}.npz"
        r = run("simulate", kind.removesuffix("-6"), "--out", str(path), *more)
        assert r.exit_code == 0, r.output
        out[kind] = path
    out["table"] = folder / "table.toml"
    assert run("turntable", "example", "--out", str(out["table"])).exit_code == 0
    out["specs"] = folder / "specs.toml"
    out["specs"].write_text(example_specs_toml())
    return out


#: How each analysis command runs on the small captures: (capture kind, further arguments).
ANALYSES: dict[tuple[str, ...], tuple[str, list[str]]] = {
    ("allan",): ("gyro-noise", []),
    ("inspect",): ("fog", []),
    ("gyro", "frequency-response"): ("gyro-sine", ["{gyro-sine-6}", "--lines", "3600"]),
    ("gyro", "multiposition"): ("multiposition", ["--axis", "x", "--latitude-deg", "45.75"]),
    ("gyro", "resolution"): ("gyro-steps", []),
    ("gyro", "rotations"): ("gyro-rotations", ["--sections", "{gyro-rotations}.truth.json"]),
    ("gyro", "accelerometer"): ("ferraris", ["--sections", "{ferraris}.truth.json"]),
    ("gyro", "scale-factor"): ("gyro-rates", []),
    ("gyro", "triad"): ("gyro-triad", []),
    ("motion", "encoder"): ("encoder", ["--lines", "36000"]),
    ("motion", "fog"): ("fog", []),
    ("motion", "lts"): ("lts", ["--radius-mm", "100"]),
    ("position",): ("position", ["--harmonics", "2"]),
    ("motion", "angle"): ("angle", ["--counts-per-rev", "144000"]),
    ("rate",): ("pulses", ["--pulses-per-rev", "360"]),
    ("selfcal",): ("pulses", ["--pulses-per-rev", "360"]),
    # the paper's derivation allocates once, the default twice: the outputs are the same kind
    ("turntable", "identify"): ("orientation", []),
    ("turntable", "budget"): (
        "table",
        ["--runs", "2000", "--requirement-derivation", "earth-rate-only"],
    ),
}
#: Commands that write files of their own (--out): the names they write for ``--out NAME``.
WRITERS: dict[tuple[str, ...], list[str]] = {
    **{
        ("simulate", kind): ["x.npz", "x.npz.truth.json"]
        for kind in (
            "angle",
            "encoder",
            "ferraris",
            "fog",
            "gyro-log",
            "gyro-noise",
            "gyro-rates",
            "gyro-rotations",
            "gyro-sine",
            "gyro-steps",
            "gyro-triad",
            "gyro-triad-log",
            "lts",
            "multiposition",
            "orientation",
            "position",
            "pulses",
        )
    },
    ("turntable", "example"): ["x.toml"],
    ("specs", "example"): ["x.toml"],
}
WRITER_ARGS = {
    ("simulate", "pulses"): ["--heads", "3", "--pulses-per-rev", "360", "--revolutions", "1.5"],
    ("simulate", "gyro-noise"): ["--duration-s", "60"],
    ("simulate", "gyro-log"): ["--plateau-s", "5"],
    ("simulate", "gyro-triad-log"): ["--run-s", "61", "--fs-hz", "5"],
    ("simulate", "gyro-sine"): ["--frequency-hz", "2", "--periods", "2"],
    ("simulate", "encoder"): ["--duration-s", "1"],
    ("simulate", "lts"): ["--duration-s", "1"],
    ("simulate", "fog"): ["--duration-s", "1"],
    ("simulate", "angle"): ["--duration-s", "1"],
}


def test_every_command_has_a_recipe():
    # certify's convention (wrote lines, --overwrite, identical JSON) is checked in
    # tests/certificate/test_certify.py, on a plan of its own; the records commands' in
    # tests/records/test_cli.py, on a store of their own; batch's (its folder and batch.json,
    # which each run of the same batch rewrites, a foreign batch.json refused) in tests/batch;
    # verify's in tests/certificate/test_signing.py, on a signed certificate of its own
    records = {("records", c) for c in ("list", "show", "history", "audit", "export", "import")}
    records |= {("records", "upgrade"), ("records", "settings")}
    special = {("demo",), ("certify",), ("batch",), ("verify",), *records}
    assert set(_commands(cli)) == {*ANALYSES, *WRITERS, *special}


def _analysis_argv(path: tuple[str, ...], captures: dict[str, Path]) -> list[str]:
    kind, more = ANALYSES[path]
    return [
        *path,
        str(captures[kind]),
        *(
            m.replace("{gyro-rotations}", str(captures["gyro-rotations"]))
            .replace("{gyro-sine-6}", str(captures["gyro-sine-6"]))
            .replace("{ferraris}", str(captures["ferraris"]))
            for m in more
        ),
    ]


# ------------------------------------------------------------------ wrote lines and --overwrite
@pytest.mark.parametrize(
    "path",
    [
        # the budget with the other budgets of the example table (tests/conftest.py)
        pytest.param(path, marks=pytest.mark.xdist_group("demo"))
        if path == ("turntable", "budget")
        else path
        for path in sorted(ANALYSES)
    ],
    ids=" ".join,
)
def test_analysis_wrote_lines_overwrite_and_identical_json(
    captures, tmp_path, path, unrendered_figures
):
    """One ``wrote`` line per file; a second run refuses to replace them without --overwrite
    (before any work, leaving them as they were); with it, the JSON comes out byte-identical.
    (The reports' figures are one pixel here: tests/report draws and looks at them.)"""
    argv = _analysis_argv(path, captures)
    out_json, out_html = tmp_path / "r.json", tmp_path / "r.html"
    first = run(*argv, "--json", str(out_json), "--report", str(out_html))
    assert first.exit_code == 0, first.output
    assert wrote_lines(first) == [f"wrote {out_json}", f"wrote {out_html}"]
    data = json.loads(out_json.read_text())
    assert isinstance(data["warnings"], list)
    assert data["provenance"]["command"] == " ".join(path)
    assert data["provenance"]["inputs"][0] == _record(captures[ANALYSES[path][0]])
    _check_plus_minus(first.stdout, data)
    before = {p.name: p.read_bytes() for p in tmp_path.iterdir()}

    one_line_error(run(*argv, "--json", str(out_json)), f"--json {out_json} already exists")
    one_line_error(run(*argv, "--report", str(out_html)), f"--report {out_html} already exists")
    assert {p.name: p.read_bytes() for p in tmp_path.iterdir()} == before

    again = run(*argv, "--json", str(out_json), "--overwrite")
    assert again.exit_code == 0, again.output
    assert wrote_lines(again) == [f"wrote {out_json}"]
    assert out_json.read_bytes() == before["r.json"]  # no wall-clock time in the provenance


@pytest.mark.parametrize("path", sorted(WRITERS), ids=" ".join)
def test_writer_wrote_lines_and_overwrite(tmp_path, path):
    names = WRITERS[path]
    target = tmp_path / names[0]
    argv = [*path, "--out", str(target), *WRITER_ARGS.get(path, [])]
    first = run(*argv)
    assert first.exit_code == 0, first.output
    assert wrote_lines(first) == [f"wrote {tmp_path / name}" for name in names]
    assert first.stdout == ""
    before = {p.name: p.read_bytes() for p in tmp_path.iterdir()}
    one_line_error(run(*argv), "already exists", "--overwrite")
    assert {p.name: p.read_bytes() for p in tmp_path.iterdir()} == before
    again = run(*argv, "--overwrite")
    assert again.exit_code == 0, again.output
    assert wrote_lines(again) == [f"wrote {tmp_path / name}" for name in names]


def test_json_to_stdout_is_json_alone(captures):
    r = run(*_analysis_argv(("gyro", "scale-factor"), captures), "--json", "-")
    assert r.exit_code == 0, r.output
    data = json.loads(r.stdout)  # no summary, no wrote line mixed in
    assert data["provenance"]["command"] == "gyro scale-factor"
    assert wrote_lines(r) == []


# ------------------------------------------------------------------------------------- the demo
def test_demo_writes_one_line_per_file(tmp_path, monkeypatch):
    """The CLI's part of the demo (the campaign itself takes minutes: a stand-in writes its files
    as run_demo does, all together)."""
    import rotacal.demo

    def stand_in(out, progress=None, *, overwrite=False):  # type: ignore[no-untyped-def]
        outputs = [Output(Path(out) / name, "{}\n") for name in demo_files()]
        return write_outputs(outputs, overwrite=overwrite, make_folders=True)

    monkeypatch.setattr(rotacal.demo, "run_demo", stand_in)
    out = tmp_path / "demo"
    r = run("demo", "--out", str(out))
    assert r.exit_code == 0, r.output
    assert wrote_lines(r) == [f"wrote {out / name}" for name in demo_files()]
    assert "report.html" in demo_files()


@pytest.mark.parametrize("name", ["report.html", "summary.json", "motion_0.5deg_2hz_encoder.json"])
def test_demo_refuses_to_replace_an_earlier_demo_or_an_edited_file(tmp_path, name):
    """Refused before the campaign runs (so at once), the file kept as the user left it."""
    out = tmp_path / "demo"
    out.mkdir()
    (out / name).write_text("edited by the user\n")
    one_line_error(
        run("demo", "--out", str(out)), f"--out {out} already holds {name}", "--overwrite"
    )
    assert [p.name for p in out.iterdir()] == [name]
    assert (out / name).read_text() == "edited by the user\n"


def test_demo_files_are_those_the_demo_writes():
    """Every name once, the report last (it is written after the JSONs it summarises)."""
    names = demo_files()
    assert len(names) == len(set(names)) and names[-1] == "report.html"
    assert sum(n.startswith("motion_") for n in names) == 10  # Table 1: 5 motions × 2 schemes


# ---------------------------------------------------------------------------------- extensions
def _dummy_argv(path: tuple[str, ...], tmp_path: Path) -> list[str]:
    """The command with dummy input files (never read: the extension check comes first)."""
    _, more = ANALYSES[path]
    capture = tmp_path / "cap.npz"
    capture.write_bytes(b"not read")
    sections = tmp_path / "sec.json"
    sections.write_text("{}")
    return [
        *path,
        str(capture),
        *(
            m.replace("{gyro-rotations}.truth.json", str(sections))
            .replace("{gyro-sine-6}", str(capture))
            .replace("{ferraris}.truth.json", str(sections))
            for m in more
        ),
    ]


@pytest.mark.parametrize("path", sorted(ANALYSES), ids=" ".join)
@pytest.mark.parametrize(
    ("option", "name", "needles"),
    [
        ("--report", "r.pdf", ["PDF certificates", "rotacal certify", ".html"]),
        ("--report", "r.json", ["the report is HTML", ".html"]),
        ("--report", "r", ["the report is HTML"]),
        ("--json", "r.html", ["the results are JSON", ".json"]),
        ("--json", "r.txt", ["the results are JSON", ".json"]),
    ],
)
def test_an_output_named_for_another_format_is_refused(tmp_path, path, option, name, needles):
    r = run(*_dummy_argv(path, tmp_path), option, str(tmp_path / name))
    one_line_error(r, f"{option} {tmp_path / name}", *needles)
    assert not (tmp_path / name).exists()


@pytest.mark.parametrize("path", sorted(ANALYSES), ids=" ".join)
def test_swapped_json_and_report_are_refused_naming_both(tmp_path, path):
    json_name, report_name = tmp_path / "r.html", tmp_path / "r.json"
    r = run(*_dummy_argv(path, tmp_path), "--json", str(json_name), "--report", str(report_name))
    one_line_error(r, f"--json {json_name}", f"--report {report_name}", "swapped")


def test_extensions_are_case_blind_and_htm_is_html(captures, tmp_path, unrendered_figures):
    argv = _analysis_argv(("gyro", "scale-factor"), captures)
    r = run(*argv, "--json", str(tmp_path / "R.JSON"), "--report", str(tmp_path / "r.htm"))
    assert r.exit_code == 0, r.output


# ---------------------------------------------------------------------------------- provenance
def _sha256(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def _record(path: Path) -> dict:
    return {"path": str(path), "sha256": _sha256(path), "bytes": len(path.read_bytes())}


def test_provenance_of_an_analysis(captures, tmp_path):
    capture, specs = captures["gyro-rates"], captures["specs"]
    out = tmp_path / "r.json"
    r = run(
        "gyro",
        "scale-factor",
        str(capture),
        "--specs",
        str(specs),
        "--full-scale-deg-s",
        "100",
        "--column",
        "output=output",
        "--json",
        str(out),
    )
    assert r.exit_code == 0, r.output
    data = json.loads(out.read_text())
    assert isinstance(data["warnings"], list)
    prov = data["provenance"]
    assert set(prov) == {"rotacal_version", "command", "options", "inputs"}
    assert prov["rotacal_version"] == rotacal.__version__
    assert prov["command"] == "gyro scale-factor"
    assert prov["inputs"] == [_record(capture), _record(specs)]
    assert prov["options"] == {
        "capture": str(capture),
        "more_captures": [],
        "rate-from-name": False,
        "rates": None,
        "rest-from": [],
        "rest-band-deg-s": 0.5,
        "rest-guard-samples": 3,
        "plateaus": None,  # a continuous log or not: chosen by a time_s column
        "settle-s": None,
        "plateau-window-s": None,
        "min-plateau-s": None,
        "full-scale-deg-s": 100.0,
        "requirement": None,
        "output-unit": "",
        "sample-rate-hz": None,
        "bandwidth-hz": None,
        "chunked": None,  # streamed or in memory: chosen by the log's length
        "workers": None,
        "scheduler": None,
        "allow-clipped": False,
        "column": ["output=output"],
        "group": None,
        "specs": str(specs),  # the path as given, not the specifications read from it
        "delimiter": None,
        "decimal": ".",
        "names": None,
    }


def test_provenance_names_every_input_file(captures, tmp_path):
    """rate with --selfcal: the capture and the selfcal JSON, each hashed."""
    selfcal = tmp_path / "sc.json"
    pulses = captures["pulses"]
    assert (
        run("selfcal", str(pulses), "--pulses-per-rev", "360", "--json", str(selfcal)).exit_code
        == 0
    )
    out = tmp_path / "rate.json"
    r = run(
        "rate",
        str(pulses),
        "--pulses-per-rev",
        "360",
        "--selfcal",
        str(selfcal),
        "--json",
        str(out),
    )
    assert r.exit_code == 0, r.output
    prov = json.loads(out.read_text())["provenance"]
    assert prov["command"] == "rate"
    assert prov["inputs"] == [_record(pulses), _record(selfcal)]
    assert prov["options"]["selfcal"] == str(selfcal)


def _check_plus_minus(summary: str, data: dict) -> None:
    """The summary (printed also when the results go to files) states U with k and p, never a
    bare u; a result with a U shows one."""
    assert summary.strip(), "no summary on the terminal"
    for line in summary.splitlines():
        assert "u = " not in line, line
        if "±" in line:
            assert "(k = " in line and "p = 95 %)" in line, line
    if any(key.endswith("_U") and data[key] for key in data):
        assert "±" in summary or "true value in [" in summary, summary


def test_scale_factor_line_is_the_rounded_statement(captures):
    """S = value ± U with U to two significant digits and the value to the same place."""
    from rotacal.numbers import format_quantity

    argv = _analysis_argv(("gyro", "scale-factor"), captures)
    data = json.loads(run(*argv, "--json", "-").stdout)
    line = next(x for x in run(*argv).stdout.splitlines() if x.startswith("scale factor S"))
    U = data["scale_factor_U"]
    digits_after_point = -int(f"{U:.1e}".split("e")[1]) + 1
    value = f"{data['scale_factor']:.{digits_after_point}f}"
    assert f"{value} ± " in line
    assert line.endswith(
        format_quantity(
            data["scale_factor"],
            "output unit/(deg/s)",
            U=U,
            k=data["k"]["scale_factor"],
            p=data["coverage_probability"],
        )
    )


def test_the_json_does_not_depend_on_the_order_of_the_arguments(captures, tmp_path):
    capture, specs = str(captures["gyro-rates"]), str(captures["specs"])
    a, b = tmp_path / "a.json", tmp_path / "b.json"
    assert run("gyro", "scale-factor", capture, "--specs", specs, "--json", str(a)).exit_code == 0
    assert run("gyro", "scale-factor", "--json", str(b), "--specs", specs, capture).exit_code == 0
    assert a.read_bytes() == b.read_bytes()


def test_a_file_is_hashed_in_blocks_to_the_same_digest(tmp_path):
    """Larger than two 1 MiB blocks and not a multiple of one; and an empty file."""
    from rotacal.provenance import HASH_BLOCK_BYTES, file_record

    data = np.random.default_rng(1).bytes(2 * HASH_BLOCK_BYTES + 12_345)
    big, empty = tmp_path / "big.bin", tmp_path / "empty.csv"
    big.write_bytes(data)
    empty.write_bytes(b"")
    assert file_record(big) == {
        "path": str(big),
        "sha256": hashlib.sha256(data).hexdigest(),
        "bytes": len(data),
    }
    assert file_record(empty)["sha256"] == hashlib.sha256(b"").hexdigest()


@pytest.mark.parametrize("command", [("turntable", "example"), ("specs", "example")])
def test_a_toml_example_must_be_named_toml(tmp_path, command):
    one_line_error(run(*command, "--out", str(tmp_path / "x.txt")), "ending in .toml")
    assert list(tmp_path.iterdir()) == []
