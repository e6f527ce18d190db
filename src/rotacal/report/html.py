"""Self-contained HTML reports a metrologist reads: a summary first, then figures, then details.

A :class:`Report` is a title, a summary of results (each value ± U with k and p, and a verdict
where a limit is given), then one :class:`Section` per analysis: its text and figures first, its
tables after, and its uncertainty budgets folded away (``<details>``) below. The references the
sections cite (:mod:`rotacal.references`) are listed at the end; the page scrolls no wider than a
phone (tables scroll inside themselves) and prints with one analysis per page.

Figures are PNGs reduced to an adaptive 128-colour palette (a fifth of the bytes of a full-colour
PNG, no visible change on line plots) and embedded as data URIs: one file, no network request.
"""

from __future__ import annotations

import base64
import dataclasses
import datetime as _dt
import io
import platform
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import jinja2

import rotacal
from rotacal.io.outputs import InputFile, write_output
from rotacal.references import reference_list

__all__ = [
    "Figure",
    "Link",
    "Report",
    "ResultRow",
    "Section",
    "Table",
    "figure_from_matplotlib",
    "render_html",
    "write_html",
]


@dataclasses.dataclass
class Figure:
    """A PNG figure, base64-encoded so the report needs no other file."""

    title: str
    png_base64: str
    caption: str = ""
    width: int = 0  # pixels, for the img element (0: unknown)
    height: int = 0


@dataclasses.dataclass
class Table:
    """A table; ``caption`` is one short line, ``note`` (optional) the longer explanation."""

    columns: list[str]
    rows: list[list[str]]
    caption: str = ""
    first_column_header: bool = True
    note: str = ""


@dataclasses.dataclass
class ResultRow:
    """One result in a report's summary: ``value`` already written as ``value ± U unit``.

    ``coverage`` reads ``k = 2.00, p = 95 %`` (empty for a value without U, e.g. a count);
    ``limit`` states the requirement where one is given and ``passed`` the verdict (None: no
    limit). ``note`` is a short remark shown under the name (e.g. "bias-corrected").
    """

    quantity: str
    value: str
    coverage: str = ""
    limit: str = ""
    passed: bool | None = None
    note: str = ""


@dataclasses.dataclass
class Section:
    """One analysis (or one part of one) in a report.

    ``results`` go to the report's summary at the top; ``paragraphs``, ``figures`` and ``tables``
    make the section's body in that order; ``details`` (uncertainty budgets, long lists) are folded
    away under the body; ``references`` are keys of :data:`rotacal.references.REFERENCES` that the
    section cites, listed at the end of the report.
    """

    title: str
    paragraphs: list[str] = dataclasses.field(default_factory=list)
    tables: list[Table] = dataclasses.field(default_factory=list)
    figures: list[Figure] = dataclasses.field(default_factory=list)
    anchor: str = ""
    results: list[ResultRow] = dataclasses.field(default_factory=list)
    details: list[Table] = dataclasses.field(default_factory=list)
    references: list[str] = dataclasses.field(default_factory=list)


@dataclasses.dataclass
class Link:
    """A line of an index page: a report, what it holds, and its headline results."""

    title: str
    href: str
    description: str = ""
    results: list[ResultRow] = dataclasses.field(default_factory=list)


@dataclasses.dataclass
class Report:
    title: str
    subtitle: str = ""
    sections: list[Section] = dataclasses.field(default_factory=list)
    inputs: dict[str, str] = dataclasses.field(default_factory=dict)
    #: what the reader must know before trusting the numbers (the results' ``warnings``)
    warnings: list[str] = dataclasses.field(default_factory=list)
    #: an index page's reports (the demo's report.html); shown before the sections
    links: list[Link] = dataclasses.field(default_factory=list)
    #: references cited by the report's own text (the sections add theirs)
    references: list[str] = dataclasses.field(default_factory=list)
    #: the index page this report belongs to (relative href; empty: none), linked at the top
    home: str = ""


#: Colours of the palette a figure is reduced to (adaptive; line plots need far fewer).
FIGURE_COLOURS = 128


