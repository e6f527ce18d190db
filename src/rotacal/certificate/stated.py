"""Results a command states as a value and its standard uncertainty, made budgets a certificate
can report.

Most analyses write GUM budgets (``uncertainty_budgets``); the acceptance commands of a rate table
(``rate --window-deg``, ``position``, ``turntable identify``) and two gyro tests state their
results as ``<key>`` and its standard uncertainty u (``<key>_u``), and the coverage factor k
beside them or by their definition. :func:`stated_budgets` turns each into the budget form
(value, U = k·u, k, p, unit, a name) that :func:`rotacal.certificate.quantities.reported_quantities`
rounds and reports, so that these results get the same ILAC-P14 rounding and the same conformity
decision as every other.

A result keyed by a window or a parameter (``rate_stability_percent`` → {"1": …, "10": …}) gives
one quantity per entry, keyed ``rate_stability_percent.10``: the key a plan's limit names
(``limits = { "rate_stability_percent.10" = { max = 0.01 } }``). An entry without a value (a
geometric error the positions cannot separate: null) is not a result; a separable combination of
such errors is, keyed by its terms in ASCII (``errors_arcsec.phi_y1+eps_y``).

References
----------
JCGM 100:2008 (GUM) §6.2–6.3 (U = k·u), G.3–G.4 (k from Student's t for ν degrees of freedom).
"""

from __future__ import annotations

import dataclasses
import math
import re
from collections.abc import Mapping
from typing import Any

from rotacal.errors import ConfigError
from rotacal.plan.model import Limit
from rotacal.table.rate_windows import window_coverage_factor

__all__ = [
    "STATED_RESULTS",
    "StatedResult",
    "allocation_limits",
    "stated_budgets",
    "window_limit_problem",
]


@dataclasses.dataclass(frozen=True)
class StatedResult:
    """How one key of a command's JSON is reported.

    ``u_key`` names the standard uncertainty (default ``<key>_u``). ``k`` is the coverage factor:
    a number, ``"json"`` for the JSON's own ``k`` (a number, or a mapping by key; 2 when it
    has none), ``"windows"`` for Student's t of ν = N − 1 over the N windows (``window_count``)
    of that window size, as the spread of N window rates has, or ``"rectangular"`` for the k of
    a rectangular distribution (:data:`rotacal.gyro.threshold.K_RECTANGULAR_95`). ``name`` is the reader's name; ``{}``
    takes the entry (the window, the parameter).
    """

    unit: str
    name: str
    k: float | str = "json"
    u_key: str = ""


_WINDOWS = "windows"
#: A rectangular distribution over the bracketing steps (gyro resolution): the k of
#: rotacal.gyro.threshold for p = 95 %.
_RECTANGULAR = "rectangular"
_RATE = {
    "rate_accuracy_percent": StatedResult("%", "rate accuracy over {}°", _WINDOWS),
    "rate_stability_percent": StatedResult("%", "rate stability over {}°", _WINDOWS),
    "rate_stability_peak_percent": StatedResult("%", "rate stability (peak) over {}°", _WINDOWS),
}
#: ISO 230-2 values of a rotary axis; position states u, and k = t₉₅(ν_eff) of each in ``k``.
_POSITION = {
    f"{name}_{direction}_arcsec": StatedResult("arcsec", f"{label} ({direction}, ISO 230-2)")
    for name, label in (
        ("positioning_accuracy", "positioning accuracy A"),
        ("systematic_deviation", "systematic positioning deviation E"),
        ("repeatability", "repeatability of positioning R"),
    )
    for direction in ("bidirectional", "forward", "reverse")
} | {
    "reversal_value_arcsec": StatedResult("arcsec", "reversal value B (ISO 230-2)"),
    "error_pp_arcsec": StatedResult("arcsec", "position error, peak-to-peak"),
}

