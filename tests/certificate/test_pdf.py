"""The PDF certificate: what ISO/IEC 17025 §7.8 asks to be on it is in the text pypdf extracts.

The truth is the certificate's content (the ReportedQuantity and Conformity strings, the plan's
administrative data): every test looks for it in the PDF's text, laid out only by
``printed_number`` (digit groups, minus sign), whose own examples are checked by hand-written
strings below.
"""

from __future__ import annotations

import dataclasses
import datetime as dt
import io
import re
import xml.etree.ElementTree as ET
from pathlib import Path
from typing import Any

import pypdf
import pytest

from rotacal.certificate.conformity import RULE_TEXT
from rotacal.certificate.content import CertificateContent, Figure
from rotacal.certificate.figures import draw_figures
from rotacal.certificate.pdf import (
    END_MARKER,
    NOT_REPRODUCED,
    ONLY_THE_ITEM,
    page_label,
    printed_interval,
    printed_number,
    printed_text,
    render_pdf,
)

pytestmark = pytest.mark.xdist_group("certificate")

NNBSP = "\u202f"
#: Characters that Typst markup would read as markup, in names a plan may hold.
SPECIAL = "Gyro #Maker* $Ltd$ _x_ <y> @z \\ [a] // `c` ~ é"


def _with_figures(content: CertificateContent, folder: Path) -> CertificateContent:
    """The content with every measurement's figures drawn into ``folder``."""
    measurements = []
    for m in content.measurements:
        figures = draw_figures(m)
        for name, _caption, svg in figures:
            (folder / name).write_bytes(svg)
        measurements.append(
            dataclasses.replace(m, figures=tuple(Figure(n, c) for n, c, _ in figures))
        )
    return dataclasses.replace(content, measurements=tuple(measurements))


def _pages(pdf: bytes) -> list[str]:
    return [page.extract_text() for page in pypdf.PdfReader(io.BytesIO(pdf)).pages]


def _flat(text: str) -> str:
    """Text with its line breaks undone: a break after a hyphen or slash joins, others are a
    space (digit groups' narrow no-break spaces stay)."""
    text = re.sub(r"(?<=[-/])\n", "", text)
    return re.sub(r"[ \n]+", " ", text)


def _loose(text: str) -> str:
    """Text without any space or hyphen, for prose that Typst may hyphenate at a line end."""
    return re.sub(r"[\s\-\u00ad]+", "", text)


