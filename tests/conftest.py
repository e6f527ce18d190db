"""Shared test fixtures: where the real recordings of ../shared/data are."""

from __future__ import annotations

import os

# One BLAS thread per process: pytest runs one worker per core (-n auto), and threaded BLAS on
# top of that oversubscribes the cores (small least-squares fits get many times slower). Set
# before NumPy is first imported in this process; the workers inherit it.
for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

# rotacal's state (the default records store) goes to a folder of this test process, never to the
# user's own data folder; ROTACAL_DB from the environment would send certificates elsewhere.
import atexit  # noqa: E402
import shutil  # noqa: E402
import tempfile  # noqa: E402

os.environ["ROTACAL_DATA_DIR"] = tempfile.mkdtemp(prefix="rotacal-test-state-")
atexit.register(shutil.rmtree, os.environ["ROTACAL_DATA_DIR"], ignore_errors=True)
os.environ.pop("ROTACAL_DB", None)

from collections.abc import Callable, Iterator  # noqa: E402
from pathlib import Path  # noqa: E402
from typing import Any  # noqa: E402

import pytest  # noqa: E402

#: The project's shared folder of real recordings (never copied into the repository): the folder
#: named by the environment variable ROTACAL_SHARED_DATA, else shared/data beside the repository.
SHARED_DATA = Path(
    os.environ.get("ROTACAL_SHARED_DATA", Path(__file__).resolve().parents[2] / "shared" / "data")
)


@pytest.fixture(scope="session")
def shared_data() -> Callable[..., Path]:
    """``shared_data("imucal", "example_data")``: the path; a skip only when the whole shared
    folder is absent from this machine, a failure when the folder is there but not the file.

    The only skip the test suite allows: real data that this machine does not have. A recording
    missing from a folder that is present (renamed, moved) fails the test, which could otherwise
    never fail where the data are.
    """

    def need(*parts: str) -> Path:
        path = SHARED_DATA.joinpath(*parts)
        if path.exists():
            return path
        if SHARED_DATA.is_dir():
            pytest.fail(f"real data {path} is missing from {SHARED_DATA}, which is present")
        pytest.skip(
            f"real data {SHARED_DATA} is absent (the shared recordings are not on this "
            "machine; set ROTACAL_SHARED_DATA to their folder)"
        )

    return need


#: Linux capabilities that let root write past permission bits (capability.h).
_CAP_DAC_OVERRIDE, _CAP_DAC_READ_SEARCH = 1, 2
_PR_CAPBSET_DROP = 24


def _drop_permission_override() -> None:
    """In a child before exec: take away root's power to ignore permission bits (bounding set)."""
    import ctypes

    libc = ctypes.CDLL(None, use_errno=True)
    for cap in (_CAP_DAC_OVERRIDE, _CAP_DAC_READ_SEARCH):
        if libc.prctl(_PR_CAPBSET_DROP, cap, 0, 0, 0) != 0:
            raise OSError(ctypes.get_errno(), "prctl(PR_CAPBSET_DROP) failed")


@pytest.fixture
def bound_by_permissions() -> Callable[..., Any]:
    """``run(argv, unwritable=folder)``: a Python child process that permission bits really stop.

    Tests run as root here, and root writes into a read-only folder. For root the child drops the
    capabilities that override permission bits (so the kernel refuses it as it refuses anyone);
    for another user the child is unprivileged already. It imports this rotacal.
    """
    import subprocess
    import sys

    import rotacal

    src = str(Path(rotacal.__file__).resolve().parents[1])

    def run(argv: list[str], unwritable: Path) -> subprocess.CompletedProcess[str]:
        """Run ``python argv`` after checking that such a child cannot create a file in
        ``unwritable`` by itself (so what the test sees is the kernel's refusal, not rotacal's
        guess)."""

        def child(args: list[str]) -> subprocess.CompletedProcess[str]:
            return subprocess.run(
                [sys.executable, *args],
                capture_output=True,
                text=True,
                env={**os.environ, "PYTHONPATH": src},
                preexec_fn=_drop_permission_override if os.geteuid() == 0 else None,
                check=False,
            )

        probe = child(["-c", f"open({str(unwritable / 'probe')!r}, 'w')"])
        assert "PermissionError" in probe.stderr, "the child is not bound by permission bits"
        return child(argv)

    return run


