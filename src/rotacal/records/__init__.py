"""The records store: every certificate issued, kept unchanged, with the history and drift of
each item (ISO/IEC 17025:2017 §7.5, §8.4; ILAC-G24 on calibration intervals).

SQLite by default (a file in the user's data folder), PostgreSQL for a laboratory with several
stations; the schema by Alembic migrations. See :func:`open_store`.
"""

from __future__ import annotations

from .engine import data_dir, default_url, resolve_url
from .history import ItemHistory, item_history
from .store import DEFAULT_SETTINGS, Store, open_store

__all__ = [
    "DEFAULT_SETTINGS",
    "ItemHistory",
    "Store",
    "data_dir",
    "default_url",
    "item_history",
    "open_store",
    "resolve_url",
]
