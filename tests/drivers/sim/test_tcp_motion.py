"""The simulated TCP's motion (drivers/sim/twins/tcp_motion.py) at the tilt limit."""

from __future__ import annotations

import math

import numpy as np
import pytest

from core.devices import Pose
from core.envelope import Envelope
from core.spatial import tilt_of_quat
from drivers.sim.twins.tcp_motion import TcpMotion

ENV = Envelope(
    x_min_m=0.1, x_max_m=0.5, y_min_m=-0.3, y_max_m=0.3, z_min_m=0.0, z_max_m=0.4,
    max_linear_speed_m_s=0.2, max_angular_speed_rad_s=1.0, max_tilt_rad=0.35,
)  # fmt: skip


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_changing_twists_never_tilt_the_tool_past_the_limit(seed):
    """Each step's orientation is projected into the tilt cone, not the previous one's: a
    twist that turns about the vertical at the limit overshot it by microradians before."""
    rng = np.random.default_rng(seed)
    motion = TcpMotion(ENV, Pose((0.3, 0.0, 0.2), (math.pi, 0.1, 0.2)), 2.0, 8.0, 1 / 500)
    worst = 0.0
    for _ in range(8):
        w_des = tuple(rng.normal(0.0, 1.0, 3))
        for _ in range(150):
            motion.step((0.0, 0.0, 0.0), w_des)
            worst = max(worst, tilt_of_quat(motion.rotation)[0])
    assert worst == pytest.approx(ENV.max_tilt_rad, abs=1e-12)  # it reaches the limit ...
    assert worst <= ENV.max_tilt_rad + 1e-12  # ... and stays on it
