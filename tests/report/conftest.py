"""The reports the tests of tests/report look at: the demo's (one run per session, shared with
tests/cli/test_plausibility_cli.py) and one of each CLI command that writes a report; the
headless browser (Debian's chromium, driven by Playwright — never a downloaded browser)."""

from __future__ import annotations

import dataclasses
import json
import shutil
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import pytest
from click.testing import CliRunner

from rotacal.cli import cli

CHROMIUM = "/usr/bin/chromium"
#: No network, no first-run work, no GPU: the browser sees only the file it is given.
CHROMIUM_ARGS = [
    "--no-sandbox",
    "--disable-gpu",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--no-first-run",
]
INSTALL_HINT = (
    "the report tests need Debian's chromium at /usr/bin/chromium and the Python package "
    "playwright: apt-get update && apt-get install -y chromium; pip install -e '.[dev]'"
)


def _run(*args: str) -> Any:
    result = CliRunner().invoke(cli, list(args), prog_name="rotacal")
    assert result.exit_code == 0, result.output
    return result


@pytest.fixture(scope="session")
def browser() -> Iterator[Any]:
    """A headless chromium; missing chromium or Playwright FAILS the test with how to install."""
    if shutil.which(CHROMIUM) is None:
        pytest.fail(f"{CHROMIUM} is missing: {INSTALL_HINT}", pytrace=False)
    try:
        from playwright.sync_api import sync_playwright
    except ImportError:
        pytest.fail(f"playwright is not installed: {INSTALL_HINT}", pytrace=False)
    with sync_playwright() as p:
        chromium = p.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS)
        yield chromium
        chromium.close()


#: The twins of ``rotacal simulate`` whose analysis writes a report, each with its defaults (the
#: defaults must give warning-free results: tests/report/test_warning_free.py).
_TWINS = [
    "encoder",
    "lts",
    "fog",
    "pulses",
    "gyro-rates",
    "gyro-triad",
    "gyro-noise",
    "gyro-rotations",
    "multiposition",
    "position",
]


@dataclasses.dataclass(frozen=True)
class CliRun:
    """One CLI analysis of the session: its report, its JSON result, what it wrote on stderr."""

    report: Path
    result: dict[str, Any]
    stderr: str


@pytest.fixture(scope="session")
def cli_runs(
    tmp_path_factory: pytest.TempPathFactory,
    analysis_args: Callable[[str, str, dict[str, Any]], list[str]],
) -> dict[str, CliRun]:
    """One run of each command that writes a report (``--report``, and ``--json`` beside it), on
    the twins with their defaults: {command: CliRun}. The browser reads the reports
    (test_browser.py); the results' warnings are checked by test_warning_free.py, so each twin
    is simulated and analysed once per session for both."""
    folder = tmp_path_factory.mktemp("cli-reports")
    runs: dict[str, CliRun] = {}

    def report(name: str, *args: str) -> None:
        path = folder / f"{name.replace(' ', '-')}.html"
        result = path.with_suffix(".json")
        done = _run(*args, "--report", str(path), "--json", str(result))
        runs[name] = CliRun(path, json.loads(result.read_text()), done.stderr)

    for kind in _TWINS:
        capture = folder / f"{kind}.npz"
        _run("simulate", kind, "--out", str(capture))
        truth = json.loads(Path(f"{capture}.truth.json").read_text())
        args = analysis_args(kind, str(capture), truth)
        report(" ".join(args[: args.index(str(capture))]), *args)  # "gyro triad"
        if kind == "pulses":
            lines = str(truth["pulses_per_rev"])
            rate = str(truth["set_rate_deg_s"])
            report(
                "rate", "rate", str(capture), "--pulses-per-rev", lines, "--set-rate-deg-s", rate,
                "--window-deg", "1,10,360",
            )  # fmt: skip
            report("inspect", "inspect", str(capture))
    config = folder / "table.toml"
    _run("turntable", "example", "--out", str(config))
    report("turntable budget", "turntable", "budget", str(config), "--runs", "20000")
    errors = folder / "orientation.npz"
    _run("simulate", "orientation", "--out", str(errors))
    budget = folder / "turntable-budget.json"
    report("turntable identify", "turntable", "identify", str(errors), "--budget", str(budget))
    sweep = [folder / f"sine{f}.npz" for f in (1, 4, 8, 12)]
    for i, path in enumerate(sweep):
        _run(
            "simulate",
            "gyro-sine",
            "--frequency-hz",
            path.stem[4:],
            "--seed",
            str(i),
            "--out",
            str(path),
        )
    report(
        "gyro frequency-response", "gyro", "frequency-response", *map(str, sweep), "--lines", "3600"
    )
    return runs


@pytest.fixture(scope="session")
def cli_reports(cli_runs: dict[str, CliRun]) -> dict[str, Path]:
    """One report of each command that writes one: {command: path} (``cli_runs``' reports)."""
    return {name: run.report for name, run in cli_runs.items()}


@pytest.fixture(scope="session")
def demo_folder(demo_run: tuple[Path, Any]) -> Path:
    """The folder of the session's demo (tests using it carry xdist_group("demo"))."""
    return demo_run[0]
