"""The motion envelope of the tool: a workspace box, a tilt cone and speed limits, with the
clamps that bring a command inside. One implementation for the arm driver's envelope
(``drivers.arm.arm_envelope``: every command the driver sends, whatever the caller) and the
control loop's limits (``controller.safety``: every command the loop sends, usually tighter).

Frames and units: TCP (frame T) poses in the arm base B (``Pose`` is T2B, core/spatial.py);
m, rad, m/s, rad/s, s. Every function maps a requested command to the nearest one inside the
envelope and reports which limits acted (``speed``, ``workspace``, ``tilt``, ``step``); none
raises on an out-of-envelope request (non-finite numbers are refused before, by
``require_finite``: a clamp would carry a NaN through).

* **Position**: each coordinate of the TCP is clipped into the box
  ``[x_min_m, x_max_m] x [y_min_m, y_max_m] x [z_min_m, z_max_m]`` in B.
* **Tilt** (core/spatial.py): a more tilted orientation is turned toward vertical along the
  shortest arc (about the horizontal axis ``z_T x -z_B``) until its tilt is exactly
  ``max_tilt_rad``; the rotation about the vertical is kept. A tool pointing straight up has
  no unique shortest arc; it is tipped about ``x_B``.
* **Pose target** (``limit_pose``): clamped as above, then approached from the previous
  command by at most ``max_step_m`` and ``max_step_rad``, along the straight line and the
  geodesic. Stepping along a geodesic between two orientations inside the tilt cone can
  leave the cone slightly, so the stepped orientation is tilt-clamped again; if that pushes
  the turn above ``max_step_rad`` the step fraction is halved once, which is enough: the
  re-clamp turns by at most the tilt excess, itself at most the stepped turn, so the total
  is at most twice half the bound.
* **Twist** (``limit_twist``, held for ``duration_s``): the linear speed is scaled down to
  ``max_linear_speed_m_s`` and the angular one to ``max_angular_speed_rad_s`` (directions
  kept); each linear component is then limited so the TCP stays in the box for
  ``duration_s`` (a component leaving the box at its face becomes zero; moving back in is
  allowed); if the rotation would tilt the tool beyond ``max_tilt_rad`` (or beyond its
  current tilt, if already outside) within ``duration_s``, the horizontal angular
  components are zeroed, leaving only the rotation about the vertical, which keeps the tilt.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from typing import Generic, NamedTuple, TypeVar

import numpy as np

from core import quaternion
from core.config import Config, config_dataclass, number
from core.devices import Pose, Twist
from core.quaternion import Quat
from core.spatial import (
    clamp_norm,
    quat_from_rpy,
    rpy_from_quat,
    tilt_of_quat,
    tilts_of_tool_axes,
    tool_z_from_rpy,
    turned,
    vec3,
)

T = TypeVar("T")

MAX_LINEAR_SPEED_M_S = 0.25
"""The product's ceiling on any TCP speed limit (m/s): ISO 10218-1's reduced speed."""
MAX_ANGULAR_SPEED_RAD_S = 1.0
"""The product's ceiling on any TCP angular speed limit (rad/s)."""
ROUNDING_RAD = 1e-12  # tilts this close to the limit count as within (float round-off)
_TWIST_TILT_SAMPLES = 8  # points along a twist's horizon at which the tilt is checked


class WorkspaceBox:
    """Mixin for a Config with ``x_min_m`` ... ``z_max_m`` (a box of TCP positions in B, m):
    checks each min < max on construction and gives the corners as arrays."""

    x_min_m: float
    x_max_m: float
    y_min_m: float
    y_max_m: float
    z_min_m: float
    z_max_m: float

    def __post_init__(self) -> None:
        for axis in "xyz":
            low, high = f"{axis}_min_m", f"{axis}_max_m"
            if not getattr(self, low) < getattr(self, high):
                raise ValueError(
                    f"key '{high}': expected a number greater than {low} "
                    f"({getattr(self, low)!r}), got {getattr(self, high)!r}"
                )

    @property
    def box_min_m(self) -> np.ndarray:
        return np.array([self.x_min_m, self.y_min_m, self.z_min_m])

    @property
    def box_max_m(self) -> np.ndarray:
        return np.array([self.x_max_m, self.y_max_m, self.z_max_m])


