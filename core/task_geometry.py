"""The insertion task's geometry, shared by the controller (which plans with the nominal
values) and the simulated scene (which builds the true ones): the task file's ``plug:`` and
``hole:`` sections, and the workspace box checks of the arm envelope and the limits. SI
units; frames as in docs/ARCHITECTURE.md (B the arm base, T the tool at the grasp point
with z_T from the gripper toward the plug's tip, H the opening)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from core.config import Config, number


@dataclass(frozen=True)
class PlugGeometry(Config):
    """The plug in the grasp (``plug:``): a box ``width_m`` (along T's x) by ``thickness_m``
    (along T's y, the fingers' closing direction: the gel presses its wide face), and
    ``length_m`` from the grasp point (the TCP) to the tip along T's z. The code defaults
    are a USB-C plug; a task file gives every key."""

    width_m: float = number(1e-3, 0.05, default=0.00825)
    thickness_m: float = number(5e-4, 0.02, default=0.0024)
    length_m: float = number(5e-3, 0.1, default=0.012)


@dataclass(frozen=True)
class HolePose(Config):
    """A hole pose in B (``hole:`` holds the nominal one): the opening's centre at the board
    surface (m) and its yaw about B's z (rad), the angle of the opening's width axis (H's x)
    from B's x axis."""

    x_m: float = number(-2.0, 2.0, default=0.4)
    y_m: float = number(-2.0, 2.0, default=0.0)
    z_m: float = number(-2.0, 2.0, default=0.1)
    yaw_rad: float = number(-math.pi, math.pi, default=0.0)


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
