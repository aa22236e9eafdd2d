#!/usr/bin/env python3
"""Check the configured devices: connect each, read one sample, disconnect; one line each.

    python scripts/check_hardware.py                          # the default set (configs/)
    python scripts/check_hardware.py configs/gripper/hande.yaml --backend real

Each argument is a device YAML (see drivers/registry.py for the layout); ``--backend``
overrides the files' ``backend:`` key. Nothing moves: the arm is connected and read, the
gripper's status is read (it is not activated), the camera's newest frame, the pad's state
and the force/torque sensor's wrench are read.

Output: per device ``OK`` with a key reading, or ``FAIL`` with the driver's error and what
to check (docs/HARDWARE.md has the set-up of each device). A device that reports a fault in
its reading (an xArm error or warning code, a gripper fault) fails too. An unexpected
exception from one device is reported as a failure of that device, so the others are still
checked.

Standard output holds exactly these lines (the xArm SDK's version banner, printed when the
SDK is imported, goes to standard error).

Exit status: 0 if every device is OK, 1 if any failed, 2 for bad arguments or a bad
configuration file (one line on stderr, nothing is connected).
"""

from __future__ import annotations

import argparse
import os
import sys
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager, nullcontext, redirect_stdout
from dataclasses import dataclass
from typing import Any, NoReturn

from drivers import registry
from drivers.arm import xarm_codes
from drivers.base import Arm, ForceTorqueSensor, Gamepad, Gripper, TactileSensor
from drivers.config import CONFIG_ROOT, ConfigError, build, load_yaml
from drivers.errors import DeviceError, DeviceFaultError, DeviceNotConnectedError

DEFAULT_CONFIGS = (
    CONFIG_ROOT / "robot" / "xarm6.yaml",
    CONFIG_ROOT / "gripper" / "hande.yaml",
    CONFIG_ROOT / "sensors" / "gelsight_mini_camera.yaml",
    CONFIG_ROOT / "gamepad" / "xbox.yaml",
)
HINTS = {
    "arm": "the control box's power and emergency stop, the Ethernet link and key 'ip' "
    "(docs/HARDWARE.md, xArm6)",
    "gripper": "the gripper's 24 V supply, the RS-485 wiring and keys 'transport', 'port', "
    "'baudrate', 'slave_id' (docs/HARDWARE.md, Robotiq Hand-E)",
    "tactile": "the USB cable, membership of group 'video' and key 'by_id_pattern' "
    "(docs/HARDWARE.md, tactile cameras)",
    "gamepad": "the USB cable or Bluetooth pairing and read access to /dev/input/event* "
    "(docs/HARDWARE.md, gamepad)",
    "force_torque": "the wrench source of the simulated sensor (docs/HARDWARE.md)",
}
FRAME_MAX_AGE_S = 1.0


@dataclass(frozen=True)
class Item:
    """One device to check: its file, what the file selects, and its built config."""

    path: str
    selection: registry.Selection
    config: Any


def load_item(path: str, backend: str | None) -> Item:
    """Load and validate one device YAML; ConfigError names the file and key."""
    data = load_yaml(path)
    try:
        selection = registry.select(data, backend)
    except ValueError as exc:
        raise ConfigError(f"{path}: {exc}") from None
    return Item(path, selection, build(selection.config_class, selection.keys, source=path))


# ------------------------------------------------------------------------------- readings


def read_arm(arm: Arm) -> str:
    state = arm.read_state()
    if state.error_code or state.warning_code:
        parts = []
        if state.error_code:
            parts.append(xarm_codes.describe_controller_error(state.error_code))
        if state.warning_code:
            parts.append(xarm_codes.describe_controller_warning(state.warning_code))
        raise DeviceFaultError(arm.name, "; ".join(parts), state.error_code or state.warning_code)
    x, y, z = state.tcp.xyz_m
    return f"TCP at ({x:.3f}, {y:.3f}, {z:.3f}) m in B, mode {state.mode}, state {state.state}"


def read_gripper(gripper: Gripper) -> str:
    status = gripper.read_status()
    if status.fault_code:
        raise DeviceFaultError(gripper.name, status.fault_message, status.fault_code)
    activated = "activated" if status.activated else "not activated"
    return f"opening {status.width_m * 1e3:.1f} mm, {activated}, {status.object.name}"


def read_tactile(sensor: TactileSensor) -> str:
    frame = sensor.read_latest(max_age_s=FRAME_MAX_AGE_S)
    height, width = frame.image.shape[:2]
    return f"{width}x{height} frame, mean grey level {float(frame.image.mean()):.0f}"


def read_gamepad(pad: Gamepad) -> str:
    state = pad.read()
    if not state.connected:
        raise DeviceNotConnectedError(pad.name, "the pad went away during the check")
    pressed = [name for name, down in state.buttons.items() if down]
    return (
        f"{len(state.axes)} axes, {len(state.buttons)} buttons mapped; "
        f"pressed: {', '.join(pressed) or 'none'}"
    )


