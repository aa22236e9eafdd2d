"""The load-time checks of a task's limits (controller/limit_checks.py), as ``load_task``
raises them: one line naming the file and the key."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from controller.run.task import load_task, task_path
from core.config import CONFIG_ROOT, ConfigError

ROBOT = CONFIG_ROOT / "robot" / "xarm6.yaml"


def robot_with(tmp_path: Path, old: str, new: str) -> Path:
    """A copy of the shipped robot file with one line changed."""
    text = ROBOT.read_text()
    assert old in text
    path = tmp_path / "robot.yaml"
    path.write_text(text.replace(old, new))
    return path


def refusal(name: str, overrides: list[str]) -> str:
    with pytest.raises(ConfigError) as error:
        load_task(name, overrides)
    message = str(error.value)
    assert "\n" not in message
    return message


def test_the_shipped_tasks_pass_the_checks():
    for name in ("usb_a", "usb_c"):
        load_task(name)


def test_a_machine_tilt_limit_the_limiter_never_lets_happen_is_refused():
    message = refusal("usb_c", ["machine.limits.tilt_limit_rad=0.4"])
    assert message == (
        f"{task_path('usb_c')}: key 'machine.limits.tilt_limit_rad': expected less than "
        "limits.max_tilt_rad (0.35), got 0.4: the loop's limiter keeps the tool within 0.35 "
        "rad, so this limit could never trip"
    )


def test_a_machine_tilt_limit_beyond_the_arm_envelope_is_refused(tmp_path):
    robot = robot_with(tmp_path, "  max_tilt_rad: 0.35 ", "  max_tilt_rad: 0.30 ")
    message = refusal("usb_c", [f"devices.arm={robot}"])
    assert message.startswith(
        f"{task_path('usb_c')}: key 'machine.limits.tilt_limit_rad': expected less than "
        f"envelope.max_tilt_rad of {robot} (0.3), got 0.3: the arm's envelope keeps"
    )


def test_an_arm_envelope_that_stops_above_the_insertion_is_refused(tmp_path):
    robot = robot_with(tmp_path, "  z_min_m: 0.011 ", "  z_min_m: 0.02 ")
    message = refusal("usb_c", [f"devices.arm={robot}"])
    # USB-C: 20 mm plug, tip driven 5 mm deep (the machine's depth): TCP at 15 mm, less 2 mm
    assert message == (
        f"{robot}: key 'envelope.z_min_m': expected at most 0.0130 (the TCP's height with the "
        f"plug of {task_path('usb_c')} inserted, less 0.002 m to press it home), got 0.02: the "
        "TCP would stop above the insertion"
    )


def test_task_limits_that_stop_above_the_insertion_are_refused():
    message = refusal("usb_a", ["limits.z_min_m=0.0135"])
    # USB-A: 25 mm plug, tip driven 10 mm deep (the machine's depth): TCP at 15 mm, less 2 mm
    assert re.fullmatch(
        re.escape(f"{task_path('usb_a')}: key 'limits.z_min_m': expected at most 0.0130 ")
        + r".* got 0\.0135: the TCP would stop above the insertion",
        message,
    )


def test_a_limits_box_that_excludes_the_hole_is_refused():
    message = refusal("usb_c", ["limits.x_max_m=0.3"])
    assert message == (
        f"{task_path('usb_c')}: keys 'limits.x_min_m', 'limits.x_max_m': expected a box holding "
        "the hole's x 0.4 m with the search's +-0.003 m, got [0.2, 0.3]: the machine would "
        "search against a face of the box"
    )


def test_an_arm_envelope_that_excludes_the_search_is_refused(tmp_path):
    robot = robot_with(tmp_path, "  y_max_m: 0.25\n", "  y_max_m: 0.002\n")
    message = refusal("usb_a", [f"devices.arm={robot}"])
    assert message.startswith(f"{robot}: keys 'envelope.y_min_m', 'envelope.y_max_m': ")
    assert "the hole's y 0.0 m with the search's +-0.003 m, got [-0.25, 0.002]" in message


@pytest.mark.parametrize(
    ("override", "key", "bound"),
    [
        ("limits.max_linear_speed_m_s=0.2", "limits.max_linear_speed_m_s", "0.1"),
        ("limits.max_angular_speed_rad_s=0.6", "limits.max_angular_speed_rad_s", "0.5"),
        ("limits.x_max_m=0.6", "limits.x_max_m", "0.55"),
        ("limits.y_min_m=-0.3", "limits.y_min_m", "-0.25"),
        ("limits.z_max_m=0.5", "limits.z_max_m", "0.4"),
    ],
)
@pytest.mark.parametrize("backend", ["sim", "real"])
def test_a_task_limit_looser_than_the_arm_envelope_is_refused(override, key, bound, backend):
    with pytest.raises(ConfigError) as error:
        load_task("usb_c", [override], backend=backend)
    message = str(error.value)
    assert "\n" not in message
    assert message.startswith(f"{task_path('usb_c')}: key '{key}': expected within envelope.*")
    assert f"({bound}), got" in message and "never loosen it" in message


def test_a_task_tilt_beyond_the_arm_envelope_is_refused_by_one_of_the_checks():
    message = refusal("usb_c", ["limits.max_tilt_rad=0.4"])
    assert "max_tilt_rad" in message


@pytest.mark.parametrize("key", ["stick_speed_m_s=0.06", "stick_angular_speed_rad_s=0.6"])
def test_teleop_faster_than_the_task_limits_is_refused(key):
    message = refusal("usb_c", [f"teleop.{key}"])
    assert f"key 'teleop.{key.split('=')[0]}': expected at most limits." in message
    assert "never loosen it" in message


def test_a_task_may_tighten_the_limits():
    load_task("usb_c", ["limits.max_linear_speed_m_s=0.03", "teleop.stick_speed_m_s=0.01"])


@pytest.mark.parametrize(
    ("old", "new", "key"),
    [
        ("max_linear_speed_m_s: 0.10 ", "max_linear_speed_m_s: 0.30 ", "max_linear_speed_m_s"),
        ("max_angular_speed_rad_s: 0.5", "max_angular_speed_rad_s: 1.5", "max_angular_speed_rad_s"),
    ],
)
def test_no_robot_file_can_exceed_the_product_speed_ceilings(tmp_path, old, new, key):
    robot = robot_with(tmp_path, old, new)
    message = refusal("usb_c", [f"devices.arm={robot}"])
    ceiling = {"max_linear_speed_m_s": 0.25, "max_angular_speed_rad_s": 1.0}[key]
    assert f"key 'envelope.{key}': expected a number in [0.0, {ceiling}]" in message
