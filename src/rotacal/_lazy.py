"""Lazy public names of a package (private): a name's module is imported when the name is used.

A command pays at start-up only for what it uses: ``rotacal motion encoder`` needs the encoder's
demodulation, not the self-calibration, Allan deviation or SciPy's statistics that the same
packages also export. Each package ``__init__`` keeps its public names in one place, the
``if TYPE_CHECKING:`` block of ``from .module import name`` lines that type checkers and readers
see; :func:`attach` reads that block once (a few hundred µs) and serves the names through a PEP 562
module ``__getattr__`` and ``__dir__``, so ``from rotacal.signal import fit_sine_3p`` and
``rotacal.signal.fit_sine_3p`` work exactly as with eager imports.
"""

from __future__ import annotations

import ast
import importlib
import importlib.util
import sys
from collections.abc import Callable
from typing import Any


def _imported_names(source_path: str, package: str) -> dict[str, str]:
    """Name -> absolute module of every ``from X import name`` under ``if TYPE_CHECKING:``."""
    with open(source_path, encoding="utf-8") as f:
        tree = ast.parse(f.read(), source_path)
    where: dict[str, str] = {}
    for node in tree.body:
        if not (isinstance(node, ast.If) and ast.unparse(node.test) == "TYPE_CHECKING"):
            continue
        for imp in node.body:
            if not isinstance(imp, ast.ImportFrom):
                continue
            module = ("." * imp.level + (imp.module or "")) if imp.level else imp.module or ""
            absolute = importlib.util.resolve_name(module, package)
            for alias in imp.names:
                where[alias.asname or alias.name] = absolute
    return where


def attach(
    package: str, source_path: str, public: list[str]
) -> tuple[Callable[[str], Any], Callable[[], list[str]]]:
    """PEP 562 ``__getattr__`` and ``__dir__`` serving the names of ``package``'s TYPE_CHECKING
    imports (read from ``source_path``, the package's ``__init__.py``), each imported on first use
    and then kept in the package's namespace. Every name of ``public`` (the ``__all__``) must be
    among them: a missing one raises at import time, not at a user's first call."""
    where = _imported_names(source_path, package)
    missing = sorted(set(public) - set(where))
    if missing:  # pragma: no cover - a developer's slip, caught by the first test run
        raise ImportError(f"{package}: __all__ names without a lazy import: {missing}")

    def __getattr__(name: str) -> Any:
        module = where.get(name)
        if module is None:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        value = getattr(importlib.import_module(module), name)
        setattr(sys.modules[package], name, value)  # later look-ups skip __getattr__
        return value

    def __dir__() -> list[str]:
        return sorted(set(vars(sys.modules[package])) | set(where))

    return __getattr__, __dir__
