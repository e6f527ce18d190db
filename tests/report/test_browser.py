"""Every report as a reader's browser shows it: headless chromium at a phone's width and in print.

Each page must load with no console error and no network request (it is one self-contained file:
its figures are data URIs), every image must decode, the page must not scroll sideways at 420 px
(tables scroll inside themselves), and in print every folded section must open.
"""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from rotacal.demo import demo_files

#: Every page the demo writes (index and per-analysis reports), relative to its folder.
DEMO_PAGES = [name for name in demo_files() if name.endswith(".html")]
PHONE = {"width": 420, "height": 900}


class Reader:
    """One page of the session's browser, at a phone's width, that every report is opened in (a
    context per page cost ~0.3 s each; the document, its console and its requests are new with
    each visit, and what one page leaves behind could only fail the next, never pass it)."""

    def __init__(self, browser: Any) -> None:
        self.context = browser.new_context(viewport=PHONE, java_script_enabled=True)
        self.page = self.context.new_page()
        self.url = ""
        self.requests: list[str] = []
        self.errors: list[str] = []
        self.page.route("**/*", self._route)
        self.page.on("console", lambda m: self.errors.append(m.text) if m.type == "error" else None)
        self.page.on("pageerror", lambda e: self.errors.append(str(e)))

    def _route(self, r: Any) -> None:
        if r.request.url == self.url or r.request.url.startswith("data:"):
            r.continue_()
        else:
            self.requests.append(r.request.url)
            r.abort()


@pytest.fixture(scope="module")
def reader(browser: Any) -> Iterator[Reader]:
    r = Reader(browser)
    yield r
    r.context.close()


def look_at(reader: Reader, path: Path) -> dict[str, Any]:
    """What a reader's browser finds on the page ``path``: console errors, requests beyond the
    file itself, the page's width at 420 px, images that did not load, folded sections left
    closed in print."""
    from playwright.sync_api import TimeoutError as PlaywrightTimeout  # the browser fixture has it

    page = reader.page
    page.goto("about:blank")  # the last page's document (and its events) gone before counting
    reader.url = path.resolve().as_uri()
    reader.errors.clear()
    reader.requests.clear()
    page.emulate_media(media="screen")
    page.goto(reader.url, wait_until="load")
    found = {
        "scroll_width": page.evaluate("document.documentElement.scrollWidth"),
        "broken_images": page.evaluate(
            "Array.from(document.images).filter(i => !(i.complete && i.naturalWidth > 0))"
            ".map(i => i.alt)"
        ),
        "images": page.evaluate("document.images.length"),
        "details": page.evaluate("document.querySelectorAll('details').length"),
    }
    page.emulate_media(media="print")
    closed = "Array.from(document.querySelectorAll('details')).filter(d => !d.open).length"
    try:  # the print medium's change event reaches the page's script asynchronously
        page.wait_for_function(f"{closed} === 0", timeout=3000)
    except PlaywrightTimeout:
        pass  # the count below reports what stayed closed
    found["closed_in_print"] = page.evaluate(closed)
    found["errors"] = list(reader.errors)
    found["requests"] = list(reader.requests)
    return found


def assert_readable(found: dict[str, Any]) -> None:
    assert found["errors"] == [], f"console errors: {found['errors']}"
    assert found["requests"] == [], f"network requests: {found['requests']}"
    assert found["scroll_width"] <= PHONE["width"], "the page scrolls sideways at 420 px"
    assert found["broken_images"] == [], f"images that did not load: {found['broken_images']}"
    assert found["closed_in_print"] == 0, "folded sections stay closed in print"


@pytest.mark.xdist_group("demo")
@pytest.mark.parametrize("name", DEMO_PAGES)
def test_every_demo_page_reads_in_a_browser(reader, demo_folder, name) -> None:
    found = look_at(reader, demo_folder / name)
    assert_readable(found)
    if name != "report.html":  # an analysis shows its figures; the index only links
        assert found["images"] > 0 or "comparison" in name


@pytest.mark.xdist_group("demo")
def test_the_index_links_every_report_and_only_those(demo_folder) -> None:
    import re

    html = (demo_folder / "report.html").read_text()
    hrefs = re.findall(r'<a href="([^"#]+)"', html)
    assert sorted(hrefs) == sorted(n for n in DEMO_PAGES if n != "report.html")
    for name in hrefs:  # each report links back to the index
        assert '<a href="../report.html">' in (demo_folder / name).read_text(), name


@pytest.mark.xdist_group(
    "demo"
)  # the browser and the example table's allocations: tests/conftest.py
def test_every_commands_report_reads_in_a_browser(reader, cli_reports) -> None:
    # motion ×3, selfcal, rate, inspect, gyro ×5, allan, turntable ×2, position
    assert len(cli_reports) == 15
    for command, path in cli_reports.items():
        found = look_at(reader, path)
        try:
            assert_readable(found)
        except AssertionError as exc:
            raise AssertionError(f"{command}: {exc}") from None


@pytest.mark.xdist_group("demo")  # the demo worker's browser: one chromium per session
def test_the_checks_catch_a_page_that_breaks_them(reader, tmp_path) -> None:
    """The browser checks can fail: a wide table outside a scroller, a missing image, a fetch."""
    from rotacal.report.html import Report, Section, Table, render_html

    html = render_html(Report("t", sections=[Section("s", tables=[Table(["a"], [["x"]])])]))
    broken = html.replace(
        "</body>",
        '<div style="width:900px">wide</div><img src="missing.png" alt="gone">'
        "<script>console.error('boom')</script></body>",
    )
    path = tmp_path / "broken.html"
    path.write_text(broken)
    found = look_at(reader, path)
    assert found["scroll_width"] > PHONE["width"]
    assert found["broken_images"] == ["gone"]
    assert any("boom" in e for e in found["errors"])
    assert any(r.endswith("missing.png") for r in found["requests"])
