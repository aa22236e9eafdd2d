"""Kinematics of the simulated TCP: speed- and acceleration-limited motion inside the envelope.

The TCP (frame T) is a rigid body in the base frame B with position ``p`` (m), linear
velocity ``v`` (m/s), orientation ``R`` (T2B, a unit quaternion (x, y, z, w) of
``core.quaternion``) and angular velocity ``w``
(rad/s, in B). ``step(v_des, w_des)`` advances it by ``dt_s``:

1. ``v_des`` is scaled to the envelope's ``max_linear_speed_m_s`` and each component is
   capped so that the TCP can still stop on the faces of the box: toward a face at
   distance ``d`` the speed is at most ``max(sqrt(2 b d) - b dt / 2, min(d / dt, b dt))`` with
   ``b = max_accel_m_s2 / sqrt(3)``. With the position updated by the new velocity, braking
   by ``b dt`` per step from that speed stops on or before the face, and after one step at
   that speed the bound for the remaining distance still allows braking by ``b dt`` (for
   the square root: with ``x = v / (b dt)`` and ``D = d / (b dt^2)``, ``x <= sqrt(2D) - 1/2``
   gives ``x - 1 <= sqrt(2 (D - x)) - 1/2``); so braking never needs more than ``b dt`` per
   axis, i.e. ``max_accel_m_s2 * dt`` in norm. The second term lets the TCP reach a face
   exactly (a target clamped onto it).
2. ``v`` moves toward ``v_des`` by at most ``max_accel_m_s2 * dt`` (norm). If that leaves the
   per-axis caps, the new velocity is the point nearest the candidate on the segment from the
   current velocity clipped into the caps (within the acceleration bound, by 1.) to the
   candidate. Both ends lie within the speed and acceleration bounds, so the result does too.
3. ``w`` likewise, with the angular limits; the only wall is the tilt limit, for the tilt
   rate ``w . a`` (``a`` the horizontal axis about which the tool tilts away from vertical),
   braking at half the angular acceleration limit (the margin covers the axis turning with
   the tool's rotation about the vertical).
4. ``p += v dt``, ``R = exp(w dt) R``; a final projection on the box and the tilt cone
   (``core.envelope.clamp_tilt``) only absorbs rounding.

Vectors and quaternions are tuples of Python floats: the twin steps this at hundreds of Hz,
where NumPy's per-call overhead on 3-vectors, and a scipy ``Rotation``'s on one orientation,
would dominate; ``core.spatial`` (roll/pitch/yaw, tilt) and ``core.envelope`` (tilt clamp)
give the closed forms.
"""

from __future__ import annotations

import math
from collections.abc import Iterable

from core import quaternion
from core.devices import Pose
from core.envelope import Envelope, clamp_tilt
from core.quaternion import Quat
from core.spatial import quat_from_rpy, rpy_from_quat, tilt_of_quat

Vec = tuple[float, float, float]
_ZERO: Vec = (0.0, 0.0, 0.0)


