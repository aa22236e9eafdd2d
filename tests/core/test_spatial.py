"""Rotations and tilts (core/spatial.py): the xArm roll/pitch/yaw convention, the tilt from
the downward vertical and its axis, seeded property tests."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

from core.spatial import (
    DOWN_B,
    clamp_norm,
    cross,
    rotation_from_rpy,
    rpy_from_rotation,
    tilt_of_rotation,
    tilt_of_tool_axis,
    tilts_of_tool_axes,
    tool_z_from_rpy,
    tool_z_in_base,
    turned,
)

angles = st.floats(-math.pi, math.pi)
rotations = st.builds(
    lambda q: Rotation.from_quat(q),
    st.tuples(*(st.floats(-1.0, 1.0),) * 4).filter(lambda q: np.linalg.norm(q) > 0.1),
)
away_from_gimbal_lock = st.tuples(angles, st.floats(-1.5, 1.5), angles).map(rotation_from_rpy)
vectors = st.tuples(*(st.floats(-10.0, 10.0),) * 3).map(np.array)


def test_a_remembered_rotation_is_scipys_to_the_bit():
    """rotation_from_rpy keeps its last few Rotations (core.spatial.remembers_recent): asked
    again, or for angles that differ only in a zero's sign, it gives scipy's own to the bit."""
    poses = [(0.1, -0.2, 0.3), (math.pi, -0.0, 0.0), (math.pi, 0.0, 0.0), (-0.0, 0.0, -0.0)]
    for rpy in [*poses, *poses[::-1], *poses]:
        expected = Rotation.from_euler("xyz", rpy).as_quat()
        assert rotation_from_rpy(rpy).as_quat().tobytes() == expected.tobytes()
        assert rotation_from_rpy(np.array(rpy)).as_quat().tobytes() == expected.tobytes()


def test_rpy_is_fixed_axis_roll_then_pitch_then_yaw():
    roll, pitch, yaw = 0.3, -0.2, 1.1
    expected = (
        Rotation.from_rotvec([0, 0, yaw])
        * Rotation.from_rotvec([0, pitch, 0])
        * Rotation.from_rotvec([roll, 0, 0])
    )
    np.testing.assert_allclose(
        rotation_from_rpy((roll, pitch, yaw)).as_matrix(), expected.as_matrix(), atol=1e-15
    )


@settings(max_examples=200, deadline=None)
@given(rotation=away_from_gimbal_lock)
def test_rpy_round_trips(rotation):
    again = rotation_from_rpy(rpy_from_rotation(rotation))
    assert (again * rotation.inv()).magnitude() < 1e-9


def test_rpy_from_rotation_near_keeps_roll_on_the_side_of_the_reference():
    rotation = rotation_from_rpy((math.pi, 0.0, 0.0))
    assert rpy_from_rotation(rotation, (3.1, 0.0, 0.0))[0] == pytest.approx(math.pi)
    assert rpy_from_rotation(rotation, (-3.1, 0.0, 0.0))[0] == pytest.approx(-math.pi)


@settings(max_examples=200, deadline=None)
@given(rotation=away_from_gimbal_lock, reference=st.tuples(angles, angles, angles))
def test_rpy_near_a_reference_is_the_same_rotation_within_pi_of_it(rotation, reference):
    rpy = rpy_from_rotation(rotation, reference)
    assert (rotation_from_rpy(rpy) * rotation.inv()).magnitude() < 1e-9
    assert all(abs(a - r) <= math.pi + 1e-9 for a, r in zip(rpy, reference, strict=True))


def test_tilt_is_zero_pointing_down_and_grows_with_pitch():
    assert tilt_of_rotation(rotation_from_rpy((math.pi, 0.0, 0.7))) == pytest.approx(0.0, abs=1e-12)
    assert tilt_of_rotation(rotation_from_rpy((math.pi, 0.3, 0.0))) == pytest.approx(0.3)
    assert tilt_of_rotation(rotation_from_rpy((0.0, 0.0, 0.0))) == pytest.approx(math.pi)


@settings(max_examples=200, deadline=None)
@given(rotation=rotations, spin=angles)
def test_the_tilt_ignores_a_turn_about_the_vertical(rotation, spin):
    turned = Rotation.from_rotvec([0.0, 0.0, spin]) * rotation
    assert tilt_of_rotation(turned) == pytest.approx(tilt_of_rotation(rotation), abs=1e-9)


@settings(max_examples=200, deadline=None)
@given(rotation=rotations)
def test_turning_about_the_tilt_axis_by_the_tilt_points_the_tool_down(rotation):
    angle, axis = tilt_of_tool_axis(tool_z_in_base(rotation))
    assert 0.0 <= angle <= math.pi
    if angle < math.pi - 1e-6:  # pointing straight up has no unique axis
        upright = Rotation.from_rotvec(axis * angle) * rotation
        np.testing.assert_allclose(tool_z_in_base(upright), DOWN_B, atol=1e-9)
        assert axis[2] == 0.0 and (angle < 1e-9 or np.linalg.norm(axis) == pytest.approx(1.0))


@settings(max_examples=200, deadline=None)
@given(a=vectors, b=vectors)
def test_cross_agrees_with_numpy(a, b):
    np.testing.assert_array_equal(cross(a, b), np.cross(a, b))


@settings(max_examples=200, deadline=None)
@given(vector=vectors, limit=st.just(0.0) | st.floats(1e-6, 20.0))
def test_clamp_norm_bounds_the_norm_and_keeps_the_direction(vector, limit):
    clamped = clamp_norm(vector, limit)
    assert np.linalg.norm(clamped) <= limit * (1 + 1e-12) or clamped is vector
    if np.linalg.norm(vector) <= limit:
        assert clamped is vector
    else:
        np.testing.assert_allclose(np.cross(clamped, vector), 0.0, atol=1e-9)
        assert np.dot(clamped, vector) >= 0.0


def test_the_tilts_of_many_tool_axes_are_each_axis_tilt():
    rng = np.random.default_rng(3)
    axes = rng.normal(size=(200, 3))
    axes /= np.linalg.norm(axes, axis=1, keepdims=True)
    axes[0], axes[1] = (0.0, 0.0, -1.0), (0.0, 0.0, 1.0)  # straight down, straight up
    expected = [tilt_of_tool_axis(axis)[0] for axis in axes]
    np.testing.assert_allclose(tilts_of_tool_axes(axes), expected, rtol=0, atol=1e-15)
    assert tilts_of_tool_axes(axes)[0] == 0.0 and tilts_of_tool_axes(axes)[1] == math.pi


@settings(max_examples=200, deadline=None)
@given(st.tuples(angles, angles, angles))
def test_the_tool_axis_in_closed_form_is_scipys(rpy):
    expected = tool_z_in_base(rotation_from_rpy(rpy))
    np.testing.assert_allclose(tool_z_from_rpy(rpy), expected, rtol=0, atol=1e-15)


@settings(max_examples=200, deadline=None)
@given(st.tuples(*(st.floats(-3.0, 3.0),) * 3), st.tuples(angles, angles, angles))
def test_turning_by_rodrigues_is_scipys_rotation(angular, rpy):
    vector, angular = tool_z_from_rpy(rpy), np.array(angular)
    times = np.linspace(0.01, 0.05, 5)
    expected = Rotation.from_rotvec(np.outer(times, angular)).apply(vector)
    np.testing.assert_allclose(turned(vector, angular, times), expected, rtol=0, atol=1e-14)
