"""inspect_capture on files: captures of every format, files that are not captures, damage."""

from __future__ import annotations

import json

import numpy as np
import pytest

from rotacal.errors import CaptureError
from rotacal.inspect import inspect_capture
from rotacal.io import write_capture


@pytest.mark.parametrize("ext", [".csv", ".npz", ".h5", ".tdms"])
def test_every_capture_format_gives_the_same_answer(tmp_path, ext):
    t = np.arange(4_000) / 200.0
    t = np.delete(t, np.arange(1_000, 1_100))  # a gap of 100 samples
    a = np.cos(t)
    a[7] = np.nan
    path = write_capture(tmp_path / f"enc{ext}", {"time_s": t, "a": a, "b": np.sin(t)})
    r = inspect_capture(path)
    assert r.kind == "capture" and r.format in ext.upper().replace(".H5", "HDF5")
    assert r.rows == t.size and list(r.columns) == ["time_s", "a", "b"]
    assert r.columns["a"].nan == 1 and r.columns["a"].first_nonfinite_row == 7
    assert r.sample_rate_hz == pytest.approx(200.0, rel=1e-9)
    assert [(g.start_s, g.end_s, g.missing_samples) for g in r.gaps] == [(t[999], t[1000], 100)]
    assert r.fits == ("motion encoder",)


def test_a_long_capture_streams_in_chunks_with_the_same_answer(tmp_path, monkeypatch):
    import rotacal.inspect.files as files

    t = np.arange(50_000) * 1e-3
    x = np.round(np.sin(t) * 100) / 8
    path = write_capture(tmp_path / "long.csv", {"time_s": t, "rate_deg_s": x})
    whole = inspect_capture(path)
    monkeypatch.setattr(files, "CHUNK_ROWS", 999)
    chunked = inspect_capture(path)
    assert chunked.columns == whole.columns
    assert chunked.sample_rate_hz == pytest.approx(1000.0, rel=1e-9)


def test_the_column_mapping_applies(tmp_path):
    path = write_capture(tmp_path / "raw.csv", {"t": np.arange(10.0), "ch1": np.ones(10)})
    r = inspect_capture(path, mapping=["t=time_s", "ch1=rate_deg_s"])
    assert list(r.columns) == ["time_s", "rate_deg_s"]
    assert r.fits == ("allan", "motion fog")
    assert r.sample_rate_hz == 1.0


def test_columns_of_different_lengths(tmp_path):
    heads = {f"head_{k}": np.cumsum(np.full(100 + k, 0.01)) for k in range(3)}
    for ext in (".csv", ".npz"):
        r = inspect_capture(write_capture(tmp_path / f"p{ext}", heads))
        assert [c.samples for c in r.columns.values()] == [100, 101, 102]
        assert all(c.nan == 0 and c.increasing for c in r.columns.values())
        assert r.fits == ("rate", "selfcal")


def test_empty_cells_in_the_middle_count_as_nan(tmp_path):
    path = tmp_path / "holes.csv"
    path.write_text("time_s,x\n0,1\n1,\n2,3\n3,4\n")
    c = inspect_capture(path).columns["x"]
    assert (c.samples, c.nan, c.first_nonfinite_row) == (4, 1, 1)


def test_a_label_column_is_left_out_and_named(tmp_path):
    path = tmp_path / "labelled.csv"
    path.write_text("part,time_s,x\nstatic,0,1\nstatic,1,2\nturn,2,3\n")
    r = inspect_capture(path)
    assert list(r.columns) == ["time_s", "x"]
    assert list(r.unreadable_columns) == ["part"]
    assert "'static'" in r.unreadable_columns["part"] and "line 2" in r.unreadable_columns["part"]
    assert any(w.startswith("column 'part' was left out") for w in r.warnings)


def test_a_file_of_text_cells_only_is_refused(tmp_path):
    path = tmp_path / "words.csv"
    path.write_text("a,b\n1,x\n2,y\n3,z\n4,w\n")
    r = inspect_capture(path)  # column a reads
    assert list(r.columns) == ["a"] and list(r.unreadable_columns) == ["b"]
    only_text = tmp_path / "text.csv"
    only_text.write_text("name\n1\nx\n3\n")
    with pytest.raises(CaptureError, match=r"line 3, column 'name': 'x'"):
        inspect_capture(only_text)


@pytest.mark.parametrize(
    ("name", "content", "kind"),
    [
        ("cal.json", json.dumps({"K_g": [[1, 0, 0]], "b_g": [0.1, 0.2]}), "json"),
        ("README.md", "# Data\n\nSome 1 2 3 numbers in prose.\n", "markdown"),
        ("imu.yaml", "gyr_n: 2.1e-03\ngyr_w: 1.5e-05\nacc_n: 0.02\n", "yaml"),
        ("LICENSE", "MIT License\n\nCopyright (c) 2020 Someone\n\nPermission is granted\n", "text"),
        ("LICENSE.txt", "Copyright 2014, A. Person.\nAll rights reserved.\n", "text"),
        ("notes.csv", "This file was exported by hand.\nAsk Jane for the data.\n", "text"),
        ("gyro.xyz", "0.01 32786 32429\n0.02 32797 32410\n", "text-table"),
        ("blob.bin", "\x00\x01\x02binary", "binary"),
        ("empty.csv", "", "empty"),
    ],
)
def test_a_file_that_is_no_capture_gets_a_short_answer(tmp_path, name, content, kind):
    path = tmp_path / name
    path.write_text(content)
    r = inspect_capture(path)
    assert r.kind == kind
    assert r.fits == () and r.columns == {} and r.rows == 0
    assert r.description.startswith(f"{name} is ")


def test_a_damaged_capture_is_refused_with_one_line(tmp_path):
    path = write_capture(tmp_path / "cap.npz", {"time_s": np.arange(1000.0), "x": np.ones(1000)})
    raw = bytearray(path.read_bytes())
    raw[600:640] = b"\xff" * 40  # inside the first member's data
    path.write_bytes(bytes(raw))
    with pytest.raises(CaptureError, match="damaged") as err:
        inspect_capture(path)
    assert "\n" not in str(err.value)


def test_a_missing_file_is_refused(tmp_path):
    with pytest.raises(CaptureError, match="does not exist"):
        inspect_capture(tmp_path / "nope.csv")
