"""The arm's safety envelope (the robot YAML's ``envelope:``), enforced by the driver on
every command whatever the caller sends, with the clamps of ``core.envelope`` (the same
geometry as the control loop's limits): a target is clamped into the box and the tilt cone,
a servo target is also stepped from the previous one by at most ``max_step_m`` and
``max_step_rad`` (and the speeds times the time since it), a twist is limited in speed, box
and tilt over the time it is held.
"""

from __future__ import annotations

from core.config import config_dataclass, number
from core.devices import Pose
from core.envelope import Envelope, limit_pose


@config_dataclass(kw_only=True)
class SafetyEnvelope(Envelope):
    """The arm's envelope: ``core.envelope.Envelope`` (box in B, speeds, tilt) and the largest
    step of one servo command (m, rad)."""

    max_step_m: float = number(1e-6, 0.05, default=0.002)
    max_step_rad: float = number(1e-6, 0.5, default=0.01)


def timed_servo_target(
    previous: Pose,
    target: Pose,
    env: SafetyEnvelope,
    previous_time_s: float | None,
    now_s: float,
    servo_rate_hz: float,
) -> Pose:
    """The next servo command from ``previous`` toward ``target``, its step bounded by the
    envelope's steps and by its speeds times the time since the previous command (one servo
    period, ``1 / servo_rate_hz``, for the first command)."""
    if previous_time_s is None:
        elapsed_s = 1.0 / servo_rate_hz
    else:
        elapsed_s = max(0.0, now_s - previous_time_s)
    return limit_pose(
        target,
        previous,
        env,
        max_step_m=min(env.max_step_m, env.max_linear_speed_m_s * elapsed_s),
        max_step_rad=min(env.max_step_rad, env.max_angular_speed_rad_s * elapsed_s),
    ).value
