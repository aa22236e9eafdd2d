"""Command limits (property tests: the limited command never exceeds a limit), the tactile
budget, the watchdog's rules and the safe stop."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

from controller.insertion.interface import Command, GripperTarget, TeleopInput
from controller.safety import (
    CommandLimiter,
    LimitsConfig,
    Watchdog,
    over_budget,
    safe_stop,
)
from controller.tactile.wrench import WrenchEstimate
from core.devices import ArmMode, ArmState, ArmStatus, Pose, Twist
from core.envelope import Envelope, limit_twist
from core.errors import DeviceFaultError, DeviceTimeoutError
from core.spatial import rotation_from_rpy, rpy_from_rotation, tilt_of_rotation
from drivers.arm.arm_envelope import SafetyEnvelope

LIMITS = LimitsConfig(max_linear_speed_m_s=0.05, max_angular_speed_rad_s=0.5, max_tilt_rad=0.3)
PERIOD, HOLD = 0.01, 0.05
EPS = 1e-9

coordinate = st.floats(-1.0, 1.0, allow_nan=False)
speeds = st.floats(-0.5, 0.5, allow_nan=False)


@st.composite
def poses(draw, max_tilt=0.6):
    """A TCP pose near the box (sometimes outside it), tool tilted up to ``max_tilt``."""
    xyz = [
        draw(st.floats(low - 0.05, high + 0.05))
        for low, high in zip(LIMITS.box_min_m, LIMITS.box_max_m, strict=True)
    ]
    axis_angle = draw(st.floats(0, 2 * math.pi))
    tilt = draw(st.floats(0, max_tilt))
    yaw = draw(st.floats(-math.pi, math.pi))
    tilted = Rotation.from_rotvec([tilt * math.cos(axis_angle), tilt * math.sin(axis_angle), 0])
    rotation = tilted * Rotation.from_euler("z", yaw) * Rotation.from_euler("x", math.pi)
    return Pose(tuple(xyz), rpy_from_rotation(rotation))


twists = st.builds(
    lambda lin, ang: Twist(tuple(lin), tuple(ang)),
    st.lists(speeds, min_size=3, max_size=3),
    st.lists(st.floats(-3.0, 3.0, allow_nan=False), min_size=3, max_size=3),
)


def box_excess(xyz) -> float:
    """How far ``xyz`` lies outside the box (0 inside), m."""
    p = np.asarray(xyz)
    return float(np.max(np.maximum(0, LIMITS.box_min_m - p) + np.maximum(0, p - LIMITS.box_max_m)))


def tilt_rad(rpy_rad) -> float:
    return tilt_of_rotation(rotation_from_rpy(rpy_rad))


def after(pose: Pose, twist: Twist, t_s: float) -> Pose:
    turn = Rotation.from_rotvec(np.asarray(twist.angular_rad_s) * t_s)
    rotation = turn * rotation_from_rpy(pose.rpy_rad)
    xyz = np.asarray(pose.xyz_m) + np.asarray(twist.linear_m_s) * t_s
    return Pose(tuple(xyz), rpy_from_rotation(rotation))


@settings(max_examples=300, deadline=None)
@given(tcp=poses(), twist=twists)
def test_a_limited_twist_never_exceeds_the_limits(tcp, twist):
    out = CommandLimiter(LIMITS, PERIOD, HOLD).limit(Command(twist=twist), tcp, None).command
    assert np.linalg.norm(out.twist.linear_m_s) <= LIMITS.max_linear_speed_m_s + EPS
    assert np.linalg.norm(out.twist.angular_rad_s) <= LIMITS.max_angular_speed_rad_s + EPS
    # Over the hold: no further out of the box than at the start, no more tilted than allowed.
    end = after(tcp, out.twist, HOLD)
    assert box_excess(end.xyz_m) <= box_excess(tcp.xyz_m) + EPS
    allowed = max(LIMITS.max_tilt_rad, tilt_rad(tcp.rpy_rad))
    for t in np.linspace(0, HOLD, 6):
        assert tilt_rad(after(tcp, out.twist, t).rpy_rad) <= allowed + 1e-6


@settings(max_examples=200, deadline=None)
@given(tcp=poses(max_tilt=0.29), target=poses(), twist=twists)
def test_a_limited_pose_target_stays_in_the_box_the_cone_and_the_step(tcp, target, twist):
    tcp = Pose(tuple(np.clip(tcp.xyz_m, LIMITS.box_min_m, LIMITS.box_max_m)), tcp.rpy_rad)
    out = CommandLimiter(LIMITS, PERIOD, HOLD).limit(Command(pose=target), tcp, None).command
    assert box_excess(out.pose.xyz_m) <= EPS
    assert tilt_rad(out.pose.rpy_rad) <= LIMITS.max_tilt_rad + 1e-9
    step = np.linalg.norm(np.subtract(out.pose.xyz_m, tcp.xyz_m))
    assert step <= LIMITS.max_linear_speed_m_s * PERIOD + EPS
    turn = rotation_from_rpy(out.pose.rpy_rad) * rotation_from_rpy(tcp.rpy_rad).inv()
    assert turn.magnitude() <= LIMITS.max_angular_speed_rad_s * PERIOD + 1e-9


@settings(max_examples=100, deadline=None)
@given(tcp=poses(), twist=twists)
def test_the_limiter_and_the_arm_envelope_share_one_geometry(tcp, twist):
    """The same box, speeds and tilt give the same twist, bit for bit, in the loop's limiter
    and in the arm driver's envelope (both core.envelope's, read by the same key names)."""
    arm = SafetyEnvelope(**{f.name: getattr(LIMITS, f.name) for f in dataclasses.fields(Envelope)})
    limited = CommandLimiter(LIMITS, PERIOD, HOLD).limit(Command(twist=twist), tcp, None)
    assert limited.command.twist == limit_twist(twist, tcp, HOLD, arm).value


def test_a_reachable_pose_target_passes_unchanged_and_steps_from_the_last_target():
    tcp = Pose((0.3, 0.0, 0.2), (math.pi, 0.0, 0.0))
    limiter = CommandLimiter(LIMITS, PERIOD, HOLD)
    near = Pose((0.3, 0.0002, 0.2), (math.pi, 0.0, 0.001))
    result = limiter.limit(Command(pose=near), tcp, None)
    assert result.command.pose.xyz_m == pytest.approx(near.xyz_m)
    assert result.limited == ()
    far = Pose((0.3, 0.1, 0.2), (math.pi, 0.0, 0.0))
    first = limiter.limit(Command(pose=far), tcp, None).command.pose
    second = limiter.limit(Command(pose=far), tcp, None).command.pose  # tcp not updated
    assert second.xyz_m[1] - first.xyz_m[1] == pytest.approx(LIMITS.max_linear_speed_m_s * PERIOD)


def test_a_twist_into_a_face_is_cut_at_the_face():
    tcp = Pose((0.3, 0.0, LIMITS.z_min_m + 0.001), (math.pi, 0.0, 0.0))
    result = CommandLimiter(LIMITS, PERIOD, HOLD).limit(
        Command(twist=Twist((0.01, 0.0, -0.04))), tcp, None
    )
    assert result.command.twist.linear_m_s == pytest.approx((0.01, 0.0, -0.001 / HOLD))
    assert result.limited == ("workspace",)


def test_a_tilting_rotation_at_the_cone_keeps_only_the_vertical_part():
    at_limit = Rotation.from_rotvec([LIMITS.max_tilt_rad, 0, 0]) * Rotation.from_euler("x", math.pi)
    tcp = Pose((0.3, 0.0, 0.2), rpy_from_rotation(at_limit))
    outward = Command(twist=Twist((0, 0, 0), (0.2, 0.0, 0.1)))
    result = CommandLimiter(LIMITS, PERIOD, HOLD).limit(outward, tcp, None)
    assert result.command.twist.angular_rad_s == (0.0, 0.0, 0.1)
    assert "tilt" in result.limited
    inward = Command(twist=Twist((0, 0, 0), (-0.2, 0.0, 0.0)))
    assert CommandLimiter(LIMITS, PERIOD, HOLD).limit(inward, tcp, None).limited == ()


def estimate(calibrated=True, **values) -> WrenchEstimate:
    base = WrenchEstimate.zero(1.0, zeroing=False, calibrated=calibrated)
    return dataclasses.replace(base, **values)


BUDGET = dataclasses.replace(LIMITS, max_tilt_torque=0.02, max_twist_torque=0.01, max_normal=5.0)


@pytest.mark.parametrize(
    ("values", "expected"),
    [
        ({}, None),
        ({"tau_x": 0.015, "tau_y": -0.015}, "tilt_torque"),  # |(tau_x, tau_y)| = 0.021
        ({"tau_x": 0.014, "tau_y": 0.014}, None),
        ({"tau_z": -0.011}, "twist_torque"),
        ({"normal": -6.0}, "normal"),
    ],
)
def test_the_tactile_budget(values, expected):
    assert over_budget(estimate(**values), BUDGET) == expected


def test_the_budget_is_not_checked_while_zeroing_or_without_an_estimate():
    assert over_budget(None, BUDGET) is None
    zeroing = dataclasses.replace(estimate(tau_x=1.0), zeroing=True)
    assert over_budget(zeroing, BUDGET) is None


def test_a_budget_in_other_units_is_refused():
    with pytest.raises(ValueError, match="key 'wrench_units' is 'calibrated'.*raw"):
        over_budget(estimate(calibrated=False, tau_x=1.0), BUDGET)
    assert over_budget(estimate(calibrated=False, tau_x=1.0), LIMITS) is None  # no budget


@settings(max_examples=100, deadline=None)
@given(tcp=poses(max_tilt=0.29), twist=twists)
def test_over_budget_only_lifting_passes(tcp, twist):
    loaded = estimate(tau_x=0.05)
    result = CommandLimiter(BUDGET, PERIOD, HOLD).limit(Command(twist=twist), tcp, loaded)
    out = result.command.twist
    assert out.linear_m_s[:2] == (0.0, 0.0) and out.linear_m_s[2] >= 0.0
    assert out.angular_rad_s == (0.0, 0.0, 0.0)
    assert "budget:tilt_torque" in result.limited

    stopping = dataclasses.replace(BUDGET, over_budget="stop")
    out = CommandLimiter(stopping, PERIOD, HOLD).limit(Command(twist=twist), tcp, loaded)
    assert out.command.twist == Twist()


def test_over_budget_a_pose_target_may_only_rise():
    tcp = Pose((0.3, 0.0, 0.1), (math.pi, 0.0, 0.0))
    loaded = estimate(tau_z=0.02)
    limiter = CommandLimiter(BUDGET, PERIOD, HOLD)
    down = limiter.limit(Command(pose=Pose((0.31, 0.0, 0.09), (math.pi, 0.1, 0.0))), tcp, loaded)
    assert down.command.pose == tcp
    limiter = CommandLimiter(BUDGET, PERIOD, HOLD)
    up = limiter.limit(Command(pose=Pose((0.3, 0.0, 0.2), (math.pi, 0.0, 0.0))), tcp, loaded)
    assert up.command.pose.xyz_m == pytest.approx((0.3, 0.0, 0.1 + 0.05 * PERIOD))


def test_gripper_and_rezero_pass_through():
    tcp = Pose((0.3, 0.0, 0.2), (math.pi, 0.0, 0.0))
    target = GripperTarget(0.01, 0.05, 20.0)
    command = Command(gripper=target, rezero_tactile=True)
    assert CommandLimiter(LIMITS, PERIOD, HOLD).limit(command, tcp, None).command == command
    twist = Command(twist=Twist((1.0, 0, 0)), gripper=target, rezero_tactile=True)
    out = CommandLimiter(LIMITS, PERIOD, HOLD).limit(twist, tcp, None).command
    assert out.gripper == target and out.rezero_tactile


def test_non_finite_commands_are_refused():
    tcp = Pose((0.3, 0.0, 0.2), (math.pi, 0.0, 0.0))
    with pytest.raises(ValueError, match="command twist: expected finite"):
        bad = Command(twist=Twist((math.nan, 0, 0)))
        CommandLimiter(LIMITS, PERIOD, HOLD).limit(bad, tcp, None)


def test_limits_config_checks_the_box():
    with pytest.raises(ValueError, match="key 'x_max_m': expected a number greater than x_min_m"):
        LimitsConfig(x_min_m=0.5, x_max_m=0.4)


# -- watchdog ------------------------------------------------------------------------------


def status(error_code=0) -> ArmStatus:
    pose = Pose((0.3, 0.0, 0.2), (math.pi, 0.0, 0.0))
    return ArmStatus(1.0, pose, (0.0,) * 6, ArmMode.VELOCITY, ArmState.MOVING, error_code)


def watchdog() -> Watchdog:
    return Watchdog(0.1, max_consecutive_overruns=3, max_overruns_in_window=4,
                    overrun_window_ticks=10)  # fmt: skip


NO_PAD = TeleopInput()


def check(dog, now_s=1.0, frame_t_s=0.95, arm=None, teleop=NO_PAD, errors=None):
    return dog.check(now_s, frame_t_s=frame_t_s, arm=arm or status(), gripper=None,
                     teleop=teleop, errors=errors or {})  # fmt: skip


def test_the_watchdog_rules():
    assert check(watchdog()) is None
    assert check(watchdog(), frame_t_s=0.89).startswith("stale tactile frame: 0.110 s old")
    for bad in (float("nan"), float("inf"), float("-inf")):  # never "not older than budget"
        assert check(watchdog(), frame_t_s=bad).startswith(f"tactile frame time {bad!r}")
    stale = DeviceTimeoutError("mini", "newest frame is 200 ms old")
    assert check(watchdog(), errors={"tactile": stale}) == (
        "stale tactile frame: mini: newest frame is 200 ms old"
    )
    fault = DeviceFaultError("xarm6", "overcurrent", 21)
    assert check(watchdog(), errors={"arm": fault}).startswith("device fault (arm): xarm6")
    assert check(watchdog(), arm=status(31)) == "device fault (arm): error code 31"
    lost = TeleopInput(connected=False, in_control=True)
    assert check(watchdog(), teleop=lost) == "gamepad lost while the operator was in control"
    assert check(watchdog(), teleop=TeleopInput(connected=False)) is None


def test_the_first_trip_is_latched():
    dog = watchdog()
    first = check(dog, arm=status(31))
    assert check(dog) == first == dog.trip


def test_overrun_policy():
    dog = Watchdog(0.1, max_consecutive_overruns=3, max_overruns_in_window=10,
                   overrun_window_ticks=10)  # fmt: skip
    assert [dog.record_tick(o) for o in (True, True, False, True, True)] == [None] * 5
    assert dog.record_tick(True) == "overruns: 3 in a row"
    dog = watchdog()
    pattern = [True, False, True, False, True, False]
    assert [dog.record_tick(o) for o in pattern] == [None] * 6
    assert dog.record_tick(True) == "overruns: 4 in the last 7 ticks"
    dog = watchdog()  # overruns older than the window are forgotten
    for overran in [True, False, True, False] + [False] * 10 + [True, False, True, False]:
        assert dog.record_tick(overran) is None


# -- safe stop -----------------------------------------------------------------------------


class FakeArm:
    def __init__(self, stop_error=None, estop_error=None):
        self.calls = []
        self.stop_error, self.estop_error = stop_error, estop_error

    def stop(self):
        self.calls.append("stop")
        if self.stop_error:
            raise self.stop_error

    def emergency_stop(self):
        self.calls.append("emergency_stop")
        if self.estop_error:
            raise self.estop_error


def test_safe_stop_stops_the_arm():
    arm = FakeArm()
    assert safe_stop(arm, gripper=object()) is None and arm.calls == ["stop"]


def test_safe_stop_escalates_and_keeps_the_first_error():
    first = DeviceTimeoutError("xarm6", "no reply")
    arm = FakeArm(stop_error=first, estop_error=OSError("socket closed"))
    assert safe_stop(arm) is first
    assert arm.calls == ["stop", "emergency_stop"]
