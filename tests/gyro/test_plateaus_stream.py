"""The continuous log streamed (rotacal.gyro.plateaus_stream, scale_factor_log chunked, the CLI's
choice of path): equal to the whole-array path to 1e-9 whatever the chunks, chunk boundaries on
the plateaus' edges included; the refusals the same."""

from __future__ import annotations

import functools
import itertools
import json

import numpy as np
import pytest
from tests.cli.test_gyro_cli import run

from rotacal.errors import CaptureError
from rotacal.gyro.plateaus import find_plateaus
from rotacal.gyro.plateaus_stream import find_plateaus_chunked, log_chunks
from rotacal.gyro.scale_factor_log import (
    calibrate_scale_factor_log,
    calibrate_scale_factor_log_chunked,
)
from rotacal.sim import simulate_gyro_log


@functools.cache
def _twin():
    # five plateaus of 12 s at 100 Hz (7 001 rows), the DUT lagging: small, and every step seen
    cap = simulate_gyro_log(rates_deg_s=(0, 50, -50, 100, -100), plateau_s=12, lag_s=0.3, seed=7)
    c = cap.columns
    temp = 20.0 + 0.001 * c["time_s"]
    return (c["time_s"], c["rate_deg_s"], c["output"], temp), cap.truth


def _cut_at(columns, cuts):
    """A chunk source whose chunks end at the given rows."""
    edges = [0, *sorted(cuts), columns[0].size]
    names = ("time_s", "rate_deg_s", "output", "temperature_c")

    def chunks(wanted):
        for a, b in itertools.pairwise(edges):
            yield {k: columns[names.index(k)][a:b] for k in wanted}

    return chunks


def _close(a, b, path=""):
    """Every number of two JSON trees equal to 1e-9 relative (strings, shapes exactly)."""
    if isinstance(a, dict):
        assert a.keys() == b.keys(), path
        for k in a:
            _close(a[k], b[k], f"{path}.{k}")
    elif isinstance(a, list | tuple):
        assert len(a) == len(b), path
        for i, (x, y) in enumerate(zip(a, b, strict=True)):
            _close(x, y, f"{path}[{i}]")
    elif isinstance(a, float):
        scale = max(abs(a), abs(b), 1e6 if path.endswith("_ppm") else 0.0)
        assert a == b or abs(a - b) <= 1e-9 * scale, (path, a, b)
    else:
        assert a == b, (path, a, b)


def test_streamed_equals_in_memory_with_cuts_on_the_plateau_edges():
    cols, truth = _twin()
    t = cols[0]
    ref = calibrate_scale_factor_log(
        *cols[:3], temperature_c=cols[3], chunked=False, mc_trials=2000
    )
    # chunk boundaries on each plateau's first and last rows and a few rows either side (the
    # detector's window, the refined edges and the settling all straddle them) …
    edges = [int(np.searchsorted(t, p[k])) for p in truth["plateaus"] for k in ("start_s", "end_s")]
    cuts = {e + d for e in edges for d in (-3, 0, 2)} - {0}
    sources = [_cut_at(cols, [c for c in cuts if 0 < c < t.size])]
    # … and chunks shorter than the window (100 rows), as well as plain ones
    sources += [log_chunks(*cols, chunk_rows=k) for k in (37, 1024)]
    for source in sources:
        got = calibrate_scale_factor_log_chunked(
            source, rows=t.size, temperature=True, mc_trials=2000
        )
        _close(ref.to_dict(), got.to_dict())
        assert got.settle_s == ref.settle_s > 0
    # the truth is not the method's: the plateaus' ends within two samples of the twin's
    for p, q in zip(ref.plateaus, truth["plateaus"], strict=True):
        assert abs(p["end_s"] - q["end_s"]) <= 2 / truth["sensor"]["fs_hz"]


def test_streamed_refusals_name_the_row_as_in_memory():
    cols, _ = _twin()
    t = cols[0].copy()
    t[5000] = t[4999]  # time stands still at row 5000, which is a chunk's first row
    with pytest.raises(CaptureError) as whole:
        find_plateaus(t, *cols[1:3])
    with pytest.raises(CaptureError) as streamed:
        find_plateaus_chunked(log_chunks(t, *cols[1:3], chunk_rows=1000), rows=t.size)
    assert str(whole.value) == str(streamed.value) and "row 5000" in str(whole.value)

    grown = {"n": 0}

    def growing(names):  # a file still being written: longer on each pass
        grown["n"] += 1
        end = 3_000 + 1_000 * grown["n"]
        yield {c: cols[("time_s", "rate_deg_s", "output").index(c)][:end] for c in names}

    with pytest.raises(CaptureError, match="changed between the passes"):
        find_plateaus_chunked(growing)


def test_cli_streams_a_long_log_by_itself(tmp_path, monkeypatch):
    from rotacal.cli import _gyro_log

    cols, _ = _twin()
    path = tmp_path / "log.npz"
    np.savez(path, time_s=cols[0], rate_deg_s=cols[1], output=cols[2])
    memory = run("gyro", "scale-factor", str(path), "--in-memory", "--json", "-")
    # the twin's 7 001 rows count as long: the command streams without being told
    monkeypatch.setattr(_gyro_log, "LOG_IN_MEMORY_MAX_ROWS", 5_000)
    monkeypatch.setattr(_gyro_log, "_CHUNK_ROWS", 1_500)
    streamed = run("gyro", "scale-factor", str(path), "--json", "-")
    assert memory.exit_code == streamed.exit_code == 0, streamed.output
    a, b = json.loads(memory.stdout), json.loads(streamed.stdout)
    assert a.pop("provenance")["options"]["chunked"] is False
    assert b.pop("provenance")["options"]["chunked"] is None
    _close(a, b)
