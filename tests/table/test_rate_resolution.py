"""The readout's resolution in the rate's uncertainty (rate on angle/count readings, issue 20).

Truth: the same analysis of the twin's true mark crossings (Newton on its closed-form θ(t)), so
only the readout's quantisation separates the two. Sampling commensurate with the rotation
repeats the crossing errors every revolution (the Type A estimates see none of them);
incommensurate sampling shows them.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from rotacal.errors import ConfigError
from rotacal.sim.angle import constant_rate_angle_deg, simulate_angle
from rotacal.table.rate import calibrate_rate
from rotacal.table.rate_angle import (
    _pieces,
    calibrate_rate_from_marks,
    mark_times_from_chunks,
    readout_quantum,
)
from rotacal.table.rate_windows import rate_windows

N, M, A, FW = 36_000, 3600, 1e-3, 1.0  # counts/rev (q = 0.01°), marks/rev, fluctuation, Hz
Q = 360 / N
WINDOWS = ("1", "10", "360")
CASES = [  # rate (deg/s), fs (Hz), duration (s), reading; 3 revolutions each
    (360.0, 10_000, 3.0, "count"),  # 3.6 counts a sample: the errors repeat every revolution
    (361.7, 10_000, 3.0, "count"),
    (97.3, 10_000, 11.2, "count"),  # its quantisation repeats every 973 marks: no period refusal
    (131.1, 10_000, 8.3, "angle"),  # a rounding angle readout; q found from the readings
]
COMMENSURATE = {0}


def _true_crossings(w: float, n: int) -> np.ndarray:
    marks = (360.0 / M) * np.arange(1, n + 1)  # the first reading is θ = 0, a count boundary
    t = marks / w
    for _ in range(8):
        t -= (constant_rate_angle_deg(t, w, A, FW) - marks) / (
            w * (1 + A * np.cos(2 * np.pi * FW * t))
        )
    return t


@pytest.fixture(scope="module")
def runs():
    out = []
    for w, fs, dur, reading in CASES:
        kw = {"counts_per_rev": N} if reading == "count" else {"resolution_deg": Q}
        cap = simulate_angle(
            rate_deg_s=w, fluctuation=A, fluctuation_hz=FW, fs_hz=fs, duration_s=dur,
            reading=reading, **kw,
        )  # fmt: skip
        col = "count" if reading == "count" else "angle_deg"
        marks = mark_times_from_chunks(
            _pieces(cap.columns["time_s"], cap.columns[col]), pulses_per_rev=M,
            **({"counts_per_rev": N} if reading == "count" else {}),
        )  # fmt: skip
        r = calibrate_rate_from_marks(marks, pulses_per_rev=M, set_rate_deg_s=w)
        win = rate_windows(
            marks.times, pulses_per_rev=M, windows_deg=[1, 10, 360], set_rate_deg_s=w,
            timing_jitter_s=r.timing_jitter_s, readout_resolution_deg=marks.resolution_deg,
        )  # fmt: skip
        true_t = _true_crossings(w, marks.times.size)
        rt = calibrate_rate([true_t], pulses_per_rev=M, set_rate_deg_s=w, compensate=False)
        wt = rate_windows(true_t, pulses_per_rev=M, windows_deg=[1, 10, 360], set_rate_deg_s=w)
        out.append((marks.resolution_deg, r, win, rt, wt))
    return out


def _errors(run):
    """(name, measured − true, u) of every figure with a u."""
    _, r, win, rt, wt = run
    d = r.to_dict()
    rows = [
        ("mean_rate", r.mean_rate_deg_s - rt.mean_rate_deg_s, d["mean_rate_deg_s_u"]),
        ("bias_percent", r.rate_bias_percent - rt.rate_bias_percent, d["rate_bias_percent_u"]),
    ]
    for key in WINDOWS:
        for name in (
            "rate_accuracy_percent",
            "rate_stability_percent",
            "rate_stability_peak_percent",
        ):
            m, t = getattr(win, name)[key], getattr(wt, name)[key]
            rows.append((f"{name}[{key}]", m - t, getattr(win, name + "_u")[key]))
    return rows


def test_every_u_covers_the_error_and_is_not_absurdly_wide(runs):
    z_incommensurate = []
    for i, run in enumerate(runs):
        assert run[0] == pytest.approx(Q, rel=1e-9)
        for name, err, u in _errors(run):
            assert abs(err) <= 2 * u, (CASES[i], name, err, u)
            if i not in COMMENSURATE:
                z_incommensurate.append(err / u)
        _, r, _, rt, _ = run
        d = r.to_dict()
        for key in ("rate_deviation_rms_percent", "rate_deviation_peak_percent"):
            lo, hi = d[f"{key}_interval"]
            assert lo <= getattr(rt, key) <= hi, (CASES[i], key)
    # the errors the resolution makes show at incommensurate sampling, and u is their size
    z = np.asarray(z_incommensurate)
    assert 0.15 <= float(np.sqrt(np.mean(z**2))) <= 1.0 and np.max(np.abs(z)) > 0.5


def test_commensurate_sampling_keeps_the_resolution_in_u(runs):
    """The brief's case: exact-looking figures (errors repeat every revolution) with a u of
    1e-14 % were a wrong number; the budget now holds the readout's quantum."""
    _, r, win, _, _ = runs[0]
    assert r.timing_jitter_s < 1e-12 and abs(r.rate_bias_percent) < 1e-9  # Type A sees nothing
    span = 360.0 * r.revolutions
    d = r.to_dict()
    rel = Q / math.sqrt(3) / span  # rectangular ±q on the window's angle
    assert d["mean_rate_deg_s_u"] == pytest.approx(rel * r.mean_rate_deg_s, rel=1e-6)
    assert d["rate_bias_percent_u"] >= 100 * rel
    rows = {row.source: row for row in r.budgets["mean_rate_deg_s"].rows}
    assert rows["readout resolution at the window's two ends"].distribution.startswith("rect")
    assert win.rate_stability_percent_u["360"] >= 100 * Q / math.sqrt(3) / 360
    assert win.rate_accuracy_percent_u["360"] >= 100 * rel
    assert "readout resolution" in " ".join(r.notes)


