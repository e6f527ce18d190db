"""Requirements a gyro's scale-factor test is judged against, and the verdicts (Kokuyama et al. 2015, Table 1).

:data:`REQUIREMENTS` names the known ones (FMVSS 126: range ±100 °/s, resolution < 0.004 °/s,
accuracy < 0.05 %FS); :func:`resolve_requirement` checks a named or a user's own,
:func:`evaluate_requirement` gives pass/fail with margins, and :func:`decide_with_u` judges the
accuracy with the uncertainty of the nonlinearity (ILAC-G8:09/2019 §4.2, JCGM 106:2012 §8).

References
----------
Kokuyama W., Watanabe T., Nozato H., Ota A., "Development of angular velocity calibration facility
using self-calibratable rotary encoder", Table 1. NHTSA, FMVSS 126 Laboratory Test Procedure for
Electronic Stability Control Systems (2008). ILAC-G8:09/2019 §4.2; JCGM 106:2012 §8.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from typing import Any

from rotacal.errors import ConfigError
from rotacal.results import Result

__all__ = [
    "REQUIREMENTS",
    "DecisionWithU",
    "RequirementCheck",
    "RequirementVerdict",
    "decide_with_u",
    "evaluate_requirement",
    "resolve_requirement",
]

#: Named requirements, FMVSS 126 first. Limits: ``range_deg_s`` (the tested rates must reach ±it),
#: ``resolution_deg_s`` (must be below), ``accuracy_percent_fs`` (the nonlinearity must be below).
REQUIREMENTS: dict[str, dict[str, Any]] = {
    "fmvss126": {
        "title": "FMVSS 126",
        "source": "Kokuyama et al. (2015), Table 1 (NHTSA FMVSS 126 laboratory test procedure, 2008)",
        "range_deg_s": 100.0,
        "resolution_deg_s": 0.004,
        "accuracy_percent_fs": 0.05,
    },
}
_LIMIT_KEYS = ("range_deg_s", "resolution_deg_s", "accuracy_percent_fs")
_TEXT_KEYS = ("name", "title", "source")


@dataclasses.dataclass(frozen=True)
class RequirementCheck(Result):
    """One line of a requirement: the limit, the measured value, pass/fail and the margin.

    ``margin`` is in ``unit`` and positive when the requirement is met (limit − value for an upper
    limit; tested reach − range for the range). ``passed`` is None when the value could not be
    assessed from the capture.
    """

    quantity: str
    limit: float
    value: float | None
    unit: str
    passed: bool | None
    margin: float | None
    basis: str
    line: str


@dataclasses.dataclass(frozen=True)
class RequirementVerdict(Result):
    """A named requirement applied to a scale-factor result (``passed``: every check passed)."""

    name: str
    title: str
    source: str
    passed: bool | None
    checks: tuple[RequirementCheck, ...]
    note: str

    def lines(self) -> list[str]:
        """One pass/fail line per check, headed by the requirement's title."""
        head = {True: "PASS", False: "FAIL", None: "NOT ASSESSED"}[self.passed]
        return [f"{self.title}: {head}"] + [f"  {c.line}" for c in self.checks]


@dataclasses.dataclass(frozen=True)
class DecisionWithU(Result):
    """A requirement's accuracy check judged with the uncertainty of NL (ILAC-G8).

    With the 95 % interval [low, high] for the true NL (``interval``): ``verdict`` is
    ``"pass with U"`` when high < limit, ``"fail with U"`` when low > limit and ``"inconclusive"``
    when the limit lies within it. Without one, the interval is NL ± U (guard band w = U,
    ILAC-G8:09/2019 §4.2). ``value`` is the plain NL (the value the verdict without U uses), ``U``
    its expanded uncertainty (half the interval's width), all in ``unit``.
    """

    quantity: str
    limit: float
    value: float
    U: float
    unit: str
    verdict: str
    agrees: bool
    rule: str
    line: str
    interval: tuple[float, float] | None = None


def _positive(name: str, value: Any, what: str) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ConfigError(f"{name} must be a number ({what}), got {value!r}.") from None
    if not math.isfinite(v) or v <= 0:
        raise ConfigError(f"{name} must be a finite number > 0 ({what}), got {value!r}.")
    return v