@pytest.fixture(scope="module")
def issued(content: CertificateContent, tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    folder = tmp_path_factory.mktemp("certificate")
    drawn = _with_figures(content, folder)
    pdf = render_pdf(drawn, folder)
    again = render_pdf(drawn, folder)
    pages = _pages(pdf)
    return {
        "content": drawn,
        "folder": folder,
        "pdf": pdf,
        "again": again,
        "pages": pages,
        "text": _flat("\n".join(pages)),
    }


@pytest.fixture(scope="module")
def special(content: CertificateContent) -> list[str]:
    """A certificate whose administrative texts and a warning hold markup characters."""
    plan = content.plan
    plan = dataclasses.replace(
        plan,
        location="on site: <Hall 3> #2",
        supersedes="RC-2026-0041",
        laboratory=dataclasses.replace(plan.laboratory, name="Lab *#1* $"),
        customer=dataclasses.replace(plan.customer, name=SPECIAL, address="<addr> @ref"),
        item=dataclasses.replace(
            plan.item,
            description="_under_ #emph[x] {y}",
            received=dt.date(2026, 11, 20),
            condition="as new, seal intact",
        ),
    )
    m = dataclasses.replace(
        content.measurements[0], name="Name = [#set text(red)]", warnings=("warn $a$ *b* _c_",)
    )
    odd = dataclasses.replace(content, plan=plan, measurements=(m,))
    return _pages(render_pdf(odd, Path(".")))


# --- the number layout --------------------------------------------------------------------


@pytest.mark.parametrize(
    ("text", "printed"),
    [
        ("0.012499841", "0.012 499 841"),
        ("0.000000082", "0.000 000 082"),
        ("78.9568331", "78.956 833 1"),
        ("1234.5678", "1234.5678"),  # four digits a side: not grouped (SI Brochure §5.4.4)
        ("12345.67891", "12 345.678 91"),
        ("-0.002042", "−0.002 042"),
        ("-0.3000", "−0.3000"),
        ("7", "7"),
        ("5760518", "5 760 518"),
        ("1e-05", "1e-05"),  # not a plain decimal: left as it is
    ],
)
def test_printed_number_groups_digits_by_three(text: str, printed: str) -> None:
    assert printed_number(text) == printed.replace(" ", NNBSP)


def test_printed_text_lays_out_the_numbers_of_a_sentence_only() -> None:
    sentence = (
        "The K_xy, 0.003060 V/(°/s) ± 0.000054 V/(°/s), is between -0.003 and 12345 "
        "(ILAC-G8:09/2019 §4.2.2; 1e-05)."
    )
    assert printed_text(sentence) == (
        "The K_xy, 0.003 060 V/(°/s) ± 0.000 054 V/(°/s), is between −0.003 and 12 345 "
        "(ILAC-G8:09/2019 §4.2.2; 1e-05)."
    ).replace("0.003 060", f"0.003{NNBSP}060").replace("0.000 054", f"0.000{NNBSP}054").replace(
        "12 345", f"12{NNBSP}345"
    )


# --- every page ---------------------------------------------------------------------------


def test_every_page_carries_the_number_and_page_n_of_m(issued: dict[str, Any]) -> None:
    pages = issued["pages"]
    number = issued["content"].number
    assert len(pages) >= 3
    for n, text in enumerate(pages, start=1):
        assert number in text, f"page {n}"
        assert page_label(n, len(pages)) in text, f"page {n}"


def test_end_marker_on_the_last_page_only(issued: dict[str, Any]) -> None:
    pages = issued["pages"]
    assert END_MARKER in pages[-1]
    assert not any(END_MARKER in text for text in pages[:-1])
    # nothing of the certificate follows the marker but the footer
    tail = pages[-1].split(END_MARKER, 1)[1]
    assert page_label(len(pages), len(pages)) in tail
    assert "SHA-256" not in tail


def test_two_renders_are_identical(issued: dict[str, Any]) -> None:
    assert issued["again"] == issued["pdf"]


def _xobject_kinds(resources: Any) -> list[str]:
    """The subtypes of every XObject a page draws, forms opened recursively."""
    kinds = []
    xobjects = resources.get("/XObject", {}) if resources else {}
    for ref in xobjects.values():
        obj = ref.get_object()
        kinds.append(str(obj["/Subtype"]))
        if obj["/Subtype"] == "/Form":
            kinds += _xobject_kinds(obj.get("/Resources"))
    return kinds


def test_figures_are_vector_in_the_pdf(issued: dict[str, Any]) -> None:
    reader = pypdf.PdfReader(io.BytesIO(issued["pdf"]))
    kinds = [k for page in reader.pages for k in _xobject_kinds(page.get("/Resources"))]
    assert sum(len(m.figures) for m in issued["content"].measurements) >= 5
    # Typst draws an SVG's paths into the page itself; a raster would be an image XObject
    assert "/Image" not in kinds


def test_only_the_fonts_inside_typst_and_the_date_of_issue(issued: dict[str, Any]) -> None:
    """No font of the machine and no clock enter the PDF: it is the same on every machine."""
    reader = pypdf.PdfReader(io.BytesIO(issued["pdf"]))
    fonts = {
        str(font.get_object()["/BaseFont"]).split("+", 1)[-1]
        for page in reader.pages
        for font in page["/Resources"].get("/Font", {}).values()
    }
    assert fonts
    assert all(f.startswith(("LibertinusSerif", "NewCM", "DejaVuSansMono")) for f in fonts), fonts
    issue = issued["content"].plan.issue_date.strftime("%Y%m%d")
    assert reader.metadata is not None
    assert str(reader.metadata["/CreationDate"]).startswith(f"D:{issue}")


# --- what §7.8 asks for -------------------------------------------------------------------


def _row(*cells: str) -> str:
    return " ".join(c for c in cells if c)


def test_each_result_prints_with_its_u_unit_k_and_p(issued: dict[str, Any]) -> None:
    text = issued["text"]
    checked = 0
    for m in issued["content"].measurements:
        for q in m.quantities:
            spread = printed_interval(q.interval) if q.interval else printed_number(q.U)
            p = f"{round(float(q.p) * 100)} %"
            assert _row(printed_number(q.value), spread, q.unit, q.k, p) in text, q.key
            checked += 1
    assert checked >= len(issued["content"].measurements)


def test_every_conformity_statement_with_its_verdict(issued: dict[str, Any]) -> None:
    text = issued["text"]
    rows = [(m, c) for m in issued["content"].measurements for c in m.conformity]
    assert {c.verdict for _, c in rows} == {"pass", "fail", "indeterminate"}
    for m, c in rows:
        q = next(q for q in m.quantities if q.key == c.key)
        spread = printed_interval(q.interval) if q.interval else printed_number(c.U)
        if c.limit_min and c.limit_max:
            limits = f"{printed_number(c.limit_min)} to {printed_number(c.limit_max)}"
        else:
            limits = (
                f"≤ {printed_number(c.limit_max)}"
                if c.limit_max
                else f"≥ {printed_number(c.limit_min)}"
            )
        line = _row(printed_number(c.value), spread, c.unit, limits, c.decision_rule)
        assert f"{line} {c.verdict.upper()}" in text, c.key
        assert printed_text(c.statement) in text, c.key
    for rule in {c.decision_rule for _, c in rows}:
        assert RULE_TEXT[rule][0].upper() + RULE_TEXT[rule][1:] in text, rule


def test_the_administrative_elements(issued: dict[str, Any]) -> None:
    content = issued["content"]
    plan = content.plan
    text = issued["text"]
    first = _flat(issued["pages"][0])
    for expected in (
        plan.title,
        plan.laboratory.name,
        plan.laboratory.address,
        plan.laboratory.email,
        plan.laboratory.phone,
        plan.customer.name,
        plan.customer.address,
        plan.item.kind,
        plan.item.manufacturer,
        plan.item.model,
        plan.item.serial,
        plan.item.description,
        f"{plan.start_date.isoformat()} to {plan.end_date.isoformat()}",
        plan.issue_date.isoformat(),
        ONLY_THE_ITEM,
        NOT_REPRODUCED,
    ):
        assert expected in first, expected
    for person in plan.persons:
        assert person.name in first
    for standard in plan.standards:
        for expected in (
            standard.name,
            standard.id,
            standard.certificate,
            standard.due.isoformat(),
        ):
            assert expected in text, expected
    conditions = plan.conditions
    if conditions.temperature_c is not None:
        assert f"{conditions.temperature_c!r} °C" in text
    if conditions.temperature_u_c is not None:
        assert f"standard uncertainty {conditions.temperature_u_c!r} °C" in text
    if conditions.humidity_percent is not None:
        assert f"relative humidity {conditions.humidity_percent!r} %" in text
    for _key, value in conditions.others:
        assert str(value) in text
    # prose is justified and hyphenated: compare it without spaces and hyphens
    prose = _loose(text)
    for m in content.measurements:
        assert m.name in text
        assert _loose(m.method) in prose
        for ref in m.references:
            assert _loose(ref) in prose
        for capture in m.captures:
            assert capture.sha256 in text
        for figure in m.figures:
            assert _loose(figure.caption) in prose
    assert f"rotacal {content.software_version}" in text
    assert content.plan_sha256 in text


def test_markup_characters_print_as_typed(special: list[str]) -> None:
    text = _flat("\n".join(special))
    for typed in (
        SPECIAL,
        "<addr> @ref",
        "_under_ #emph[x] {y}",
        "Name = [#set text(red)]",
        "warn $a$ *b* _c_",
        "Lab *#1* $",
    ):
        assert typed in text, typed


def test_optional_plan_keys_and_a_superseded_certificate(special: list[str]) -> None:
    first = _flat(special[0])
    assert "Place of calibration on site: <Hall 3> #2" in first
    assert "Date of receipt 2026-11-20" in first
    assert "Condition of the item as new, seal intact" in first
    assert "Supersedes certificate No. RC-2026-0041, which this certificate replaces" in first


def test_every_command_kind_prints_its_results(
    kind_content: dict[str, CertificateContent],
) -> None:
    for command, content in kind_content.items():
        text = _flat("\n".join(_pages(render_pdf(content, Path(".")))))
        assert f"rotacal {command}" in text
        for q in content.measurements[0].quantities:
            spread = printed_interval(q.interval) if q.interval else printed_number(q.U)
            assert _row(printed_number(q.value), spread, q.unit, q.k) in text, (command, q.key)


# --- the figures' files -------------------------------------------------------------------


def test_figure_files_are_vector_svg(issued: dict[str, Any]) -> None:
    svg = "{http://www.w3.org/2000/svg}"
    for m in issued["content"].measurements:
        for figure in m.figures:
            assert re.fullmatch(rf"figure-{m.index}-\d-[a-z-]+\.svg", figure.file)
            root = ET.parse(issued["folder"] / figure.file).getroot()
            assert root.tag == f"{svg}svg"
            assert not list(root.iter(f"{svg}image")), figure.file
            assert len(list(root.iter(f"{svg}path"))) > 20, figure.file
