"""Which class drives a device: the YAML's ``type:`` and ``backend:`` -> driver and config.

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

Loading (the drivers do not import ``controller``; a script joins the two)::

    data = drivers.config.load_yaml(path)
    selection = registry.select(data)                     # or select(data, backend="real")
    cfg = drivers.config.build(selection.config_class, selection.keys, source=str(path))
    with registry.make_device(selection.kind, cfg) as device: ...

``make_arm(cfg)`` etc. return the device for an already-built config, not connected; the
config's class says which driver (real or twin) to use.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, cast

from drivers.arm.xarm6 import XArm6, XArm6Config
from drivers.base import Arm, Device, ForceTorqueSensor, Gamepad, Gripper, TactileSensor
from drivers.gamepad.mapping import GamepadConfig
from drivers.gamepad.pad import PygameGamepad
from drivers.gripper.hande import HandE, HandEConfig
from drivers.sim.twins.arm import SimArm, SimArmConfig
from drivers.sim.twins.force_torque import SimForceTorque, SimForceTorqueConfig
from drivers.sim.twins.gamepad import SimGamepad, SimGamepadConfig
from drivers.sim.twins.gripper import SimGripper, SimGripperConfig
from drivers.sim.twins.tactile import SimTactileConfig, SimTactileSensor
from drivers.tactile.camera import TactileCamera, TactileCameraConfig

BACKENDS = ("sim", "real")
DEFAULT_BACKEND = "sim"
SELECTOR_KEYS = ("type", "backend")
SIM_SECTION = "sim"


@dataclass(frozen=True)
class Driver:
    """A device class and the config dataclass its ``from_config`` takes."""

    device_class: type
    config_class: type


DRIVERS: Mapping[str, Mapping[str, Mapping[str, Driver]]] = {
    "arm": {
        "xarm6": {
            "real": Driver(XArm6, XArm6Config),
            "sim": Driver(SimArm, SimArmConfig),
        },
    },
    "gripper": {
        "hande": {
            "real": Driver(HandE, HandEConfig),
            "sim": Driver(SimGripper, SimGripperConfig),
        },
    },
    "tactile": {
        "tactile_camera": {
            "real": Driver(TactileCamera, TactileCameraConfig),
            "sim": Driver(SimTactileSensor, SimTactileConfig),
        },
    },
    "gamepad": {
        "sdl_gamepad": {
            "real": Driver(PygameGamepad, GamepadConfig),
            "sim": Driver(SimGamepad, SimGamepadConfig),
        },
    },
    "force_torque": {
        "ft_sensor": {
            "sim": Driver(SimForceTorque, SimForceTorqueConfig),
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
"""kind -> the ``drivers.base`` Protocol its devices implement."""

_KIND_OF_TYPE = {type_name: kind for kind, types in DRIVERS.items() for type_name in types}
_DRIVER_OF_CONFIG = {
    (kind, driver.config_class): driver
    for kind, types in DRIVERS.items()
    for backends in types.values()
    for driver in backends.values()
}


@dataclass(frozen=True)
class Selection:
    """What a device YAML selects: its kind, type and backend, the config dataclass to build,
    and the keys to build it from (the YAML without ``type``/``backend``, and without the
    ``sim`` section for the real backend)."""

    kind: str
    type_name: str
    backend: str
    config_class: type
    keys: Mapping[str, Any]


def kind_of(type_name: str) -> str:
    """The device kind of a YAML ``type:`` (types are unique across kinds)."""
    try:
        return _KIND_OF_TYPE[type_name]
    except KeyError:
        raise ValueError(
            f"key 'type': unknown device type {type_name!r}; known: {', '.join(_KIND_OF_TYPE)}"
        ) from None


def config_class(kind: str, type_name: str, backend: str = DEFAULT_BACKEND) -> type:
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


def make_device(kind: str, config: Any, **transport: Any) -> Device:
    """The device of ``kind`` for ``config`` (real driver or twin, by the config's class),
    built by its ``from_config`` and not connected. ``transport`` passes on keyword
    arguments of ``from_config`` (the Hand-E's ``arm=``)."""
    driver = _DRIVER_OF_CONFIG.get((kind, type(config)))
    if driver is None:
        known = sorted(c.__name__ for k, c in _DRIVER_OF_CONFIG if k == kind)
        raise TypeError(
            f"no {kind} driver takes a {type(config).__name__}; expected one of: {', '.join(known)}"
        )
    return driver.device_class.from_config(config, **transport)


def make_arm(config: XArm6Config, api: Any = None) -> Arm:
    """The arm for ``config``: ``XArm6`` for an ``XArm6Config``, ``SimArm`` for a
    ``SimArmConfig``. ``api``: an ``XArmAPI``-like object to use instead of a new one (the
    twin ignores it)."""
    return cast(Arm, make_device("arm", config, api=api))


def make_gripper(config: HandEConfig, arm: Any = None) -> Gripper:
    """The gripper for ``config``. ``arm``: the connected ``XArmAPI`` when a real Hand-E uses
    the xArm tool port (``transport: xarm_tool``); the twin ignores it."""
    return cast(Gripper, make_device("gripper", config, arm=arm))


def make_tactile_sensor(config: TactileCameraConfig, capture_factory: Any = None) -> TactileSensor:
    """The tactile camera for ``config``. ``capture_factory``: opens a capture for a device
    node, instead of V4L2 (the twin ignores it)."""
    transport = {} if capture_factory is None else {"capture_factory": capture_factory}
    return cast(TactileSensor, make_device("tactile", config, **transport))


def make_gamepad(config: GamepadConfig) -> Gamepad:
    """The gamepad for ``config``."""
    return cast(Gamepad, make_device("gamepad", config))


def make_force_torque(config: SimForceTorqueConfig) -> ForceTorqueSensor:
    """The force/torque sensor for ``config`` (the twin only, for now)."""
    return cast(ForceTorqueSensor, make_device("force_torque", config))


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
