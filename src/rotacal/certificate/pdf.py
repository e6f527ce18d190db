"""The PDF calibration certificate (ISO/IEC 17025:2017 §7.8), typeset by Typst.

:func:`render_pdf` turns a :class:`CertificateContent` into the certificate a person signs. The
layout lives in one Typst template shipped with the package (``templates/certificate.typ``); this
module hands it the certificate as JSON data (``sys.inputs``), every text already in the words and
number layout it is printed in. The template only lays the data out: no Typst markup is ever built
from a user's text, so a customer named ``A #1 *Ltd* $x$ <y> @z`` prints as typed.

Why Typst (and not ReportLab): Typst is a typesetting system — Knuth–Plass line breaking,
hyphenation, kerning and ligatures, tables whose header repeats on every page they span — where
ReportLab places strings on a canvas. It draws SVG figures as vectors (ReportLab needs svglib and
loses parts of matplotlib's SVG), counts pages natively ("page n of m" without a second pass),
and writes PDF/A-2b for the archive. Its Python package is one pip wheel with the compiler and the
fonts inside (no TeX, no system library); only those embedded fonts are used, so the PDF is the
same on every machine. Compiling a certificate of five measurements (six pages, five figures)
takes 0.12–0.19 s (``benchmarks/bench_certificate_pdf.py``); drawing its figures 0.1–0.35 s each.

Number layout: a value or U prints exactly as :class:`ReportedQuantity` holds it (ILAC-P14
rounded), with its digits grouped by three on both sides of the decimal point with a narrow
no-break space once a side has more than four (ISO 80000-1:2009 §7.3.1; SI Brochure, 9th ed.,
§5.4.4) and a true minus sign: :func:`printed_number`. The tests find every value in the text
pypdf extracts by the same function.
"""

from __future__ import annotations

import datetime as dt
import json
import re
from collections.abc import Iterable, Mapping
from decimal import Decimal
from importlib import resources
from pathlib import Path
from typing import TYPE_CHECKING, Any

from .conformity import RULE_TEXT
from .content import CertificateContent, Conformity, MeasurementResult, ReportedQuantity
from .quantities import standard_uncertainty

if TYPE_CHECKING:
    from .sign import SignatureInfo

__all__ = [
    "END_MARKER",
    "GROUP_SEPARATOR",
    "NOT_REPRODUCED",
    "ONLY_THE_ITEM",
    "certificate_data",
    "page_label",
    "printed_interval",
    "printed_number",
    "printed_text",
    "render_pdf",
]

#: The space between digit groups: U+202F NARROW NO-BREAK SPACE (a thin space that never breaks
#: a number over two lines).
GROUP_SEPARATOR = "\u202f"
#: The line that closes the certificate (ISO/IEC 17025 §7.8.2.1 d: a clear identification of
#: the end).
END_MARKER = "— End of certificate —"
#: ISO/IEC 17025 §7.8.2.1 l.
ONLY_THE_ITEM = "The results relate only to the item calibrated."
#: ILAC-P8 / common practice of accredited laboratories.
NOT_REPRODUCED = (
    "This certificate shall not be reproduced except in full without the written approval of "
    "the laboratory."
)
_MINUS = "\u2212"
_NUMBER = re.compile(r"^([+-]?)(\d+)(?:\.(\d+))?$")
_TEMPLATE = "templates/certificate.typ"
_ROLES = {"performed": "Calibration performed by", "approved": "Approved by"}
_VERDICT_WORDS = {"pass": "PASS", "fail": "FAIL", "indeterminate": "INDETERMINATE"}
_SIMPLE_RISK = (
    "With simple acceptance a measured value close to a limit can be accepted or rejected "
    "wrongly with a probability of up to 50 % (ILAC-G8:09/2019 §4.2.1)."
)
_INTERVAL_NOTE = (
    "Coverage interval for the true value at the stated coverage probability, given instead of "
    "± U: the estimate of a peak, rms or distortion is biased by noise, so the interval is not "
    "centred on the measured value (JCGM 101:2008 §7.7)."
)
#: Units of further ``[conditions]`` keys, by the ending of their name.
_CONDITION_UNITS = {
    "_c": "°C",
    "_k": "K",
    "_hpa": "hPa",
    "_kpa": "kPa",
    "_pa": "Pa",
    "_percent": "%",
    "_v": "V",
    "_hz": "Hz",
    "_s": "s",
}


