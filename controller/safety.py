"""Safety of the control loop: command limits, the watchdog and the safe stop.

**Limits** (``CommandLimiter.limit``, applied by the loop to every command before it is
sent; frames: B the arm base, T the tool; SI units): the task's ``limits:``, an
``core.envelope.Envelope`` applied with that module's clamps (its docstring gives the
policy), the same geometry as the arm driver's own envelope (drivers/arm/arm_envelope.py),
usually tighter. A twist is limited over the loop's
``hold_s``; a pose target is stepped from the previous pose target (or, for the first, the
measured TCP) by at most ``max_linear_speed_m_s`` and ``max_angular_speed_rad_s`` times one
period.

* **Tactile budget**: the newest ``WrenchEstimate`` is over budget when ``|(tau_x, tau_y)|
  > max_tilt_torque``, ``|tau_z| > max_twist_torque`` or ``|normal| > max_normal`` (each
  ``None``: unchecked), in the estimate's own units, which must be ``wrench_units``
  (``calibrated``: N*m and N; ``raw``: the uncalibrated mm, mm^2 of
  controller/tactile/wrench.py); a mismatch is a ValueError, since a budget in the wrong
  units guards nothing. Over budget, with ``over_budget: lift_only``, only lifting is let
  through: the twist keeps only its upward (+z_B) linear part, a pose target only its rise
  in z at the reference pose; with ``stop`` the arm holds still. Rule and reason: every load
  the gel sees during insertion comes from pressing the plug down onto the board or into
  the receptacle, so moving up unloads it whatever the torque's sign, and this needs no
  sensor-to-base calibration. The wrist spring's deflection is not used (not measured on
  hardware).

**Watchdog** (``Watchdog``): trips, once and latched, on a tactile frame older than
``tactile_max_age_s`` (or a sensor that refuses its stale frame), a device error or a
device reporting an error code, ``max_consecutive_overruns`` overruns in a row or
``max_overruns_in_window`` within the last ``overrun_window_ticks`` ticks, and a gamepad
lost while the operator holds control.

**Safe stop** (``safe_stop``): see its docstring.
"""

from __future__ import annotations

import dataclasses
import math
from collections import deque
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Literal

from controller.insertion.interface import Command, TeleopInput
from controller.tactile.wrench import WrenchEstimate
from controller.teleop import lost_in_control
from core.config import config_dataclass, number
from core.devices import Arm, ArmStatus, Gripper, GripperStatus, Pose, Twist
from core.envelope import Envelope, limit_pose, limit_twist, require_finite
from core.errors import DeviceTimeoutError


@config_dataclass(kw_only=True)
class LimitsConfig(Envelope):
    """The task YAML's ``limits:`` section (see the module doc): an ``Envelope`` (the TCP's
    box in B, speeds, tilt from the downward vertical) and the tactile budget."""

    wrench_units: Literal["calibrated", "raw"] = "calibrated"
    max_tilt_torque: float | None = number(0.0, 1e6, default=None)
    max_twist_torque: float | None = number(0.0, 1e6, default=None)
    max_normal: float | None = number(0.0, 1e6, default=None)
    over_budget: Literal["lift_only", "stop"] = "lift_only"


@dataclass(frozen=True)
class LimitedCommand:
    """The command to send and the limits that changed it (``speed``, ``workspace``,
    ``tilt``, ``step``, ``budget:<what>``), empty when it passed unchanged."""

    command: Command
    limited: tuple[str, ...] = ()


def over_budget(wrench: WrenchEstimate | None, limits: LimitsConfig) -> str | None:
    """Which budget the estimate exceeds (``tilt_torque``, ``twist_torque``, ``normal``),
    or None. ValueError if its units are not ``limits.wrench_units``."""
    budgets = (limits.max_tilt_torque, limits.max_twist_torque, limits.max_normal)
    if wrench is None or wrench.zeroing or all(b is None for b in budgets):
        return None
    if wrench.calibrated != (limits.wrench_units == "calibrated"):
        got = "calibrated" if wrench.calibrated else "raw"
        raise ValueError(
            f"limits: key 'wrench_units' is '{limits.wrench_units}' but the tactile estimates "
            f"are {got}: the budget would compare different units"
        )
    checks = (
        ("tilt_torque", math.hypot(wrench.tau_x, wrench.tau_y), limits.max_tilt_torque),
        ("twist_torque", abs(wrench.tau_z), limits.max_twist_torque),
        ("normal", abs(wrench.normal), limits.max_normal),
    )
    for name, value, budget in checks:
        if budget is not None and value > budget:
            return name
    return None