def resolve_requirement(requirement: str | Mapping[str, Any]) -> dict[str, Any]:
    """The limits of a named requirement, or a user's own, checked.

    Parameters
    ----------
    requirement : str or mapping
        A name from :data:`REQUIREMENTS` (case, spaces, ``-`` and ``_`` ignored: ``"FMVSS 126"``)
        or a mapping with any of ``range_deg_s`` (°/s), ``resolution_deg_s`` (°/s),
        ``accuracy_percent_fs`` (%FS) and optionally ``name``, ``title``, ``source``.

    Returns
    -------
    dict
        ``name``, ``title``, ``source`` and the limits given.
    """
    if isinstance(requirement, str):
        key = "".join(ch for ch in requirement.lower() if ch not in " -_")
        if key not in REQUIREMENTS:
            raise ConfigError(
                f"unknown requirement {requirement!r}; known: {', '.join(REQUIREMENTS)} (or pass a "
                "dict of range_deg_s, resolution_deg_s, accuracy_percent_fs)."
            )
        return {"name": key, **REQUIREMENTS[key]}
    if not isinstance(requirement, Mapping):
        raise ConfigError(
            f"requirement must be a name ({', '.join(REQUIREMENTS)}) or a dict of limits, got "
            f"{requirement!r}."
        )
    bad = [k for k in requirement if k not in _LIMIT_KEYS + _TEXT_KEYS]
    if bad:
        raise ConfigError(
            f"unknown requirement key {bad[0]!r}; use {', '.join(_LIMIT_KEYS + _TEXT_KEYS)}."
        )
    out: dict[str, Any] = {
        "name": str(requirement.get("name", "custom")),
        "title": str(requirement.get("title", requirement.get("name", "custom requirement"))),
        "source": str(requirement.get("source", "user")),
    }
    for k in _LIMIT_KEYS:
        if k in requirement:
            out[k] = _positive(f"requirement {k}", requirement[k], "a limit")
    if not any(k in out for k in _LIMIT_KEYS):
        raise ConfigError(
            f"the requirement gives no limit: add at least one of {', '.join(_LIMIT_KEYS)}."
        )
    return out


def evaluate_requirement(
    requirement: str | Mapping[str, Any],
    *,
    rate_min_deg_s: float,
    rate_max_deg_s: float,
    nonlinearity_percent_fs: float,
    full_scale_deg_s: float,
    resolution_deg_s: float | None,
    resolution_basis: str = "",
) -> RequirementVerdict:
    """Pass/fail, with margins, of measured gyro figures against a requirement.

    Parameters
    ----------
    requirement : str or mapping
        See :func:`resolve_requirement`.
    rate_min_deg_s, rate_max_deg_s : float
        The lowest and highest set rates tested (°/s); the range passes when they reach −R and +R.
    nonlinearity_percent_fs : float
        NL (%FS) of the fit; the accuracy passes when it is below the limit.
    full_scale_deg_s : float
        FS (°/s) NL refers to (stated on the line).
    resolution_deg_s : float or None
        Estimated resolution (°/s); None leaves the resolution not assessed.
    resolution_basis : str
        How the resolution was estimated (stated on the line).

    Returns
    -------
    RequirementVerdict

    References
    ----------
    Seed 004, Table 1 (FMVSS 126: range ±100 °/s, resolution < 0.004 °/s, accuracy < 0.05 %FS).
    """
    req = resolve_requirement(requirement)
    checks: list[RequirementCheck] = []
    if "range_deg_s" in req:
        lim = req["range_deg_s"]
        reach = min(rate_max_deg_s, -rate_min_deg_s)
        ok = bool(reach >= lim)
        margin = reach - lim
        line = (
            f"{'PASS' if ok else 'FAIL'} range: tested {rate_min_deg_s:+.6g} … "
            f"{rate_max_deg_s:+.6g} °/s {'covers' if ok else 'does not cover'} ±{lim:g} °/s "
            f"(margin {margin:+.4g} °/s)"
        )
        checks.append(
            RequirementCheck(
                "range", lim, reach, "deg/s", ok, margin, "smallest |extreme set rate|", line
            )
        )
    if "resolution_deg_s" in req:
        lim = req["resolution_deg_s"]
        if resolution_deg_s is None or not math.isfinite(resolution_deg_s):
            line = (
                f"NOT ASSESSED resolution: neither an output quantum nor the noise of a point is "
                f"visible in the capture (limit < {lim:g} °/s)"
            )
            checks.append(
                RequirementCheck("resolution", lim, None, "deg/s", None, None, "none", line)
            )
        else:
            ok = bool(resolution_deg_s < lim)
            margin = lim - resolution_deg_s
            line = (
                f"{'PASS' if ok else 'FAIL'} resolution: {resolution_deg_s:.3g} °/s "
                f"{'<' if ok else '≥'} {lim:g} °/s (margin {margin:+.3g} °/s; {resolution_basis})"
            )
            checks.append(
                RequirementCheck(
                    "resolution", lim, resolution_deg_s, "deg/s", ok, margin, resolution_basis, line
                )
            )
    if "accuracy_percent_fs" in req:
        lim = req["accuracy_percent_fs"]
        ok = bool(nonlinearity_percent_fs < lim)
        margin = lim - nonlinearity_percent_fs
        line = (
            f"{'PASS' if ok else 'FAIL'} accuracy: nonlinearity {nonlinearity_percent_fs:.4g} %FS "
            f"{'<' if ok else '≥'} {lim:g} %FS (margin {margin:+.3g} %FS; FS = "
            f"{full_scale_deg_s:g} °/s)"
        )
        checks.append(
            RequirementCheck(
                "accuracy",
                lim,
                nonlinearity_percent_fs,
                "percent_fs",
                ok,
                margin,
                "nonlinearity of the least-squares line",
                line,
            )
        )
    states = [c.passed for c in checks]
    passed: bool | None = (
        False if any(s is False for s in states) else (None if None in states else True)
    )
    note = (
        "Accuracy is judged by the nonlinearity alone. A full accuracy statement would also count "
        "the uncertainty of the scale factor (including the table's rate traceability), the bias "
        "and its repeatability, temperature sensitivity and cross-axis sensitivity."
    )
    return RequirementVerdict(req["name"], req["title"], req["source"], passed, tuple(checks), note)


