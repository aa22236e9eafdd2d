"""Simulated twin of the xArm6 (implements ``core.devices.Arm``): a TCP that tracks commands.

What is modelled. The TCP (frame T) as a rigid body moving in the base frame B with a linear
velocity and an angular velocity, each limited in magnitude (the envelope's
``max_linear_speed_m_s`` / ``max_angular_speed_rad_s``) and in rate of change (the ``sim:``
section's ``max_accel_m_s2`` / ``max_angular_accel_rad_s2``, limits on the norm). There is
no joint model: ``ArmState.joints_rad`` holds six NaNs.

Commands go through the same ``core.envelope`` clamps as in ``drivers.arm.xarm6`` and in
the same way (``move_to``: ``clamp_pose`` and the speed capped at the envelope's;
``servo_pose``: ``limit_pose`` with the step budget min(max step, max speed x time since
the previous command); ``move_velocity``: ``limit_twist`` over ``min(duration_s,
velocity_timeout_s)``), then the TCP tracks the result:

* position and servo targets: straight toward the goal (along the geodesic for the
  orientation) at the allowed speed, slowing down so as to stop at the goal;
* velocity: the clamped twist until the watchdog deadline, then zero.

The twin also keeps the TCP inside the envelope whatever the command stream, braking
before the faces of the box and the tilt limit (``drivers.sim.twins.tcp_motion``), so no
overshoot of a clamped target leaves the envelope.

Time. The state is integrated in fixed steps of ``1 / control_rate_hz`` up to the injected
clock's ``now()`` at the start of every call (see ``core.clock``). ``move_to`` with
``wait=True`` sleeps on the clock until the goal is reached, or raises DeviceTimeoutError
(code 100, as the SDK's wait) after ``move_timeout_s``. ``ArmState.t_s`` is the time of the
last integration step.

Force. With ``ft_sensor`` (the arm YAML's key, as for the real driver)
``ArmStatus.external_force_n`` is the force of the attached **force source**
(``attach_force_source``: a callable giving the external force on the tool in B, N; the
insertion world attaches the wrist's reaction on the flange) at the time of the reading,
plus independent Gaussian noise per component (``sim.force_noise_n``) drawn from the
generator attached with it; the zero force before one is attached. Without ``ft_sensor``
it is None, as on an arm without the sensor.

Errors and states are the real driver's: DeviceNotConnectedError before ``connect()``;
``emergency_stop()`` and ``inject_fault()`` latch a DeviceFaultError that motion commands
raise until ``clear_fault()``. ``ArmStatus.mode`` is ``ArmMode.POSITION``, ``SERVO`` or
``VELOCITY`` (the last mode armed); ``state`` is ``ArmState.MOVING``, ``READY`` (armed, at
rest at the goal) or ``STOPPED`` (not armed, or a fault latched).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from core.clock import Clock, MonotonicClock
from core.config import Config, config_dataclass, number
from core.devices import (
    ArmMode,
    ArmState,
    ArmStatus,
    ContextManagedDevice,
    Pose,
    Twist,
    Vector3,
)
from core.envelope import clamp_pose, limit_twist, require_finite
from core.errors import DeviceFaultError, DeviceNotConnectedError, DeviceTimeoutError
from core.spatial import quat_from_rpy, rotation_from_rpy, tilt_of_rotation
from drivers.arm.arm_envelope import timed_servo_target
from drivers.arm.xarm6 import XArm6Config
from drivers.arm.xarm_codes import WAIT_FINISH_TIMEOUT
from drivers.sim.twins.tcp_motion import TcpMotion

ForceSource = Callable[[], Vector3]
"""Gives the external force on the tool in B, N, now."""


def _no_force() -> Vector3:
    return (0.0, 0.0, 0.0)


ARRIVED_M = 1e-6  # a position goal counts as reached within this distance ...
ARRIVED_RAD = 1e-6  # ... and this angle, with the TCP at rest
_AT_REST = 1e-9  # m/s and rad/s below which the TCP is at rest


@config_dataclass
class SimArmSettings(Config):
    """The ``sim:`` section of an arm YAML: what only the twin needs.

    ``control_rate_hz``: integration rate of the motion. ``max_accel_m_s2`` and
    ``max_angular_accel_rad_s2``: limits on the norm of the TCP's linear and angular
    acceleration. ``start_*``: the TCP pose in B at start-up (m, rad; must lie inside the
    envelope). ``force_noise_n``: the standard deviation of the force reading's noise per
    component, N (with ``ft_sensor``).
    """

    control_rate_hz: float = number(50.0, 2000.0)
    max_accel_m_s2: float = number(0.01, 50.0)
    max_angular_accel_rad_s2: float = number(0.01, 100.0)
    start_x_m: float = number(-2.0, 2.0)
    start_y_m: float = number(-2.0, 2.0)
    start_z_m: float = number(-2.0, 2.0)
    start_roll_rad: float = number(-math.pi, math.pi)
    start_pitch_rad: float = number(-math.pi, math.pi)
    start_yaw_rad: float = number(-math.pi, math.pi)
    force_noise_n: float = number(0.0, 10.0)

    @property
    def start_pose(self) -> Pose:
        return Pose(
            (self.start_x_m, self.start_y_m, self.start_z_m),
            (self.start_roll_rad, self.start_pitch_rad, self.start_yaw_rad),
        )


@config_dataclass(kw_only=True)
class SimArmConfig(XArm6Config):
    """An xArm6 YAML with ``backend: sim``: the real driver's keys (the same envelope, rates
    and name) plus the ``sim:`` section."""

    sim: SimArmSettings

    def __post_init__(self) -> None:
        super().__post_init__()
        env, start = self.envelope, self.sim.start_pose
        for axis, value in zip("xyz", start.xyz_m, strict=True):
            low, high = getattr(env, f"{axis}_min_m"), getattr(env, f"{axis}_max_m")
            if not low <= value <= high:
                raise ValueError(
                    f"key 'sim.start_{axis}_m': expected a number in [{low}, {high}] (inside "
                    f"the envelope), got {value!r}"
                )
        tilt = tilt_of_rotation(rotation_from_rpy(start.rpy_rad))
        if tilt > env.max_tilt_rad:
            raise ValueError(
                f"key 'sim.start_roll_rad': the start orientation tilts the tool {tilt:.3f} rad "
                f"from vertical, more than envelope.max_tilt_rad = {env.max_tilt_rad}"
            )


class SimArm(ContextManagedDevice):
    """The xArm6 twin; see the module docstring. ``clock`` defaults to real time."""

    def __init__(self, config: SimArmConfig, clock: Clock | None = None) -> None:
        self.config = config
        self.name = config.name
        self._clock = clock if clock is not None else MonotonicClock()
        sim = config.sim
        self._dt_s = 1.0 / sim.control_rate_hz
        self._motion = TcpMotion(
            config.envelope,
            sim.start_pose,
            sim.max_accel_m_s2,
            sim.max_angular_accel_rad_s2,
            self._dt_s,
        )
        self._rpy_hint = sim.start_pose.rpy_rad
        self._t0_s = self._clock.now()
        self._steps = 0
        self._connected = False
        self._mode: ArmMode | None = None  # None: not armed (stopped)
        self._last_mode = ArmMode.POSITION
        self._goal: _Goal | None = None
        self._twist = Twist()
        self._twist_until_s = -math.inf
        self._fault: DeviceFaultError | None = None
        self._servo_reference: Pose | None = None
        self._servo_time_s: float | None = None
        self._force_source: ForceSource = _no_force
        self._force_rng = np.random.default_rng(0)

    @classmethod
    def from_config(
        cls, config: SimArmConfig, clock: Clock | None = None, api: Any = None
    ) -> SimArm:
        """The twin on ``clock`` (real time when None), not connected yet; ``api`` is
        accepted for the same call as ``XArm6.from_config`` and ignored."""
        return cls(config, clock)

    def attach_force_source(self, source: ForceSource, rng: np.random.Generator) -> None:
        """Read the external force from ``source`` and its noise from ``rng`` (see the
        module docstring)."""
        self._force_source = source
        self._force_rng = rng

    # ----------------------------------------------------------------- lifecycle

    @property
    def is_connected(self) -> bool:
        return self._connected

    @property
    def fault(self) -> DeviceFaultError | None:
        """The latched fault, or None."""
        return self._fault

    def connect(self) -> None:
        """Connect and arm position mode (unless a fault is latched)."""
        self._advance()
        if self._connected:
            return
        self._connected = True
        if self._fault is None:
            self._arm(ArmMode.POSITION)

    def disconnect(self) -> None:
        """Stop (decelerating) and disconnect. Idempotent."""
        self._advance()
        self._halt()
        self._connected = False

    # ----------------------------------------------------------------- reading

    def read_status(self) -> ArmStatus:
        """TCP pose in B at the last integration step; works while a fault is latched."""
        self._require_connected()
        self._advance()
        return ArmStatus(
            t_s=self._t0_s + self._steps * self._dt_s,
            tcp=self._pose(),
            joints_rad=(math.nan,) * 6,
            mode=self._last_mode,
            state=self._state(),
            error_code=(self._fault.code or 0) if self._fault is not None else 0,
            external_force_n=self._read_force() if self.config.ft_sensor else None,
        )

    def _read_force(self) -> Vector3:
        noise = self._force_rng.normal(0.0, self.config.sim.force_noise_n, 3)
        fx, fy, fz = (float(f + n) for f, n in zip(self._force_source(), noise, strict=True))
        return (fx, fy, fz)

    # ----------------------------------------------------------------- motion

    def move_to(self, target: Pose, speed_m_s: float, wait: bool = True) -> None:
        """Straight move to ``target`` clamped into the envelope at ``speed_m_s`` (capped at
        the envelope's); with ``wait`` sleeps on the clock until reached."""
        require_finite("target", (*target.xyz_m, *target.rpy_rad))
        if not math.isfinite(speed_m_s) or speed_m_s <= 0:
            raise ValueError(f"speed_m_s: expected a positive number, got {speed_m_s!r}")
        self._prepare_motion(ArmMode.POSITION)
        goal = clamp_pose(target, self.config.envelope).value
        self._goal = _Goal.at(goal, min(speed_m_s, self.config.envelope.max_linear_speed_m_s))
        if not wait:
            return
        deadline_s = self._clock.now() + self.config.move_timeout_s
        while not self._goal_reached():
            if self._clock.now() > deadline_s:
                self._halt()
                raise DeviceTimeoutError(
                    self.name,
                    f"set_position failed: move not finished within {self.config.move_timeout_s} s",
                    WAIT_FINISH_TIMEOUT,
                )
            self._clock.sleep(self._dt_s)
            self._advance()

    def servo_pose(self, target: Pose) -> None:
        """One servo target, clamped and stepped exactly as ``XArm6.servo_pose`` does."""
        require_finite("target", (*target.xyz_m, *target.rpy_rad))
        self._prepare_motion(ArmMode.SERVO)
        env = self.config.envelope
        now = self._clock.now()
        if self._servo_reference is None:
            self._servo_reference = clamp_pose(self._pose(), env).value
        command = timed_servo_target(
            self._servo_reference,
            target,
            env,
            self._servo_time_s,
            now,
            self.config.servo_rate_hz,
        )
        self._goal = _Goal.at(command, env.max_linear_speed_m_s)
        self._servo_reference = command
        self._servo_time_s = now

    def move_velocity(self, twist: Twist, duration_s: float) -> None:
        """Hold the clamped twist for ``min(duration_s, velocity_timeout_s)``, then stop."""
        require_finite("twist", (*twist.linear_m_s, *twist.angular_rad_s))
        if not math.isfinite(duration_s) or duration_s <= 0:
            raise ValueError(
                f"duration_s: expected a positive number (the SDK reads 0 as 'never stop'), "
                f"got {duration_s!r}"
            )
        self._prepare_motion(ArmMode.VELOCITY)
        duration = min(duration_s, self.config.velocity_timeout_s)
        self._twist = limit_twist(twist, self._pose(), duration, self.config.envelope).value
        self._twist_until_s = self._clock.now() + duration

    def stop(self) -> None:
        """Controlled stop: decelerate to rest and hold; the mode stays armed unless a fault
        is latched."""
        self._require_connected()
        self._advance()
        mode = self._mode
        self._halt()
        if self._fault is None and mode is not None:
            self._arm(mode)

    def emergency_stop(self) -> None:
        """Stop (decelerating at the acceleration limits) and latch a fault."""
        self._require_connected()
        self._advance()
        self._halt()
        self._latch(DeviceFaultError(self.name, "emergency stop requested; call clear_fault()"))

    def clear_fault(self) -> None:
        """Clear the latched fault and re-arm position mode."""
        self._require_connected()
        self._advance()
        self._fault = None
        self._arm(ArmMode.POSITION)

    def inject_fault(self, code: int, message: str) -> None:
        """Simulate controller error ``code``: the arm stops and the fault is latched, as
        the real driver's error callback does."""
        self._advance()
        self._halt()
        self._latch(
            DeviceFaultError(
                self.name,
                f"{message}; the arm was stopped; remove the cause, then call clear_fault()",
                code,
            )
        )

    # ----------------------------------------------------------------- internals

    def _require_connected(self) -> None:
        if not self._connected:
            raise DeviceNotConnectedError(self.name, "not connected; call connect() first")

    def _prepare_motion(self, mode: ArmMode) -> None:
        self._require_connected()
        self._advance()
        if self._fault is not None:
            raise DeviceFaultError(
                self.name,
                f"fault latched, call clear_fault(): {self._fault.message}",
                self._fault.code,
            )
        if self._mode != mode:
            self._arm(mode)

    def _arm(self, mode: ArmMode) -> None:
        self._halt()
        self._mode = mode
        self._last_mode = mode

    def _halt(self) -> None:
        """Drop every target (the TCP decelerates to rest) and disarm."""
        self._mode = None
        self._goal = None
        self._twist = Twist()
        self._twist_until_s = -math.inf
        self._servo_reference = None
        self._servo_time_s = None

    def _latch(self, fault: DeviceFaultError) -> None:
        if self._fault is None:  # keep the first fault: the root cause
            self._fault = fault

    def _state(self) -> ArmState:
        if self._mode is None or self._fault is not None:
            return ArmState.STOPPED
        return ArmState.READY if self._goal_reached() else ArmState.MOVING

    def _goal_reached(self) -> bool:
        """At rest, and at the goal if there is one."""
        if not self._motion.at_rest(_AT_REST):
            return False
        if self._goal is None:
            return True
        delta, turn = self._motion.offset_to(self._goal.xyz_m, self._goal.quaternion)
        return math.hypot(*delta) <= ARRIVED_M and math.hypot(*turn) <= ARRIVED_RAD

    def _pose(self) -> Pose:
        pose = self._motion.pose(self._rpy_hint)
        self._rpy_hint = pose.rpy_rad
        return pose

    def _advance(self) -> None:
        """Integrate in fixed steps up to the clock's ``now()``."""
        target_steps = math.floor((self._clock.now() - self._t0_s) / self._dt_s + 1e-9)
        while self._steps < target_steps:
            t_s = self._t0_s + self._steps * self._dt_s
            goal = self._goal
            if goal is not None:
                v_des, w_des = self._motion.approach(
                    goal.xyz_m,
                    goal.quaternion,
                    goal.speed_m_s,
                    self.config.envelope.max_angular_speed_rad_s,
                )
            elif t_s < self._twist_until_s:
                v_des, w_des = self._twist.linear_m_s, self._twist.angular_rad_s
            else:
                v_des = w_des = (0.0, 0.0, 0.0)
            self._motion.step(v_des, w_des)
            self._steps += 1


@dataclass(frozen=True)
class _Goal:
    """A position or servo target (inside the envelope) and the speed to approach it."""

    xyz_m: tuple[float, float, float]
    quaternion: tuple[float, float, float, float]
    speed_m_s: float

    @classmethod
    def at(cls, pose: Pose, speed_m_s: float) -> _Goal:
        return cls(pose.xyz_m, quat_from_rpy(pose.rpy_rad), speed_m_s)
