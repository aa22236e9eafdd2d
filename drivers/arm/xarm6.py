"""UFACTORY xArm6 driver (implements ``core.devices.Arm``) over xarm-python-sdk's ``XArmAPI``.

Units. Our side is SI in the base frame B (m, rad, m/s, rad/s). The SDK speaks mm and,
for angles, degrees or radians depending on ``is_radian``. ``from_config`` builds
``XArmAPI(ip, is_radian=True, do_not_open=True)`` and every call passes ``is_radian=True``
explicitly, so angles cross unchanged (no degree round-off) and the only conversion is
m <-> mm, done here and nowhere else. Mode and state codes become ``ArmMode``/``ArmState``
here too (``drivers.arm.xarm_codes``).

Modes. ``move_to`` uses mode 0 (position, ``set_position``), ``servo_pose`` mode 1 (servo
Cartesian, ``set_servo_cartesian``), ``move_velocity`` mode 5 (Cartesian velocity,
``vc_set_cartesian_velocity`` always with a positive ``duration``, the controller's
watchdog). Entering a mode runs ``motion_enable(True)``, ``set_mode(m)``, ``set_state(0)``,
the order the SDK documents (``XArmAPI.clean_error``/``set_mode`` docstrings).

Silence and Ctrl-C (``drivers.arm.xarm_sdk``). ``connect()`` gives up after
``connect_timeout_s`` (DeviceTimeoutError) even when the controller accepts the TCP
connection and never replies; every reply is then awaited at most ``io_timeout_s``
(API code 3: DeviceTimeoutError), a waited move at most ``move_timeout_s``. SDK calls made
from the main thread wait interruptibly, so Ctrl-C always raises KeyboardInterrupt at once.

Safety envelope. Every target, step and twist passes through ``drivers.arm.arm_envelope``
(the clamps of ``core.envelope``) before it reaches the SDK (see those modules for the
policy). Servo streams start from the measured pose (projected into the envelope; refused
if the arm is more than 1 mm / 0.01 rad outside); the step per command is bounded by
``max_step_m``/``max_step_rad`` and by the maximum speeds times the time since the previous
command.

Faults. Every ``(code, value)`` or ``code`` the SDK returns is checked: -1 raises
DeviceNotConnectedError, reply/motion timeouts (3, 100) DeviceTimeoutError, anything else
DeviceFaultError; each carries the SDK code and its documented meaning. The SDK's
error/warning callback (and any failed motion command) latches a fault and stops the arm
(``set_state(4)``); until ``clear_fault()`` every motion command raises DeviceFaultError.
Any controller warning counts as a fault: the controller reports rejected commands as
warnings (e.g. W14, no solution), so the arm is not where it was told to be.
``read_status`` still works while faulted and reports the controller's codes.
"""

from __future__ import annotations

import ipaddress
import logging
import math
import threading
from collections.abc import Sequence
from typing import Any

import numpy as np

from core.clock import Clock, MonotonicClock
from core.config import Config, config_dataclass, number
from core.devices import ArmMode, ArmStatus, ContextManagedDevice, Pose, Twist, Vector3
from core.envelope import clamp_pose, limit_twist, require_finite
from core.errors import (
    DeviceError,
    DeviceFaultError,
    DeviceNotConnectedError,
    DeviceTimeoutError,
)
from core.spatial import rotation_from_rpy
from drivers.arm import xarm_codes, xarm_sdk
from drivers.arm.arm_envelope import SafetyEnvelope, timed_servo_target

_LOG = logging.getLogger(__name__)

MM_PER_M = 1000.0
MIN_VELOCITY_FIRMWARE = (1, 8, 0)  # vc_set_cartesian_velocity ignores duration before this
_ENTRY_TOLERANCE_M = 1e-3
_ENTRY_TOLERANCE_RAD = 1e-2


