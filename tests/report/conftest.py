"""The reports the tests of tests/report look at: the demo's (one run per session, shared with
tests/cli/test_plausibility_cli.py) and one of each CLI command that writes a report; the
headless browser (Debian's chromium, driven by Playwright — never a downloaded browser)."""

from __future__ import annotations

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


#: Small twins (seconds each, in-process) and the extra options of their analysis commands.
_TWINS: dict[str, list[str]] = {
    "encoder": ["--duration-s", "3.1"],
    "lts": [],
    "fog": [],
    "pulses": ["--pulses-per-rev", "3600", "--revolutions", "3.2"],
    "gyro-rates": [],
    "gyro-triad": [],
    "gyro-noise": ["--duration-s", "1800"],
    "gyro-rotations": [],
    "multiposition": [],
}


@pytest.fixture(scope="session")
def cli_reports(
    tmp_path_factory: pytest.TempPathFactory,
    analysis_args: Callable[[str, str, dict[str, Any]], list[str]],
) -> dict[str, Path]:
    """One report of each command that writes one (``--report``), made from small twins:
    {command: path}."""
    folder = tmp_path_factory.mktemp("cli-reports")
    reports: dict[str, Path] = {}

    def report(name: str, *args: str) -> None:
        path = folder / f"{name.replace(' ', '-')}.html"
        _run(*args, "--report", str(path))
        reports[name] = path

    for kind, options in _TWINS.items():
        capture = folder / f"{kind}.npz"
        _run("simulate", kind, "--out", str(capture), *options)
        truth = json.loads(Path(f"{capture}.truth.json").read_text())
        args = analysis_args(kind, str(capture), truth)
        report(" ".join(args[: args.index(str(capture))]), *args)  # "gyro triad"
        if kind == "pulses":
            report("rate", "rate", str(capture), "--pulses-per-rev", "3600")
            report("inspect", "inspect", str(capture))
    config = folder / "table.toml"
    _run("turntable", "example", "--out", str(config))
    report("turntable budget", "turntable", "budget", str(config), "--runs", "20000")
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
    return reports


@pytest.fixture(scope="session")
def demo_folder(demo_run: tuple[Path, Any]) -> Path:
    """The folder of the session's demo (tests using it carry xdist_group("demo"))."""
    return demo_run[0]