def _group(digits: str, from_left: bool) -> str:
    if len(digits) <= 4:
        return digits
    if from_left:
        parts = [digits[i : i + 3] for i in range(0, len(digits), 3)]
    else:
        head = len(digits) % 3 or 3
        parts = [digits[:head]] + [digits[i : i + 3] for i in range(head, len(digits), 3)]
    return GROUP_SEPARATOR.join(parts)


def printed_number(text: str) -> str:
    """A decimal number's text as the certificate prints it: the same digits, grouped.

    Groups of three digits counted from the decimal point, separated by :data:`GROUP_SEPARATOR`,
    on a side that has more than four digits; a minus sign U+2212 for a leading ``-``. Text that
    is not a plain decimal number comes back unchanged.

    >>> printed_number("0.012499841")
    '0.012\\u202f499\\u202f841'
    >>> printed_number("-0.0030")
    '−0.0030'

    References
    ----------
    ISO 80000-1:2009 §7.3.1; BIPM, The International System of Units, 9th ed. (2019), §5.4.4.
    """
    match = _NUMBER.match(text.strip())
    if match is None:
        return text
    sign, whole, fraction = match.groups()
    out = {"-": _MINUS, "+": "+", "": ""}[sign] + _group(whole, from_left=False)
    if fraction is not None:
        out += "." + _group(fraction, from_left=True)
    return out


#: A decimal number inside a sentence: not part of a word, a code ("ILAC-G8:09/2019") or a
#: longer number; its minus follows a space or an opening bracket.
_NUMBER_IN_TEXT = re.compile(r"(?<![\w.:/-])(?:(?<=[\s(\[])-)?\d+(?:\.\d+)?(?![\w.:/-]*\d)")


def printed_text(sentence: str) -> str:
    """A sentence with each decimal number in it laid out by :func:`printed_number`, so that a
    conformity statement shows its numbers as the tables do."""
    return _NUMBER_IN_TEXT.sub(lambda m: printed_number(m.group(0)), sentence)


def printed_interval(interval: tuple[str, str]) -> str:
    """A coverage interval as printed: ``[low, high]`` of :func:`printed_number`."""
    return f"[{printed_number(interval[0])}, {printed_number(interval[1])}]"


def page_label(page: int, pages: int) -> str:
    """The page label every page carries (ISO/IEC 17025 §7.8.2.1 d): ``Page 2 of 7``."""
    return f"Page {page} of {pages}"


def _percent(p: str) -> str:
    """A coverage probability as a percentage: ``0.95`` → ``95 %`` (exactly, in decimal)."""
    value = (Decimal(p) * 100).normalize()
    return f"{value:f} %"


def _symbolic(name: str) -> dict[str, str]:
    """A quantity name whose symbol has an index (``K_xy``) as name and subscript."""
    base, sep, index = name.rpartition("_")
    # one index only: "φ_y1 + ε_y" (a sum of symbols) is printed as it is
    if sep and base and index.isalnum() and base[-1].isalpha() and "_" not in base:
        return {"name": base, "sub": index}
    return {"name": name, "sub": ""}


def _text(value: Any) -> str:
    """A plan value as a reader wrote it (``23.0``, ``true``, a date as ISO 8601)."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, (dt.date, dt.datetime)):
        return value.isoformat()
    return str(value)


def _contact(c: Any) -> dict[str, str]:
    return {"name": c.name, "address": c.address, "email": c.email, "phone": c.phone}


def _dates(start: dt.date, end: dt.date) -> str:
    return start.isoformat() if start == end else f"{start.isoformat()} to {end.isoformat()}"


def _conditions(content: CertificateContent) -> list[dict[str, str]]:
    c = content.plan.conditions
    rows = []
    if c.temperature_c is not None:
        value = f"{_text(c.temperature_c)} °C"
        if c.temperature_u_c is not None:
            value += f", standard uncertainty {_text(c.temperature_u_c)} °C"
        rows.append({"name": "ambient temperature", "value": value})
    if c.humidity_percent is not None:
        rows.append({"name": "relative humidity", "value": f"{_text(c.humidity_percent)} %"})
    for key, value in c.others:
        unit = next((u for end, u in _CONDITION_UNITS.items() if key.endswith(end)), "")
        name = key[: -len(next(e for e in _CONDITION_UNITS if key.endswith(e)))] if unit else key
        rows.append(
            {
                "name": name.replace("_", " "),
                "value": f"{_text(value)} {unit}".strip(),
            }
        )
    return rows


def _verdict_summary(verdicts: list[str]) -> str:
    """The first page's sentence on the conformity statements: only the verdicts that occur."""
    n = len(verdicts)
    if n == 0:
        return "No statement of conformity with a specification is made."
    if n == 1:
        return f"Its one statement of conformity (section 4) is {_VERDICT_WORDS[verdicts[0]]}."
    counts = [(verdicts.count(v), _VERDICT_WORDS[v]) for v in ("pass", "fail", "indeterminate")]
    parts = [f"{count} {word}" for count, word in counts if count]
    said = (
        f"all {n} are {parts[0].split(' ', 1)[1]}"
        if len(parts) == 1
        else (", ".join(parts[:-1]) + " and " + parts[-1])
    )
    return f"Of its {n} statements of conformity (section 4), {said}."


