"""Load-time checks that a task's limits agree with each other and with the arm's envelope.

A limit that can never act, or an envelope that cannot reach the task, is a configuration
error, not a run that quietly fails: ``check_task_limits`` raises a one-line ConfigError
naming the file and the key.

* **The machine's tilt limit must be able to trip.** The state machine fails a run whose
  tool tilts more than ``machine.limits.tilt_limit_rad``, but the loop's limiter
  (``limits.max_tilt_rad``) and the arm's envelope (the robot file's
  ``envelope.max_tilt_rad``) keep the tool within their own cones; a machine limit at or
  above the tighter of the two could never trip.
* **The envelopes must reach the insertion.** With the hole's opening at height
  ``hole.z_m`` (in B), a plug of ``plug.length_m`` from the TCP to the tip, driven
  ``tip_depth_m`` below the opening (the deepest the task's controllers target: the
  machine's ``insert.depth_m``; the blind baseline pushes until its force limit, as deep as
  the opening lets the plug, which the press margin below covers), puts the TCP at
  ``hole.z_m + plug.length_m - tip_depth_m``; pressing it in through the compliant wrist
  takes the TCP up to ``PRESS_MARGIN_M`` lower. Both the arm's ``envelope.z_min_m`` and the
  task's ``limits.z_min_m`` must allow that height, or a run stops at the board. The check
  reads only the product's own configuration, so it holds for the robot and the simulator
  alike (the simulated arm uses the robot file's envelope unchanged).
* **A task tightens the arm's envelope, never loosens it.** The task's ``limits:`` (the
  loop's limiter) may not allow more than the robot file's ``envelope:`` (the driver's, on
  every command): a box reaching outside the arm's sides or above its top, a faster linear
  or angular speed, a larger tilt. The driver would hold the arm's envelope anyway; a looser
  task limit is refused so that no setting appears to loosen a safety rule. The floor is the
  exception: the arm's ``z_min_m`` is the hard floor that the blind baseline pushes down to,
  and the task's own floor may lie below it so that the loop does not report the driver's
  floor as its limit holding the machine back (the driver keeps the arm's floor whatever
  the task says). The same holds one level up: the teleop's full-stick speeds
  (``teleop.stick_speed_m_s``, ``teleop.stick_angular_speed_rad_s``) may not exceed the
  task's limits.
* **The boxes must hold the search.** The hole's nominal x and y, widened by the search's
  half width (``search_half_width_m``: the farthest the task's controllers search from the
  nominal hole), must lie inside both workspace boxes, or the machine would search and
  insert against a face of the box.
"""

from __future__ import annotations

from controller.insertion.machine_config import Limits
from controller.safety import LimitsConfig
from controller.teleop import TeleopConfig
from core.config import ConfigError
from core.envelope import Envelope
from core.task_geometry import HolePose, PlugGeometry

PRESS_MARGIN_M = 0.002
"""How far below the fully inserted height the TCP may have to go (m): the compliant wrist's
give while the plug is pressed home (about 2 N on its 1000 N/m axial spring)."""


def check_task_limits(
    *,
    source: str,
    machine_limits: Limits,
    limits: LimitsConfig,
    arm_file: str,
    arm_envelope: Envelope,
    plug: PlugGeometry,
    hole: HolePose,
    tip_depth_m: float,
    search_half_width_m: float,
    teleop: TeleopConfig,
) -> None:
    """ConfigError (one line) unless the task's limits agree (module doc). ``source``: the
    task file; ``arm_file``: the robot file its ``devices.arm`` names, and ``arm_envelope``
    the envelope that file holds."""
    for name, envelope, where in (
        ("limits.max_tilt_rad", limits, "the loop's limiter"),
        (f"envelope.max_tilt_rad of {arm_file}", arm_envelope, "the arm's envelope"),
    ):
        if not machine_limits.tilt_limit_rad < envelope.max_tilt_rad:
            raise ConfigError(
                f"{source}: key 'machine.limits.tilt_limit_rad': expected less than {name} "
                f"({envelope.max_tilt_rad}), got {machine_limits.tilt_limit_rad}: {where} keeps "
                f"the tool within {envelope.max_tilt_rad} rad, so this limit could never trip"
            )
    lowest_m = inserted_tcp_z_m(plug, hole, tip_depth_m) - PRESS_MARGIN_M
    _check_reaches(arm_file, "envelope.z_min_m", arm_envelope, lowest_m, source)
    _check_reaches(source, "limits.z_min_m", limits, lowest_m, source)
    _check_holds_search(arm_file, "envelope.", arm_envelope, hole, search_half_width_m)
    _check_holds_search(source, "limits.", limits, hole, search_half_width_m)
    _check_no_looser(source, "limits.", limits, f"envelope.* of {arm_file}", arm_envelope)
    _check_teleop_within(source, teleop, limits)


