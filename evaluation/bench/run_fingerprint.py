"""Digests of what a simulated run produced, to tell whether two versions of the code make
the same run bit for bit (a speed-up that keeps behaviour must): every tactile frame, every
estimate and the ground truth's table, each as one SHA-256."""

from __future__ import annotations

import dataclasses
import hashlib

import numpy as np

from controller.tactile.wrench import WrenchEstimate
from drivers.sim.scenes.insertion.truth import TruthLog


class RunFingerprint:
    """Fed the frames and estimates of a run as they come, then its truth."""

    def __init__(self) -> None:
        self._frames = hashlib.sha256()
        self._estimates = hashlib.sha256()
        self.frames = self.estimates = 0

    def frame(self, image: np.ndarray) -> None:
        """A frame's pixels (any layout: the bytes of its values in C order)."""
        self._frames.update(np.ascontiguousarray(image).tobytes())
        self.frames += 1

    def estimate(self, estimate: WrenchEstimate) -> None:
        """An estimate's fields (time, values, flags) as float64."""
        self._estimates.update(np.array(dataclasses.astuple(estimate), float).tobytes())
        self.estimates += 1

    def digests(self, truth: TruthLog) -> dict[str, str]:
        """The frames', the estimates' and ``truth``'s table's digests (hex, 16 digits)."""
        table = np.concatenate([np.ravel(a) for a in truth.arrays().values()])
        return {
            "frames": self._frames.hexdigest()[:16],
            "estimates": self._estimates.hexdigest()[:16],
            "truth": hashlib.sha256(table.astype(float).tobytes()).hexdigest()[:16],
        }
