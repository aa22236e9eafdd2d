"""Unit quaternions as tuples of Python floats, (x, y, z, w) in scipy's order, in closed form.

For code that turns one orientation at a time hundreds of times a second (the simulated
arm's 250 Hz kinematics, drivers/sim/twins/tcp_motion.py), where a scipy ``Rotation`` costs
tens of microseconds a call in overhead. Conventions are scipy's: ``multiply(a, b)`` is the
rotation ``a * b`` (b first, then a), a rotation vector is the axis times the angle (rad),
``rotvec`` returns the shortest turn (angle at most pi). tests/core/test_quaternion.py
checks each against scipy.
"""

from __future__ import annotations

import math

Quat = tuple[float, float, float, float]
Vec = tuple[float, float, float]

_SMALL = 1e-8  # below this angle (rad), the series of sin(a/2)/a and a/sin(a/2)


def multiply(a: Quat, b: Quat) -> Quat:
    """The rotation ``a * b``: ``b`` applied first."""
    ax, ay, az, aw = a
    bx, by, bz, bw = b
    return (
        aw * bx + ax * bw + ay * bz - az * by,
        aw * by - ax * bz + ay * bw + az * bx,
        aw * bz + ax * by - ay * bx + az * bw,
        aw * bw - ax * bx - ay * by - az * bz,
    )


def inverse(q: Quat) -> Quat:
    """The inverse of a unit quaternion."""
    return (-q[0], -q[1], -q[2], q[3])


def from_rotvec(v: Vec) -> Quat:
    """The rotation by ``|v|`` rad about ``v``."""
    angle = math.sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2])
    k = 0.5 - angle * angle / 48.0 if angle < _SMALL else math.sin(0.5 * angle) / angle
    return (v[0] * k, v[1] * k, v[2] * k, math.cos(0.5 * angle))


def rotvec(q: Quat) -> Vec:
    """The rotation vector of the shortest turn (angle in [0, pi])."""
    x, y, z, w = q if q[3] >= 0 else (-q[0], -q[1], -q[2], -q[3])
    s = math.sqrt(x * x + y * y + z * z)
    angle = 2.0 * math.atan2(s, w)
    k = 2.0 + angle * angle / 12.0 if angle < _SMALL else angle / s
    return (x * k, y * k, z * k)


def z_axis(q: Quat) -> Vec:
    """The rotated z axis: the third column of the rotation matrix."""
    x, y, z, w = q
    return (2.0 * (x * z + w * y), 2.0 * (y * z - w * x), 1.0 - 2.0 * (x * x + y * y))


def normalised(q: Quat) -> Quat:
    """``q`` scaled to unit norm (against drift over many products)."""
    n = math.sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3])
    return (q[0] / n, q[1] / n, q[2] / n, q[3] / n)
