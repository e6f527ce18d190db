"""``rotacal gyro triad --runs``: a continuous log of rotation runs, each averaged over whole revolutions.

With ``--runs`` the capture (``time_s`` and the 3-axis test's columns) is one log of rotation
runs (the robot-manipulator study's one minute per rate, rests between):
:func:`rotacal.gyro.triad_log.calibrate_triad_log` splits it into runs, averages each over its
whole revolutions and fits K and b to the run means. Without it every row is one measurement, as
before.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any, TypeVar

import click

from rotacal.errors import ConfigError

from ._gyro_log import option_group

F = TypeVar("F", bound=Callable[..., Any])


def runs_options(func: F) -> F:
    """Add ``--runs``, ``--settle-s`` and ``--all-rows``; the command receives them as one dict
    ``runs_opts``."""

    options = [
        click.option(
            "--runs",
            is_flag=True,
            help="The capture is one log of rotation runs (time_s, rests between): split it "
            "into runs and average each over its whole revolutions (seed 003's procedure).",
        ),
        click.option(
            "--settle-s",
            type=float,
            default=None,
            help="With --runs: seconds dropped from each run's start [0].",
        ),
        click.option(
            "--all-rows",
            is_flag=True,
            help="With --runs: average every row of each run, the partial revolution too (it "
            "keeps the orientation-dependent terms; for comparison only).",
        ),
    ]
    return option_group("runs_opts", ("runs", "settle_s", "all_rows"), options)(func)


def triad_from_log(
    capture: str,
    columns: Sequence[str],
    group: str | None,
    runs_opts: dict[str, Any],
    options: dict[str, Any],
) -> Any:
    """Read the log and run :func:`calibrate_triad_log` on it."""
    import numpy as np

    from rotacal.gyro import RATE_COLUMNS, TRIAD_OUTPUT_COLUMNS
    from rotacal.gyro.triad_log import calibrate_triad_log

    from ._common import _read, _status

    cap = _read(capture, ["time_s", *RATE_COLUMNS, *TRIAD_OUTPUT_COLUMNS], columns, group)
    with _status("splitting the runs and fitting"):
        return calibrate_triad_log(
            cap["time_s"],
            np.column_stack([cap[c] for c in RATE_COLUMNS]),
            np.column_stack([cap[c] for c in TRIAD_OUTPUT_COLUMNS]),
            whole_revolutions=not runs_opts["all_rows"],
            settle_s=runs_opts["settle_s"] or 0.0,
            **options,
        )


def check_runs_options(runs_opts: dict[str, Any]) -> bool:
    """Whether the log path is asked for; refuse its options without ``--runs``."""
    if not runs_opts["runs"]:
        given = [k for k in ("settle_s", "all_rows") if runs_opts[k] not in (None, False)]
        if given:
            raise ConfigError(
                f"--{given[0].replace('_', '-')} applies to a log of rotation runs: add --runs"
            )
    return bool(runs_opts["runs"])


def runs_sections(result: Any) -> list[Any]:
    """The runs' figure section of a log's result (none for a per-row one)."""
    if not hasattr(result, "runs"):
        return []
    from rotacal.report.gyro_triad_runs import runs_section

    return [runs_section(result)]