def figure_from_matplotlib(fig: Any, title: str, caption: str = "", dpi: int = 96) -> Figure:
    """Render a matplotlib figure to an embedded, palette-optimised PNG and close it."""
    import matplotlib.pyplot as plt
    from PIL import Image

    buf = io.BytesIO()
    # an uncompressed intermediate PNG: it is decoded again at once (its pixels are the same at
    # every compression level; compressing it cost ~20 ms a figure)
    fig.savefig(buf, format="png", dpi=dpi, bbox_inches="tight", pil_kwargs={"compress_level": 0})
    plt.close(fig)
    buf.seek(0)
    with Image.open(buf) as image:
        palette = image.convert("RGB").quantize(
            colors=FIGURE_COLOURS,
            method=Image.Quantize.FASTOCTREE,
            dither=Image.Dither.NONE,
        )
        out = io.BytesIO()
        palette.save(out, format="PNG", optimize=True)
        width, height = image.size
    return Figure(
        title=title,
        png_base64=base64.b64encode(out.getvalue()).decode("ascii"),
        caption=caption,
        width=width,
        height=height,
    )


_CSS = """
 :root { --ink: #1d232b; --muted: #56606b; --rule: #c8d0d8; --head: #eef3f8; --accent: #2c5d8a; }
 * { box-sizing: border-box; }
 body { font-family: -apple-system, "Segoe UI", Helvetica, Arial, sans-serif; color: var(--ink);
        max-width: 1100px; margin: 1.5em auto; padding: 0 1em; line-height: 1.45;
        overflow-wrap: break-word; }
 h1 { font-size: 1.6em; margin: 0 0 0.1em; }
 h2 { font-size: 1.3em; border-bottom: 2px solid var(--accent); padding-bottom: 0.2em;
      margin-top: 2em; }
 h3 { font-size: 1.05em; margin: 1.4em 0 0.4em; }
 .subtitle { color: var(--muted); margin-top: 0; }
 .table-wrap { overflow-x: auto; max-width: 100%; margin: 0.6em 0 1.2em; }
 table { border-collapse: collapse; font-size: 0.92em; }
 th, td { border: 1px solid var(--rule); padding: 0.3em 0.6em; text-align: right;
          vertical-align: top; }
 th { background: var(--head); } td.k, th.k { text-align: left; }
 caption { caption-side: top; text-align: left; font-weight: 600; padding-bottom: 0.3em; }
 p.note { font-size: 0.88em; color: var(--muted); margin: -0.8em 0 1.2em; }
 table.summary td.v { white-space: nowrap; font-variant-numeric: tabular-nums; }
 table.summary tr.group th { text-align: left; background: #f6f8fa; }
 table.summary .remark { display: block; font-size: 0.85em; color: var(--muted); }
 .pass { color: #1d6b35; font-weight: 600; } .fail { color: #a4161a; font-weight: 600; }
 figure { margin: 1em 0 1.6em; } figure img { max-width: 100%; height: auto;
          border: 1px solid #e3e7eb; }
 figcaption { font-size: 0.9em; color: #445; margin-top: 0.3em; }
 details { border: 1px solid var(--rule); border-radius: 4px; padding: 0.3em 0.8em;
           margin: 0.5em 0; }
 details > summary { cursor: pointer; font-weight: 600; color: var(--accent); }
 .meta td, .meta th { text-align: left; }
 nav { margin: 1em 0; } nav a { margin-right: 1em; display: inline-block; }
 .warnings { border: 2px solid #b8860b; background: #fff8e1; padding: 0.4em 1em; margin: 1em 0; }
 .warnings h2 { margin: 0.3em 0; font-size: 1.05em; color: #7a5200; border: none; }
 ul.links { list-style: none; padding: 0; } ul.links > li { margin: 0 0 1.2em; }
 ul.links table.summary { font-size: 0.88em; margin-top: 0.3em; }
 table.summary td.v + td { white-space: nowrap; }
 ul.links a { font-weight: 600; font-size: 1.05em; }
 ol.references li { margin-bottom: 0.3em; }
 @media (max-width: 600px) { body { padding: 0 0.6em; } th, td { padding: 0.25em 0.4em; } }
 @media print {
   body { max-width: none; margin: 0; font-size: 10pt; }
   nav { display: none; }
   section.analysis { break-before: page; }
   figure, table, details { break-inside: avoid; }
   .table-wrap { overflow: visible; }
   details { border: none; padding: 0; }
   a { color: inherit; text-decoration: none; }
 }
"""

