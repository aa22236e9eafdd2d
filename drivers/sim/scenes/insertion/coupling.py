"""The tactile coupling: the grasp's wrench drives the gel model, whose image field drives
the simulated camera (``SimTactileSensor.set_field_source``).

Both fingers are alike and hold the plug symmetrically, so the sensing finger's gel
carries ``load_share`` of the grasp's forces and of its torque about the grasp point on the
plug's axis, about the gel's own centre (the moments of the two fingers' shear forces about
the plug's axis cancel). That wrench, in S (``frames``), is what the gel exerts on the plug:
the gel model's ``Wrench`` convention and the tactile estimate's. The plug's wide face is a
``square_peg`` of the plug's width along its axis, which runs down the image (S's y) at the
nominal grasp and where the seed's grasp puts it otherwise (``imprint``): across by the
grasp's offset, turned by its tilt about S's z. The grip presses the face where the plug
lies, so its own moment about the gel's centre (the grip force times the face's offset) is
added to the wrench's: the gel then carries, about the face's centre, only the load's
moment, as a real gel does.

``GelCoupling(world, model, grasp)`` is the field source: for a frame captured at ``t_s``
it syncs the world to ``t_s``, and when the fingers squeeze the plug it solves the gel for
the grip force and the gel's wrench at that time (warm-started from the previous frame's
solution) and returns its ``field_px``; ``None`` (the reference image) otherwise. The camera
asks once per frame it delivers, so only frames that are read are solved; the last answer is
cached for a repeated time. When the grip force and the gel's wrench are within
``REUSE_FORCE_N`` and ``REUSE_TORQUE_NM`` of the last solve's (free motion, a steady
press), its field is reused: far below what the estimator resolves (its noise is about
1e-4 N*m on the jig), and most frames of a trial are such frames.
"""

from __future__ import annotations

import math

import numpy as np

from drivers.sim.gel.model import GelModel, GelState, Wrench
from drivers.sim.scenes.insertion.draws import NOMINAL_GRASP, GraspPose
from drivers.sim.scenes.insertion.world import InsertionWorld

REUSE_FORCE_N = 1e-3
REUSE_TORQUE_NM = 1e-5
_TOLERANCE = np.array([REUSE_FORCE_N] * 4 + [REUSE_TORQUE_NM] * 3)  # grip, forces, torques


def imprint(grasp: GraspPose) -> tuple[tuple[float, float], float]:
    """Where the plug's face lies on the gel: the point of its axis on S's x axis (x, y in
    S, m: the fingers press there) and the axis's turn about S's z (rad). The axis runs from
    the grasp point (``across_m``, ``along_m``) along (-sin b, cos b) in S's x-y plane, b
    the grasp's ``tilt_z_rad``, so it crosses y = 0 at x = across + along tan b."""
    b = grasp.tilt_z_rad
    return (grasp.across_m + grasp.along_m * math.tan(b), 0.0), b


class GelCoupling:
    """See the module docstring."""

    def __init__(
        self, world: InsertionWorld, model: GelModel, grasp: GraspPose = NOMINAL_GRASP
    ) -> None:
        self._world = world
        self._model = model
        self._offset_m, self._angle_rad = imprint(grasp)
        self._previous: GelState | None = None
        self._cached: tuple[float, np.ndarray | None] | None = None
        self._solved: tuple[np.ndarray, np.ndarray] | None = None  # (inputs, field)
        self.solves = 0

    def __call__(self, t_s: float) -> np.ndarray | None:
        if self._cached is not None and self._cached[0] == t_s:
            return self._cached[1]
        self._world.sync(t_s)
        grip_n = self._world.grip_force_n
        field = None
        if grip_n > 0:
            field = self._field(grip_n, self._world.physics.gel_wrench_at(t_s))
        else:
            self._previous = self._solved = None
        self._cached = (t_s, field)
        return field

    def _field(self, grip_n: float, gel_wrench: np.ndarray) -> np.ndarray:
        inputs = np.concatenate([[grip_n], gel_wrench])
        if self._solved is not None and np.all(np.abs(inputs - self._solved[0]) <= _TOLERANCE):
            return self._solved[1]
        fx, fy, fz, tau_x, tau_y, tau_z = (float(v) for v in gel_wrench)
        x_m, y_m = self._offset_m  # the grip's moment: tau_x = sum y p, tau_y = -sum x p
        wrench = Wrench(fx, fy, fz, tau_x + y_m * grip_n, tau_y - x_m * grip_n, tau_z)
        state = self._model.solve(
            grip_n, wrench, self._offset_m, self._angle_rad, start=self._previous
        )
        self.solves += 1
        self._previous = state
        self._solved = (inputs, state.field_px)
        return state.field_px
