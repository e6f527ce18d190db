"""The canonical columns each analysis command reads (INTERFACE.md, "Captures"): the one table.

The CLI reads a capture's columns by these names and ``rotacal inspect`` tells from them which
commands a file fits, so a command and the first look at a file never disagree. No imports of
the methods here: every layer may use the names, and ``rotacal --help`` stays quick.
"""

from __future__ import annotations

import dataclasses
import re
from collections.abc import Iterable

#: Pulse-timestamp columns of a multi-head encoder: head_0 … head_{n-1}.
HEAD_NAME = re.compile(r"^head_(\d+)$")
#: Reference rates of the "3-axis gyro test" capture, in the DUT's nominal axes (deg/s).
RATE_COLUMNS = ("wx_deg_s", "wy_deg_s", "wz_deg_s")
#: Raw outputs of the "3-axis gyro test" capture (and of rotations through a known angle).
TRIAD_OUTPUT_COLUMNS = ("ux", "uy", "uz")
#: Raw outputs of an accelerometer triad (a Ferraris session's other sensor).
ACCEL_OUTPUT_COLUMNS = ("ax", "ay", "az")


@dataclasses.dataclass(frozen=True)
class CommandColumns:
    """The columns one analysis command reads.

    Attributes
    ----------
    command : str — the command as typed after ``rotacal`` (``"motion encoder"``).
    required : tuple of str — canonical names the capture must have.
    optional : tuple of str — canonical names the command uses when present.
    min_heads : int — for pulse-timestamp commands, the fewest ``head_k`` columns (0: none).
    """

    command: str
    required: tuple[str, ...]
    optional: tuple[str, ...] = ()
    min_heads: int = 0

    def fits(self, names: Iterable[str]) -> bool:
        """Whether a capture with these column names has what the command reads."""
        have = set(names)
        if not set(self.required) <= have:
            return False
        if self.min_heads:
            heads = {int(m.group(1)) for m in map(HEAD_NAME.match, have) if m}
            return set(range(self.min_heads)) <= heads
        return True


MOTION_ENCODER = CommandColumns("motion encoder", ("time_s", "a", "b"))
MOTION_LTS = CommandColumns("motion lts", ("time_s", "displacement_mm"))
MOTION_FOG = CommandColumns("motion fog", ("time_s", "rate_deg_s"))
GYRO_SCALE_FACTOR = CommandColumns("gyro scale-factor", ("rate_deg_s", "output"))
GYRO_TRIAD = CommandColumns("gyro triad", RATE_COLUMNS + TRIAD_OUTPUT_COLUMNS)
GYRO_ROTATIONS = CommandColumns(
    "gyro rotations", TRIAD_OUTPUT_COLUMNS, ("time_s", *ACCEL_OUTPUT_COLUMNS)
)
GYRO_ACCELEROMETER = CommandColumns("gyro accelerometer", ACCEL_OUTPUT_COLUMNS)
GYRO_MULTIPOSITION = CommandColumns("gyro multiposition", ("phi1_deg", "phi2_deg", "output_deg_h"))
TURNTABLE_IDENTIFY = CommandColumns(
    "turntable identify",
    ("phi1_deg", "phi2_deg", "dpsi_arcsec", "dtheta_arcsec", "dgamma_arcsec"),
)
ALLAN = CommandColumns("allan", ("rate_deg_s",), ("time_s",))
#: The reference is the encoder's a, b (with --lines) or an angle column: two ways to fit.
GYRO_FREQUENCY_RESPONSE = CommandColumns(
    "gyro frequency-response", ("time_s", "rate_deg_s", "a", "b")
)
GYRO_FREQUENCY_RESPONSE_ANGLE = CommandColumns(
    "gyro frequency-response", ("time_s", "rate_deg_s", "angle_deg")
)
#: A position test: the reference encoder's reading, or the deviation (an autocollimator's).
POSITION_OPTIONAL = ("run", "direction", "face")
POSITION_REFERENCE = CommandColumns(
    "position", ("position_deg", "reference_deg"), POSITION_OPTIONAL
)
POSITION_DEVIATION = CommandColumns("position", ("position_deg", "error_arcsec"), POSITION_OPTIONAL)
SELFCAL = CommandColumns("selfcal", (), min_heads=2)
RATE = CommandColumns("rate", (), min_heads=1)
#: Angle or counter readings: `motion angle`, and `rate` timed at the angle's marks.
MOTION_ANGLE = CommandColumns("motion angle", ("time_s", "angle_deg"))
MOTION_COUNT = CommandColumns("motion angle", ("time_s", "count"))
RATE_ANGLE = CommandColumns("rate", ("time_s", "angle_deg"))
RATE_COUNT = CommandColumns("rate", ("time_s", "count"))

#: Every analysis command that reads a capture, in the order ``rotacal --help`` lists them.
COMMANDS: tuple[CommandColumns, ...] = (
    ALLAN,
    GYRO_SCALE_FACTOR,
    GYRO_TRIAD,
    GYRO_ROTATIONS,
    GYRO_ACCELEROMETER,
    GYRO_MULTIPOSITION,
    TURNTABLE_IDENTIFY,
    GYRO_FREQUENCY_RESPONSE,
    GYRO_FREQUENCY_RESPONSE_ANGLE,
    MOTION_ENCODER,
    MOTION_LTS,
    MOTION_FOG,
    POSITION_REFERENCE,
    POSITION_DEVIATION,
    MOTION_ANGLE,
    MOTION_COUNT,
    RATE,
    RATE_ANGLE,
    RATE_COUNT,
    SELFCAL,
)

#: Every canonical column name (``head_k`` stands for the pulse columns).
CANONICAL_NAMES: tuple[str, ...] = tuple(
    dict.fromkeys(n for c in COMMANDS for n in (*c.required, *c.optional))
)


def fitting_commands(names: Iterable[str]) -> tuple[str, ...]:
    """The analysis commands whose columns a capture with these column names has."""
    have = list(names)
    return tuple(dict.fromkeys(c.command for c in COMMANDS if c.fits(have)))
