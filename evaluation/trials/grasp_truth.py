"""The plug's true pose in the hand, in the machine's terms, to score FEEL's estimate
(``controller.insertion.grasp_estimate``) per seed.

The scene draws the grasp in the sensor frame S (``drivers.sim.scenes.insertion.draws``:
the plug's axis along y_S toward the tip); the machine's tool frame T has S's x, y, z along
T's x, z and -y (the task's ``signals.torque_axes``). In T the plug's axis p and its tip are
p = M R_S y_S and tip = M (across, along, 0) + L p; the width-plane tilt (the one FEEL
finds) is atan2(p_x, p_z), the thickness-plane tilt atan2(p_y, p_z).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from drivers.sim.scenes.insertion.draws import GraspPose

# S's axes as columns in T: x_S = T x, y_S = T z, z_S = -T y
S2T = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])


@dataclass(frozen=True)
class GraspTruth:
    """The plug's true tilts in the hand (rad: the width plane, about T y, positive with the
    tip toward +T x; the thickness plane, about T x) and its tip in T (m)."""

    tilt_width_rad: float
    tilt_thickness_rad: float
    tip_t_m: np.ndarray


def grasp_truth(grasp: GraspPose, length_m: float) -> GraspTruth:
    """The truth of ``grasp`` for a plug ``length_m`` from the grasp point to the tip."""
    axis_t = S2T @ grasp.rotation() @ np.array([0.0, 1.0, 0.0])
    offset_t = S2T @ grasp.offset_s()
    tip_t = offset_t + length_m * axis_t
    return GraspTruth(
        math.atan2(float(axis_t[0]), float(axis_t[2])),
        math.atan2(float(axis_t[1]), float(axis_t[2])),
        tip_t,
    )
