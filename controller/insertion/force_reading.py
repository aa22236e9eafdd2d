"""Where a press-spiral machine (controller/insertion/spiral/) reads the upward force on the
tool: the tactile estimate's axial force (the product, ``dipole``, and its variants) or the
arm's F/T sensor at the flange (the ``blind`` baseline).

Both give the force in N, positive when the board pushes the plug up into the hand (z in B
for the upright tool), untared (the machine tares it at the hover), with the time the
reading describes (its capture time, s), from which a catch rewinds the pattern.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Sequence
from typing import Protocol

import numpy as np

from controller.insertion.interface import Observation
from controller.tactile.wrench import WrenchEstimate


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

    def torque_t(self) -> np.ndarray | None:
        """The torques on the plug at the last reading (N*m, about T's axes), or None for a
        source without them."""
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

    def torque_t(self) -> np.ndarray | None:
        return None


#: the estimate's channels an axial-force map weighs, in order: the six of S, then the
#: magnitudes of the three torques (the cross-talk of a plug pressed sideways does not
#: change sign with the side)
AXIAL_TERMS = (
    "tau_x", "tau_y", "tau_z", "shear_x", "shear_y", "normal", "|tau_x|", "|tau_y|", "|tau_z|",
)  # fmt: skip


def axial_terms(channels: Sequence[float]) -> np.ndarray:
    """The ``AXIAL_TERMS`` of an estimate's six channels (``AXIAL_TERMS[:6]``, in that order;
    N*m and N when calibrated)."""
    values = np.asarray(channels, dtype=float)
    return np.concatenate([values, np.abs(values[:3])])


def estimate_channels(estimate: WrenchEstimate) -> tuple[float, ...]:
    """The estimate's six channels in ``AXIAL_TERMS`` order."""
    return tuple(getattr(estimate, name) for name in AXIAL_TERMS[:6])


class TactileAxialForce:
    """The plug's axial force (along T z, toward the tip; N) read by touch: ``weights`` (N
    per unit of each of ``AXIAL_TERMS``) times the estimate's terms, the median of the last
    ``window`` frames (a single frame's outlier never reads as the load's drop), described
    at their median capture time. Zeroing frames give nothing. The weights are the task's
    ``touch_spiral.axial_weights`` (the settings of ``dipole`` and its variants): fitted
    against the plug's true axial force by ``python -m evaluation fit_axial_map``, or the
    force channel along T z over the sensing finger's share of the load. ``s2t``: the
    rotation R_S2T (3 x 3) that gives the newest frame's torques in T (``torque_t``)."""

    zeroes_tactile = True

    def __init__(
        self, weights: Sequence[float], window: int, s2t: np.ndarray | None = None
    ) -> None:
        self._weights = np.asarray(weights, dtype=float)
        self._frames: deque[tuple[float, float]] = deque(maxlen=window)
        self._s2t = np.eye(3) if s2t is None else np.asarray(s2t, dtype=float)
        self._torque_t: np.ndarray | None = None

    def available(self, obs: Observation) -> bool:
        return True

    def read(self, obs: Observation) -> tuple[float, float] | None:
        w = obs.wrench
        if w is None or w.zeroing:
            self._frames.clear()
            self._torque_t = None
            return None
        if not self._frames or w.t_s != self._frames[-1][1]:
            channels = estimate_channels(w)
            force = float(self._weights @ axial_terms(channels))
            self._frames.append((force, w.t_s))
            self._torque_t = self._s2t @ np.asarray(channels[:3])
        median = np.median(self._frames, axis=0)
        return float(median[0]), float(median[1])

    def torque_t(self) -> np.ndarray | None:
        return self._torque_t
