"""rotacal.sim — the digital twin: table motion and sensor models that make every capture type.

Its truth is independent of rotacal's methods: it imports only numpy, scipy, rotacal.errors and
rotacal.results (``SimCapture.write`` imports ``rotacal.io`` lazily).
"""

from rotacal.sim.angle import simulate_angle
from rotacal.sim.ferraris import simulate_ferraris
from rotacal.sim.gyro_log import simulate_gyro_log
from rotacal.sim.gyro_noise import simulate_gyro_noise
from rotacal.sim.gyro_rates import simulate_gyro_rates
from rotacal.sim.gyro_sine import simulate_gyro_sine
from rotacal.sim.gyro_steps import simulate_gyro_steps
from rotacal.sim.gyro_triad import simulate_gyro_rotations, simulate_gyro_triad
from rotacal.sim.gyro_triad_log import simulate_gyro_triad_log
from rotacal.sim.motion import SineMotion
from rotacal.sim.multiposition import simulate_multiposition
from rotacal.sim.orientation_errors import simulate_orientation_errors
from rotacal.sim.position import simulate_position
from rotacal.sim.pulses import simulate_pulses, table_angle_deg, table_rate_deg_s
from rotacal.sim.scenarios import (
    FOG_NOISE_DENSITY_DEG_S_RT_HZ,
    HARMONIC_SHAPE,
    table1_scenarios,
)
from rotacal.sim.sensors import (
    SimCapture,
    default_duration_s,
    known_kinds,
    register_kind,
    simulate,
    simulate_encoder,
    simulate_fog,
    simulate_lts,
)

__all__ = [
    "FOG_NOISE_DENSITY_DEG_S_RT_HZ",
    "HARMONIC_SHAPE",
    "SimCapture",
    "SineMotion",
    "default_duration_s",
    "known_kinds",
    "register_kind",
    "simulate",
    "simulate_angle",
    "simulate_encoder",
    "simulate_ferraris",
    "simulate_fog",
    "simulate_gyro_log",
    "simulate_gyro_noise",
    "simulate_gyro_rates",
    "simulate_gyro_rotations",
    "simulate_gyro_sine",
    "simulate_gyro_steps",
    "simulate_gyro_triad",
    "simulate_gyro_triad_log",
    "simulate_lts",
    "simulate_multiposition",
    "simulate_orientation_errors",
    "simulate_position",
    "simulate_pulses",
    "table1_scenarios",
    "table_angle_deg",
    "table_rate_deg_s",
]
