"""Gyro outputs at their rails: every gyro analysis refuses them with the share the twin clipped,
analyses them only with allow_clipped (saying so in ``warnings``), and says nothing on unclipped
twins with coarse quanta and on the real recordings."""

from __future__ import annotations

import glob
import json
import re

import numpy as np
import pytest

from rotacal.errors import CaptureError
from rotacal.gyro import (
    calibrate_multiposition,
    calibrate_scale_factor,
    calibrate_triad_columns,
    calibrate_triad_rotations,
    ferraris_sections,
)
from rotacal.gyro.noise import gyro_noise
from rotacal.signal import find_clipping
from rotacal.sim import (
    simulate_gyro_noise,
    simulate_gyro_rates,
    simulate_gyro_rotations,
    simulate_gyro_triad,
    simulate_multiposition,
)


def _share(message: str) -> float:
    m = re.search(r"clipped \(a saturated sensor or ADC\): ([0-9.]+) %", message)
    assert m is not None, message
    return float(m.group(1)) / 100


def _rates(cap, **kw):
    # 20 000 Monte Carlo trials, not the default 200 000: these tests read the clipping findings
    # and the warnings, which do not depend on the trials (a tenth of the time)
    kw.setdefault("mc_trials", 20_000)
    return calibrate_scale_factor(cap.columns["rate_deg_s"], cap.columns["output"], **kw)


def _triad(cap, **kw):
    return calibrate_triad_columns(cap.columns, **kw)


def _rotations(cap, **kw):
    u = np.column_stack([cap.columns[c] for c in ("ux", "uy", "uz")])
    t = cap.truth
    return calibrate_triad_rotations(u, 100.0, t["rotations"], static=t["static"], **kw)


def _multiposition(cap, **kw):
    c = cap.columns
    return calibrate_multiposition(
        c["phi1_deg"], c["phi2_deg"], c["output_deg_h"], axis="x", latitude_deg=45.75, **kw
    )


def _noise(cap, **kw):
    return gyro_noise(cap.columns["rate_deg_s"], time_s=cap.columns["time_s"], **kw)


CLIPPED = [
    # (twin, analysis, column whose rail the message names, clipped samples in the truth)
    (lambda: simulate_gyro_rates(saturation=(1.3, 3.7), seed=1), _rates, "output"),
    (lambda: simulate_gyro_triad(output_limit=91.0, seed=1), _triad, "ux"),
    (lambda: simulate_gyro_triad(output_limit=91.0, quantum=0.05, seed=1), _triad, "ux"),
    (lambda: simulate_gyro_rotations(output_limit=150.0, seed=1), _rotations, "ux"),
    (lambda: simulate_multiposition(output_limit_deg_h=120.0, seed=1), _multiposition, None),
    (lambda: simulate_gyro_noise(duration_s=600.0, range_deg_s=0.125, seed=1), _noise, None),
]


def _clipped_samples(cap) -> int:
    t = cap.truth
    return int(t.get("clipped_samples", t.get("sensor", {}).get("clipped_samples", 0)))


@pytest.mark.parametrize(("make", "run", "column"), CLIPPED)
def test_a_gyro_output_at_its_rails_is_refused_then_allowed(make, run, column):
    cap = make()
    beyond = _clipped_samples(cap)
    assert beyond > 0
    with pytest.raises(CaptureError) as exc:
        run(cap)
    msg = str(exc.value)
    assert "\n" not in msg and "--allow-clipped" in msg
    if column is not None:
        assert msg.startswith(f"column '{column}' is clipped")
    # the samples at the rails are those the twin clipped (for a quantised output, the rail's
    # code also holds the honest samples within half a quantum of it)
    found = sum(rail.samples for c in exc.value.clippings for rail in c.rails)
    assert beyond <= found <= 1.5 * beyond + 1
    r = run(cap, allow_clipped=True)
    # outputs held at the rails also leave the model (rotacal.gyro.plausibility): lack of fit;
    # 600 s of noise is too short to resolve the bias instability, and says so
    clipping = [w for w in r.warnings if not w.startswith(("lack of fit:", "no bias instability"))]
    assert [w.split("; analysed anyway")[0] for w in clipping] == [
        c.describe() for c in exc.value.clippings
    ]
    assert _share(msg) > 0