#: Opens every folded section before printing, so that paper shows the budgets too: on the
#: browser's print event and when the print medium applies (a PDF printer, print preview).
_PRINT_SCRIPT = (
    "(function(){function o(){document.querySelectorAll('details')"
    ".forEach(function(d){d.open=true;});}"
    "window.addEventListener('beforeprint',o);"
    "var m=window.matchMedia&&window.matchMedia('print');"
    "if(m){m.addEventListener('change',function(e){if(e.matches)o();});}})();"
)

_TEMPLATE = jinja2.Template(
    """<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8">
<meta name="viewport" content="width=device-width, initial-scale=1">
<title>{{ report.title }}</title>
<style>{{ css|safe }}</style>
<script>{{ script|safe }}</script></head><body>
{%- macro table(t, cls="", caption=True) %}
<div class="table-wrap"><table{% if cls %} class="{{ cls }}"{% endif %}>
{%- if caption and t.caption %}<caption>{{ t.caption }}</caption>{% endif %}
<thead><tr>{% for c in t.columns %}<th{% if loop.first and t.first_column_header %} class="k"{% endif %}>{{ c }}</th>{% endfor %}</tr></thead>
<tbody>{% for r in t.rows %}<tr>{% for c in r %}<td{% if loop.first and t.first_column_header %} class="k"{% endif %}>{{ c }}</td>{% endfor %}</tr>
{% endfor %}</tbody></table></div>
{%- if t.note %}<p class="note">{{ t.note }}</p>{% endif %}
{%- endmacro %}
{%- macro results_rows(rows, limits) %}
{%- for r in rows %}<tr><td class="k">{{ r.quantity }}{% if r.note %}<span class="remark">{{ r.note }}</span>{% endif %}</td>
<td class="v">{{ r.value }}</td><td>{{ r.coverage }}</td>
{%- if limits %}<td>{{ r.limit }}</td><td>{% if r.passed is true %}<span class="pass">pass</span>{% elif r.passed is false %}<span class="fail">fail</span>{% endif %}</td>{% endif %}</tr>
{% endfor %}
{%- endmacro %}
{%- macro section(s, index, cls) %}
<section class="{{ cls }}">
<h2 id="{{ s.anchor or 's' ~ index }}">{{ s.title }}</h2>
{% for p in s.paragraphs %}<p>{{ p }}</p>{% endfor %}
{% for f in s.figures %}<figure><img alt="{{ f.title }}" src="data:image/png;base64,{{ f.png_base64 }}"
{%- if f.width %} width="{{ f.width }}" height="{{ f.height }}"{% endif %}>
<figcaption><b>{{ f.title }}.</b> {{ f.caption }}</figcaption></figure>{% endfor %}
{% for t in s.tables %}{{ table(t) }}{% endfor %}
{% for t in s.details %}<details><summary>{{ t.caption or "Details" }}</summary>
{{ table(t, caption=False) }}</details>{% endfor %}
</section>
{%- endmacro %}
<header>
{% if report.home %}<nav class="home"><a href="{{ report.home }}">← all reports</a></nav>{% endif %}
<h1>{{ report.title }}</h1>
{% if report.subtitle %}<p class="subtitle">{{ report.subtitle }}</p>{% endif %}
</header>
{% if report.warnings %}<div class="warnings" role="note"><h2>Warnings — read these before using the results</h2>
<ul>{% for w in report.warnings %}<li>{{ w }}</li>{% endfor %}</ul></div>{% endif %}
{% if report.links %}{% for s in report.sections %}{{ section(s, loop.index, "intro") }}{% endfor %}
<section><h2 id="reports">Reports</h2><ul class="links">
{% for l in report.links %}<li><a href="{{ l.href }}">{{ l.title }}</a>
{% if l.description %}<div>{{ l.description }}</div>{% endif %}
{% if l.results %}<div class="table-wrap"><table class="summary"><tbody>{{ results_rows(l.results, l.results|selectattr("passed", "ne", none)|list or l.results|selectattr("limit")|list) }}</tbody></table></div>{% endif %}
</li>{% endfor %}</ul></section>{% endif %}
{% if summary_groups %}<section><h2 id="summary">Summary</h2>
<div class="table-wrap"><table class="summary">
<thead><tr><th class="k">quantity</th><th>value ± U</th><th>coverage</th>
{%- if limits %}<th>limit</th><th>verdict</th>{% endif %}</tr></thead><tbody>
{% for title, rows in summary_groups %}
{%- if summary_groups|length > 1 %}<tr class="group"><th colspan="{{ 5 if limits else 3 }}">{{ title }}</th></tr>{% endif %}
{{ results_rows(rows, limits) }}
{%- endfor %}</tbody></table></div>
<p class="note">U is the expanded uncertainty for the coverage probability p with the coverage factor k; U is rounded to two significant digits and the value to the same decimal place (ILAC-P14).</p>
</section>{% endif %}
{% if not report.links %}
{% if report.sections|length > 2 %}<nav class="contents" aria-label="Contents">{% for s in report.sections %}
<a href="#{{ s.anchor or 's' ~ loop.index }}">{{ s.title }}</a>{% endfor %}</nav>{% endif %}
{% for s in report.sections %}{{ section(s, loop.index, "analysis") }}{% endfor %}
{% endif %}
<section><h2 id="about">About this report</h2>
<div class="table-wrap"><table class="meta">
 <tr><th class="k">rotacal</th><td>{{ version }}</td></tr>
 <tr><th class="k">made</th><td>{{ made }}</td></tr>
 <tr><th class="k">machine</th><td>{{ machine }}</td></tr>
 {% for k, v in report.inputs.items() %}<tr><th class="k">{{ k }}</th><td>{{ v }}</td></tr>{% endfor %}
</table></div></section>
{% if references %}<section><h2 id="references">References</h2><ol class="references">
{% for r in references %}<li id="ref-{{ r.key }}">{{ r.full() }}</li>{% endfor %}</ol></section>{% endif %}
</body></html>
""",
    autoescape=True,
)


