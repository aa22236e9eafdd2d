"""Building a device from its YAML: ``type:`` and ``backend:`` -> driver and config.

Device YAML layout (one file per device, e.g. ``configs/robot/xarm6.yaml``)::

    type: xarm6          # the device model: a key of DRIVERS[kind]
    backend: sim         # sim | real; sim when the key is absent
    name: xarm6          # the real driver's keys, as its config dataclass names them
    ip: 192.168.1.185
    ...
    sim:                 # the simulated twin's own keys (read only with backend: sim)
      max_accel_m_s2: 1.0
      ...

The twin's config dataclass extends the real driver's with the ``sim`` field (e.g.
``SimArmConfig(XArm6Config)``), so a twin runs with the very envelope, rates, sizes and
names of the device it stands for, and switching ``backend:`` changes nothing else. With
``backend: real`` the ``sim:`` section is ignored. A type with no real driver yet (the
force/torque sensor) has only the sim backend.

The one way to build a device::

    with registry.load_device("configs/robot/xarm6.yaml") as arm: ...
    arm = registry.load_device(path, backend="real", kind="arm", clock=clock)  # not connected

``load_device_config`` is its first half (read and validate the file, no device built):
a script that checks every file before touching any device loads them all first, then
calls ``DeviceSpec.build``. Transport keywords (``api=``, ``arm=``, ``capture_factory=``)
go to the driver's ``from_config``; the twins accept and ignore them.

A run's whole device set (``build_device_set``): with ``backend: real`` each device file's
real driver on one ``MonotonicClock``; with ``backend: sim`` the simulated world
(``drivers.sim.scenes.insertion``) with its twins behind the same Protocols, on the world's
own clock. Either way the caller gets ``Devices`` and a clock; the simulated ``world``
(its truth, for scoring) is an opaque handle the controller never reads.

Lazy imports. The table below names modules, and a driver's module is imported only when
that backend is built (or its config class is asked for): ``backend: sim`` needs only the
base dependencies, and pygame, pymodbus and the xArm SDK (the ``hw`` extra) load only with
the real gamepad, the serial Hand-E and the real xArm.
"""

from __future__ import annotations

import dataclasses
import importlib
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Required, TypedDict, cast

from core.clock import Clock, MonotonicClock
from core.config import Config, ConfigError, build, load_yaml
from core.devices import (
    Arm,
    Device,
    Devices,
    ForceTorqueSensor,
    Gamepad,
    Gripper,
    TactileSensor,
)

BACKENDS = ("sim", "real")
DEFAULT_BACKEND = "sim"
SELECTOR_KEYS = ("type", "backend")
SIM_SECTION = "sim"


@dataclass(frozen=True)
class Driver:
    """Where a device class and the config dataclass of its ``from_config`` live, as
    ``"module:Name"``; each is imported when first asked for."""

    device: str
    config: str

    @property
    def device_class(self) -> type[Device]:
        return _load(self.device)

    @property
    def config_class(self) -> type[Config]:
        return _load(self.config)


DRIVERS: Mapping[str, Mapping[str, Mapping[str, Driver]]] = {
    "arm": {
        "xarm6": {
            "real": Driver("drivers.arm.xarm6:XArm6", "drivers.arm.xarm6:XArm6Config"),
            "sim": Driver("drivers.sim.twins.arm:SimArm", "drivers.sim.twins.arm:SimArmConfig"),
        },
    },
    "gripper": {
        "hande": {
            "real": Driver("drivers.gripper.hande:HandE", "drivers.gripper.hande:HandEConfig"),
            "sim": Driver(
                "drivers.sim.twins.gripper:SimGripper", "drivers.sim.twins.gripper:SimGripperConfig"
            ),
        },
    },
    "tactile": {
        "tactile_camera": {
            "real": Driver(
                "drivers.tactile.camera:TactileCamera",
                "drivers.tactile.camera:TactileCameraConfig",
            ),
            "sim": Driver(
                "drivers.sim.twins.tactile:SimTactileSensor",
                "drivers.sim.twins.tactile:SimTactileConfig",
            ),
        },
    },
    "gamepad": {
        "sdl_gamepad": {
            "real": Driver(
                "drivers.gamepad.pad:PygameGamepad", "drivers.gamepad.mapping:GamepadConfig"
            ),
            "sim": Driver(
                "drivers.sim.twins.gamepad:SimGamepad", "drivers.sim.twins.gamepad:SimGamepadConfig"
            ),
        },
    },
    "force_torque": {
        "ft_sensor": {
            "sim": Driver(
                "drivers.sim.twins.force_torque:SimForceTorque",
                "drivers.sim.twins.force_torque:SimForceTorqueConfig",
            ),
        },
    },
}
"""kind -> YAML ``type:`` -> backend -> Driver."""

