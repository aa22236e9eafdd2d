"""The plug's true pose in the hand, in the machine's terms, to score FEEL's estimate
(``controller.insertion.grasp_estimate``) per seed.

The scene draws the grasp in the sensor frame S (``drivers.sim.scenes.insertion.draws``:
the plug's axis along y_S toward the tip); the machine's tool frame T has S's x, y, z along
T's x, z and -y (the task's ``signals.torque_axes``). In T the plug's axis p and its tip are
p = M R_S y_S and tip = M (across, along, 0) + L p; the width-plane tilt (the one FEEL
finds) is atan2(p_x, p_z), the thickness-plane tilt atan2(p_y, p_z).

FEEL by rocking finds where the tip's face lies flat on the board, so it measures the plug's
tilt from the board's normal, the receptacle's axis (the board tilts by up to a degree,
``board_tilt_rad``): ``receptacle_tilts_rad`` gives that axis's tilts in T's two planes with
the tool upright at the hole's yaw (T x along H x, T y and T z along -H y and -H z).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.spatial.transform import Rotation

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


def receptacle_tilts_rad(board_tilt_rad: tuple[float, float]) -> tuple[float, float]:
    """The receptacle's axis (into the board, -the board's normal) in T's width plane (about
    T y) and its thickness plane (about T x), rad, the signs of ``GraspTruth``'s tilts, for a
    board tilted by ``board_tilt_rad`` about H's x and then its y (rad), the tool upright at
    the hole's yaw."""
    into_h = Rotation.from_euler("xy", board_tilt_rad).apply([0.0, 0.0, -1.0])
    into_t = np.array([into_h[0], -into_h[1], -into_h[2]])
    return (
        math.atan2(float(into_t[0]), float(into_t[2])),
        math.atan2(float(into_t[1]), float(into_t[2])),
    )
