"""Sphinx configuration of the rotacal documentation site.

Build it (from the repository's root; the HTML lands in docs/_build/html/index.html)::

    python -m sphinx -W --keep-going -b html docs docs/_build/html

A clean build takes about 25 s of CPU on one core. Not ``-j``: sphinx-mathjax-offline does not
declare itself parallel-safe, so a parallel build warns, and ``-W`` makes that an error.

Pages are MyST Markdown; the API reference comes from the docstrings (autodoc + napoleon, NumPy
style), the CLI reference from the click commands (sphinx-click), the JSON-key table from
rotacal.glossary (docs/_ext/rotacal_keys.py). Everything the pages load is served from the build
(MathJax included, by sphinx-mathjax-offline): the site works without a network.
"""

from __future__ import annotations

import logging
import sys
from pathlib import Path

# The theme's a11y_pygments configures the root logger at INFO when imported; Alembic's start-up
# chatter (imported with rotacal.records' reference page) is not the build's business.
logging.getLogger("alembic").setLevel(logging.WARNING)

DOCS = Path(__file__).resolve().parent
# the package from this checkout (also when it is not installed), and the local extension
sys.path.insert(0, str(DOCS.parent / "src"))
sys.path.insert(0, str(DOCS / "_ext"))

import rotacal  # noqa: E402

project = "rotacal"
author = "the rotacal contributors"
copyright = "the rotacal contributors, BSD-3-Clause"
release = rotacal.__version__
version = release

extensions = [
    "myst_parser",
    "sphinx.ext.autodoc",
    "sphinx.ext.napoleon",
    "sphinx_click",
    # MathJax copied into _static/ and loaded from there instead of a CDN (works offline)
    "sphinx-mathjax-offline",
    "rotacal_keys",
    "plain_docstrings",
]

source_suffix = {".md": "markdown", ".rst": "restructuredtext"}
root_doc = "index"
exclude_patterns = ["_build", "Thumbs.db", ".DS_Store", "README.md"]
# the methods/tutorials pages use these: $…$ and $$…$$ math, ::: fences, definition lists
myst_enable_extensions = ["dollarmath", "colon_fence", "deflist"]
# anchors for `page.md#a-heading` links (README-style links between pages keep working)
myst_heading_anchors = 3
nitpicky = False
# Help texts and docstrings are written for a terminal: "--out" stays two hyphens (no en dash)
# and `demo` in single backquotes is code, as a reader of `rotacal --help` reads it.
smartquotes = False
default_role = "code"
suppress_warnings = [
    # "more than one target found": the docstrings' Attributes sections read "name : meaning"
    # (the type is in the annotation) and napoleon renders the meaning as a type, whose words
    # ("unit", "name") Sphinx then tries to link to the attributes of that name in other
    # classes. The text is right; only the guessed link is ambiguous, so it stays unlinked.
    "ref.python",
]

# autodoc: the documented signature shows the hints; members in source order (the order in which
# a module reads, which is the order a reader learns it)
autodoc_member_order = "bysource"
autodoc_typehints = "description"
# hints only for parameters the docstring describes: a result class documents its public
# attributes, and its private fields (figures' data) stay out of the reference
autodoc_typehints_description_target = "documented"
autodoc_typehints_format = "short"
autodoc_default_options = {"members": True, "show-inheritance": False}
napoleon_google_docstring = False
napoleon_numpy_docstring = True
napoleon_use_rtype = False

html_theme = "furo"
html_title = f"rotacal {release}"
html_static_path: list[str] = []
html_show_sourcelink = False
# no web fonts, no analytics: furo loads nothing from outside by default
