"""INSERT's torque servo on the press-spiral machine: it yields to the torque (turning the
TCP the way the torque on the plug would), about the plug's tip, no faster than its cap and
no further than its tilt from the pass's orientation; the tactile reading gives the newest
frame's torques in T; the task file's gains are checked."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from controller.insertion.force_reading import ArmForce, TactileAxialForce
from controller.insertion.machine_config import s2t_matrix
from controller.insertion.spiral.torque_servo import TorqueServo, TorqueServoSettings
from controller.run.task import load_task
from core.config import ConfigError
from tests.controller.insertion.world import ToyWorld, estimate

UPRIGHT = Rotation.from_euler("x", math.pi)  # T z straight down (T2B)
SERVO = TorqueServo(TorqueServoSettings((20.0, 20.0, 10.0), max_rate_rad_s=0.2, max_turn_rad=0.1))


def test_it_turns_against_the_gels_torque_about_each_axis_of_t():
    torque_t = np.array([0.003, -0.002, 0.001])  # N*m about T x, y, z
    w_b = SERVO.rate_b(torque_t, UPRIGHT, UPRIGHT)
    w_t = UPRIGHT.inv().apply(w_b)
    assert w_t == pytest.approx([-0.06, 0.04, -0.01])


def test_the_rate_is_capped():
    w_b = SERVO.rate_b(np.array([0.1, 0.0, 0.0]), UPRIGHT, UPRIGHT)
    assert np.linalg.norm(w_b) == pytest.approx(0.2)


def test_at_its_tilt_limit_it_turns_no_further_but_may_turn_back():
    away_b = np.array([1.0, 0.0, 0.0])  # the TCP turned 0.12 rad about B x from the pass's
    tilted = Rotation.from_rotvec(0.12 * away_b) * UPRIGHT
    torque_out = tilted.inv().apply(-away_b) * 0.005  # would turn it further about B x
    assert float(SERVO.rate_b(torque_out, tilted, UPRIGHT) @ away_b) == pytest.approx(0.0)
    inside = Rotation.from_rotvec(0.05 * away_b) * UPRIGHT  # within the limit: it turns
    assert float(SERVO.rate_b(torque_out, inside, UPRIGHT) @ away_b) > 0.05
    assert float(SERVO.rate_b(-torque_out, tilted, UPRIGHT) @ away_b) < 0.0  # back: allowed


def test_off_without_gains():
    assert not TorqueServoSettings().on
    assert TorqueServoSettings((0.0, 1.0, 0.0)).on


def test_the_tactile_reading_gives_the_newest_frames_torque_in_t():
    s2t = s2t_matrix(("+x", "+z", "-y"))
    reading = TactileAxialForce([0.0] * 4 + [2.0] + [0.0] * 4, window=3, s2t=s2t)
    obs = ToyWorld().observe()
    assert reading.torque_t() is None
    frame = estimate(0.1, tau_x=0.001, tau_y=0.002, tau_z=0.003, shear_y=1.0)
    reading.read(replace(obs, wrench=frame))
    assert reading.torque_t() == pytest.approx(s2t @ [0.001, 0.002, 0.003])
    reading.read(replace(obs, wrench=estimate(0.14, zeroing=True)))
    assert reading.torque_t() is None  # none while the estimator re-zeroes
    assert ArmForce(5).torque_t() is None  # the F/T reading has no torques


def test_a_negative_gain_is_refused_naming_its_key():
    with pytest.raises(ConfigError, match="gain_rad_s_nm"):
        load_task("usb_c", ["touch_spiral.push_servo.gain_rad_s_nm=[-1.0, 0.0, 0.0]"])
