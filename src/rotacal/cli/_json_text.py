"""JSON text of a result, as ``json.dumps(data, indent=2, allow_nan=False)`` writes it, fast.

With ``indent`` set, the standard library encodes in pure Python (its C encoder serves only the
compact form): about a microsecond per number, a minute for the four 5·10⁶-point curves of
``rotacal allan --taus all``. Long lists of plain floats are taken out before encoding and written
back in the same layout (one number per line, ``float.__repr__``, as ``json`` writes them), so
the text is byte for byte what ``json.dumps`` gives.
"""

from __future__ import annotations

import json
import math
import re
import secrets
from typing import Any

#: Lists of floats at least this long are written outside the encoder.
_LONG = 256


def dumps_indented(data: Any) -> str:
    """``json.dumps(data, indent=2, allow_nan=False)``, with long float lists written directly."""
    token = f"rotacal-list-{secrets.token_hex(8)}-"
    lists: list[list[float]] = []

    def swap(value: Any) -> Any:
        if type(value) is dict:
            return {k: swap(v) for k, v in value.items()}
        if type(value) is list:
            if (
                len(value) >= _LONG
                and set(map(type, value)) == {float}
                and all(map(math.isfinite, value))
            ):
                lists.append(value)
                return f"{token}{len(lists) - 1}"
            return [swap(v) for v in value]
        return value

    text = json.dumps(swap(data), indent=2, allow_nan=False)
    if not lists:
        return text

    def write_back(match: re.Match[str]) -> str:
        start = match.string.rfind("\n", 0, match.start()) + 1
        line = match.string[start : match.start()]
        outer = " " * (len(line) - len(line.lstrip(" ")))
        inner = ",\n" + outer + "  "
        values = lists[int(match.group(1))]
        return "[\n" + outer + "  " + inner.join(map(float.__repr__, values)) + "\n" + outer + "]"

    return re.sub('"' + re.escape(token) + r'(\d+)"', write_back, text)