@config_dataclass
class TcpConfig(Config):
    """The tool on the flange (compliant wrist + gripper + plug).

    ``offset_*``: pose of the TCP (frame T) in the flange frame, xyz in m, rpy in rad.
    ``load_mass_kg`` and ``load_com_*_m``: mass of everything on the flange and its centre
    of mass in the flange frame, m.
    """

    offset_x_m: float = number(-0.5, 0.5)
    offset_y_m: float = number(-0.5, 0.5)
    offset_z_m: float = number(-0.5, 0.5)
    offset_roll_rad: float = number(-math.pi, math.pi)
    offset_pitch_rad: float = number(-math.pi, math.pi)
    offset_yaw_rad: float = number(-math.pi, math.pi)
    load_mass_kg: float = number(0.0, 5.0)  # xArm6 payload: 5 kg
    load_com_x_m: float = number(-0.5, 0.5)
    load_com_y_m: float = number(-0.5, 0.5)
    load_com_z_m: float = number(-0.5, 0.5)


@config_dataclass
class XArm6Config(Config):
    """Configuration of the xArm6 driver (``configs/robot/xarm6.yaml``).

    ``ip``: the control box's IPv4 address. ``servo_rate_hz``: nominal servo streaming rate
    (50-200 Hz), the step budget of the first command of a stream. ``velocity_timeout_s``:
    the longest a velocity command may be held (watchdog ceiling). ``move_timeout_s``: the
    longest a waited position move may take. ``connect_timeout_s``: the longest
    ``connect()`` waits for the controller to answer. ``io_timeout_s``: the longest any
    request waits for its reply. ``ft_sensor``: UFACTORY's six-axis force/torque sensor is
    fitted at the flange; ``connect()`` enables it (``set_ft_sensor_enable(1)``) and
    ``read_status()`` reports its filtered, load-compensated force
    (``get_ft_sensor_data()``, N) turned into B as ``ArmStatus.external_force_n``, its axes
    taken as the flange's (T's without the TCP offset's rotation; UFACTORY does not document
    the frame: check the sign on the robot with a known push).
    """

    ip: str
    servo_rate_hz: float = number(50, 200)
    velocity_timeout_s: float = number(0.01, 1.0)
    move_timeout_s: float = number(0.1, 300.0)
    tcp: TcpConfig
    envelope: SafetyEnvelope
    name: str = "xarm6"
    connect_timeout_s: float = number(0.5, 60.0, default=5.0)
    io_timeout_s: float = number(0.05, 10.0, default=2.0)
    ft_sensor: bool = False

    def __post_init__(self) -> None:
        try:
            ipaddress.IPv4Address(self.ip)
        except (ipaddress.AddressValueError, TypeError):
            raise ValueError(
                f"key 'ip': expected an IPv4 address like '192.168.1.185', got {self.ip!r}"
            ) from None


