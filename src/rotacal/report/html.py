"""Self-contained HTML reports: sections of text, tables and figures, all embedded in one file."""

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

__all__ = [
    "Figure",
    "Report",
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


@dataclasses.dataclass
class Table:
    columns: list[str]
    rows: list[list[str]]
    caption: str = ""
    first_column_header: bool = True


@dataclasses.dataclass
class Section:
    title: str
    paragraphs: list[str] = dataclasses.field(default_factory=list)
    tables: list[Table] = dataclasses.field(default_factory=list)
    figures: list[Figure] = dataclasses.field(default_factory=list)
    anchor: str = ""


@dataclasses.dataclass
class Report:
    title: str
    subtitle: str = ""
    sections: list[Section] = dataclasses.field(default_factory=list)
    inputs: dict[str, str] = dataclasses.field(default_factory=dict)
    #: what the reader must know before trusting the numbers (the results' ``warnings``)
    warnings: list[str] = dataclasses.field(default_factory=list)


def figure_from_matplotlib(fig: Any, title: str, caption: str = "", dpi: int = 110) -> Figure:
    """Render a matplotlib figure to an embedded PNG and close it."""
    import matplotlib.pyplot as plt

    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=dpi, bbox_inches="tight")
    plt.close(fig)
    return Figure(
        title=title, png_base64=base64.b64encode(buf.getvalue()).decode("ascii"), caption=caption
    )


_TEMPLATE = jinja2.Template(
    """<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8">
<title>{{ report.title }}</title>
<style>
 body { font-family: -apple-system, "Segoe UI", Helvetica, Arial, sans-serif; color: #1d232b;
        max-width: 1100px; margin: 2em auto; padding: 0 1.5em; line-height: 1.45; }
 h1 { font-size: 1.7em; margin-bottom: 0.1em; }
 h2 { font-size: 1.3em; border-bottom: 2px solid #2c5d8a; padding-bottom: 0.2em; margin-top: 2em; }
 .subtitle { color: #566; margin-top: 0; }
 table { border-collapse: collapse; margin: 0.8em 0 1.2em; font-size: 0.92em; }
 th, td { border: 1px solid #c8d0d8; padding: 0.3em 0.7em; text-align: right; }
 th { background: #eef3f8; } td.k, th.k { text-align: left; }
 caption { caption-side: top; text-align: left; font-weight: 600; padding-bottom: 0.3em; }
 figure { margin: 1em 0 1.6em; } figure img { max-width: 100%; border: 1px solid #e3e7eb; }
 figcaption { font-size: 0.9em; color: #445; margin-top: 0.3em; }
 .meta td { text-align: left; } nav a { margin-right: 1em; }
 .warnings { border: 2px solid #b8860b; background: #fff8e1; padding: 0.4em 1em; margin: 1em 0; }
 .warnings h3 { margin: 0.3em 0; font-size: 1.05em; color: #7a5200; }
 @media print { h2 { page-break-before: auto; } figure { page-break-inside: avoid; } }
</style></head><body>
<h1>{{ report.title }}</h1>
{% if report.subtitle %}<p class="subtitle">{{ report.subtitle }}</p>{% endif %}
<table class="meta">
 <tr><th class="k">rotacal</th><td>{{ version }}</td></tr>
 <tr><th class="k">made</th><td>{{ made }}</td></tr>
 <tr><th class="k">machine</th><td>{{ machine }}</td></tr>
 {% for k, v in report.inputs.items() %}<tr><th class="k">{{ k }}</th><td>{{ v }}</td></tr>{% endfor %}
</table>
{% if report.warnings %}<div class="warnings"><h3>Warnings — read these before using the results</h3>
<ul>{% for w in report.warnings %}<li>{{ w }}</li>{% endfor %}</ul></div>{% endif %}
{% if report.sections|length > 2 %}<nav>{% for s in report.sections %}
<a href="#{{ s.anchor or 's' ~ loop.index }}">{{ s.title }}</a>{% endfor %}</nav>{% endif %}
{% for s in report.sections %}
<h2 id="{{ s.anchor or 's' ~ loop.index }}">{{ s.title }}</h2>
{% for p in s.paragraphs %}<p>{{ p }}</p>{% endfor %}
{% for t in s.tables %}<table>{% if t.caption %}<caption>{{ t.caption }}</caption>{% endif %}
<tr>{% for c in t.columns %}<th{% if loop.first %} class="k"{% endif %}>{{ c }}</th>{% endfor %}</tr>
{% for r in t.rows %}<tr>{% for c in r %}<td{% if loop.first %} class="k"{% endif %}>{{ c }}</td>{% endfor %}</tr>
{% endfor %}</table>{% endfor %}
{% for f in s.figures %}<figure><img alt="{{ f.title }}" src="data:image/png;base64,{{ f.png_base64 }}">
<figcaption><b>{{ f.title }}.</b> {{ f.caption }}</figcaption></figure>{% endfor %}
{% endfor %}
</body></html>
""",
    autoescape=True,
)


def render_html(report: Report) -> str:
    """The whole report as one HTML string (figures embedded as data URIs)."""
    made = _dt.datetime.now(_dt.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    machine = f"{platform.node()} · Python {platform.python_version()} · {platform.machine()}"
    return _TEMPLATE.render(report=report, version=rotacal.__version__, made=made, machine=machine)


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
