"""Figures and self-contained HTML reports (on top of every calibration; nothing imports it back)."""

from rotacal.report.html import (
    Figure,
    Report,
    Section,
    Table,
    figure_from_matplotlib,
    render_html,
    write_html,
)

__all__ = [
    "Figure",
    "Report",
    "Section",
    "Table",
    "figure_from_matplotlib",
    "render_html",
    "write_html",
]
