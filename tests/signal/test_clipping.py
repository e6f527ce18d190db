"""The detector of samples at the rails (rotacal.signal.clipping) against closed forms."""

from __future__ import annotations

import math

import numpy as np
import pytest

from rotacal.errors import CaptureError
from rotacal.signal import (
    ClippedSignalError,
    RailDetector,
    check_clipping,
    find_clipping,
    find_quadrature_clipping,
    quadrature_rail_detectors,
)
from rotacal.signal.clipping import RAIL_RATIO


def _sine(n: int = 200_000, periods: float = 20.0, phase: float = 0.3) -> np.ndarray:
    return np.sin(2 * np.pi * periods * np.arange(n) / n + phase)


def _quantise(x: np.ndarray, bits: int, full_scale: float = 1.25) -> np.ndarray:
    q = 2 * full_scale / 2**bits
    return (np.floor(x / q) + 0.5) * q


@pytest.mark.parametrize("level", [0.7, 0.95])
def test_a_clipped_sine_is_found_with_its_share(level):
    x = np.clip(_sine(), -level, level)
    clip = find_clipping(x, "x")
    assert clip is not None and clip.column == "x"
    # closed form: a sine spends arccos(c)/π of its time beyond +c, as much beyond −c
    per_rail = math.acos(level) / math.pi
    assert {r.side for r in clip.rails} == {"maximum", "minimum"}
    for r in clip.rails:
        assert r.value == pytest.approx(level if r.side == "maximum" else -level)
        assert r.samples / x.size == pytest.approx(per_rail, abs=2e-3)
        assert x[r.first_row] == r.value and np.all(x[: r.first_row] != r.value)
    assert clip.share == pytest.approx(2 * per_rail, abs=4e-3)


@pytest.mark.parametrize("bits", [8, 10, 12, 16])
@pytest.mark.parametrize("phase", [0.0, 0.4, 1.3])
def test_a_quantised_sine_is_not_clipped_and_obeys_the_bound(bits, phase):
    """The top level of a quantised smooth peak holds at most 1/(√2 − 1) times the next one."""
    for amplitude in (0.8, 0.9137, 1.0, 1.2):
        x = _quantise(amplitude * _sine(phase=phase), bits)
        assert find_clipping(x, "x") is None
        det = RailDetector("x")
        det.add(x)
        for ratio_next, _, _ in det._ratios().values():
            assert ratio_next <= 1 / (math.sqrt(2) - 1) + 0.2  # counting: ± a sample or two


def test_a_flat_quartic_peak_obeys_its_bound():
    """x = 1 − t⁴ (a table reversing where an encoder channel peaks): at most 1/(2^¼ − 1)."""
    t = np.linspace(-1, 1, 2_000_001)
    bound = 1 / (2**0.25 - 1)
    worst = 0.0
    for offset in (0.2, 0.5, 0.8, 0.99):  # where the peak lies in its level
        q = 1e-3
        x = np.floor((1 - t**4) / q + offset) * q
        det = RailDetector("x")
        det.add(np.concatenate([x, -x]))  # both extremes, the other one a mirror
        worst = max(worst, *(r[0] for r in det._ratios().values()))
    assert 0.95 * bound < worst <= bound * 1.01
    assert bound < RAIL_RATIO


def test_the_same_finding_in_any_chunking():
    rng = np.random.default_rng(5)
    x = np.clip(np.round(_sine(300_000) * 400 + rng.normal(0, 2, 300_000)) / 400, -0.9, 0.93)
    x[1234] = np.nan
    whole = find_clipping(x, "x")
    assert whole is not None and len(whole.rails) == 2
    ref = RailDetector("x")
    ref.add(x)
    hinted = RailDetector("x", rows=x.size)  # the subsample at its final stride from the start
    hinted.add(x)
    assert hinted._stride == ref._stride == 2 and hinted._ratios() == ref._ratios()
    for _ in range(4):
        det = RailDetector("x")
        pos = 0
        while pos < x.size:
            k = int(rng.integers(1, 90_000))
            det.add(x[pos : pos + k])
            pos += k
        assert det.result() == whole
        assert det._ratios() == ref._ratios()


