"""The Allan family of stability deviations of a rate (or phase) record, with edf and intervals.

:func:`stability_deviation` computes, at octave, decade, log-spaced, explicit or all averaging
times τ = m/fs, one of

* ``"adev"`` — overlapping Allan deviation (:func:`rotacal.signal.allan.overlapping_adev`);
* ``"mdev"`` — modified Allan deviation, NIST SP 1065 eq. (14): the second differences averaged
  over m before squaring, which separates white from flicker angle (phase) noise;
* ``"hdev"`` — overlapping Hadamard deviation, eq. (18): third differences, insensitive to a
  constant rate ramp (linear frequency drift);
* ``"tdev"`` — time deviation, eq. (15): τ·MDEV/√3, in the *phase* unit (° for a rate in °/s);
* ``"totdev"`` — total deviation, eq. (25): the overlapping Allan variance of the phase extended
  by reflection at both ends, whose long-τ estimates scatter less;

each in the unit of the rate (°/s for °/s, fractional frequency for fractional frequency) except
TDEV, with the equivalent degrees of freedom of Greenhall & Riley (2003) (the total deviation:
NIST SP 1065 Table 8) and the χ² confidence interval (:func:`rotacal.signal.allan.
adev_confidence_interval`). The sums are whole-array NumPy, O(N) per τ
(:mod:`rotacal.signal._deviation_sums`); the all-τ O(N log² N) method exists for the ADEV only.
A record read in chunks: :class:`rotacal.signal.deviations_stream.ChunkedDeviation` (octave or
decade τ, the same numbers to rounding).
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import numpy as np

from rotacal.errors import ConfigError
from rotacal.results import Result
from rotacal.signal._allan_edf import edf_greenhall, edf_totdev
from rotacal.signal._deviation_sums import hadamard_sums, modified_sums, total_sums
from rotacal.signal.allan import (
    ONE_SIGMA,
    DataType,
    _check_alpha,
    _cluster_sizes,
    adev_confidence_interval,
    overlapping_adev,
    prepared_phase,
)

__all__ = [
    "DEVIATIONS",
    "DEVIATION_NAMES",
    "StabilityDeviation",
    "deviation_from_sums",
    "deviation_keys",
    "edf_deviation",
    "longest_cluster",
    "stability_deviation",
]

#: The deviations :func:`stability_deviation` computes.
DEVIATIONS = ("adev", "mdev", "hdev", "tdev", "totdev")
#: Their names in words (figures, messages).
DEVIATION_NAMES = {
    "adev": "overlapping Allan deviation",
    "mdev": "modified Allan deviation",
    "hdev": "overlapping Hadamard deviation",
    "tdev": "time deviation",
    "totdev": "total deviation",
}
#: ``taus="all"`` costs one O(N) pass per τ for all but the ADEV: refused above this many
#: sample·τ products (about a minute of one core).
ALL_TAUS_BUDGET = 3e9


@dataclasses.dataclass(frozen=True, eq=False)
class StabilityDeviation(Result):
    """One deviation of the Allan family of one record.

    Attributes
    ----------
    kind : "adev", "mdev", "hdev", "tdev" or "totdev".
    tau_s : averaging times τ = m/fs (s), increasing.
    deviation : σ(τ); in the rate's unit (°/s for °/s or ° input; dimensionless for fractional
        frequency or time error in s), TDEV in the phase's unit (° for °/s or ° input; s for
        fractional frequency or time error).
    low, high : χ² confidence interval of σ(τ) at ``confidence`` (same unit).
    edf : equivalent degrees of freedom of σ²(τ) for the noise type ``noise_alpha``.
    n_terms : number of terms (differences) averaged at each τ.
    cluster_sizes : m, samples per cluster.
    fs_hz : sampling rate (Hz); n_samples : samples given; n_phase : phase points used.
    data_type : "rate" or "phase"; confidence : level of the interval (0–1).
    noise_alpha : power-law exponent(s) α assumed for the edf (0 = white rate noise).
    notes : remarks on the τ list.
    """

    kind: str
    tau_s: np.ndarray
    deviation: np.ndarray
    low: np.ndarray
    high: np.ndarray
    edf: np.ndarray
    n_terms: np.ndarray
    cluster_sizes: np.ndarray
    fs_hz: float
    n_samples: int
    n_phase: int
    data_type: str
    confidence: float
    noise_alpha: Any
    notes: tuple[str, ...] = ()


def _check_kind(kind: Any) -> str:
    if kind not in DEVIATIONS:
        raise ConfigError(f"kind must be one of {', '.join(DEVIATIONS)}; got {kind!r}.")
    return str(kind)


def longest_cluster(kind: str, n_phase: int) -> tuple[int, int]:
    """(longest cluster size the deviation can use at all, longest kept in the octave and
    decade lists) for ``n_phase`` phase points: at least one term, and two for the lists."""
    kind = _check_kind(kind)
    if kind in ("mdev", "tdev"):  # N − 3m + 1 terms
        return n_phase // 3, (n_phase - 1) // 3
    if kind == "hdev":  # N − 3m terms
        return (n_phase - 1) // 3, (n_phase - 2) // 3
    return (n_phase - 1) // 2, (n_phase - 2) // 2  # adev: N − 2m; totdev: ADEV's range


def _n_terms(kind: str, n_phase: int, ms: np.ndarray) -> np.ndarray:
    if kind in ("mdev", "tdev"):
        return n_phase - 3 * ms + 1
    if kind == "hdev":
        return n_phase - 3 * ms
    if kind == "totdev":
        return np.full(ms.size, n_phase - 2, dtype=np.int64)
    return n_phase - 2 * ms


def edf_deviation(kind: str, n_phase: int, cluster_sizes: Any, noise_alpha: Any = 0) -> np.ndarray:
    """Equivalent degrees of freedom of the variance behind one deviation of the family.

    Parameters
    ----------
    kind : "adev", "mdev", "hdev", "tdev" or "totdev".
    n_phase : int — phase points N (rate samples + 1).
    cluster_sizes : array_like of int — m (τ = m/fs), each within :func:`longest_cluster`.
    noise_alpha : int or array_like of int (one per m) — power-law exponent α of the rate
        (fractional-frequency) noise, S_y(f) ∝ f^α: 2 white PM (white angle noise,
        quantization), 1 flicker PM, 0 white FM (angle random walk), −1 flicker FM (bias
        instability), −2 random-walk FM (rate random walk).

    Returns
    -------
    ndarray — edf for each m (dimensionless).

    References
    ----------
    C. A. Greenhall and W. J. Riley, "Uncertainty of stability variances based on finite
    differences", Proc. 35th PTTI Meeting (2003), §3–4, eqs. (7)–(10), Tables 1–3: ADEV d = 2
    and HDEV d = 3 unmodified (F = m), MDEV and TDEV d = 2 modified (F = 1), all overlapping
    (S = m) — the algorithm of Stable32 and allantools. TOTDEV: NIST SP 1065 (Riley 2008),
    §5.2.11, Table 8 (edf = b·N/m − c for α = 0, −1, −2; the ADEV's edf for α = 2, 1).
    """
    kind = _check_kind(kind)
    m = np.asarray(cluster_sizes, dtype=np.int64).ravel()
    top = longest_cluster(kind, int(n_phase))[0]
    if m.size and (m.min() < 1 or m.max() > top):
        raise ConfigError(
            f"cluster sizes of the {kind} must satisfy 1 ≤ m ≤ {top} for N = {n_phase}."
        )
    alphas = _check_alpha(noise_alpha, m.size)
    out = np.empty(m.size)
    for a in np.unique(alphas).tolist():
        sel = alphas == a
        if kind == "totdev":
            out[sel] = edf_totdev(int(n_phase), m[sel], int(a))
        else:
            d = 3 if kind == "hdev" else 2
            out[sel] = edf_greenhall(int(n_phase), m[sel], int(a), d, kind in ("mdev", "tdev"))
    return out


def _from_adev(adev: Any) -> StabilityDeviation:
    return StabilityDeviation(
        kind="adev",
        tau_s=adev.tau_s,
        deviation=adev.adev,
        low=adev.adev_low,
        high=adev.adev_high,
        edf=adev.edf,
        n_terms=adev.n_terms,
        cluster_sizes=adev.cluster_sizes,
        fs_hz=adev.fs_hz,
        n_samples=adev.n_samples,
        n_phase=adev.n_phase,
        data_type=adev.data_type,
        confidence=adev.confidence,
        noise_alpha=adev.noise_alpha,
        notes=adev.notes,
        warnings=adev.warnings,
    )


def stability_deviation(
    data: Any,
    *,
    fs: float,
    kind: str = "mdev",
    taus: Any = None,
    data_type: DataType = "rate",
    confidence: float = ONE_SIGMA,
    noise_alpha: Any = 0,
    allow_clipped: bool = False,
) -> StabilityDeviation:
    """One deviation of the Allan family, with edf and χ² confidence interval at each τ.

    For N phase points x (the rate's running integral x_0 = 0, x_k = Σ_{i<k} y_i/fs, or the
    phase as given) and τ = m/fs:

    * MDEV² = Σ_{j=0}^{N−3m} (Σ_{i=j}^{j+m−1} (x_{i+2m} − 2x_{i+m} + x_i))² / (2m²τ²(N − 3m + 1));
    * HDEV² = Σ_{i=0}^{N−3m−1} (x_{i+3m} − 3x_{i+2m} + 3x_{i+m} − x_i)² / (6τ²(N − 3m));
    * TDEV = τ·MDEV/√3;
    * TOTDEV² = Σ_{i=1}^{N−2} (x*_{i−m} − 2x*_i + x*_{i+m})² / (2τ²(N − 2)), x* the phase
      reflected at both ends (x*_{−j} = 2x_0 − x_j, x*_{N−1+j} = 2x_{N−1} − x_{N−1−j});
    * ADEV as :func:`rotacal.signal.allan.overlapping_adev`.

    Parameters
    ----------
    data : array_like
        Rate samples (°/s, rad/s, fractional frequency, …) for ``data_type="rate"``; phase or
        angle samples (°, or time error in s) for ``"phase"``.
    fs : float
        Sampling rate (Hz).
    kind : str
        One of :data:`DEVIATIONS`.
    taus : None, str or array_like
        As :func:`~rotacal.signal.allan.overlapping_adev` (``None``/``"octave"``, ``"decade"``,
        ``"log"``, ``"all"`` or τ in s), up to the deviation's longest cluster
        (:func:`longest_cluster`: N/3 for MDEV/TDEV/HDEV). ``"all"`` costs O(N) per τ here
        (except the ADEV) and is refused above :data:`ALL_TAUS_BUDGET` sample·τ products.
    data_type : "rate" or "phase"
    confidence : float — level of ``low``/``high`` (default ±1σ, 68.3 %).
    noise_alpha : int or array_like of int — noise type(s) for the edf (:func:`edf_deviation`).
    allow_clipped : bool — accept a rate record at the rails (``warnings`` say so).

    Returns
    -------
    StabilityDeviation

    Raises
    ------
    CaptureError
        As :func:`~rotacal.signal.allan.overlapping_adev` (non-finite, too short, constant or
        clipped record).
    ConfigError
        An unknown ``kind``, a τ the record cannot represent, ``"all"`` over the budget, and the
        other options' errors.

    References
    ----------
    NIST SP 1065 (W. J. Riley, "Handbook of Frequency Stability Analysis", 2008), §5.2.5
    eq. (14) (MDEV), §5.2.6 eq. (15) (TDEV), §5.2.9 eq. (18) (overlapping HDEV), §5.2.11
    eq. (25) (TOTDEV); IEEE Std 1139-2008, §5 and Annex C; edf: :func:`edf_deviation`.
    """
    kind = _check_kind(kind)
    if kind == "adev":
        return _from_adev(
            overlapping_adev(
                data,
                fs=fs,
                taus=taus,
                data_type=data_type,
                confidence=confidence,
                noise_alpha=noise_alpha,
                allow_clipped=allow_clipped,
            )
        )
    # the Hadamard's third differences annihilate a rate ramp: it is removed before the rate is
    # integrated, so that a steep ramp's parabola costs the phase no digits
    fs_hz, conf, x, n_samples, clipped = prepared_phase(
        data,
        fs,
        data_type,
        confidence,
        allow_clipped,
        f"the {DEVIATION_NAMES[kind]}",
        ramp_blind=kind == "hdev",
    )
    n_phase = x.size
    top, listed = longest_cluster(kind, n_phase)
    ms, notes = _cluster_sizes(taus, n_phase, fs_hz, top, listed)
    if ms.size == 0:
        raise ConfigError(
            f"no τ of the {kind} is representable with {n_phase} phase points; supply a longer "
            "record."
        )
    if (
        isinstance(taus, str)
        and taus.lower() == "all"
        and ms.size * float(n_phase) > ALL_TAUS_BUDGET
    ):
        raise ConfigError(
            f"--taus all for the {kind} sums each of its {ms.size} τ over the whole record "
            f"({ms.size * float(n_phase):.2g} terms, beyond {ALL_TAUS_BUDGET:.0e}): use log, "
            "octave or decade τ (every τ is fast for the adev only)."
        )
    kernel = {"hdev": hadamard_sums, "totdev": total_sums}.get(kind, modified_sums)
    return deviation_from_sums(
        kind,
        kernel(x, ms),
        ms,
        n_phase=int(n_phase),
        n_samples=n_samples,
        fs_hz=fs_hz,
        data_type=data_type,
        confidence=conf,
        noise_alpha=noise_alpha,
        notes=tuple(notes),
        warnings=clipped,
    )


def deviation_from_sums(
    kind: str,
    sums: np.ndarray,
    ms: np.ndarray,
    *,
    n_phase: int,
    n_samples: int,
    fs_hz: float,
    data_type: str,
    confidence: float,
    noise_alpha: Any,
    notes: tuple[str, ...] = (),
    warnings: tuple[str, ...] = (),
) -> StabilityDeviation:
    """The deviation ``kind`` (not the ADEV) from its sums of squares at the cluster sizes ``ms``
    (:mod:`rotacal.signal._deviation_sums`, in the phase unit squared: (° )² for a rate in °/s),
    with edf and χ² interval; the formulas of :func:`stability_deviation`."""
    alphas = _check_alpha(noise_alpha, ms.size)
    tau = ms / fs_hz
    n_terms = _n_terms(kind, n_phase, ms)
    if kind in ("mdev", "tdev"):
        dev = np.sqrt(sums / (2.0 * ms.astype(np.float64) ** 2 * n_terms)) / tau
        if kind == "tdev":
            dev = dev * tau / math.sqrt(3.0)
    elif kind == "hdev":
        dev = np.sqrt(sums / (6.0 * n_terms)) / tau
    else:
        dev = np.sqrt(sums / (2.0 * n_terms)) / tau
    edf = edf_deviation(kind, n_phase, ms, alphas)
    lo, hi = adev_confidence_interval(dev, edf, confidence)
    return StabilityDeviation(
        kind=kind,
        tau_s=tau,
        deviation=dev,
        low=lo,
        high=hi,
        edf=edf,
        n_terms=n_terms,
        cluster_sizes=ms,
        fs_hz=fs_hz,
        n_samples=n_samples,
        n_phase=n_phase,
        data_type=data_type,
        confidence=confidence,
        noise_alpha=int(alphas[0]) if np.all(alphas == alphas[0]) else alphas,
        notes=notes,
        warnings=warnings,
    )


def deviation_keys(dev: StabilityDeviation) -> dict[str, Any]:
    """The JSON keys of one deviation as ``rotacal allan --deviation`` writes them.

    ``deviation`` (its name), ``<kind>_tau_s`` (s), ``<kind>_deg_s`` with its interval
    ``<kind>_low_deg_s``/``<kind>_high_deg_s`` (the rate unit, °/s for a record in °/s) and
    ``<kind>_edf``; the TDEV, an angle, as ``tdev_deg``/``tdev_low_deg``/``tdev_high_deg`` (° for a
    record in °/s). For a record in another unit the values are in that unit (rate) or that unit
    times seconds (TDEV), as ``adev_deg_s`` is.
    """
    unit = "deg" if dev.kind == "tdev" else "deg_s"
    k = dev.kind
    return {
        "deviation": k,
        f"{k}_tau_s": np.asarray(dev.tau_s, dtype=np.float64).tolist(),
        f"{k}_{unit}": np.asarray(dev.deviation, dtype=np.float64).tolist(),
        f"{k}_low_{unit}": np.asarray(dev.low, dtype=np.float64).tolist(),
        f"{k}_high_{unit}": np.asarray(dev.high, dtype=np.float64).tolist(),
        f"{k}_edf": np.asarray(dev.edf, dtype=np.float64).tolist(),
    }
