"""Rotations and tilts of the tool, with their frames in the names.

Frames (docs/ARCHITECTURE.md): B the arm base (z_B up), T the tool at the grasp point (z_T from
the gripper toward the plug's tip). A ``Pose`` (core/devices.py) is T2B: its ``xyz_m`` is the
TCP in B (m) and its ``rpy_rad`` the orientation of T in B as fixed-axis roll, pitch, yaw
(rad): R_T2B = Rz(yaw) @ Ry(pitch) @ Rx(roll), the xArm convention. This module is the one
place that convention is written; everything else converts through ``rotation_from_rpy`` and
``rpy_from_rotation``. Rotations are scipy ``Rotation`` objects, or, where one orientation is
turned hundreds of times a second, quaternion tuples (``core.quaternion``; ``quat_from_rpy``
and ``rpy_from_quat``).

The tilt of the tool is the angle (rad, in [0, pi]) between z_T and the downward vertical
-z_B: 0 with the tool pointing straight down.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable
from typing import TypeVar

import numpy as np
from scipy.spatial.transform import Rotation

from core import quaternion
from core.quaternion import Quat

Vec3 = tuple[float, float, float]

DOWN_B = np.array([0.0, 0.0, -1.0])
"""The downward vertical, a unit vector in B."""

_RPY_AXES = "xyz"  # scipy's extrinsic (fixed-axis) x, then y, then z: R = Rz @ Ry @ Rx


R = TypeVar("R")


def remembers_recent(size: int) -> Callable[[Callable[..., R]], Callable[..., R]]:
    """A pure function of floats, made to keep its last ``size`` results (an LRU cache,
    thread-safe), keyed by the arguments' exact bits (so -0.0 and 0.0 stay apart; the function
    gets the same floats back): a tick turns one pose or one pass's yaw into a Rotation in many
    places, and scipy's Rotation is slow to make. Only for results never changed in place (a
    Rotation, a read-only array)."""

    def wrap(function: Callable[..., R]) -> Callable[..., R]:
        @functools.lru_cache(maxsize=size)
        def by_bits(bits: tuple[str, ...]) -> R:
            return function(*(float.fromhex(b) for b in bits))

        @functools.wraps(function)
        def call(*values: float) -> R:
            return by_bits(tuple(float(value).hex() for value in values))

        return call

    return wrap


@remembers_recent(8)
def _rotation_from_angles(roll: float, pitch: float, yaw: float) -> Rotation:
    return Rotation.from_euler(_RPY_AXES, [roll, pitch, yaw])


def rotation_from_rpy(rpy_rad: tuple[float, float, float] | np.ndarray) -> Rotation:
    """R_T2B from ``Pose.rpy_rad`` (fixed-axis roll, pitch, yaw, rad); an array of them gives
    one Rotation of many."""
    angles = np.asarray(rpy_rad, dtype=float)
    if angles.shape != (3,):
        return Rotation.from_euler(_RPY_AXES, angles)
    return _rotation_from_angles(*angles)


def rpy_from_rotation(
    T2B: Rotation, near_rpy_rad: tuple[float, float, float] | None = None
) -> tuple[float, float, float]:
    """Roll, pitch, yaw (rad) of R_T2B; with ``near_rpy_rad``, each angle is wrapped by 2*pi
    to lie nearest the reference (so that a roll near +pi is not reported as -pi)."""
    rpy = T2B.as_euler(_RPY_AXES)
    if near_rpy_rad is not None:
        reference = np.asarray(near_rpy_rad, dtype=float)
        rpy = rpy + 2.0 * np.pi * np.round((reference - rpy) / (2.0 * np.pi))
    return vec3(rpy)


def quat_from_rpy(rpy_rad: tuple[float, float, float]) -> Quat:
    """R_T2B of ``Pose.rpy_rad`` as a quaternion (x, y, z, w): Rz(yaw) Ry(pitch) Rx(roll)."""
    roll, pitch, yaw = (0.5 * float(a) for a in rpy_rad)
    cr, sr = math.cos(roll), math.sin(roll)
    cp, sp = math.cos(pitch), math.sin(pitch)
    cy, sy = math.cos(yaw), math.sin(yaw)
    return (
        cy * cp * sr - sy * sp * cr,
        cy * sp * cr + sy * cp * sr,
        sy * cp * cr - cy * sp * sr,
        cy * cp * cr + sy * sp * sr,
    )


def rpy_from_quat(
    T2B: Quat, near_rpy_rad: tuple[float, float, float] | None = None
) -> tuple[float, float, float]:
    """``rpy_from_rotation`` of a quaternion (x, y, z, w), in closed form away from pitch
    +-pi/2 (where scipy's gimbal-lock rule decides)."""
    x, y, z, w = T2B
    r20 = 2.0 * (x * z - w * y)
    if abs(r20) > 1.0 - 1e-9:
        return rpy_from_rotation(Rotation.from_quat(T2B), near_rpy_rad)
    rpy = (
        math.atan2(2.0 * (y * z + w * x), 1.0 - 2.0 * (x * x + y * y)),
        -math.asin(r20),
        math.atan2(2.0 * (x * y + w * z), 1.0 - 2.0 * (y * y + z * z)),
    )
    if near_rpy_rad is None:
        return rpy
    two_pi = 2.0 * math.pi
    r, p, yw = (
        a + two_pi * round((ref - a) / two_pi) for a, ref in zip(rpy, near_rpy_rad, strict=True)
    )
    return (r, p, yw)


def tilt_of_quat(T2B: Quat) -> tuple[float, Vec3]:
    """``tilt_of_tool_axis`` of the tool oriented by a quaternion, in closed form: the tilt
    (rad) and the unit horizontal axis (x, y, 0) in B about which turning by it brings z_T
    straight down (zeros when straight down or up)."""
    zx, zy, zz = quaternion.z_axis(T2B)
    # z_T x -z_B = (-zy, zx, 0)
    norm = math.hypot(zx, zy)
    angle = math.atan2(norm, -zz)
    if norm <= 1e-12:
        return angle, (0.0, 0.0, 0.0)
    return angle, (-zy / norm, zx / norm, 0.0)


def tool_z_in_base(T2B: Rotation) -> np.ndarray:
    """z_T expressed in B (a unit 3-vector): the third column of R_T2B."""
    return T2B.as_matrix()[:, 2]


def tilt_of_tool_axis(z_T_in_B: np.ndarray) -> tuple[float, np.ndarray]:
    """The tilt (rad) of a tool whose z-axis in B is ``z_T_in_B`` (unit 3-vector), and the
    unit axis in B about which turning by the tilt brings z_T straight down (the shortest
    arc, ``z_T x -z_B`` normalised; zeros when pointing straight down or straight up)."""
    turn = cross(z_T_in_B, DOWN_B)
    norm = float(np.linalg.norm(turn))
    angle = math.atan2(norm, float(np.dot(z_T_in_B, DOWN_B)))
    axis = turn / norm if norm > 1e-12 else np.zeros(3)
    return angle, axis


def tilts_of_tool_axes(z_T_in_B: np.ndarray) -> np.ndarray:
    """The tilts (rad, in [0, pi]) of tools whose z-axes in B are the rows of ``z_T_in_B``
    (N x 3, unit rows): ``tilt_of_tool_axis``'s angle for each row, computed at once."""
    horizontal = np.hypot(z_T_in_B[:, 0], z_T_in_B[:, 1])  # |z_T x -z_B|
    return np.arctan2(horizontal, -z_T_in_B[:, 2])  # z_T . -z_B


def tool_z_from_rpy(rpy_rad: tuple[float, float, float]) -> np.ndarray:
    """z_T in B (a unit 3-vector) of ``Pose.rpy_rad``: the third column of
    Rz(yaw) Ry(pitch) Rx(roll), in closed form (``rotation_from_rpy`` costs ~0.25 ms a call,
    too much for every command's tilt check; the same vector to round-off)."""
    roll, pitch, yaw = (float(a) for a in rpy_rad)
    cr, sr = math.cos(roll), math.sin(roll)
    cp, sp = math.cos(pitch), math.sin(pitch)
    cy, sy = math.cos(yaw), math.sin(yaw)
    return np.array([cy * sp * cr + sy * sr, sy * sp * cr - cy * sr, cp * cr])


def turned(vector: np.ndarray, angular_rad_s: np.ndarray, times_s: np.ndarray) -> np.ndarray:
    """``vector`` (3,) turned at the constant angular velocity ``angular_rad_s`` (rad/s, in
    the vector's frame) for each of ``times_s`` (N,): the (N, 3) rows, by Rodrigues' formula
    (``Rotation.from_rotvec(...).apply`` costs ~0.2 ms a call; the same rows to round-off)."""
    speed = math.sqrt(float(np.dot(angular_rad_s, angular_rad_s)))
    if speed == 0.0:
        return np.tile(vector, (len(times_s), 1))
    axis = angular_rad_s / speed
    angles = speed * np.asarray(times_s, dtype=float)
    cos, sin = np.cos(angles)[:, None], np.sin(angles)[:, None]
    along = axis * float(np.dot(axis, vector))
    return vector * cos + cross(axis, vector) * sin + along * (1.0 - cos)


def tilt_of_rotation(T2B: Rotation) -> float:
    """The tilt (rad, in [0, pi]) of the tool oriented by R_T2B."""
    return tilt_of_tool_axis(tool_z_in_base(T2B))[0]


def cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """a x b for 3-vectors (``np.cross`` costs ~20 us a call, too much for every tick)."""
    return np.array(
        [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
    )


def clamp_norm(vector: np.ndarray, limit: float) -> np.ndarray:
    """``vector`` scaled down to a norm of at most ``limit`` (its direction kept); the same
    object when already within."""
    norm = float(np.linalg.norm(vector))
    return vector * (limit / norm) if norm > limit else vector


def vec3(values: np.ndarray | tuple[float, ...]) -> tuple[float, float, float]:
    """Three Python floats from a 3-vector (the tuples of ``Pose`` and ``Twist``)."""
    x, y, z = (float(v) for v in values)
    return (x, y, z)