def test_nan_and_inf_are_skipped_and_rows_keep_their_numbers():
    x = np.clip(_sine(), -0.8, 0.8)
    clean = find_clipping(x, "x")
    y = x.copy()
    y[:10] = np.nan
    y[50_000] = np.inf
    dirty = find_clipping(y, "x")
    assert clean is not None and dirty is not None
    assert [r.first_row for r in dirty.rails] == [r.first_row for r in clean.rails]


def test_constant_and_two_level_columns_are_not_judged():
    assert find_clipping(np.full(1000, 3.0), "c") is None
    assert find_clipping(np.repeat([0.0, 1.0], 500), "d") is None
    assert find_clipping(np.empty(0), "e") is None


def test_noise_and_unquantised_tails_are_not_clipped():
    rng = np.random.default_rng(6)
    assert find_clipping(rng.standard_normal(100_000), "n") is None
    assert find_clipping(np.round(rng.standard_normal(100_000) * 3), "counts") is None


def test_a_quadrature_channel_at_rest_where_it_peaks_is_not_clipped():
    """The table stops (stagnates) where a = cos φ peaks: b stands still, no rail."""
    n = 100_000
    # the table holds at each reversal, φ = ±40π, where a = cos φ peaks
    phi = 40 * np.pi * np.clip(1.02 * np.sin(2 * np.pi * 3 * np.arange(n) / n), -1, 1)
    a, b = _quantise(np.cos(phi), 12), _quantise(np.sin(phi), 12)
    assert find_clipping(a, "a") is not None  # the column alone cannot tell…
    assert find_clipping(a, "a", companion=b) is None  # …its companion can
    clipped = np.clip(_quantise(1.3 * np.cos(phi), 16), -1.0, 1.0)  # …and a real rail stays
    assert find_clipping(clipped, "a", companion=b) is not None


def test_a_quadrature_pair_gives_the_findings_of_two_calls():
    """Both channels fed in turn, piece by piece (more rows than one piece), as two calls."""
    n = 300_000
    phi = 30 * np.pi * np.sin(2 * np.pi * 4 * np.arange(n) / n)
    for gain in (1.0, 1.3):  # not clipped, then a clipped at ±1 while b sweeps
        a = np.clip(_quantise(gain * np.cos(phi), 12), -1.0, 1.0)
        b = _quantise(np.sin(phi), 12)
        b[77_777] = np.nan
        want = (find_clipping(a, "a", companion=b), find_clipping(b, "b", companion=a))
        assert find_quadrature_clipping(a, b) == want
        assert (want[0] is not None) == (gain > 1.0) and want[1] is None


def _detector_state(det: RailDetector) -> tuple:
    """Everything a detector's verdicts and messages read (a run of one sample counts as 1)."""
    det._close_open_run()

    def side(s):
        return (s.value, s.count, s.first, s.next_value, s.next_count, s.comp_lo, s.comp_hi,
                max(s.run, 1))  # fmt: skip

    return (side(det._hi), side(det._lo), max(det._elsewhere_run, 1), det._comp_lo,
            det._comp_hi, det._finite, det._mode_elsewhere())  # fmt: skip


def test_the_compiled_pass_leaves_the_numpy_detectors_state():
    """The Numba pass over a pair against the NumPy detectors fed piece by piece: the same
    extremes, counts, first rows, companion spans, runs and subsample, so the same findings —
    on a clipped quantised pair with runs, an unquantised one and a table at rest where a peaks
    (more rows than one piece and one block); a NaN leaves the pair to the NumPy detectors."""
    from rotacal.signal import clipping

    n = 70_000
    rng = np.random.default_rng(7)
    phi = 30 * np.pi * np.clip(1.02 * np.sin(2 * np.pi * 4 * np.arange(n) / n), -1, 1)
    pairs = [
        (np.clip(_quantise(1.3 * np.cos(phi), 12), -1.0, 0.9), _quantise(np.sin(phi), 12)),
        (np.cos(phi) + rng.normal(0, 1e-3, n), np.sin(phi) + rng.normal(0, 1e-3, n)),
        (_quantise(np.cos(phi), 12), np.round(np.sin(phi) * 3)),  # long runs at every level
    ]
    for a, b in pairs:
        numpy_dets = (RailDetector("a", n), RailDetector("b", n))
        for det, x, c in ((numpy_dets[0], a, b), (numpy_dets[1], b, a)):
            det.add(x, c)
        jit_dets = (RailDetector("a", n), RailDetector("b", n))
        assert clipping._compiled_pass(a, b, *jit_dets)
        assert [_detector_state(d) for d in jit_dets] == [_detector_state(d) for d in numpy_dets]
        assert find_quadrature_clipping(a, b, jit=True) == find_quadrature_clipping(a, b, jit=False)
    assert find_quadrature_clipping(pairs[0][0], pairs[0][1], jit=True)[0] is not None
    a, b = pairs[0]
    a = a.copy()
    a[66_666] = np.nan
    assert not clipping._compiled_pass(a, b, RailDetector("a", n), RailDetector("b", n))
    assert find_quadrature_clipping(a, b, jit=True) == find_quadrature_clipping(a, b, jit=False)


