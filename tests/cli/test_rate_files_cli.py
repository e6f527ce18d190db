"""`rotacal gyro scale-factor` on one file per set rate: names, a table, the 0 °/s point at rest."""

from __future__ import annotations

import json

import numpy as np
import pytest

from rotacal.errors import ConfigError
from rotacal.gyro import calibrate_scale_factor
from rotacal.gyro.rate_sets import set_rate_from_name

from .test_gyro_cli import one_line_error, run

RATES = (10, 30, 60, 90, 120)


@pytest.mark.parametrize(
    ("name", "rate"),
    [
        ("p10.dat", 10.0),
        ("m10.dat", -10.0),
        ("M120.DAT", -120.0),
        ("+10.csv", 10.0),
        ("-10.5.txt", -10.5),
        ("10dps.dat", 10.0),
        ("neg_30_deg_s.csv.gz", -30.0),
        ("0.csv", 0.0),
    ],
)
def test_rate_from_name(name, rate):
    assert set_rate_from_name(name) == rate


@pytest.mark.parametrize(
    "name", ["p10_1turn.dat", "run3.csv", "p.dat", "10x.dat", "p10m.dat", "p-10.dat", "m-10.dat"]
)
def test_a_name_without_a_rate_is_refused(name):
    with pytest.raises(ConfigError, match=f"{name}: its name does not state a set rate"):
        set_rate_from_name(name)


def _plateau_files(tmp_path, sep="\t"):
    """A twin: known S and V0, one headerless file per set rate, the output in column 3."""
    rng = np.random.default_rng(4)
    s_true, v0_true = 0.0125, 0.31
    paths = []
    for r in RATES:
        for sign, pre in ((1, "p"), (-1, "m")):
            out = s_true * sign * r + v0_true + rng.normal(0, 1e-4, 200)
            rows = np.column_stack([np.arange(200) * 0.1, np.full(200, 7.0), out])
            path = tmp_path / f"{pre}{r}.dat"
            path.write_text("\n".join(sep.join(repr(float(v)) for v in row) for row in rows))
            paths.append(path)
    return paths, s_true, v0_true


def test_one_file_per_rate_equals_the_pooled_rows(tmp_path):
    paths, s_true, v0_true = _plateau_files(tmp_path)
    args = ["gyro", "scale-factor", *map(str, paths), "--column", "col_3=output"]
    r = run(*args, "--rate-from-name", "--json", "-")
    assert r.exit_code == 0, r.output
    d = json.loads(r.stdout)
    assert d["scale_factor"] == pytest.approx(s_true, rel=1e-4)
    assert d["bias"] == pytest.approx(v0_true, abs=1e-4)
    # the same analysis on the same rows given as arrays: nothing is lost between the files
    rate = np.concatenate([np.full(200, set_rate_from_name(p)) for p in paths])
    out = np.concatenate([np.loadtxt(p)[:, 2] for p in paths])
    direct = calibrate_scale_factor(rate, out)
    assert d["scale_factor"] == direct.scale_factor and d["bias"] == direct.bias
    assert [p["n"] for p in d["points"]] == [200] * 10
    # a table of set rates gives the same; its rows may come in any order
    table = tmp_path / "rates.csv"
    table.write_text(
        "file,rate_deg_s\n" + "".join(f"{p.name},{set_rate_from_name(p)}\n" for p in paths[::-1])
    )
    r2 = run(*args, "--rates", str(table), "--json", "-")
    assert r2.exit_code == 0, r2.output
    assert json.loads(r2.stdout)["scale_factor"] == d["scale_factor"]


def test_rate_file_faults_are_one_line(tmp_path):
    paths, _, _ = _plateau_files(tmp_path)
    turn = tmp_path / "p10_1turn.dat"
    turn.write_text(paths[0].read_text())
    base = ["gyro", "scale-factor", *map(str, paths), "--column", "col_3=output"]
    one_line_error(run(*base, str(turn), "--rate-from-name"), "p10_1turn.dat", "--rest-from")
    table = tmp_path / "rates.csv"
    table.write_text("file,rate\np10.dat,10\n")
    one_line_error(run(*base, "--rates", str(table)), "m10.dat is not in --rates")
    table.write_text("file,rate\np10.dat,ten\n")
    one_line_error(run(*base, "--rates", str(table)), "line 2", "'ten' is not a rate")
    one_line_error(run(*base, "--rest-from", str(turn)), "--rest-from", "--rate-from-name")
    one_line_error(run(*base), "p10.dat has no column 'rate_deg_s'", "--rate-from-name or --rates")
    one_line_error(run(*base[:3], "--rate-from-name", "--names", "a,b"), "--names gives 2 names")
    # a file given twice would count its samples twice
    one_line_error(run(*base, base[3], "--rate-from-name"), f"{base[3]} is given twice")


def _xinli_args(shared_data):
    files = shared_data("xinli_turntable") / "data"
    plateaus = [files / f"{pre}{r}.dat" for r in RATES for pre in ("p", "m")]
    rest = sorted(files.glob("*turn.dat"))
    return files, plateaus, rest


def test_xinli_plateau_files_give_the_published_points_and_fit(shared_data):
    files, plateaus, rest = _xinli_args(shared_data)
    ref = np.loadtxt(files.parent / "summary_rate_points.csv", delimiter=",", skiprows=1)
    args = ["gyro", "scale-factor", *map(str, plateaus), "--rate-from-name"]
    args += ["--column", "col_5=output", "--output-unit", "°/s", "--json", "-"]
    for f in rest:
        args += ["--rest-from", str(f)]
    r = run(*args)
    assert r.exit_code == 0, r.output
    d = json.loads(r.stdout)
    points = {p["rate_deg_s"]: p for p in d["points"]}
    assert sorted(points) == sorted(ref[:, 0])
    for rate, n, mean in ref[:, :3]:
        if rate == 0:
            continue
        assert points[rate]["n"] == n
        assert points[rate]["mean"] == pytest.approx(mean, rel=5e-7, abs=5e-8)  # 7 digits
    # the 0 °/s point: the rest is told by the output's indicated rate (bias taken off) within
    # ±0.5 °/s, 3 samples off the motion; the summary's rule (|output| < 0.5) kept 3 fewer ramp
    # samples. Either way its mean is the rest output to 1e-4 of its 0.019 °/s noise.
    assert points[0.0]["n"] == 4345 and ref[ref[:, 0] == 0][0, 1] == 4342
    assert points[0.0]["mean"] == pytest.approx(ref[ref[:, 0] == 0][0, 2], abs=2e-5)
    # the README's 11-point fit
    assert d["scale_factor"] == pytest.approx(1.000199, abs=5e-7)
    assert d["bias"] == pytest.approx(0.109, abs=5e-4)
    assert d["nonlinearity_percent_fs"] == pytest.approx(0.082, abs=5e-4)
    assert d["full_scale_deg_s"] == 120.0
