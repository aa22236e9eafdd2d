"""The loop's three configuration sections load from YAML as a task file will hold them."""

from __future__ import annotations

import pytest
import yaml

from controller.loop import LoopConfig
from controller.run.task import TaskConfig, load_task
from controller.safety import LimitsConfig
from controller.teleop import TeleopConfig
from core.config import CONFIG_ROOT, ConfigError, build, safety_rule_keys

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
  stick_speed_m_s: 0.02
  stick_angular_speed_rad_s: 0.2
  takeover_threshold: 0.0
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
        ("teleop", "takeover_threshold", 2, "key 'teleop.takeover_threshold'"),
    ],
)
def test_a_bad_value_names_the_file_and_key(section, key, value, message):
    data = yaml.safe_load(TASK_SECTIONS)[section]
    data[key] = value
    with pytest.raises(ConfigError, match=f"task.yaml: {message}"):
        build(CLASSES[section], data, "task.yaml", f"{section}.")


@pytest.mark.parametrize("value", [False, True, "no"])
def test_a_file_setting_the_deadman_is_refused_as_a_safety_rule(value):
    data = yaml.safe_load(TASK_SECTIONS)["teleop"]
    data["require_deadman"] = value
    with pytest.raises(ConfigError, match="task.yaml: key 'teleop.require_deadman': a safety rule"):
        build(TeleopConfig, data, "task.yaml", "teleop.")


@pytest.mark.parametrize("backend", ["sim", "real"])
def test_an_override_of_the_deadman_is_refused_by_every_task_load(backend):
    with pytest.raises(ConfigError, match="override 'teleop.require_deadman': a safety rule"):
        load_task("usb_c", ["teleop.require_deadman=false"], backend=backend)


def test_a_task_file_that_sets_the_deadman_is_refused(tmp_path):
    task = tmp_path / "task.yaml"
    base = CONFIG_ROOT / "tasks" / "usb_c.yaml"
    task.write_text(f"extends: {base}\nteleop:\n  require_deadman: false\n")
    with pytest.raises(ConfigError, match=r"key 'teleop.require_deadman': a safety rule"):
        load_task(str(task))


def test_every_safety_rule_key_is_found_in_the_task():
    assert safety_rule_keys(TaskConfig) == {
        "teleop.require_deadman": "takeover and motion always need the deadman held"
    }
