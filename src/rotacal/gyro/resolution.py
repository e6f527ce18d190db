"""The resolution of a gyro's output, as a requirement such as FMVSS 126 means it.

Seed 004 tabulates the FMVSS 126 requirements for the gyroscope of ESC testing equipment (its
Table 1, from NHTSA's FMVSS 126 laboratory test procedure, 2008): "Measurement Range ± 100 deg/s;
Resolution < 0.004 deg/s; Accuracy < 0.05 % Full Scale". Resolution is a property of the
instrument's output: the smallest change of angular rate that its reading shows. Two things limit
it, and the larger sets it:

* **the output quantum** q (output units): a rate change below q/|S| may leave the output
  unchanged (S the scale factor, output units per °/s);
* **the noise of one reading at the stated bandwidth** B: a rate change below σ_B/|S| is lost in
  the noise of a single output sample (a signal-to-noise ratio of 1). σ_B is the standard deviation
  of the output within a rate point after averaging blocks of N = round(fs/(2B)) consecutive
  samples — an N-sample mean has the noise-equivalent bandwidth fs/(2N) (fs the sample rate), which
  is the bandwidth reported; without a bandwidth, the samples as recorded (N = 1: bandwidth fs/2,
  or "as recorded" when fs is not known). The largest σ_B over the rate points counts (the worst
  rate), and it includes whatever the output does within a point at that bandwidth (the table's
  own rate noise too).

Neither shrinks with the length of the record. The standard error of a point's mean (σ/√n), which
rotacal judged before, does: a noisy gyro recorded long enough passed. The scale factor, bias and
nonlinearity do not depend on any of this.

References
----------
Kokuyama W., Watanabe T., Nozato H., Ota A., "Development of angular velocity calibration facility
using self-calibratable rotary encoder", §2 and Table 1 (FMVSS 126: resolution
< 0.004 deg/s). NHTSA, FMVSS 126 Laboratory Test Procedure for Electronic Stability Control Systems
(2008), as cited there. IEEE Std 1431-2004 (its resolution test with small rate increments,
which a test at set rates does not replace).
"""

from __future__ import annotations

import dataclasses

import numpy as np

from rotacal.errors import ConfigError
from rotacal.gyro.scale_factor_requirement import _positive as _positive_option
from rotacal.results import Result

__all__ = [
    "NoiseBlock",
    "OutputResolution",
    "check_blocks_fit",
    "noise_block",
    "output_resolution",
    "resolution_from_noise",
]


@dataclasses.dataclass(frozen=True)
class OutputResolution(Result):
    """The smallest rate change the output resolves, and what set it (°/s unless stated).

    ``resolution_deg_s`` is the larger of ``quantum_deg_s`` (output quantum / |S|) and
    ``noise_deg_s`` (σ_B / |S|); ``set_by`` names it (``"quantum"``, ``"noise"``; ``None`` when
    neither is visible). ``bandwidth_hz`` is the noise bandwidth realised (fs/(2N); ``None`` when
    the sample rate is not known), ``bandwidth_source`` where it came from, ``block_samples`` N,
    ``sample_rate_hz`` fs (``None``: not given). ``basis`` says all of it on one line.
    """

    resolution_deg_s: float | None
    set_by: str | None
    quantum_deg_s: float | None
    noise_deg_s: float | None
    bandwidth_hz: float | None
    bandwidth_source: str
    sample_rate_hz: float | None
    block_samples: int
    basis: str


