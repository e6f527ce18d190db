"""The pages of a streamed NPZ chunk are dropped after use (flat memory) and read back intact."""

from __future__ import annotations

import numpy as np
import pytest

from rotacal.errors import CaptureError
from rotacal.io import iter_capture_chunks
from rotacal.io.capture import release_pages
from rotacal.table._stream_source import chunks_from_file


def test_released_rows_read_back_the_same(tmp_path):
    data = np.random.default_rng(1).standard_normal(300_001)
    path = tmp_path / "r.npz"
    np.savez(path, rate_deg_s=data)
    got = [
        c["rate_deg_s"].copy() for c in iter_capture_chunks(path, ["rate_deg_s"], chunk_rows=7_919)
    ]
    np.testing.assert_array_equal(np.concatenate(got), data)
    np.save(tmp_path / "r.npy", data)
    mapped = np.load(tmp_path / "r.npy", mmap_mode="r")
    before = np.array(mapped[1000:200_000])
    release_pages({"x": mapped[:]})  # the whole array: every page dropped, then faulted back in
    np.testing.assert_array_equal(mapped[1000:200_000], before)


def test_a_verified_pass_skips_the_checks_the_first_pass_made(tmp_path):
    # truth: the unverified reader refuses the NaN; a verified pass (a later pass of a streaming
    # analysis) hands the same values over unchecked, and the chunk source verifies once
    data = np.arange(50_000, dtype=np.float64)
    data[31_234] = np.nan
    path = tmp_path / "n.npz"
    np.savez(path, time_s=data, rate_deg_s=data)
    with pytest.raises(CaptureError, match="not a finite number"):
        list(iter_capture_chunks(path, ["rate_deg_s"], chunk_rows=4_096))
    got = iter_capture_chunks(path, ["rate_deg_s"], chunk_rows=4_096, verified=True)
    np.testing.assert_array_equal(np.concatenate([c["rate_deg_s"] for c in got]), data)
    source = chunks_from_file(path, ("time_s", "rate_deg_s"), chunk_rows=4_096)
    for _ in range(2):  # no pass reads through, so none is trusted
        with pytest.raises(CaptureError, match="not a finite number"):
            list(source())


def test_reading_an_npz_capture_does_not_import_the_text_reader(tmp_path):
    """A binary capture's command pays no import of the CSV reader (~8 ms); the same process
    then reads a CSV file, which imports it: the module name checked is the one in use."""
    import subprocess
    import sys

    np.savez(tmp_path / "c.npz", time_s=np.arange(5.0), a=np.ones(5))
    (tmp_path / "c.csv").write_text("time_s,a\n0,1\n1,1\n")
    code = (
        "import sys\nfrom rotacal.io import read_capture\n"
        "read_capture(sys.argv[1]); print('rotacal.io._csv' in sys.modules)\n"
        "read_capture(sys.argv[2]); print('rotacal.io._csv' in sys.modules)\n"
    )
    out = subprocess.run(
        [sys.executable, "-c", code, str(tmp_path / "c.npz"), str(tmp_path / "c.csv")],
        capture_output=True,
        text=True,
        check=True,
    ).stdout.split()
    assert out == ["False", "True"]
