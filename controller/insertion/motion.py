"""Kinematics the machine needs: the plug's tip and its lowest edge, the yaw, twists about
the tip, bounded twists.
Vectors are NumPy arrays in B (m, m/s, rad/s); rotations and tilts are core.spatial's.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.spatial.transform import Rotation

from core.devices import Pose, Twist
from core.spatial import clamp_norm, cross, remembers_recent, rotation_from_rpy, vec3
from core.task_geometry import PlugGeometry


def tip_position(pose: Pose, length_m: float) -> np.ndarray:
    """Position in B of the plug's tip, ``length_m`` along T z from the TCP."""
    return np.asarray(pose.xyz_m, dtype=float) + _tip_offset_b(*pose.rpy_rad, length_m)


@remembers_recent(8)
def _tip_offset_b(roll: float, pitch: float, yaw: float, length_m: float) -> np.ndarray:
    """The tip less the TCP in B (m) with T at ``roll, pitch, yaw``; read only."""
    offset = rotation_from_rpy((roll, pitch, yaw)).apply([0.0, 0.0, length_m])
    offset.flags.writeable = False
    return offset


def lowest_edge(pose: Pose, plug: PlugGeometry, rotation: Rotation) -> np.ndarray:
    """The lowest of the four edge midpoints of the plug's tip face, in B (m), for the TCP
    at ``pose`` turned by ``rotation`` (T2B): the edge a tilted plug leads with, and the one
    caught in the opening (ALIGN turns about it)."""
    tip = tip_position(pose, plug.length_m)
    half_w, half_t = 0.5 * plug.width_m, 0.5 * plug.thickness_m
    offsets = rotation.apply(
        [[half_w, 0.0, 0.0], [-half_w, 0.0, 0.0], [0.0, half_t, 0.0], [0.0, -half_t, 0.0]]
    )
    return tip + offsets[int(np.argmin(offsets[:, 2]))]


def yaw_of(rotation: Rotation) -> float:
    """The heading (rad) of T x in B's x-y plane, for the T2B ``rotation``."""
    x_t = rotation.apply([1.0, 0.0, 0.0])
    return math.atan2(float(x_t[1]), float(x_t[0]))


def pivot_twist(
    p_tcp: np.ndarray, p_tip: np.ndarray, v_tip: np.ndarray, w: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """The TCP twist (v_tcp, w) that moves the tip at ``v_tip`` while turning at ``w``
    (all in B): v_tcp = v_tip + w x (p_tcp - p_tip), so a rigid body's tip point moves at
    v_tcp + w x (p_tip - p_tcp) = v_tip."""
    return v_tip + cross(w, p_tcp - p_tip), w


def bounded_twist(v: np.ndarray, w: np.ndarray, max_linear: float, max_angular: float) -> Twist:
    """A Twist with each part's norm bounded (the direction kept)."""
    v = clamp_norm(np.asarray(v, dtype=float), max_linear)
    w = clamp_norm(np.asarray(w, dtype=float), max_angular)
    return Twist(linear_m_s=vec3(v), angular_rad_s=vec3(w))


def rotation_error(current: Rotation, target: Rotation) -> np.ndarray:
    """Rotation vector in B (rad) that turns ``current`` into ``target``."""
    return (target * current.inv()).as_rotvec()


def approach_rotation(yaw_rad: float, tilt_rad: float, tilt_axis: str) -> Rotation:
    """The T2B rotation of the tilted approach: T x along the opening's width axis (yaw),
    T z straight down, then turned by ``tilt_rad`` about T's ``tilt_axis`` (``x`` or ``y``)."""
    down = Rotation.from_euler("z", yaw_rad) * Rotation.from_euler("x", math.pi)
    return down * Rotation.from_euler(tilt_axis, tilt_rad)