class CommandLimiter:
    """Applies ``LimitsConfig`` to each command (module doc). ``period_s``: the loop period
    (the step of a pose target); ``hold_s``: how long a twist is held (its horizon)."""

    def __init__(self, limits: LimitsConfig, period_s: float, hold_s: float) -> None:
        if not period_s > 0 or not hold_s > 0:
            raise ValueError(f"period_s and hold_s: expected > 0, got {period_s}, {hold_s}")
        self.limits = limits
        self.period_s = period_s
        self.hold_s = hold_s
        self._last_target: Pose | None = None  # the previous pose target sent

    def limit(self, command: Command, tcp: Pose, wrench: WrenchEstimate | None) -> LimitedCommand:
        """``command`` within the limits, from the measured TCP pose ``tcp`` (T2B) and the
        newest tactile estimate. Call it once per sent command: it remembers the last pose
        target."""
        budget = over_budget(wrench, self.limits)
        limited: list[str] = []
        if command.twist is not None:
            self._last_target = None
            twist = self._limit_twist(command.twist, tcp, limited)
            if budget is not None:
                twist = self._unloading_twist(twist)
                limited.append(f"budget:{budget}")
            out = dataclasses.replace(command, twist=twist)
        elif command.pose is not None:
            reference = self._last_target if self._last_target is not None else tcp
            pose = self._limit_pose(command.pose, reference, limited)
            if budget is not None:
                pose = self._unloading_pose(pose, reference)
                limited.append(f"budget:{budget}")
            self._last_target = pose
            out = dataclasses.replace(command, pose=pose)
        else:
            self._last_target = None
            out = command
        return LimitedCommand(out, tuple(limited))

    # -- twists --------------------------------------------------------------------------

    def _limit_twist(self, twist: Twist, tcp: Pose, limited: list[str]) -> Twist:
        require_finite("command twist", (*twist.linear_m_s, *twist.angular_rad_s))
        twist, changes = limit_twist(twist, tcp, self.hold_s, self.limits)
        limited.extend(changes)
        return twist

    def _unloading_twist(self, twist: Twist) -> Twist:
        if self.limits.over_budget == "stop":
            return Twist()
        return Twist((0.0, 0.0, max(0.0, twist.linear_m_s[2])), (0.0, 0.0, 0.0))

    # -- pose targets ----------------------------------------------------------------------

    def _limit_pose(self, target: Pose, reference: Pose, limited: list[str]) -> Pose:
        require_finite("command pose", (*target.xyz_m, *target.rpy_rad))
        lim = self.limits
        pose, changes = limit_pose(
            target,
            reference,
            lim,
            max_step_m=lim.max_linear_speed_m_s * self.period_s,
            max_step_rad=lim.max_angular_speed_rad_s * self.period_s,
        )
        limited.extend(changes)
        return pose

    def _unloading_pose(self, pose: Pose, reference: Pose) -> Pose:
        if self.limits.over_budget == "stop":
            return reference
        x, y, z = reference.xyz_m
        return Pose((x, y, max(z, pose.xyz_m[2])), reference.rpy_rad)


# -- watchdog ------------------------------------------------------------------------------


HOLDING_LIMITS = ("workspace", "tilt")
"""The limits that stop a command's motion (``speed`` only slows it, ``step`` only splits it)."""


