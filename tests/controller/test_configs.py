"""The loop's three configuration sections load from YAML as a task file will hold them."""

from __future__ import annotations

import pytest
import yaml

from controller.loop import LoopConfig
from controller.safety import LimitsConfig
from controller.teleop import TeleopConfig
from core.config import ConfigError, build

TASK_SECTIONS = """
loop:
  rate_hz: 100
  hold_s: 0.05
  tactile_max_age_s: 0.15
  rezero_frames: 5
  max_consecutive_overruns: 5
  max_overruns_in_window: 20
  overrun_window_ticks: 100
  rt_priority: null
  max_held_by_limits_s: 1.0
limits:
  x_min_m: 0.20
  x_max_m: 0.55
  y_min_m: -0.25
  y_max_m: 0.25
  z_min_m: 0.02
  z_max_m: 0.40
  max_linear_speed_m_s: 0.05
  max_angular_speed_rad_s: 0.5
  max_tilt_rad: 0.35
  wrench_units: calibrated
  max_tilt_torque: 0.05
  max_twist_torque: null
  max_normal: null
  over_budget: lift_only
teleop:
  max_linear_speed_m_s: 0.02
  max_angular_speed_rad_s: 0.2
  takeover_threshold: 0.0
  require_deadman: false
"""

CLASSES = {"loop": LoopConfig, "limits": LimitsConfig, "teleop": TeleopConfig}


def test_the_sections_load_and_match_the_defaults():
    data = yaml.safe_load(TASK_SECTIONS)
    loaded = {n: build(cls, data[n], "task.yaml", f"{n}.") for n, cls in CLASSES.items()}
    assert loaded["loop"] == LoopConfig()
    assert loaded["teleop"] == TeleopConfig()
    assert loaded["limits"] == LimitsConfig(max_tilt_torque=0.05)


@pytest.mark.parametrize(
    ("section", "key", "value", "message"),
    [
        ("loop", "rate_hz", 0, "key 'loop.rate_hz'"),
        ("loop", "rt_priority", 100, "key 'loop.rt_priority'"),
        ("limits", "over_budget", "retreat", "key 'limits.over_budget': expected one of"),
        ("limits", "max_normal", -1, "key 'limits.max_normal'"),
        ("teleop", "require_deadman", "yes", "key 'teleop.require_deadman'"),
    ],
)
def test_a_bad_value_names_the_file_and_key(section, key, value, message):
    data = yaml.safe_load(TASK_SECTIONS)[section]
    data[key] = value
    with pytest.raises(ConfigError, match=f"task.yaml: {message}"):
        build(CLASSES[section], data, "task.yaml", f"{section}.")