def _one_pixel_figures(monkeypatch: pytest.MonkeyPatch) -> None:
    """Make every PNG figure that ``rotacal.report`` saves a one-pixel image (what
    ``unrendered_figures`` does)."""
    import io

    from matplotlib.figure import Figure
    from PIL import Image

    pixel = io.BytesIO()
    Image.new("RGB", (1, 1), "white").save(pixel, format="PNG")
    drawn = Figure.savefig

    def savefig(self: Figure, fname: Any, *args: Any, **kwargs: Any) -> None:
        if kwargs.get("format") != "png":  # the certificate's SVG figures are drawn as ever
            return drawn(self, fname, *args, **kwargs)
        fname.write(pixel.getvalue())
        return None

    monkeypatch.setattr(Figure, "savefig", savefig)


@pytest.fixture
def unrendered_figures(monkeypatch: pytest.MonkeyPatch) -> None:
    """Reports made in the test are written with every figure a one-pixel PNG.

    For tests of where outputs go and what a report's text says, not of what its figures show:
    drawing a figure (matplotlib's layout pass and raster pass) takes 0.1–0.4 s, most of a
    report's cost. The figures themselves are checked by the tests that look at them
    (tests/report renders every command's report in a browser); everything else of the report —
    its text, tables, captions, the PNG's palette step, the file written — still runs.
    """
    _one_pixel_figures(monkeypatch)


@pytest.fixture(scope="module")
def unrendered_figures_in_module() -> Iterator[None]:
    """``unrendered_figures`` for the module-scoped fixtures of one module."""
    with pytest.MonkeyPatch.context() as monkeypatch:
        _one_pixel_figures(monkeypatch)
        yield


@pytest.fixture(scope="session")
def postgres() -> Iterator[Any]:
    """A PostgreSQL server of this test session, on loopback (the records and batch tests); fails,
    never skips, without PostgreSQL (.ci/run installs it)."""
    from rotacal.records.testing import ThrowawayPostgres

    server = ThrowawayPostgres()
    yield server
    server.stop()


@pytest.fixture(scope="session")
def demo_run(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Any]:
    """``rotacal demo`` run once per test session (it takes about a minute): its folder and the
    CliRunner result. Tests that use it carry ``@pytest.mark.xdist_group("demo")`` so that, with
    ``--dist loadgroup``, they all run in the one worker that ran it.

    The tests that budget the example (seed) table carry that group too: the allocations of its
    requirement (~8 s, the same inputs in each) are then made once per session and kept by
    ``rotacal.turntable.allocation``'s memo of the last allocations of the process, not once per
    test on whichever worker runs it; each test still checks the budget it asked for. They share
    the demo's worker, whose headless browser the report tests use as well."""
    from click.testing import CliRunner

    from rotacal.cli import cli

    out = tmp_path_factory.mktemp("demo") / "demo"
    result = CliRunner().invoke(cli, ["demo", "--out", str(out)], prog_name="rotacal")
    assert result.exit_code == 0, result.output
    return out, result


def _analysis_args(kind: str, path: str, truth: dict[str, Any]) -> list[str]:
    """The analysis command of a twin of ``kind``, with the set values its truth states."""
    motion = truth.get("motion", {})
    sensor = truth.get("sensor", {})
    sets = [
        "--set-amplitude-deg",
        str(motion.get("amplitude_deg")),
        "--set-frequency-hz",
        str(motion.get("frequency_hz")),
    ]
    return {
        "encoder": ["motion", "encoder", path, "--lines", str(sensor.get("lines")), *sets],
        "lts": ["motion", "lts", path, "--radius-mm", str(sensor.get("radius_mm")), *sets],
        "fog": ["motion", "fog", path, *sets],
        "pulses": ["selfcal", path, "--pulses-per-rev", str(truth.get("pulses_per_rev"))],
        "gyro-rates": ["gyro", "scale-factor", path],
        "gyro-triad": ["gyro", "triad", path],
        "gyro-noise": ["allan", path, "--column", "rate_deg_s"],
        "position": ["position", path],
        "gyro-rotations": ["gyro", "rotations", path, "--sections", f"{path}.truth.json"],
        "multiposition": [
            "gyro",
            "multiposition",
            path,
            "--axis",
            str(truth.get("axis")),
            "--latitude-deg",
            str(truth.get("latitude_deg")),
        ],
    }[kind]


