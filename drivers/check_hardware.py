"""Check the configured devices: connect each, read one sample, disconnect; one line each.

    tactile check-hardware                          # the default set (configs/)
    tactile check-hardware configs/gripper/hande.yaml --backend real

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
SDK is imported, is dropped by the driver). A silent device fails within its YAML's timeouts
(the arm's ``connect_timeout_s``, the gripper's ``timeout_s`` x (1 + ``retries``), the
camera's ``connect_timeout_s``); Ctrl-C stops the check at once.

Exit status: 0 if every device is OK, 1 if any failed, 2 for bad arguments or a bad
configuration file (one line on stderr, nothing is connected), 130 when interrupted
(Ctrl-C; one line on stderr).
"""

from __future__ import annotations

import argparse
import os
import sys
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager, nullcontext
from typing import Any, NoReturn

from core.config import CONFIG_ROOT, ConfigError
from core.devices import Arm, ForceTorqueSensor, Gamepad, Gripper, TactileSensor
from core.errors import DeviceError, DeviceFaultError, DeviceNotConnectedError
from core.subcommands import job_prog
from drivers import registry
from drivers.arm import xarm_codes, xarm_sdk

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
INTERRUPTED = 130  # 128 + SIGINT, as a shell reports a process ended by Ctrl-C


# ------------------------------------------------------------------------------- readings


def read_arm(arm: Arm) -> str:
    status = arm.read_status()
    if status.error_code or status.warning_code:
        parts = []
        if status.error_code:
            parts.append(xarm_codes.describe_controller_error(status.error_code))
        if status.warning_code:
            parts.append(xarm_codes.describe_controller_warning(status.warning_code))
        code = status.error_code or status.warning_code
        raise DeviceFaultError(arm.name, "; ".join(parts), code)
    x, y, z = status.tcp.xyz_m
    return (
        f"TCP at ({x:.3f}, {y:.3f}, {z:.3f}) m in B, mode {status.mode.value}, "
        f"state {status.state.value}"
    )


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
    """A connected ``XArmAPI`` to reach a Hand-E on the xArm's tool RS-485 port, connected
    and answering within the arm's ``connect_timeout_s`` and ``io_timeout_s``. Nothing moves:
    the arm is not enabled."""
    api = xarm_sdk.InterruptibleApi(xarm_sdk.new_api(arm_config.ip))
    try:
        xarm_sdk.connect(
            api.wrapped,
            ip=arm_config.ip,
            device=f"{arm_config.name} (tool port)",
            timeout_s=arm_config.connect_timeout_s,
            io_timeout_s=arm_config.io_timeout_s,
        )
        yield api
    finally:
        api.disconnect()


def probe(spec: registry.DeviceSpec, arm_config: Any = None) -> tuple[bool, str]:
    """Connect, read, disconnect: (ok, reading or what went wrong)."""
    kind = spec.kind
    culprit = "arm"  # until the tool port's arm is reached
    try:
        via_arm = tool_port(arm_config) if arm_config is not None else nullcontext()
        with via_arm as arm_api:
            culprit = kind
            transport = {"arm": arm_api} if kind == "gripper" else {}
            with spec.build(**transport) as device:
                return True, READERS[kind](device)
    except DeviceError as exc:
        return False, f"{type(exc).__name__}: {_with_hint(str(exc), culprit)}"
    except Exception as exc:  # a diagnostic tool reports every failure and goes on
        return False, f"unexpected {type(exc).__name__}: {_with_hint(str(exc), culprit)}"


def _with_hint(message: str, kind: str) -> str:
    """The driver's message, then what to check for ``kind``, unless the driver's message
    already says what to check (a hint is given once)."""
    if "check" in message.lower():
        return message
    return f"{message}. Check {HINTS[kind]}"


def tool_port_arm(spec: registry.DeviceSpec, specs: Sequence[registry.DeviceSpec]) -> Any:
    """The arm config through which a real Hand-E on ``transport: xarm_tool`` is reached,
    or None when the gripper does not need one."""
    if not (
        spec.kind == "gripper" and spec.backend == "real" and spec.config.transport == "xarm_tool"
    ):
        return None
    arms = [s for s in specs if s.kind == "arm" and s.backend == "real"]
    if not arms:
        raise ConfigError(
            f"{spec.path}: key 'transport': 'xarm_tool' reaches the gripper through the arm; "
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
        prog=job_prog("check_hardware"),
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
        specs = [registry.load_device_config(path, args.backend) for path in paths]
        arm_configs = [tool_port_arm(spec, specs) for spec in specs]
    except ConfigError as exc:
        print(f"check_hardware: error: {exc}", file=sys.stderr)
        return 2
    failures = 0
    try:
        for spec, arm_config in zip(specs, arm_configs, strict=True):
            failures += not check(spec, arm_config)
    except KeyboardInterrupt:
        print("check_hardware: interrupted", file=sys.stderr)
        return INTERRUPTED
    return 1 if failures else 0


def check(spec: registry.DeviceSpec, arm_config: Any) -> bool:
    """Probe one device and print its line; True if it is OK."""
    ok, text = probe(spec, arm_config)
    device = f"{spec.kind} {spec.type_name}/{spec.backend}"
    print(f"{'OK' if ok else 'FAIL':<4} {device:<32} {_shown(spec.path)}: {text}", flush=True)
    return ok