def _block_noise(y: np.ndarray, groups: np.ndarray, n_groups: int, block: int) -> np.ndarray:
    """Per group, the standard deviation (ddof 1) of the means of consecutive blocks of ``block``
    samples (in recorded order; an incomplete last block is left out); NaN below two blocks."""
    order = np.argsort(groups, kind="stable")
    g = groups[order]
    starts = np.flatnonzero(np.r_[True, g[1:] != g[:-1]])
    sizes = np.diff(np.r_[starts, g.size])
    within = np.arange(g.size) - np.repeat(starts, sizes)
    blocks_of = sizes // block  # complete blocks per present group
    keep = within < np.repeat(blocks_of * block, sizes)
    g, v, k = g[keep], y[order][keep], within[keep] // block
    first = np.zeros(n_groups, dtype=np.int64)
    counts = np.zeros(n_groups, dtype=np.int64)
    present = g[np.r_[True, g[1:] != g[:-1]]] if g.size else np.zeros(0, dtype=np.int64)
    counts[present] = blocks_of[blocks_of > 0]
    first[1:] = np.cumsum(counts)[:-1]
    block_id = first[g] + k
    # each group's samples less its first one: the block means keep the digits of the noise even
    # on a large offset, and a streamed capture sums the same differences
    shift = np.zeros(n_groups)
    if g.size:
        shift[present] = v[np.r_[True, g[1:] != g[:-1]]]
    means = np.bincount(block_id, weights=v - shift[g], minlength=int(counts.sum())) / block
    owner = np.repeat(np.arange(n_groups), counts)
    with np.errstate(invalid="ignore", divide="ignore"):
        centre = np.bincount(owner, weights=means, minlength=n_groups) / counts  # less shift
        dev = means - centre[owner]
        ss = np.bincount(owner, weights=dev * dev, minlength=n_groups)
        return np.where(counts > 1, np.sqrt(ss / np.maximum(counts - 1, 1)), np.nan)


@dataclasses.dataclass(frozen=True)
class NoiseBlock:
    """How the noise of one reading is measured: blocks of ``block`` samples (1: as recorded).

    ``sample_rate_hz`` fs (Hz, None: not given), ``bandwidth_hz`` the realised bandwidth fs/(2N)
    (Hz, None without fs), ``source`` where it came from, ``asked_hz`` the bandwidth the user gave.
    """

    sample_rate_hz: float | None
    block: int
    bandwidth_hz: float | None
    source: str
    asked_hz: float | None


def noise_block(sample_rate_hz: float | None, bandwidth_hz: float | None) -> NoiseBlock:
    """The block length N = round(fs/(2B)) for a stated bandwidth B (Hz), the settings checked.

    Raises
    ------
    ConfigError
        A bandwidth without a sample rate, a non-positive or non-finite one, or one above fs/2.
    """
    fs = (
        None
        if sample_rate_hz is None
        else _positive_option(
            "the sample rate (--sample-rate-hz)", sample_rate_hz, "the capture's sample rate in Hz"
        )
    )
    if bandwidth_hz is None:
        source = "the recorded samples' own" + (
            ", fs/2" if fs is not None else "; sample rate not given"
        )
        return NoiseBlock(fs, 1, None if fs is None else fs / 2.0, source, None)
    b = _positive_option("the bandwidth (--bandwidth-hz)", bandwidth_hz, "of one reading, in Hz")
    if fs is None:
        raise ConfigError(
            f"the bandwidth (--bandwidth-hz) {b:g} Hz needs the capture's sample rate: give "
            "--sample-rate-hz too."
        )
    if b > fs / 2.0:
        raise ConfigError(
            f"the bandwidth (--bandwidth-hz) {b:g} Hz is above the capture's bandwidth fs/2 "
            f"= {fs / 2:g} Hz: the samples cannot show noise there; give at most {fs / 2:g}."
        )
    block = max(1, round(fs / (2.0 * b)))
    return NoiseBlock(
        fs, block, fs / (2.0 * block), f"stated {b:g} Hz: means of {block} samples at {fs:g} Hz", b
    )


def check_blocks_fit(settings: NoiseBlock, sizes: np.ndarray) -> None:
    """Refuse a bandwidth whose blocks no rate point (``sizes``: finite samples each) holds twice."""
    longest = int(np.max(sizes, initial=0))
    if settings.block > 1 and longest < 2 * settings.block:
        raise ConfigError(
            f"the bandwidth (--bandwidth-hz) {settings.asked_hz:g} Hz averages blocks of "
            f"{settings.block} samples, but no rate point holds two of them (the longest has "
            f"{longest} samples): raise the bandwidth or record longer points."
        )


