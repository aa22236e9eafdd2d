"""Frames of the insertion scene and the conversions between them.

* B: the arm's base, z up. T: the tool (TCP at the plug's grasp point), ``Pose`` is T2B
  with the xArm's roll/pitch/yaw (``core.devices.Pose``); the tool axis z_T points from
  the gripper toward the plug's tip (down when the tool points down, rpy = (pi, 0, yaw)).
* The plug's width runs along x_T, its thickness along y_T: the fingers close along y_T,
  and the sensing finger (its gel) sits on the +y_T side of the plug.
* S, the sensor frame (docs/ARCHITECTURE.md): origin at the gel's centre, on the plug's
  wide face at the grasp point (``thickness_m / 2`` along +y_T from the TCP); x_S along
  the image columns = x_T (the plug's width); y_S along the image rows = z_T (toward the
  plug's tip: the tip is at the bottom of the image); z_S = x_S x y_S = -y_T, from the
  camera through the gel into the plug. S2T is a rotation by +90 degrees about x_T.
* H: the hole, origin at the opening's centre on the board surface, x along the
  opening's width, z up; its pose in B is (x, y, z, yaw about B's z).
"""

from __future__ import annotations

import math

import numpy as np

from core.devices import Pose

S_IN_T = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])
"""S2T rotation: its columns are x_S, y_S, z_S in T."""

S_IN_T_QUAT_WXYZ = (math.cos(math.pi / 4), math.sin(math.pi / 4), 0.0, 0.0)
"""The same rotation as MuJoCo's (w, x, y, z) quaternion."""


def quat_wxyz_from_pose(pose: Pose) -> np.ndarray:
    """MuJoCo's (w, x, y, z) quaternion of a ``Pose``'s orientation (T2B: R = Rz(yaw)
    Ry(pitch) Rx(roll)), in closed form (it runs at every sync of the scene)."""
    roll, pitch, yaw = (0.5 * float(a) for a in pose.rpy_rad)
    cr, sr = math.cos(roll), math.sin(roll)
    cp, sp = math.cos(pitch), math.sin(pitch)
    cy, sy = math.cos(yaw), math.sin(yaw)
    return np.array(
        [
            cy * cp * cr + sy * sp * sr,
            cy * cp * sr - sy * sp * cr,
            cy * sp * cr + sy * cp * sr,
            sy * cp * cr - cy * sp * sr,
        ]
    )


def upright_pose(xyz_m: tuple[float, float, float], yaw_rad: float) -> Pose:
    """The tool pointing straight down at ``xyz_m`` (B), its x turned by ``yaw_rad``."""
    return Pose(tuple(float(v) for v in xyz_m), (math.pi, 0.0, float(yaw_rad)))
