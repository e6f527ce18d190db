"""Out-of-core sinusoidal-motion calibration from an optical shaft encoder (seed 000, OSE scheme).

:func:`calibrate_encoder_motion_chunked` gives the same :class:`~rotacal.table.MotionResult` as
:func:`~rotacal.table.calibrate_encoder_motion` while reading the capture chunk by chunk, so
memory is set by the chunk size, not by the capture's length. The capture is read in passes, each
a fresh call of ``chunks()``:

1. checks (lengths, NaN/inf, time order across chunks) and the sample count N;
2. the Heydemann fit on the same even stride as in memory (at most 2·10⁵ points);
3. signal phase with the cycle count carried from chunk to chunk (:class:`PhaseState`; a
   per-chunk ``np.unwrap`` would lose whole cycles at the boundaries), the subinterval
   transitions (global index and count k), the phase state at each chunk's start, and a
   decimated copy for the figures; then the reversals from the transition list (the same code
   as in memory, :func:`~rotacal.encoder.plan_reversals`);
4. the signals in each reversing subinterval (eqs. (7)–(8)) and the time of each reversal;
5. the n whole periods between 2n+1 reversals fed to :class:`HarmonicFitAccumulator` (normal
   equations accumulated over chunks; θ recomputed from the saved phase state), with the
   three-parameter fit at the set frequency accumulated beside it;
6. with set values, the angular position error (eq. (2)), its maximum and rms.

Passes 4–6 stop reading after the last sample they need. What grows with the capture is only
per-event: the transition list (16 bytes per transition), the reversal windows, the block
moments of the fit (~1 % of the analysed samples) and the decimated copies (≈ 20 000 points).

References
----------
Feng R., Yan J., Wu Y., Yu N., Yin X. (2023). Methods for Comprehensive Calibration of a
Low-Frequency Angular Acceleration Rotary Table. Sensors 23, 4876, §3, eqs. (1)–(8).
IEEE Std 1057-2017, §4.1.3 (sine fitting).
"""

from __future__ import annotations

import dataclasses
import math
import mmap
import os
from collections.abc import Callable, Iterator, Mapping
from typing import Any

import numpy as np

from rotacal.encoder import (
    PhaseState,
    QuadratureCorrection,
    ReversalPlan,
    correct_quadrature,
    fit_quadrature_correction,
    plan_reversals,
    reversal_point_in_window,
    reversal_window,
    subinterval_transitions,
    unwrapped_phase,
)
from rotacal.errors import CaptureError, ConfigError
from rotacal.io import iter_capture_chunks
from rotacal.signal import HarmonicFitAccumulator, SineFit, fit_harmonics
from rotacal.table.motion import (
    _ELLIPSE_POINTS,
    MotionResult,
    _check_settings,
    _cut,
    _finish,
    _plot_stride,
    position_error,
)

__all__ = ["ChunkSource", "calibrate_encoder_motion_chunked", "encoder_chunks_from_file"]

#: A callable that starts a fresh pass over the capture each time it is called.
ChunkSource = Callable[[], Iterator[Mapping[str, np.ndarray]]]

_COLUMNS = ("time_s", "a", "b")
_MIN_SAMPLES = 16
#: Analysed spans up to this many samples are gathered and fitted exactly as in memory (16 MB).
_GATHER_MAX_SAMPLES = 1_000_000
#: Samples held back before the first ``HarmonicFitAccumulator.add`` (the in-memory fit takes its
#: working offset from the first 2¹⁶ samples; the same samples give the same offset here).
_FIRST_ADD_SAMPLES = 1 << 16
_SUB_RAD = 2.0 * math.pi / 12.0
_TWO_PI = 2.0 * math.pi
