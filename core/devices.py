"""Device interfaces (Protocols) and the samples they exchange.

The controller depends on this module only; it never imports a concrete driver. Every
driver, real or simulated, implements one of these Protocols, is created by
``drivers.registry`` from its configuration, and has the lifecycle ``connect()``,
``disconnect()``, ``is_connected`` and use as a context manager
(``with registry.load_device("configs/robot/xarm6.yaml") as arm``).

Every device class also has ``from_config(config, clock=None, ...)``, the constructor
``drivers.registry.load_device`` calls; its transport keyword (``api=``, ``arm=``,
``capture_factory=``) lets tests and scripts pass a fake or a real protocol peer, and the
simulated twins accept and ignore it so one call builds either backend.

Units are SI everywhere (m, rad, N, N*m, s). Frames (see docs/ARCHITECTURE.md):
``B`` the arm base, ``T`` the tool (TCP at the stick's grasp point), ``S`` the tactile
sensor. Timestamps ``t_s`` are seconds on the device's injected ``Clock`` (``core.clock``,
re-exported here; ``MonotonicClock``, i.e. ``time.monotonic()``, unless one is given).
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, field
from enum import Enum, IntEnum
from types import TracebackType
from typing import Any, Protocol, Self, runtime_checkable

import numpy as np

from core.clock import Clock, ManualClock, MonotonicClock

__all__ = [
    "Arm", "ArmMode", "ArmState", "ArmStatus", "Clock", "ContextManagedDevice", "Device", "Devices",
    "ForceTorqueSensor", "Gamepad", "GamepadState", "Gripper", "GripperObject", "GripperStatus",
    "ManualClock", "MonotonicClock", "Pose", "TactileFrame", "TactileSensor", "Twist",
    "Vector3", "WrenchSample",
]  # fmt: skip

Vector3 = tuple[float, float, float]


@dataclass(frozen=True)
class Pose:
    """Pose of the tool frame T in the base frame B (``T2B``).

    ``xyz_m``: TCP position in B, metres.
    ``rpy_rad``: fixed-axis roll, pitch, yaw in radians, R = Rz(yaw) @ Ry(pitch) @ Rx(roll)
    (the xArm convention).
    """

    xyz_m: Vector3
    rpy_rad: Vector3


@dataclass(frozen=True)
class Twist:
    """TCP velocity in the base frame B: linear in m/s, angular in rad/s."""

    linear_m_s: Vector3 = (0.0, 0.0, 0.0)
    angular_rad_s: Vector3 = (0.0, 0.0, 0.0)


class ArmMode(Enum):
    """How the arm takes motion commands. Each driver maps its controller's mode codes to
    these at its boundary (the xArm's in ``drivers.arm.xarm_codes``)."""

    POSITION = "position"  # point-to-point moves: Arm.move_to
    SERVO = "servo"  # streamed Cartesian servo targets: Arm.servo_pose
    VELOCITY = "velocity"  # Cartesian velocity with a watchdog: Arm.move_velocity
    MANUAL = "manual"  # hand-guided (teaching) mode, set on the controller itself
    OTHER = "other"  # a mode this interface never commands (e.g. joint velocity)


class ArmState(Enum):
    """What the arm's motion is doing. Each driver maps its controller's state codes to these
    at its boundary (the xArm's in ``drivers.arm.xarm_codes``)."""

    MOVING = "moving"  # executing a motion command
    READY = "ready"  # armed and at rest: motion commands are accepted
    PAUSED = "paused"  # a motion was suspended (from the controller's pendant or app)
    STOPPED = "stopped"  # not armed (after a stop, a fault or start-up): commands re-arm it
    UNKNOWN = "unknown"  # a state code this interface does not know


@dataclass(frozen=True)
class ArmStatus:
    """One reading of the arm: TCP pose in B, joint angles (rad), the motion ``mode`` and
    ``state``, and the controller's own ``error_code``/``warning_code`` (0 = none; look them
    up in the vendor's manual, as the gripper's fault codes).

    ``external_force_n``: the external force on the tool, in B, N, as the arm measures it at
    its flange (the force the environment applies to whatever hangs below the flange: on
    our cell the compliant wrist, the gripper and the plug), the tool's own weight
    compensated; None when the arm has no force reading (no force/torque sensor fitted or
    enabled)."""

    t_s: float
    tcp: Pose
    joints_rad: tuple[float, ...]
    mode: ArmMode
    state: ArmState
    error_code: int = 0
    warning_code: int = 0
    external_force_n: Vector3 | None = None


class GripperObject(IntEnum):
    """Object detection status (Robotiq gOBJ)."""

    MOVING = 0  # fingers moving toward the target, no object detected
    CONTACT_OPENING = 1  # stopped by an object while opening
    CONTACT_CLOSING = 2  # stopped by an object while closing: an object is held
    AT_TARGET = 3  # reached the target position, no object


@dataclass(frozen=True)
class GripperStatus:
    """One reading of the gripper. ``width_m`` is the finger opening in metres;
    ``fault_code`` is the device's own fault code (0 = none) and ``fault_message`` its meaning."""

    t_s: float
    activated: bool
    moving: bool
    object: GripperObject
    width_m: float
    fault_code: int = 0
    fault_message: str = ""

    @property
    def holding(self) -> bool:
        """True when the fingers stopped on an object while closing."""
        return self.object is GripperObject.CONTACT_CLOSING


@dataclass(frozen=True)
class TactileFrame:
    """A tactile image (uint8, H x W x 3, BGR as OpenCV delivers it) and its capture time;
    ``jpeg``: the same image compressed as JPEG by the camera's driver, when it was asked to
    (``compress_frames`` of the camera and its simulated twin: for an episode), else None.
    The estimator takes ``image``."""

    t_s: float
    image: np.ndarray = field(repr=False)
    jpeg: bytes | None = field(default=None, repr=False)


@dataclass(frozen=True)
class GamepadState:
    """Gamepad input by name: axes in [-1, 1] after the dead zone, buttons pressed or not."""

    t_s: float
    connected: bool
    axes: dict[str, float]
    buttons: dict[str, bool]

    @classmethod
    def unplugged(cls, t_s: float, axes: Iterable[str], buttons: Iterable[str]) -> GamepadState:
        """The safe state with no pad: every named axis at zero, every button released."""
        return cls(
            t_s=t_s,
            connected=False,
            axes=dict.fromkeys(axes, 0.0),
            buttons=dict.fromkeys(buttons, False),
        )


@dataclass(frozen=True)
class WrenchSample:
    """A force/torque reading: force in N and torque in N*m, both in the named frame."""

    t_s: float
    force_n: Vector3
    torque_nm: Vector3
    frame: str


class ContextManagedDevice:
    """Mixin for drivers: ``with device:`` connects on entry and disconnects on exit, also
    when the body raises. The driver provides ``connect()`` and ``disconnect()``."""

    def connect(self) -> None:
        raise NotImplementedError

    def disconnect(self) -> None:
        raise NotImplementedError

    def __enter__(self) -> Self:
        self.connect()
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self.disconnect()


@runtime_checkable
class Device(Protocol):
    """Lifecycle shared by every device, and its constructor from configuration."""

    name: str

    @classmethod
    def from_config(cls, config: Any, clock: Clock | None = None) -> Self:
        """The device for ``config`` (its driver's config dataclass), not connected, reading
        time from ``clock`` (``MonotonicClock`` when None)."""
        ...

    def connect(self) -> None: ...

    def disconnect(self) -> None: ...

    @property
    def is_connected(self) -> bool: ...

    def __enter__(self) -> Self: ...

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None: ...


@runtime_checkable
class Arm(Device, Protocol):
    """A 6-axis arm commanded at its TCP (frame T) in its base frame B."""

    @classmethod
    def from_config(cls, config: Any, clock: Clock | None = None, api: Any = None) -> Self:
        """``api``: the controller's SDK object to drive instead of a new one."""
        ...

    def read_status(self) -> ArmStatus: ...

    def move_to(self, target: Pose, speed_m_s: float, wait: bool = True) -> None:
        """Position move (approach); blocks until reached when ``wait``."""
        ...

    def servo_pose(self, target: Pose) -> None:
        """Stream one Cartesian servo target; the step from the last target is bounded."""
        ...

    def move_velocity(self, twist: Twist, duration_s: float) -> None:
        """Cartesian velocity command that stops by itself after ``duration_s`` (watchdog)."""
        ...

    def stop(self) -> None:
        """Controlled stop: zero velocity, hold position."""
        ...

    def emergency_stop(self) -> None: ...

    def clear_fault(self) -> None:
        """Documented recovery: clear the error, then re-enable motion."""
        ...


@runtime_checkable
class Gripper(Device, Protocol):
    """A parallel gripper commanded by finger opening."""

    @classmethod
    def from_config(cls, config: Any, clock: Clock | None = None, arm: Any = None) -> Self:
        """``arm``: the connected arm SDK object, for a gripper on the arm's tool port."""
        ...

    def activate(self) -> None:
        """Activate without dropping a held object (reads status first)."""
        ...

    def move(self, width_m: float, speed_m_s: float, force_n: float) -> None: ...

    def read_status(self) -> GripperStatus: ...


@runtime_checkable
class TactileSensor(Device, Protocol):
    """A visuotactile camera."""

    @classmethod
    def from_config(
        cls, config: Any, clock: Clock | None = None, capture_factory: Any = None
    ) -> Self:
        """``capture_factory``: opens a capture for a device node, instead of V4L2."""
        ...

    def read_latest(self, max_age_s: float) -> TactileFrame:
        """The newest frame; raises DeviceTimeoutError if it is older than ``max_age_s``."""
        ...


@runtime_checkable
class Gamepad(Device, Protocol):
    """A game controller read through named axes and buttons."""

    def read(self) -> GamepadState: ...


@runtime_checkable
class ForceTorqueSensor(Device, Protocol):
    """A 6-axis force/torque sensor (calibration jig ground truth)."""

    def read(self) -> WrenchSample: ...


@dataclass(frozen=True)
class Devices:
    """The devices one run drives, each behind its Protocol (the caller connects them):
    the control loop's inputs and outputs. ``gamepad`` is None when the task names none."""

    arm: Arm
    gripper: Gripper
    tactile: TactileSensor
    gamepad: Gamepad | None = None

    def named(self) -> tuple[tuple[str, Device], ...]:
        """(role, device) of the devices present, arm first (the order they connect in)."""
        roles = (("arm", self.arm), ("gripper", self.gripper), ("tactile", self.tactile),
                 ("gamepad", self.gamepad))  # fmt: skip
        return tuple((role, device) for role, device in roles if device is not None)