def test_pulse_timestamps_have_no_resolution_and_a_bad_one_is_refused(runs):
    _, _, _, rt, _ = runs[1]
    names = [row.source for row in rt.budgets["mean_rate_deg_s"].rows]
    assert not any("resolution" in n for n in names)
    with pytest.raises(ConfigError, match="readout_resolution_deg must be ≥ 0"):
        calibrate_rate([np.arange(100) / 10], pulses_per_rev=10, readout_resolution_deg=-0.01)


@pytest.mark.parametrize(("rate", "q"), [(131.1, 0.001), (300.0, 0.0025), (131.1, 0.0)])
def test_the_quantum_of_a_readout_stepping_many_quanta_a_sample(rate, q):
    """13.1 and 12 quanta a sample: the smallest step is a multiple of q (angle_quantum of
    motion angle finds none here); a continuous readout has none."""
    cap = simulate_angle(
        rate_deg_s=rate, fluctuation=A, reading="angle", resolution_deg=q, fs_hz=10_000,
        duration_s=0.5,
    )  # fmt: skip
    found = readout_quantum(cap.columns["angle_deg"])
    assert found is None if q == 0 else found == pytest.approx(q, rel=1e-9)


def test_the_cli_windows_carry_the_resolution(tmp_path):
    from tests.cli.test_gyro_cli import run, simulated

    path, _ = simulated(
        tmp_path, "angle", "--rate-deg-s", "360", "--duration-s", "3", "--fs-hz", "10000",
        "--counts-per-rev", str(N), "--counter-bits", "16",
    )  # fmt: skip
    r = run(
        "rate", str(path), "--pulses-per-rev", str(M), "--counts-per-rev", str(N),
        "--window-deg", "1,360", "--set-rate-deg-s", "360", "--json", "-",
    )  # fmt: skip
    assert r.exit_code == 0, r.output
    d = json.loads(r.stdout)
    assert d["rate_accuracy_percent_u"]["360"] >= 100 * Q / math.sqrt(3) / (360 * 3)
    assert d["rate_stability_percent_u"]["360"] >= 100 * Q / math.sqrt(3) / 360
    budget = json.dumps(d["uncertainty_budgets"]["mean_rate_deg_s"])
    assert "readout resolution at the window's two ends" in budget