def read_force_torque(sensor: ForceTorqueSensor) -> str:
    sample = sensor.read()
    fx, fy, fz = sample.force_n
    tx, ty, tz = sample.torque_nm
    return (
        f"force ({fx:.2f}, {fy:.2f}, {fz:.2f}) N, torque ({tx:.3f}, {ty:.3f}, {tz:.3f}) N*m "
        f"in {sample.frame}"
    )


READERS: dict[str, Callable[[Any], str]] = {
    "arm": read_arm,
    "gripper": read_gripper,
    "tactile": read_tactile,
    "gamepad": read_gamepad,
    "force_torque": read_force_torque,
}


# ------------------------------------------------------------------------------- probing


@contextmanager
def tool_port(arm_config: Any) -> Iterator[Any]:
    """A connected ``XArmAPI`` to reach a Hand-E on the xArm's tool RS-485 port."""
    from xarm.wrapper import XArmAPI

    api = XArmAPI(arm_config.ip, is_radian=True, do_not_open=True)
    try:
        api.connect()
    except Exception as exc:  # the SDK raises a bare Exception ('connect socket failed')
        api.disconnect()
        raise DeviceNotConnectedError(
            arm_config.name,
            f"cannot connect to the xArm at {arm_config.ip} to reach the tool port ({exc})",
        ) from exc
    try:
        yield api
    finally:
        api.disconnect()


def probe(item: Item, arm_config: Any = None) -> tuple[bool, str]:
    """Connect, read, disconnect: (ok, reading or what went wrong)."""
    kind = item.selection.kind
    try:
        via_arm = tool_port(arm_config) if arm_config is not None else nullcontext()
        with via_arm as arm_api:
            transport = {"arm": arm_api} if kind == "gripper" else {}
            with registry.make_device(kind, item.config, **transport) as device:
                return True, READERS[kind](device)
    except DeviceError as exc:
        return False, f"{type(exc).__name__}: {exc}. Check {HINTS[kind]}"
    except Exception as exc:  # a diagnostic tool reports every failure and goes on
        return False, f"unexpected {type(exc).__name__}: {exc}. Check {HINTS[kind]}"


def tool_port_arm(item: Item, items: Sequence[Item]) -> Any:
    """The arm config through which a real Hand-E on ``transport: xarm_tool`` is reached,
    or None when the gripper does not need one."""
    selection = item.selection
    if not (
        selection.kind == "gripper"
        and selection.backend == "real"
        and item.config.transport == "xarm_tool"
    ):
        return None
    arms = [i for i in items if i.selection.kind == "arm" and i.selection.backend == "real"]
    if not arms:
        raise ConfigError(
            f"{item.path}: key 'transport': 'xarm_tool' reaches the gripper through the arm; "
            "give the arm's YAML (backend real) as well"
        )
    return arms[0].config


# ------------------------------------------------------------------------------- command line


def _shown(path: str) -> str:
    """``path`` relative to the working directory when it lies below it."""
    relative = os.path.relpath(path)
    return path if relative.startswith("..") else relative


class _Parser(argparse.ArgumentParser):
    def error(self, message: str) -> NoReturn:
        self.exit(2, f"{self.prog}: error: {message}\n")


def main(argv: Sequence[str] | None = None) -> int:
    parser = _Parser(
        prog="check_hardware",
        description="Connect each configured device, read one sample, disconnect.",
    )
    parser.add_argument(
        "configs",
        nargs="*",
        help="device YAML files (default: " + ", ".join(p.name for p in DEFAULT_CONFIGS) + ")",
    )
    parser.add_argument(
        "--backend", choices=registry.BACKENDS, help="override the files' 'backend:' key"
    )
    args = parser.parse_args(argv)
    paths = args.configs or [str(p) for p in DEFAULT_CONFIGS]
    try:
        items = [load_item(path, args.backend) for path in paths]
        arm_configs = [tool_port_arm(item, items) for item in items]
    except ConfigError as exc:
        print(f"check_hardware: error: {exc}", file=sys.stderr)
        return 2
    if any(i.selection.kind == "arm" and i.selection.backend == "real" for i in items):
        with redirect_stdout(sys.stderr):  # the SDK prints 'SDK_VERSION: ...' on import
            import xarm.wrapper  # noqa: F401
    failures = 0
    for item, arm_config in zip(items, arm_configs, strict=True):
        ok, text = probe(item, arm_config)
        failures += not ok
        selection = item.selection
        device = f"{selection.kind} {selection.type_name}/{selection.backend}"
        print(f"{'OK' if ok else 'FAIL':<4} {device:<32} {_shown(item.path)}: {text}", flush=True)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
