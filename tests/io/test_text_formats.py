"""Text captures as labs' DAQs write them: sniffed separators, decimal comma, no header, gzip.

Every synthetic file is written from known numbers (``repr``, which reads back bit for bit) and
must read back exactly, whole, in chunks and by length; every fault is one line naming the file,
the line and the column, or the option at fault.
"""

from __future__ import annotations

import gzip
import re
from pathlib import Path

import numpy as np
import pytest

from rotacal.errors import CaptureError, ConfigError
from rotacal.io import ReadOptions, capture_length, iter_capture_chunks, read_capture
from rotacal.io.read_options import delimiter_from_word

ROWS = 53  # more than one chunk of 7 rows, and more rows than the sniffer looks at
_RNG = np.random.default_rng(13)
VALUES = {
    "time_s": np.arange(ROWS) * 0.01,
    "a": _RNG.normal(size=ROWS) * 1e3,
    "b": -np.abs(_RNG.normal(size=ROWS)) * 1e-6,
}


def _text(delimiter: str, decimal: str = ".", header: bool = True, lead: str = "") -> str:
    """The VALUES as a text capture with this separator and decimal mark."""
    cells = [[repr(float(x)) for x in VALUES[name]] for name in VALUES]
    if decimal == ",":
        cells = [[c.replace(".", ",") for c in col] for col in cells]
    sep = "   " if delimiter == " " else delimiter
    rows = [lead + sep.join(row) for row in zip(*cells, strict=True)]
    head = [sep.join(VALUES)] if header else []
    return "# recorded by a DAQ\n" + "\n".join(head + rows) + "\n"


def _write(path: Path, text: str) -> Path:
    if path.suffix == ".gz":
        with gzip.open(path, "wt", encoding="utf-8") as fh:
            fh.write(text)
    else:
        path.write_text(text, encoding="utf-8", newline="")
    return path


