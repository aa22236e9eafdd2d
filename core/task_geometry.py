"""The insertion task's geometry, shared by the controller (which plans with the nominal
values) and the simulated scene (which builds the true ones): the task file's ``plug:`` and
``hole:`` sections. SI units; frames as in docs/ARCHITECTURE.md (B the arm base, T the tool
at the grasp point with z_T from the gripper toward the plug's tip, H the opening)."""

from __future__ import annotations

import math

from core.config import Config, config_dataclass, number


@config_dataclass
class PlugGeometry(Config):
    """The plug in the grasp (``plug:``): a box ``width_m`` (along T's x) by ``thickness_m``
    (along T's y, the fingers' closing direction: the gel presses its wide face), and
    ``length_m`` from the grasp point (the TCP) to the tip along T's z. The code defaults
    are a USB-C plug; a task file gives every key."""

    width_m: float = number(1e-3, 0.05, default=0.00825)
    thickness_m: float = number(5e-4, 0.02, default=0.0024)
    length_m: float = number(5e-3, 0.1, default=0.012)


@config_dataclass
class HolePose(Config):
    """A hole pose in B (``hole:`` holds the nominal one): the opening's centre at the board
    surface (m) and its yaw about B's z (rad), the angle of the opening's width axis (H's x)
    from B's x axis."""

    x_m: float = number(-2.0, 2.0, default=0.4)
    y_m: float = number(-2.0, 2.0, default=0.0)
    z_m: float = number(-2.0, 2.0, default=0.1)
    yaw_rad: float = number(-math.pi, math.pi, default=0.0)