@pytest.fixture(scope="session")
def analysis_args() -> Callable[[str, str, dict[str, Any]], list[str]]:
    """``analysis_args(kind, path, truth)``: the arguments of the command that analyses a twin
    of ``kind`` (``rotacal simulate KIND``) at ``path``, with the set values its truth states."""
    return _analysis_args


def _module_of(item: pytest.Item) -> str:
    return item.nodeid.split("::", 1)[0]


def _uses_a_module_fixture(item: pytest.Item) -> bool:
    info = getattr(item, "_fixtureinfo", None)
    definitions = info.name2fixturedefs.values() if info is not None else []
    return any(defs and defs[-1].scope == "module" for defs in definitions)


@pytest.hookimpl(tryfirst=True)
def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    """A module whose tests share a module-scoped fixture runs whole on one xdist worker
    (``--dist loadgroup``, pyproject's addopts).

    Those fixtures are the expensive twins and Monte Carlo runs; spread test by test over the
    workers, every worker would make them again (a test may also ask for one by name, through
    ``request.getfixturevalue``, hence the whole module). Modules without one stay spread test by
    test, so long modules of independent tests still use both workers. A test that names its own
    ``xdist_group`` (the demo's: one demo per session for several modules) keeps it. Runs before
    xdist's hook, which turns the marks into the groups it schedules.
    """
    if not config.pluginmanager.hasplugin("xdist"):
        return
    shared = {_module_of(item) for item in items if _uses_a_module_fixture(item)}
    for item in items:
        if item.get_closest_marker("xdist_group") is None and _module_of(item) in shared:
            item.add_marker(pytest.mark.xdist_group(_module_of(item)))


@pytest.hookimpl(trylast=True)
def pytest_collection_finish(session: pytest.Session) -> None:
    """On an xdist worker: count the tests that carry ``xdist_group`` but that xdist does not group.

    xdist marks a grouped test by the suffix ``@group`` on its node id, which its scheduler reads;
    with pytest 9.2 and pytest-xdist 3.8 the suffix no longer takes (pytest-dev/pytest-xdist#1386)
    and the groups are spread like any other test: still correct, but every worker then builds
    the demo and the shared twins again (the suite took 20 % longer). pyproject's dev extra keeps
    pytest below 9.2; the controller fails the run when it happens all the same.
    """
    config = session.config
    # on a worker xdist keeps the choice as option.loadgroup (its dist option reads "no" there)
    if not (hasattr(config, "workerinput") and getattr(config.option, "loadgroup", False)):
        return
    config.workeroutput["ungrouped"] = [  # type: ignore[attr-defined]
        item.nodeid
        for item in session.items
        if item.get_closest_marker("xdist_group") is not None and "@" not in item.nodeid
    ]


_UNGROUPED: list[str] = []


def pytest_testnodedown(node: Any, error: Any) -> None:
    """On the controller: collect what the workers found ungrouped."""
    lost = getattr(node, "workeroutput", {}).get("ungrouped", [])
    if lost and not _UNGROUPED:
        _UNGROUPED.extend(lost)


def pytest_sessionfinish(session: pytest.Session, exitstatus: int) -> None:
    if _UNGROUPED and not hasattr(session.config, "workerinput"):
        session.exitstatus = pytest.ExitCode.USAGE_ERROR


def pytest_terminal_summary(terminalreporter: Any) -> None:
    if _UNGROUPED:
        terminalreporter.write_line(
            f"pytest {pytest.__version__} with this pytest-xdist ignored xdist_group "
            f"({len(_UNGROUPED)} tests, e.g. {_UNGROUPED[0]}; pytest-dev/pytest-xdist#1386), "
            'so the run took longer and failed: install the dev extra again (pip install -e ".[dev]" '
            "keeps pytest below 9.2).",
            red=True,
            bold=True,
        )
