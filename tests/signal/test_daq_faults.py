"""DAQ faults from time_s: gaps, duplicated times, repeated rows; chunked = whole; real data."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from rotacal.errors import CaptureError
from rotacal.signal.daq_faults import DaqFaultFinder, find_daq_faults


def _record():
    t = np.arange(5_000) * 0.001
    v = np.sin(t * 7.0)
    keep = np.ones(t.size, dtype=bool)
    keep[[100, 2_000, 2_001, 2_002]] = False  # 1 + 3 samples lost
    t, v = t[keep], v[keep]
    # row 3000 written twice; row 4000's time stamped twice with another value
    t = np.insert(t, [3_000, 4_000], [t[2_999], t[3_999]])
    v = np.insert(v, [3_000, 4_000], [v[2_999], 9.0])
    return t, v


def test_faults_are_found_where_they_are():
    t, v = _record()
    f, keep = find_daq_faults(t, v)
    assert f.gaps == (100, 1_999) and f.gap_count == 2 and f.missing == 4
    assert f.repeated == (3_000,) and f.duplicated == (4_001,)
    assert keep.sum() == t.size - 2 and not keep[3_000] and not keep[4_001]
    lines = f.warnings()
    assert "2 gap(s), about 4 sample(s) missing, before sample(s) 100, 1999" in lines[0]
    assert "at sample(s) 4001" in lines[1] and "at sample(s) 3000" in lines[2]
    assert f.fraction == pytest.approx(6 / t.size)
    f.check(allow=False)  # 0.12 %: accepted


def test_chunked_equals_whole():
    t, v = _record()
    whole, keep = find_daq_faults(t, v)
    finder = DaqFaultFinder()
    cuts = [0, 1_500, 1_501, 3_000, 3_001, 4_001, t.size]
    masks = [finder.feed(t[a:b], v[a:b]) for a, b in itertools.pairwise(cuts)]
    assert finder.result() == whole
    np.testing.assert_array_equal(np.concatenate(masks), keep)


def test_refusals():
    t = np.arange(1_000) * 0.01
    v = t.copy()
    with pytest.raises(CaptureError, match="back in time at sample 500"):
        find_daq_faults(np.concatenate((t[:500], t[499:998] - 1)), v[:999])
    many = np.delete(t, np.arange(10, 900, 40))  # 23 samples lost of ~1000: 2.3 %
    f, _ = find_daq_faults(many, many)
    with pytest.raises(CaptureError, match=r"more than 1%.*--allow-gaps"):
        f.check(allow=False)
    f.check(allow=True)


def test_real_logger_counter_has_no_faults_until_rows_are_removed(shared_data):
    """xinli's sample counter (+10 per 0.1 s sample) as the time base: a clean record, then the
    same record with rows removed and one written twice, found at their rows."""
    path = shared_data("xinli_turntable", "data", "m30.dat")
    d = np.loadtxt(path, usecols=(1, 4))
    t, w = d[:, 0] / 100.0, d[:, 1]
    f, keep = find_daq_faults(t, w)
    assert f.gap_count == f.duplicated_count == f.repeated_count == 0 and keep.all()
    t2, w2 = np.delete(t, [50, 51, 400]), np.delete(w, [50, 51, 400])
    t2, w2 = np.insert(t2, 300, t2[299]), np.insert(w2, 300, w2[299])
    f, _ = find_daq_faults(t2, w2)
    assert f.gaps == (50, 399) and f.missing == 3 and f.repeated == (300,)
