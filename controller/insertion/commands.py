"""The commands the machine's phases send: hold still, a bounded TCP twist, a twist moving
the plug's tip, the gripper's targets and the operator's command in TELEOP. Vectors are in
B (m/s, rad/s); widths in m.
"""

from __future__ import annotations

import numpy as np

from controller.insertion.interface import Command, GripperTarget, Observation, TeleopInput
from controller.insertion.machine_config import GripperSettings, MachineConfig
from controller.insertion.motion import bounded_twist, pivot_twist, tip_position
from core.devices import Twist
from core.task_geometry import PlugGeometry


def hold() -> Command:
    """Hold still: a zero twist."""
    return Command(twist=Twist())


def twist_command(config: MachineConfig, v: np.ndarray, w: np.ndarray) -> Command:
    """The TCP twist (``v`` m/s, ``w`` rad/s, in B), each part bounded by ``limits``'
    command caps."""
    limits = config.limits
    return Command(
        twist=bounded_twist(
            v, w, limits.max_command_speed_m_s, limits.max_command_angular_speed_rad_s
        )
    )


def lift_command(config: MachineConfig, v: np.ndarray) -> Command:
    """The TCP moving at ``v`` (m/s, in B) without turning."""
    return twist_command(config, v, np.zeros(3))


def tip_command(
    config: MachineConfig, plug: PlugGeometry, obs: Observation, v_tip: np.ndarray, w: np.ndarray
) -> Command:
    """The command moving the plug's tip at ``v_tip`` (m/s) while turning at ``w`` (rad/s),
    both in B."""
    p_tcp = np.asarray(obs.arm.tcp.xyz_m, dtype=float)
    p_tip = tip_position(obs.arm.tcp, plug.length_m)
    v_tcp, w = pivot_twist(p_tcp, p_tip, v_tip, w)
    return twist_command(config, v_tcp, w)


def close_target(config: MachineConfig) -> GripperTarget:
    """The gripper's close command (``gripper.close_*``)."""
    return config.gripper.close_target()


def open_target(config: MachineConfig, width_m: float) -> GripperTarget:
    """The gripper's open command to ``width_m`` (m)."""
    return config.gripper.open_target(width_m)


def capture_open(config: MachineConfig, plug: PlugGeometry, obs: Observation) -> Command:
    """Capture the open gel; the fingers (if wider) travel fast to just above the plug."""
    gripper = config.gripper.preclose_target(plug.thickness_m, obs.gripper.width_m)
    return Command(twist=Twist(), gripper=gripper, capture_open_tactile=True)


def operator_command(
    teleop: TeleopInput, gripper: GripperSettings, max_linear_m_s: float, max_angular_rad_s: float
) -> Command:
    """The operator's command in TELEOP: the pad's twist (TCP, in B) bounded by
    ``max_linear_m_s`` and ``max_angular_rad_s``, and a gripper target on a gripper button's
    press (``gripper``'s close, or its open to ``open_width_m``)."""
    twist = bounded_twist(
        np.asarray(teleop.twist.linear_m_s),
        np.asarray(teleop.twist.angular_rad_s),
        max_linear_m_s,
        max_angular_rad_s,
    )
    target = None
    if teleop.gripper_close:
        target = gripper.close_target()
    elif teleop.gripper_open:
        target = gripper.open_target(gripper.open_width_m)
    return Command(twist=twist, gripper=target)
