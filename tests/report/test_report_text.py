"""The text a reader sees in every demo report: plain names, fixed-notation numbers, U on results.

The visible text (scripts and styles left out) must hold no JSON key as a name
(``angular_acceleration_amplitude_deg_s2``), no E notation (``1.2e-05``), no internal file name
of a paper ("seed 004"), no placeholder unit ("output unit"); every row of a summary that states
a coverage (k, p) states the value's U (``±``) or its coverage interval.
"""

from __future__ import annotations

import re
from html.parser import HTMLParser
from pathlib import Path

import pytest

from rotacal.demo import demo_files

DEMO_PAGES = [name for name in demo_files() if name.endswith(".html")]

#: The faults a reader must never see, each with the pattern that finds it.
FAULTS = {
    # A name the user types is shown as typed: a capture's column in quotes (“rate_deg_s”), a key
    # of the specification file with its table (encoder.undetectable_harmonics_arcsec).
    "a JSON key as a name": re.compile(r"(?<![\w.“])[a-z]+(?:_[a-z0-9]+)+\b(?!”)"),
    "E notation": re.compile(r"\d[eE][+-]?\d"),
    "an internal paper name": re.compile(r"seed 00\d", re.IGNORECASE),
    "a placeholder unit": re.compile(r"\boutput unit\b(?!s)"),
}


class _Visible(HTMLParser):
    """The page's text as a reader sees it, and its summary rows (cells of table.summary)."""

    def __init__(self) -> None:
        super().__init__()
        self.text: list[str] = []
        self.rows: list[list[str]] = []
        self._skip = 0
        self._summary = 0
        self._cell: list[str] | None = None

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        if tag in ("script", "style"):
            self._skip += 1
        elif tag == "table" and ("class", "summary") in attrs:
            self._summary += 1
        elif tag == "tr" and self._summary:
            self.rows.append([])
        elif tag == "td" and self._summary:
            self._cell = []

    def handle_endtag(self, tag: str) -> None:
        if tag in ("script", "style"):
            self._skip -= 1
        elif tag == "table" and self._summary:
            self._summary -= 1
        elif tag == "td" and self._cell is not None:
            self.rows[-1].append(" ".join(self._cell))
            self._cell = None

    def handle_data(self, data: str) -> None:
        if self._skip:
            return
        self.text.append(data)
        if self._cell is not None:
            self._cell.append(data)


def visible(html: str) -> _Visible:
    parser = _Visible()
    parser.feed(html)
    return parser


def faults(html: str) -> list[str]:
    """Every fault of the page's visible text, each as "what: the text found"."""
    page = visible(html)
    text = " ".join(" ".join(page.text).split())
    found = [f"{what}: {m.group(0)!r}" for what, rx in FAULTS.items() for m in rx.finditer(text)]
    for row in page.rows:
        has_coverage = any(re.search(r"\bk = \d", cell) for cell in row)
        if has_coverage and not any("±" in cell or "true value in [" in cell for cell in row):
            found.append(f"a result with a coverage but no U: {' | '.join(row)!r}")
    return found


@pytest.mark.xdist_group("demo")
@pytest.mark.parametrize("name", DEMO_PAGES)
def test_every_demo_page_reads_in_plain_words(demo_folder: Path, name: str) -> None:
    found = faults((demo_folder / name).read_text(encoding="utf-8"))
    assert found == [], f"{len(found)} faults, e.g. {found[:8]}"


@pytest.mark.xdist_group("demo")
def test_the_index_states_each_headline_result_with_its_u(demo_folder: Path) -> None:
    rows = visible((demo_folder / "report.html").read_text(encoding="utf-8")).rows
    assert len(rows) >= 20  # 2–4 headline results for each of the 13 reports but one
    with_u = [r for r in rows if any("±" in c or "true value in [" in c for c in r)]
    assert len(with_u) >= 20


def test_the_text_checks_find_the_old_reports_faults() -> None:
    """Lines of the report before issue 14 (ad48006^): each fault is found, the fixed line passes."""
    old = (
        "<p>angular_acceleration_amplitude_deg_s2</p><td>3.2e-05</td>"
        "<p>Angular-velocity standard (Kokuyama et al., seed 004)</p>"
        "<td>scale factor 1.00 output unit per °/s</td>"
        '<table class="summary"><tr><td>THD</td><td>5.42 %</td><td>k = 2.00, p = 95 %</td></tr>'
        "</table><style>p_q { } x1e-5</style>"
    )
    found = faults(old)
    assert [f.split(":")[0] for f in found] == [
        "a JSON key as a name",
        "E notation",
        "an internal paper name",
        "a placeholder unit",
        "a result with a coverage but no U",
    ]
    fixed = (
        "<p>angular-acceleration amplitude</p><td>3.2 × 10⁻⁵</td>"
        "<p>Kokuyama et al. (2015)</p><td>scale factor 1.00 output units per °/s</td>"
        '<table class="summary"><tr><td>THD</td><td>5.42 ± 0.03 %</td>'
        "<td>k = 2.00, p = 95 %</td></tr></table>"
    )
    assert faults(fixed) == []


def test_budget_text_is_rewritten_for_a_reader_without_changing_a_number() -> None:
    """The JSON's words of a budget (``edf 6.797e+04``) in fixed notation, same digits, same sign."""
    from rotacal.report.wording import readable

    assert readable("χ², edf 6.797e+04 (white)") == "χ², edf 67970 (white)"
    assert readable("bias +6.8e-05 and -1.6e-07 pp") == "bias +6.8 × 10⁻⁵ and -1.6 × 10⁻⁷ pp"
    assert readable("τ = 1.16e+03 s; k = t_p(ν)") == "τ = 1160 s; k = tₚ(ν)"
    assert readable("1.2 output unit/(°/s), 3 output units") == (
        "1.2 output units/(°/s), 3 output units"
    )
    assert readable("head_5 2.1430190 … 2.1430220") == "head 5 2.1430190 … 2.1430220"
    assert readable("max_K|e_j| ≤ |e_j*|") == "max_K|eⱼ| ≤ |eⱼ*|"
