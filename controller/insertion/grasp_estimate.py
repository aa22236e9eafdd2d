"""The plug's pose in the hand, found by touch (FEEL): its tilt in the width plane and
where its tip really is.

The plug is held with its axis along T z at the nominal grasp; in the hand it may be turned
by ``tilt_rad`` about T y (the width plane: its tip moves along T x). FEEL presses the tip's
face on the board and rocks the TCP about the horizontal axis across the opening's width
until the in-plane torque changes sign: there the tip's face lies flat on the board. At
that TCP rotation ``flat`` (T2B), the face's width edge, T x turned by ``tilt_rad`` about
T y, is horizontal, which gives ``tilt_rad`` (``from_flat_rotation``).

This FEEL (the ``align`` machine's) does not find the thickness-plane tilt (about T x) nor
the plug's offset along its width: the torque about the plug's grasp point does not depend
on the offset, and the thickness face's lever (half of 2.4 mm) is below the tilt torque's
noise at a light press. The press spiral's FEEL finds the tilts in both planes by rocking
(controller/insertion/spiral/spiral_feel.py); ``tilt_tip_offset_m`` gives the tip's
offset each implies.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.spatial.transform import Rotation


@dataclass(frozen=True)
class GraspEstimate:
    """The plug turned by ``tilt_rad`` about T y in the hand (positive: its tip toward +T x),
    ``length_m`` from the TCP to its tip."""

    tilt_rad: float
    length_m: float

    @classmethod
    def from_flat_rotation(cls, flat: Rotation, length_m: float) -> GraspEstimate:
        """The estimate from the TCP rotation (T2B) at which the tip's face lies flat on a
        level board: the width edge (cos a, 0, -sin a) in T is horizontal, so with
        d = flat^-1 (0, 0, -1) (straight down, in T), tan a = d_x / d_z."""
        down_t = flat.inv().apply([0.0, 0.0, -1.0])
        return cls(math.atan2(float(down_t[0]), float(down_t[2])), length_m)

    @property
    def tip_t(self) -> np.ndarray:
        """The tip in T (m)."""
        a = self.tilt_rad
        return self.length_m * np.array([math.sin(a), 0.0, math.cos(a)])

    def tip_shift_b(self, rotation: Rotation) -> np.ndarray:
        """Where the tip is, less where the nominal grasp puts it, in B (m), for the TCP
        turned by ``rotation`` (T2B)."""
        return rotation.apply(self.tip_t - np.array([0.0, 0.0, self.length_m]))


def tilt_tip_offset_m(tilt_rad: float, length_m: float) -> float:
    """The tip's offset from the nominal (m) implied by a tilt ``tilt_rad`` (rad) of the plug
    in the hand, ``length_m`` (m) from the TCP to the tip: ``length_m * sin(tilt_rad)``, along
    T y for a tilt about T x (its thickness plane), along T x for one about T y (its width
    plane).

    About T x the tilt is the TCP turn that sets the plug upright (the press spiral's FEEL
    estimate, ``SpiralMachine.tilt_x_estimate_rad``), which is the plug's axis p in T at
    atan2(p_y, p_z) (positive with the tip toward +T y; the scene's truth is measured alike,
    evaluation/trials/grasp_truth.py); about T y it is atan2(p_x, p_z). The nominal tip is
    ``length_m`` along T z; turned by the tilt it lies at ``length_m * (0, sin a, cos a)`` in
    T (the grasp's offset, which the rock does not see, taken as zero)."""
    return length_m * math.sin(tilt_rad)
