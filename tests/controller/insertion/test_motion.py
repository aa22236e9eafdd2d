"""Kinematics: the tip-pivot twist, the approach rotation, bounded twists, the search patterns."""

import math

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from controller.insertion.motion import (
    approach_rotation,
    bounded_twist,
    pivot_twist,
    tip_position,
)
from controller.insertion.search_path import SearchPattern
from core.devices import Pose
from core.spatial import rpy_from_rotation, tilt_of_tool_axis, tool_z_in_base


def test_pivot_twist_keeps_the_tip_still_to_first_order():
    rng = np.random.default_rng(3)
    for _ in range(20):
        rotation = Rotation.random(random_state=rng)
        p_tcp = rng.normal(0, 0.3, 3)
        length = 0.02
        p_tip = p_tcp + rotation.apply([0, 0, length])
        w = rng.normal(0, 0.5, 3)
        v_tip = rng.normal(0, 0.01, 3)
        v_tcp, w_out = pivot_twist(p_tcp, p_tip, v_tip, w)
        np.testing.assert_array_equal(w_out, w)
        # the rigid body's tip velocity: v_tcp + w x (p_tip - p_tcp)
        np.testing.assert_allclose(v_tcp + np.cross(w, p_tip - p_tcp), v_tip, atol=1e-15)
        # integrated over a short step, the tip moves by v_tip dt (second-order error)
        dt = 1e-4
        moved = Rotation.from_rotvec(w * dt) * rotation
        pose = Pose(tuple(p_tcp + v_tcp * dt), rpy_from_rotation(moved))
        np.testing.assert_allclose(tip_position(pose, length), p_tip + v_tip * dt, atol=1e-9)


def test_pivot_twist_with_zero_tip_velocity_moves_the_tcp_on_a_circle():
    v_tcp, _ = pivot_twist(np.zeros(3), np.array([0, 0, -0.02]), np.zeros(3), np.array([1, 0, 0]))
    np.testing.assert_allclose(v_tcp, [0, -0.02, 0])  # w x (p_tcp - p_tip) = x cross 0.02 z


def test_tip_position_straight_down():
    pose = Pose((0.1, 0.2, 0.3), (math.pi, 0.0, 0.0))
    np.testing.assert_allclose(tip_position(pose, 0.015), [0.1, 0.2, 0.285], atol=1e-12)


def test_approach_rotation_tilts_by_the_angle_and_keeps_the_width_axis():
    rotation = approach_rotation(0.3, math.radians(15), "x")
    angle, axis = tilt_of_tool_axis(tool_z_in_base(rotation))
    assert angle == pytest.approx(math.radians(15))
    np.testing.assert_allclose(
        rotation.apply([1, 0, 0]), [math.cos(0.3), math.sin(0.3), 0], atol=1e-12
    )
    # turning about the axis by the angle brings T z straight down
    upright = Rotation.from_rotvec(axis * angle) * rotation
    np.testing.assert_allclose(upright.apply([0, 0, 1]), [0, 0, -1], atol=1e-12)


def test_bounded_twist_scales_each_part_keeping_direction():
    twist = bounded_twist(np.array([3.0, 4.0, 0.0]), np.array([0.0, 0.0, 0.1]), 1.0, 0.5)
    np.testing.assert_allclose(twist.linear_m_s, [0.6, 0.8, 0.0])
    np.testing.assert_allclose(twist.angular_rad_s, [0.0, 0.0, 0.1])


@pytest.mark.parametrize("kind", ["spiral", "raster"])
def test_search_pattern_is_continuous_bounded_and_covers_the_square(kind):
    half, pitch = 0.003, 0.0008
    pattern = SearchPattern(kind, pitch, half)
    s = np.arange(0.0, 2.5 * pattern.length_m, 2e-5)
    points = np.array([pattern.offset(x) for x in s])
    np.testing.assert_allclose(points[0], [0.0, 0.0], atol=1e-12)  # starts at the centre
    steps = np.linalg.norm(np.diff(points, axis=0), axis=1)
    assert steps.max() <= 2e-5 * 1.6 + 1e-9 or kind == "spiral"  # no jumps (spiral: centre)
    assert steps.max() < 5e-4
    assert np.abs(points).max() <= math.sqrt(2) * half + 1e-9
    grid = np.stack(np.meshgrid(np.linspace(-half, half, 13), np.linspace(-half, half, 13)), -1)
    grid = grid.reshape(-1, 2)
    gaps = np.min(np.linalg.norm(grid[:, None, :] - points[None, ::10, :], axis=2), axis=1)
    assert gaps.max() <= pitch  # every point of the square lies within a pitch of the path


def test_search_pattern_without_uncertainty_stays_at_the_centre():
    for kind in ("spiral", "raster"):
        pattern = SearchPattern(kind, 0.001, 0.0)
        np.testing.assert_allclose(pattern.offset(0.01), [0.0, 0.0], atol=1e-12)
