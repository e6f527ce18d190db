"""Wording of the gyro and encoder reports: diagnostics labelled as such, numbers and names a
person reads.

A quantity a report states as a result carries its expanded uncertainty (the summary's
:class:`~rotacal.report.html.ResultRow`); the numbers that only help a reader judge the analysis
(rows used, a condition number, a residual rms, the uncompensated rate) go to a table whose caption
says they are diagnostics, not results, so that nobody copies one onto a certificate.

The analyses' notes and budget notes are also JSON (which keeps them as they are); :func:`readable`
rewrites them for the page: a number in E notation in fixed notation or with a power of ten
(:func:`rotacal.numbers.fixed`), a head's column name ``head_3`` as "head 3".
"""

from __future__ import annotations

import dataclasses
import re
from collections.abc import Iterable, Sequence

from rotacal.glossary import GLOSSARY
from rotacal.numbers import fixed
from rotacal.references import cite
from rotacal.report.html import ResultRow, Table

__all__ = [
    "DIAGNOSTICS",
    "diagnostics_table",
    "paragraph",
    "readable",
    "readable_rows",
    "readable_tables",
]

#: The caption every diagnostics table starts with.
DIAGNOSTICS = "Diagnostics, not results"

_E_NUMBER = re.compile(r"(?<![\w.])([-+]?\d+(?:\.\d+)?[eE][-+]?\d+)(?!\w)(?!\.\d)")
#: The papers as the analyses' notes name them (the JSON keeps the notes as they are).
_SEEDS = {"000": "feng2023", "001": "gyrowheel", "003": "robot2023", "004": "kokuyama2015"}
_SEED = re.compile(r"\b(?:the )?seed (00[0134])('s)?\b")
#: Functions and fields an analysis's notes name, in words.
_FIELDS = {"timing_jitter": "the timing-noise estimate"}
_FIELD = re.compile(r"\b(" + "|".join(_FIELDS) + r")\b")
#: A rate unit as the JSON writes it (deg/s, deg/h/g): the degree sign on the page.
_DEG_PER = re.compile(r"\bdeg/")
#: A square written with a caret (s^2), not a power with more digits (2^20).
_SQUARED = re.compile(r"\^2(?!\d)")
#: A triad's bias symbol b_x as the budgets name it.
_BIAS_SYMBOL = re.compile(r"\bb_([xyz])\b")
_KEY_U = re.compile(r"\b([a-z][a-z0-9]*(?:_[a-z0-9]+)*)_u\b")
_HEAD = re.compile(r"\bhead_(\d+)\b")
#: An index written as a subscript in a method's note (e_j): the Unicode subscript letter.
_SUBSCRIPT_J = re.compile(r"\b([a-z])_j\b")
#: What an analysis writes when the user named no output unit: words, not a unit's name.
_NO_UNIT = re.compile(r"\boutput unit\b(?!s)")


def diagnostics_table(rows: Sequence[Sequence[str]], what: str = "") -> Table:
    """A two-column table (quantity, value) captioned "Diagnostics, not results[: what]"."""
    caption = f"{DIAGNOSTICS}: {what}" if what else DIAGNOSTICS
    return Table(["quantity", "value"], [list(r) for r in rows], caption=caption)


def _significant(text: str) -> int:
    mantissa = text.lstrip("+-").split("e")[0].split("E")[0].replace(".", "").lstrip("0")
    return max(len(mantissa), 1)


def readable(text: str) -> str:
    """``text`` with E-notation numbers in fixed notation (same significant digits), head column
    names (``head_3``) as words ("head 3"), "seed 004" by its author and year, ``<key>_u`` of a
    glossary key as u(plain name), "deg/" as "°/", the GUM's ``t_p`` as tₚ, an index ``e_j`` as eⱼ, and "output unit" (no unit given) as "output
    units"."""

    def plain(m: re.Match[str]) -> str:
        number = m.group(1)
        sign = "+" if number.startswith("+") else ""
        return sign + fixed(float(number), _significant(number), keep_zeros=True)

    def key_u(m: re.Match[str]) -> str:
        term = GLOSSARY.get(m.group(1))
        return f"u({term.name})" if term is not None else m.group(0)

    text = _E_NUMBER.sub(plain, text)
    text = _SEED.sub(lambda m: cite(_SEEDS[m.group(1)]) + (m.group(2) or ""), text)
    text = _KEY_U.sub(key_u, text)
    text = _FIELD.sub(lambda m: _FIELDS[m.group(1)], text)
    text = _DEG_PER.sub("°/", _SQUARED.sub("²", text).replace("t_p(", "tₚ("))
    text = _BIAS_SYMBOL.sub(r"b(\1)", text)
    text = _SUBSCRIPT_J.sub(r"\1ⱼ", text)
    return _NO_UNIT.sub("output units", _HEAD.sub(r"head \1", text))


def paragraph(text: str) -> str:
    """:func:`readable` of an analysis's note, starting with a capital as a paragraph does."""
    text = readable(text)
    return text[:1].upper() + text[1:]


def readable_tables(tables: Iterable[Table]) -> list[Table]:
    """Copies of ``tables`` with :func:`readable` applied to the caption, the note and every cell."""
    return [
        dataclasses.replace(
            t,
            caption=readable(t.caption),
            note=readable(t.note),
            rows=[[readable(str(c)) for c in row] for row in t.rows],
        )
        for t in tables
    ]


def readable_rows(rows: Iterable[ResultRow]) -> list[ResultRow]:
    """Copies of summary rows with :func:`readable` applied to the name, the value and the note."""
    return [
        dataclasses.replace(
            r, quantity=readable(r.quantity), value=readable(r.value), note=readable(r.note)
        )
        for r in rows
    ]
