"""The plug's offset across the fingers, from its imprint on the gel.

The estimator measures where the grasp presses the gel, against the open gel, each time it
takes a new reference (``TactileEstimator.contact_centre_mm``: the centre of the closing
press's support, in S). The plug's wide face lies across the gel as a band of the plug's
width; the band's centre along S's x moves with the plug's offset across its width, which
moves the tip along T x by as much. The camera sees the pressed gel in perspective (a
marker's image moves by its depth times its distance from the image's centre over the
camera's distance), which draws the measured centre toward the image's centre: it reads
``gain`` times the offset, a gain that depends on the sensor and on the plug's width and
hardly on the grip (``python -m evaluation fit_imprint_gain``; docs/BENCHMARKS.md).

``FaceOffset(gain, s2t).read(obs)`` is the offset along T x (m), None before the estimator
has measured a grasp (or with ``gain`` 0: the imprint unused, the nominal grasp's 0).
"""

from __future__ import annotations

import numpy as np

from controller.insertion.interface import Observation


class FaceOffset:
    """See the module docstring. ``gain``: the measured centre's shift per unit of the
    plug's offset (dimensionless; 0: unused); ``s2t``: the rotation R_S2T (3 x 3) from the
    sensor frame S to the tool frame T."""

    def __init__(self, gain: float, s2t: np.ndarray) -> None:
        self.gain = float(gain)
        self._s2t = np.asarray(s2t, dtype=float)

    def read(self, obs: Observation) -> float | None:
        """The plug's offset along T x (m) from ``obs.contact_centre_s_m``, None without one."""
        centre = obs.contact_centre_s_m
        if centre is None or self.gain == 0.0:
            return None
        return float((self._s2t @ np.array([centre[0], centre[1], 0.0]))[0]) / self.gain
