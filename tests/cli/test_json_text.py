"""The fast JSON writer gives exactly the text of ``json.dumps(data, indent=2, allow_nan=False)``."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from rotacal.cli._json_text import dumps_indented
from rotacal.results import to_jsonable


def sample() -> dict:
    rng = np.random.default_rng(3)
    curve = (rng.standard_normal(3000) * 10.0 ** rng.integers(-300, 300, 3000)).tolist()
    return {
        "tau_s": curve,
        "short": [1.5, -0.0, 2.0],
        "ints": list(range(400)),
        "mixed": [1.0] * 300 + [None, 2],
        "nested": {"deeper": [[0.1] * 500, {"x": [3e-310] * 260}], "empty": [], "s": "a\u00e9"},
        "rows": [[1e300, -1e-300] * 200, []],
        "value": 1.0,
    }


def test_text_equals_the_standard_library():
    data = sample()
    assert dumps_indented(data) == json.dumps(data, indent=2, allow_nan=False)


def test_non_finite_numbers_are_refused_as_json_does():
    data = {"curve": [1.0] * 300 + [math.nan]}
    with pytest.raises(ValueError):
        json.dumps(data, indent=2, allow_nan=False)
    with pytest.raises(ValueError):
        dumps_indented(data)


def test_to_jsonable_of_a_float_curve_is_unchanged_and_nan_becomes_null():
    curve = [0.5, math.inf, -2.0, math.nan]
    assert to_jsonable(curve) == [0.5, None, -2.0, None]
    assert to_jsonable(np.array([0.25, 1e-320])) == [0.25, 1e-320]
    assert to_jsonable((1.0, 2.0)) == [1.0, 2.0]