PROTOCOLS: Mapping[str, type] = {
    "arm": Arm,
    "gripper": Gripper,
    "tactile": TactileSensor,
    "gamepad": Gamepad,
    "force_torque": ForceTorqueSensor,
}
"""kind -> the ``core.devices`` Protocol its devices implement."""

RUN_DEVICE_KINDS = ("arm", "gripper", "tactile", "gamepad")
"""The kinds a run drives (``Devices``' fields); the gamepad is optional."""


class _RunDevices(TypedDict, total=False):
    """A run's devices by kind (``RUN_DEVICE_KINDS``): ``Devices``' keyword arguments."""

    arm: Required[Arm]
    gripper: Required[Gripper]
    tactile: Required[TactileSensor]
    gamepad: Gamepad


SIM_WORLD = Driver(
    "drivers.sim.scenes.insertion.builder:build_world",
    "drivers.sim.scenes.insertion.scene_config:InsertionSceneConfig",
)
"""The simulated insertion world (``backend: sim``) and the config dataclass of a task's
``scene:`` section."""

_KIND_OF_TYPE = {type_name: kind for kind, types in DRIVERS.items() for type_name in types}


@dataclass(frozen=True)
class Selection:
    """What a device YAML selects: its kind, type and backend, the config dataclass to build,
    and the keys to build it from (the YAML without ``type``/``backend``, and without the
    ``sim`` section for the real backend)."""

    kind: str
    type_name: str
    backend: str
    config_class: type[Config]
    keys: Mapping[str, Any]


@dataclass(frozen=True)
class DeviceSpec:
    """A device YAML read and validated: what it selects and its config dataclass."""

    path: str
    kind: str
    type_name: str
    backend: str
    config: Any

    def build(self, clock: Clock | None = None, **transport: Any) -> Device:
        """The device, not connected: its driver's ``from_config(config, clock=clock,
        **transport)`` (``clock``: ``MonotonicClock`` when None)."""
        device_class = _driver(self.kind, self.type_name, self.backend).device_class
        return device_class.from_config(self.config, clock=clock, **transport)


def load_device_config(
    path: Path | str, backend: str | None = None, kind: str | None = None
) -> DeviceSpec:
    """Read and validate the device YAML at ``path``; ``backend`` overrides the file's, and
    ``kind`` (e.g. ``"arm"``), when given, is required of the file's type. Raises
    ConfigError naming the file and the key."""
    if kind is not None and kind not in DRIVERS:
        raise ValueError(f"unknown device kind {kind!r}; known: {', '.join(DRIVERS)}")
    source = str(path)
    data = load_yaml(path)
    try:
        selection = select(data, backend)
    except ValueError as exc:
        raise ConfigError(f"{source}: {exc}") from None
    if kind is not None and selection.kind != kind:
        raise ConfigError(
            f"{source}: key 'type': expected a device of kind '{kind}' "
            f"({', '.join(DRIVERS[kind])}), got {selection.type_name!r} (kind '{selection.kind}')"
        )
    config = build(selection.config_class, selection.keys, source=source)
    return DeviceSpec(source, selection.kind, selection.type_name, selection.backend, config)


def load_device(
    path: Path | str,
    backend: str | None = None,
    *,
    kind: str | None = None,
    clock: Clock | None = None,
    **transport: Any,
) -> Device:
    """The device of the YAML at ``path``, built and not connected (see the module doc)."""
    return load_device_config(path, backend, kind).build(clock, **transport)


def kind_of(type_name: str) -> str:
    """The device kind of a YAML ``type:`` (types are unique across kinds)."""
    try:
        return _KIND_OF_TYPE[type_name]
    except KeyError:
        raise ValueError(
            f"key 'type': unknown device type {type_name!r}; known: {', '.join(_KIND_OF_TYPE)}"
        ) from None


def config_class(kind: str, type_name: str, backend: str = DEFAULT_BACKEND) -> type[Config]:
    """The config dataclass of ``type_name`` (of ``kind``) on ``backend``."""
    return _driver(kind, type_name, backend).config_class


def select(data: Mapping[str, Any], backend: str | None = None) -> Selection:
    """Read ``type:`` and ``backend:`` from a device YAML's top-level mapping; ``backend``
    overrides the file's. Raises ValueError naming the key for a missing or unknown type or
    an unknown backend."""
    if "type" not in data:
        raise ValueError(f"missing key 'type'; expected one of: {', '.join(_KIND_OF_TYPE)}")
    type_name = data["type"]
    if not isinstance(type_name, str):
        raise ValueError(f"key 'type': expected a device type name, got {type_name!r}")
    kind = kind_of(type_name)
    chosen = backend if backend is not None else data.get("backend", DEFAULT_BACKEND)
    driver = _driver(kind, type_name, chosen)
    dropped = SELECTOR_KEYS if chosen == "sim" else (*SELECTOR_KEYS, SIM_SECTION)
    keys = {key: value for key, value in data.items() if key not in dropped}
    return Selection(kind, type_name, chosen, driver.config_class, keys)


