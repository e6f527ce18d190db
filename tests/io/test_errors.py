"""Every user fault gives ONE line naming the file and what is wrong, and a fix."""

from __future__ import annotations

import h5py
import numpy as np
import pytest
from nptdms import ChannelObject, GroupObject, RootObject, TdmsWriter

import rotacal.io._common as common
from rotacal.errors import CaptureError, ConfigError
from rotacal.io import (
    Capture,
    capture_length,
    check_time,
    iter_capture_chunks,
    parse_column_mapping,
    read_capture,
    write_capture,
)


def _msg(exc_info) -> str:
    text = str(exc_info.value)
    assert "\n" not in text, text
    return text


def _csv(tmp_path, text, name="cap.csv"):
    path = tmp_path / name
    path.write_text(text)
    return path


def _raises(match_all, fn, *args, err=CaptureError, **kw):
    with pytest.raises(err) as ei:
        fn(*args, **kw)
    text = _msg(ei)
    for part in match_all:
        assert part in text, (part, text)
    return text


# --- the file itself --------------------------------------------------------------------------


def test_missing_file(tmp_path):
    _raises(["nope.csv", "does not exist"], read_capture, tmp_path / "nope.csv")


def test_directory(tmp_path):
    (tmp_path / "d.h5").mkdir()
    _raises(["d.h5", "is a directory"], read_capture, tmp_path / "d.h5")


@pytest.mark.parametrize("ext", ["csv", "npz", "h5", "tdms"])
def test_empty_file(tmp_path, ext):
    (tmp_path / f"e.{ext}").write_bytes(b"")
    _raises([f"e.{ext}", "is empty"], read_capture, tmp_path / f"e.{ext}")


def test_unreadable_file(tmp_path, monkeypatch):
    path = _csv(tmp_path, "t\n1\n")

    def denied(*args, **kwargs):
        raise PermissionError(13, "Permission denied")

    monkeypatch.setattr(common, "open", denied, raising=False)
    _raises(["cap.csv", "cannot be read", "permission"], read_capture, path)


def test_unknown_extension(tmp_path):
    path = tmp_path / "run.xlsx"
    path.write_bytes(b"PK\x03\x04junk")
    text = _raises(["run.xlsx", "unknown capture extension"], read_capture, path)
    for ext in (".csv", ".npz", ".h5", ".hdf5", ".tdms"):
        assert ext in text


def test_npz_that_is_csv_text(tmp_path):
    path = _csv(tmp_path, "t,a\n1,2\n", name="run.npz")
    _raises(["run.npz is not an NPZ file (it looks like CSV text)", ".csv"], read_capture, path)


def test_csv_that_is_binary(tmp_path):
    path = tmp_path / "run.csv"
    np.savez(tmp_path / "x.npz", a=np.arange(3.0))
    path.write_bytes((tmp_path / "x.npz").read_bytes())
    _raises(["run.csv is not a CSV file", "ZIP"], read_capture, path)
    path.write_bytes(b"\x00\x01\x02garbage")
    _raises(["run.csv is not a CSV file", "binary"], read_capture, path)


def test_h5_that_is_tdms_and_tdms_that_is_h5(tmp_path):
    write_capture(tmp_path / "x.tdms", {"a": np.arange(3.0)})
    write_capture(tmp_path / "x.h5", {"a": np.arange(3.0)})
    (tmp_path / "y.h5").write_bytes((tmp_path / "x.tdms").read_bytes())
    (tmp_path / "y.tdms").write_bytes((tmp_path / "x.h5").read_bytes())
    _raises(
        ["y.h5 is not an HDF5 file (it looks like a TDMS file)"], read_capture, tmp_path / "y.h5"
    )
    _raises(["y.tdms is not a TDMS file", "HDF5"], read_capture, tmp_path / "y.tdms")


