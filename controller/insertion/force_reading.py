"""Where a press-spiral machine (controller/insertion/blind.py) reads the upward force on the
tool: the arm's F/T sensor at the flange, or the tactile estimate's axial force.

Both give the force in N, positive when the board pushes the plug up into the hand (z in B
for the upright tool), untared (the machine tares it at the hover), with the time the
reading describes (its capture time, s), from which a catch rewinds the pattern.
"""

from __future__ import annotations

from collections import deque
from typing import Protocol

import numpy as np

from controller.insertion.interface import Observation


class ForceReading(Protocol):
    """A source of the upward force on the tool (see the module doc)."""

    #: the machine captures the open gel before closing and re-zeroes the estimator after
    #: the grasp (the tactile reading's forces are then relative to the held plug)
    zeroes_tactile: bool

    def available(self, obs: Observation) -> bool:
        """False when the device gives no such force at all (the run cannot go on)."""
        ...

    def read(self, obs: Observation) -> tuple[float, float] | None:
        """The force (N) and the time it describes (s), or None while there is none yet."""
        ...


class ArmForce:
    """The F/T sensor's force at the flange (``ArmStatus.external_force_n``, z in B): the mean
    of the last ``window`` readings, described at the mean of their times."""

    zeroes_tactile = False

    def __init__(self, window: int) -> None:
        self._forces: deque[tuple[float, float]] = deque(maxlen=window)

    def available(self, obs: Observation) -> bool:
        return obs.arm.external_force_n is not None

    def read(self, obs: Observation) -> tuple[float, float] | None:
        force = obs.arm.external_force_n
        if force is None:
            return None
        self._forces.append((float(force[2]), obs.t_s))
        mean = np.mean(self._forces, axis=0)
        return float(mean[0]), float(mean[1])


class TactileAxialForce:
    """The tactile estimate's force along the plug's axis (T z, toward the tip): the force
    vector (shear_x, shear_y, normal) of S rotated into T by ``s2t`` (R_S2T), in the
    calibration's N, over ``finger_share`` (the sensing finger's share of the plug's load):
    the median of the last ``window`` frames (a single frame's outlier never reads as the
    load's drop), described at their median capture time. Zeroing frames give nothing."""

    zeroes_tactile = True

    def __init__(self, s2t: np.ndarray, finger_share: float, window: int) -> None:
        self._axial = np.asarray(s2t)[2] / finger_share
        self._frames: deque[tuple[float, float]] = deque(maxlen=window)

    def available(self, obs: Observation) -> bool:
        return True

    def read(self, obs: Observation) -> tuple[float, float] | None:
        w = obs.wrench
        if w is None or w.zeroing:
            self._frames.clear()
            return None
        if not self._frames or w.t_s != self._frames[-1][1]:
            self._frames.append((float(self._axial @ (w.shear_x, w.shear_y, w.normal)), w.t_s))
        median = np.median(self._frames, axis=0)
        return float(median[0]), float(median[1])