@config_dataclass(kw_only=True)
class Envelope(WorkspaceBox, Config):
    """The keys every envelope has (the robot YAML's ``envelope:``, a task's ``limits:``):
    the TCP's box in B (m), its linear and angular speed (norms, m/s and rad/s) and its tilt
    from the downward vertical (rad). The code defaults are the shipped task limits.

    The speeds' ranges are the product's ceilings, which no file can exceed: 0.25 m/s, the
    reduced speed of ISO 10218-1 for a robot with a person beside it (the teleop demo's
    case), and 1 rad/s, which keeps a point 0.25 m from the TCP within that speed."""

    x_min_m: float = number(-2.0, 2.0, default=0.20)
    x_max_m: float = number(-2.0, 2.0, default=0.55)
    y_min_m: float = number(-2.0, 2.0, default=-0.25)
    y_max_m: float = number(-2.0, 2.0, default=0.25)
    z_min_m: float = number(-2.0, 2.0, default=0.02)
    z_max_m: float = number(-2.0, 2.0, default=0.40)
    max_linear_speed_m_s: float = number(0.0, MAX_LINEAR_SPEED_M_S, default=0.05)
    max_angular_speed_rad_s: float = number(0.0, MAX_ANGULAR_SPEED_RAD_S, default=0.5)
    max_tilt_rad: float = number(0.0, math.pi / 2, default=0.35)


class Limited(NamedTuple, Generic[T]):
    """A command brought inside the envelope and the limits that changed it (empty when it
    passed unchanged)."""

    value: T
    limited: tuple[str, ...]


def require_finite(name: str, values: Iterable[float]) -> None:
    """Refuse a command holding anything but finite numbers (ValueError naming it)."""
    values = tuple(values)
    try:
        finite = all(math.isfinite(float(v)) for v in values)
    except (TypeError, ValueError):
        finite = False
    if not finite:
        raise ValueError(f"{name}: expected finite numbers, got {values!r}")


def clamp_position(xyz_m: tuple[float, float, float] | np.ndarray, box: WorkspaceBox) -> np.ndarray:
    """The point of the workspace box nearest to ``xyz_m`` (m, in B). (``np.clip``'s
    result, in plain floats: the arm twin clamps every servo command, and NumPy's per-call
    overhead on three numbers was most of it.)"""
    x, y, z = (float(v) for v in xyz_m)
    return np.array(
        (
            min(max(x, box.x_min_m), box.x_max_m),
            min(max(y, box.y_min_m), box.y_max_m),
            min(max(z, box.z_min_m), box.z_max_m),
        )
    )


def clamp_tilt(T2B: Quat, max_tilt_rad: float) -> Quat:
    """R_T2B (a quaternion (x, y, z, w), ``core.quaternion``) turned toward vertical along
    the shortest arc until its tilt is at most ``max_tilt_rad``; returned unchanged (the
    same tuple) when already within. Closed form: the simulated arm clamps every step."""
    tilt, axis = tilt_of_quat(T2B)
    if tilt <= max_tilt_rad + ROUNDING_RAD:
        return T2B
    if axis == (0.0, 0.0, 0.0):  # pointing straight up
        axis = (1.0, 0.0, 0.0)
    excess = tilt - max_tilt_rad
    turn = quaternion.from_rotvec((axis[0] * excess, axis[1] * excess, axis[2] * excess))
    return quaternion.multiply(turn, T2B)


def clamp_pose(pose: Pose, envelope: Envelope) -> Limited[Pose]:
    """``pose`` with its position clipped into the box and its tilt limited; its
    ``rpy_rad`` is kept exactly when the tilt is within."""
    xyz = clamp_position(pose.xyz_m, envelope)
    limited = () if xyz.tolist() == [float(v) for v in pose.xyz_m] else ("workspace",)
    rotation = quat_from_rpy(pose.rpy_rad)
    clamped = clamp_tilt(rotation, envelope.max_tilt_rad)
    if clamped is rotation:
        return Limited(Pose(vec3(xyz), pose.rpy_rad), limited)
    return Limited(Pose(vec3(xyz), rpy_from_quat(clamped, pose.rpy_rad)), (*limited, "tilt"))