@pytest.mark.parametrize("ext", ["npz", "h5", "tdms"])
def test_truncated_binary_files(tmp_path, ext):
    good = write_capture(tmp_path / f"g.{ext}", {"a": np.arange(1000.0)})
    bad = tmp_path / f"bad.{ext}"
    bad.write_bytes(good.read_bytes()[:60])
    # a TDMS cut off while written (what LabVIEW leaves after a crash) is named as such
    fault = "ends inside segment 1" if ext == "tdms" else "is damaged or incomplete"
    _raises([f"bad.{ext}", fault], read_capture, bad)


def test_csv_not_utf8(tmp_path):
    path = tmp_path / "l1.csv"
    path.write_bytes("t,\u00e9\n1,2\n".encode("latin-1"))
    _raises(["l1.csv", "UTF-8"], read_capture, path)


# --- CSV content ------------------------------------------------------------------------------


def test_csv_no_header_reads_as_numbered_columns(tmp_path):
    path = _csv(tmp_path, "# only a comment\n1.0,2.0\n3.0,4.0\n")
    cap = read_capture(path)
    assert cap.names == ["col_1", "col_2"]
    assert cap["col_1"].tolist() == [1.0, 3.0] and cap["col_2"].tolist() == [2.0, 4.0]


def test_csv_only_comments(tmp_path):
    _raises(["cap.csv holds only comments or blank lines"], read_capture, _csv(tmp_path, "# x\n\n"))


def test_csv_header_only(tmp_path):
    path = _csv(tmp_path, "t,a\n\n")
    _raises(["cap.csv", "no data rows"], read_capture, path)
    _raises(["cap.csv", "no data rows"], lambda: list(iter_capture_chunks(path, ["a"])))


def test_csv_semicolons_are_sniffed(tmp_path):
    cap = read_capture(_csv(tmp_path, "t;a\n1;2\n"))
    assert cap.names == ["t", "a"] and cap["a"].tolist() == [2.0]


def test_csv_non_numeric_cell(tmp_path):
    path = _csv(tmp_path, "# x\ntime_s,a,b\n0,1,2\n1,oops,3\n2,1,2\n")
    _raises(["cap.csv line 4, column 'a'", "'oops' is not a number"], read_capture, path)
    # the chunked reader names the same line, also in a later chunk
    _raises(
        ["cap.csv line 4, column 'a'"], lambda: list(iter_capture_chunks(path, ["a"], chunk_rows=1))
    )


def test_csv_non_numeric_cell_in_unrequested_column_is_ignored(tmp_path):
    path = _csv(tmp_path, "time_s,a,note\n0,1,x\n1,2,y\n")
    assert read_capture(path, columns=["a"])["a"].tolist() == [1.0, 2.0]
    # a column of words is labels, not data: left out of "every column", named when asked for
    assert read_capture(path).names == ["time_s", "a"]
    _raises(
        ["cap.csv column 'note' holds text ('x' on line 2)"], read_capture, path, columns=["note"]
    )


def test_csv_wrong_cell_count(tmp_path):
    _raises(
        ["cap.csv line 2 has 2 cells", "header names 3 columns"],
        read_capture,
        _csv(tmp_path, "t,a,b\n1,2\n"),
    )
    _raises(
        ["cap.csv line 4 has 2 cells", "3 columns"],
        read_capture,
        _csv(tmp_path, "t,a,b\n1,2,3\n2,3,4\n3,4\n", name="cap.csv"),
    )


def test_csv_empty_cell_without_ragged(tmp_path):
    path = _csv(tmp_path, "head_0,head_1\n1,2\n3,\n")
    _raises(
        ["cap.csv line 3, column 'head_1' is empty", "rotacal selfcal", "trailing cells empty"],
        read_capture,
        path,
    )


def test_csv_bad_header_names(tmp_path):
    _raises(["cap.csv", "'a' more than once"], read_capture, _csv(tmp_path, "a,a\n1,2\n"))
    _raises(["cap.csv", "empty name in column 2"], read_capture, _csv(tmp_path, "a,,b\n1,2,3\n"))


@pytest.mark.parametrize("bad", ["nan", "inf", "-inf"])
def test_csv_non_finite_names_column_and_line(tmp_path, bad):
    path = _csv(tmp_path, f"# c\ntime_s,a\n0,1\n\n1,{bad}\n2,3\n")
    _raises(
        ["cap.csv column 'a'", "line 5 (data row 2)", "not a finite number"], read_capture, path
    )


