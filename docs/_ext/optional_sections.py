"""Sections of the site that fill as their pages are written: an empty one is not a build error.

The index's Getting started, Tutorials and Methods toctrees are globs (``tutorials/*``), so a page
joins the site by being added to its folder. Sphinx warns when a glob matches nothing, and that
warning has no type that ``suppress_warnings`` could name; this filter drops exactly it, for
exactly the globs in :data:`OPTIONAL_GLOBS`. Every other warning, and an empty glob anywhere
else, still fails the ``-W`` build.
"""

from __future__ import annotations

import logging
from typing import Any

#: The toctree globs of docs/index.md that may match no page yet.
OPTIONAL_GLOBS = frozenset({"getting-started*", "tutorials/*", "methods/*"})

# sphinx.util.logging.getLogger(__name__) of sphinx/directives/other.py prefixes "sphinx."
_TOCTREE_LOGGER = "sphinx.sphinx.directives.other"
_EMPTY_GLOB = "didn't match any documents"


class _OptionalGlobFilter(logging.Filter):
    def filter(self, record: logging.LogRecord) -> bool:
        if _EMPTY_GLOB not in str(record.msg) or not record.args:
            return True
        args = record.args if isinstance(record.args, tuple) else (record.args,)
        return args[0] not in OPTIONAL_GLOBS


def setup(app: Any) -> dict[str, Any]:
    logging.getLogger(_TOCTREE_LOGGER).addFilter(_OptionalGlobFilter())
    return {"parallel_read_safe": True, "parallel_write_safe": True}
