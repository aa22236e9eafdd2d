"""The task file (configs/tasks/NAME.yaml): the one schema of a run's configuration.

A task file holds the controller's sections (``machine:``, ``blind:``, ``loop:``,
``limits:``, ``teleop:``), the task's geometry (``plug:``, the nominal ``hole:``), the device
files (``devices:``), the estimator, its calibration for the grasped plug (``calibration:``,
controller/run/task_calibration.py) and the simulated scene (``scene:``). A task file may build
on a base file (``extends: base/usb.yaml``, ``core.config.load_yaml_extending``), holding only
what differs: configs/tasks/usb_a.yaml and usb_c.yaml share configs/tasks/base/usb.yaml.
``--set KEY=VALUE`` overrides are applied to the merged mapping before it is checked, so an
override is checked exactly as the file is, and a run records the merged, overridden mapping.

``scene:`` belongs to the simulator: it is checked (through ``drivers.registry``, which
imports the simulator's config) only when the task is loaded for ``backend: sim``, so a real
run never loads the simulator.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from controller.insertion import MachineConfig
from controller.insertion.spiral import SpiralConfig, TouchSpiralConfig
from controller.limit_checks import check_task_limits
from controller.loop import LoopConfig
from controller.run.task_calibration import grasp_scene_sha256, load_task_calibration
from controller.safety import LimitsConfig
from controller.tactile.calibration import Calibration
from controller.tactile.settings import sensor_estimator
from controller.teleop import TeleopConfig
from core.config import (
    CONFIG_ROOT,
    Config,
    ConfigError,
    apply_overrides,
    build,
    config_dataclass,
    load_yaml_extending,
    number,
    resolve_config_path,
    safety_rule_keys,
)
from core.sensor_profile import sensor_profile
from core.task_geometry import HolePose, PlugGeometry
from drivers import registry

SCENE_KEY = "scene"
BACKENDS = registry.BACKENDS


@config_dataclass
class DeviceFiles(Config):
    """``devices:``: each device's YAML, relative to configs/ (or absolute)."""

    arm: str
    gripper: str
    tactile: str
    gamepad: str | None = None

    def paths(self) -> dict[str, Path]:
        """Device kind -> its YAML path, for the kinds named (the gamepad is optional)."""
        paths = {}
        for kind in registry.RUN_DEVICE_KINDS:
            name = getattr(self, kind)
            if name is not None:
                path = Path(name)
                paths[kind] = path if path.is_absolute() else CONFIG_ROOT / path
        return paths


@config_dataclass
class TaskConfig(Config):
    """A task file but its ``scene:`` (see the module doc). ``force_limit_n``: the largest
    true force (N) the compliant wrist may pass to the plug; a simulated trial over it counts
    against the controller (judged on the simulator's truth, never seen by the controller).
    ``contact_force_limit_n``: the connector's specified insertion force (N, docs/TRIALS.md):
    the largest true net contact force on the plug along the hole's axis; a simulated trial
    over it fails (``insertion_force_exceeded``).
    ``estimator``: the estimator configuration (None: the tactile sensor's own);
    ``calibration``: its calibration file for this task's grasp, relative to configs/ (None:
    raw estimates; controller/run/task_calibration.py)."""

    task: str
    estimator: str | None
    calibration: str | None
    force_limit_n: float = number(0.1, 1000.0)
    contact_force_limit_n: float = number(0.1, 1000.0)
    devices: DeviceFiles
    plug: PlugGeometry
    hole: HolePose
    machine: MachineConfig
    blind: SpiralConfig
    touch_spiral: TouchSpiralConfig
    loop: LoopConfig
    limits: LimitsConfig
    teleop: TeleopConfig