def _driver(kind: str, type_name: str, backend: str) -> Driver:
    if kind not in DRIVERS:
        raise ValueError(f"unknown device kind {kind!r}; known: {', '.join(DRIVERS)}")
    types = DRIVERS[kind]
    if type_name not in types:
        raise ValueError(
            f"key 'type': unknown {kind} type {type_name!r}; known: {', '.join(types)}"
        )
    if backend not in BACKENDS:
        raise ValueError(
            f"key 'backend': expected one of {', '.join(map(repr, BACKENDS))}, got {backend!r}"
        )
    backends = types[type_name]
    if backend not in backends:
        raise ValueError(
            f"key 'backend': {type_name!r} has no {backend!r} driver yet; known: "
            f"{', '.join(backends)}"
        )
    return backends[backend]


def _load(reference: str) -> Any:
    module, name = reference.split(":")
    return getattr(importlib.import_module(module), name)


@dataclass(frozen=True)
class WorldSpec:
    """What the simulated world needs beyond the device files: the task's ``scene:``
    configuration (``scene_config``), the plug (``core.task_geometry.PlugGeometry``), the
    nominal hole in B (``HolePose``), the scene's ``seed`` and whether the world's clock
    follows the wall clock (``realtime``; else as fast as possible), and with ``paced``
    whether it waits for the controller (``core.clock.PacedClock``) rather than running
    on regardless (``MonotonicClock``)."""

    scene: Any
    plug: Any
    hole: Any
    seed: int
    realtime: bool = False
    paced: bool = False


@dataclass(frozen=True)
class DeviceSet:
    """A run's devices, built and not connected: the ``devices`` the loop drives, the
    ``clock`` they share, and, in simulation only, the ``world`` behind them (its truth is
    for scoring and recording; the controller never reads it). ``world`` is None on the
    real backend."""

    devices: Devices
    clock: Clock
    world: Any = None


PAD_ATTACHED = "drivers.gamepad.pad:controller_attached"
"""Whether SDL lists a game controller (the real pad's driver; pygame, the ``hw`` extra)."""

PAD_SCRIPT = "drivers.sim.twins.pad_script:load_pad_script"
"""A gamepad script for the simulated pad, read and checked (the simulator's twin)."""


def real_pad_attached() -> bool:
    """True if a real game controller is plugged in (SDL lists one)."""
    return bool(_load(PAD_ATTACHED)())


def load_pad_script(path: Path, axes: Any, buttons: Any) -> Any:
    """The simulated pad's script at ``path`` (drivers/sim/twins/pad_script.py), checked
    against the mapping's ``axes`` and ``buttons`` action names; imports the simulator's
    twin."""
    return _load(PAD_SCRIPT)(path, axes, buttons)


def scene_config(raw: Mapping[str, Any], source: str) -> Any:
    """A task's ``scene:`` mapping checked into the simulator's config dataclass
    (ConfigError naming ``source`` and the key); imports the simulator's config."""
    return build(SIM_WORLD.config_class, raw, source, prefix="scene.")


def build_device_set(
    files: Mapping[str, Path],
    backend: str,
    world: WorldSpec | None = None,
    arm_force: bool = False,
) -> DeviceSet:
    """The devices of ``files`` (kind -> device YAML, for the kinds of
    ``RUN_DEVICE_KINDS``; a missing gamepad is none) on ``backend``: each real driver on one
    ``MonotonicClock``, or the simulated world described by ``world`` with the files' twins
    (see the module doc). ``arm_force``: the run needs the arm's force reading: the twin's
    F/T sensor is switched on; a real arm's file must have it (``ft_sensor: true``).
    ConfigError for a bad file or a real arm without its force; ValueError for a sim without
    a world."""
    specs = {
        kind: load_device_config(path, backend=backend, kind=kind) for kind, path in files.items()
    }
    if arm_force:
        arm = specs["arm"]
        if backend == "real" and not arm.config.ft_sensor:
            raise ConfigError(
                f"{files['arm']}: key 'ft_sensor': this controller needs the arm's force "
                "reading; expected true (UFACTORY's F/T sensor fitted), got false"
            )
        specs["arm"] = dataclasses.replace(
            arm, config=dataclasses.replace(arm.config, ft_sensor=True)
        )
    if backend == "real":
        clock = MonotonicClock.from_now()  # the run's times start at 0
        # each kind's drivers implement its Protocol (PROTOCOLS; tests/drivers/test_registry.py)
        built = cast(_RunDevices, {kind: spec.build(clock) for kind, spec in specs.items()})
        return DeviceSet(Devices(**built), clock)
    if world is None:
        raise ValueError("backend 'sim': the simulated world needs a WorldSpec")
    build_world = _load(SIM_WORLD.device)
    configs = {kind: spec.config for kind, spec in specs.items()}
    sim = build_world(world, configs)
    return DeviceSet(Devices(sim.arm, sim.gripper, sim.tactile, sim.gamepad), sim.clock, sim)
