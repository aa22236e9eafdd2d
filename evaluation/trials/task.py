"""A task file (configs/tasks/NAME.yaml) read whole and checked: the controller's sections,
the scene's, the device files and the estimator, with ``--set KEY=VALUE`` overrides applied
to the raw mapping first, so an override is checked exactly as the file is."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from controller.insertion import MachineConfig
from controller.insertion.blind import BlindConfig
from controller.limit_checks import check_task_limits
from controller.loop import LoopConfig
from controller.safety import LimitsConfig
from controller.teleop import TeleopConfig
from core.config import (
    CONFIG_ROOT,
    Config,
    ConfigError,
    apply_overrides,
    build,
    load_yaml,
    number,
    resolve_config_path,
)
from core.task_geometry import HolePose, PlugGeometry
from drivers.sim.scenes.insertion import InsertionSceneConfig

TASKS = ("usb_a", "usb_c")


@dataclass(frozen=True)
class DeviceFiles(Config):
    """``devices:``: each device's YAML, relative to configs/ (or absolute)."""

    arm: str
    gripper: str
    tactile: str
    gamepad: str | None = None

    def path(self, kind: str) -> Path | None:
        """The file of device ``kind`` (arm, gripper, tactile, gamepad), or None."""
        name = getattr(self, kind)
        if name is None:
            return None
        path = Path(name)
        return path if path.is_absolute() else CONFIG_ROOT / path


@dataclass(frozen=True)
class TaskConfig(Config):
    """A whole task file (see configs/tasks/usb_c.yaml's header). ``force_limit_n``: the
    largest true force (N) the compliant wrist may pass to the plug; a trial over it counts
    against the controller (judged on the simulator's truth, never seen by the controller)."""

    task: str
    estimator: str | None
    force_limit_n: float = number(0.1, 1000.0)
    devices: DeviceFiles
    plug: PlugGeometry
    hole: HolePose
    scene: InsertionSceneConfig
    machine: MachineConfig
    blind: BlindConfig
    loop: LoopConfig
    limits: LimitsConfig
    teleop: TeleopConfig


@dataclass(frozen=True)
class Task:
    """A loaded task: its ``config``, the file it came from, the overrides applied and the
    resolved raw mapping (what a run records)."""

    config: TaskConfig
    path: Path
    overrides: tuple[str, ...]
    raw: dict[str, Any]


def task_path(name_or_path: str) -> Path:
    """configs/tasks/NAME.yaml for a task name, or the YAML path given."""
    return resolve_config_path(name_or_path, "tasks")


def load_task(name_or_path: str, overrides: Sequence[str] = ()) -> Task:
    """The task ``name_or_path`` with ``overrides`` (``KEY=VALUE``, dotted keys) applied;
    ConfigError (one line, naming the file and the key) for anything wrong."""
    path = task_path(name_or_path)
    source = str(path)
    raw = apply_overrides(load_yaml(path), overrides, source)
    config = build(TaskConfig, raw, source)
    for kind in ("arm", "gripper", "tactile", "gamepad"):
        device = config.devices.path(kind)
        if device is not None and not device.is_file():
            raise ConfigError(f"{source}: key 'devices.{kind}': no such file {device}")
    check_task_limits(
        source=source,
        machine_limits=config.machine.limits,
        limits=config.limits,
        arm_file=config.devices.path("arm"),
        plug=config.plug,
        hole=config.hole,
        hole_depth_m=config.scene.receptacle.depth_m,
    )
    return Task(config, path, tuple(overrides), raw)