#: command → key → how it is reported.
STATED_RESULTS: dict[str, dict[str, StatedResult]] = {
    "rate": _RATE,
    "position": _POSITION,
    "turntable identify": {
        "errors_arcsec": StatedResult("arcsec", "geometric error {}", "json", "errors_u_arcsec")
    },
    "gyro frequency-response": {
        "natural_frequency_hz": StatedResult("Hz", "natural frequency fn"),
        "damping_ratio": StatedResult("", "damping ratio ζ"),
        "bandwidth_hz": StatedResult("Hz", "bandwidth (−3 dB)"),
    },
    "gyro resolution": {
        "threshold_deg_s": StatedResult("°/s", "threshold", _RECTANGULAR),
        "resolution_deg_s": StatedResult("°/s", "resolution", _RECTANGULAR),
    },
}


#: The Greek letters of seed 001's error names (``alpha_x2`` → ``α_x2``), as the paper prints them.
_GREEK = {"phi": "φ", "alpha": "α", "eps": "ε", "eta": "η"}


def _symbol(name: str) -> str:
    """A geometric error's name, or a sum of them, in the paper's letters: ``φ_y1 + ε_y``."""
    return re.sub(r"\b(phi|alpha|eps|eta)(?=_|\b)", lambda m: _GREEK[m.group(1)], name)


def _finite(x: Any) -> bool:
    return isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x)


def _number(x: Any, default: float) -> float:
    return float(x) if _finite(x) else default


def _k(how: StatedResult, key: str, entry: str | None, results: Mapping[str, Any]) -> float:
    if isinstance(how.k, float):
        return how.k
    if how.k == _RECTANGULAR:
        from rotacal.gyro.threshold import K_RECTANGULAR_95

        return K_RECTANGULAR_95
    if how.k == _WINDOWS:
        count = _number((results.get("window_count") or {}).get(entry), 2.0)
        return window_coverage_factor(int(count))
    k = results.get("k")
    if isinstance(k, Mapping):
        k = k.get(key)
    return _number(k, 2.0)


def _budget(value: Any, u: Any, k: float, p: float, how: StatedResult, name: str) -> dict | None:
    if not (_finite(value) and _finite(u)):
        return None
    return {"value": value, "U": k * u, "k": k, "p": p, "unit": how.unit, "quantity": name}


def stated_budgets(command: str, results: Mapping[str, Any]) -> dict[str, dict[str, Any]]:
    """The results ``command`` states as value and u, as budgets keyed as a plan names them.

    Parameters
    ----------
    command : str
        The analysis command ("rate", "position", …).
    results : mapping
        The command's JSON.

    Returns
    -------
    dict
        key (``rate_stability_percent.10``) → {value, U, k, p, unit, quantity}; empty for a
        command not in :data:`STATED_RESULTS` or a JSON without those keys.
    """
    p = _number(results.get("coverage_probability"), 0.95)
    out: dict[str, dict[str, Any]] = {}
    for key, how in STATED_RESULTS.get(command, {}).items():
        value, u = results.get(key), results.get(how.u_key or f"{key}_u")
        if isinstance(value, Mapping) and isinstance(u, Mapping):
            for entry, v in value.items():
                k = _k(how, key, entry, results)
                b = _budget(v, u.get(entry), k, p, how, how.name.format(_symbol(entry)))
                if b is not None:
                    out[f"{key}.{entry}"] = b
        else:
            b = _budget(value, u, _k(how, key, None, results), p, how, how.name)
            if b is not None:
                out[key] = b
    if command == "turntable identify":
        out.update(_combinations(results, p))
    return out


def _error_key(name: str, coefficients: Mapping[str, Any]) -> str:
    """The key of an identified error or sum: ``errors_arcsec.alpha_x2``,
    ``errors_arcsec.phi_y1+eps_y`` ("phi_z2 − 0.5·eta" typed as "phi_z2-0.5*eta")."""
    if len(coefficients) < 2:
        return "errors_arcsec." + next(iter(coefficients), name)
    return "errors_arcsec." + "".join(name.split()).replace("−", "-").replace("·", "*")