class XArm6(ContextManagedDevice):
    """An xArm6 commanded at its TCP in B. ``api`` is an ``xarm.wrapper.XArmAPI`` (or a
    faithful fake) not yet connected; ``clock`` stamps readings and times the servo step
    budget (``MonotonicClock`` when None)."""

    def __init__(self, config: XArm6Config, api: Any, clock: Clock | None = None) -> None:
        self.config = config
        self.name = config.name
        self._api = xarm_sdk.InterruptibleApi(api)
        self._clock = clock if clock is not None else MonotonicClock()
        self._fault_lock = threading.Lock()
        self._fault: DeviceFaultError | None = None
        self._mode: ArmMode | None = None  # None: not armed (after connect failure or a stop)
        self._servo_reference: Pose | None = None
        self._servo_time_s: float | None = None

    @classmethod
    def from_config(cls, config: XArm6Config, clock: Clock | None = None, api: Any = None) -> XArm6:
        """The driver over ``api``, by default a real ``XArmAPI`` for ``config.ip`` (not
        connected yet)."""
        return cls(config, api if api is not None else xarm_sdk.new_api(config.ip), clock)

    @property
    def api(self) -> xarm_sdk.InterruptibleApi:
        """The SDK object (calls interruptible): what a Hand-E on the tool port talks through
        (``HandE.from_config(config, arm=xarm6.api)``)."""
        return self._api

    # ----------------------------------------------------------------- lifecycle

    @property
    def is_connected(self) -> bool:
        return bool(self._api.connected)

    @property
    def fault(self) -> DeviceFaultError | None:
        """The latched fault, or None. Motion commands raise while one is latched."""
        with self._fault_lock:
            return self._fault

    def connect(self) -> None:
        """Open the connection, read the controller's codes, arm mode 0 and set the TCP.

        Raises DeviceNotConnectedError when the controller cannot be reached and
        DeviceTimeoutError when it does not answer within ``connect_timeout_s``. A
        controller error or warning found here is latched (not raised): the arm stays
        unarmed and the first motion command says to call ``clear_fault()``.
        """
        if self.is_connected:
            return
        cfg = self.config
        self._api.register_error_warn_changed_callback(self._on_error_warn)
        try:
            xarm_sdk.connect(
                self._api.wrapped,
                ip=cfg.ip,
                device=self.name,
                timeout_s=cfg.connect_timeout_s,
                io_timeout_s=cfg.io_timeout_s,
            )
        except BaseException:
            self._api.release_error_warn_changed_callback(self._on_error_warn)
            self._api.disconnect()  # closes the socket the SDK opened and left behind
            raise
        try:
            if not self.is_connected:
                raise DeviceNotConnectedError(
                    self.name, f"no connection to the controller at {self.config.ip}"
                )
            error, warning = self._read_controller_codes()
            if error or warning:
                self._latch(self._controller_fault(error, warning))
            if cfg.ft_sensor:
                self._check(self._api.set_ft_sensor_enable(1), "set_ft_sensor_enable(1)")
            if self.fault is None:
                self._arm(ArmMode.POSITION)
                self._configure_tcp()
        except BaseException:
            self.disconnect()
            raise

    def disconnect(self) -> None:
        """Stop any motion (best effort), release the SDK callback and close. Idempotent."""
        if self.is_connected:
            code = self._api.set_state(xarm_codes.SET_STATE_STOP)
            if code != 0:
                _LOG.warning(
                    "%s: stop before disconnect: %s", self.name, xarm_codes.describe_api_code(code)
                )
        self._api.release_error_warn_changed_callback(self._on_error_warn)
        self._api.disconnect()
        self._mode = None

    # ----------------------------------------------------------------- reading

    def read_status(self) -> ArmStatus:
        """TCP pose in B (m, rad), joint angles (rad), mode, state, the controller's
        error/warning codes and, with ``ft_sensor``, the external force in B (N). Works while
        a fault is latched."""
        self._require_connected()
        tcp = self._read_pose()
        t_s = self._clock.now()
        code, joints = self._api.get_servo_angle(is_radian=True)
        self._check_reply(code, joints, "get_servo_angle(is_radian=True)")
        force = self._read_external_force(tcp) if self.config.ft_sensor else None
        return ArmStatus(
            t_s=t_s,
            tcp=tcp,
            joints_rad=tuple(float(q) for q in joints[:6]),
            mode=xarm_codes.mode_from_code(int(self._api.mode)),
            state=xarm_codes.state_from_code(int(self._api.state)),
            error_code=int(self._api.error_code),
            warning_code=int(self._api.warn_code),
            external_force_n=force,
        )

    # ----------------------------------------------------------------- motion

    def move_to(self, target: Pose, speed_m_s: float, wait: bool = True) -> None:
        """Linear move (mode 0) to ``target`` clamped into the envelope, at ``speed_m_s``
        limited to the envelope's maximum; waits up to ``move_timeout_s`` when ``wait``."""
        require_finite("target", (*target.xyz_m, *target.rpy_rad))
        if not math.isfinite(speed_m_s) or speed_m_s <= 0:
            raise ValueError(f"speed_m_s: expected a positive number, got {speed_m_s!r}")
        self._prepare_motion()
        goal = clamp_pose(target, self.config.envelope).value
        speed = min(speed_m_s, self.config.envelope.max_linear_speed_m_s)
        self._enter_mode(ArmMode.POSITION)
        x, y, z, roll, pitch, yaw = _sdk_pose(goal)
        code = self._api.set_position(
            x=x, y=y, z=z, roll=roll, pitch=pitch, yaw=yaw,
            speed=speed * MM_PER_M, is_radian=True, wait=wait,
            timeout=self.config.move_timeout_s if wait else None,
        )  # fmt: skip
        self._check_motion(code, "set_position")

    def servo_pose(self, target: Pose) -> None:
        """Stream one servo target (mode 1), clamped into the envelope and stepped from the
        previous command by at most the step bounds (and speed x elapsed time)."""
        require_finite("target", (*target.xyz_m, *target.rpy_rad))
        self._prepare_motion()
        self._enter_mode(ArmMode.SERVO)
        env = self.config.envelope
        now = self._clock.now()
        command = timed_servo_target(
            self._servo_reference,
            target,
            env,
            self._servo_time_s,
            now,
            self.config.servo_rate_hz,
        )
        code = self._api.set_servo_cartesian(
            _sdk_pose(command), is_radian=True, is_tool_coord=False
        )
        self._check_motion(code, "set_servo_cartesian")
        self._servo_reference = command
        self._servo_time_s = now

    def move_velocity(self, twist: Twist, duration_s: float) -> None:
        """Cartesian velocity (mode 5, in B) held for at most ``duration_s`` (capped at
        ``velocity_timeout_s``), after which the controller stops by itself."""
        require_finite("twist", (*twist.linear_m_s, *twist.angular_rad_s))
        if not math.isfinite(duration_s) or duration_s <= 0:
            raise ValueError(
                f"duration_s: expected a positive number (the SDK reads 0 as 'never stop'), "
                f"got {duration_s!r}"
            )
        self._prepare_motion()
        duration = min(duration_s, self.config.velocity_timeout_s)
        self._enter_mode(ArmMode.VELOCITY)
        command = limit_twist(twist, self._read_pose(), duration, self.config.envelope).value
        code = self._api.vc_set_cartesian_velocity(
            _sdk_twist(command), is_radian=True, is_tool_coord=False, duration=duration
        )
        self._check_motion(code, "vc_set_cartesian_velocity")

    def stop(self) -> None:
        """Controlled stop: zero velocity in mode 5; otherwise ``set_state(4)`` (which also
        drops queued moves) and re-arm the same mode so the arm holds its position. While a
        fault is latched it only stops (``set_state(4)``) and stays unarmed."""
        self._require_connected()
        if self.fault is not None or self._mode is None:
            self._safe_stop()
        elif self._mode is ArmMode.VELOCITY:
            code = self._api.vc_set_cartesian_velocity(
                [0.0] * 6, is_radian=True, is_tool_coord=False,
                duration=self.config.velocity_timeout_s,
            )  # fmt: skip
            self._check_motion(code, "vc_set_cartesian_velocity(zero)")
        else:
            mode = self._mode
            self._check(self._api.set_state(xarm_codes.SET_STATE_STOP), "set_state(4)")
            self._arm(mode)

    def emergency_stop(self) -> None:
        """The SDK's emergency stop (state 4, queue flushed); latches a fault so motion
        needs ``clear_fault()``. Raises DeviceFaultError if the controller does not
        confirm state 4."""
        self._require_connected()
        self._api.emergency_stop()  # returns None (xarm/x3/xarm.py: XArm.emergency_stop)
        self._mode = None
        self._latch(DeviceFaultError(self.name, "emergency stop requested; call clear_fault()"))
        state = self._api.state
        if state != xarm_codes.STATE_STOPPED:
            raise DeviceFaultError(
                self.name, f"emergency stop not confirmed: controller state {state}, expected 4"
            )

    def clear_fault(self) -> None:
        """Documented recovery: ``clean_error``, ``clean_warn``, check the codes are gone,
        then ``motion_enable(True)``, ``set_mode(0)``, ``set_state(0)`` and the TCP again."""
        self._require_connected()
        # clean_error/clean_warn return the raw reply flag (not passed through the SDK's
        # _check_code), so 1/2 only say an error/warning was present; the codes are read next.
        flags = (0, xarm_codes.HAS_ERROR, xarm_codes.HAS_WARNING)
        code = self._api.clean_error()
        if code not in flags:
            self._check(code, "clean_error")
        code = self._api.clean_warn()
        if code not in flags:
            self._check(code, "clean_warn")
        error, warning = self._read_controller_codes()
        if error or warning:
            fault = self._controller_fault(error, warning)
            raise DeviceFaultError(
                self.name, f"fault persists after clearing: {fault.message}", fault.code
            )
        with self._fault_lock:
            self._fault = None
        self._arm(ArmMode.POSITION)
        self._configure_tcp()

    # ----------------------------------------------------------------- internals

    def _arm(self, mode: ArmMode) -> None:
        self._mode = None
        self._servo_reference = None
        self._servo_time_s = None
        code = xarm_codes.MODE_CODES[mode]
        self._check(self._api.motion_enable(enable=True), "motion_enable(True)")
        self._check(self._api.set_mode(code), f"set_mode({code})")
        self._check(self._api.set_state(xarm_codes.SET_STATE_READY), "set_state(0)")
        self._mode = mode

    def _enter_mode(self, mode: ArmMode) -> None:
        if mode is ArmMode.VELOCITY and tuple(self._api.version_number) < MIN_VELOCITY_FIRMWARE:
            raise DeviceFaultError(
                self.name,
                f"firmware {self._api.version_number} ignores the velocity watchdog duration "
                "(needs >= 1.8.0); refusing velocity mode",
            )
        if self._mode != mode:
            self._arm(mode)
        if mode is ArmMode.SERVO and self._servo_reference is None:
            measured = self._read_pose()
            start = clamp_pose(measured, self.config.envelope).value
            offset_m = float(np.linalg.norm(np.subtract(measured.xyz_m, start.xyz_m)))
            turn = rotation_from_rpy(start.rpy_rad) * rotation_from_rpy(measured.rpy_rad).inv()
            if offset_m > _ENTRY_TOLERANCE_M or turn.magnitude() > _ENTRY_TOLERANCE_RAD:
                raise DeviceFaultError(
                    self.name,
                    f"TCP at {measured} is outside the safety envelope; bring it inside with "
                    "move_to() before streaming servo targets",
                )
            self._servo_reference = start

    def _configure_tcp(self) -> None:
        tcp = self.config.tcp
        offset = [
            tcp.offset_x_m * MM_PER_M, tcp.offset_y_m * MM_PER_M, tcp.offset_z_m * MM_PER_M,
            tcp.offset_roll_rad, tcp.offset_pitch_rad, tcp.offset_yaw_rad,
        ]  # fmt: skip
        self._check(self._api.set_tcp_offset(offset, is_radian=True, wait=True), "set_tcp_offset")
        com_mm = [
            tcp.load_com_x_m * MM_PER_M,
            tcp.load_com_y_m * MM_PER_M,
            tcp.load_com_z_m * MM_PER_M,
        ]
        self._check(self._api.set_tcp_load(tcp.load_mass_kg, com_mm, wait=True), "set_tcp_load")

    def _read_pose(self) -> Pose:
        code, pose = self._api.get_position(is_radian=True)
        self._check_reply(code, pose, "get_position(is_radian=True)")
        return _pose_from_sdk(pose)

    def _read_external_force(self, tcp: Pose) -> Vector3:
        """The F/T sensor's force (``get_ft_sensor_data()``: Fx, Fy, Fz in N, then torques,
        in the flange's axes) turned into B with the flange's rotation at ``tcp``."""
        code, wrench = self._api.get_ft_sensor_data()
        self._check_reply(code, wrench, "get_ft_sensor_data()")
        offset = self.config.tcp
        tcp_in_flange = rotation_from_rpy(
            (offset.offset_roll_rad, offset.offset_pitch_rad, offset.offset_yaw_rad)
        )
        flange = rotation_from_rpy(tcp.rpy_rad) * tcp_in_flange.inv()
        fx, fy, fz = (float(v) for v in flange.apply([float(v) for v in wrench[:3]]))
        return (fx, fy, fz)

    def _read_controller_codes(self) -> tuple[int, int]:
        code, codes = self._api.get_err_warn_code()
        self._check(code, "get_err_warn_code")
        error, warning = codes
        return int(error), int(warning)

    def _require_connected(self) -> None:
        if not self.is_connected:
            raise DeviceNotConnectedError(self.name, "not connected; call connect() first")

    def _prepare_motion(self) -> None:
        self._require_connected()
        fault = self.fault
        if fault is not None:
            raise DeviceFaultError(
                self.name, f"fault latched, call clear_fault(): {fault.message}", fault.code
            )

    def _check(self, code: int, what: str) -> None:
        if code != 0:
            raise self._error_for_code(code, what)

    def _check_reply(self, code: int, value: object, what: str) -> None:
        """A getter's ``(code, value)``: the value is a list only when the code is 0 (when
        not connected the SDK returns ``(-1, 'xArm is not connect')``)."""
        self._check(code, what)
        if not isinstance(value, Sequence) or isinstance(value, str) or len(value) < 6:
            raise DeviceFaultError(
                self.name, f"{what} returned {value!r}, expected 6 or more numbers"
            )

    def _check_motion(self, code: int, what: str) -> None:
        """A motion command's code: on failure stop the arm, latch faults, and raise."""
        if code == 0:
            return
        error = self._error_for_code(code, what)
        if isinstance(error, DeviceFaultError):
            self._latch(error)
        self._safe_stop()
        raise error

    def _error_for_code(self, code: int, what: str) -> DeviceError:
        text = f"{what} failed, {xarm_codes.describe_api_code(code)}"
        if code == xarm_codes.NOT_CONNECTED:
            return DeviceNotConnectedError(
                self.name, f"{text}; check the Ethernet link to {self.config.ip}", code
            )
        if code in (xarm_codes.REPLY_TIMEOUT, xarm_codes.WAIT_FINISH_TIMEOUT):
            return DeviceTimeoutError(self.name, text, code)
        if code in (xarm_codes.HAS_ERROR, xarm_codes.HAS_WARNING):
            error, warning = int(self._api.error_code), int(self._api.warn_code)
            if error or warning:
                text = f"{text}; {self._controller_fault(error, warning).message}"
        return DeviceFaultError(self.name, text, code)

    def _controller_fault(self, error: int, warning: int) -> DeviceFaultError:
        parts = [xarm_codes.describe_controller_error(error)] if error else []
        if warning:
            parts.append(xarm_codes.describe_controller_warning(warning))
        parts.append("the arm was stopped; remove the cause, then call clear_fault()")
        return DeviceFaultError(self.name, "; ".join(parts), error or warning)

    def _on_error_warn(self, item: dict[str, int]) -> None:
        """The SDK's error/warning-changed callback (runs on the SDK's report thread)."""
        error, warning = int(item.get("error_code", 0)), int(item.get("warn_code", 0))
        if error or warning:
            self._latch(self._controller_fault(error, warning))
            self._safe_stop()

    def _latch(self, fault: DeviceFaultError) -> None:
        with self._fault_lock:
            if self._fault is None:  # keep the first fault: the root cause
                self._fault = fault

    def _safe_stop(self) -> None:
        """Best effort, never raises: stop the arm (state 4); it stays unarmed."""
        self._mode = None
        code = self._api.set_state(xarm_codes.SET_STATE_STOP)
        if code != 0:
            _LOG.warning("%s: safe stop failed: %s", self.name, xarm_codes.describe_api_code(code))


def _sdk_pose(pose: Pose) -> list[float]:
    """Pose (m, rad) -> the SDK's [x, y, z (mm), roll, pitch, yaw (rad)]."""
    return [*(float(v) * MM_PER_M for v in pose.xyz_m), *(float(a) for a in pose.rpy_rad)]


def _pose_from_sdk(values: Sequence[float]) -> Pose:
    """The SDK's [x, y, z (mm), roll, pitch, yaw (rad)] -> Pose (m, rad)."""
    x, y, z, roll, pitch, yaw = (float(v) for v in values[:6])
    return Pose((x / MM_PER_M, y / MM_PER_M, z / MM_PER_M), (roll, pitch, yaw))


def _sdk_twist(twist: Twist) -> list[float]:
    """Twist (m/s, rad/s) -> the SDK's [vx, vy, vz (mm/s), wx, wy, wz (rad/s)]."""
    return [
        *(float(v) * MM_PER_M for v in twist.linear_m_s),
        *(float(w) for w in twist.angular_rad_s),
    ]