# --- binary content ---------------------------------------------------------------------------


def test_nan_in_npz_names_row(tmp_path):
    a = np.arange(10.0)
    a[7] = np.nan
    np.savez(tmp_path / "n.npz", time_s=np.arange(10.0), a=a)
    _raises(["n.npz column 'a'", "row 7 (0-based)", "nan"], read_capture, tmp_path / "n.npz")
    _raises(
        ["n.npz column 'x' (file column 'a')", "row 7"],
        lambda: list(iter_capture_chunks(tmp_path / "n.npz", ["x"], chunk_rows=3, mapping=["a=x"])),
    )


def test_inner_nan_is_error_even_when_ragged(tmp_path):
    np.savez(tmp_path / "p.npz", head_0=np.array([0.0, np.nan, 2.0, np.nan]))
    _raises(
        ["p.npz column 'head_0'", "row 1", "trailing"],
        read_capture,
        tmp_path / "p.npz",
        ragged=True,
    )
    path = _csv(tmp_path, "head_0,head_1\n1,2\n3,\n4,5\n5,\n")
    _raises(["cap.csv column 'head_1'", "line 3", "trailing"], read_capture, path, ragged=True)


def test_different_lengths_without_ragged(tmp_path):
    np.savez(tmp_path / "l.npz", time_s=np.arange(5.0), a=np.arange(4.0))
    text = _raises(
        ["l.npz", "different lengths", "time_s: 5", "a: 4", "trim them", "rotacal rate"],
        read_capture,
        tmp_path / "l.npz",
    )
    assert text
    _raises(
        ["l.npz", "different lengths"],
        lambda: list(iter_capture_chunks(tmp_path / "l.npz", ["a", "time_s"])),
    )


def test_empty_and_all_padding_columns(tmp_path):
    np.savez(tmp_path / "z.npz", a=np.zeros(0), b=np.array([np.nan, np.nan]))
    _raises(["z.npz column 'a' is empty"], read_capture, tmp_path / "z.npz", columns=["a"])
    _raises(
        ["z.npz column 'b' is empty"], read_capture, tmp_path / "z.npz", columns=["b"], ragged=True
    )


def test_not_1d_or_not_numeric(tmp_path):
    np.savez(tmp_path / "s.npz", a=np.zeros((3, 2, 2)), s=np.array(["x", "y"]), ok=np.zeros(3))
    _raises(
        ["s.npz column 'a' has shape (3, 2, 2)", "1-D"],
        read_capture,
        tmp_path / "s.npz",
        columns=["a"],
    )
    _raises(
        ["s.npz column 's'", "not real numbers"], read_capture, tmp_path / "s.npz", columns=["s"]
    )
    with h5py.File(tmp_path / "s.h5", "w") as f:
        f["m"] = np.zeros((4, 4, 1))
        f["c"] = np.zeros(3, dtype=complex)
    _raises(
        ["s.h5 dataset 'm' has shape (4, 4, 1)"], read_capture, tmp_path / "s.h5", columns=["m"]
    )
    _raises(
        ["s.h5 dataset 'c'", "not real numbers"], read_capture, tmp_path / "s.h5", columns=["c"]
    )
    _raises(["s.h5", "not 1-D"], capture_length, tmp_path / "s.h5", "m")


def test_huge_integers_refused(tmp_path):
    np.savez(tmp_path / "i.npz", t=np.array([0, 2**60], dtype=np.int64))
    _raises(["i.npz column 't'", "2**53"], read_capture, tmp_path / "i.npz")


# --- columns, mapping, groups -----------------------------------------------------------------


def test_missing_columns_one_message(tmp_path):
    path = write_capture(
        tmp_path / "capture.csv", {"t": [0.0, 1.0], "ch1": [1.0, 2], "ch2": [3.0, 4]}
    )
    text = _raises(
        ["capture.csv has no column 'a', 'b' (it has: t, ch1, ch2)", "--column OLD=a"],
        read_capture,
        path,
        columns=["t", "a", "b"],
    )
    assert text.count("capture.csv") == 1