def _check_reads_back(path: Path, options: ReadOptions | None = None, names=tuple(VALUES)):
    cap = read_capture(path, read_options=options)
    assert cap.names == list(names)
    for name, own in zip(names, VALUES, strict=True):
        assert cap[name].tobytes() == VALUES[own].tobytes(), name
    chunks = list(iter_capture_chunks(path, list(names), chunk_rows=7, read_options=options))
    assert len(chunks) == -(-ROWS // 7)
    for name, own in zip(names, VALUES, strict=True):
        joined = np.concatenate([c[name] for c in chunks])
        assert joined.tobytes() == VALUES[own].tobytes(), name
    assert capture_length(path, names[1], read_options=options) == ROWS


@pytest.mark.parametrize("delimiter", [",", ";", "\t", " "])
@pytest.mark.parametrize("suffix", [".csv", ".txt", ".dat", ".tsv", ".txt.gz"])
def test_separator_is_sniffed(tmp_path, delimiter, suffix):
    _check_reads_back(_write(tmp_path / f"cap{suffix}", _text(delimiter)))


@pytest.mark.parametrize("delimiter", [";", "\t", " "])
def test_decimal_comma_is_recognised_and_can_be_given(tmp_path, delimiter):
    path = _write(tmp_path / "cap.csv", _text(delimiter, decimal=","))
    _check_reads_back(path)
    _check_reads_back(path, ReadOptions(decimal=","))
    _check_reads_back(path, ReadOptions(delimiter=delimiter, decimal=","))


def test_given_separator_wins(tmp_path):
    path = _write(tmp_path / "cap.dat", _text("\t"))
    _check_reads_back(path, ReadOptions(delimiter="\t"))
    with pytest.raises(
        ConfigError, match=re.escape("--delimiter ';' does not separate the cells of cap.dat")
    ):
        read_capture(path, read_options=ReadOptions(delimiter=";"), columns=["time_s"])


@pytest.mark.parametrize("delimiter", [",", "\t", " "])
def test_headerless_file_numbered_or_named(tmp_path, delimiter):
    path = _write(
        tmp_path / "cap.txt", _text(delimiter, header=False, lead=" " * (delimiter == " "))
    )
    _check_reads_back(path, names=("col_1", "col_2", "col_3"))
    _check_reads_back(path, ReadOptions(names=("t", "x", "y")), names=("t", "x", "y"))
    cap = read_capture(path, mapping=["col_2=output"], columns=["output"])
    assert cap["output"].tobytes() == VALUES["a"].tobytes()


def test_crlf_and_leading_blanks_one_column(tmp_path):
    x = VALUES["b"]
    path = tmp_path / "phase.DAT"
    path.write_bytes("".join(f"  {float(v)!r}\r\n" for v in x).encode())
    cap = read_capture(path)
    assert cap.names == ["col_1"] and cap["col_1"].tobytes() == x.tobytes()


def test_headerless_decimal_comma_pairs_are_refused_until_told(tmp_path):
    """ "0,2945" is one number with a decimal comma or two whole numbers: never guessed."""
    x = np.round(_RNG.normal(size=ROWS), 4)
    path = tmp_path / "rate.txt"
    path.write_text("\n".join(f"{v:.4f}".replace(".", ",") for v in x) + "\n")
    with pytest.raises(ConfigError, match=r"rate\.txt: rows like .* give --decimal , \(one col"):
        read_capture(path)
    one = read_capture(path, read_options=ReadOptions(decimal=","))
    np.testing.assert_array_equal(one["col_1"], x)
    two = read_capture(path, read_options=ReadOptions(delimiter=","))
    np.testing.assert_array_equal(two["col_1"], np.trunc(x) + 0.0 * x)  # the whole parts
    # a header, or a row that is not a pair of whole numbers, settles it: read as before
    path.write_text("n,m\n1,2\n3,4\n")
    assert read_capture(path).file_columns == ["n", "m"]


def test_an_indented_comment_line_is_named(tmp_path):
    path = tmp_path / "ic.csv"
    path.write_text("time_s,x\n0,1\n  # a note\n0.01,2\n")
    with pytest.raises(CaptureError, match=r"ic\.csv line 3 is a comment that does not start"):
        read_capture(path)


def test_option_faults_are_one_line_config_errors(tmp_path):
    path = _write(tmp_path / "cap.dat", _text("\t", header=False))
    with pytest.raises(
        ConfigError, match=re.escape("--names gives 2 names but cap.dat has 3 columns")
    ):
        read_capture(path, read_options=ReadOptions(names=("a", "b")))
    head = _write(tmp_path / "head.csv", _text(","))
    with pytest.raises(ConfigError, match=re.escape("head.csv starts with one")):
        read_capture(head, read_options=ReadOptions(names=("a", "b", "c")))
    with pytest.raises(ConfigError, match=re.escape("--decimal , cannot go with --delimiter ,")):
        ReadOptions(delimiter=",", decimal=",")
    with pytest.raises(ConfigError, match=re.escape("more than once")):
        ReadOptions(names=("a", "a"))
    with pytest.raises(ConfigError, match=re.escape("--delimiter '|'")):
        delimiter_from_word("|")
    assert [delimiter_from_word(w) for w in ("tab", "\\t", "space", "whitespace", ";")] == [
        "\t",
        "\t",
        " ",
        " ",
        ";",
    ]
    np.savez(tmp_path / "c.npz", a=np.zeros(3))
    with pytest.raises(ConfigError, match=re.escape("apply to text captures, not to c.npz")):
        read_capture(tmp_path / "c.npz", read_options=ReadOptions(delimiter=";"))


@pytest.mark.parametrize("delimiter", ["\t", ";", " "])
def test_bad_cells_are_named_by_line_and_column(tmp_path, delimiter):
    sep = "   " if delimiter == " " else delimiter
    text = f"t{sep}x\n0{sep}1\n1{sep}oops\n2{sep}3\n"
    path = _write(tmp_path / "bad.dat", text)
    with pytest.raises(
        CaptureError, match=re.escape("bad.dat line 3, column 'x': 'oops' is not a number")
    ):
        read_capture(path)
    with pytest.raises(CaptureError, match=re.escape("bad.dat line 3, column 'x'")):
        list(iter_capture_chunks(path, ["x"], chunk_rows=1))
    extra = _write(tmp_path / "extra.dat", f"t{sep}x\n0{sep}1\n1{sep}2{sep}9\n")
    with pytest.raises(
        CaptureError, match=re.escape("extra.dat line 3 has 3 cells but the header names 2")
    ):
        read_capture(extra, columns=["x"])


def test_a_decimal_comma_among_points_gets_a_hint(tmp_path):
    path = _write(tmp_path / "mixed.csv", "t;x\n0;1.5\n1;2.5\n2;3,5\n")
    with pytest.raises(CaptureError, match=r"line 4, column 'x'.*decimal comma: give --decimal ,"):
        read_capture(path)


def test_gzip_and_mat_files(tmp_path):
    fake = tmp_path / "x.csv.gz"
    fake.write_text("t,a\n1,2\n")
    with pytest.raises(CaptureError, match=re.escape("x.csv.gz is not gzip-compressed")):
        read_capture(fake)
    with pytest.raises(CaptureError, match=re.escape("gzip-compressed text captures")):
        read_capture(_write(tmp_path / "y.npz.gz", "1\n"))
    cut = tmp_path / "cut.csv.gz"
    cut.write_bytes(gzip.compress(_text(",").encode())[:-30])
    with pytest.raises(CaptureError, match=re.escape("cut.csv.gz")):
        read_capture(cut)
    matlab = tmp_path / "m.mat"
    matlab.write_bytes(b"MATLAB 5.0 MAT-file, Platform: GLNXA64" + bytes(200))
    with pytest.raises(CaptureError, match=r"m\.mat is a binary MATLAB MAT-file.*CSV"):
        read_capture(matlab)
    _check_reads_back(_write(tmp_path / "ascii.mat", _text(" ")))
    with pytest.raises(CaptureError, match=r"unknown capture extension '.xlsx'.*\.dat"):
        read_capture(_write(tmp_path / "a.xlsx", "t\n1\n"))


# --- the real recordings each feature was made for ----------------------------------------------


def test_xinli_tab_separated_headerless_dat(shared_data):
    data = shared_data("xinli_turntable")
    cap = read_capture(data / "data" / "p10.dat", columns=["col_5"])
    # the published mean output at +10 °/s (summary_rate_points.csv, 7 significant digits)
    summary = np.loadtxt(data / "summary_rate_points.csv", delimiter=",", skiprows=1)
    row = summary[summary[:, 0] == 10.0][0]
    assert cap["col_5"].size == int(row[1])
    assert np.mean(cap["col_5"]) == pytest.approx(row[2], rel=5e-7)
    named = read_capture(
        data / "data" / "p10.dat",
        read_options=ReadOptions(names=tuple(f"c{k}" for k in range(12))),
        mapping=["c4=output"],
        columns=["output"],
    )
    assert named["output"].tobytes() == cap["col_5"].tobytes()


def test_imu_tk_ascii_mat(shared_data):
    path = shared_data("imu_tk", "bin", "test_data") / "xsens_gyro.mat"
    cap = read_capture(path, read_options=ReadOptions(names=("timestamp_s", "x", "y", "z")))
    # the README: 100 Hz, 512 s, raw 16-bit counts about an offset of 32768
    assert np.median(np.diff(cap["timestamp_s"])) == pytest.approx(0.01, rel=1e-3)
    assert cap["timestamp_s"][-1] - cap["timestamp_s"][0] == pytest.approx(512, rel=0.01)
    assert 0 <= cap["x"].min() and cap["x"].max() < 65536
    assert abs(np.median(cap["x"]) - 32768) < 1000


@pytest.mark.parametrize(
    ("path", "points"),
    [
        # Stable32's own count of the points it read ("Phase Data Points 1 thru N of N")
        (("Cs5071A", "5071A_phase.txt.gz"), 556990),
        (("gps", "gps_1pps_phase_data.txt.gz"), 241218),
        (("phasedat", "PHASE.DAT"), 1001),
    ],
)
def test_allantools_one_column_text_and_gzip(shared_data, path, points):
    file = shared_data("allantools", "tests", *path)
    assert capture_length(file, "col_1") == points
    cap = read_capture(file)
    assert cap.names == ["col_1"] and cap["col_1"].size == points
    chunked = np.concatenate([c["col_1"] for c in iter_capture_chunks(file, ["col_1"])])
    assert chunked.tobytes() == cap["col_1"].tobytes()


def test_a_column_of_labels_is_left_out_and_named_when_asked_for(tmp_path):
    path = _write(tmp_path / "lab.csv", "part,t,x\nx_a,0,1.5\nx_a,1,2.5\ny_p,2,3.5\n")
    cap = read_capture(path)
    assert cap.names == ["t", "x"] and cap["x"].tolist() == [1.5, 2.5, 3.5]
    with pytest.raises(
        CaptureError, match=re.escape("lab.csv column 'part' holds text ('x_a' on line 2)")
    ):
        read_capture(path, columns=["part"])
    assert capture_length(path, "x") == 3


def test_imucal_annotated_session_with_its_section_labels(shared_data):
    path = shared_data("imucal", "example_data") / "annotated_session.csv"
    cap = read_capture(path)
    assert "part" not in cap.names
    assert cap.names == ["samples", "acc_x", "acc_y", "acc_z", "gyr_x", "gyr_y", "gyr_z"]
    # raw counts (the data README): whole numbers, as imucal's own reader gives them
    assert np.all(cap["gyr_x"] == np.round(cap["gyr_x"]))
    assert cap["samples"][:2].tolist() == [1028.0, 1029.0]  # the file's first two rows
