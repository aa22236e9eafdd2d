"""Kinematics the machine needs: the plug's tip, twists about the tip, bounded pose servoing,
and the search patterns. Vectors are NumPy arrays in B (m, m/s, rad/s) unless named ``_t``.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.spatial.transform import Rotation

from drivers.base import Pose, Twist

DOWN_B = np.array([0.0, 0.0, -1.0])


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
    return v_tip + np.cross(w, p_tcp - p_tip), w


def tilt_from_down(rotation: Rotation) -> tuple[float, np.ndarray]:
    """Angle (rad) between T z and straight down, and the unit axis in B turning T z toward
    straight down (zero when already aligned or exactly opposite)."""
    z_t = rotation.apply([0.0, 0.0, 1.0])
    cross = np.cross(z_t, DOWN_B)
    norm = float(np.linalg.norm(cross))
    angle = math.atan2(norm, float(np.dot(z_t, DOWN_B)))
    axis = cross / norm if norm > 1e-12 else np.zeros(3)
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


class SearchPattern:
    """A planar search path in the opening's frame (u along its width axis, v across),
    centred on the nominal opening and parameterised by the path length s (m). Past its end
    the path is run backwards and forwards again (a triangle wave in s), so the tip never
    jumps.

    ``spiral``: Archimedean, r = pitch theta / (2 pi), out to radius sqrt(2) half_width
    (the corners of the uncertainty square); s ~ pitch theta^2 / (4 pi).
    ``raster``: from the centre straight to the corner (-half_width, -half_width), then lines
    along u from -half_width to half_width, ``pitch`` apart in v.
    """

    def __init__(self, kind: str, pitch_m: float, half_width_m: float) -> None:
        self.kind = kind
        self.pitch_m = pitch_m
        self.half_width_m = half_width_m
        if kind == "spiral":
            self._a = pitch_m / (2.0 * math.pi)
            theta_max = math.sqrt(2.0) * half_width_m / self._a
            self.length_m = self._a * theta_max**2 / 2.0
        else:
            self._lines = int(math.floor(2.0 * half_width_m / pitch_m + 1e-9)) + 1
            self._lead_m = math.sqrt(2.0) * half_width_m
            span = 2.0 * half_width_m
            self.length_m = self._lead_m + self._lines * span + (self._lines - 1) * pitch_m

    def offset(self, s_m: float) -> np.ndarray:
        """(u, v) offset in m at path length ``s_m`` (folded into the path)."""
        if self.length_m <= 0.0:
            return np.zeros(2)
        period = 2.0 * self.length_m
        s = math.fmod(max(s_m, 0.0), period)
        s = period - s if s > self.length_m else s
        return self._spiral(s) if self.kind == "spiral" else self._raster(s)

    def _spiral(self, s: float) -> np.ndarray:
        theta = math.sqrt(2.0 * s / self._a)
        r = self._a * theta
        return np.array([r * math.cos(theta), r * math.sin(theta)])

    def _raster(self, s: float) -> np.ndarray:
        if s < self._lead_m:
            return -np.full(2, s / math.sqrt(2.0))
        s -= self._lead_m
        span = 2.0 * self.half_width_m
        unit = span + self.pitch_m
        line = min(int(s // unit), self._lines - 1)
        along = s - line * unit
        v = -self.half_width_m + line * self.pitch_m
        if along > span:  # the step to the next line
            v += along - span
            along = span
        u = -self.half_width_m + along if line % 2 == 0 else self.half_width_m - along
        return np.array([u, v])
