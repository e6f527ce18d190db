"""``rotacal inspect`` on the real recordings of ../shared/data: every file answers, and the
counts and resolutions agree with what their publishers and reference programs state."""

from __future__ import annotations

import json

import pytest
from click.testing import CliRunner

from rotacal.cli import cli
from rotacal.inspect import inspect_capture


def look(path, *options: str) -> dict:
    result = CliRunner().invoke(cli, ["inspect", str(path), *options, "--json", "-"])
    assert result.exit_code == 0, f"{path}: {result.output}"
    return json.loads(result.stdout)


def test_every_file_answers_without_error(shared_data):
    root = shared_data()
    files = sorted(p for p in root.rglob("*") if p.is_file())
    assert len(files) >= 250
    failed, kinds = [], {}
    for path in files:
        result = CliRunner().invoke(cli, ["inspect", str(path), "--json", "-"])
        if result.exit_code != 0:
            failed.append(f"{path.relative_to(root)}: {result.output.strip()}")
            continue
        found = json.loads(result.stdout)
        kinds[found["kind"]] = kinds.get(found["kind"], 0) + 1
        if found["kind"] != "capture":
            assert found["fits"] == [] and found["columns"] == {}, path
    assert failed == [], f"{len(failed)} files fail, e.g. " + "; ".join(failed[:5])
    # the data, the reference outputs of allantools and imu_utils, the turn tables, the IMUs
    assert kinds["capture"] >= 240
    assert {"json", "markdown", "yaml", "text"} <= set(kinds)


def test_imucal_session_resolution_is_the_gyro_lsb(shared_data):
    path = shared_data("imucal", "example_data", "example_ferraris_session.csv")
    found = inspect_capture(path)
    assert found.rows == 10376
    # a 16-bit gyro at ±2000 °/s: one count is 2000/32768 °/s
    for axis in "xyz":
        assert found.columns[f"gyr_{axis}"].smallest_step == 2000 / 32768
    assert found.columns["n_samples"].increasing
    assert found.time_column is None and found.fits == ()


def test_annotated_session_names_its_label_column(shared_data):
    path = shared_data("imucal", "example_data", "annotated_session.csv")
    found = inspect_capture(path)
    assert list(found.unreadable_columns) == ["part"]
    assert found.rows == 9414
    assert found.columns["gyr_x"].smallest_step == 1.0  # raw counts


def test_xinli_turn_table_files_hold_the_published_sample_counts(shared_data):
    root = shared_data("xinli_turntable")
    summary = (root / "summary_rate_points.csv").read_text().splitlines()[1:]
    counts = {int(float(row.split(",")[0])): int(row.split(",")[1]) for row in summary}
    for rate in (10, 30, 60, 90, 120):
        for sign, prefix in ((1, "p"), (-1, "m")):
            found = look(root / "data" / f"{prefix}{rate}.dat")
            assert found["rows"] == counts[sign * rate]
            counter = found["columns"]["col_2"]  # the sample counter, +10 per sample
            assert counter["smallest_step"] == 10 and counter["increasing"]


def test_adis16405_quantum_is_the_published_one(shared_data):
    found = look(shared_data("imudata_smac", "npz", "adis_16405_imu1.npz"))
    assert found["rows"] == 1_000_000
    gyro = [found["columns"][f"data[:,{k}]"] for k in range(3)]
    for column in gyro:
        assert column["smallest_step"] == pytest.approx(0.05, rel=1e-6)  # °/s, README


def test_xsens_ascii_mat_is_sampled_at_100_hz(shared_data):
    path = shared_data("imu_tk", "bin", "test_data", "xsens_gyro.mat")
    plain = look(path)
    assert "col_1=time_s" in plain["suggested_columns"]
    timed = look(path, "--column", "col_1=time_s")
    assert timed["sample_rate_hz"] == pytest.approx(100.0, rel=2e-3)


@pytest.mark.parametrize(
    ("parts", "points"),
    [
        # the point counts Stable32 printed in the reference files beside each data set
        (("allantools", "tests", "phasedat", "PHASE.DAT"), 1001),
        (("allantools", "tests", "ocxo", "ocxo_frequency.txt"), 19982),
        (("allantools", "tests", "Cs5071A", "5071A_phase.txt.gz"), 556990),
    ],
)
def test_allantools_data_hold_the_points_stable32_counted(shared_data, parts, points):
    found = look(shared_data(*parts))
    assert found["rows"] == points and list(found["columns"]) == ["col_1"]