def allocation_limits(results: Mapping[str, Any]) -> tuple[Limit, ...]:
    """The limits ``errors_arcsec = "allocation"`` stands for: each identified error or sum the
    allocation bounds, within ± its bound B = Σ|aᵢ|·UBᵢ (arcsec, as ``turntable identify``
    computes it), B cut to 0.01 arcsec toward zero so that the certificate prints it and never
    passes more than the allocation allows. Guarded acceptance of value ± U within ± B is then
    the command's own decision |value| + U ≤ B.

    Raises
    ------
    ConfigError
        When the results hold no allocation (the command ran without --config or --budget).
    """
    allocation = results.get("allocation")
    if not isinstance(allocation, Mapping):
        raise ConfigError(
            'errors_arcsec = "allocation": the identification has no allocation to compare '
            "with; give the measurement options.config or options.budget"
        )
    coefficients = {
        c.get("name"): c.get("coefficients") or {} for c in results.get("combinations") or ()
    }
    limits = []
    for entry in allocation.get("combinations") or ():
        bound = entry.get("bound_arcsec")
        if not _finite(bound):
            continue  # "no bound": the allocation says nothing of it
        cut = math.floor(float(bound) * 100.0) / 100.0
        key = _error_key(str(entry["name"]), coefficients.get(entry["name"], {}))
        limits.append(Limit(key, -cut, cut))
    return tuple(limits)


def _combinations(results: Mapping[str, Any], p: float) -> dict[str, dict[str, Any]]:
    """The separable combinations of errors the positions could not separate, as results."""
    how = STATED_RESULTS["turntable identify"]["errors_arcsec"]
    k = _k(how, "errors_arcsec", None, results)
    out: dict[str, dict[str, Any]] = {}
    for c in results.get("combinations") or ():
        if len(c.get("coefficients") or ()) < 2:
            continue  # a single parameter: reported under errors_arcsec already
        name = str(c.get("name", ""))
        b = _budget(
            c.get("value_arcsec"), c.get("u_arcsec"), k, p, how, how.name.format(_symbol(name))
        )
        if b is not None:
            out[_error_key(name, c["coefficients"])] = b
    return out


def _windows(text: Any) -> list[float]:
    """The window angles of a plan's ``window-deg`` option (what does not parse is left to the
    rate command, which refuses it naming the option)."""
    out = []
    for part in str(text).split(","):
        try:
            out.append(float(part))
        except ValueError:
            continue
    return out


def window_limit_problem(command: str, options: Mapping[str, Any], key: str) -> str | None:
    """Why a plan's limit on ``key`` cannot be judged from the windows ``command`` will measure
    with ``options`` (the measurement's options, as the plan gives them), or None.

    A limit on a per-window result names its window: ``rate_stability_percent.10`` needs
    ``window-deg`` to hold 10 (written as the JSON writes it, ``"10"`` not ``"10.0"``), and a
    rate accuracy needs the set rate. Checked when the plan is read, before anything runs.
    """
    group, _, window = key.partition(".")
    if command != "rate" or group not in _RATE:
        return None
    given = options.get("window-deg")
    if given is None:
        return (
            "is a result over angle windows: give the measurement options.window-deg (e.g. "
            'window-deg = "1,10,360")'
        )
    names = [f"{float(w):g}" for w in _windows(given)]  # rate_windows.window_key
    if not window:
        return f"name the window: {', '.join(f'{group}.{n}' for n in names)}"
    if window not in names:
        try:
            same = f"{float(window):g}" in names
        except ValueError:
            same = False
        spelled = f"; write it {group}.{float(window):g}" if same else ""
        return (
            f"no window of {window}° is measured (options.window-deg = {str(given)!r}){spelled}; "
            f"the limits it can take: {', '.join(f'{group}.{n}' for n in names)}"
        )
    if group == "rate_accuracy_percent" and options.get("set-rate-deg-s") is None:
        return "a rate accuracy is against the set rate: give options.set-rate-deg-s"
    return None
