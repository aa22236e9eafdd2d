"""Device interfaces (Protocols) and the samples they exchange.

The controller depends on this module only; it never imports a concrete driver. Every
driver, real or simulated, implements one of these Protocols, is created by
``drivers.registry`` from its configuration, and has the lifecycle ``connect()``,
``disconnect()``, ``is_connected`` and use as a context manager (``with make_arm(cfg) as arm``).

Units are SI everywhere (m, rad, N, N*m, s). Frames (see docs/ARCHITECTURE.md):
``B`` the arm base, ``T`` the tool (TCP at the stick's grasp point), ``S`` the tactile
sensor. Timestamps ``t_s`` are seconds on ``time.monotonic()`` of the reading process.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, field
from enum import IntEnum
from types import TracebackType
from typing import Protocol, Self, runtime_checkable

import numpy as np

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


@dataclass(frozen=True)
class ArmState:
    """One reading of the arm. ``error_code``/``warning_code`` are the controller's own
    codes (0 = none); ``mode`` and ``state`` are the controller's motion mode and state."""

    t_s: float
    tcp: Pose
    joints_rad: tuple[float, ...]
    mode: int
    state: int
    error_code: int = 0
    warning_code: int = 0


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
    """A tactile image (uint8, H x W x 3, BGR as OpenCV delivers it) and its capture time."""

    t_s: float
    image: np.ndarray = field(repr=False)


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
    """Lifecycle shared by every device."""

    name: str

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

    def read_state(self) -> ArmState: ...

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

    def activate(self) -> None:
        """Activate without dropping a held object (reads status first)."""
        ...

    def move(self, width_m: float, speed_m_s: float, force_n: float) -> None: ...

    def read_status(self) -> GripperStatus: ...


@runtime_checkable
class TactileSensor(Device, Protocol):
    """A visuotactile camera."""

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