def test_the_level_at_rest_is_not_a_rail():
    """A coarse output that rests at its minimum between one-way rotations."""
    t = np.arange(3000) / 100.0
    rate = np.where((t % 10) > 6, 180 * np.sin(np.pi * ((t % 10) - 6) / 4) ** 2, 0.0)
    out = np.round(rate + 0.4)  # quantum 1 °/s, rest at 0
    rest = rate == 0
    assert find_clipping(out, "uy") is not None  # the column alone cannot tell…
    assert find_clipping(out, "uy", rest=rest) is None  # …the static rows can
    assert find_clipping(np.minimum(out, 150.0), "uy", rest=rest) is not None


def test_points_explain_plateaus_and_show_a_rail_cut_through_one():
    rng = np.random.default_rng(7)
    levels = np.array([-2.0, -1.0, 0.0, 1.0, 2.0])
    sizes = np.array([40, 40, 40, 40, 400])  # the top point recorded ten times longer
    groups = np.repeat(np.arange(5), sizes)
    flat = levels[groups]  # noise-free: every point flat
    assert find_clipping(flat, "u") is not None  # the column alone cannot tell…
    assert find_clipping(flat, "u", groups=groups) is None  # …the points can
    # a rail at the top point's mean, noise σ, quantum σ/2: half its samples pile on the rail
    noisy = np.round((flat + 0.05 * rng.standard_normal(groups.size)) / 0.025) * 0.025
    cut = np.minimum(noisy, 2.0)
    assert find_clipping(noisy, "u", groups=groups) is None
    clip = find_clipping(cut, "u", groups=groups)
    assert clip is not None and clip.rails[0].value == 2.0
    assert clip.rails[0].samples == pytest.approx(200, abs=40)


def test_check_clipping_refuses_with_one_line_or_warns():
    x = np.clip(2 * _sine(), -1.0, 1.0)
    with pytest.raises(ClippedSignalError) as exc:
        check_clipping({"rate_deg_s": x, "other": _sine()})
    msg = str(exc.value)
    assert isinstance(exc.value, CaptureError)
    assert "\n" not in msg and msg.endswith(".")
    share = 100 * math.acos(0.5) / math.pi * 2
    for needle in ("'rate_deg_s'", f"{share:.1f} %", "maximum 1 ", "minimum -1 ", "from row"):
        assert needle in msg
    assert "--allow-clipped" in msg
    lines = check_clipping({"rate_deg_s": x, "other": _sine()}, allow_clipped=True)
    assert len(lines) == 1 and "'rate_deg_s'" in lines[0] and "analysed anyway" in lines[0]
    assert check_clipping({"other": _sine()}) == ()


def test_companion_of_another_length_is_refused():
    with pytest.raises(CaptureError, match="differ in length"):
        find_clipping(np.zeros(10), "a", companion=np.zeros(9))


def test_in_working_range_is_check_magnitudes_verdict():
    """A detector that saw the whole column tells whether check_magnitudes would pass it: the
    same verdict on ordinary, non-finite, huge, tiny and all-zero columns (both paths)."""
    from rotacal.signal._values import check_magnitudes

    base = _sine(5_000)
    columns = {"ordinary": base, "zeros": np.zeros(5_000), "tiny": 1e-120 * base}
    for name, value in (("nan", np.nan), ("inf", np.inf), ("huge", 1e120)):
        columns[name] = base.copy()
        columns[name][1234] = value
    for name, x in columns.items():
        try:
            check_magnitudes(name, x)
            passes = True
        except CaptureError:
            passes = False
        for jit in (False, True):
            det_x, _ = quadrature_rail_detectors(x, base, jit=jit)
            assert det_x.in_working_range() == passes, (name, jit)