def test_capture_getitem_message(tmp_path):
    path = write_capture(
        tmp_path / "capture.csv", {"t": [0.0, 1.0], "ch1": [1.0, 2], "ch2": [3.0, 4]}
    )
    cap = read_capture(path)
    _raises(
        ["capture.csv has no column 'a' (it has: t, ch1, ch2); map one with --column OLD=a"],
        cap.__getitem__,
        "a",
    )
    part = read_capture(path, columns=["t"])
    _raises(
        ["capture.csv column 'ch1' is in the file but was not read (read: t)", "asking for 'ch1'"],
        part.__getitem__,
        "ch1",
    )
    _raises(["c.csv has no column 'x'"], Capture({"t": np.zeros(1)}, "c.csv").__getitem__, "x")


def test_mapping_source_missing_and_clash(tmp_path):
    path = write_capture(tmp_path / "m.npz", {"t": [0.0, 1.0], "a": [1.0, 2.0], "ch1": [1.0, 2.0]})
    _raises(
        ["m.npz has no column 'ch9' to map", "it has: t, a, ch1", "ch9=x"],
        read_capture,
        path,
        mapping={"ch9": "x"},
    )
    _raises(
        ["m.npz", "clashes", "'a'", "--column a=a_raw"], read_capture, path, mapping={"ch1": "a"}
    )
    cap = read_capture(path, mapping={"ch1": "a", "a": "a_raw"})
    assert cap.names == ["t", "a_raw", "a"]


@pytest.mark.parametrize(
    ("items", "part"),
    [
        (["ch1"], "must be OLD=NEW"),
        (["=a"], "must be OLD=NEW"),
        (["a=b=c"], "must be OLD=NEW"),
        (["a=x", "a=y"], "maps 'a' twice"),
        (["a=x", "b=x"], "onto 'x'"),
    ],
)
def test_parse_column_mapping_errors(items, part):
    _raises([part], parse_column_mapping, items, err=ConfigError)


def test_hdf5_group_errors(tmp_path):
    path = tmp_path / "g.h5"
    with h5py.File(path, "w") as f:
        f["raw/a"] = np.arange(3.0)
        f["raw/sub/b"] = np.arange(3.0)
    _raises(["g.h5 has no datasets at its root", "raw", "--group raw"], read_capture, path)
    _raises(
        ["g.h5 has no group 'cooked'", "raw, raw/sub", "--group"],
        read_capture,
        path,
        group="cooked",
    )
    _raises(["g.h5 has a dataset, not a group, at 'raw/a'"], read_capture, path, group="raw/a")
    assert read_capture(path, group="raw/sub")["b"].tolist() == [0, 1, 2]


def test_tdms_group_errors(tmp_path):
    path = tmp_path / "g.tdms"
    with TdmsWriter(str(path)) as w:
        w.write_segment(
            [
                RootObject(),
                GroupObject("enc"),
                GroupObject("fog"),
                ChannelObject("enc", "a", np.arange(3.0)),
                ChannelObject("fog", "rate", np.arange(3.0)),
            ]
        )
    _raises(["g.tdms has several groups (enc, fog)", "--group"], read_capture, path)
    _raises(["g.tdms has no group 'x' (it has: enc, fog)"], read_capture, path, group="x")
    assert read_capture(path, group="fog")["rate"].tolist() == [0, 1, 2]


def test_group_for_csv_is_config_error(tmp_path):
    path = write_capture(tmp_path / "c.csv", {"a": [1.0]})
    _raises(["c.csv", "--group", "HDF5 and TDMS"], read_capture, path, group="g", err=ConfigError)


def test_bad_chunk_rows(tmp_path):
    path = write_capture(tmp_path / "c.npz", {"a": [1.0]})
    _raises(
        ["chunk_rows"],
        lambda: next(iter_capture_chunks(path, ["a"], chunk_rows=0)),
        err=ConfigError,
    )


