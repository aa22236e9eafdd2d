"""Each setting name means one thing.

A setting is a leaf of the shipped task files (configs/tasks/, the base laid under each
task) or of the robot file they name (its ``envelope:``, the driver's safety limits). Its
meaning is the config field it sets: the class that declares the field and the field's
name. Two sections that are instances of one class (``blind:`` and ``touch_spiral:``, both
``SpiralConfig``; every ``gripper:`` block; the task's ``limits:`` and the robot's
``envelope:``, both ``Envelope``) set the same settings, each for its own controller or
layer. A leaf name declared by two different classes is refused unless it is in
``SHARED_NAMES`` below, with the reason it is one quantity.
"""

from __future__ import annotations

import dataclasses
from collections import defaultdict
from collections.abc import Iterator, Mapping
from typing import Any

import pytest

from controller.run.task import load_task
from core.config import load_yaml, load_yaml_extending

TASKS = ("usb_c", "usb_a")

# Leaf names that different config classes declare for one quantity, each the quantity of
# the thing its section names. Keep this short: a name that limits something says what.
_MACHINES = "the same quantity in the align machine (its phase) and the press spiral"
_OBJECT = "a size or pose coordinate of the object (or its uncertainty) its section names"
_PHASE = "the same quantity of each phase of the align machine that has it"
SHARED_NAMES: Mapping[str, str] = {
    "pattern": _MACHINES,  # the search pattern: spiral | raster
    "pitch_m": _MACHINES,  # between the pattern's turns or lines
    "move_speed_m_s": _MACHINES,  # free moves
    "rotate_speed_rad_s": _MACHINES,  # free turns
    "descend_speed_m_s": _MACHINES,  # down to the touch
    "pose_gain_1_s": _MACHINES,  # the pose servo's gain (speed = gain x error)
    "pose_tol_m": _MACHINES,  # a pose target counts as reached within this
    "stall_s": _MACHINES,  # a push no lower for this long has stalled
    "tilt_limit_rad": _MACHINES,  # the TCP's tilt from straight down that fails the run
    "rock_speed_rad_s": _MACHINES,  # FEEL's turn while rocking the pressed plug
    "rock_max_rad": _MACHINES,  # ... as far each way
    "enabled": "the section's own step switched on (the align machine's FEEL, the spiral's)",
    "speed_m_s": _PHASE,  # search, insert, backoff: the phase's motion
    "settle_s": _PHASE,  # gripper, feel, search, release: the phase's wait to settle
    "press_depth_m": _PHASE,  # feel, search: the tip held this far below the contact height
    "width_m": _OBJECT,  # the plug's, the receptacle's
    "thickness_m": _OBJECT,  # the plug's, the board's
    "height_m": _OBJECT,  # the receptacle's, the board's; the tip's over the board (approach)
    "depth_m": _OBJECT,  # the receptacle's; the tip's below the board that counts as inserted
    "tilt_rad": _OBJECT,  # the board's, the grasp's; the approach's tilted plug
    "x_m": _OBJECT,  # the hole's nominal and its uncertainty
    "y_m": _OBJECT,
    "yaw_rad": _OBJECT,
}


def _declaring_class(owner: object, name: str) -> type:
    """The class whose own annotations declare the field ``name`` of ``owner``."""
    for cls in type(owner).__mro__:
        if name in vars(cls).get("__annotations__", {}):
            return cls
    raise AssertionError(f"{type(owner).__name__} declares no field {name!r}")


def _leaves(data: Mapping[str, Any], owner: object, prefix: str) -> Iterator[tuple[str, type]]:
    """(dotted path, declaring class) of every leaf of ``data``, read into ``owner``."""
    for key, value in data.items():
        path = f"{prefix}{key}"
        field_value = getattr(owner, key)
        if isinstance(value, dict) and dataclasses.is_dataclass(field_value):
            yield from _leaves(value, field_value, f"{path}.")
        else:
            yield path, _declaring_class(owner, key)


def _settings() -> dict[str, dict[str, set[type]]]:
    """Leaf name -> dotted path -> declaring classes, over the shipped tasks and their robot
    files."""
    names: dict[str, dict[str, set[type]]] = defaultdict(lambda: defaultdict(set))
    for name in TASKS:
        task = load_task(name)
        data = load_yaml_extending(task.path)
        scene = data.pop("scene")
        envelope = load_yaml(task.device_files["arm"])["envelope"]
        sources = [
            (data, task.config, ""),
            (scene, task.scene, "scene."),
            (envelope, task.devices["arm"].config.envelope, "robot:envelope."),
        ]
        for mapping, owner, prefix in sources:
            for path, cls in _leaves(mapping, owner, prefix):
                names[path.rsplit(".", 1)[-1].split(":")[-1]][path].add(cls)
    return names


SETTINGS = _settings()


@pytest.mark.parametrize("name", sorted(SETTINGS))
def test_a_setting_name_means_one_thing(name):
    classes = {cls for found in SETTINGS[name].values() for cls in found}
    if len(classes) > 1:
        paths = ", ".join(sorted(SETTINGS[name]))
        assert name in SHARED_NAMES, f"'{name}' means different things: {paths}"


@pytest.mark.parametrize("name", sorted(SHARED_NAMES))
def test_every_shared_name_is_still_shared(name):
    classes = {cls for found in SETTINGS.get(name, {}).values() for cls in found}
    assert len(classes) > 1, f"'{name}' is declared by one class only: drop it from SHARED_NAMES"


def test_the_limits_keep_one_name_each():
    # the safety limits (the task's limits:, the robot's envelope:) are one Envelope's keys
    for name in ("max_tilt_rad", "max_linear_speed_m_s", "max_angular_speed_rad_s"):
        assert set(SETTINGS[name]) == {f"limits.{name}", f"robot:envelope.{name}"}
