"""Size and length of the demo's reports, as a reader's browser lays them out; the docs' screenshots.

Runs ``rotacal demo`` into a temporary folder and opens every report it writes (the index
``report.html`` and each per-analysis report in ``reports/``) in headless chromium (Debian's
``/usr/bin/chromium``, driven by Playwright): for each page its bytes, its height in px at 1200 px
wide, and the pages it prints to (A4, from ``page.pdf()``). Prints one table and the totals.

With ``--baseline`` (the default) it also runs the demo of the commit before issue 14
(``ad48006^``, one endless report.html), taken from git with ``git archive`` into a temporary
folder, and measures that page the same way, so the table holds before and after from one run.

With ``--screenshots DIR`` it writes the first screen (1200 × 900 px) of the index
(``report-index.png``) and of the 0.1° / 5 Hz report (``report-motion.png``) into DIR, the
pictures in ``docs/images/``. No asserts.

Run: ``python benchmarks/bench_reports.py [--no-baseline] [--screenshots docs/images]``
"""

from __future__ import annotations

import argparse
import os
import re
import subprocess
import sys
import tempfile
from pathlib import Path
from typing import Any

CHROMIUM = "/usr/bin/chromium"
CHROMIUM_ARGS = [
    "--no-sandbox",
    "--disable-gpu",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--no-first-run",
]
BASELINE_COMMIT = "ad48006^"
DESKTOP = {"width": 1200, "height": 900}
#: A page object of a PDF ("/Type /Page", not the "/Type /Pages" tree node).
_PDF_PAGE = re.compile(rb"/Type\s*/Page(?![a-z])")
REPO = Path(__file__).resolve().parents[1]


def run_demo(src: Path, out: Path) -> None:
    """``rotacal demo --out out`` of the package under ``src``, in a child process."""
    env = {**os.environ, "PYTHONPATH": str(src)}
    subprocess.run(
        [sys.executable, "-m", "rotacal", "demo", "--out", str(out)],
        env=env,
        check=True,
        capture_output=True,
    )


def baseline_source(folder: Path) -> Path:
    """The package of ``BASELINE_COMMIT`` extracted into ``folder`` (no worktree, no checkout)."""
    folder.mkdir(parents=True, exist_ok=True)
    archive = subprocess.run(
        ["git", "-C", str(REPO), "archive", BASELINE_COMMIT, "src"],
        check=True,
        capture_output=True,
    ).stdout
    subprocess.run(["tar", "-x", "-C", str(folder)], input=archive, check=True)
    return folder / "src"


def measure(browser: Any, path: Path) -> dict[str, Any]:
    """Bytes, height at 1200 px and printed A4 pages of one report."""
    page = browser.new_page(viewport=DESKTOP)
    page.goto(path.resolve().as_uri(), wait_until="load")
    height = page.evaluate("document.documentElement.scrollHeight")
    pdf = page.pdf(format="A4", print_background=False)
    page.close()
    return {"bytes": path.stat().st_size, "height": height, "printed": len(_PDF_PAGE.findall(pdf))}


def screenshot(browser: Any, path: Path, png: Path) -> None:
    page = browser.new_page(viewport=DESKTOP)
    page.goto(path.resolve().as_uri(), wait_until="load")
    png.parent.mkdir(parents=True, exist_ok=True)
    page.screenshot(path=str(png))
    page.close()


def table(title: str, rows: list[tuple[str, dict[str, Any]]]) -> None:
    print(f"\n{title}")
    print(f"{'page':<42} {'bytes':>11} {'height at 1200 px':>18} {'printed A4 pages':>17}")
    for name, m in rows:
        print(f"{name:<42} {m['bytes']:>11,} {m['height']:>15,} px {m['printed']:>17}")
    total = sum(m["bytes"] for _, m in rows)
    tallest = max(m["height"] for _, m in rows)
    printed = sum(m["printed"] for _, m in rows)
    print(
        f"{'total (' + str(len(rows)) + ' pages)':<42} {total:>11,} "
        f"{'tallest ' + format(tallest, ','):>15} px {printed:>17}"
    )
    print(f"total size: {total / 1e6:.2f} MB")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--no-baseline", action="store_true", help="skip the old single page")
    parser.add_argument("--screenshots", type=Path, help="folder for the docs' screenshots")
    args = parser.parse_args()

    from playwright.sync_api import sync_playwright

    with tempfile.TemporaryDirectory() as tmp:
        tmp_path = Path(tmp)
        new = tmp_path / "new"
        run_demo(REPO / "src", new)
        old = tmp_path / "old"
        if not args.no_baseline:
            run_demo(baseline_source(tmp_path / "baseline"), old)
        with sync_playwright() as p:
            browser = p.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS)
            if not args.no_baseline:
                table(
                    f"before ({BASELINE_COMMIT}): one report",
                    [("report.html", measure(browser, old / "report.html"))],
                )
            pages = [new / "report.html", *sorted((new / "reports").glob("*.html"))]
            table(
                "after: an index and one report per analysis",
                [(p.relative_to(new).as_posix(), measure(browser, p)) for p in pages],
            )
            if args.screenshots:
                screenshot(browser, new / "report.html", args.screenshots / "report-index.png")
                screenshot(
                    browser,
                    new / "reports" / "motion_0.1deg_5hz.html",
                    args.screenshots / "report-motion.png",
                )
                print(f"\nscreenshots written to {args.screenshots}")
            browser.close()


if __name__ == "__main__":
    main()
