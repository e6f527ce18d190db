"""rotacal.io — captures in and out: CSV, NPZ, HDF5 and TDMS readers and writers.

See the "Captures (input files)" section of INTERFACE.md for the contract.
"""

from typing import TYPE_CHECKING

from rotacal._lazy import attach

if TYPE_CHECKING:
    from ._common import FORMATS, check_time
    from .capture import (
        Capture,
        DeferredChecks,
        capture_columns,
        capture_length,
        iter_capture_chunks,
        parse_column_mapping,
        read_capture,
        read_capture_deferred,
        read_capture_rows,
    )
    from .read_options import ReadOptions
    from .write import write_capture

__all__ = [
    "FORMATS",
    "Capture",
    "DeferredChecks",
    "ReadOptions",
    "capture_columns",
    "capture_length",
    "check_time",
    "iter_capture_chunks",
    "parse_column_mapping",
    "read_capture",
    "read_capture_deferred",
    "read_capture_rows",
    "write_capture",
]

__getattr__, __dir__ = attach(__name__, __file__, __all__)