# --- writing ----------------------------------------------------------------------------------


@pytest.mark.parametrize("ext", ["csv", "npz", "h5", "tdms"])
def test_overwrite_refused_bytes_unchanged(tmp_path, ext):
    path = tmp_path / f"keep.{ext}"
    original = b"precious user data \x00\x01"
    path.write_bytes(original)
    _raises(
        [f"keep.{ext} already exists", "--overwrite"],
        write_capture,
        path,
        {"a": np.arange(3.0)},
        err=ConfigError,
    )
    assert path.read_bytes() == original
    assert sorted(p.name for p in tmp_path.iterdir()) == [f"keep.{ext}"]  # no temp file left
    write_capture(path, {"a": np.arange(3.0)}, overwrite=True)
    assert read_capture(path)["a"].tolist() == [0, 1, 2]


def test_write_errors(tmp_path):
    _raises(
        ["x.xlsx", "unknown capture extension"],
        write_capture,
        tmp_path / "x.xlsx",
        {"a": [1.0]},
        err=ConfigError,
    )
    _raises(
        ["does not exist"], write_capture, tmp_path / "no" / "x.csv", {"a": [1.0]}, err=ConfigError
    )
    _raises(["column 'a'", "1-D"], write_capture, tmp_path / "x.csv", {"a": np.zeros((2, 2))})
    _raises(["column 'a'", "real numbers"], write_capture, tmp_path / "x.npz", {"a": ["x"]})
    _raises(["'a,b'", "CSV"], write_capture, tmp_path / "x.csv", {"a,b": [1.0]}, err=ConfigError)
    _raises(["'a/b'", "HDF5"], write_capture, tmp_path / "x.h5", {"a/b": [1.0]}, err=ConfigError)
    _raises(
        ["--group", "x.npz"],
        write_capture,
        tmp_path / "x.npz",
        {"a": [1.0]},
        group="g",
        err=ConfigError,
    )
    assert list(tmp_path.iterdir()) == []  # failed writes leave nothing behind


# --- check_time -------------------------------------------------------------------------------


def test_check_time():
    check_time(np.array([0.0, 0.5, 2.0]))
    _raises(
        ["column 'time_s' is not strictly increasing at row 2 (0-based)", "0.5 s follows 0.5 s"],
        check_time,
        np.array([0.0, 0.5, 0.5, 1.0]),
    )
    _raises(
        ["run.csv column 't'", "row 3"],
        check_time,
        np.array([0.0, 1.0, 2.0, 1.5]),
        "t",
        source="d/run.csv",
    )
    _raises(["row 1 (0-based)", "finite"], check_time, np.array([0.0, np.inf, 2.0]))
    _raises(["1-D"], check_time, np.zeros((2, 2)))


def test_check_time_across_blocks(monkeypatch):
    monkeypatch.setattr(common, "BLOCK", 4)
    t = np.arange(20.0)
    check_time(t)
    t[8] = t[7]  # the repeat sits exactly on a block boundary
    _raises(["row 8 (0-based)"], check_time, t)


def test_csv_row_with_an_extra_cell_is_refused(tmp_path):
    """np.loadtxt(usecols=…) ignores extra cells; a shifted row must not be read silently."""
    from rotacal.errors import CaptureError
    from rotacal.io import iter_capture_chunks, read_capture

    p = tmp_path / "shifted.csv"
    p.write_text("time_s,rate_deg_s\n0,1\n1,2\n2,3,999\n3,4\n")
    with pytest.raises(CaptureError, match="line 4 has 3 cells"):
        read_capture(p, columns=["time_s"])
    with pytest.raises(CaptureError, match="line 4 has 3 cells"):
        list(iter_capture_chunks(p, ["time_s"], chunk_rows=2))
    ok = tmp_path / "ok.csv"
    ok.write_text("# a comment, with a comma\ntime_s,rate_deg_s\n0,1\n1,2\n\n")
    assert read_capture(ok)["rate_deg_s"].tolist() == [1.0, 2.0]
