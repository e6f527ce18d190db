"""Make the tutorials' figures: run each tutorial as written and keep figures of its reports.

Run from the repository's root (with rotacal installed or ``src`` on PYTHONPATH)::

    python docs/tutorials/make_figures.py            # every tutorial
    python docs/tutorials/make_figures.py noise      # one

Each tutorial's commands run in a temporary folder exactly as tests/docs/test_tutorials.py runs
them; the figures are taken from the HTML reports they write (``--report``), so the docs show what
a user's report shows. A section on a real recording runs only when the shared recordings are
present (``ROTACAL_SHARED_DATA``, else ../shared/data); its figures are derived from the data,
never the data itself. Each figure is stored as a palette PNG (Pillow, 128 colours) in
docs/tutorials/figures/.
"""

from __future__ import annotations

import base64
import io
import re
import sys
import tempfile
from pathlib import Path

from PIL import Image

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))  # the tests' helpers, which run the tutorials

from tests.docs.test_tutorials import SHARED_DATA, run_section, sections  # noqa: E402

FIGURES = Path(__file__).resolve().parent / "figures"

#: tutorial -> (report it writes, title of the report's figure, file in figures/)
WANTED: dict[str, list[tuple[str, str, str]]] = {
    "sinusoidal-motion": [
        ("run.html", "Motion, fitted curve and reversing moments", "sinusoidal-motion-encoder"),
        ("run.html", "Harmonic spectrum", "sinusoidal-motion-spectrum"),
        ("fog.html", "Motion, fitted curve and reversing moments", "sinusoidal-motion-fog"),
    ],
    "angular-velocity-standard": [
        ("selfcal.html", "Scale deviation", "angular-velocity-standard-deviation"),
        ("rate.html", "Angular velocity over time", "angular-velocity-standard-rate"),
    ],
    "gyro-scale-factor": [
        ("sf.html", "Output against rate", "gyro-scale-factor-twin"),
        ("xinli.html", "Output against rate", "gyro-scale-factor-xinli"),
    ],
    "gyro-triad": [
        ("triad.html", "Residuals before and after", "gyro-triad-residuals"),
        ("rot.html", "Recording and its sections", "gyro-triad-rotations"),
        ("imucal.html", "Recording and its sections", "gyro-triad-imucal"),
    ],
    "multiposition": [
        ("mp.html", "Residuals per turntable position", "multiposition-residuals"),
    ],
    "noise": [
        ("noise.html", "Allan deviation", "noise-twin"),
        ("smac.html", "Allan deviation", "noise-adis16405"),
    ],
    "turntable-budget": [
        ("budget.html", "Sensitivity", "turntable-budget-sensitivity"),
        ("budget.html", "Monte Carlo", "turntable-budget-monte-carlo"),
    ],
}

_IMAGE = re.compile(r'<img alt="([^"]*)" src="data:image/png;base64,([^"]+)"')


def report_figures(report: Path) -> dict[str, bytes]:
    """The PNG figures embedded in a report, by their title."""
    html = report.read_text(encoding="utf-8")
    return {title: base64.b64decode(data) for title, data in _IMAGE.findall(html)}


def save_palette_png(png: bytes, path: Path) -> int:
    """Store ``png`` reduced to a 128-colour palette; returns the file's size in bytes."""
    with Image.open(io.BytesIO(png)) as image:
        palette = image.convert("RGB").quantize(colors=128, dither=Image.Dither.NONE)
        palette.save(path, format="PNG", optimize=True)
    return path.stat().st_size


def make(tutorial: str) -> None:
    page = Path(__file__).resolve().parent / f"{tutorial}.md"
    with tempfile.TemporaryDirectory() as folder:
        work = Path(folder)
        for title, text in sections(page):
            if "$ROTACAL_SHARED_DATA" in text and not SHARED_DATA.exists():
                print(f"{tutorial}: {title}: skipped, {SHARED_DATA} is absent")
                continue
            run_section(text, work)
        for report, wanted, name in WANTED[tutorial]:
            if not (work / report).exists():
                continue  # a real-data section that did not run
            figures = report_figures(work / report)
            found = [png for title, png in figures.items() if title.startswith(wanted)]
            if not found:
                raise SystemExit(f"{report} has no figure '{wanted}…' (it has: {list(figures)})")
            size = save_palette_png(found[0], FIGURES / f"{name}.png")
            print(f"figures/{name}.png  {size / 1000:.0f} kB  ({report}: {wanted}…)")


def main(names: list[str]) -> None:
    FIGURES.mkdir(exist_ok=True)
    for tutorial in names or list(WANTED):
        make(tutorial)


if __name__ == "__main__":
    main(sys.argv[1:])
