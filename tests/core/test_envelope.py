"""The envelope's clamps (core/envelope.py), shared by the arm driver and the loop's limiter,
and the arm's SafetyEnvelope (drivers/arm/arm_envelope.py)."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

from core.devices import Pose, Twist
from core.envelope import (
    Envelope,
    clamp_pose,
    clamp_position,
    clamp_tilt,
    limit_pose,
    limit_twist,
)
from core.spatial import quat_from_rpy, rotation_from_rpy, rpy_from_rotation, tilt_of_rotation
from drivers.arm.arm_envelope import SafetyEnvelope

TOL = 1e-9
ENV = Envelope(
    x_min_m=0.2, x_max_m=0.5, y_min_m=-0.2, y_max_m=0.2, z_min_m=0.05, z_max_m=0.4,
    max_linear_speed_m_s=0.1, max_angular_speed_rad_s=0.5, max_tilt_rad=0.35,
)  # fmt: skip
STEP_M, STEP_RAD = 0.002, 0.01  # one servo command's step

angles = st.floats(-math.pi, math.pi)
rpys = st.tuples(angles, angles, angles)
anywhere = st.tuples(*(st.floats(-1.0, 1.0),) * 3)


@st.composite
def inside_poses(draw) -> Pose:
    """A pose inside ENV: a point of the box and an orientation tilted at most max_tilt."""
    xyz = tuple(
        draw(st.floats(lo, hi)) for lo, hi in zip(ENV.box_min_m, ENV.box_max_m, strict=True)
    )
    tilt = draw(st.floats(0.0, ENV.max_tilt_rad))
    azimuth, spin = draw(angles), draw(angles)
    tip = Rotation.from_rotvec(tilt * np.array([math.cos(azimuth), math.sin(azimuth), 0.0]))
    rotation = tip * rotation_from_rpy([math.pi, 0.0, spin])
    return Pose(xyz, rpy_from_rotation(rotation))


def _angle_between(a: Rotation, b: Rotation) -> float:
    return float((a * b.inv()).magnitude())


def test_clamp_position_clips_each_axis_into_the_box():
    clipped = clamp_position((0.0, 0.1, 9.0), ENV)
    np.testing.assert_allclose(clipped, [0.2, 0.1, 0.4])


def clamped_rotation(rotation: Rotation, max_tilt_rad: float) -> Rotation:
    return Rotation.from_quat(clamp_tilt(tuple(rotation.as_quat()), max_tilt_rad))


def test_clamp_tilt_rotates_along_the_shortest_arc_to_the_limit():
    rotation = rotation_from_rpy((math.pi, 0.8, 0.4))  # tilted 0.8 rad
    clamped = clamped_rotation(rotation, 0.35)
    assert tilt_of_rotation(clamped) == pytest.approx(0.35)
    assert _angle_between(clamped, rotation) == pytest.approx(0.8 - 0.35)
    # the tool z-axis stays in the vertical plane through its old direction
    z_old, z_new = rotation.as_matrix()[:, 2], clamped.as_matrix()[:, 2]
    assert np.dot(np.cross(z_old, [0, 0, -1.0]), z_new) == pytest.approx(0.0, abs=1e-12)


def test_clamp_tilt_keeps_an_allowed_orientation_and_handles_pointing_up():
    rotation = quat_from_rpy((math.pi, 0.1, 0.0))
    assert clamp_tilt(rotation, 0.35) is rotation
    pointing_up = rotation_from_rpy((0.0, 0.0, 0.0))
    assert tilt_of_rotation(clamped_rotation(pointing_up, 0.35)) == pytest.approx(0.35)


@settings(max_examples=150, deadline=None)
@given(xyz=anywhere, rpy=rpys)
def test_clamp_pose_lands_inside_and_is_idempotent(xyz, rpy):
    clamped = clamp_pose(Pose(xyz, rpy), ENV).value
    assert np.all(np.asarray(clamped.xyz_m) >= ENV.box_min_m - TOL)
    assert np.all(np.asarray(clamped.xyz_m) <= ENV.box_max_m + TOL)
    assert tilt_of_rotation(rotation_from_rpy(clamped.rpy_rad)) <= ENV.max_tilt_rad + TOL
    again = clamp_pose(clamped, ENV).value
    np.testing.assert_allclose(again.xyz_m, clamped.xyz_m)
    assert (
        _angle_between(rotation_from_rpy(again.rpy_rad), rotation_from_rpy(clamped.rpy_rad)) < 1e-9
    )


@settings(max_examples=100, deadline=None)
@given(pose=inside_poses())
def test_clamp_pose_leaves_a_pose_inside_unchanged(pose):
    assert clamp_pose(pose, ENV) == (pose, ())


@settings(max_examples=200, deadline=None)
@given(previous=inside_poses(), xyz=anywhere, rpy=rpys)
def test_limit_pose_respects_box_tilt_and_step(previous, xyz, rpy):
    command = limit_pose(Pose(xyz, rpy), previous, ENV, STEP_M, STEP_RAD).value
    position = np.asarray(command.xyz_m)
    assert np.all(position >= ENV.box_min_m - TOL) and np.all(position <= ENV.box_max_m + TOL)
    assert np.linalg.norm(position - previous.xyz_m) <= STEP_M + TOL
    rotation = rotation_from_rpy(command.rpy_rad)
    assert tilt_of_rotation(rotation) <= ENV.max_tilt_rad + TOL
    assert _angle_between(rotation, rotation_from_rpy(previous.rpy_rad)) <= STEP_RAD + TOL


@settings(max_examples=60, deadline=None)
@given(start=inside_poses(), goal=inside_poses())
def test_limit_pose_reaches_a_goal_inside_the_envelope(start, goal):
    pose = start
    for _ in range(40):  # the box diagonal is 0.6 m (12 steps); a half turn is 16 steps
        pose = limit_pose(goal, pose, ENV, max_step_m=0.05, max_step_rad=0.2).value
    np.testing.assert_allclose(pose.xyz_m, goal.xyz_m, atol=1e-12)
    goal_rotation = rotation_from_rpy(goal.rpy_rad)
    assert _angle_between(rotation_from_rpy(pose.rpy_rad), goal_rotation) < 1e-9


@settings(max_examples=200, deadline=None)
@given(
    xyz=st.tuples(*(st.floats(-0.2, 0.8),) * 3),
    rpy=rpys,
    linear=st.tuples(*(st.floats(-2.0, 2.0),) * 3),
    angular=st.tuples(*(st.floats(-5.0, 5.0),) * 3),
    duration=st.floats(0.001, 1.0),
)
def test_limit_twist_limits_speed_and_keeps_box_and_tilt(xyz, rpy, linear, angular, duration):
    pose = Pose(xyz, rpy)
    twist = limit_twist(Twist(linear, angular), pose, duration, ENV).value
    v, w = np.asarray(twist.linear_m_s), np.asarray(twist.angular_rad_s)
    assert np.linalg.norm(v) <= ENV.max_linear_speed_m_s + TOL
    assert np.linalg.norm(w) <= ENV.max_angular_speed_rad_s + TOL
    after = np.asarray(xyz) + v * duration
    position = np.asarray(xyz)
    for i in range(3):  # inside after the horizon, or not moving further out
        assert ENV.box_min_m[i] - TOL <= after[i] <= ENV.box_max_m[i] + TOL or (
            (position[i] > ENV.box_max_m[i] and v[i] <= 0)
            or (position[i] < ENV.box_min_m[i] and v[i] >= 0)
        )
    rotation = rotation_from_rpy(rpy)
    allowed = max(ENV.max_tilt_rad, tilt_of_rotation(rotation)) + TOL
    for t in np.linspace(0.0, duration, 9):
        assert tilt_of_rotation(Rotation.from_rotvec(w * t) * rotation) <= allowed


def test_limit_twist_zeroes_the_component_leaving_at_a_face_only():
    at_floor = Pose((0.3, 0.0, ENV.z_min_m), (math.pi, 0.0, 0.0))
    twist = limit_twist(Twist((0.05, 0.0, -0.05), (0.0, 0.0, 0.0)), at_floor, 0.1, ENV).value
    assert twist.linear_m_s == pytest.approx((0.05, 0.0, 0.0))
    up = limit_twist(Twist((0.0, 0.0, 0.05), (0.0, 0.0, 0.0)), at_floor, 0.1, ENV).value
    assert up.linear_m_s == pytest.approx((0.0, 0.0, 0.05))


def test_limit_twist_keeps_rotation_about_the_vertical_at_the_tilt_limit():
    at_limit = Pose((0.3, 0.0, 0.2), (math.pi, ENV.max_tilt_rad, 0.0))
    twist = limit_twist(Twist((0.0, 0.0, 0.0), (0.0, 0.3, 0.2)), at_limit, 0.1, ENV).value
    assert twist.angular_rad_s == pytest.approx((0.0, 0.0, 0.2))


@pytest.mark.parametrize(
    ("change", "key"),
    [
        ({"x_max_m": 0.1}, "x_max_m"),
        ({"max_tilt_rad": 2.0}, "max_tilt_rad"),
        ({"max_linear_speed_m_s": True}, "max_linear_speed_m_s"),
    ],
)
def test_envelope_validation_names_the_key(change, key):
    with pytest.raises(ValueError, match=f"key '{key}'"):
        dataclasses.replace(ENV, **change)


@settings(max_examples=100, deadline=None)
@given(yaw=angles, turn=st.floats(0.02, 3.0), sign=st.sampled_from([-1.0, 1.0]))
def test_a_limited_turn_takes_the_whole_step_not_half_of_it(yaw, turn, sign):
    """Rounding in the stepped turn (a hair over ``max_step_rad``) must not halve the step."""
    previous = Pose((0.3, 0.0, 0.2), (math.pi, 0.0, yaw))
    target = Pose((0.3, 0.0, 0.2), (math.pi, 0.0, yaw + sign * turn))
    step = limit_pose(target, previous, ENV, STEP_M, STEP_RAD)
    assert step.limited == ("step",)
    stepped = rotation_from_rpy(step.value.rpy_rad)
    turned = _angle_between(stepped, rotation_from_rpy(previous.rpy_rad))
    assert turned == pytest.approx(STEP_RAD, abs=1e-9)


def test_each_clamp_reports_the_limits_that_acted():
    inside = Pose((0.3, 0.0, 0.2), (math.pi, 0.0, 0.0))
    assert limit_twist(Twist((0.01, 0.0, 0.0)), inside, 0.1, ENV).limited == ()
    fast = limit_twist(Twist((1.0, 0.0, 0.0), (0.0, 0.0, 0.0)), inside, 0.1, ENV)
    assert fast.limited == ("speed",)
    at_floor = Pose((0.3, 0.0, ENV.z_min_m), (math.pi, 0.0, 0.0))
    assert limit_twist(Twist((0.0, 0.0, -0.01)), at_floor, 0.1, ENV).limited == ("workspace",)
    at_limit = Pose((0.3, 0.0, 0.2), (math.pi, ENV.max_tilt_rad, 0.0))
    tilting = limit_twist(Twist((0.0, 0.0, 0.0), (0.0, 0.3, 0.0)), at_limit, 0.1, ENV)
    assert tilting.limited == ("tilt",)
    outside = Pose((0.0, 0.0, 0.2), (math.pi, 0.8, 0.0))
    assert clamp_pose(outside, ENV).limited == ("workspace", "tilt")
    far = limit_pose(Pose((0.4, 0.0, 0.2), inside.rpy_rad), inside, ENV, 0.002, 0.01)
    assert far.limited == ("step",)


def test_the_arm_envelope_holds_the_step_per_servo_command():
    with pytest.raises(ValueError, match="key 'max_step_m'"):
        SafetyEnvelope(max_step_m=0.0)
    assert SafetyEnvelope().max_tilt_rad == Envelope().max_tilt_rad  # the same base keys


@given(st.lists(st.floats(-3.0, 3.0), min_size=3, max_size=3))
def test_clamp_position_is_numpys_clip_bit_for_bit(xyz):
    """The clamp in plain floats gives what ``np.clip`` into the box gave, exactly (the arm
    twin's trajectories do not change)."""
    expected = np.clip(np.asarray(xyz, float), ENV.box_min_m, ENV.box_max_m)
    clamped = clamp_position(tuple(xyz), ENV)
    assert clamped.dtype == np.float64 and clamped.tobytes() == expected.tobytes()
    assert clamp_position(np.asarray(xyz), ENV).tobytes() == expected.tobytes()
