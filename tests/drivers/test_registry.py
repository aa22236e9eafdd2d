"""The registry: every YAML type/backend maps to its driver and config; errors list the known."""

from __future__ import annotations

import dataclasses
import subprocess
import sys
import textwrap

import pytest
import yaml

from core.clock import ManualClock
from core.config import CONFIG_ROOT as CONFIGS
from core.config import ConfigError
from drivers import registry
from drivers.arm import XArm6, XArm6Config
from drivers.gamepad import GamepadConfig
from drivers.gamepad.pad import PygameGamepad
from drivers.gripper import HandE, HandEConfig
from drivers.sim.twins.arm import SimArm, SimArmConfig
from drivers.sim.twins.force_torque import SimForceTorque, SimForceTorqueConfig
from drivers.sim.twins.gamepad import SimGamepad, SimGamepadConfig
from drivers.sim.twins.gripper import SimGripper, SimGripperConfig
from drivers.sim.twins.tactile import SimTactileConfig, SimTactileSensor
from drivers.tactile import TactileCamera, TactileCameraConfig

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
        spec = registry.load_device_config(path, backend)
        device_class, config_class = EXPECTED[(kind, data["type"], backend)]
        assert (spec.kind, spec.type_name, spec.backend) == (kind, data["type"], backend)
        assert type(spec.config) is config_class
        device = registry.load_device(path, backend, kind=kind)  # real transports not opened
        assert type(device) is device_class and device.config == spec.config
        assert isinstance(device, registry.PROTOCOLS[kind])
        assert not device.is_connected


@pytest.mark.parametrize(("kind", "path"), TWINNED, ids=lambda v: getattr(v, "name", v))
def test_the_twin_runs_with_the_real_devices_settings(kind, path):
    real = registry.load_device_config(path, "real").config
    sim = registry.load_device_config(path, "sim").config
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


def test_loading_refuses_a_file_of_another_kind():
    path = CONFIGS / "gripper" / "hande.yaml"
    with pytest.raises(ConfigError) as err:
        registry.load_device(path, kind="arm")
    assert str(err.value) == (
        f"{path}: key 'type': expected a device of kind 'arm' (xarm6), got 'hande' (kind 'gripper')"
    )
    with pytest.raises(ValueError, match="unknown device kind 'robot'; known: arm, gripper"):
        registry.load_device(path, kind="robot")


def test_load_errors_name_the_file_and_the_key(tmp_path):
    bad = tmp_path / "pad.yaml"
    bad.write_text("type: joystick\nbackend: sim\n")
    with pytest.raises(ConfigError, match=f"^{bad}: key 'type': unknown device type 'joystick'"):
        registry.load_device(bad)
    bad.write_text("type: xarm6\nbackend: real\nip: 1.2.3.4\n")
    with pytest.raises(ConfigError, match=f"^{bad}: missing key 'servo_rate_hz'"):
        registry.load_device_config(bad)


def test_the_clock_and_the_transport_reach_from_config():
    clock = ManualClock(7.0)
    with registry.load_device(CONFIGS / "force_torque" / "jig.yaml", clock=clock) as sensor:
        assert sensor.read().t_s == 7.0
    with registry.load_device(CONFIGS / "robot" / "xarm6.yaml", clock=clock, api=object()) as arm:
        assert isinstance(arm, SimArm) and arm.read_status().t_s == 7.0  # the twin ignores api


# ------------------------------------------------------------------------------- lazy imports

HARDWARE_LIBRARIES = ("pygame", "pymodbus", "serial", "xarm")  # the "hw" extra
SIM_ONLY = textwrap.dedent(
    """
    import importlib.abc
    import sys

    BLOCKED = set(sys.argv[1].split(","))


    class Absent(importlib.abc.MetaPathFinder):
        \"\"\"As if the hardware libraries were not installed.\"\"\"

        def find_spec(self, name, path=None, target=None):
            if name.partition(".")[0] in BLOCKED:
                raise ModuleNotFoundError(f"No module named {name!r} (blocked)", name=name)
            return None


    sys.meta_path.insert(0, Absent())

    from drivers import registry
    from core.clock import ManualClock

    READS = {
        "arm": lambda d: d.read_status(),
        "gripper": lambda d: (d.activate(), d.read_status()),
        "tactile": lambda d: d.read_latest(max_age_s=1.0),
        "gamepad": lambda d: d.read(),
        "force_torque": lambda d: d.read(),
    }
    clock = ManualClock()
    for path in sys.argv[2:]:
        spec = registry.load_device_config(path)
        assert spec.backend == "sim", path
        with spec.build(clock) as device:
            assert isinstance(device, registry.PROTOCOLS[spec.kind])
            clock.advance(0.1)
            READS[spec.kind](device)
        print(spec.kind, type(device).__name__)

    sys.argv = ["tactile", "check-hardware", *sys.argv[2:]]
    import runpy

    try:
        runpy.run_module("controller.cli.command", run_name="__main__", alter_sys=True)
    except SystemExit as end:
        print("check_hardware exit", end.code)
    print("loaded:", sorted({m.partition(".")[0] for m in sys.modules} & BLOCKED))
    """
)


def test_sim_devices_need_none_of_the_hardware_libraries():
    """Every sim device YAML builds, connects and reads with pygame, pymodbus, pyserial and
    the xArm SDK made unimportable, and check_hardware reports them all OK."""
    paths = [str(path) for _, path in EXAMPLES]
    result = subprocess.run(
        [sys.executable, "-c", SIM_ONLY, ",".join(HARDWARE_LIBRARIES), *paths],
        capture_output=True,
        text=True,
        cwd=REPO,
        timeout=120,
    )
    assert result.returncode == 0, result.stderr
    lines = result.stdout.splitlines()
    assert [line.split()[0] for line in lines[: len(paths)]] == [kind for kind, _ in EXAMPLES]
    assert sum(line.startswith("OK ") for line in lines) == len(paths)
    assert lines[-2:] == ["check_hardware exit 0", "loaded: []"]


def test_a_real_backend_needs_its_library():
    """The same block makes the real xArm's build fail on the missing SDK, so the check above
    does block what it says."""
    script = SIM_ONLY.split("from drivers import registry")[0] + textwrap.dedent(
        """
        from drivers import registry

        registry.load_device("configs/robot/xarm6.yaml", backend="real")
        """
    )
    result = subprocess.run(
        [sys.executable, "-c", script, ",".join(HARDWARE_LIBRARIES)],
        capture_output=True,
        text=True,
        cwd=REPO,
        timeout=60,
    )
    assert result.returncode == 1
    assert "No module named 'xarm' (blocked)" in result.stderr