HONEST = [
    (lambda s: simulate_gyro_rates(seed=s), _rates),
    (lambda s: simulate_gyro_rates(quantum=1e-2, seed=s), _rates),  # coarse: flat points
    (lambda s: simulate_gyro_rates(quantum=1e-3, noise_std=0.0, seed=s), _rates),
    (lambda s: simulate_gyro_triad(quantum=0.5, seed=s), _triad),
    (lambda s: simulate_gyro_rotations(quantum=1.0, seed=s), _rotations),  # rests at its min
    (lambda s: simulate_multiposition(noise_deg_h=0.0, seed=s), _multiposition),
    (lambda s: simulate_gyro_noise(duration_s=600.0, quantum_deg_s=0.2, seed=s), _noise),
]


@pytest.mark.parametrize(("make", "run"), HONEST)
@pytest.mark.parametrize("seed", range(3))
def test_unclipped_gyro_twins_say_nothing(make, run, seed):
    warnings = run(make(seed)).warnings
    if run is _noise:  # 600 s is too short to show the bias instability, and says so
        warnings = tuple(w for w in warnings if not w.startswith("no bias instability"))
    assert warnings == ()


# ----------------------------------------------------------------------------- real recordings
def test_the_real_rate_table_and_rotation_recordings_are_not_clipped(shared_data):
    files = shared_data("xinli_turntable") / "data"
    rates, outs = [], []
    for f in sorted(glob.glob(str(files / "[pm]*[0-9].dat"))):
        z = np.loadtxt(f)[:, 4]
        sign = 1.0 if "/p" in f else -1.0
        rates.append(np.full(z.size, sign * float(re.findall(r"(\d+)\.dat$", f)[0])))
        outs.append(z)
    r = calibrate_scale_factor(np.concatenate(rates), np.concatenate(outs))
    assert r.warnings == ()
    imucal = shared_data("imucal") / "example_data"
    data = np.loadtxt(imucal / "example_ferraris_session.csv", delimiter=",", skiprows=1)
    sections = json.loads((imucal / "example_ferraris_session_list.json").read_text())
    rotations, static = ferraris_sections(sections)
    r = calibrate_triad_rotations(data[:, 1:4], 102.4, rotations, static=static, angle_deg=-360)
    assert r.warnings == ()


def test_no_real_gyro_or_frequency_record_has_a_rail(shared_data):
    """Every rate column of the real recordings, as the Allan analysis judges it."""
    columns: list[tuple[str, np.ndarray]] = []
    for f in sorted((shared_data("xinli_turntable") / "data").glob("*.dat")):
        arr = np.loadtxt(f)
        columns += [(f"{f.name}:{c}", arr[:, c]) for c in (2, 3, 4)]
    for f in sorted((shared_data("imudata_smac") / "npz").glob("*.npz")):
        d = np.load(f)["data"]
        columns += [(f"{f.name}:{c}", d[:, c]) for c in range(min(3, d.shape[1]))]
    xsens = np.loadtxt(shared_data("imu_tk", "bin", "test_data") / "xsens_gyro.mat")
    columns += [(f"xsens:{c}", xsens[:, c]) for c in (1, 2, 3)]
    for f in ("ocxo/ocxo_frequency.txt", "pink_frequency/pink_frequency.txt", "gradev/y.dat"):
        columns.append((f, np.loadtxt(shared_data("allantools", "tests") / f, comments="#")))
    assert len(columns) > 140
    called = [name for name, x in columns if find_clipping(x, name) is not None]
    assert called == []