def decide_with_u(
    value: float,
    big_u: float,
    limit: float,
    *,
    title: str = "",
    interval: tuple[float, float] | None = None,
) -> DecisionWithU:
    """Judge an upper limit on the nonlinearity with its uncertainty (ILAC-G8).

    Parameters
    ----------
    value : float
        The measured (plain) NL (%FS).
    big_u : float
        Its expanded uncertainty U (%FS, p = 95 %).
    limit : float
        The requirement's upper limit (%FS).
    title : str
        Name of the requirement, for the line.
    interval : (float, float) or None
        The 95 % interval [low, high] for the true NL (%FS), when the budget states one (a
        biased, bounded quantity: not centred on the value); None takes value ± U.

    Returns
    -------
    DecisionWithU
        ``"pass with U"`` when high < limit, ``"fail with U"`` when low > limit, otherwise
        ``"inconclusive"``; ``agrees`` tells whether the verdict without U (value < limit) holds
        with U.

    References
    ----------
    ILAC-G8:09/2019, §4.2.2–4.2.3 (guarded acceptance and rejection, guard band w = U);
    JCGM 106:2012, §8 (conformity decisions with a measurement uncertainty: the coverage
    interval for the measurand against the tolerance limit).
    """
    if interval is None:
        low, high = value - big_u, value + big_u
        rule = (
            "guard band w = U (ILAC-G8:09/2019 §4.2): pass when NL + U < limit, fail when NL − U "
            "> limit, inconclusive when the limit lies within NL ± U (p = 95 %)"
        )
        stated = f"NL {value:.4g} ± {big_u:.2g} %FS"
    else:
        low, high = float(interval[0]), float(interval[1])
        rule = (
            "guarded acceptance with the 95 % interval [low, high] for the true NL (ILAC-G8:09/2019 "
            "§4.2, JCGM 106 §8): pass when high < limit, fail when low > limit, inconclusive when "
            "the limit lies within it (the interval is not centred on the plain NL, which noise "
            "biases upward)"
        )
        stated = f"NL {value:.4g} %FS, true NL in [{low:.4g}, {high:.4g}] %FS"
    if high < limit:
        verdict = "pass with U"
    elif low > limit:
        verdict = "fail with U"
    else:
        verdict = "inconclusive"
    plain_pass = value < limit
    agrees = verdict == ("pass with U" if plain_pass else "fail with U")
    head = f"{title} accuracy " if title else "accuracy "
    line = (
        f"{head}with U: {verdict.upper()} — {stated} against < {limit:g} %FS; the verdict "
        f"without U ({'PASS' if plain_pass else 'FAIL'}) "
        f"{'holds' if agrees else 'does not hold'} with U"
    )
    return DecisionWithU(
        "accuracy",
        float(limit),
        float(value),
        float(big_u),
        "percent_fs",
        verdict,
        agrees,
        rule,
        line,
        None if interval is None else (low, high),
    )