class TcpMotion:
    """The TCP's state and its limited motion; see the module docstring."""

    def __init__(
        self,
        envelope: Envelope,
        start: Pose,
        max_accel_m_s2: float,
        max_angular_accel_rad_s2: float,
        dt_s: float,
    ) -> None:
        self.envelope = envelope
        self.dt_s = dt_s
        self.max_accel_m_s2 = max_accel_m_s2
        self.max_angular_accel_rad_s2 = max_angular_accel_rad_s2
        self.position_m: Vec = _vec(start.xyz_m)
        self.velocity_m_s: Vec = _ZERO
        self.rotation: Quat = quat_from_rpy(start.rpy_rad)
        self.angular_rad_s: Vec = _ZERO
        self._low: Vec = (envelope.x_min_m, envelope.y_min_m, envelope.z_min_m)
        self._high: Vec = (envelope.x_max_m, envelope.y_max_m, envelope.z_max_m)

    # ----------------------------------------------------------------- queries

    def pose(self, rpy_hint: Vec) -> Pose:
        """The TCP pose, its roll/pitch/yaw wrapped to lie nearest ``rpy_hint``."""
        return Pose(self.position_m, rpy_from_quat(self.rotation, rpy_hint))

    def at_rest(self, tolerance: float) -> bool:
        return _norm(self.velocity_m_s) <= tolerance and _norm(self.angular_rad_s) <= tolerance

    def offset_to(self, xyz_m: Vec, goal: Quat) -> tuple[Vec, Vec]:
        """(translation in m, rotation vector in rad) from the TCP to the given pose, in B: the
        rotation vector of the shortest turn (angle at most pi)."""
        turn = quaternion.multiply(goal, quaternion.inverse(self.rotation))
        return _sub(xyz_m, self.position_m), quaternion.rotvec(turn)

    # ----------------------------------------------------------------- motion

    def approach(
        self, xyz_m: Vec, quaternion: Quat, speed_m_s: float, angular_speed_rad_s: float
    ) -> tuple[Vec, Vec]:
        """Desired velocities toward a goal pose: straight (and along the geodesic) at most
        at the given speeds, slow enough to stop there at the acceleration limits, and not
        past it within one step."""
        dt = self.dt_s
        delta, turn = self.offset_to(xyz_m, quaternion)
        distance, angle = _norm(delta), _norm(turn)
        v_des = w_des = _ZERO
        if distance > 0:
            speed = min(speed_m_s, distance / dt, math.sqrt(2.0 * self.max_accel_m_s2 * distance))
            v_des = _scale(delta, speed / distance)
        if angle > 0:
            rate = min(
                angular_speed_rad_s,
                angle / dt,
                math.sqrt(2.0 * self.max_angular_accel_rad_s2 * angle),
            )
            w_des = _scale(turn, rate / angle)
        return v_des, w_des

    def step(self, v_des: Vec, w_des: Vec) -> None:
        """Advance by ``dt_s`` toward the desired velocities (see the module docstring)."""
        self.velocity_m_s = self._next_velocity(v_des)
        self.angular_rad_s = self._next_angular(w_des)
        dt = self.dt_s
        moved = _add(self.position_m, _scale(self.velocity_m_s, dt))
        self.position_m = _clip(moved, self._low, self._high)
        turn = quaternion.from_rotvec(_scale(self.angular_rad_s, dt))
        turned = quaternion.normalised(quaternion.multiply(turn, self.rotation))
        self.rotation = clamp_tilt(turned, self.envelope.max_tilt_rad)

    def _next_velocity(self, v_des: Vec) -> Vec:
        env, dt = self.envelope, self.dt_s
        brake = self.max_accel_m_s2 / math.sqrt(3.0)
        (px, py, pz), (lx, ly, lz), (hx, hy, hz) = self.position_m, self._low, self._high
        high = (
            stopping_speed(hx - px, brake, dt),
            stopping_speed(hy - py, brake, dt),
            stopping_speed(hz - pz, brake, dt),
        )
        low = (
            -stopping_speed(px - lx, brake, dt),
            -stopping_speed(py - ly, brake, dt),
            -stopping_speed(pz - lz, brake, dt),
        )
        v_des = _clip(_scaled_to(v_des, env.max_linear_speed_m_s), low, high)
        v = self.velocity_m_s
        candidate = _add(v, _scaled_to(_sub(v_des, v), self.max_accel_m_s2 * dt))
        if (
            low[0] <= candidate[0] <= high[0]
            and low[1] <= candidate[1] <= high[1]
            and low[2] <= candidate[2] <= high[2]
        ):
            return candidate
        safe = _clip(v, low, high)
        direction = _sub(candidate, safe)
        fraction = 1.0
        for s, d, lo, hi in zip(safe, direction, low, high, strict=True):
            if d > 0:
                fraction = min(fraction, (hi - s) / d)
            elif d < 0:
                fraction = min(fraction, (lo - s) / d)
        return _add(safe, _scale(direction, max(0.0, fraction)))

    def _next_angular(self, w_des: Vec) -> Vec:
        env, dt = self.envelope, self.dt_s
        w = self.angular_rad_s
        w_des = _scaled_to(w_des, env.max_angular_speed_rad_s)
        candidate = _add(w, _scaled_to(_sub(w_des, w), self.max_angular_accel_rad_s2 * dt))
        brake = self.max_angular_accel_rad_s2 / 2.0
        limit = stopping_speed(env.max_tilt_rad - tilt_of_quat(self.rotation)[0], brake, dt)
        zx, zy, _ = quaternion.z_axis(self.rotation)  # the tool's z-axis in B
        horizontal = math.hypot(zx, zy)
        if horizontal < 1e-9:
            # Pointing straight down: every horizontal rotation tilts the tool. The limit
            # binds here only for a tilt limit of a few mrad.
            rate = math.hypot(candidate[0], candidate[1])
            if rate <= limit:
                return candidate
            k = limit / rate
            return (candidate[0] * k, candidate[1] * k, candidate[2])
        axis = (zy / horizontal, -zx / horizontal, 0.0)  # (-z_B) x z_T, normalised
        rate = _dot(candidate, axis)
        if rate <= limit:
            return candidate
        safe = _sub(w, _scale(axis, max(0.0, _dot(w, axis) - limit)))
        safe_rate = _dot(safe, axis)
        fraction = (limit - safe_rate) / (rate - safe_rate)
        return _add(safe, _scale(_sub(candidate, safe), max(0.0, fraction)))


def stopping_speed(distance: float, brake: float, dt: float) -> float:
    """Largest speed toward a wall ``distance`` away from which braking by ``brake * dt`` per
    step stops on or before the wall (module docstring, 1.): ``sqrt(2 b d) - b dt / 2``, or
    within one step of the wall ``min(d / dt, b dt)`` (reach the wall, or come ``b dt^2``
    closer, and stop in one more step), whichever is larger."""
    d = max(distance, 0.0)
    return max(math.sqrt(2.0 * brake * d) - 0.5 * brake * dt, min(d / dt, brake * dt))


def _vec(values: Iterable[float]) -> Vec:
    x, y, z = (float(v) for v in values)
    return (x, y, z)


def _norm(v: Vec) -> float:
    return math.sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2])


def _dot(a: Vec, b: Vec) -> float:
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def _add(a: Vec, b: Vec) -> Vec:
    return (a[0] + b[0], a[1] + b[1], a[2] + b[2])


def _sub(a: Vec, b: Vec) -> Vec:
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


def _scale(v: Vec, k: float) -> Vec:
    return (v[0] * k, v[1] * k, v[2] * k)


def _scaled_to(v: Vec, limit: float) -> Vec:
    n = _norm(v)
    return _scale(v, limit / n) if n > limit else v


def _clip(v: Vec, low: tuple[float, ...], high: tuple[float, ...]) -> Vec:
    return (
        min(max(v[0], low[0]), high[0]),
        min(max(v[1], low[1]), high[1]),
        min(max(v[2], low[2]), high[2]),
    )
