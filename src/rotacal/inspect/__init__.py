"""rotacal.inspect — a first look at a file before any analysis (``rotacal inspect``).

:func:`inspect_capture` says what a file is and, for a capture, reports each column's length,
range, NaN/inf, repeated and clipped samples and resolution, the time column's sampling rate,
jitter and gaps, the analysis commands whose columns it has and the ``--column`` mappings its
names suggest. :func:`inspect_columns` does the same for arrays; :class:`Inspector` for columns
fed in chunks.
"""

from .core import Inspector, inspect_columns
from .files import inspect_capture
from .result import ColumnSummary, Gap, InspectResult

__all__ = [
    "ColumnSummary",
    "Gap",
    "InspectResult",
    "Inspector",
    "inspect_capture",
    "inspect_columns",
]
