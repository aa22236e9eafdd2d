"""FEEL's estimate of the plug in the hand (controller/insertion/grasp_estimate.py): the
tilt from the TCP rotation at which the tip's face lies flat, and where the tip is."""

import math

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from controller.insertion.grasp_estimate import GraspEstimate
from controller.insertion.motion import approach_rotation


@pytest.mark.parametrize("tilt", [-0.08, -0.01, 0.0, 0.03, 0.087])
@pytest.mark.parametrize(("yaw", "approach_tilt"), [(0.0, 0.0), (0.05, 0.2618), (-0.4, -0.1)])
def test_the_flat_rotation_gives_back_the_tilt_in_the_hand(tilt, yaw, approach_tilt):
    # the TCP turned so the plug, turned by ``tilt`` about T y in the hand, has its width
    # edge level: the approach rotation, turned back by the tilt about T y
    flat = approach_rotation(yaw, approach_tilt, "x") * Rotation.from_euler("y", -tilt)
    edge_b = flat.apply([math.cos(tilt), 0.0, -math.sin(tilt)])
    assert edge_b[2] == pytest.approx(0.0, abs=1e-12)  # the premise: the edge is level
    estimate = GraspEstimate.from_flat_rotation(flat, 0.02)
    assert estimate.tilt_rad == pytest.approx(tilt, abs=1e-9)


def test_a_level_edge_at_another_tilt_gives_another_estimate():
    flat = approach_rotation(0.0, 0.0, "x") * Rotation.from_euler("y", -0.05)
    assert GraspEstimate.from_flat_rotation(flat, 0.02).tilt_rad != pytest.approx(0.03)


def test_the_tip_moves_along_t_x_by_the_lever_and_the_shift_is_zero_without_tilt():
    estimate = GraspEstimate(0.05, 0.02)
    assert estimate.tip_t == pytest.approx([0.02 * math.sin(0.05), 0.0, 0.02 * math.cos(0.05)])
    down = approach_rotation(0.0, 0.0, "x")
    shift = estimate.tip_shift_b(down)
    # T x is B x and T z is -B z when the tool points straight down
    assert shift == pytest.approx([0.02 * math.sin(0.05), 0.0, -(0.02 * math.cos(0.05) - 0.02)])
    assert np.allclose(GraspEstimate(0.0, 0.02).tip_shift_b(down), 0.0)