def limit_pose(
    target: Pose, previous: Pose, envelope: Envelope, max_step_m: float, max_step_rad: float
) -> Limited[Pose]:
    """The next pose command from ``previous`` (inside the envelope) toward ``target``: the
    target clamped into the envelope, approached by at most ``max_step_m`` and
    ``max_step_rad`` (module doc). The result is inside the envelope."""
    goal, limited = clamp_pose(target, envelope)
    p0 = np.asarray(previous.xyz_m, dtype=float)
    delta = np.asarray(goal.xyz_m) - p0
    distance = float(np.linalg.norm(delta))
    position: tuple[float, float, float] | np.ndarray = goal.xyz_m
    if distance > max_step_m:
        position = p0 + delta * (max_step_m / distance)
        limited = (*limited, "step")
    position = clamp_position(position, envelope)  # a no-op up to rounding: the box is convex

    r0 = quat_from_rpy(previous.rpy_rad)
    back = quaternion.inverse(r0)
    tx, ty, tz = quaternion.rotvec(quaternion.multiply(quat_from_rpy(goal.rpy_rad), back))
    angle = math.sqrt(tx * tx + ty * ty + tz * tz)
    if angle <= max_step_rad:
        return Limited(Pose(vec3(position), goal.rpy_rad), limited)
    if "step" not in limited:
        limited = (*limited, "step")
    fraction = max_step_rad / angle
    for _ in range(2):  # at most one halving is needed (see the module docstring)
        step = quaternion.from_rotvec((tx * fraction, ty * fraction, tz * fraction))
        rotation = clamp_tilt(quaternion.multiply(step, r0), envelope.max_tilt_rad)
        if _norm3(quaternion.rotvec(quaternion.multiply(rotation, back))) <= (
            max_step_rad + ROUNDING_RAD
        ):
            break
        fraction /= 2.0
    return Limited(Pose(vec3(position), rpy_from_quat(rotation, goal.rpy_rad)), limited)


def _norm3(v: tuple[float, float, float]) -> float:
    return math.sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2])


def limit_twist(twist: Twist, pose: Pose, duration_s: float, envelope: Envelope) -> Limited[Twist]:
    """``twist`` (in B) limited so that holding it for ``duration_s`` from ``pose`` respects
    the speed limits, keeps the TCP in the box and does not tilt the tool beyond the limit."""
    requested_linear = np.asarray(twist.linear_m_s, dtype=float)
    requested_angular = np.asarray(twist.angular_rad_s, dtype=float)
    linear = clamp_norm(requested_linear, envelope.max_linear_speed_m_s)
    angular = clamp_norm(requested_angular, envelope.max_angular_speed_rad_s)
    limited: tuple[str, ...] = ()
    if linear is not requested_linear or angular is not requested_angular:
        limited = ("speed",)

    position = np.asarray(pose.xyz_m, dtype=float)
    low = np.minimum(0.0, (envelope.box_min_m - position) / duration_s)
    high = np.maximum(0.0, (envelope.box_max_m - position) / duration_s)
    boxed = np.clip(linear, low, high)
    if not np.array_equal(boxed, linear):
        limited = (*limited, "workspace")

    if _tilts_beyond(pose, angular, duration_s, envelope.max_tilt_rad):
        angular = np.array([0.0, 0.0, angular[2]])  # about the vertical: the tilt stays
        limited = (*limited, "tilt")
    return Limited(Twist(vec3(boxed), vec3(angular)), limited)


def _tilts_beyond(pose: Pose, angular: np.ndarray, duration_s: float, max_tilt_rad: float) -> bool:
    """Whether turning at ``angular`` (rad/s, in B) from ``pose`` tilts the tool beyond
    ``max_tilt_rad`` (or beyond its present tilt, if larger) within ``duration_s``."""
    if angular[0] == 0.0 and angular[1] == 0.0:
        return False  # about the vertical only: the tilt stays (ROUNDING_RAD covers round-off)
    z_T_in_B = tool_z_from_rpy(pose.rpy_rad)
    allowed = max(max_tilt_rad, float(tilts_of_tool_axes(z_T_in_B[None])[0])) + ROUNDING_RAD
    times = np.linspace(duration_s / _TWIST_TILT_SAMPLES, duration_s, _TWIST_TILT_SAMPLES)
    return bool(np.any(tilts_of_tool_axes(turned(z_T_in_B, angular, times)) > allowed))