def _quantity_row(q: ReportedQuantity, notes: list[str]) -> dict[str, Any]:
    marks = []
    texts = [q.note] if q.note else []
    if q.interval:
        unit = f" {q.unit}" if q.unit else ""
        texts += [
            _INTERVAL_NOTE,
            f"Standard uncertainty u = {printed_number(standard_uncertainty(q))}{unit}, "
            f"expanded uncertainty U = {printed_number(q.U)}{unit} (k = {q.k}).",
        ]
    for text in texts:
        if text not in notes:
            notes.append(text)
        marks.append(chr(ord("a") + notes.index(text)))
    return {
        **_symbolic(q.name),
        "marks": ",".join(marks),
        "value": printed_number(q.value),
        "U": printed_interval(q.interval) if q.interval else printed_number(q.U),
        "unit": q.unit,
        "k": q.k,
        "p": _percent(q.p),
    }


def _options(options: Mapping[str, Any]) -> str:
    return "; ".join(f"{key} = {_text(value)}" for key, value in options.items())


def _figures(m: MeasurementResult, folder: Path) -> list[dict[str, str]]:
    figures = []
    for f in m.figures:
        path = folder / f.file
        if not path.is_file():
            raise FileNotFoundError(
                f"the figure {f.file} of measurement {m.index} is not in {folder}: draw the "
                "figures into the folder before the PDF is rendered"
            )
        figures.append({"svg": path.read_text(encoding="utf-8"), "caption": f.caption})
    return figures


def _measurement(m: MeasurementResult, folder: Path) -> dict[str, Any]:
    notes: list[str] = []
    rows = [_quantity_row(q, notes) for q in m.quantities]
    return {
        "index": m.index,
        "name": m.name,
        "command": f"rotacal {m.command}",
        "method": m.method,
        "references": list(m.references),
        "options": _options(m.options),
        "captures": [c.path for c in m.captures],
        "quantities": rows,
        "notes": [{"mark": chr(ord("a") + i), "text": t} for i, t in enumerate(notes)],
        "warnings": list(m.warnings),
        "figures": _figures(m, folder),
    }


def _limits(c: Conformity) -> str:
    low, high = printed_number(c.limit_min), printed_number(c.limit_max)
    if c.limit_min and c.limit_max:
        return f"{low} to {high}"
    return f"≤ {high}" if c.limit_max else f"≥ {low}"


def _conformity(content: CertificateContent) -> list[dict[str, str]]:
    rows = []
    for m in content.measurements:
        quantities = {q.key: q for q in m.quantities}
        for c in m.conformity:
            q = quantities.get(c.key)
            interval = q.interval if q is not None else None
            rows.append(
                {
                    "section": f"3.{m.index}",
                    **_symbolic(c.name),
                    "value": printed_number(c.value),
                    "U": printed_interval(interval) if interval else printed_number(c.U),
                    "interval": "yes" if interval else "",
                    "unit": c.unit,
                    "limits": _limits(c),
                    "rule": c.decision_rule,
                    "verdict": c.verdict,
                    "verdict_word": _VERDICT_WORDS[c.verdict],
                    "statement": printed_text(c.statement),
                }
            )
    return rows


def _rules(used: Iterable[str]) -> list[dict[str, str]]:
    rules = []
    for rule in sorted(set(used), key=list(RULE_TEXT).index):
        text = RULE_TEXT[rule][0].upper() + RULE_TEXT[rule][1:] + "."
        rules.append(
            {"rule": rule, "text": text + (" " + _SIMPLE_RISK if rule == "simple" else "")}
        )
    return rules