def resolution_from_noise(
    noise: np.ndarray,
    output_abs_max: float,
    scale_factor: float,
    *,
    quantum: float | None,
    settings: NoiseBlock,
    output_unit: str = "",
) -> OutputResolution:
    """The resolution from the block noise σ_B of each rate point (output units, NaN where a point
    holds fewer than two blocks), the largest finite |output| (for the float floor), S (output
    units per °/s) and the quantum q (output units or None): see the module docstring."""
    unit = f" {output_unit}" if output_unit else ""
    s = abs(float(scale_factor))
    finite = noise[np.isfinite(noise)]
    sigma = float(finite.max()) if finite.size else None
    # a scatter at the float resolution of the values is rounding of the means, not noise
    floor = 64.0 * np.finfo(float).eps * float(output_abs_max)
    noise_deg_s = None if sigma is None or sigma <= floor else sigma / s
    quantum_deg_s = None if quantum is None else float(quantum) / s
    if noise_deg_s is None and quantum_deg_s is None:
        value, set_by = None, None
    elif noise_deg_s is None or (quantum_deg_s is not None and quantum_deg_s >= noise_deg_s):
        value, set_by = quantum_deg_s, "quantum"
    else:
        value, set_by = noise_deg_s, "noise"
    bw = settings.bandwidth_hz
    bw_text = (
        "the recorded samples' bandwidth (sample rate not given)"
        if bw is None
        else f"{bw:.4g} Hz ({settings.source})"
    )
    noise_text = (
        "not visible"
        if noise_deg_s is None
        else f"{noise_deg_s:.3g} °/s ({sigma:.4g}{unit} rms of one reading at {bw_text}; the "
        "largest over the rate points)"
    )
    quantum_text = (
        "not visible" if quantum is None else f"{quantum_deg_s:.3g} °/s ({quantum:.4g}{unit})"
    )
    basis = (f"set by the {set_by}" if set_by else "neither visible") + (
        f": noise {noise_text}; output quantum {quantum_text}"
    )
    return OutputResolution(
        resolution_deg_s=value,
        set_by=set_by,
        quantum_deg_s=quantum_deg_s,
        noise_deg_s=noise_deg_s,
        bandwidth_hz=bw,
        bandwidth_source=settings.source,
        sample_rate_hz=settings.sample_rate_hz,
        block_samples=settings.block,
        basis=basis,
    )


def output_resolution(
    output: np.ndarray,
    groups: np.ndarray,
    scale_factor: float,
    *,
    quantum: float | None,
    sample_rate_hz: float | None = None,
    bandwidth_hz: float | None = None,
    output_unit: str = "",
) -> OutputResolution:
    """The smallest rate change the output resolves: output quantum or noise at a bandwidth.

    See the module docstring. Whole-array: the block means are one ``bincount``.

    Parameters
    ----------
    output : array
        Output samples in recorded order (output units); non-finite values are left out.
    groups : array of int
        Rate point of each sample (0 … n_points − 1).
    scale_factor : float
        S (output units per °/s, nonzero).
    quantum : float or None
        The output quantum q (output units; :func:`rotacal.gyro.scale_factor.output_quantum`), or
        None when the values show no grid.
    sample_rate_hz : float, optional
        fs of the samples (Hz, > 0). Needed for ``bandwidth_hz``; with it alone the bandwidth is
        the recorded one, fs/2.
    bandwidth_hz : float, optional
        B (Hz, 0 < B ≤ fs/2): the bandwidth the requirement's reading has; default the recorded
        samples' own.
    output_unit : str
        Name of the output unit, for the basis line.

    Returns
    -------
    OutputResolution

    Raises
    ------
    ConfigError
        A bandwidth without a sample rate, a non-positive or non-finite one, a bandwidth above
        fs/2, or one so low that no rate point holds two blocks of N samples.

    References
    ----------
    Seed 004, §2 and Table 1 (FMVSS 126: resolution < 0.004 deg/s).
    """
    settings = noise_block(sample_rate_hz, bandwidth_hz)
    y = np.asarray(output, dtype=float).reshape(-1)
    g = np.asarray(groups).reshape(-1).astype(np.int64)
    ok = np.isfinite(y)
    y, g = y[ok], g[ok]
    n_groups = int(g.max()) + 1 if g.size else 0
    check_blocks_fit(settings, np.bincount(g, minlength=n_groups))
    noise = _block_noise(y, g, n_groups, settings.block)
    return resolution_from_noise(
        noise,
        float(np.max(np.abs(y), initial=0.0)),
        scale_factor,
        quantum=quantum,
        settings=settings,
        output_unit=output_unit,
    )