def render_html(report: Report) -> str:
    """The whole report as one HTML string (figures embedded as data URIs)."""
    made = _dt.datetime.now(_dt.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    machine = f"{platform.node()} · Python {platform.python_version()} · {platform.machine()}"
    groups = [(s.title, s.results) for s in report.sections if s.results]
    limits = any(r.limit or r.passed is not None for _, rows in groups for r in rows) or any(
        r.limit or r.passed is not None for link in report.links for r in link.results
    )
    cited = [*report.references, *(key for s in report.sections for key in s.references)]
    return _TEMPLATE.render(
        report=report,
        version=rotacal.__version__,
        made=made,
        machine=machine,
        summary_groups=groups,
        limits=limits,
        references=reference_list(cited),
        css=_CSS,
        script=_PRINT_SCRIPT,
    )


def write_html(
    report: Report,
    path: str | Path,
    *,
    overwrite: bool = False,
    inputs: Sequence[InputFile] = (),
    label: str | None = None,
) -> Path:
    """Write the report as every rotacal output is written (:mod:`rotacal.io.outputs`).

    Missing folders are created; the file appears whole or not at all, never replaces one of
    ``inputs``, and replaces an existing file (atomically) only with ``overwrite``. ``label`` names
    the file in messages (e.g. ``--report r.html``).
    """
    return write_output(
        path,
        render_html(report),
        label=label,
        overwrite=overwrite,
        inputs=inputs,
        make_folders=True,
    )