def inserted_tcp_z_m(plug: PlugGeometry, hole: HolePose, tip_depth_m: float) -> float:
    """The TCP's height in B (m) with the plug upright and inserted: its tip ``tip_depth_m``
    below the opening at ``hole.z_m``."""
    return hole.z_m + plug.length_m - tip_depth_m


def _check_reaches(file: str, key: str, envelope: Envelope, lowest_m: float, task: str) -> None:
    if envelope.z_min_m > lowest_m:
        raise ConfigError(
            f"{file}: key '{key}': expected at most {lowest_m:.4f} (the TCP's height with the "
            f"plug of {task} inserted, less {PRESS_MARGIN_M} m to press it home), got "
            f"{envelope.z_min_m}: the TCP would stop above the insertion"
        )


def _check_no_looser(
    source: str, prefix: str, limits: Envelope, bound_name: str, bound: Envelope
) -> None:
    """``limits`` no looser than ``bound``: inside its box (the floor aside: module doc), no
    faster, no more tilted."""
    for key, looser in (
        ("x_min_m", limits.x_min_m < bound.x_min_m),
        ("y_min_m", limits.y_min_m < bound.y_min_m),
        ("x_max_m", limits.x_max_m > bound.x_max_m),
        ("y_max_m", limits.y_max_m > bound.y_max_m),
        ("z_max_m", limits.z_max_m > bound.z_max_m),
        ("max_linear_speed_m_s", limits.max_linear_speed_m_s > bound.max_linear_speed_m_s),
        ("max_angular_speed_rad_s",
         limits.max_angular_speed_rad_s > bound.max_angular_speed_rad_s),
        ("max_tilt_rad", limits.max_tilt_rad > bound.max_tilt_rad),
    ):  # fmt: skip
        if looser:
            raise ConfigError(
                f"{source}: key '{prefix}{key}': expected within {bound_name} "
                f"({getattr(bound, key)}), got {getattr(limits, key)}: a setting may tighten "
                "a safety limit, never loosen it"
            )


def _check_teleop_within(source: str, teleop: TeleopConfig, limits: Envelope) -> None:
    for key, limit_key in (
        ("stick_speed_m_s", "max_linear_speed_m_s"),
        ("stick_angular_speed_rad_s", "max_angular_speed_rad_s"),
    ):
        speed, limit = getattr(teleop, key), getattr(limits, limit_key)
        if speed > limit:
            raise ConfigError(
                f"{source}: key 'teleop.{key}': expected at most limits.{limit_key} ({limit}), "
                f"got {speed}: a setting may tighten a safety limit, never loosen it"
            )


def _check_holds_search(
    file: str, prefix: str, box: Envelope, hole: HolePose, margin_m: float
) -> None:
    for axis, centre_m in (("x", hole.x_m), ("y", hole.y_m)):
        low_m, high_m = getattr(box, f"{axis}_min_m"), getattr(box, f"{axis}_max_m")
        if not (low_m <= centre_m - margin_m and centre_m + margin_m <= high_m):
            raise ConfigError(
                f"{file}: keys '{prefix}{axis}_min_m', '{prefix}{axis}_max_m': expected a box "
                f"holding the hole's {axis} {centre_m} m with the search's +-{margin_m} m, got "
                f"[{low_m}, {high_m}]: the machine would search against a face of the box"
            )