@dataclass(frozen=True)
class Task:
    """A loaded task: its ``config``, the simulator's checked ``scene`` configuration (None
    when loaded for the real backend), the file it came from, the overrides applied and the
    resolved raw mapping (what a run records), each device file as read for the backend
    it was loaded for (``registry.DeviceSpec``, by kind), and the estimator's checked
    ``calibration`` (None: the task names none, or it was loaded without it)."""

    config: TaskConfig
    scene: Any
    path: Path
    overrides: tuple[str, ...]
    raw: Mapping[str, Any]
    devices: Mapping[str, registry.DeviceSpec]
    calibration: Calibration | None = None

    @property
    def device_files(self) -> dict[str, Path]:
        """Device kind -> its YAML path (``devices:``)."""
        return self.config.devices.paths()

    @property
    def tactile_model(self) -> str:
        """The tactile sensor's model (its profile's name), from its device file."""
        return str(self.devices["tactile"].config.model)

    @property
    def grasp_scene_sha256(self) -> str:
        """The fingerprint of the grasp's scene a calibration is fitted for
        (``task_calibration.grasp_scene_sha256``)."""
        return grasp_scene_sha256(self.raw, self.devices["tactile"].config)


def task_path(name_or_path: str) -> Path:
    """configs/tasks/NAME.yaml for a task name, or the YAML path given."""
    return resolve_config_path(name_or_path, "tasks")


def load_task(
    name_or_path: str,
    overrides: Sequence[str] = (),
    backend: str = "sim",
    *,
    with_calibration: bool = True,
) -> Task:
    """The task ``name_or_path`` with ``overrides`` (``KEY=VALUE``, dotted keys) applied,
    checked for ``backend`` (``sim`` also checks ``scene:``) and, ``with_calibration``, with
    its calibration file loaded and checked against the sensor, the estimator and the
    grasp's scene (``python -m evaluation calibrate_task`` loads the task without it, to fit it);
    ConfigError (one line, naming the file and the key) for anything wrong."""
    if backend not in BACKENDS:
        raise ConfigError(f"backend {backend!r}: expected one of {', '.join(BACKENDS)}")
    path = task_path(name_or_path)
    source = str(path)
    raw = apply_overrides(
        load_yaml_extending(path), overrides, source, safety_rule_keys(TaskConfig)
    )
    if SCENE_KEY not in raw:
        raise ConfigError(f"{source}: missing key '{SCENE_KEY}'")
    sections = {key: value for key, value in raw.items() if key != SCENE_KEY}
    config = build(TaskConfig, sections, source)
    devices = _checked_devices(config, source, backend)
    check_task_limits(
        source=source,
        machine_limits=config.machine.limits,
        limits=config.limits,
        arm_file=devices["arm"].path,
        arm_envelope=devices["arm"].config.envelope,
        plug=config.plug,
        hole=config.hole,
        tip_depth_m=config.machine.insert.depth_m,
        search_half_width_m=max(config.machine.search.uncertainty_xy_m, config.blind.half_width_m),
        teleop=config.teleop,
    )
    scene = registry.scene_config(raw[SCENE_KEY], source) if backend == "sim" else None
    task = Task(config, scene, path, tuple(overrides), raw, devices)
    if not with_calibration or config.calibration is None:
        return task
    profile = sensor_profile(task.tactile_model)
    _, estimator = sensor_estimator(profile, config.estimator)
    # The grasp's scene is the simulator's: on hardware the file must be the cell's own
    # (docs/ARCHITECTURE.md, "Calibrated units"), checked for its sensor and estimator.
    scene_sha256 = task.grasp_scene_sha256 if backend == "sim" else None
    calibration = load_task_calibration(
        source, config.calibration, profile.name, estimator, scene_sha256, config.task
    )
    return dataclasses.replace(task, calibration=calibration)


def _checked_devices(
    config: TaskConfig, source: str, backend: str
) -> dict[str, registry.DeviceSpec]:
    """Each device file read for ``backend``: it holds a device of its kind (content and
    ``type:`` checked by the registry), and the estimator configuration exists and suits the
    tactile sensor; a ConfigError naming ``source`` and the key otherwise, so every tool
    refuses the task when it loads, not at a trial's start."""
    specs = {}
    for kind, device in config.devices.paths().items():
        if not device.is_file():
            problem = "is not a regular file" if device.exists() else "does not exist"
            raise ConfigError(f"{source}: key 'devices.{kind}': {device} {problem}")
        try:
            specs[kind] = registry.load_device_config(device, backend, kind)
        except ConfigError as exc:
            raise ConfigError(f"{source}: key 'devices.{kind}': {exc}") from None
    try:
        sensor_estimator(sensor_profile(specs["tactile"].config.model), config.estimator)
    except ConfigError as exc:
        raise ConfigError(f"{source}: key 'estimator': {exc}") from None
    return specs
