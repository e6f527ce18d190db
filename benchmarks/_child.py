"""Run a benchmark's measurement in a child process (its own peak RSS, one BLAS thread) and read
the JSON object it prints on its last line."""

from __future__ import annotations

import json
import os
import subprocess
import sys


def child_json(script: str, *args: str) -> dict[str, float]:
    """``python -c script args…`` with one BLAS/OpenMP thread; the dict of its last stdout line."""
    env = dict(os.environ, OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1")
    out = subprocess.run(
        [sys.executable, "-c", script, *args], check=True, capture_output=True, text=True, env=env
    )
    result: dict[str, float] = json.loads(out.stdout.strip().splitlines()[-1])
    return result
