"""Safety envelope of the tool (TCP, frame T) in the arm base frame B: pure clamp functions.

Every function maps a requested command to the nearest command inside the envelope; none
raises on an out-of-envelope request. Units: m, rad, m/s, rad/s, s. Orientations are
``Pose.rpy_rad`` (R = Rz(yaw) @ Ry(pitch) @ Rx(roll), the xArm convention).

Policy, applied by the arm driver to every command whatever the caller sends:

* **Position**: each coordinate of the TCP is clipped into the workspace box
  ``[x_min_m, x_max_m] x [y_min_m, y_max_m] x [z_min_m, z_max_m]`` in B.
* **Tilt**: the angle between the tool z-axis and the downward vertical ``-z_B`` (tool
  pointing down = 0 tilt). A more tilted orientation is rotated toward vertical along the
  shortest arc (about the horizontal axis ``z_T x -z_B``) until its tilt is exactly
  ``max_tilt_rad``; the rotation about the vertical is kept. A tool pointing straight up has
  no unique shortest arc; it is tipped about ``x_B``.
* **Step** (one servo command): the position moves at most ``max_step_m`` and the
  orientation turns at most ``max_step_rad`` from the previous command, each along the
  straight line / geodesic toward the (clamped) target. Stepping along a geodesic between
  two orientations inside the tilt cone can leave the cone slightly, so the stepped
  orientation is tilt-clamped again; if that pushes the turn above ``max_step_rad`` the
  step fraction is halved once, which is enough: the re-clamp turns by at most the tilt
  excess, itself at most the stepped turn, so the total is at most twice half the bound.
* **Twist** (velocity mode, held for ``duration_s``): the linear speed is scaled down to
  ``max_speed_m_s`` and the angular speed to ``max_angular_speed_rad_s`` (directions kept);
  then each linear component is limited so the position after ``duration_s`` stays in the
  box (a component pointing out of the box at its face becomes zero; motion back into the
  box is allowed); if the rotation would tilt the tool beyond ``max_tilt_rad`` (or beyond
  its current tilt, if already outside) within ``duration_s``, the horizontal angular
  components are zeroed, leaving only the rotation about the vertical, which keeps the tilt.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np
from scipy.spatial.transform import Rotation

from core.config import Config, number
from core.devices import Pose, Twist
from core.task_geometry import WorkspaceBox

_DOWN_B = np.array([0.0, 0.0, -1.0])
_ROUNDING_RAD = 1e-12  # tilts this close to the limit count as within (float round-off)
_TWIST_TILT_SAMPLES = 8  # points along the velocity horizon at which the tilt is checked


@dataclass(frozen=True)
class SafetyEnvelope(WorkspaceBox, Config):
    """Limits on the TCP: a box in B (m), speeds, the step per servo command, the tilt."""

    x_min_m: float = number(-2.0, 2.0)
    x_max_m: float = number(-2.0, 2.0)
    y_min_m: float = number(-2.0, 2.0)
    y_max_m: float = number(-2.0, 2.0)
    z_min_m: float = number(-2.0, 2.0)
    z_max_m: float = number(-2.0, 2.0)
    max_speed_m_s: float = number(1e-4, 1.0)
    max_angular_speed_rad_s: float = number(1e-4, math.pi)
    max_step_m: float = number(1e-6, 0.05)
    max_step_rad: float = number(1e-6, 0.5)
    max_tilt_rad: float = number(0.0, math.pi / 2)



def require_finite(name: str, values: Iterable[float]) -> None:
    """Refuse a command holding anything but finite numbers (ValueError naming it), before
    it reaches the envelope's clamps, which would carry a NaN through."""
    values = tuple(values)
    try:
        finite = all(math.isfinite(float(v)) for v in values)
    except (TypeError, ValueError):
        finite = False
    if not finite:
        raise ValueError(f"{name}: expected finite numbers, got {values!r}")


def rotation_from_rpy(rpy_rad: tuple[float, float, float] | np.ndarray) -> Rotation:
    """Rotation T2B from fixed-axis roll, pitch, yaw (R = Rz @ Ry @ Rx), radians."""
    return Rotation.from_euler("xyz", rpy_rad)


def tilt_rad(rotation: Rotation) -> float:
    """Angle (rad, in [0, pi]) between the tool z-axis and the downward vertical of B."""
    z_t = rotation.as_matrix()[:, 2]
    return math.atan2(math.hypot(z_t[0], z_t[1]), -z_t[2])


def clamp_position(
    xyz_m: tuple[float, float, float] | np.ndarray, env: SafetyEnvelope
) -> np.ndarray:
    """The point of the workspace box nearest to ``xyz_m`` (m, in B)."""
    return np.clip(np.asarray(xyz_m, dtype=float), env.box_min_m, env.box_max_m)


def clamp_tilt(rotation: Rotation, max_tilt_rad: float) -> Rotation:
    """``rotation`` turned toward vertical along the shortest arc until its tilt is at most
    ``max_tilt_rad``; returned unchanged (the same object) when already within."""
    tilt = tilt_rad(rotation)
    if tilt <= max_tilt_rad + _ROUNDING_RAD:
        return rotation
    axis = np.cross(rotation.as_matrix()[:, 2], _DOWN_B)
    norm = np.linalg.norm(axis)
    axis = np.array([1.0, 0.0, 0.0]) if norm < 1e-12 else axis / norm
    return Rotation.from_rotvec(axis * (tilt - max_tilt_rad)) * rotation


