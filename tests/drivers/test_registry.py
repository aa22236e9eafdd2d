"""The registry: every YAML type/backend maps to its driver and config; errors list the known."""

from __future__ import annotations

import ast
import dataclasses

import pytest
import yaml

from drivers import registry
from drivers.arm import XArm6, XArm6Config
from drivers.gamepad import GamepadConfig, PygameGamepad
from drivers.gripper import HandE, HandEConfig
from drivers.sim.twins.arm import SimArm, SimArmConfig
from drivers.sim.twins.force_torque import SimForceTorque, SimForceTorqueConfig
from drivers.sim.twins.gamepad import SimGamepad, SimGamepadConfig
from drivers.sim.twins.gripper import SimGripper, SimGripperConfig
from drivers.sim.twins.tactile import SimTactileConfig, SimTactileSensor
from drivers.tactile import TactileCamera, TactileCameraConfig
from tests.drivers.device_configs import CONFIGS, load_device_config

REPO = CONFIGS.parent
DEVICE_YAMLS = {
    "arm": [CONFIGS / "robot" / "xarm6.yaml"],
    "gripper": [CONFIGS / "gripper" / "hande.yaml"],
    "tactile": sorted((CONFIGS / "sensors").glob("*_camera.yaml")),
    "gamepad": sorted((CONFIGS / "gamepad").glob("*.yaml")),
    "force_torque": sorted((CONFIGS / "force_torque").glob("*.yaml")),
}
EXPECTED = {
    ("arm", "xarm6", "real"): (XArm6, XArm6Config),
    ("arm", "xarm6", "sim"): (SimArm, SimArmConfig),
    ("gripper", "hande", "real"): (HandE, HandEConfig),
    ("gripper", "hande", "sim"): (SimGripper, SimGripperConfig),
    ("tactile", "tactile_camera", "real"): (TactileCamera, TactileCameraConfig),
    ("tactile", "tactile_camera", "sim"): (SimTactileSensor, SimTactileConfig),
    ("gamepad", "sdl_gamepad", "real"): (PygameGamepad, GamepadConfig),
    ("gamepad", "sdl_gamepad", "sim"): (SimGamepad, SimGamepadConfig),
    ("force_torque", "ft_sensor", "sim"): (SimForceTorque, SimForceTorqueConfig),
}
MAKERS = {
    "arm": registry.make_arm,
    "gripper": registry.make_gripper,
    "tactile": registry.make_tactile_sensor,
    "gamepad": registry.make_gamepad,
    "force_torque": registry.make_force_torque,
}
EXAMPLES = [(kind, path) for kind, paths in DEVICE_YAMLS.items() for path in paths]
TWINNED = [(kind, path) for kind, path in EXAMPLES if kind != "force_torque"]  # real and sim


def test_the_table_holds_exactly_the_expected_drivers():
    table = {
        (kind, type_name, backend): (driver.device_class, driver.config_class)
        for kind, types in registry.DRIVERS.items()
        for type_name, backends in types.items()
        for backend, driver in backends.items()
    }
    assert table == EXPECTED
    for (kind, type_name, backend), (_, config_class) in EXPECTED.items():
        assert registry.config_class(kind, type_name, backend) is config_class
        assert registry.kind_of(type_name) == kind


@pytest.mark.parametrize("kind", list(DEVICE_YAMLS))
def test_every_kind_has_an_example_config(kind):
    assert DEVICE_YAMLS[kind]


@pytest.mark.parametrize(("kind", "path"), EXAMPLES, ids=lambda v: getattr(v, "name", v))
def test_example_configs_default_to_sim_and_build_every_backend(kind, path):
    data = yaml.safe_load(path.read_text())
    assert data["backend"] == "sim"
    selection = registry.select(data)
    assert (selection.kind, selection.backend) == (kind, "sim")
    for backend in registry.DRIVERS[kind][data["type"]]:
        config = load_device_config(path, backend)
        device_class, config_class = EXPECTED[(kind, data["type"], backend)]
        assert type(config) is config_class
        device = MAKERS[kind](config)  # real drivers build their transport without opening it
        assert type(device) is device_class
        assert isinstance(device, registry.PROTOCOLS[kind])
        assert not device.is_connected


@pytest.mark.parametrize(("kind", "path"), TWINNED, ids=lambda v: getattr(v, "name", v))
def test_the_twin_runs_with_the_real_devices_settings(kind, path):
    real, sim = load_device_config(path, "real"), load_device_config(path, "sim")
    assert isinstance(sim, type(real))
    for field in dataclasses.fields(real):
        assert getattr(sim, field.name) == getattr(real, field.name)


def test_backend_defaults_to_sim_when_absent_and_can_be_overridden():
    data = yaml.safe_load((CONFIGS / "gripper" / "hande.yaml").read_text())
    del data["backend"]
    assert registry.select(data).config_class is SimGripperConfig
    assert "sim" in registry.select(data).keys
    real = registry.select(data, backend="real")
    assert real.config_class is HandEConfig
    assert "sim" not in real.keys and "type" not in real.keys and "backend" not in real.keys


@pytest.mark.parametrize(
    ("data", "backend", "message"),
    [
        ({"name": "x"}, None, "missing key 'type'; expected one of: xarm6, hande"),
        ({"type": "ur5"}, None, "unknown device type 'ur5'; known: xarm6, hande, tactile_camera"),
        ({"type": ["xarm6"]}, None, "key 'type': expected a device type name"),
        ({"type": "xarm6", "backend": "mujoco"}, None, "expected one of 'sim', 'real'"),
        ({"type": "xarm6", "backend": "sim"}, "gazebo", "got 'gazebo'"),
        ({"type": "ft_sensor", "backend": "real"}, None, "no 'real' driver yet; known: sim"),
    ],
)
def test_selection_errors_name_the_key_and_list_the_known(data, backend, message):
    with pytest.raises(ValueError) as err:
        registry.select(data, backend)
    assert message in str(err.value)


def test_config_class_errors_list_the_known():
    with pytest.raises(ValueError, match="unknown device kind 'robot'; known: arm, gripper"):
        registry.config_class("robot", "xarm6", "sim")
    with pytest.raises(ValueError, match="unknown gripper type 'xarm6'; known: hande"):
        registry.config_class("gripper", "xarm6", "sim")


def test_a_maker_refuses_another_kinds_config():
    gripper_config = load_device_config(CONFIGS / "gripper" / "hande.yaml")
    with pytest.raises(TypeError, match="no arm driver takes a SimGripperConfig; expected one of"):
        registry.make_arm(gripper_config)


# ------------------------------------------------------------------------------- layering


def _imports(package: str) -> set[tuple[str, str]]:
    found = set()
    for path in (REPO / package).rglob("*.py"):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Import):
                found |= {(str(path), alias.name) for alias in node.names}
            elif isinstance(node, ast.ImportFrom) and node.module:
                found.add((str(path), node.module))
    return found


def test_drivers_never_import_controller():
    assert not [(p, m) for p, m in _imports("drivers") if m.split(".")[0] == "controller"]


def test_controller_imports_only_the_driver_interfaces():
    allowed = {
        "drivers.base",
        "drivers.errors",
        "drivers.config",
        "drivers.clock",
        "drivers.tactile.profile",  # sensor geometry: a driver-level fact, not a driver
    }
    imported = _imports("controller")
    assert not [(p, m) for p, m in imported if m.startswith("drivers") and m not in allowed]