class Watchdog:
    """Decides each tick whether the loop must stop (module doc). ``trip`` holds the first
    reason (a one-line message), latched."""

    def __init__(
        self,
        tactile_max_age_s: float,
        max_consecutive_overruns: int,
        max_overruns_in_window: int,
        overrun_window_ticks: int,
        max_held_by_limits_s: float = 1.0,
    ) -> None:
        self.tactile_max_age_s = tactile_max_age_s
        self.max_held_by_limits_s = max_held_by_limits_s
        self._held_since_s: float | None = None
        self.max_consecutive_overruns = max_consecutive_overruns
        self.max_overruns_in_window = max_overruns_in_window
        self._window: deque[bool] = deque(maxlen=overrun_window_ticks)
        self._consecutive = 0
        self.trip: str | None = None

    def check(
        self,
        now_s: float,
        *,
        frame_t_s: float | None,
        arm: ArmStatus | None,
        gripper: GripperStatus | None,
        teleop: TeleopInput,
        errors: Mapping[str, Exception],
    ) -> str | None:
        """The trip message for this tick's readings, or None. ``errors`` maps a device's
        role (``arm``, ``gripper``, ``tactile``, ``gamepad``) to the error its read raised."""
        if errors:
            role, error = next(iter(errors.items()))  # the first failure is the root cause
            if role == "tactile" and isinstance(error, DeviceTimeoutError):
                return self._latch(f"stale tactile frame: {error}")
            return self._latch(f"device fault ({role}): {error}")
        if frame_t_s is not None and not math.isfinite(frame_t_s):
            return self._latch(f"tactile frame time {frame_t_s!r}: expected a finite time (s)")
        if frame_t_s is not None and now_s - frame_t_s > self.tactile_max_age_s:
            return self._latch(
                f"stale tactile frame: {now_s - frame_t_s:.3f} s old "
                f"(budget {self.tactile_max_age_s} s)"
            )
        if arm is not None and arm.error_code != 0:
            return self._latch(f"device fault (arm): error code {arm.error_code}")
        if gripper is not None and gripper.fault_code != 0:
            return self._latch(
                f"device fault (gripper): fault code {gripper.fault_code:#04x} "
                f"{gripper.fault_message}".rstrip()
            )
        if lost_in_control(teleop):
            return self._latch("gamepad lost while the operator was in control")
        return self.trip

    def record_tick(self, overran: bool) -> str | None:
        """Count one finished tick; the trip message if overruns now exceed the policy."""
        self._window.append(overran)
        self._consecutive = self._consecutive + 1 if overran else 0
        if self._consecutive >= self.max_consecutive_overruns:
            return self._latch(f"overruns: {self._consecutive} in a row")
        in_window = sum(self._window)
        if in_window >= self.max_overruns_in_window:
            return self._latch(f"overruns: {in_window} in the last {len(self._window)} ticks")
        return self.trip

    def record_limits(
        self, now_s: float, limited: tuple[str, ...], operator_in_control: bool
    ) -> str | None:
        """Note which limits acted on this tick's command; the trip message once the
        workspace or tilt limit has held the machine's commands back for
        ``max_held_by_limits_s`` without a break (an operator in control is never tripped:
        the envelope holds the pad's commands at its faces)."""
        holding = [name for name in limited if name in HOLDING_LIMITS]
        if not holding or operator_in_control:
            self._held_since_s = None
            return self.trip
        if self._held_since_s is None:
            self._held_since_s = now_s
        held_s = now_s - self._held_since_s
        if held_s >= self.max_held_by_limits_s:
            return self._latch(
                f"the {' and '.join(holding)} limit held the commands back for {held_s:.2f} s "
                f"(budget {self.max_held_by_limits_s} s): the target lies outside the envelope"
            )
        return self.trip

    def _latch(self, message: str) -> str:
        if self.trip is None:
            self.trip = message
        return self.trip


# -- safe stop -----------------------------------------------------------------------------


def safe_stop(arm: Arm, gripper: Gripper | None = None) -> Exception | None:
    """Bring the devices to a safe state; never raises: returns the first error, or None.

    The arm gets ``stop()`` (decelerate, hold position); if that raises, ``emergency_stop()``
    is tried as well. The gripper is left as commanded: holding the plug is its safe state
    (opening could drop it, and the Hand-E has no stop of its own), so nothing is sent to it.
    Errors are returned rather than raised so a caller inside ``finally`` does not mask the
    exception that brought it there; the control loop reports it in its result.
    """
    first: Exception | None = None
    try:
        arm.stop()
    except Exception as error:  # noqa: BLE001 - every failure must leave the others tried
        first = error
        try:
            arm.emergency_stop()
        except Exception:  # noqa: BLE001,S110 - the first error is the one reported
            pass
    del gripper  # nothing to send: see the docstring
    return first