def clamp_pose(pose: Pose, env: SafetyEnvelope) -> Pose:
    """``pose`` with its position clipped into the box and its tilt limited."""
    rotation = rotation_from_rpy(pose.rpy_rad)
    clamped = clamp_tilt(rotation, env.max_tilt_rad)
    rpy = pose.rpy_rad if clamped is rotation else rpy_near(clamped, pose.rpy_rad)
    return Pose(_vec3(clamp_position(pose.xyz_m, env)), rpy)


def servo_target(
    previous: Pose, target: Pose, env: SafetyEnvelope, max_step_m: float, max_step_rad: float
) -> Pose:
    """The next servo command from ``previous`` (inside the envelope) toward ``target``.

    The target is clamped into the envelope, then approached by at most ``max_step_m`` and
    ``max_step_rad`` (callers pass bounds no larger than the envelope's, e.g. tightened by
    the time since the previous command). The result is inside the envelope.
    """
    goal = clamp_pose(target, env)
    p0 = np.asarray(previous.xyz_m, dtype=float)
    delta = np.asarray(goal.xyz_m) - p0
    distance = float(np.linalg.norm(delta))
    position = goal.xyz_m if distance <= max_step_m else p0 + delta * (max_step_m / distance)
    position = clamp_position(position, env)  # a no-op up to rounding: the box is convex

    r0 = rotation_from_rpy(previous.rpy_rad)
    turn = (rotation_from_rpy(goal.rpy_rad) * r0.inv()).as_rotvec()
    angle = float(np.linalg.norm(turn))
    if angle <= max_step_rad:
        return Pose(_vec3(position), goal.rpy_rad)
    fraction = max_step_rad / angle
    for _ in range(2):  # at most one halving is needed (see the module docstring)
        rotation = clamp_tilt(Rotation.from_rotvec(turn * fraction) * r0, env.max_tilt_rad)
        if (rotation * r0.inv()).magnitude() <= max_step_rad:
            break
        fraction /= 2.0
    return Pose(_vec3(position), rpy_near(rotation, goal.rpy_rad))


def timed_servo_target(
    previous: Pose,
    target: Pose,
    env: SafetyEnvelope,
    previous_time_s: float | None,
    now_s: float,
    servo_rate_hz: float,
) -> Pose:
    """``servo_target`` with the step bounded by the envelope's speeds times the time since
    the previous command (one servo period, ``1 / servo_rate_hz``, for the first command)."""
    if previous_time_s is None:
        elapsed_s = 1.0 / servo_rate_hz
    else:
        elapsed_s = max(0.0, now_s - previous_time_s)
    return servo_target(
        previous,
        target,
        env,
        max_step_m=min(env.max_step_m, env.max_speed_m_s * elapsed_s),
        max_step_rad=min(env.max_step_rad, env.max_angular_speed_rad_s * elapsed_s),
    )


def clamp_twist(pose: Pose, twist: Twist, duration_s: float, env: SafetyEnvelope) -> Twist:
    """``twist`` (in B) limited so that holding it for ``duration_s`` from ``pose`` respects
    the speed limits, keeps the TCP in the box and does not tilt the tool beyond the limit."""
    linear = _scaled_to(np.asarray(twist.linear_m_s, dtype=float), env.max_speed_m_s)
    position = np.asarray(pose.xyz_m, dtype=float)
    low = np.minimum(0.0, (env.box_min_m - position) / duration_s)
    high = np.maximum(0.0, (env.box_max_m - position) / duration_s)
    linear = np.clip(linear, low, high)

    angular = _scaled_to(np.asarray(twist.angular_rad_s, dtype=float), env.max_angular_speed_rad_s)
    rotation = rotation_from_rpy(pose.rpy_rad)
    allowed = max(env.max_tilt_rad, tilt_rad(rotation))
    times = np.linspace(duration_s / _TWIST_TILT_SAMPLES, duration_s, _TWIST_TILT_SAMPLES)
    if any(tilt_rad(Rotation.from_rotvec(angular * t) * rotation) > allowed for t in times):
        angular[:2] = 0.0  # rotation about the vertical only: the tilt stays constant
    return Twist(_vec3(linear), _vec3(angular))


def rpy_near(
    rotation: Rotation, reference_rpy: tuple[float, float, float]
) -> tuple[float, float, float]:
    """Roll, pitch, yaw of ``rotation``, each wrapped by 2*pi to lie nearest ``reference_rpy``
    (so that e.g. a roll near +pi is not reported as -pi)."""
    rpy = rotation.as_euler("xyz")
    ref = np.asarray(reference_rpy, dtype=float)
    return _vec3(rpy + 2.0 * np.pi * np.round((ref - rpy) / (2.0 * np.pi)))


def _scaled_to(vector: np.ndarray, limit: float) -> np.ndarray:
    norm = float(np.linalg.norm(vector))
    return vector * (limit / norm) if norm > limit else vector


def _vec3(values: np.ndarray | tuple[float, ...]) -> tuple[float, float, float]:
    x, y, z = (float(v) for v in values)
    return (x, y, z)
