"""Kinematics the machine needs: the plug's tip, twists about the tip, bounded twists, tilt.
Vectors are NumPy arrays in B (m, m/s, rad/s).
"""

from __future__ import annotations

import math

import numpy as np
from scipy.spatial.transform import Rotation

from core.devices import Pose, Twist

DOWN_B = np.array([0.0, 0.0, -1.0])


def cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """a x b for 3-vectors (``np.cross`` costs ~20 us a call, too much for every tick)."""
    return np.array(
        [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
    )


def rotation_of(pose: Pose) -> Rotation:
    """T2B rotation of ``pose`` (R = Rz(yaw) Ry(pitch) Rx(roll), the xArm convention)."""
    return Rotation.from_euler("xyz", pose.rpy_rad)


def tip_position(pose: Pose, length_m: float) -> np.ndarray:
    """Position in B of the plug's tip, ``length_m`` along T z from the TCP."""
    return np.asarray(pose.xyz_m, dtype=float) + rotation_of(pose).apply([0.0, 0.0, length_m])


def pivot_twist(
    p_tcp: np.ndarray, p_tip: np.ndarray, v_tip: np.ndarray, w: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """The TCP twist (v_tcp, w) that moves the tip at ``v_tip`` while turning at ``w``
    (all in B): v_tcp = v_tip + w x (p_tcp - p_tip), so a rigid body's tip point moves at
    v_tcp + w x (p_tip - p_tcp) = v_tip."""
    return v_tip + cross(w, p_tcp - p_tip), w


def tilt_from_down(rotation: Rotation) -> tuple[float, np.ndarray]:
    """Angle (rad) between T z and straight down, and the unit axis in B turning T z toward
    straight down (zero when already aligned or exactly opposite)."""
    z_t = rotation.apply([0.0, 0.0, 1.0])
    turn = cross(z_t, DOWN_B)
    norm = float(np.linalg.norm(turn))
    angle = math.atan2(norm, float(np.dot(z_t, DOWN_B)))
    axis = turn / norm if norm > 1e-12 else np.zeros(3)
    return angle, axis


def clamp_norm(vector: np.ndarray, limit: float) -> np.ndarray:
    """``vector`` scaled down to a norm of at most ``limit``."""
    norm = float(np.linalg.norm(vector))
    return vector * (limit / norm) if norm > limit else vector


def bounded_twist(v: np.ndarray, w: np.ndarray, max_linear: float, max_angular: float) -> Twist:
    """A Twist with each part's norm bounded (the direction kept)."""
    v = clamp_norm(np.asarray(v, dtype=float), max_linear)
    w = clamp_norm(np.asarray(w, dtype=float), max_angular)
    return Twist(linear_m_s=tuple(map(float, v)), angular_rad_s=tuple(map(float, w)))


def rotation_error(current: Rotation, target: Rotation) -> np.ndarray:
    """Rotation vector in B (rad) that turns ``current`` into ``target``."""
    return (target * current.inv()).as_rotvec()


def approach_rotation(yaw_rad: float, tilt_rad: float, tilt_axis: str) -> Rotation:
    """The T2B rotation of the tilted approach: T x along the opening's width axis (yaw),
    T z straight down, then turned by ``tilt_rad`` about T's ``tilt_axis`` (``x`` or ``y``)."""
    down = Rotation.from_euler("z", yaw_rad) * Rotation.from_euler("x", math.pi)
    return down * Rotation.from_euler(tilt_axis, tilt_rad)