def certificate_data(
    content: CertificateContent, folder: Path, signature: SignatureInfo | None = None
) -> dict[str, Any]:
    """The certificate as the template reads it: every text in its printed form.

    ``folder`` holds the figure files that ``MeasurementResult.figures`` name; ``signature``
    describes the signature of certificate.xml, which the last page names.
    """
    plan = content.plan
    conformity = _conformity(content)
    verdicts = [row["verdict"] for row in conformity]
    return {
        "title": plan.title,
        "number": content.number,
        "laboratory": _contact(plan.laboratory),
        "customer": _contact(plan.customer),
        "item": {
            "kind": plan.item.kind,
            "manufacturer": plan.item.manufacturer,
            "model": plan.item.model,
            "serial": plan.item.serial,
            "description": plan.item.description,
            "condition": plan.item.condition,
            "received": plan.item.received.isoformat() if plan.item.received else "",
        },
        "location": plan.location,
        "calibration_dates": _dates(plan.start_date, plan.end_date),
        "issue_date": plan.issue_date.isoformat(),
        "date": {
            "year": plan.issue_date.year,
            "month": plan.issue_date.month,
            "day": plan.issue_date.day,
        },
        "supersedes": plan.supersedes or "",
        "persons": [
            {"role": _ROLES.get(p.role, p.role), "name": p.name, "title": p.title}
            for p in sorted(plan.persons, key=lambda p: p.role != "performed")
        ],
        "standards": [
            {
                "name": s.name,
                "id": s.id,
                "certificate": s.certificate,
                "traceability": s.traceability,
                "due": s.due.isoformat(),
            }
            for s in plan.standards
        ],
        "conditions": _conditions(content),
        "measurements": [_measurement(m, folder) for m in content.measurements],
        "conformity": conformity,
        "verdict_summary": _verdict_summary(verdicts),
        "rules": _rules(row["rule"] for row in conformity),
        "software": f"rotacal {content.software_version}",
        "plan_sha256": content.plan_sha256,
        "captures": [
            {
                "measurement": str(m.index),
                "path": c.path,
                "sha256": c.sha256,
                "bytes": printed_number(str(c.bytes)),
            }
            for m in content.measurements
            for c in m.captures
        ],
        "signature": _signature(signature),
        "statements": {
            "only_item": ONLY_THE_ITEM,
            "not_reproduced": NOT_REPRODUCED,
            "end": END_MARKER,
        },
    }


def _signature(signature: SignatureInfo | None) -> dict[str, str] | None:
    """The last page's signature block: who signed certificate.xml, with which certificate, and
    the SHA-256 of the signed file — which ties this PDF to that DCC (a reader compares it with
    ``sha256sum certificate.xml``; ``rotacal verify`` checks the signature itself)."""
    if signature is None:
        return None
    return {
        "signer": signature.signer,
        "fingerprint": signature.fingerprint_sha256,
        "time": signature.signing_time.replace("T", " ").replace("+00:00", " UTC"),
        "xml_sha256": signature.xml_sha256,
    }


def render_pdf(
    content: CertificateContent, folder: Path, signature: SignatureInfo | None = None
) -> bytes:
    """The certificate as a PDF/A-2b document.

    Parameters
    ----------
    content : CertificateContent
        What the certificate states.
    folder : Path
        The folder that holds the figure files (SVG) named by each measurement's ``figures``.
    signature : SignatureInfo, optional
        The signature of certificate.xml (:func:`rotacal.certificate.sign.sign_dcc`): the last
        page then names the signer, the certificate's SHA-256 fingerprint and the signed XML's
        SHA-256.

    Returns
    -------
    bytes
        The PDF. The same content and figures give the same bytes: the document's date is the
        plan's date of issue, never the clock, and only the fonts inside the Typst package are
        used (system fonts are ignored).
    """
    import typst

    template: bytes = resources.files("rotacal.certificate").joinpath(_TEMPLATE).read_bytes()
    data = json.dumps(certificate_data(content, Path(folder), signature), ensure_ascii=False)
    # only the fonts inside the typst wheel (Libertinus Serif, New Computer Modern, DejaVu Sans
    # Mono): the machine's own fonts never enter, so every machine typesets the same
    fonts = typst.Fonts(include_system_fonts=False, include_embedded_fonts=True, font_paths=[])
    return bytes(
        typst.compile(
            template,
            sys_inputs={"data": data},
            font_paths=fonts,
            ignore_system_fonts=True,
            pdf_standards=["a-2b"],
        )
    )
