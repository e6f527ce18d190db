"""Docstrings written for a reader of the source read the same on the site.

rotacal's docstrings write absolute values and norms as in the papers, ``max|δ|/(|S|·FS)``. In
reStructuredText ``|S|`` is a substitution reference, which the build reports as undefined. This
hook escapes every ``|`` of a docstring outside literal text (````…````) and roles
(``:math:`…```), so it prints as written. No docstring of rotacal uses substitutions, line
blocks or grid tables, which are what ``|`` means in reStructuredText.
"""

from __future__ import annotations

import re
from typing import Any

# literal text and role contents keep their characters as they are
_VERBATIM = re.compile(r"(``.+?``|:[\w:.-]+:`[^`]*`)")


def escape_bars(line: str) -> str:
    """``line`` with each ``|`` outside literal text and roles escaped as ``\\|``."""
    parts = _VERBATIM.split(line)
    # split() with one group: even indices are plain text, odd ones the verbatim spans
    return "".join(p if i % 2 else p.replace("|", r"\|") for i, p in enumerate(parts))


def _escape_docstring(
    app: Any, what: str, name: str, obj: Any, options: Any, lines: list[str]
) -> None:
    lines[:] = [escape_bars(line) for line in lines]


def setup(app: Any) -> dict[str, Any]:
    # priority above napoleon's (500): runs on the reStructuredText napoleon produced
    app.connect("autodoc-process-docstring", _escape_docstring, priority=600)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
