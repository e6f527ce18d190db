"""Every twin's analysis with its defaults says nothing: no warning in its JSON, none on stderr.

The runs are the session's ``cli_runs`` (tests/report/conftest.py), whose reports the browser
reads: each twin of ``rotacal simulate`` with its defaults analysed by its command, ``rate`` of the
pulse twin at its set rate, the example table's budget, and the frequency response of a sine
sweep. Faults that must speak are in tests/cli/test_plausibility_cli.py.
"""

from __future__ import annotations

import pytest


@pytest.mark.xdist_group("demo")  # the session's cli_runs live on the demo's worker
def test_every_twin_with_defaults_is_warning_free(cli_runs) -> None:
    # motion ×3, selfcal, rate, inspect, gyro ×5, allan, turntable ×2, position
    assert len(cli_runs) == 15
    for command, run in cli_runs.items():
        assert run.result["warnings"] == [], command
        assert "warning" not in run.stderr, command
